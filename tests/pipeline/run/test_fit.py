"""Does a scene fit its recordings: delays, windows and folds checked before any work, every
problem named with the shortest recording; the limits of the built-in data known without
generating it."""

import numpy as np
import pytest

from pipeline.chain.taxels import cut_samples, taxel_delays_s, taxel_signals
from pipeline.design.grid import Grid
from pipeline.design.scene import Scene
from pipeline.errors import SceneError
from pipeline.recordings.sources import Recordings
from pipeline.run.fit import DatasetLimits, check_fits, check_scene_fits, scene_misfits
from pipeline.run.stages import cache_key


def test_check_fits_lists_windows_longer_than_recordings_and_small_classes():
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"w": {"axes": {"coding.window_s": [0.1, 5.0]}}}}
    )
    key = cache_key(grid.base, "recordings")
    fitting = Grid.from_dict(
        {"base": "smoke", "sweeps": {"w": {"axes": {"coding.window_s": [0.1]}}}}
    )
    check_fits(fitting, {key: DatasetLimits(fs_hz=2000.0, min_samples=3000, min_class_size=4)})
    with pytest.raises(SceneError) as info:
        check_fits(grid, {key: DatasetLimits(fs_hz=2000.0, min_samples=3000, min_class_size=3)})
    message = str(info.value)
    assert "sweeps.w[1]: 1 window(s) of 5.0 s do not fit" in message
    assert "4 folds need at least that many recordings per class" in message


def recordings_with_short_class(short: int, fs_hz: float = 1000.0) -> Recordings:
    """Ten recordings of ``short`` samples in class ``a``, ten of 2000 in class ``b``."""
    rng = np.random.default_rng(0)
    lengths = [short] * 10 + [2000] * 10
    return Recordings(
        signals=tuple(rng.normal(size=n) for n in lengths),
        labels=np.repeat([0, 1], 10),
        class_names=("a", "b"),
        fs_hz=fs_hz,
        names=tuple(f"{c}/r{i:02d}.npy" for c in "ab" for i in range(10)),
        units="a.u.",
        name="mine",
    )


def test_dataset_limits_name_the_first_shortest_recording():
    limits = DatasetLimits.of(recordings_with_short_class(50))
    assert limits == DatasetLimits(
        1000.0, 50, 10, shortest="a/r00.npy", dataset="mine", smallest_class="a"
    )


def test_shared_check_refuses_delays_that_use_up_a_recording_naming_it():
    scene = Scene.paper()  # 3x3 taxels, 1 mm at 20 mm/s: delays up to 0.1 s
    cut = cut_samples(taxel_delays_s(scene.array), 1000.0)
    assert cut == 100
    with pytest.raises(SceneError) as info:
        check_scene_fits(scene, DatasetLimits.of(recordings_with_short_class(50)))
    message = str(info.value)
    assert message.startswith("invalid scene 'paper': array: the delays of a 3x3 array")
    for expected in ("0.1 s, 100 samples at 1000 Hz", "a/r00.npy of dataset 'mine'", "50 samples"):
        assert expected in message
    # The boundary is the simulation's own: taxel_signals needs 2 samples left.
    delays = taxel_delays_s(scene.array)
    with pytest.raises(ValueError, match="leave 1 samples"):
        taxel_signals(np.zeros(cut + 1), 1000.0, delays)
    taxel_signals(np.zeros(cut + 2), 1000.0, delays)
    at = {
        n: [f for f, _ in scene_misfits(scene, DatasetLimits.of(recordings_with_short_class(n)))]
        for n in (cut + 1, cut + 2)
    }
    assert at == {cut + 1: ["array"], cut + 2: ["coding.window_s"]}


def test_shared_check_refuses_windows_that_do_not_fit_naming_the_recording():
    scene = Scene.paper()
    limits = DatasetLimits.of(recordings_with_short_class(300))  # 0.199 s after the delays
    check_scene_fits(scene, limits)  # "auto": one 0.1 s window fits
    with pytest.raises(
        SceneError,
        match=r"coding\.n_windows: 2 window\(s\) of 0\.1 s do not fit "
        r"the shortest recording, a/r00\.npy of dataset 'mine' \(300 samples\)",
    ):
        check_scene_fits(scene.replace(**{"coding.n_windows": 2}), limits)
    with pytest.raises(SceneError, match=r"coding\.window_s: 1 window\(s\) of 0\.25 s .* a/r00"):
        check_scene_fits(scene.replace(**{"coding.window_s": 0.25}), limits)


def test_check_fits_is_the_shared_check_at_every_point():
    grid = Grid.from_dict({"base": "paper", "sweeps": {"t": {"axes": {"array.rows": [1, 3]}}}})
    # 0.1 s: one window for a 1x3 array along y (no delays), 1 sample left by the 3x3 delays.
    limits = DatasetLimits.of(recordings_with_short_class(101))
    with pytest.raises(SceneError) as info:
        check_fits(grid, {cache_key(grid.base, "recordings"): limits})
    message = str(info.value)
    assert "sweeps.t[0]" not in message
    assert message.startswith("invalid grid 'grid': sweeps.t[1]: the delays of a 3x3 array")
    assert "use up the shortest recording, a/r00.npy of dataset 'mine'" in message
    # One problem at many points is listed once.
    thresholds = {"readout.threshold_v": [0.05, 0.07, 0.09, 0.11, 0.13]}
    grid = Grid.from_dict({"base": "paper", "sweeps": {"t": {"axes": thresholds}}})
    with pytest.raises(SceneError) as info:
        check_fits(grid, {cache_key(grid.base, "recordings"): limits})
    message = str(info.value)
    assert "invalid grid 'grid': sweeps.t[0], sweeps.t[1], sweeps.t[2] and 2 more: " in message
    assert message.count("a/r00.npy") == 1


@pytest.mark.parametrize(
    "dataset",
    [
        {"kind": "synthetic", "recordings_per_class": 2, "duration_s": 0.5},
        {
            "kind": "synthetic",
            "recordings_per_class": 3,
            "duration_s": 0.2501,
            "sampling_rate_hz": 999.0,
        },
        {"kind": "synthetic", "seed": 7, "recordings_per_class": 1, "duration_s": 0.1},
    ],
)
def test_described_limits_of_the_built_in_data_are_those_of_the_generated_data(dataset):
    """Checking a grid describes the built-in recordings without generating them."""
    from pipeline.recordings.sources import load_recordings

    spec = Scene.from_dict({"dataset": dataset}).dataset
    assert DatasetLimits.describe(spec) == DatasetLimits.of(load_recordings(spec))


def test_described_limits_of_a_folder_dataset_are_read(tmp_path):
    from pipeline.recordings.sources import load_recordings

    (tmp_path / "dataset.toml").write_text("sampling_rate_hz = 100.0\n")
    for name, lengths in {"a": (30, 20), "b": (25, 40)}.items():
        (tmp_path / name).mkdir()
        for i, n in enumerate(lengths):
            np.save(tmp_path / name / f"r{i}.npy", np.sin(np.arange(n, dtype=np.float64)))
    spec = Scene.from_dict({"dataset": {"kind": "folder", "path": str(tmp_path)}}).dataset
    limits = DatasetLimits.describe(spec)
    assert limits == DatasetLimits.of(load_recordings(spec))
    assert (limits.min_samples, limits.shortest) == (20, "a/r1.npy")


def test_check_fits_reports_as_the_per_point_check():
    grid = Grid.from_dict(
        {
            "base": "paper",
            "sweeps": {
                "a": {"axes": {"array.rows": [1, 3, 5], "coding.window_s": [0.1, 0.2, 0.5]}},
                "b": {"axes": {"training.folds": [2, 4, 12], "coding.n_windows": [1, 3]}},
            },
        }
    )
    limits = DatasetLimits.of(recordings_with_short_class(401))
    places: dict[str, list[str]] = {}
    for point in grid.points():
        for _, text in scene_misfits(point.scene, limits):
            where = f"sweeps.{point.sweep}[{', '.join(map(str, point.index))}]"
            places.setdefault(text, []).append(where)
    expected = [
        ", ".join(w[:3]) + (f" and {len(w) - 3} more" if len(w) > 3 else "") + f": {text}"
        for text, w in places.items()
    ]
    assert len(expected) >= 4
    with pytest.raises(SceneError) as info:
        check_fits(grid, {cache_key(grid.base, "recordings"): limits})
    assert info.value.problems == expected
