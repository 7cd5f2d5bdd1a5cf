"""Reading and writing single entries of the built-in stored levels, for tests (the sweep
reads and writes entries in batches, through the stage registry's record declarations)."""

from typing import Any

from pipeline.run.entries import ResultEntry, SpikeEntry
from pipeline.run.records import Record
from pipeline.run.stages import RESULTS, SPIKES
from storage import StoreError, SweepStore


def write_spikes(store: SweepStore, key: str, entry: SpikeEntry) -> None:
    """Store one spike entry, as a batch of its own."""
    store.write_entries(SPIKES.record, {key: entry})


def write_result(store: SweepStore, key: str, entry: ResultEntry) -> None:
    """Store one result entry, as a batch of its own."""
    store.write_entries(RESULTS.record, {key: entry})


def read_spikes(store: SweepStore, key: str) -> SpikeEntry:
    return read_one(store, SPIKES.record, key)


def read_result(store: SweepStore, key: str) -> ResultEntry:
    return read_one(store, RESULTS.record, key)


def peek_result(store: SweepStore, key: str) -> ResultEntry | None:
    """The result entry ``key`` if complete and valid, else None; writes nothing."""
    return store.peek_many(RESULTS.record, [key]).get(key)


def read_one(store: SweepStore, kind: Record, key: str) -> Any:
    """The entry ``kind/key``; StoreError if absent, CorruptEntryError if corrupt."""
    found = store.read_many(kind, [key], discard_corrupt=False)
    if key not in found:
        raise StoreError(f"no {kind.name} entry {key} in {store.root}")
    return found[key]
