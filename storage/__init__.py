"""Sweep store: cached stage outputs and result cubes of a run root (see :mod:`storage.store`)."""

from storage.store import (
    CorruptEntryError,
    EntryKind,
    RateEntry,
    ResultEntry,
    SpikeEntry,
    StoreBusyError,
    StoreError,
    SweepStore,
    open_results,
)

__all__ = [
    "CorruptEntryError",
    "EntryKind",
    "RateEntry",
    "ResultEntry",
    "SpikeEntry",
    "StoreBusyError",
    "StoreError",
    "SweepStore",
    "open_results",
]
