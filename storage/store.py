"""The sweep store: cached stage outputs and result cubes of one run root, in one Zarr v3 store.

On-disk layout (every node is a Zarr v3 group or array, written and read through xarray)::

    <root>/                             the run root; may also hold our own .state/, ...
      store.lock                        the sweep lock (see :meth:`SweepStore.lock`)
      store.zarr/                       group, attrs {"eskin_sweep_store": 2} (the layout)
        spikes/batch-<hex>/             a batch of SpikeEntry (keys: pipeline.scene.cache_key)
        results/batch-<hex>/            a batch of ResultEntry
        cubes/<name>/                   one result cube (name: [A-Za-z0-9_-]{1,64})
        <kind>/.partial-batch-<hex>/    a batch being written (or abandoned); never read
      store.zarr-layout-1-<time>/       a store of an older layout, set aside (never read)

A batch (:mod:`storage.batches`) holds the entries one task wrote at once, stacked variable by
variable, with their keys, attributes and shapes in its group attributes: its files grow with
its variables, not with its entries, so a sweep of 10,000 cheap points writes well under one
file per point instead of about sixty. Rate matrices are not kept (see
:mod:`pipeline.stages`: coding a point's trains takes milliseconds).

Entry variables (entry-level dimension names in parentheses; all arrays little-endian)

spike entry
    ``true_times_s`` float64 (true_event) s, ``true_polarity`` int8 (true_event) +-1,
    ``true_start``/``true_count`` int64 (recording, taxel): train ``(r, t)`` is
    ``true_times_s[true_start[r, t] : true_start[r, t] + true_count[r, t]]``; the same four
    with ``real_`` on ``real_event`` unless attrs ``ideal`` is true (ideal readout: REAL *is*
    TRUE, stored once, and reading gives an :class:`~pipeline.simulate.Encoded` whose
    ``real is true``); ``duration_s`` float64 (recording) s, shared by TRUE and REAL;
    ``metrics`` float64 (metric), one value per :class:`~pipeline.metrics.SpikeMetrics` field
    in its order (names and units in the variable's attrs), because those may be +-inf or
    NaN, which JSON attributes cannot hold.
result entry
    ``accuracy`` float64 (model, repeat, fold) with the strings ``model``; where the writer kept
    them, the out-of-fold predictions: ``predicted`` int64 (model, repeat, recording),
    ``test_fold`` int64 (repeat, recording), ``labels`` int64 (recording) and the strings
    ``recording`` (names); and ``metrics`` as for spikes. Attrs ``dataset_name`` (str),
    ``class_names`` (list of str) and ``sampling_rate_hz`` (float) where the writer stated
    them (a fact not stated is never guessed on reading).
``cubes/<name>``
    any xarray Dataset, as the caller built it (:mod:`pipeline.cube` describes the result
    cubes); every chunk carries a CRC-32C.

Every entry's attrs hold ``seconds`` (stage name -> wall seconds, finite floats). A batch's
attrs hold ``sha256``: one hex digest per stored array, over its dtype, shape and raw bytes,
plus ``"@entries"`` over the canonical JSON of its entry list. Cubes carry ``eskin_sha256``
(digests of their variables; NaN payloads are canonicalized because xarray's CF decoding of
cubes rewrites them), removed again on reading.

Why this design
---------------
* **Consolidated metadata is off everywhere** (``consolidated=False`` on every ``to_zarr`` and
  ``open_zarr``): many independent workers add batches concurrently, and consolidation keeps
  one copy of all metadata at the root that every addition would have to rewrite globally (a
  read-modify-write race between workers, and stale metadata for readers in between).
* **Completeness by rename.** A batch is written in full under ``.partial-batch-<uuid4 hex>``
  beside its final place and then renamed to ``batch-<same hex>`` (one ``os.rename`` of a
  directory, atomic within a file system), so a killed worker never leaves an entry that
  :meth:`SweepStore.has` reports. Batch names are unique, so writers never race for a name;
  two workers that made the same key store it twice (equal keys mean equal content) and
  readers take either copy. Nothing is fsynced, so this protects against killed processes,
  not power loss; a torn batch after a power loss fails its checksum on reading instead
  (:class:`CorruptEntryError`) and is discarded (all its entries) and recomputed.
* **Listing by metadata.** Which keys a kind holds is one directory listing plus, per batch
  not seen before, one read of its small ``zarr.json`` (batches never change once in place,
  so a process remembers their keys).
* **One sweep per root.** :meth:`SweepStore.lock` takes an exclusive ``fcntl.flock`` on
  ``<root>/store.lock`` for a sweep's whole life. The kernel drops the lock when its process
  ends, however it ends (SIGKILL included), so a killed sweep never blocks the next one, and
  the next one may then remove every partial batch (:meth:`SweepStore.clean_partials`): no
  other writer of that root can be running. ``flock`` is advisory and, on network file
  systems, only as good as the file system's support for it.
* **Old layouts are never misread.** A store of layout 1 (one group per entry) is set aside
  whole by the next sweep of its root, which then computes every point again; nothing reads
  it as if it were of this layout.
* **Exact round trips.** Batches are written with ``write_empty_chunks=True`` (otherwise a
  chunk equal to the fill value, e.g. all ``-0.0`` or a NaN with another payload, would not be
  written and would read back as the canonical fill value) and read with ``decode_cf=False``
  (no masking of fill values). Strings are stored as Zarr's variable-length ``string`` type
  (specified in v3, unlike fixed-width ``<U``) and read back as numpy ``<U`` arrays.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import enum
import errno
import fcntl
import json
import math
import os
import re
import shutil
import socket
import tempfile
import threading
import time
import uuid
import warnings
from collections import OrderedDict
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
import zarr
from zarr.codecs import Crc32cCodec, ZstdCodec

from pipeline.cube import OutOfFold, RecordingsInfo
from pipeline.errors import EskinError
from pipeline.metrics import SpikeMetrics
from pipeline.spikes import Encoded, SpikeTrains, train_starts
from pipeline.stages import LEVELS
from storage.batches import (
    BATCH_PREFIX,
    Record,
    Variables,
    digest,
    read_batch,
    read_batch_keys,
    write_batch,
)

__all__ = [
    "CorruptEntryError",
    "EntryKind",
    "ResultEntry",
    "SpikeEntry",
    "StoreBusyError",
    "StoreError",
    "StoreLayoutError",
    "SweepStore",
    "open_results",
    "replace_folder",
]

STORE_NAME = "store.zarr"
LOCK_NAME = "store.lock"
MARKER = "eskin_sweep_store"
#: The store layout this code writes and reads: 2 stores entries in batches
#: (:mod:`storage.batches`); 1 stored one group per entry.
VERSION = 2
# A store of an older layout is kept beside the new one under this name (plus a suffix).
OLD_STORE_PREFIX = "store.zarr-layout-"
CUBES = "cubes"
PARTIAL_PREFIX = ".partial-"
# A new store is built here (inside the root, so the final rename stays on one file system).
STORE_PARTIAL_PREFIX = ".store.zarr-partial-"
CUBE_DIGESTS = "eskin_sha256"

_KEY = re.compile(r"[0-9a-f]{32}")
_BATCH = re.compile(BATCH_PREFIX + r"[0-9a-f]{32}")
_CUBE_NAME = re.compile(r"[A-Za-z0-9_-]{1,64}")
_METRICS = tuple(f.name for f in dataclasses.fields(SpikeMetrics))
_TO_ZARR = {"consolidated": False, "zarr_format": 3, "write_empty_chunks": True}
_OPEN_ZARR = {"consolidated": False, "zarr_format": 3}


class StoreError(EskinError):
    """A run root is not (or cannot become) a sweep store, or an entry is missing.

    The message is one line naming the root and, where there is one, the entry.
    """


class CorruptEntryError(StoreError):
    """An entry's data fails its checksum or cannot be read; discard and recompute it."""


class StoreLayoutError(StoreError):
    """The run root's store was written in an older layout, which this version does not read.

    ``layout`` is that store's layout number.
    """

    def __init__(self, message: str, layout: int):
        super().__init__(message)
        self.layout = layout


class StoreBusyError(StoreError):
    """Another sweep holds the run root's lock."""


#: Kinds of cached entries: one per stored level of :data:`pipeline.stages.LEVELS`, in its
#: order (``SPIKES``, ``RATES``, ``RESULTS``); the value is the level's name, which names the
#: kind's group.
EntryKind = enum.StrEnum(
    "EntryKind",
    [(level.name.upper(), level.name) for level in LEVELS if level.stored],
    module=__name__,
)


@dataclass(frozen=True, eq=False)
class SpikeEntry:
    """Cached output of the readout and metrics stages.

    Attributes
    ----------
    encoded : Encoded
        TRUE and REAL trains; ``encoded.real is encoded.true`` for an ideal readout (kept so).
        Both share ``duration_s`` float64 (n_recordings,) s.
    metrics : SpikeMetrics
        Scene-level metrics; any field may be +-inf or NaN and round trips bit for bit.
    seconds : dict[str, float]
        Wall seconds per stage (finite), e.g. ``{"taxels": 1.0, "readout": 2.5}``.
    """

    encoded: Encoded
    metrics: SpikeMetrics
    seconds: dict[str, float]


@dataclass(frozen=True, eq=False)
class ResultEntry:
    """Everything a result cube needs of one point: accuracy, spike metrics, stage seconds.

    Attributes
    ----------
    fold_accuracy : dict[str, np.ndarray]
        Model name (e.g. ``"ffnn"``) -> float64 (repeats, folds) accuracy in [0, 1] (a 1-D
        ``(folds,)`` array is one repeat); every model has the same shape; insertion order is
        kept.
    seconds : dict[str, float]
        Wall seconds of every stage of the point (finite), as measured when each was computed,
        e.g. ``{"load": 0.3, ..., "coding": 0.01, "train_ffnn": 1.2, "train_cnn": 5.0}``.
    metrics : SpikeMetrics
        The point's spike metrics (copied from its spike entry, so a cube reads results only).
    recordings : RecordingsInfo or None
        What the point was computed on (dataset name, class names, sampling rate), for the
        cube's attributes; None in entries written before results stated it.
    out_of_fold : OutOfFold or None
        Every recording's out-of-fold prediction per model and repeat (models as in
        ``fold_accuracy``), for paired comparisons; None in entries written before results kept
        them.
    """

    fold_accuracy: dict[str, np.ndarray]
    seconds: dict[str, float]
    metrics: SpikeMetrics
    recordings: RecordingsInfo | None = None
    out_of_fold: OutOfFold | None = None


class SweepStore:
    """One run root's sweep store; see the module docstring for the layout.

    Build it with :meth:`open_or_create` or :meth:`open`, not the constructor (which checks
    nothing). The object holds only paths, so it pickles cheaply to Dask workers; every method
    opens what it needs and closes it again.

    Attributes
    ----------
    root : Path
        The run root; the Zarr store is ``root / "store.zarr"``.
    """

    def __init__(self, root: Path):
        self.root = Path(root)

    def __repr__(self) -> str:
        return f"SweepStore({str(self.root)!r})"

    @property
    def path(self) -> Path:
        """The Zarr store, ``root / "store.zarr"``."""
        return self.root / STORE_NAME

    # -----------------------------------------------------------------------------------------
    # Opening

    @classmethod
    def open_or_create(cls, root: str | Path) -> SweepStore:
        """Open the sweep store at ``root``, creating it if ``root`` is missing or empty.

        ``root`` is acceptable when it does not exist (it is created, parents too), is an empty
        directory, or contains ``store.zarr`` carrying the sweep-store marker (other files beside
        it, e.g. ``.prefect/`` or ``logs/``, are fine then). Leftovers of our own interrupted
        store creation (``.store.zarr-partial-*``) do not count as contents. Everything else is
        refused before anything is written: a file, a non-empty directory without
        ``store.zarr``, a foreign ``store.zarr``, or a directory we cannot write to.

        Raises
        ------
        StoreError
            ``root`` is refused; the message says why.
        """
        root = Path(root)
        if root.exists() or root.is_symlink():
            try:
                _check_store_root(root, need_store=False)
            except StoreLayoutError as error:
                _check_writable(root)
                _set_aside(root, error)
        else:
            try:
                root.mkdir(parents=True, exist_ok=True)
            except OSError as error:
                raise StoreError(f"cannot create run root {root}: {_one_line(error)}") from error
        _check_writable(root)
        store = cls(root)
        if not store.path.exists():
            store._create()
        else:
            store._add_missing_kind_groups()
        return store

    @classmethod
    def open(cls, root: str | Path) -> SweepStore:
        """Open an existing sweep store without writing anything (``root`` may be read-only).

        Raises
        ------
        StoreError
            ``root`` is missing, not a directory, or holds no ``store.zarr`` with the marker.
        """
        root = Path(root)
        if not root.exists():
            raise StoreError(f"not a sweep store: {root} does not exist")
        _check_store_root(root, need_store=True)
        return cls(root)

    @classmethod
    def open_readonly(cls, root: str | Path) -> SweepStore | None:
        """The sweep store at ``root`` to read only, or None where a sweep would create one.

        Writes nothing, not even ``root``: use it to look at a run root without touching it
        (read entries with :meth:`peek_result`, never :meth:`read_valid`, which discards
        corrupt ones).

        Returns
        -------
        SweepStore or None
            None if ``root`` does not exist or is a directory without ``store.zarr`` that
            :meth:`open_or_create` would accept (empty, or only leftovers of an interrupted
            store creation), or holds a store of an older layout (a sweep sets it aside and
            computes everything again): nothing usable is cached there.

        Raises
        ------
        StoreError
            ``root`` is one that :meth:`open_or_create` refuses: a file, a non-empty directory
            without ``store.zarr``, a foreign or unreadable ``store.zarr``.
        """
        root = Path(root)
        if not root.exists() and not root.is_symlink():
            return None
        try:
            _check_store_root(root, need_store=False)
        except StoreLayoutError:
            return None
        if not (root / STORE_NAME).exists():
            return None
        return cls(root)

    def _create(self) -> None:
        """Build the store under a temporary name in ``root`` and rename it into place."""
        partial = self.root / f"{STORE_PARTIAL_PREFIX}{uuid.uuid4().hex}"
        try:
            group = zarr.open_group(
                zarr.storage.LocalStore(partial),
                mode="w-",
                zarr_format=3,
                attributes={MARKER: VERSION},
            )
            for name in _group_names():
                group.create_group(name)
            try:
                os.rename(partial, self.path)
            except OSError as error:
                # Another process created the store first: use theirs (checked below).
                if error.errno not in (errno.EEXIST, errno.ENOTEMPTY):
                    raise
        finally:
            shutil.rmtree(partial, ignore_errors=True)
        _check_store_root(self.root, need_store=True)

    def _add_missing_kind_groups(self) -> None:
        # Stores are created complete; this only repairs a kind group someone deleted.
        for name in _group_names():
            if not (self.path / name / "zarr.json").is_file():
                zarr.open_group(zarr.storage.LocalStore(self.path / name), mode="a", zarr_format=3)

    # -----------------------------------------------------------------------------------------
    # The sweep lock

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the root's exclusive sweep lock for the ``with`` block; refuse if taken.

        The lock is ``fcntl.flock(LOCK_EX | LOCK_NB)`` on ``<root>/store.lock``, which then holds
        the holder's PID and host (for the message a refused sweep prints). The kernel releases
        it when the holding process ends, even by SIGKILL. Taking it again in the process that
        holds it (the command line, then the flow it runs) nests: only the outermost release
        unlocks. File descriptors are not inherited by child processes (Python opens them
        non-inheritable), so a Dask worker or server left behind never keeps a root locked.

        Raises
        ------
        StoreBusyError
            Another process holds the lock; the message names the root and the holder's PID.
        """
        path = self.root / LOCK_NAME
        name = str(path.resolve())
        with _LOCKS_GUARD:
            held = _LOCKS.get(name)
            if held is not None:
                held[1] += 1
            else:
                _LOCKS[name] = [_acquire(path, self.root), 1]
        try:
            yield
        finally:
            with _LOCKS_GUARD:
                held = _LOCKS[name]
                held[1] -= 1
                if held[1] == 0:
                    del _LOCKS[name]
                    os.close(held[0])  # closing the last descriptor releases the flock

    # -----------------------------------------------------------------------------------------
    # Entries

    def read_valid(self, kind: EntryKind | str, key: str) -> Any:
        """The entry ``kind/key``, or None if absent or corrupt (then discarded, with a warning).

        A corrupt batch (checksum mismatch, truncated or unreadable chunk) emits one
        ``RuntimeWarning`` naming it and is removed with every entry it holds, so that the
        caller recomputes what it needs.
        """
        return self.read_many(kind, [key], discard_corrupt=True).get(key)

    def read_many(
        self, kind: EntryKind | str, keys: Iterable[str], *, discard_corrupt: bool
    ) -> dict[str, Any]:
        """The stored entries of ``kind`` among ``keys``, reading each batch that holds one once.

        Keys the store does not hold are left out. A batch that fails its checksums or cannot be
        read is, with ``discard_corrupt``, removed (one ``RuntimeWarning`` naming it; its keys are
        left out, to be recomputed); without, it raises.

        Raises
        ------
        CorruptEntryError
            A batch is corrupt and ``discard_corrupt`` is false.
        """
        kind = EntryKind(kind)
        left = dict.fromkeys(_checked_key(kind, key) for key in keys)
        found: dict[str, Any] = {}
        tried: set[str] = set()
        # A key may sit in two batches (two tasks made it); when the one read first is corrupt
        # or gone, the next round reads the other.
        while left:
            index = self._index(kind)
            by_batch: dict[str, list[str]] = {}
            for key in left:
                if key in index and index[key] not in tried:
                    by_batch.setdefault(index[key], []).append(key)
            if not by_batch:
                break
            for batch, wanted in by_batch.items():
                tried.add(batch)
                try:
                    entries = self._read_batch(kind, batch)
                except CorruptEntryError as exc:
                    if not discard_corrupt:
                        raise
                    warnings.warn(f"{exc}; recomputing its entries", RuntimeWarning, stacklevel=2)
                    self._discard_batch(kind, batch)
                    continue
                except StoreError:  # removed since it was listed (another worker discarded it)
                    continue
                for key in wanted:
                    found[key] = entries[key]
                    del left[key]
        return found

    def peek_results(self, keys: Iterable[str]) -> dict[str, ResultEntry]:
        """The valid result entries among ``keys``; writes nothing.

        Unlike :meth:`read_many`, a corrupt batch is left where it is (the next sweep that holds
        the lock discards and recomputes it) and its keys are simply left out.
        """
        keys = [_checked_key(EntryKind.RESULTS, key) for key in keys]
        index = self._index(EntryKind.RESULTS)
        found: dict[str, ResultEntry] = {}
        for batch in {index[key] for key in keys if key in index}:
            try:
                found |= self._read_batch(EntryKind.RESULTS, batch)
            except (StoreError, OSError):
                continue
        return {key: found[key] for key in keys if key in found}

    def write_entry(self, kind: EntryKind | str, key: str, entry: Any) -> None:
        """Store one entry as a batch of its own (:meth:`write_entries`)."""
        self.write_entries(kind, {key: entry})

    def write_entries(self, kind: EntryKind | str, entries: Mapping[str, Any]) -> None:
        """Store ``entries`` (key -> entry of ``kind``) as one batch, complete or not at all.

        The batch is written under a partial name and renamed into place in one step, so a
        killed writer leaves nothing that :meth:`has` reports. A key stored before is stored
        again (the copies are equal: equal keys mean equal content).

        Raises
        ------
        TypeError
            An entry is not the entry type of ``kind``.
        ValueError
            An invalid key; or as :func:`_spike_record` and :func:`_result_record` raise.
        """
        kind = EntryKind(kind)
        entry_type, to_record = _RECORDS[kind][:2]
        records = []
        for key, entry in entries.items():
            _checked_key(kind, key)
            if not isinstance(entry, entry_type):
                raise TypeError(
                    f"a {kind} entry must be a {entry_type.__name__}, got {type(entry)}"
                )
            records.append(to_record(key, entry))
        if not records:
            return
        name = f"{BATCH_PREFIX}{uuid.uuid4().hex}"
        final = self.path / kind.value / name
        partial = final.parent / f"{PARTIAL_PREFIX}{name}"
        try:
            write_batch(partial, kind.value, records)
            os.rename(partial, final)
        finally:
            shutil.rmtree(partial, ignore_errors=True)

    def has(self, kind: EntryKind | str, key: str) -> bool:
        """True only if a complete entry ``kind/key`` exists (partial batches are invisible)."""
        kind = EntryKind(kind)
        return _checked_key(kind, key) in self._index(kind)

    def complete_keys(self, kind: EntryKind | str) -> frozenset[str]:
        """Keys of the complete entries of ``kind``, from one listing of its batches.

        Each batch's keys are read once per process from its group metadata (batches never
        change once written); partial batches and anything that is not a batch are left out.
        """
        return frozenset(self._index(EntryKind(kind)))

    def entry_location(self, kind: EntryKind | str, key: str) -> Path | None:
        """The batch folder that holds the entry ``kind/key``, or None if none does."""
        kind = EntryKind(kind)
        batch = self._index(kind).get(_checked_key(kind, key))
        return None if batch is None else self.path / kind.value / batch

    def discard(self, kind: EntryKind | str, key: str) -> bool:
        """Remove the entry ``kind/key`` (e.g. a corrupt one, to recompute it).

        Entries are stored in batches, so the whole batch that holds it goes (every batch, if
        two tasks stored it), with every other entry in it: they are recomputed when next
        needed. The batch is first renamed to a
        partial name, so :meth:`has` turns false at once and never sees a half-deleted batch.
        Returns whether there was an entry to remove.
        """
        kind = EntryKind(kind)
        _checked_key(kind, key)
        removed = False
        while (batch := self._index(kind).get(key)) is not None:  # every copy of it
            removed = self._discard_batch(kind, batch) or removed
        return removed

    def _discard_batch(self, kind: EntryKind, batch: str) -> bool:
        path = self.path / kind.value / batch
        doomed = path.parent / f"{PARTIAL_PREFIX}{batch}-{uuid.uuid4().hex}"
        try:
            os.rename(path, doomed)
        except FileNotFoundError:
            return False
        shutil.rmtree(doomed, ignore_errors=True)
        return True

    def clean_partials(self, *, older_than_s: float = 0.0) -> int:
        """Remove leftover partial batches, cubes and store builds, and batches whose metadata
        cannot be read; return how many.

        Parameters
        ----------
        older_than_s : float
            Only remove partials whose directory was last modified at least this many seconds
            ago. The default 0 removes every partial, including those of writers still running:
            use it only when no writer is active, else a threshold well above the longest write.
        """
        now = time.time()
        candidates = [p for p in self.root.glob(f"{STORE_PARTIAL_PREFIX}*") if p.is_dir()]
        for name in _group_names():
            folder = self.path / name
            if folder.is_dir():
                candidates += [p for p in folder.glob(f"{PARTIAL_PREFIX}*") if p.is_dir()]
        for kind in EntryKind:
            # A batch whose metadata cannot be read lists no entry: nothing would remove it.
            folder = self.path / kind.value
            if folder.is_dir():
                candidates += [
                    p
                    for p in folder.glob(f"{BATCH_PREFIX}*")
                    if _BATCH.fullmatch(p.name) and not _batch_keys(p)
                ]
        removed = 0
        for path in candidates:
            try:
                if now - path.stat().st_mtime < older_than_s:
                    continue
            except FileNotFoundError:  # finished or removed meanwhile
                continue
            shutil.rmtree(path, ignore_errors=True)
            removed += 1
        return removed

    def write_spikes(self, key: str, entry: SpikeEntry) -> None:
        """Store the spike trains and metrics of ``key`` (a batch of one; see the module
        docstring for its variables).

        Raises
        ------
        ValueError
            Inconsistent trains (counts not matching the event arrays, TRUE and REAL of different
            shapes or durations), values that do not fit the stored dtypes, non-finite seconds.
        """
        self.write_entries(EntryKind.SPIKES, {key: entry})

    def read_spikes(self, key: str) -> SpikeEntry:
        """The spike entry ``key``, bit for bit as written (``real is true`` if ideal).

        Raises
        ------
        StoreError
            No complete entry ``key``.
        CorruptEntryError
            Its batch fails its checksum or cannot be read.
        """
        return self._read_one(EntryKind.SPIKES, key)

    def write_result(self, key: str, entry: ResultEntry) -> None:
        """Store the per-fold accuracy of every model of ``key`` (a batch of one).

        Raises
        ------
        ValueError
            No model, models with different (repeats, folds) shapes, out-of-fold predictions
            that do not match the models and repeats, non-finite seconds.
        """
        self.write_entries(EntryKind.RESULTS, {key: entry})

    def read_result(self, key: str) -> ResultEntry:
        """The result entry ``key`` as written (models in their original order).

        Raises
        ------
        StoreError
            No complete entry ``key``.
        CorruptEntryError
            Its batch fails its checksum or cannot be read.
        """
        return self._read_one(EntryKind.RESULTS, key)

    def peek_result(self, key: str) -> ResultEntry | None:
        """The result entry ``key`` if it is complete and valid, else None; writes nothing
        (:meth:`peek_results` of one key)."""
        return self.peek_results([key]).get(key)

    def _read_one(self, kind: EntryKind, key: str) -> Any:
        found = self.read_many(kind, [key], discard_corrupt=False)
        if key not in found:
            raise StoreError(f"no {kind} entry {key} in {self.root}")
        return found[key]

    def _index(self, kind: EntryKind) -> dict[str, str]:
        """Key -> name of a complete batch holding it, from one listing of the kind's folder."""
        folder = self.path / kind.value
        try:
            with os.scandir(folder) as found:
                names = sorted(e.name for e in found if _BATCH.fullmatch(e.name))
        except FileNotFoundError:
            return {}
        index: dict[str, str] = {}
        for name in names:
            for key in _batch_keys(folder / name):
                index.setdefault(key, name)
        return index

    def _read_batch(self, kind: EntryKind, batch: str) -> dict[str, Any]:
        """Every entry of one batch, by key; any failure to read or verify it is corruption."""
        path = self.path / kind.value / batch
        keys = _batch_keys(path)
        shown = ", ".join(keys[:3]) + (f" and {len(keys) - 3} more" if len(keys) > 3 else "")
        where = f"{kind} batch {batch} (entries {shown or 'unknown'}) in {self.root}"
        if not (path / "zarr.json").is_file():
            raise StoreError(f"no {where}")
        from_record = _RECORDS[kind][2]
        try:
            return {record.key: from_record(record) for record in read_batch(path, kind.value)}
        except FileNotFoundError as error:
            raise StoreError(f"no {where} (removed while reading)") from error
        except Exception as error:
            raise CorruptEntryError(f"corrupt {where}: {_one_line(error)}") from error

    # -----------------------------------------------------------------------------------------
    # Cubes

    def write_cube(self, name: str, cube: xr.Dataset) -> None:
        """Store ``cube`` as ``cubes/<name>``, replacing an older cube of that name atomically.

        The new cube is written in full under a partial name, then swapped in with one
        ``renameat2(RENAME_EXCHANGE)`` (Linux), so the name always refers to a complete cube,
        old or new, never a mix; where the exchange is unavailable the old cube is moved aside
        first and the name is briefly missing. A reader in the middle of reading the old cube at
        the swap may fail (its files are then deleted) and should retry. The cube is computed
        first if it is Dask-backed, and its variables' encodings are dropped (a cube read from
        another store would otherwise carry that store's chunking and codecs); ``cube`` itself is
        not modified.

        Raises
        ------
        ValueError
            ``name`` is not ``[A-Za-z0-9_-]{1,64}``, or ``cube`` uses the reserved attribute
            ``eskin_sha256``.
        """
        path = self._cube_path(name)
        if not isinstance(cube, xr.Dataset):
            raise TypeError(f"cube {name!r}: expected an xarray.Dataset, got {type(cube)}")
        if CUBE_DIGESTS in cube.attrs:
            raise ValueError(f"cube {name!r}: attribute {CUBE_DIGESTS!r} is reserved")
        cube = cube.compute().drop_encoding()
        digests = {str(n): digest(v.values, canonical_nan=True) for n, v in cube.variables.items()}
        cube = _strings_to_objects(cube)
        cube.attrs = {**cube.attrs, CUBE_DIGESTS: digests}
        # Every chunk carries a CRC-32C, which Zarr checks on each read: a lazy reader, which
        # never reads a whole variable to check its sha256, still never reads a torn chunk.
        encoding = {str(n): {"compressors": (ZstdCodec(), Crc32cCodec())} for n in cube.variables}
        partial = path.parent / f"{PARTIAL_PREFIX}{name}-{uuid.uuid4().hex}"
        try:
            cube.to_zarr(str(partial), mode="w-", encoding=encoding, **_TO_ZARR)
            replace_folder(partial, path)
        finally:
            shutil.rmtree(partial, ignore_errors=True)

    def cube_names(self) -> list[str]:
        """Names of the stored cubes, sorted."""
        folder = self.path / CUBES
        if not folder.is_dir():
            return []
        return sorted(
            p.name
            for p in folder.iterdir()
            if _CUBE_NAME.fullmatch(p.name) and (p / "zarr.json").is_file()
        )

    def read_cube(self, name: str, *, lazy: bool = False) -> xr.Dataset:
        """The cube ``name``, string variables as ``<U``.

        Parameters
        ----------
        lazy
            False (default): loaded into memory and checked against its sha256 digests. True:
            its data variables are Dask arrays, read chunk by chunk when computed (for cubes
            larger than memory); each chunk is checked against its CRC-32C as it is read (a
            mismatch raises then), the whole-variable digests are not. Coordinates are loaded.

        Raises
        ------
        StoreError
            No cube ``name``.
        CorruptEntryError
            The cube fails its checksum or cannot be read (when loaded).
        """
        path = self._cube_path(name)
        if not (path / "zarr.json").is_file():
            raise StoreError(f"no cube {name!r} in {self.root}")
        where = f"cube {name} in {self.root}"
        try:
            if lazy:
                cube = _objects_to_strings(xr.open_zarr(str(path), **_OPEN_ZARR, chunks={}))
                cube.attrs.pop(CUBE_DIGESTS, None)
                return cube
            with xr.open_zarr(str(path), **_OPEN_ZARR, chunks=None) as opened:
                cube = _objects_to_strings(opened.load())
            digests = cube.attrs.pop(CUBE_DIGESTS)
            if not isinstance(digests, dict) or set(digests) != {str(n) for n in cube.variables}:
                raise CorruptEntryError(f"corrupt {where}: variables do not match its checksums")
            for var, variable in cube.variables.items():
                if digest(variable.values, canonical_nan=True) != digests[str(var)]:
                    raise CorruptEntryError(f"corrupt {where}: variable {var!r} fails its sha256")
        except StoreError:
            raise
        except Exception as error:
            raise CorruptEntryError(f"corrupt {where}: {_one_line(error)}") from error
        return cube

    # -----------------------------------------------------------------------------------------
    # Internals

    def _cube_path(self, name: str) -> Path:
        if not isinstance(name, str) or not _CUBE_NAME.fullmatch(name):
            raise ValueError(f"invalid cube name {name!r}: expected [A-Za-z0-9_-]{{1,64}}")
        return self.path / CUBES / name


def open_results(root: str | Path, *, lazy: bool = False) -> dict[str, xr.Dataset]:
    """Every result cube of the run root ``root``, by sweep name.

    Parameters
    ----------
    lazy
        False (default): loaded into memory and checked whole. True: Dask-backed, read chunk by
        chunk (each chunk checked as it is read) when computed: for cubes larger than memory,
        e.g. ``open_results(root, lazy=True)["grid"]["accuracy_mean"].max("threshold_v")``.

    Raises
    ------
    StoreError
        ``root`` is not a sweep store.
    CorruptEntryError
        A cube fails its checksum or cannot be read.
    """
    store = SweepStore.open(root)
    return {name: store.read_cube(name, lazy=lazy) for name in store.cube_names()}


def _checked_key(kind: EntryKind, key: str) -> str:
    if not isinstance(key, str) or not _KEY.fullmatch(key):
        raise ValueError(f"invalid {kind} key {key!r}: expected 32 lowercase hex characters")
    return key


# Keys of the batches this process has listed, by batch path. A batch never changes once
# renamed into place (and a removed one's name never comes back), so its keys are read once.
_BATCH_KEYS: OrderedDict[str, tuple[str, ...]] = OrderedDict()
_BATCH_KEYS_LIMIT = 100_000
_BATCH_KEYS_GUARD = threading.Lock()


def _batch_keys(path: Path) -> tuple[str, ...]:
    """The keys of the complete batch at ``path``; none if its metadata is unreadable."""
    name = str(path)
    with _BATCH_KEYS_GUARD:
        if name in _BATCH_KEYS:
            _BATCH_KEYS.move_to_end(name)
            return _BATCH_KEYS[name]
    try:
        keys = tuple(key for key in read_batch_keys(path) if _KEY.fullmatch(key))
    except (OSError, ValueError, KeyError, TypeError):
        # Unreadable metadata: its entries count as absent and are recomputed; reading the
        # batch would report it corrupt.
        return ()
    with _BATCH_KEYS_GUARD:
        _BATCH_KEYS[name] = keys
        while len(_BATCH_KEYS) > _BATCH_KEYS_LIMIT:
            _BATCH_KEYS.popitem(last=False)
    return keys


# ---------------------------------------------------------------------------------------------
# Locking

# Locks this process holds: resolved lock path -> [file descriptor, nesting depth].
_LOCKS: dict[str, list[int]] = {}
_LOCKS_GUARD = threading.Lock()


def _acquire(path: Path, root: Path) -> int:
    """Open ``path`` and take its exclusive flock without waiting; return the descriptor."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as error:
        raise StoreError(f"cannot open the lock of run root {root}: {_one_line(error)}") from error
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as error:
        os.close(fd)
        if error.errno not in (errno.EAGAIN, errno.EACCES):
            raise StoreError(f"cannot lock run root {root}: {_one_line(error)}") from error
        try:
            holder = path.read_text(encoding="utf-8").strip() or "unknown"
        except (OSError, UnicodeDecodeError):
            holder = "unknown"
        raise StoreBusyError(
            f"run root {root} is in use by another sweep (PID {holder[:80]}); wait for it to "
            "finish or give another --root"
        ) from None
    os.ftruncate(fd, 0)
    os.write(fd, f"{os.getpid()} on {socket.gethostname()}\n".encode())
    return fd


# ---------------------------------------------------------------------------------------------
# Root validation


def _group_names() -> tuple[str, ...]:
    return (*(kind.value for kind in EntryKind), CUBES)


def _check_store_root(root: Path, *, need_store: bool) -> None:
    """Refuse ``root`` unless it is a directory that is empty (if allowed) or a sweep store."""
    if not root.is_dir():
        what = "a file" if root.is_file() else "not a directory"
        raise StoreError(f"run root {root} is {what}")
    store = root / STORE_NAME
    if not store.exists():
        try:
            contents = [p.name for p in root.iterdir()]
        except OSError as error:
            raise StoreError(f"cannot list run root {root}: {_one_line(error)}") from error
        contents = [
            n for n in contents if not n.startswith((STORE_PARTIAL_PREFIX, OLD_STORE_PREFIX))
        ]
        if need_store:
            raise StoreError(f"not a sweep store: {root} has no {STORE_NAME}")
        if contents:
            shown = ", ".join(sorted(contents)[:3]) + (", ..." if len(contents) > 3 else "")
            raise StoreError(
                f"refusing run root {root}: not empty and holds no {STORE_NAME} ({shown})"
            )
        return
    metadata = store / "zarr.json"
    try:
        with open(metadata, encoding="utf-8") as file:
            meta = json.load(file)
    except (OSError, ValueError) as error:
        raise StoreError(
            f"not a sweep store: cannot read {metadata}: {_one_line(error)}"
        ) from error
    if (
        not isinstance(meta, dict)
        or meta.get("zarr_format") != 3
        or meta.get("node_type") != "group"
    ):
        raise StoreError(f"not a sweep store: {store} is not a Zarr v3 group")
    attributes = meta.get("attributes")
    version = attributes.get(MARKER) if isinstance(attributes, dict) else None
    if version is None:
        raise StoreError(f"not a sweep store: {store} lacks the {MARKER!r} marker (foreign store)")
    if isinstance(version, int) and not isinstance(version, bool) and 0 < version < VERSION:
        raise StoreLayoutError(
            f"{store} was written by an older eskin-sweep (store layout {version}) and is not "
            f"read: a sweep of run root {root} sets it aside as {OLD_STORE_PREFIX}{version}-* "
            "and computes its points again",
            version,
        )
    if version != VERSION:
        raise StoreError(f"unsupported sweep store version {version!r} in {store}")


def _set_aside(root: Path, reason: StoreLayoutError) -> None:
    """Move a store of an older layout out of the way (kept, never deleted), with a warning.

    Its entries cannot be read by this version, and reading them as if they could would give
    wrong results; the user keeps them (and their cubes) under the new name.
    """
    old = root / STORE_NAME
    kept = root / f"{OLD_STORE_PREFIX}{reason.layout}-{time.strftime('%Y%m%dT%H%M%S')}"
    try:
        os.rename(old, kept)
    except FileNotFoundError:  # another sweep set it aside first
        return
    except OSError as error:
        raise StoreError(f"cannot set aside {old}: {_one_line(error)}") from error
    warnings.warn(
        f"{old} was written by an older eskin-sweep in a layout this version does not read; "
        f"kept as {kept.name}, its points are computed again",
        RuntimeWarning,
        stacklevel=3,
    )


def _check_writable(root: Path) -> None:
    """Refuse a root we cannot write to, without leaving anything behind."""
    if not os.access(root, os.W_OK | os.X_OK):
        raise StoreError(f"run root {root} is not writable")
    # os.access says yes to root whatever the mode bits or mount flags (e.g. a read-only file
    # system), so also try it.
    try:
        fd, probe = tempfile.mkstemp(prefix=".eskin-probe-", dir=root)
    except OSError as error:
        raise StoreError(f"run root {root} is not writable: {_one_line(error)}") from error
    os.close(fd)
    os.unlink(probe)


# ---------------------------------------------------------------------------------------------
# Encoding helpers


def _cast(value: Any, dtype: type, what: str) -> np.ndarray:
    """``value`` as a contiguous little-endian ``dtype`` array.

    Refuses casts across kinds (float to int) and integer casts that change values.
    """
    array = np.asarray(value)
    target = np.dtype(dtype).newbyteorder("<")
    if not np.can_cast(array.dtype, target, "same_kind"):
        raise ValueError(f"{what}: cannot store {array.dtype} values as {target}")
    cast = np.asarray(array, dtype=target, order="C")  # keeps 0-d arrays 0-d
    if target.kind in "iu" and not np.array_equal(cast, array):
        raise ValueError(f"{what}: values do not fit {target}")
    return cast


def _spike_record(key: str, entry: SpikeEntry) -> Record:
    """A spike entry as a batch stores it, checked for consistency."""
    encoded = entry.encoded
    ideal = encoded.real is encoded.true
    variables = _train_variables("true", encoded.true)
    duration = _cast(encoded.true.duration_s, np.float64, "duration_s")
    n_recordings, _ = variables["true_count"][1].shape
    if duration.shape != (n_recordings,):
        raise ValueError(f"duration_s: shape {duration.shape}, expected ({n_recordings},)")
    if not ideal:
        variables |= _train_variables("real", encoded.real)
        if variables["real_count"][1].shape != variables["true_count"][1].shape:
            raise ValueError("REAL and TRUE trains differ in (recording, taxel) shape")
        real_duration = _cast(encoded.real.duration_s, np.float64, "real duration_s")
        if real_duration.tobytes() != duration.tobytes():
            raise ValueError("REAL and TRUE trains differ in duration_s")
    variables["duration_s"] = (("recording",), duration, {"units": "s"})
    variables |= _metric_variables(entry.metrics)
    return Record(key, variables, {"ideal": ideal, "seconds": _seconds(entry.seconds)})


def _spike_entry(record: Record) -> SpikeEntry:
    variables, attrs = record.variables, record.attrs
    duration = _variable(variables, "duration_s", ("recording",), np.float64)
    true = _read_trains(variables, "true", duration)
    ideal = attrs["ideal"]
    if not isinstance(ideal, bool):
        raise TypeError("attribute 'ideal' is not a bool")
    real = true if ideal else _read_trains(variables, "real", duration)
    return SpikeEntry(Encoded(true, real), _read_metrics(variables), _read_seconds(attrs))


def _result_record(key: str, entry: ResultEntry) -> Record:
    """A result entry as a batch stores it, checked for consistency."""
    if not entry.fold_accuracy:
        raise ValueError("fold_accuracy: no model")
    models = [str(model) for model in entry.fold_accuracy]
    rows = [
        np.atleast_2d(_cast(values, np.float64, f"fold_accuracy[{model!r}]"))
        for model, values in zip(models, entry.fold_accuracy.values(), strict=True)
    ]
    if any(row.ndim != 2 or row.shape != rows[0].shape for row in rows):
        shapes = {m: r.shape for m, r in zip(models, rows, strict=True)}
        raise ValueError(
            f"fold_accuracy: every model needs the same (repeats, folds) shape: {shapes}"
        )
    variables = {
        "accuracy": (("model", "repeat", "fold"), np.stack(rows), {"units": "1"}),
        "model": (("model",), np.array(models, dtype=object), {}),
        **_out_of_fold_variables(entry.out_of_fold, models, rows[0].shape[0]),
        **_metric_variables(entry.metrics),
    }
    attrs = {"seconds": _seconds(entry.seconds), **_recordings_attrs(entry.recordings)}
    return Record(key, variables, attrs)


def _result_entry(record: Record) -> ResultEntry:
    variables, attrs = record.variables, record.attrs
    accuracy = _variable(variables, "accuracy", ("model", "repeat", "fold"), np.float64)
    models = _strings(variables["model"][1]).tolist()
    if len(models) != accuracy.shape[0]:
        raise ValueError("model coordinate does not match accuracy")
    return ResultEntry(
        {m: accuracy[i] for i, m in enumerate(models)},
        _read_seconds(attrs),
        _read_metrics(variables),
        _read_recordings(attrs),
        _read_out_of_fold(variables, models),
    )


# Per kind: the entry type, how it becomes a batch record, how a record becomes it again.
_RECORDS: dict[EntryKind, tuple[type, Callable[[str, Any], Record], Callable[[Record], Any]]] = {
    EntryKind.SPIKES: (SpikeEntry, _spike_record, _spike_entry),
    EntryKind.RESULTS: (ResultEntry, _result_record, _result_entry),
}


def _train_variables(prefix: str, trains: SpikeTrains) -> Variables:
    """Flat variables of one set of ragged trains, checked for consistency."""
    times = _cast(trains.times_s, np.float64, f"{prefix} times_s")
    polarity = _cast(trains.polarity, np.int8, f"{prefix} polarity")
    count = _cast(trains.count, np.int64, f"{prefix} count")
    if count.ndim != 2:
        raise ValueError(f"{prefix} count: {count.ndim} dimensions, expected (recording, taxel)")
    if times.ndim != 1 or polarity.shape != times.shape:
        raise ValueError(f"{prefix} times_s and polarity must be 1-D of equal length")
    if (count < 0).any() or int(count.sum()) != times.size:
        raise ValueError(f"{prefix} count: must be >= 0 and sum to the {times.size} events")
    start = train_starts(count)
    event = f"{prefix}_event"
    return {
        f"{prefix}_times_s": ((event,), times, {"units": "s"}),
        f"{prefix}_polarity": ((event,), polarity, {}),
        f"{prefix}_start": (("recording", "taxel"), start, {}),
        f"{prefix}_count": (("recording", "taxel"), count, {}),
    }


def _read_trains(variables: Variables, prefix: str, duration: np.ndarray) -> SpikeTrains:
    event = (f"{prefix}_event",)
    times = _variable(variables, f"{prefix}_times_s", event, np.float64)
    polarity = _variable(variables, f"{prefix}_polarity", event, np.int8)
    count = _variable(variables, f"{prefix}_count", ("recording", "taxel"), np.int64)
    start = _variable(variables, f"{prefix}_start", ("recording", "taxel"), np.int64)
    flat = count.ravel()
    if (flat < 0).any() or int(flat.sum()) != times.size:
        raise ValueError(f"{prefix}_count does not match {prefix}_times_s")
    if not np.array_equal(start, train_starts(count)):
        raise ValueError(f"{prefix}_start is not the running sum of {prefix}_count")
    return SpikeTrains(times_s=times, polarity=polarity, count=count, duration_s=duration)


def _variable(variables: Variables, name: str, dims: tuple[str, ...], dtype: type) -> np.ndarray:
    """A stored variable's values, checked against the dims and dtype this module writes."""
    found_dims, values, _ = variables[name]
    if tuple(found_dims) != dims or values.dtype != np.dtype(dtype):
        raise TypeError(f"variable {name!r} is {values.dtype} {found_dims}, not {dims}")
    return np.asarray(values)


def _seconds(seconds: Mapping[str, float]) -> dict[str, float]:
    out = {str(stage): float(value) for stage, value in seconds.items()}
    bad = [stage for stage, value in out.items() if not math.isfinite(value)]
    if bad:
        raise ValueError(f"seconds: not finite for {bad} (JSON attributes cannot hold them)")
    return out


def _metric_variables(metrics: SpikeMetrics) -> Variables:
    """The metrics as one float64 variable on ``metric`` (attrs are JSON, which cannot hold
    +-inf): one array per batch rather than one per metric, each a file or two."""
    fields = dataclasses.fields(SpikeMetrics)
    values = np.array([_cast(getattr(metrics, f.name), np.float64, f.name) for f in fields])
    attrs = {
        "metric": [f.name for f in fields],
        "units": [f.metadata["units"] for f in fields],
        "long_name": [f.metadata["long_name"] for f in fields],
    }
    return {"metrics": (("metric",), values, attrs)}


def _read_metrics(variables: Variables) -> SpikeMetrics:
    values = _variable(variables, "metrics", ("metric",), np.float64)
    if values.shape != (len(_METRICS),):
        raise ValueError(f"metrics: {values.shape[0]} values, expected {len(_METRICS)}")
    return SpikeMetrics(*(float(value) for value in values))


def _out_of_fold_variables(
    out_of_fold: OutOfFold | None, models: list[str], repeats: int
) -> Variables:
    """The variables of a result's out-of-fold predictions; none when it kept none."""
    if out_of_fold is None:
        return {}
    if list(out_of_fold.predicted) != models:
        raise ValueError(
            f"out_of_fold: predictions of {list(out_of_fold.predicted)}, accuracy of {models}"
        )
    test_fold = _cast(out_of_fold.test_fold, np.int64, "out_of_fold.test_fold")
    if test_fold.shape[0] != repeats:
        raise ValueError(f"out_of_fold: {test_fold.shape[0]} repeats, accuracy has {repeats}")
    predicted = np.stack(
        [_cast(v, np.int64, f"predicted[{m!r}]") for m, v in out_of_fold.predicted.items()]
    )
    return {
        "predicted": (("model", "repeat", "recording"), predicted, {}),
        "test_fold": (("repeat", "recording"), test_fold, {}),
        "labels": (("recording",), _cast(out_of_fold.labels, np.int64, "out_of_fold.labels"), {}),
        "recording": (("recording",), np.array(out_of_fold.recording_names, dtype=object), {}),
    }


def _read_out_of_fold(variables: Variables, models: list[str]) -> OutOfFold | None:
    """The out-of-fold predictions of a result entry; None for an entry that kept none."""
    if "predicted" not in variables:
        return None
    predicted = _variable(variables, "predicted", ("model", "repeat", "recording"), np.int64)
    if predicted.shape[0] != len(models):
        raise ValueError("model coordinate does not match predicted")
    return OutOfFold(
        recording_names=tuple(_strings(variables["recording"][1]).tolist()),
        labels=_variable(variables, "labels", ("recording",), np.int64),
        predicted={m: predicted[i] for i, m in enumerate(models)},
        test_fold=_variable(variables, "test_fold", ("repeat", "recording"), np.int64),
    )


def _recordings_attrs(info: RecordingsInfo | None) -> dict[str, Any]:
    """A result's recordings facts as entry attributes; a fact not known is not written."""
    if info is None:
        return {}
    attrs: dict[str, Any] = {}
    if info.dataset_name is not None:
        attrs["dataset_name"] = str(info.dataset_name)
    if info.class_names is not None:
        names = list(info.class_names)
        if not all(isinstance(name, str) for name in names):
            raise ValueError("recordings.class_names: every name must be a str")
        attrs["class_names"] = names
    if info.sampling_rate_hz is not None:
        rate = float(info.sampling_rate_hz)
        if not (math.isfinite(rate) and rate > 0):
            raise ValueError(f"recordings.sampling_rate_hz: {rate!r} is not a rate > 0")
        attrs["sampling_rate_hz"] = rate
    return attrs


def _read_recordings(attrs: dict[str, Any]) -> RecordingsInfo | None:
    """The recordings facts of a result entry; None for an entry that states none (older)."""
    name, names, rate = (attrs.get(k) for k in ("dataset_name", "class_names", "sampling_rate_hz"))
    if name is None and names is None and rate is None:
        return None
    if name is not None and not isinstance(name, str):
        raise TypeError("attribute 'dataset_name' is not a str")
    if names is not None and (
        not isinstance(names, list) or not all(isinstance(n, str) for n in names)
    ):
        raise TypeError("attribute 'class_names' is not a list of str")
    if rate is not None and (isinstance(rate, bool) or not isinstance(rate, int | float)):
        raise TypeError("attribute 'sampling_rate_hz' is not a number")
    return RecordingsInfo(
        dataset_name=name,
        class_names=None if names is None else tuple(names),
        sampling_rate_hz=None if rate is None else float(rate),
    )


def _read_seconds(attrs: dict[str, Any]) -> dict[str, float]:
    seconds = attrs["seconds"]
    if not isinstance(seconds, dict):
        raise TypeError("attribute 'seconds' is not a mapping")
    return {str(stage): float(value) for stage, value in seconds.items()}


def _strings(values: np.ndarray) -> np.ndarray:
    """Object or StringDType strings as a numpy ``<U`` array."""
    return np.array([str(v) for v in np.asarray(values).ravel().tolist()], dtype=str).reshape(
        np.shape(values)
    )


def _strings_to_objects(ds: xr.Dataset) -> xr.Dataset:
    """``<U`` variables as object arrays, which Zarr v3 stores as its specified ``string`` type."""
    names = [name for name, v in ds.variables.items() if v.dtype.kind == "U"]
    return _convert(ds, names, lambda v: v.astype(object))


def _objects_to_strings(ds: xr.Dataset) -> xr.Dataset:
    """Read-back strings (StringDType or object) as ``<U``, the dtype cubes are built with."""
    names = [name for name, v in ds.variables.items() if v.dtype.kind in "OT"]
    return _convert(
        ds, names, lambda v: xr.Variable(v.dims, _strings(v.values), v.attrs, v.encoding)
    )


def _convert(
    ds: xr.Dataset, names: list[Any], convert: Callable[[xr.Variable], xr.Variable]
) -> xr.Dataset:
    coords = {n: convert(ds.variables[n]) for n in names if n in ds.coords}
    data = {n: convert(ds.variables[n]) for n in names if n not in ds.coords}
    return ds.assign_coords(coords).assign(data)


# ---------------------------------------------------------------------------------------------
# Filesystem helpers

_AT_FDCWD = -100
_RENAME_EXCHANGE = 2


def _renameat2() -> Callable[..., int] | None:
    """glibc's ``renameat2``, or None where it does not exist (not Linux, old glibc)."""
    try:
        return ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return None


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swap two directories; False where the platform cannot."""
    renameat2 = _renameat2()
    if renameat2 is None:
        return False
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):  # file system cannot exchange
        return False
    raise OSError(code, os.strerror(code), str(b))


def replace_folder(new: Path, final: Path) -> None:
    """Put directory ``new`` at ``final``, replacing what is there; ``new`` is gone afterwards.

    Readers of ``final`` see the old folder or the new one whole, never a mix: where Linux offers
    ``renameat2(RENAME_EXCHANGE)`` the two are swapped in one step, elsewhere the old folder is
    renamed aside first (a reader may then briefly find no folder). ``new`` and ``final`` must be
    on one file system.

    Raises
    ------
    OSError
        A rename failed (``final`` keeps its old folder where it had one).
    StoreError
        Concurrent writers of ``final`` kept replacing it (100 tries).
    """
    for _ in range(100):  # only concurrent writers of the same name make this loop
        if not final.exists():
            try:
                os.rename(new, final)
                return
            except OSError as error:
                if error.errno not in (errno.EEXIST, errno.ENOTEMPTY):
                    raise
                continue
        try:
            swapped = _exchange(new, final)
        except FileNotFoundError:  # final vanished between the check and the swap
            continue
        if swapped:
            shutil.rmtree(new, ignore_errors=True)  # now the old directory
            return
        # No atomic exchange: move the old one aside, then the new one in.
        old = final.parent / f"{PARTIAL_PREFIX}{final.name}-{uuid.uuid4().hex}"
        try:
            os.rename(final, old)
        except FileNotFoundError:
            continue
        try:
            os.rename(new, final)
        except OSError as error:
            if error.errno in (errno.EEXIST, errno.ENOTEMPTY):  # another writer's cube came in
                shutil.rmtree(old, ignore_errors=True)
                continue
            with contextlib.suppress(OSError):  # keep the old cube rather than none
                os.rename(old, final)
            raise
        shutil.rmtree(old, ignore_errors=True)
        return
    raise StoreError(f"could not replace {final}: too many concurrent writers")


def _one_line(error: BaseException) -> str:
    text = " ".join(str(error).split()) or type(error).__name__
    return f"{type(error).__name__}: {text}"
