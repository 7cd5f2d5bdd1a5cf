"""Sweep store: cached stage outputs and result cubes of a run root (see :mod:`storage.store`)."""

from storage.store import (
    CorruptEntryError,
    StoreBusyError,
    StoreError,
    StoreLayoutError,
    StoreWriteError,
    SweepStore,
    open_results,
    replace_folder,
)
from storage.tree import open_tree

__all__ = [
    "CorruptEntryError",
    "StoreBusyError",
    "StoreError",
    "StoreLayoutError",
    "StoreWriteError",
    "SweepStore",
    "open_results",
    "open_tree",
    "replace_folder",
]
