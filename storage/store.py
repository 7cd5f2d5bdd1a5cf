"""The sweep store: cached stage outputs and result cubes of one run root, in one Zarr v3 store.

On-disk layout (every node is a Zarr v3 group or array, written and read through xarray)::

    <root>/                             the run root; may also hold our own .state/, ...
      store.lock                        the sweep lock (see :meth:`SweepStore.lock`)
      store.zarr/                       group, attrs {"eskin_sweep_store": 3} (the layout)
        <kind>/batch-<hex>/             a batch of entries of one kind (a stored level's name,
                                        e.g. spikes, results; keys: pipeline.run.stages.cache_key)
        cubes/<name>/                   one result cube (name: [A-Za-z0-9_-]{1,64}: a sweep's;
                                        <search>.trials, <search>.front: a search's)
        <kind>/.partial-batch-<hex>/    a batch being written (or abandoned); never read
      store.zarr-layout-2-<time>/       a store of an older layout, set aside (never read)

A batch (:mod:`storage.batches`) holds the entries one task wrote at once, stacked variable by
variable, with their keys, attributes and shapes in its group attributes: its files grow with
its variables, not with its entries, so a sweep of 10,000 cheap points writes well under one
file per point instead of about sixty. Rate matrices are not kept (see
:mod:`pipeline.run.stages`: coding a point's trains takes milliseconds).

Entry variables and attributes are whatever the kind's record declaration says (the stage
registry, :mod:`pipeline.run.stages`, declares them per stored level; :mod:`storage.codec` writes
and reads any declared record). ``cubes/<name>`` is any xarray Dataset, as the caller built it
(:mod:`pipeline.results.cube` describes the result cubes); every chunk carries a CRC-32C.

A batch's attrs hold ``sha256``: one hex digest per stored array, over its dtype, shape and raw
bytes, plus ``"@entries"`` over the canonical JSON of its entry list. Cubes carry
``eskin_sha256`` (:mod:`storage.cube_files`).

A run root may also be an object store's URL (``s3://bucket/prefix``): the same layout, with
the guarantees that rename and ``flock`` give here made of objects instead
(:mod:`storage.object_root`, :mod:`storage.lease`, through :mod:`storage.objects`).

Its jobs live in modules of their own: :mod:`storage.layout` (the root, opening, older
layouts), :mod:`storage.locking` (the sweep lock), :mod:`storage.index` (which keys a kind's
batches hold), :mod:`storage.batches` (a batch on disk), :mod:`storage.codec` (entries as
batch records, by their declaration) and :mod:`storage.cube_files` (cubes on disk); this module
joins them into :class:`SweepStore`.

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
  (:class:`storage.errors.CorruptEntryError`) and is discarded (all its entries) and recomputed.
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

import asyncio
import contextlib
import os
import re
import shutil
import time
import uuid
import warnings
from collections.abc import Iterable, Iterator, Mapping
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path
from typing import Any

import xarray as xr
from zarr.core import sync as zarr_sync

from storage import cube_files, index
from storage.batches import BATCH_PREFIX, read_batch, write_batch
from storage.codec import Declaration, from_record, to_record
from storage.cube_files import replace_folder
from storage.errors import (
    CorruptEntryError,
    StoreBusyError,
    StoreError,
    StoreLayoutError,
    StoreWriteError,
    one_line,
    write_failure,
)
from storage.layout import (
    CUBES,
    PARTIAL_PREFIX,
    STORE_NAME,
    STORE_PARTIAL_PREFIX,
    check_store_root,
    check_writable,
    create_store,
    ensure_group,
    set_aside,
)
from storage.lease import hold_lease
from storage.locking import hold_lock
from storage.object_root import ObjectRoot
from storage.objects import is_object_url, objects_for, run_root
from storage.search_log import named_search_cubes

__all__ = [
    "CorruptEntryError",
    "StoreBusyError",
    "StoreError",
    "StoreLayoutError",
    "StoreWriteError",
    "SweepStore",
    "open_results",
    "replace_folder",
]

#: A kind of entry: its declaration, or (to list, test or remove entries) just its name.
Kind = Declaration | str
_KIND = re.compile(r"[a-z][a-z0-9_]{0,63}")


class SweepStore:
    """One run root's sweep store; see the module docstring for the layout.

    Build it with :meth:`open_or_create` or :meth:`open`, not the constructor (which checks
    nothing). The object holds only paths, so it pickles cheaply to Dask workers; every method
    opens what it needs and closes it again. A kind of entry is given by its record declaration
    (:mod:`storage.codec`) to read or write entries, or by its name to list, test or remove them.

    Attributes
    ----------
    root : pathlib.Path or str
        The run root, a folder or an object root's URL (``s3://bucket/prefix``,
        :mod:`storage.object_root`); the Zarr store is ``root / "store.zarr"``.
    """

    def __init__(self, root: str | Path):
        self.root = run_root(root)
        self._objects = ObjectRoot(objects_for(self.root)) if is_object_url(self.root) else None

    def __repr__(self) -> str:
        return f"SweepStore({str(self.root)!r})"

    @property
    def path(self) -> Path:
        """The Zarr store of a folder root, ``root / "store.zarr"``."""
        if isinstance(self.root, str):
            raise TypeError(f"the object root {self.root} has no path")
        return self.root / STORE_NAME

    def identity(self) -> str:
        """The root as one string naming it wherever it is read: an object root's URL, a folder
        root's resolved absolute path."""
        return self.root if isinstance(self.root, str) else str(self.root.resolve())

    def cube_location(self, name: str) -> str:
        """Where the cube ``name`` is stored (a folder, or the URL of its prefix)."""
        if isinstance(self.root, str):
            return f"{self.root}/{STORE_NAME}/{CUBES}/{name}"
        return str(self.path / CUBES / name)

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

        An object root (``s3://...``) is acceptable when it holds no object or a sweep store.

        Raises
        ------
        StoreError
            ``root`` is refused; the message says why.
        """
        if is_object_url(root):
            store = cls(root)
            if not store._objects.has_store():
                store._objects.create()
            return store
        root = Path(root)
        if root.exists() or root.is_symlink():
            try:
                check_store_root(root, need_store=False)
            except StoreLayoutError as error:
                check_writable(root)
                set_aside(root, error)
        else:
            try:
                root.mkdir(parents=True, exist_ok=True)
            except OSError as error:
                raise StoreError(f"cannot create run root {root}: {one_line(error)}") from error
        check_writable(root)
        store = cls(root)
        if not store.path.exists():
            create_store(root)
        else:
            ensure_group(store.path / CUBES)  # only repairs a cubes group someone deleted
        return store

    @classmethod
    def open(cls, root: str | Path) -> SweepStore:
        """Open an existing sweep store without writing anything (``root`` may be read-only).

        Raises
        ------
        StoreError
            ``root`` is missing, not a directory, or holds no ``store.zarr`` with the marker.
        """
        if is_object_url(root):
            store = cls(root)
            if not store._objects.has_store():
                raise StoreError(f"not a sweep store: {store.root} holds nothing")
            return store
        root = Path(root)
        if not root.exists():
            raise StoreError(f"not a sweep store: {root} does not exist")
        check_store_root(root, need_store=True)
        return cls(root)

    @classmethod
    def open_readonly(cls, root: str | Path) -> SweepStore | None:
        """The sweep store at ``root`` to read only, or None where a sweep would create one.

        Writes nothing, not even ``root``: use it to look at a run root without touching it
        (read entries with :meth:`peek_many`, never :meth:`read_valid`, which discards corrupt
        ones).

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
        if is_object_url(root):
            store = cls(root)
            return store if store._objects.has_store() else None
        root = Path(root)
        if not root.exists() and not root.is_symlink():
            return None
        try:
            check_store_root(root, need_store=False)
        except StoreLayoutError:
            return None
        if not (root / STORE_NAME).exists():
            return None
        return cls(root)

    def lock(self) -> AbstractContextManager[None]:
        """Hold the root's exclusive sweep lock for the ``with`` block; refuse if taken.

        The lock is ``fcntl.flock(LOCK_EX | LOCK_NB)`` on ``<root>/store.lock``, which then holds
        the holder's PID and host (for the message a refused sweep prints). The kernel releases
        it when the holding process ends, even by SIGKILL. Taking it again in the process that
        holds it (the command line, then the flow it runs) nests: only the outermost release
        unlocks. File descriptors are not inherited by child processes (Python opens them
        non-inheritable), so a Dask worker or server left behind never keeps a root locked.

        On an object root the lock is a lease object instead (:mod:`storage.lease`), which
        expires when its holder stops renewing it.

        Raises
        ------
        StoreBusyError
            Another process holds the lock; the message names the root and the holder's PID.
        """
        if self._objects is not None:
            return hold_lease(self._objects.objects)
        return hold_lock(self.root)

    # -----------------------------------------------------------------------------------------
    # Entries

    def read_valid(self, kind: Declaration, key: str) -> Any:
        """The entry ``kind/key``, or None if absent or corrupt (then discarded, with a warning).

        A corrupt batch (checksum mismatch, truncated or unreadable chunk) emits one
        ``RuntimeWarning`` naming it and is removed with every entry it holds, so that the
        caller recomputes what it needs.
        """
        return self.read_many(kind, [key], discard_corrupt=True).get(key)

    def read_many(
        self, kind: Declaration, keys: Iterable[str], *, discard_corrupt: bool
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
        name = _kind_name(kind)
        left = dict.fromkeys(index.checked_key(name, key) for key in keys)
        found: dict[str, Any] = {}
        tried: set[str] = set()
        # A key may sit in two batches (two tasks made it); when the one read first is corrupt
        # or gone, the next round reads the other.
        while left:
            listed = self._index(name)
            by_batch: dict[str, list[str]] = {}
            for key in left:
                if key in listed and listed[key] not in tried:
                    by_batch.setdefault(listed[key], []).append(key)
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
                    self._discard_batch(name, batch)
                    continue
                except StoreError:  # removed since it was listed (another worker discarded it)
                    continue
                for key in wanted:
                    found[key] = entries[key]
                    del left[key]
        return found

    def peek_many(self, kind: Declaration, keys: Iterable[str]) -> dict[str, Any]:
        """The valid entries of ``kind`` among ``keys``; writes nothing.

        Unlike :meth:`read_many`, a corrupt batch is left where it is (the next sweep that holds
        the lock discards and recomputes it) and its keys are simply left out.
        """
        name = _kind_name(kind)
        keys = [index.checked_key(name, key) for key in keys]
        listed = self._index(name)
        found: dict[str, Any] = {}
        for batch in {listed[key] for key in keys if key in listed}:
            try:
                found |= self._read_batch(kind, batch)
            except (StoreError, OSError):
                continue
        return {key: found[key] for key in keys if key in found}

    def write_entries(self, kind: Declaration, entries: Mapping[str, Any]) -> None:
        """Store ``entries`` (key -> entry of ``kind``) as one batch, complete or not at all.

        The batch is written under a partial name and renamed into place in one step, so a
        killed writer leaves nothing that :meth:`has` reports. A key stored before is stored
        again (the copies are equal: equal keys mean equal content).

        Raises
        ------
        TypeError
            An entry is not of the kind's entry type.
        ValueError
            An invalid key; or as :func:`storage.codec.to_record` raises.
        StoreWriteError
            The root has no space (or quota) left or is not writable; nothing of the batch
            is left behind.
        """
        name = _kind_name(kind)
        records = [to_record(kind, index.checked_key(name, key), e) for key, e in entries.items()]
        if not records:
            return
        if self._objects is not None:
            with self._writing():
                self._objects.write_batch(name, records)
            return
        folder = self.path / name
        batch = f"{BATCH_PREFIX}{uuid.uuid4().hex}"
        partial = folder / f"{PARTIAL_PREFIX}{batch}"
        with self._writing():
            ensure_group(folder)
            try:
                write_batch(partial, name, records)
                os.rename(partial, folder / batch)
            except BaseException:
                # Zarr writes a batch's chunks concurrently on its own event loop and does not
                # cancel the others when one fails (a full disk): wait for them to end, or one
                # still writing would make the partial folder again after it is removed.
                _settle_zarr_writes()
                raise
            finally:
                shutil.rmtree(partial, ignore_errors=True)

    def has(self, kind: Kind, key: str) -> bool:
        """True only if a complete entry ``kind/key`` exists (partial batches are invisible)."""
        name = _kind_name(kind)
        return index.checked_key(name, key) in self._index(name)

    def complete_keys(self, kind: Kind) -> frozenset[str]:
        """Keys of the complete entries of ``kind``, from one listing of its batches.

        Each batch's keys are read once per process from its group metadata (batches never
        change once written); partial batches and anything that is not a batch are left out.
        """
        return frozenset(self._index(_kind_name(kind)))

    def entry_location(self, kind: Kind, key: str) -> Path | str | None:
        """The batch folder (an object root: its URL) that holds the entry ``kind/key``, or None
        if none does."""
        name = _kind_name(kind)
        batch = self._index(name).get(index.checked_key(name, key))
        if batch is None:
            return None
        if self._objects is not None:
            return f"{self.root}/{STORE_NAME}/{name}/{batch}"
        return self.path / name / batch

    def entry_batches(self, kind: Kind) -> dict[str, str]:
        """Key -> name of the batch that holds it, for every complete entry of ``kind`` (one
        listing). Batches never change once in place: a name stands for the bytes it holds."""
        return self._index(_kind_name(kind))

    def discard(self, kind: Kind, key: str) -> bool:
        """Remove the entry ``kind/key`` (e.g. a corrupt one, to recompute it).

        Entries are stored in batches, so the whole batch that holds it goes (every batch, if
        two tasks stored it), with every other entry in it: they are recomputed when next
        needed. The batch is first renamed to a partial name, so :meth:`has` turns false at once
        and never sees a half-deleted batch. Returns whether there was an entry to remove.
        """
        name = _kind_name(kind)
        index.checked_key(name, key)
        removed = False
        while (batch := self._index(name).get(key)) is not None:  # every copy
            removed = self._discard_batch(name, batch) or removed
        return removed

    def clean_partials(self, *, older_than_s: float = 0.0) -> int:
        """Remove leftover partial batches, cubes and store builds, and batches whose metadata
        cannot be read; return how many.

        Parameters
        ----------
        older_than_s : float
            Only remove partials whose directory was last modified at least this many seconds
            ago. The default 0 removes every partial, including those of writers still running:
            use it only when no writer is active, else a threshold well above the longest write.
            On an object root, partial batches are removed once older than
            :data:`storage.object_root.PARTIAL_AGE_S` too, cube versions no longer current once
            older than :data:`storage.object_root.GRACE_S`.
        """
        if self._objects is not None:
            return self._objects.clean_partials(older_than_s=older_than_s)
        now = time.time()
        candidates = [p for p in self.root.glob(f"{STORE_PARTIAL_PREFIX}*") if p.is_dir()]
        groups = [p for p in self.path.iterdir() if p.is_dir()] if self.path.is_dir() else []
        for folder in groups:
            candidates += [p for p in folder.glob(f"{PARTIAL_PREFIX}*") if p.is_dir()]
            if folder.name != CUBES:
                # A batch whose metadata cannot be read lists no entry: nothing would remove it.
                candidates += [
                    p
                    for p in folder.glob(f"{BATCH_PREFIX}*")
                    if index.BATCH.fullmatch(p.name) and not index.batch_keys(p)
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

    @contextmanager
    def _writing(self) -> Iterator[None]:
        """Raise a write's lack of space or permission as :class:`StoreWriteError`."""
        try:
            yield
        except Exception as error:  # an OSError, or one a library raised from it
            failure = write_failure(error, self.root)
            if failure is None:
                raise
            raise failure from error

    def _index(self, name: str) -> dict[str, str]:
        """Key -> complete batch holding it, for the kind ``name`` (one listing)."""
        if self._objects is not None:
            return self._objects.index(name)
        return index.index(self.path / name)

    def _discard_batch(self, name: str, batch: str) -> bool:
        if self._objects is not None:
            return self._objects.discard_batch(name, batch)
        return index.discard_batch(self.path / name / batch)

    def _read_batch(self, kind: Declaration, batch: str) -> dict[str, Any]:
        """Every entry of one batch, by key; any failure to read or verify it is corruption."""
        name = _kind_name(kind)
        remote = self._objects
        path = self.path / name / batch if remote is None else None
        keys = index.batch_keys(path) if path is not None else remote.batch_keys(name, batch)
        shown = ", ".join(keys[:3]) + (f" and {len(keys) - 3} more" if len(keys) > 3 else "")
        where = f"{name} batch {batch} (entries {shown or 'unknown'}) in {self.root}"
        if not (
            (path / "zarr.json").is_file() if path is not None else remote.has_batch(name, batch)
        ):
            raise StoreError(f"no {where}")
        try:
            records = read_batch(path, name) if path is not None else remote.read_batch(name, batch)
            return {record.key: from_record(kind, record) for record in records}
        except FileNotFoundError as error:
            raise StoreError(f"no {where} (removed while reading)") from error
        except Exception as error:
            raise CorruptEntryError(f"corrupt {where}: {one_line(error)}") from error

    # -----------------------------------------------------------------------------------------
    # Cubes (storage.cube_files)

    def write_cube(
        self,
        name: str,
        cube: xr.Dataset,
        *,
        source: str | None = None,
        note: Mapping[str, Any] | None = None,
    ) -> None:
        """Store ``cube`` as ``cubes/<name>``, replacing an older cube of that name atomically,
        with the digest ``source`` of what it was built from and a JSON ``note`` if given
        (:func:`storage.cube_files.write_cube`); :class:`storage.errors.StoreWriteError` as
        :meth:`write_entries`."""
        with self._writing():
            if self._objects is not None:
                self._objects.write_cube(name, cube, source=source, note=note)
            else:
                cube_files.write_cube(self.path / CUBES, name, cube, source=source, note=note)

    def current_note(self, name: str, source: str) -> dict[str, Any] | None:
        """The note of cube ``name`` if it is intact and was written with ``source``, else None
        (:func:`storage.cube_files.current_note`)."""
        if self._objects is not None:
            return self._objects.current_note(name, source)
        return cube_files.current_note(self.path / CUBES, name, source)

    def cube_names(self) -> list[str]:
        """Names of the stored cubes, sorted."""
        if self._objects is not None:
            return self._objects.cube_names()
        return cube_files.cube_names(self.path / CUBES)

    def read_cube(self, name: str, *, lazy: bool = False) -> xr.Dataset:
        """The cube ``name``, string variables as ``<U`` (:func:`storage.cube_files.read_cube`)."""
        if self._objects is not None:
            return self._objects.read_cube(name, lazy=lazy)
        return cube_files.read_cube(self.path / CUBES, name, lazy=lazy)


def open_results(root: str | Path, *, lazy: bool = False) -> dict[str, xr.Dataset]:
    """Every result cube of the run root ``root`` (a folder or ``s3://bucket/prefix``), by
    name, sorted: a sweep's by its name (``threshold``), a search's by its space's name and
    what it holds (``design.trials``, ``design.front``; :mod:`storage.search_log`, which also
    names those of a root written before searches were named).

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
    return named_search_cubes(
        {name: store.read_cube(name, lazy=lazy) for name in store.cube_names()}
    )


def _kind_name(kind: Kind) -> str:
    name = kind if isinstance(kind, str) else kind.name
    if not isinstance(name, str) or not _KIND.fullmatch(name) or name == CUBES:
        raise ValueError(f"unknown entry kind {name!r}: expected [a-z][a-z0-9_]{{0,63}}, not cubes")
    return name


async def _pending_zarr_tasks() -> None:
    current = asyncio.current_task()
    await asyncio.gather(
        *(task for task in asyncio.all_tasks() if task is not current), return_exceptions=True
    )


def _settle_zarr_writes() -> None:
    """Wait until every task on Zarr's event loop has ended (their errors are dropped: the one
    that failed the write is already being raised)."""
    with contextlib.suppress(Exception):
        zarr_sync.sync(_pending_zarr_tasks())
