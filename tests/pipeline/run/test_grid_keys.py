"""The result keys of a grid's points: those of the reference key at every point, equal scenes
one point by key."""

import copy
import dataclasses
import tomllib
from importlib import resources
from pathlib import Path

from pipeline.design.grid import Grid, load_grid
from pipeline.design.scene import Scene
from pipeline.run.grid_keys import (
    KeyedPoint,
    distinct_scenes,
    keyed_points,
    keys_by_sweep,
    unique_points,
)
from pipeline.run.stages import LEVELS, cache_key
from tests.grid_helpers import MANY_AXES, reference_key


def test_keys_are_those_of_the_reference_at_every_point():
    grid = Grid.from_dict(MANY_AXES)
    points = keyed_points(grid)
    assert [(p.sweep, p.index, p.scene) for p in points] == [
        (p.sweep, p.index, p.scene) for p in grid.points()
    ]
    for point in points:
        assert point.key == reference_key(point.scene, LEVELS[-1])
        assert point == KeyedPoint(point.sweep, point.index, point.scene, "another key")
        moved = dataclasses.replace(point, scene=point.scene.replace(**{"array.rows": 7}))
        assert cache_key(moved.scene, "results") != point.key
        for level in LEVELS:
            assert level.key(point.scene) == reference_key(point.scene, level)
    # A sweep's keyed points are the grid's.
    assert keyed_points(grid, grid.sweeps[1]) == [p for p in points if p.sweep == "zipped"]
    assert [p.key for p in keyed_points(grid, grid.sweeps[1])] == [
        p.key for p in points if p.sweep == "zipped"
    ]


def test_shared_points_are_computed_once():
    grid = load_grid("paper")
    keys = [p.key for p in keyed_points(grid)]
    assert len(set(keys)) == len(unique_points(grid)) < len(keys)
    # The operating point is in the threshold sweep and in the square-taxel sweep.
    base_key = cache_key(grid.base, "results")
    assert sum(k == base_key for k in keys) >= 2


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
    points = keyed_points(grid)
    keys = [p.key for p in points]
    assert len(keys) == 6
    unique = unique_points(grid)
    assert list(unique) == list(dict.fromkeys(keys))
    assert len(unique) == 3
    assert unique[keys[0]] is points[0].scene
    assert keys[0] == keys[2] and keys[1] == keys[3] == keys[4] == cache_key(grid.base, "results")
    assert distinct_scenes(points) == unique
    # Each sweep's distinct keys, in the order of its points.
    assert keys_by_sweep(points, grid.sweeps) == {
        "seeds": (keys[0], keys[1]),
        "threshold": (keys[4], keys[5]),
    }


def test_the_encoder_example_sweeps_both_encoders_with_the_decay_keyed_for_one():
    grid = load_grid(Path(__file__).parents[3] / "examples" / "encoders.toml")
    points = keyed_points(grid)
    assert {p.scene.readout.encoder.value for p in points} == {"lcs", "decaying"}
    assert len(points) == 6 and len({p.key for p in points}) == 6
    for point in points:
        keyed = "decay" in point.scene.canonical()
        assert keyed == (point.scene.readout.encoder.value == "decaying")
        assert point.key == reference_key(point.scene, LEVELS[-1])
    paper = Scene.paper().replace(**{"readout.threshold_v": 0.05})
    lcs = [p for p in points if p.scene.readout.encoder.value == "lcs"]
    assert cache_key(paper, "results") in {p.key for p in lcs}  # the paper's own points


def test_the_paper_grid_keys_are_those_of_its_chip_sweeps_with_the_effect_named_twice():
    # The chip sweeps once named the mismatch effect in their set as well as on their axis (a
    # set was checked alone, before its axes); the same scenes keep the same cache keys.
    text = resources.files("pipeline.design.grids").joinpath("paper.toml").read_text("utf-8")
    data = tomllib.loads(text)
    twice = copy.deepcopy(data)
    chip_sweeps = [n for n, s in data["sweeps"].items() if "chips.deployment" in s.get("set", {})]
    assert chip_sweeps == ["mismatch_shared", "mismatch_robust"]
    for name in chip_sweeps:
        assert "readout.effects" not in data["sweeps"][name]["set"]
        twice["sweeps"][name]["set"]["readout.effects"] = {"threshold_mismatch": {}}
    paper = keyed_points(load_grid("paper"))
    before = keyed_points(Grid.from_dict(twice))
    assert [(p.sweep, p.index, p.key) for p in paper] == [(p.sweep, p.index, p.key) for p in before]
    assert len(paper) == 63
