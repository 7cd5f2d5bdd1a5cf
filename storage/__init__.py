"""Persistence: the sweep store of a run root, its cached stage outputs and its result cubes.

The package owns every byte a run writes or reads back (Zarr v3 groups written through xarray,
checksums, atomic swaps, the sweep lock, the run log, a search's journal, the report folder) on
a folder or an ``s3://`` root, and knows no science: a kind of entry comes with its declaration
from whoever computes it (:mod:`storage.codec`). The layout and its guarantees are in
:mod:`storage.store`.

It exports :class:`~storage.store.SweepStore`, :func:`~storage.store.open_results` and
:func:`~storage.tree.open_tree` (the result cubes of a run root, as a dict or as one
``xarray.DataTree``), :func:`~storage.cube_files.replace_folder` (a folder swapped in whole),
and the store's errors (:class:`~storage.errors.StoreError`,
:class:`~storage.errors.StoreBusyError`, :class:`~storage.errors.StoreWriteError`,
:class:`~storage.errors.CorruptEntryError`, :class:`~storage.errors.StoreLayoutError`), each
documented in the module that defines it.
"""

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
