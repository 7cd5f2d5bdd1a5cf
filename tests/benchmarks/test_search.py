"""The search benchmark's spaces, its scaling of objectives and its replay of a search against
kept exhaustive results, without the benchmark's data."""

import dataclasses

import numpy as np

from benchmarks.search import (
    MISMATCH,
    SPACES,
    WORKERS,
    Budget,
    at_budget,
    grid_cost,
    grid_params,
    oracle_share,
    point_label,
    replay,
    scaled_costs,
)
from pipeline.design.space import Sampler, Space
from pipeline.run.grid_keys import unique_points


def test_the_benchmark_spaces_grid_into_192_and_576_distinct_points():
    rows, encoder = (Space.from_dict(SPACES[n]) for n in ("rows", "encoder"))
    assert len(rows.dimensions) == 3 and len(encoder.dimensions) == 5
    for space, n in ((rows, 192), (encoder, 576)):
        params = grid_params(space)
        assert len(params) == n == len(unique_points(space.exhaustive_grid(10)))
        assert len({point_label(p) for p in params}) == n


def test_objectives_are_scaled_to_the_grid_range():
    values = np.array([[0.5, 0.0], [0.25, 99.0], [0.75, 9.0]])  # accuracy, data rate
    raw = np.column_stack([-values[:, 0], np.log10(1 + values[:, 1])])
    scaled = scaled_costs(values, raw.min(axis=0), raw.max(axis=0))
    np.testing.assert_allclose(scaled, [[0.5, 0.0], [1.0, 1.0], [0.0, 0.5]])


def test_a_replayed_search_pays_each_train_once_and_the_one_off_costs_per_worker():
    space = Space.from_dict(
        {
            **SPACES["rows"],
            "space": {
                "readout.threshold_v": {"choices": [0.045, 0.13]},
                "array.rows": {"low": 1, "high": 3},
            },
        }
    )
    params = grid_params(space)  # 6 points; trains by threshold (3 points each)
    train = np.array([0 if p["readout.threshold_v"] == 0.045 else 1 for p in params])
    arrays = {
        "values": np.column_stack([np.linspace(0.2, 0.7, 6), np.geomspace(10, 1e4, 6)]),
        "own_s": np.full(6, 1.0),
        "train_s": np.where(np.arange(6) % 3 == 0, 4.0, 0.0),  # the first point of each pays
        "train": train,
        "shared_s": np.array([3.0, 0, 0, 3.0, 0, 0]),  # each worker's first point
        "labels": np.array([point_label(p) for p in params]),
    }
    found = replay(dataclasses.replace(space, sampler=Sampler.RANDOM), arrays, budget_s=1e9)
    assert set(found.points) == set(range(6))  # a budget never spent: until every point is tried
    for number, point in enumerate(found.points):
        first = found.points.index(point)
        first_on_train = first == min(
            i for i, p in enumerate(found.points) if train[p] == train[point]
        )
        expected = 1.0 + (4.0 if first_on_train else 0.0) + (3.0 if number < WORKERS else 0.0)
        if number > first:  # a point tried before is in the store
            assert found.seconds[number] == (3.0 if number < WORKERS else 0.0)
        else:  # a train under way is waited for, not computed again
            assert found.seconds[number] == expected
    small = replay(dataclasses.replace(space, sampler=Sampler.RANDOM), arrays, budget_s=10.0)
    assert sum(small.seconds[t] for t in at_budget(small, 10.0)) < 10.0 + 2 * 8.0
    assert at_budget(found, 10.0) == at_budget(small, 10.0) == list(range(len(small.points)))


def test_the_oracle_of_a_dimension_that_moves_nothing_finds_the_front_at_any_copy():
    # Two designs (rows 1 and 2), each at two mismatch values.
    params = [{"array.rows": rows, MISMATCH: sigma} for rows in (1, 2) for sigma in (0.0, 0.1)]
    labels = np.array([point_label(p) for p in params])
    equal = {"values": np.array([[0.3, 10.0], [0.3, 10.0], [0.6, 100.0], [0.6, 100.0]])}
    assert oracle_share({**equal, "labels": labels}, MISMATCH) == (1.0, 1.0, 1.0)
    # One lucky copy of the accurate design: the oracle finds it half the time.
    lucky = {"values": np.array([[0.3, 10.0], [0.3, 10.0], [0.5, 100.0], [0.7, 100.0]])}
    median, low, high = oracle_share({**lucky, "labels": labels}, MISMATCH, draws=400)
    assert low < 1.0 and high == 1.0 and low <= median <= high
    assert oracle_share({**equal, "labels": labels}, "coding.window_s") is None


def test_a_budget_beyond_the_start_leaves_the_workers_start_out_of_the_share():
    # Two workers' starts of 3 s each in a grid of 10 points of 1 s (16 s in all).
    arrays = {
        "own_s": np.full(10, 1.0),
        "train_s": np.zeros(10),
        "shared_s": np.array([3.0, 0, 0, 0, 0, 3.0, 0, 0, 0, 0]),
    }
    assert grid_cost(arrays) == 16.0
    assert Budget.PAID.seconds(0.5, arrays) == 8.0
    assert Budget.BEYOND_START.seconds(0.5, arrays) == 6.0 + 5.0
    for budget in Budget:  # what a search spent, as the share its budget was given in
        assert budget.spent(budget.seconds(0.25, arrays), arrays) == 0.25
