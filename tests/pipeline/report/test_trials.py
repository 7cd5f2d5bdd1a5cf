"""The front of a search: Pareto masks, hypervolume, search seconds."""

import itertools

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.report.trials import hypervolume, pareto_mask, search_seconds


def test_pareto_mask_keeps_the_non_dominated_rows():
    costs = np.array([[1.0, 5.0], [2.0, 2.0], [3.0, 3.0], [5.0, 1.0], [2.0, 2.0], [np.nan, 0.0]])
    assert pareto_mask(costs).tolist() == [True, True, False, True, True, False]


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(*[st.integers(0, 5)] * 3), min_size=1, max_size=12))
def test_pareto_mask_agrees_with_the_definition(rows):
    costs = np.array(rows, dtype=float)
    on = pareto_mask(costs)
    for i, row in enumerate(costs):
        dominated = any((o <= row).all() and (o < row).any() for o in costs)
        assert on[i] == (not dominated)


def test_hypervolume_of_hand_made_fronts():
    assert hypervolume(np.array([[1.0, 1.0]]), np.array([3.0, 3.0])) == 4.0
    # Two boxes of 2 x 1 and 1 x 2 overlapping in 1 x 1.
    assert hypervolume(np.array([[1.0, 2.0], [2.0, 1.0]]), np.array([3.0, 3.0])) == 3.0
    # A dominated point and one outside the reference add nothing.
    front = np.array([[1.0, 2.0], [2.0, 1.0], [2.5, 2.5], [4.0, 0.0]])
    assert hypervolume(front, np.array([3.0, 3.0])) == 3.0
    assert hypervolume(np.array([[1.0, 1.0, 1.0]]), np.array([2.0, 3.0, 4.0])) == 6.0


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(*[st.integers(0, 4)] * 3), min_size=1, max_size=8))
def test_hypervolume_counts_the_dominated_unit_cells(rows):
    costs = np.array(rows, dtype=float)
    reference = np.array([5.0, 5.0, 5.0])
    cells = sum(
        any((c <= np.array(cell)).all() for c in costs)
        for cell in itertools.product(range(5), repeat=3)
    )
    assert hypervolume(costs, reference) == pytest.approx(cells)


def test_search_seconds_count_the_paid_seconds_of_each_point_once():
    stages = ["load", "setup", "readout", "coding", "train_ffnn"]
    # (trial, stage, charge): own, shared.
    paid = np.zeros((4, 5, 2))
    paid[0] = [[0, 2.0], [0, 0.5], [1.0, 0], [0.1, 0], [3.0, 0]]  # paid the load, the compile
    paid[1] = paid[0]  # the same point again: free
    paid[2] = [[0, 0], [0, 0], [0, 0], [0.2, 0], [4.0, 0]]  # reused the train and the load
    paid[3] = [[0, 0], [0, 0], [1.5, 0], [0.1, 0], [3.0, 0]]  # its own train
    cube = xr.Dataset(
        {"seconds": (("trial", "stage", "charge"), paid)},
        coords={
            "stage": stages,
            "charge": ["own", "shared"],
            "result_key": ("trial", ["p", "p", "q", "r"]),
        },
    )
    total = search_seconds(cube, ["a", "a", "a", "b"], ("setup", "readout"))
    assert total == pytest.approx(6.6 + 4.2 + 4.6)
    # Beyond the one-off load and compile: what a further trial is expected to cost.
    own = search_seconds(cube, ["a", "a", "a", "b"], ("setup", "readout"), shared=False)
    assert own == pytest.approx(4.1 + 4.2 + 4.6)


def test_search_seconds_of_older_points_count_each_point_and_each_spike_train_once():
    """Points stored before paid seconds were kept: work seconds, each train once."""
    stages = ["taxels", "readout", "metrics", "coding", "train_ffnn"]
    seconds = np.array(
        [
            [1.0, 2.0, 0.5, 0.1, 3.0],  # train a, point p
            [1.0, 2.0, 0.5, 0.1, 3.0],  # the same point again: free
            [1.0, 2.0, 0.5, 0.2, 4.0],  # train a again, another window: coding and training
            [1.5, 2.5, 0.5, 0.1, 3.0],  # train b
        ]
    )
    cube = xr.Dataset(
        {"seconds": (("trial", "stage"), seconds)},
        coords={"stage": stages, "result_key": ("trial", ["p", "p", "q", "r"])},
    )
    total = search_seconds(cube, ["a", "a", "a", "b"], ("taxels", "readout", "metrics"))
    assert total == pytest.approx(6.6 + 4.2 + 7.6)
