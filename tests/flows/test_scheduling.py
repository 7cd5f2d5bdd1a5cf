"""Tests of flows.scheduling: the batches in which points are submitted, and the cache keys sent
with each point (the cost model it orders points by: tests/pipeline/design/test_grid_cost.py)."""

import pytest

from flows import scheduling
from flows.scheduling import default_points_per_task, point_keys
from pipeline.design.scene import Scene
from pipeline.run.stages import LEVELS


def test_point_keys_are_every_levels_key_whatever_the_memo():
    scenes = [Scene.paper(), Scene.paper().replace(**{"coding.window_s": 0.2})]
    memo = {}
    for scene in scenes:
        keys = point_keys(scene, memo)
        assert keys == {level.name: level.key(scene) for level in LEVELS}
    assert point_keys(scenes[0])["spikes"] == point_keys(scenes[1])["spikes"]
    assert point_keys(scenes[0])["results"] != point_keys(scenes[1])["results"]


@pytest.mark.parametrize(
    ("n_points", "n_threads", "expected"),
    [(0, 2, 1), (1, 2, 1), (48, 2, 3), (10_000, 2, 500), (10_000, 64, 20), (7, 0, 1)],
)
def test_default_points_per_task_is_about_eight_tasks_per_thread(n_points, n_threads, expected):
    assert default_points_per_task(n_points, n_threads) == expected


def test_batches_keep_a_trains_points_together_where_they_fit_and_spread_big_ones():
    by_train = {"a": ["a1", "a2"], "b": ["b1", "b2", "b3"], "c": ["c1"], "d": list("dddddddd")}
    batches = scheduling._batches({t: list(k) for t, k in by_train.items()}, 4)
    flat = [[(train, tuple(keys)) for train, keys in batch] for batch in batches]
    assert flat == [
        [("a", ("a1", "a2"))],  # b does not fit beside a: it starts a batch of its own
        [("b", ("b1", "b2", "b3")), ("c", ("c1",))],
        [("d", tuple("dddd"))],  # d has more points than a batch: spread, full batches
        [("d", tuple("dddd"))],
    ]
    # Every point once, in order, and no batch above the size.
    points = [k for batch in batches for _, keys in batch for k in keys]
    assert points == [k for keys in by_train.values() for k in keys]
    assert max(sum(len(keys) for _, keys in batch) for batch in batches) == 4
    assert scheduling._batches(by_train, 1) == [
        [(t, [k])] for t, ks in by_train.items() for k in ks
    ]
