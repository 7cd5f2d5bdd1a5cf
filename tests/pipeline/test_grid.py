"""Grids: built-in grids cover the paper's figures; expansion, dimension names, validation."""

import pytest

from pipeline.errors import SceneError
from pipeline.grid import DatasetFacts, Grid, SweepMode, check_fits, load_grid
from pipeline.scene import Effect, cache_key


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


def test_describe_round_trips_through_json():
    import json

    description = load_grid("smoke").describe()
    assert json.loads(json.dumps(description)) == description
    assert description["sweeps"]["noise"]["mode"] == "zip"
