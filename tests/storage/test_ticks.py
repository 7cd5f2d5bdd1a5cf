"""Spike times kept as folded tick deltas (storage.codec): the stored bytes exactly, the round
trip bit for bit, refusals, and a store of the older layout (float64 times) refused or set aside
with one line."""

from __future__ import annotations

import json
import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import zarr

from pipeline.chain.metrics import SpikeMetrics
from pipeline.chain.spikes import TIME_RESOLUTION_S, Encoded, SpikeTrains
from pipeline.run.entries import SpikeEntry
from pipeline.run.stages import SPIKES
from storage import StoreLayoutError, SweepStore
from storage.codec import from_record, to_record
from tests.store_helpers import read_spikes, write_spikes

KEY = "0123456789abcdef0123456789abcdef"
US = TIME_RESOLUTION_S


def trains(ticks: list[list[int]], signs: list[list[int]], n_taxels: int) -> SpikeTrains:
    """Trains whose times are the given whole ticks."""
    return SpikeTrains.concatenate(
        [
            (np.array(t, np.int64) * US, np.array(s, np.int8))
            for t, s in zip(ticks, signs, strict=True)
        ],
        n_taxels,
        np.full(len(ticks) // n_taxels, 2.0),
    )


def entry(true: SpikeTrains) -> SpikeEntry:
    return SpikeEntry(Encoded(true, true), SpikeMetrics(*[0.5] * 6), {"readout": 1.0})


def test_stored_deltas_are_exactly_twice_the_gap_plus_the_rising_bit(tmp_path):
    # Three trains of 2 x 2 taxels... recording 1 taxel 0 empty: each train starts from 0.
    true = trains(
        [[0, 5, 5, 1_000_000], [3], [], [7, 2**31 - 1 + 7]],
        [[1, -1, 1, -1], [-1], [], [1, 1]],
        n_taxels=2,
    )
    store = SweepStore.open_or_create(tmp_path / "run")
    write_spikes(store, KEY, entry(true))
    batch = store.entry_location(SPIKES.record, KEY)
    stored = zarr.open_array(batch / "true_times_s", mode="r")[:]
    assert stored.dtype == np.dtype("<u4")
    assert stored.tolist() == [1, 10, 1, 1_999_990, 6, 15, 2 * (2**31 - 1) + 1]
    read = read_spikes(store, KEY)
    assert read.encoded.true.times_s.tobytes() == true.times_s.tobytes()
    assert read.encoded.true.polarity.tobytes() == true.polarity.tobytes()
    assert read.encoded.true.polarity.dtype == np.int8


def record_of(true: SpikeTrains):
    return to_record(SPIKES.record, KEY, entry(true))


@pytest.mark.parametrize(
    ("times", "polarity", "message"),
    [
        ([0.5 * US], [1], "not whole ticks"),
        ([-1 * US], [1], "not whole ticks"),
        ([2 * US, 1 * US], [1, 1], "decrease within a train"),
        ([0.0, 2**31 * US], [1, 1], "does not fit"),
        ([1 * US], [0], "other than -1 and \\+1"),
    ],
    ids=["half-tick", "negative", "decreasing", "gap", "sign"],
)
def test_times_that_are_not_ticks_are_refused(times, polarity, message):
    bad = SpikeTrains(
        np.array(times, np.float64),
        np.array(polarity, np.int8),
        np.array([[len(times)]], np.int64),
        np.array([1.0]),
    )
    with pytest.raises(ValueError, match=message):
        record_of(bad)


def test_round_trip_through_a_record_gives_the_same_times_bit_for_bit():
    rng = np.random.default_rng(3)
    counts = rng.integers(0, 40, 60)
    made = [
        (np.sort(rng.uniform(0.0, 4.0, n)), rng.choice(np.array([-1, 1], np.int8), n))
        for n in counts
    ]
    true = SpikeTrains.concatenate(made, 6, np.full(10, 4.0))
    record = record_of(true)
    assert "true_polarity" not in record.variables
    back = from_record(SPIKES.record, record)
    assert back.encoded.true.times_s.tobytes() == true.times_s.tobytes()
    assert back.encoded.true.polarity.tobytes() == true.polarity.tobytes()


def make_layout_2_store(root: Path) -> Path:
    """A store as layout 2 left it: the marker 2 and a batch of float64 spike times."""
    group = zarr.open_group(
        root / "store.zarr", mode="w", zarr_format=3, attributes={"eskin_sweep_store": 2}
    )
    group.create_group("cubes")
    batch = group.create_group("spikes").create_group(f"batch-{KEY}")
    batch.create_array("true_times_s", data=np.array([0.1, 0.25]))
    return root


def test_a_layout_2_store_is_refused_with_one_line_saying_how_to_rebuild(tmp_path):
    root = make_layout_2_store(tmp_path / "run")
    with pytest.raises(StoreLayoutError) as info:
        SweepStore.open(root)
    message = str(info.value)
    assert "\n" not in message and "store layout 2" in message
    assert f"a sweep of run root {root} sets it aside" in message
    assert info.value.layout == 2


def test_a_layout_2_store_is_set_aside_whole_and_a_new_one_made(tmp_path):
    root = make_layout_2_store(tmp_path / "run")
    with pytest.warns(RuntimeWarning, match="older eskin-sweep"):
        store = SweepStore.open_or_create(root)
    kept = [name for name in os.listdir(root) if name.startswith("store.zarr-layout-")]
    assert len(kept) == 1 and re.fullmatch(r"store\.zarr-layout-2-\d{8}T\d{6}", kept[0])
    old = zarr.open_array(root / kept[0] / "spikes" / f"batch-{KEY}" / "true_times_s", mode="r")
    assert old[:].tolist() == [0.1, 0.25]  # kept, untouched
    assert json.loads((store.path / "zarr.json").read_text())["attributes"] == {
        "eskin_sweep_store": 3
    }
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not SweepStore.open_or_create(root).has(SPIKES.record, KEY)
