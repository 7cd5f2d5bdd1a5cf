"""Rate coding: explicit half-open windows, exact accounting of every spike, frames."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pipeline.chain.coding import frames, rate_code, resolve_n_windows, window_edges_s
from pipeline.chain.spikes import SpikeTrains
from pipeline.design.scene import CodingSpec, Polarity
from pipeline.design.windows import MAX_AUTO_WINDOWS
from pipeline.errors import SimulationError


def test_contract_types():
    counts, dropped = rate_code(np.array([0.01, 0.15, 0.16, 0.5]), 0.1, 4)
    assert counts.dtype == np.int64 and counts.shape == (4,)
    assert isinstance(dropped, int)
    np.testing.assert_array_equal(counts, [1, 2, 0, 0])
    assert dropped == 1


def test_spikes_exactly_on_edges_go_to_the_window_that_starts_there():
    edges = window_edges_s(0.1, 5)
    counts, dropped = rate_code(edges, 0.1, 5)
    np.testing.assert_array_equal(counts, [1, 1, 1, 1, 1])
    assert dropped == 1  # the last edge, 5 * 0.1, is outside
    # Edges are whole microseconds: edge 3 is 300000 us = 0.3 (not 3 * 0.1 =
    # 0.30000000000000004), so 0.3 starts window 3 and the float just below it ends window 2.
    assert edges[3] == 0.3
    counts, _ = rate_code(np.array([0.3]), 0.1, 5)
    np.testing.assert_array_equal(counts, [0, 0, 0, 1, 0])
    counts, _ = rate_code(np.array([np.nextafter(0.3, 0.0)]), 0.1, 5)
    np.testing.assert_array_equal(counts, [0, 0, 1, 0, 0])


def test_negative_times_are_dropped_and_nan_is_refused():
    counts, dropped = rate_code(np.array([-1e-12, 0.0]), 1.0, 1)
    np.testing.assert_array_equal(counts, [1])
    assert dropped == 1
    with pytest.raises(ValueError, match="NaN"):
        rate_code(np.array([np.nan]), 1.0, 1)


@pytest.mark.parametrize(
    ("window_s", "n_windows", "message"),
    [
        (0.0, 4, "at least one tick"),
        (1e-7, 4, "at least one tick"),  # every edge would round to 0
        (float("inf"), 4, "at least one tick"),
        (0.1, 0, "n_windows must be >= 1"),
        (1e300, 4, "no longer whole ticks"),  # the edges would overflow to inf
        (3600.0, 2**33, "no longer whole ticks"),
    ],
)
def test_windows_whose_edges_are_not_whole_ticks_are_refused(window_s, n_windows, message):
    with pytest.raises(ValueError, match=message):
        rate_code(np.array([0.5]), window_s, n_windows)


def test_the_longest_exact_windows_are_accepted():
    counts, dropped = rate_code(np.array([0.5, 3e9]), 3600.0, 2**53 // 3_600_000_000)
    assert int(counts.sum()) == 2 and dropped == 0


def test_counts_do_not_overflow():
    times = np.zeros(40_000_000)
    counts, _ = rate_code(times, 1.0, 1)
    assert counts[0] == 40_000_000  # beyond int16/uint16 and any 24-bit counter


times_strategy = hnp.arrays(
    np.float64, st.integers(0, 300), elements=st.floats(-1.0, 10.0, allow_nan=False)
)


@settings(max_examples=300, deadline=None)
@given(
    times=times_strategy,
    window=st.floats(1e-3, 2.0),
    n_windows=st.integers(1, 60),
)
def test_every_spike_is_counted_once_or_dropped(times, window, n_windows):
    counts, dropped = rate_code(times, window, n_windows)
    assert counts.sum() + dropped == len(times)
    assert np.all(counts >= 0)
    # Same bins as a reference search on the explicit edges.
    edges = window_edges_s(window, n_windows)
    k = np.searchsorted(edges, times, side="right") - 1
    inside = (k >= 0) & (k < n_windows)
    np.testing.assert_array_equal(counts, np.bincount(k[inside], minlength=n_windows))


def test_resolve_n_windows():
    assert resolve_n_windows(CodingSpec(window_s=0.1), np.array([4.9, 5.0])) == MAX_AUTO_WINDOWS
    assert resolve_n_windows(CodingSpec(window_s=0.1), np.array([1.05, 5.0])) == 10
    assert resolve_n_windows(CodingSpec(window_s=0.1, n_windows=7), np.array([1.0])) == 7
    with pytest.raises(SimulationError, match="coding.window_s: 2.0 s is longer"):
        resolve_n_windows(CodingSpec(window_s=2.0), np.array([1.0, 5.0]))
    with pytest.raises(SimulationError, match="coding.n_windows: 40 windows"):
        resolve_n_windows(CodingSpec(window_s=0.1, n_windows=40), np.array([2.0]))


def trains_of(per_train, n_taxels):
    trains = [(np.asarray(t, float), np.asarray(p, np.int8)) for t, p in per_train]
    n_rec = len(trains) // n_taxels
    return SpikeTrains.concatenate(trains, n_taxels, np.full(n_rec, 1.0))


def test_frames_shape_and_raster_order():
    trains = trains_of(
        [
            ([0.05, 0.15], [1, -1]),
            ([], []),
            ([0.25], [1]),
            ([0.05, 0.06, 0.31], [-1, -1, 1]),
        ],
        n_taxels=2,
    )
    merged, dropped = frames(trains, 0.1, 3)
    assert merged.shape == (2, 1, 2, 3) and merged.dtype == np.int64
    np.testing.assert_array_equal(merged[0, 0], [[1, 1, 0], [0, 0, 0]])
    np.testing.assert_array_equal(merged[1, 0], [[0, 0, 1], [2, 0, 0]])
    np.testing.assert_array_equal(dropped, [[0, 0], [0, 1]])
    split, _ = frames(trains, 0.1, 3, Polarity.SPLIT)
    assert split.shape == (2, 2, 2, 3)
    np.testing.assert_array_equal(split.sum(axis=1), merged[:, 0])
    np.testing.assert_array_equal(split[1, 1, 1], [2, 0, 0])  # the -1 spikes of taxel 1


@settings(max_examples=50, deadline=None)
@given(
    per_train=st.lists(
        st.lists(st.floats(0.0, 1.5), max_size=30).map(sorted), min_size=2, max_size=8
    ).filter(lambda x: len(x) % 2 == 0)
)
def test_frames_equal_rate_code_per_train(per_train):
    trains = trains_of([(t, np.ones(len(t))) for t in per_train], n_taxels=2)
    merged, dropped = frames(trains, 0.1, 10)
    for index, times in enumerate(per_train):
        counts, lost = rate_code(np.array(times), 0.1, 10)
        np.testing.assert_array_equal(merged[index // 2, 0, index % 2], counts)
        assert dropped[index // 2, index % 2] == lost
