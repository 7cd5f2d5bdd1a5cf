"""Grids: built-in grids cover the paper's figures; expansion, dimension names, validation."""

import itertools
import json
import time

import pytest

from pipeline.design import fields
from pipeline.design.effects import Effect
from pipeline.design.grid import Grid, SweepMode, load_grid, sweep_points
from pipeline.design.scene import Scene
from pipeline.design.variants import SceneVariants
from pipeline.errors import SceneError
from pipeline.run.grid_keys import unique_points
from tests.grid_helpers import MANY_AXES, keyed_dict, reference_points


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
    assert not set(unique_points(moved)) & set(unique_points(grid))
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


# ---------------------------------------------------------------------------------------------
# Expansion: the shared-parts path gives what a plain ``Scene.replace`` per point gives


def reference_problems(data: dict) -> list[str]:
    """The problems of a grid's points as ``Scene.replace`` finds them, one point at a time, its
    ``set`` and axis values together."""
    base = Scene.builtin(data["base"])
    problems = []
    for name, spec in data["sweeps"].items():
        fixed = spec.get("set", {})
        axes = spec["axes"]
        if spec.get("mode") == "zip":
            rows = [
                dict(zip(axes, values, strict=True)) for values in zip(*axes.values(), strict=True)
            ]
        else:
            rows = [dict(zip(axes, v, strict=True)) for v in itertools.product(*axes.values())]
        for values in rows:
            try:
                base.replace(**{**fixed, **values})
            except SceneError as exc:
                at = ", ".join(f"{f} = {v!r}" for f, v in values.items())
                problems.append(f"sweeps.{name} at {at}: {'; '.join(exc.problems)}")
    return problems


def test_points_and_order_are_those_of_scene_replace_at_every_point():
    grid = Grid.from_dict(MANY_AXES)
    points = grid.points()
    assert [(p.sweep, p.index, p.scene) for p in points] == reference_points(grid)
    assert len(points) == 48 + 3 + 8
    for point in points:
        assert point == type(point)(point.sweep, point.index, point.scene)
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


# ---------------------------------------------------------------------------------------------
# Point by point: each point's whole scene, never a sweep's ``set`` alone


SHARED_CHIPS = {"chips.count": 100, "chips.deployment": "shared"}


def test_a_set_that_needs_a_swept_field_is_valid_where_every_point_has_it():
    data = {
        "base": "paper",
        "sweeps": {
            "shared": {
                "set": SHARED_CHIPS,
                "axes": {"readout.effects.threshold_mismatch.sigma_rel": [0.0, 0.1, 0.2]},
            }
        },
    }
    grid = Grid.from_dict(data)
    points = grid.points()
    assert [(p.sweep, p.index, p.scene) for p in points] == reference_points(grid)
    assert [p.scene.readout.effects[Effect.THRESHOLD_MISMATCH].sigma_rel for p in points] == [
        0.0,
        0.1,
        0.2,
    ]
    assert {(p.scene.chips.count, p.scene.chips.deployment.value) for p in points} == {
        (100, "shared")
    }
    # The same scenes as the set that named the effect too (what a grid had to write before).
    named = {"readout.effects": {"threshold_mismatch": {}}, **SHARED_CHIPS}
    twice = Grid.from_dict(
        {**data, "sweeps": {"shared": {**data["sweeps"]["shared"], "set": named}}}
    )
    assert [p.scene for p in twice.points()] == [p.scene for p in points]


def test_problems_name_the_sweep_the_point_and_the_field_all_at_once_in_one_line():
    data = {
        "base": "paper",
        "sweeps": {
            # No point has an effect drawn per chip: refused at every point, said once.
            "unmatched": {"set": SHARED_CHIPS, "axes": {"readout.threshold_v": [0.05, 0.1]}},
            # One point's axis value is refused; the set is refused at every point.
            "mixed": {
                "set": {"array.rows": 0},
                "axes": {"readout.threshold_v": [0.05, -0.1]},
            },
            # The effect only at some points: the others are named one by one.
            "some": {
                "set": SHARED_CHIPS,
                "mode": "zip",
                "axes": {
                    "readout.effects.threshold_mismatch.sigma_rel": [0.1, 0.2],
                    "readout.threshold_v": [0.05, 0.1],
                },
            },
        },
    }
    with pytest.raises(SceneError) as info:
        Grid.from_dict(data)
    message = str(info.value)
    assert "\n" not in message and message.startswith("invalid grid <dict> (3 problems): ")
    # "some" is valid: each of its points has the effect its set needs.
    assert info.value.problems == [
        "sweeps.unmatched at every point: chips.deployment: 'shared' needs a readout effect "
        "drawn per chip (amplifier_offset, comparator_offset, threshold_mismatch); with none "
        "every chip is identical",
        "sweeps.mixed at every point: array.rows: 0 is out of range: must be between 1 and 256",
        "sweeps.mixed at readout.threshold_v = -0.1: readout.threshold_v: -0.1 is out of "
        "range: must be > 0 V",
    ]


def test_a_point_without_what_the_set_needs_is_named_alone():
    data = {
        "base": "paper",
        "sweeps": {
            "s": {
                "set": {"chips.count": 10, "chips.deployment": "shared"},
                "axes": {
                    "readout.effects": [{}, {"comparator_offset": {"sigma_v": 0.01}}],
                    "readout.threshold_v": [0.05, 0.1],
                },
            }
        },
    }
    with pytest.raises(SceneError) as info:
        Grid.from_dict(data)
    expected = reference_problems(data)
    assert info.value.problems == expected
    assert [p.split(":")[0] for p in expected] == [
        "sweeps.s at readout.effects = {}, readout.threshold_v = 0.05",
        "sweeps.s at readout.effects = {}, readout.threshold_v = 0.1",
    ]


def test_checking_every_point_of_a_large_grid_stays_cheap():
    data = {
        "base": "paper",
        "sweeps": {
            "large": {
                "set": SHARED_CHIPS,
                "axes": {
                    "readout.effects.threshold_mismatch.sigma_rel": [i / 100 for i in range(20)],
                    "readout.threshold_v": [0.01 + i / 100 for i in range(25)],
                    "coding.window_s": [0.05, 0.1, 0.2, 0.4],
                    "seed": [0, 1],
                },
            }
        },
    }
    started = time.perf_counter()
    grid = Grid.from_dict(data)
    elapsed = time.perf_counter() - started
    assert len(grid.points()) == 4000
    # A few tens of microseconds per point; a generous bound for a busy machine.
    assert elapsed < 4000 * 500e-6, elapsed
