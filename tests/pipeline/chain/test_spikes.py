"""Spike trains are whole ticks of the declared resolution where they are made."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from pipeline.chain.spikes import TIME_RESOLUTION_S, SpikeTrains, floor_ticks

seconds = st.floats(0.0, 1e4, allow_nan=False, allow_subnormal=True)


@given(st.lists(seconds, max_size=50))
def test_floor_ticks_is_the_last_tick_at_or_before_each_time(values):
    times = np.array(values, np.float64)
    ticks = floor_ticks(times)
    assert ticks.dtype == np.int64
    assert (ticks * TIME_RESOLUTION_S <= times).all()
    assert ((ticks + 1) * TIME_RESOLUTION_S > times).all()
    # A quantised time is its own tick: storing and re-making a train change nothing.
    np.testing.assert_array_equal(floor_ticks(ticks * TIME_RESOLUTION_S), ticks)


def test_concatenate_floors_every_time_to_its_microsecond():
    raw = np.array([0.0, 0.1234567891, 0.1234569999, 2.5])
    trains = SpikeTrains.concatenate(
        [(raw[:2], np.array([1, -1], np.int8)), (raw[2:], np.array([1, 1], np.int8))],
        2,
        np.array([3.0]),
    )
    expected = np.array([0, 123456, 123456, 2_500_000]) * TIME_RESOLUTION_S
    assert trains.times_s.tobytes() == expected.tobytes()
    assert trains.polarity.tolist() == [1, -1, 1, 1]
    assert trains.count.tolist() == [[2, 2]]
