"""Grids: built-in grids cover the paper's figures; expansion, dimension names, validation."""

import dataclasses
import hashlib
import itertools
import json
from pathlib import Path

import numpy as np
import pytest

from pipeline.chain.taxels import cut_samples, taxel_delays_s, taxel_signals
from pipeline.design import fields
from pipeline.design.grid import (
    DatasetFacts,
    Grid,
    SweepMode,
    check_fits,
    check_scene_fits,
    load_grid,
    scene_misfits,
    sweep_points,
)
from pipeline.design.scene import MODEL_REVISION, Effect, Scene, SceneVariants
from pipeline.errors import SceneError
from pipeline.recordings.sources import Recordings
from pipeline.run.stages import LEVELS, cache_key


def sweep(grid, name):
    return next(s for s in grid.sweeps if s.name == name)


def test_paper_grid_covers_the_papers_sweeps():
    grid = load_grid("paper")
    assert grid.base.readout.threshold_v == 0.09 and grid.base.array.n_taxels == 9
    thresholds = sweep(grid, "threshold").axes[0].values
    assert len(thresholds) >= 10 and min(thresholds) <= 0.01 and max(thresholds) >= 0.3
    windows = sweep(grid, "window").axes[0].values
    assert len(windows) >= 6 and min(windows) <= 0.025 and max(windows) >= 0.4
    sizes = [p.scene.array for p in grid.points() if p.sweep == "taxels"]
    assert [(a.rows, a.cols) for a in sizes] == [(r, r) for r in range(1, 6)]
    columns = [p.scene.array for p in grid.points() if p.sweep == "taxel_rows"]
    assert [(a.rows, a.cols) for a in columns] == [(r, 1) for r in range(1, 6)]
    noise = [p.scene for p in grid.points() if p.sweep == "noise"]
    assert len(noise) >= 8 and sweep(grid, "noise").correlate
    assert all(s.array.n_taxels == 1 and s.readout.threshold_v == 0.09 for s in noise)
    assert all(Effect.AMPLIFIER_NOISE in s.readout.effects for s in noise)
    assert all(Effect.COMPARATOR_NOISE in s.readout.effects for s in noise)
    mismatch = sweep(grid, "mismatch").axes[0].values
    assert len(mismatch) >= 6 and 0.0 in mismatch


def test_shared_points_are_computed_once():
    grid = load_grid("paper")
    keys = [p.key for p in grid.points()]
    assert len(set(keys)) == len(grid.unique_points()) < len(keys)
    # The operating point is in the threshold sweep and in the square-taxel sweep.
    base_key = cache_key(grid.base, "results")
    assert sum(k == base_key for k in keys) >= 2


def test_product_and_zip_expansion_and_dimension_names():
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "both": {
                    "axes": {"readout.threshold_v": [0.05, 0.1], "coding.window_s": [0.1, 0.2, 0.3]}
                },
                "noise": {
                    "mode": "zip",
                    "axes": {
                        "readout.effects.amplifier_noise.sigma_v": [0.01, 0.02],
                        "readout.effects.comparator_noise.sigma_v": [0.03, 0.04],
                    },
                },
            },
        }
    )
    both, noise = grid.sweeps
    assert both.dims == ("threshold_v", "window_s") and both.shape == (2, 3)
    assert noise.mode == SweepMode.ZIP
    assert noise.dims == ("amplifier_noise_sigma_v",) and noise.shape == (2,)
    scenes = [p.scene for p in grid.points() if p.sweep == "noise"]
    effects = scenes[1].readout.effects
    assert effects[Effect.AMPLIFIER_NOISE].sigma_v == 0.02
    assert effects[Effect.COMPARATOR_NOISE].sigma_v == 0.04
    points = [p for p in grid.points() if p.sweep == "both"]
    assert points[4].index == (1, 1) and points[4].scene.coding.window_s == 0.2


def test_every_problem_is_reported_before_any_work():
    with pytest.raises(SceneError) as info:
        Grid.from_dict(
            {
                "base": "smoke",
                "sweeps": {
                    "a": {"axes": {"readout.treshold_v": [0.1]}},
                    "b": {"axes": {"coding.window_s": []}},
                    "c": {"axes": {"readout.threshold_v": [0.1, 0.2, 0.1]}},
                    "d": {"mode": "zip", "axes": {"array.rows": [1, 2], "array.cols": [1]}},
                    "e": {"axes": {"readout.threshold_v": [-0.1, 0.05]}},
                    "f": {"axes": {"readout.effects.wobble.sigma_v": [0.1]}},
                },
            }
        )
    message = str(info.value)
    assert "\n" not in message
    for expected in (
        "'readout.treshold_v' is not a scene field",
        "sweeps.b.axes.coding.window_s: must be a non-empty list",
        "duplicate values 0.1",
        "zipped axes need equal lengths",
        "readout.threshold_v = -0.1",
        "unknown effect",
    ):
        assert expected in message


def test_sweep_title_is_free_text_kept_in_the_description():
    axes = {"readout.threshold_v": [0.05, 0.1]}
    grid = Grid.from_dict({"base": "smoke", "sweeps": {"t": {"title": "Fig. 7a", "axes": axes}}})
    assert sweep(grid, "t").title == "Fig. 7a"
    assert sweep(Grid.from_dict(grid.describe()), "t").title == "Fig. 7a"
    with pytest.raises(SceneError, match=r"sweeps\.t\.title: expected a string, got 7"):
        Grid.from_dict({"base": "smoke", "sweeps": {"t": {"title": 7, "axes": axes}}})


def test_grid_file_with_a_relative_base_scene(tmp_path):
    (tmp_path / "base.toml").write_text("[array]\nrows = 1\ncols = 1\n")
    (tmp_path / "g.toml").write_text(
        'base = "base.toml"\n[sweeps.t]\naxes = { "readout.threshold_v" = [0.05, 0.1] }\n'
    )
    grid = load_grid(tmp_path / "g.toml")
    assert grid.name == "g" and grid.base.array.n_taxels == 1
    with pytest.raises(SceneError, match="cannot read file"):
        load_grid(tmp_path / "absent.toml")


def test_check_fits_lists_windows_longer_than_recordings_and_small_classes():
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"w": {"axes": {"coding.window_s": [0.1, 5.0]}}}}
    )
    key = cache_key(grid.base, "recordings")
    fitting = Grid.from_dict(
        {"base": "smoke", "sweeps": {"w": {"axes": {"coding.window_s": [0.1]}}}}
    )
    check_fits(fitting, {key: DatasetFacts(fs_hz=2000.0, min_samples=3000, min_class_size=4)})
    with pytest.raises(SceneError) as info:
        check_fits(grid, {key: DatasetFacts(fs_hz=2000.0, min_samples=3000, min_class_size=3)})
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


def test_dataset_facts_name_the_first_shortest_recording():
    facts = DatasetFacts.of(recordings_with_short_class(50))
    assert facts == DatasetFacts(
        1000.0, 50, 10, shortest="a/r00.npy", dataset="mine", smallest_class="a"
    )


def test_shared_check_refuses_delays_that_use_up_a_recording_naming_it():
    scene = Scene.paper()  # 3x3 taxels, 1 mm at 20 mm/s: delays up to 0.1 s
    cut = cut_samples(taxel_delays_s(scene.array), 1000.0)
    assert cut == 100
    with pytest.raises(SceneError) as info:
        check_scene_fits(scene, DatasetFacts.of(recordings_with_short_class(50)))
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
        n: [f for f, _ in scene_misfits(scene, DatasetFacts.of(recordings_with_short_class(n)))]
        for n in (cut + 1, cut + 2)
    }
    assert at == {cut + 1: ["array"], cut + 2: ["coding.window_s"]}


def test_shared_check_refuses_windows_that_do_not_fit_naming_the_recording():
    scene = Scene.paper()
    facts = DatasetFacts.of(recordings_with_short_class(300))  # 0.199 s after the delays
    check_scene_fits(scene, facts)  # "auto": one 0.1 s window fits
    with pytest.raises(
        SceneError,
        match=r"coding\.n_windows: 2 window\(s\) of 0\.1 s do not fit "
        r"the shortest recording, a/r00\.npy of dataset 'mine' \(300 samples\)",
    ):
        check_scene_fits(scene.replace(**{"coding.n_windows": 2}), facts)
    with pytest.raises(SceneError, match=r"coding\.window_s: 1 window\(s\) of 0\.25 s .* a/r00"):
        check_scene_fits(scene.replace(**{"coding.window_s": 0.25}), facts)


def test_check_fits_is_the_shared_check_at_every_point():
    grid = Grid.from_dict({"base": "paper", "sweeps": {"t": {"axes": {"array.rows": [1, 3]}}}})
    # 0.1 s: one window for a 1x3 array along y (no delays), 1 sample left by the 3x3 delays.
    facts = DatasetFacts.of(recordings_with_short_class(101))
    with pytest.raises(SceneError) as info:
        check_fits(grid, {cache_key(grid.base, "recordings"): facts})
    message = str(info.value)
    assert "sweeps.t[0]" not in message
    assert message.startswith("invalid grid 'grid': sweeps.t[1]: the delays of a 3x3 array")
    assert "use up the shortest recording, a/r00.npy of dataset 'mine'" in message
    # One problem at many points is listed once.
    thresholds = {"readout.threshold_v": [0.05, 0.07, 0.09, 0.11, 0.13]}
    grid = Grid.from_dict({"base": "paper", "sweeps": {"t": {"axes": thresholds}}})
    with pytest.raises(SceneError) as info:
        check_fits(grid, {cache_key(grid.base, "recordings"): facts})
    message = str(info.value)
    assert "invalid grid 'grid': sweeps.t[0], sweeps.t[1], sweeps.t[2] and 2 more: " in message
    assert message.count("a/r00.npy") == 1


def test_describe_round_trips_through_json():
    import json

    description = load_grid("smoke").describe()
    assert json.loads(json.dumps(description)) == description
    assert description["sweeps"]["noise"]["mode"] == "zip"


def test_with_dataset_replaces_the_dataset_of_every_point_and_the_provenance(tmp_path):
    grid = load_grid("smoke")
    table = {"kind": "vibtac12", "path": str(tmp_path)}
    moved = grid.with_dataset(table)
    assert moved.name == grid.name and moved.sweeps == grid.sweeps
    # Another kind replaces the whole table: the smoke data's size does not carry over.
    assert moved.base.dataset == Scene.from_dict({"dataset": table}).dataset
    scenes = [p.scene for p in moved.points()]
    assert len(scenes) == len(grid.points())
    assert {s.dataset for s in scenes} == {moved.base.dataset}
    assert all(s.dataset.path == str(tmp_path) for s in scenes)
    # The noise sweep's own settings stay.
    assert {p.scene.array.n_taxels for p in moved.points() if p.sweep == "noise"} == {1}
    assert moved.describe()["base"]["dataset"]["kind"] == "vibtac12"
    assert not set(moved.unique_points()) & set(grid.unique_points())
    assert grid.base.dataset.kind == "synthetic"  # the original is unchanged


def test_with_dataset_of_the_same_kind_keeps_the_bases_other_settings():
    moved = load_grid("smoke").with_dataset({"kind": "synthetic", "seed": 7})
    dataset = moved.base.dataset
    assert (dataset.seed, dataset.recordings_per_class, dataset.duration_s) == (7, 4, 1.5)


def test_with_dataset_takes_a_relative_path_from_the_current_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    moved = load_grid("smoke").with_dataset({"kind": "folder", "path": "mine"})
    assert moved.base.dataset.path == str(tmp_path / "mine")


def test_with_dataset_refuses_a_grid_whose_sweeps_set_the_dataset():
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "fine": {"axes": {"readout.threshold_v": [0.05]}},
                "sized": {
                    "set": {"dataset.recordings_per_class": 6},
                    "axes": {"readout.threshold_v": [0.05]},
                },
                "seeded": {"axes": {"dataset.seed": [1, 2]}},
            },
        }
    )
    with pytest.raises(SceneError) as info:
        grid.with_dataset({"kind": "synthetic"})
    message = str(info.value)
    assert "sweeps.sized.set: 'dataset.recordings_per_class'" in message
    assert "sweeps.seeded.axes: 'dataset.seed'" in message
    assert "sweeps.fine" not in message
    with pytest.raises(SceneError, match="dataset.kind"):
        load_grid("smoke").with_dataset({"kind": "tape"})


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
def test_described_facts_of_the_built_in_data_are_those_of_the_generated_data(dataset):
    """Checking a grid describes the built-in recordings without generating them."""
    from pipeline.recordings.sources import load_recordings

    spec = Scene.from_dict({"dataset": dataset}).dataset
    assert DatasetFacts.describe(spec) == DatasetFacts.of(load_recordings(spec))


def test_described_facts_of_a_folder_dataset_are_read(tmp_path):
    from pipeline.recordings.sources import load_recordings

    (tmp_path / "dataset.toml").write_text("sampling_rate_hz = 100.0\n")
    for name, lengths in {"a": (30, 20), "b": (25, 40)}.items():
        (tmp_path / name).mkdir()
        for i, n in enumerate(lengths):
            np.save(tmp_path / name / f"r{i}.npy", np.sin(np.arange(n, dtype=np.float64)))
    spec = Scene.from_dict({"dataset": {"kind": "folder", "path": str(tmp_path)}}).dataset
    facts = DatasetFacts.describe(spec)
    assert facts == DatasetFacts.of(load_recordings(spec))
    assert (facts.min_samples, facts.shortest) == (20, "a/r1.npy")


# ---------------------------------------------------------------------------------------------
# Expansion: the shared-parts path gives what a plain ``Scene.replace`` per point gives


def keyed_dict(scene: Scene) -> dict:
    """The scene's plain form without what no key holds: its name, the fixed-threshold
    encoder (the neutral default) with the decay of a threshold it does not decay, the chips
    part while all its fields hold their (neutral) defaults, and the spiking decoder's fields of
    a scene that does not train it."""
    data = scene.to_dict()
    data.pop("name")
    if data["readout"]["encoder"] == "lcs":
        del data["readout"]["encoder"], data["readout"]["decay"]
    if not fields.plain(scene.chips, canonical=True):
        del data["chips"]
    if "snn" not in data["training"]["models"]:
        del data["training"]["snn"]
    return data


def reference_key(scene: Scene, level) -> str:
    """A level's key as it was first written: its parts found level by level, the canonical
    form of the whole scene as one dict."""
    paths = {}
    for each in (*level.upstream(), level):
        for read in each.reads:
            if read.applies(scene):
                paths.setdefault(read.path, None)
    parts = tuple(p for p in paths if not any(p.startswith(f"{q}.") for q in paths))
    assert level.key_parts(scene) == parts
    data = keyed_dict(scene)
    canonical = json.dumps(
        fields.select(data, parts),
        sort_keys=True,
        separators=(",", ":"),
        allow_nan=False,
    )
    text = f"r{MODEL_REVISION}:{level.name}:{canonical}"
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def reference_points(grid: Grid) -> list[tuple[str, tuple[int, ...], Scene]]:
    """Every point as ``Scene.replace`` makes it, one point at a time."""
    found = []
    for s in grid.sweeps:
        fixed = grid.base.replace(**s.fixed) if s.fixed else grid.base
        found += [(s.name, index, fixed.replace(**values)) for index, values in s.index_values()]
    return found


def reference_problems(data: dict) -> list[str]:
    """The problems of a grid's points as ``Scene.replace`` finds them, one point at a time."""
    base = Scene.builtin(data["base"])
    problems = []
    for name, spec in data["sweeps"].items():
        fixed = base.replace(**spec.get("set", {}))
        axes = spec["axes"]
        if spec.get("mode") == "zip":
            rows = [
                dict(zip(axes, values, strict=True)) for values in zip(*axes.values(), strict=True)
            ]
        else:
            rows = [dict(zip(axes, v, strict=True)) for v in itertools.product(*axes.values())]
        for values in rows:
            try:
                fixed.replace(**values)
            except SceneError as exc:
                at = ", ".join(f"{f} = {v!r}" for f, v in values.items())
                problems.append(f"sweeps.{name} at {at}: {'; '.join(exc.problems)}")
    return problems


MANY_AXES = {
    "base": "paper",
    "sweeps": {
        "product": {
            "set": {"array.cols": 2, "readout.effects.amplifier_noise.sigma_v": 0.01},
            "axes": {
                "readout.threshold_v": [0.05, 0.09],
                "readout.effects.threshold_mismatch.sigma_rel": [0.0, 0.1, 0.2],
                "coding.window_s": [0.1, 0.2],
                "training.seed": [0, 1],
                "seed": [0, 5],
            },
        },
        "zipped": {
            "mode": "zip",
            "axes": {
                "readout.effects.comparator_noise.sigma_v": [0.0, 0.01, 0.02],
                "array.rows": [1, 2, 3],
                "coding.n_windows": [10, "auto", 5],
            },
        },
        "tables": {
            "axes": {
                "readout.effects": [{}, {"saturation": {"rail_v": 0.4}}],
                "training.models": [["ffnn"], ["cnn", "ffnn"]],
                "dataset.seed": [0, 1],
            }
        },
    },
}


def test_points_keys_and_order_are_those_of_scene_replace_at_every_point():
    grid = Grid.from_dict(MANY_AXES)
    points = grid.points()
    assert [(p.sweep, p.index, p.scene) for p in points] == reference_points(grid)
    assert len(points) == 48 + 3 + 8
    for point in points:
        assert point.key == reference_key(point.scene, LEVELS[-1])
        assert point == type(point)(point.sweep, point.index, point.scene)
        assert point.key == type(point)(point.sweep, point.index, point.scene).key
        moved = dataclasses.replace(point, scene=point.scene.replace(**{"array.rows": 7}))
        assert moved.key == cache_key(moved.scene, "results") != point.key
        for level in LEVELS:
            assert level.key(point.scene) == reference_key(point.scene, level)
    # The sweep's own points are the grid's.
    assert sweep_points(grid.base, grid.sweeps[1]) == [p for p in points if p.sweep == "zipped"]


def test_canonical_form_is_that_of_the_whole_selection_with_or_without_a_memo():
    scene = Grid.from_dict(MANY_AXES).points()[5].scene
    memo = {}
    data = keyed_dict(scene)
    for parts in (
        None,
        ("dataset",),
        ("readout.full_scale_v", "dataset"),
        ("readout", "readout.full_scale_v", "seed"),
        ("readout.effects", "array.rows", "training"),
    ):
        chosen = data if parts is None else fields.select(data, parts)
        expected = json.dumps(chosen, sort_keys=True, separators=(",", ":"), allow_nan=False)
        assert scene.canonical(parts) == expected
        assert scene.canonical(parts, memo) == scene.canonical(parts, memo) == expected
    assert memo  # parts were remembered
    with pytest.raises(KeyError):
        scene.canonical(("name",))


def test_scene_variants_refuse_what_scene_replace_refuses_with_the_same_problems():
    scene = Scene.paper()
    axes = [
        ("readout.threshold_v", [0.05, 2.0, -1.0]),
        ("readout.full_scale_v", [1.0, 0.01]),
        ("seed", [0, -3]),
        ("array.rows", [1, 0]),
    ]
    variants = SceneVariants(scene, axes)
    for indices in itertools.product(*(range(len(v)) for _, v in axes)):
        changes = {f: values[i] for (f, values), i in zip(axes, indices, strict=True)}
        try:
            expected = scene.replace(**changes)
        except SceneError as exc:
            assert variants.problems(indices) == exc.problems
            with pytest.raises(SceneError) as info:
                variants.scene(indices)
            assert str(info.value) == str(exc)
        else:
            assert variants.problems(indices) == []
            assert variants.scene(indices) == expected
    with pytest.raises(ValueError, match="not top-level scene fields: wobble"):
        SceneVariants(scene, [("wobble.x", [1])])


def test_refused_values_are_reported_point_by_point_as_before():
    data = {
        "base": "paper",
        "sweeps": {
            "p": {
                "axes": {
                    "readout.threshold_v": [0.05, 1.5],
                    "readout.full_scale_v": [1.0, 0.02],
                    "seed": [1, -1],
                }
            },
            "z": {
                "mode": "zip",
                "set": {"array.cols": 1},
                "axes": {"array.rows": [0, 2, 300], "training.folds": [1, 3, 4]},
            },
        },
    }
    with pytest.raises(SceneError) as info:
        Grid.from_dict(data)
    expected = reference_problems(data)
    assert len(expected) == 7 + 2  # one point of p fits, one of z
    assert info.value.problems == expected
    assert str(info.value) == str(SceneError(expected, "<dict>", "grid"))


def test_equal_scenes_at_several_points_are_one_point_by_key():
    # No random effect: the scene seed is not in any key, so both seeds are one point; the
    # operating point is in both sweeps.
    grid = Grid.from_dict(
        {
            "base": "paper",
            "sweeps": {
                "seeds": {"axes": {"seed": [0, 1], "readout.threshold_v": [0.05, 0.09]}},
                "threshold": {"axes": {"readout.threshold_v": [0.09, 0.2]}},
            },
        }
    )
    points = grid.points()
    keys = [p.key for p in points]
    assert len(keys) == 6
    unique = grid.unique_points()
    assert list(unique) == list(dict.fromkeys(keys))
    assert len(unique) == 3
    assert unique[keys[0]] is points[0].scene
    assert keys[0] == keys[2] and keys[1] == keys[3] == keys[4] == cache_key(grid.base, "results")


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
    facts = DatasetFacts.of(recordings_with_short_class(401))
    places: dict[str, list[str]] = {}
    for point in grid.points():
        for _, text in scene_misfits(point.scene, facts):
            where = f"sweeps.{point.sweep}[{', '.join(map(str, point.index))}]"
            places.setdefault(text, []).append(where)
    expected = [
        ", ".join(w[:3]) + (f" and {len(w) - 3} more" if len(w) > 3 else "") + f": {text}"
        for text, w in places.items()
    ]
    assert len(expected) >= 4
    with pytest.raises(SceneError) as info:
        check_fits(grid, {cache_key(grid.base, "recordings"): facts})
    assert info.value.problems == expected


def test_a_grid_too_large_to_plan_is_refused_from_its_axis_sizes(monkeypatch):
    from pipeline.design import grid as grid_module

    data = {
        "base": "smoke",
        "sweeps": {
            "a": {"axes": {"readout.threshold_v": [0.05, 0.09], "coding.window_s": [0.1, 0.2]}},
            "b": {"mode": "zip", "axes": {"array.rows": [1, 2, 3], "array.cols": [1, 2, 3]}},
            # Not checked point by point once the grid is known to be too large.
            "c": {"axes": {"readout.threshold_v": [-1.0]}},
        },
    }
    assert grid_module.sweep_sizes(data["sweeps"]) == {"a": 4, "b": 3, "c": 1}
    assert (
        len(
            Grid.from_dict(
                {**data, "sweeps": dict(list(data["sweeps"].items())[:2])}, max_points=7
            ).points()
        )
        == 7
    )

    def no_point_is_checked(*args):
        raise AssertionError("a point was checked")

    monkeypatch.setattr(grid_module, "_positions", no_point_is_checked)
    with pytest.raises(SceneError) as caught:
        Grid.from_dict(data, max_points=7)
    (first,) = caught.value.problems
    assert first.startswith("sweeps: 8 points (sweeps.a has 4) are more than this machine can plan")
    assert "(7 at most)" in first and "search the space with `eskin optimize` instead" in first


def test_plannable_points_follow_memory_up_to_the_planning_time():
    from pipeline.design.grid import PLAN_BYTES_PER_POINT, plannable_points

    assert plannable_points(2 * PLAN_BYTES_PER_POINT * 1000) == 1000
    assert plannable_points(24 * 2**30) == 6_000_000


def test_the_encoder_example_sweeps_both_encoders_with_the_decay_keyed_for_one():
    grid = load_grid(Path(__file__).parents[3] / "examples" / "encoders.toml")
    points = grid.points()
    assert {p.scene.readout.encoder.value for p in points} == {"lcs", "decaying"}
    assert len(points) == 6 and len({p.key for p in points}) == 6
    for point in points:
        keyed = "decay" in point.scene.canonical()
        assert keyed == (point.scene.readout.encoder.value == "decaying")
        assert point.key == reference_key(point.scene, LEVELS[-1])
    paper = Scene.paper().replace(**{"readout.threshold_v": 0.05})
    lcs = [p for p in points if p.scene.readout.encoder.value == "lcs"]
    assert cache_key(paper, "results") in {p.key for p in lcs}  # the paper's own points
