"""A sweep store on objects (an ``s3://`` root): the layout of :mod:`storage.store` without
rename, with the same guarantees.

Object layout (keys relative to the root URL)::

    store.lock                                the lease (:mod:`storage.lease`)
    store.zarr/zarr.json                      group, attrs {"eskin_sweep_store": 3}
    store.zarr/<kind>/batch-<hex>/...         a batch; complete once its zarr.json exists
    store.zarr/cubes/<name>/current           the cube's version and its objects' ETags
    store.zarr/cubes/<name>/v-<hex>/...       one written version of the cube
    sweep-runs/<time ns>-<hex>.json           the run log, one object per sweep

* **A batch appears whole or not at all.** It is written into memory first, then every object
  but its group ``zarr.json`` is PUT (concurrently), then ``zarr.json`` last: one PUT is atomic
  and listings and reads follow writes, so "complete" is "its ``zarr.json`` exists", and
  listing a kind lists its ``batch-<hex>/zarr.json`` objects. Leftovers without one are removed
  by the sweep that holds the lease once :data:`PARTIAL_AGE_S` old
  (:meth:`ObjectRoot.clean_partials`; a worker of a killed sweep may still be publishing a
  younger one). Discarding a batch
  deletes its ``zarr.json`` first (it disappears at once), then the rest.
* **A cube is swapped by a pointer.** A cube is written whole under a new version prefix, then
  the small object ``current`` is replaced with one PUT naming it, as JSON ``{"version":
  "v-<hex>", "etags": {file: ETag}}`` (a store written before ETags were kept holds the bare
  version); a reader reads ``current`` and then that version. Versions no longer current are
  deleted once older than :data:`GRACE_S`, so that a reader that read the pointer just before
  the swap still finds its version.
* **Checksums as on a folder root**: a CRC-32C per chunk, a sha256 per variable, and a cube's
  manifest, source and note in its group metadata (:mod:`storage.cube_files`).
* **Few round trips.** Each request to an object store waits a round trip, so nothing is read
  object by object: whether a cube is intact and current (planning asks it of every cube) is
  one listing of its version compared with the ETags its pointer recorded as it was written
  (an object replaced, added or removed since changes the listing), plus its group metadata;
  only a pointer without ETags has every object read, concurrently, for the manifest. The run
  log, too, is read concurrently.
"""

from __future__ import annotations

import json
import re
import time
import uuid
from collections.abc import Mapping
from typing import Any

import xarray as xr
import zarr

from storage import cube_files, index
from storage.batches import BATCH_PREFIX, BatchEntry, metadata_keys, read_batch, write_batch
from storage.errors import StoreError, one_line
from storage.layout import CUBES, MARKER, STORE_NAME, VERSION, check_metadata
from storage.objects import Conflict, Objects

#: Seconds a cube version stays after it stopped being current (readers may still read it).
GRACE_S = 600.0
#: Seconds since its last object was written after which a batch without its group metadata is
#: a leftover: a worker of a killed sweep may still be publishing a younger one.
PARTIAL_AGE_S = 600.0
POINTER = "current"
VERSION_PREFIX = "v-"
RUN_LOG = "sweep-runs/"
_GROUP = {"zarr_format": 3, "node_type": "group"}
_BATCH_METADATA = re.compile(rf"([a-z][a-z0-9_]*)/({BATCH_PREFIX}[0-9a-f]{{32}})/zarr\.json")
_VERSION = re.compile(rf"{VERSION_PREFIX}[0-9a-f]{{32}}")


class ObjectRoot:
    """The sweep store of an object root (see the module docstring); holds only its objects."""

    def __init__(self, objects: Objects):
        self.objects = objects

    def _key(self, *parts: str) -> str:
        return "/".join((STORE_NAME, *parts))

    # -----------------------------------------------------------------------------------------
    # The root

    def has_store(self) -> bool:
        """True if the root holds a sweep store (checked); False if it holds nothing at all.

        Raises
        ------
        StoreError
            The root cannot be used (:meth:`storage.objects.Objects.check`), or holds other
            objects but no store, or a foreign or unreadable store.
        """
        where = self.objects.where(STORE_NAME)
        self.objects.check()
        try:
            data, _ = self.objects.get(self._key(cube_files.METADATA))
        except FileNotFoundError:
            found = sorted({o.key.split("/")[0] for o in self.objects.list("")})
            if found:
                shown = ", ".join(found[:3]) + (", ..." if len(found) > 3 else "")
                raise StoreError(
                    f"refusing run root {self.objects.url}: not empty and holds no "
                    f"{STORE_NAME} ({shown})"
                ) from None
            return False
        try:
            meta = json.loads(data)
        except ValueError as error:
            raise StoreError(f"not a sweep store: cannot read {where}: {one_line(error)}") from None
        check_metadata(meta, where, self.objects.url)
        return True

    def create(self) -> None:
        """Create the store: its marked group metadata (unless another sweep created it first;
        the first object, so that a killed creation leaves a store, not a foreign root), then
        its cubes group."""
        marked = json.dumps({**_GROUP, "attributes": {MARKER: VERSION}}).encode()
        try:
            self.objects.put_if_absent(self._key(cube_files.METADATA), marked)
        except Conflict:
            pass
        self.has_store()
        self._ensure_group(CUBES)

    # -----------------------------------------------------------------------------------------
    # Batches

    def index(self, kind: str) -> dict[str, str]:
        """Key -> name of a complete batch holding it, from one listing of ``kind``'s objects."""
        batches = sorted(
            match.group(2)
            for info in self.objects.list(self._key(kind, BATCH_PREFIX))
            if (match := _BATCH_METADATA.fullmatch(info.key.removeprefix(f"{STORE_NAME}/")))
        )
        keys: dict[str, str] = {}
        for batch in batches:
            for key in self.batch_keys(kind, batch):
                keys.setdefault(key, batch)
        return keys

    def batch_keys(self, kind: str, batch: str) -> tuple[str, ...]:
        """The keys of a complete batch (read once per process); none if unreadable."""
        metadata = self._key(kind, batch, cube_files.METADATA)
        return index.cached_keys(
            self.objects.where(self._key(kind, batch)),
            lambda: metadata_keys(self.objects.get(metadata)[0]),
        )

    def write_batch(self, kind: str, records: list[BatchEntry]) -> None:
        """Publish ``records`` as a new batch of ``kind``, its group metadata last."""
        self._ensure_group(kind)
        files: dict[str, Any] = {}
        write_batch(zarr.storage.MemoryStore(files), kind, records)
        prefix = self._key(kind, f"{BATCH_PREFIX}{uuid.uuid4().hex}") + "/"
        self.objects.publish(prefix, _bytes(files), last=cube_files.METADATA)

    def read_batch(self, kind: str, batch: str) -> list[BatchEntry]:
        """Every entry of a complete batch (:func:`storage.batches.read_batch`)."""
        store = self.objects.zarr_store(self._key(kind, batch), read_only=True)
        return read_batch(store, kind)

    def has_batch(self, kind: str, batch: str) -> bool:
        """True if the batch ``batch`` of ``kind`` is complete (its group metadata exists)."""
        try:
            self.objects.get(self._key(kind, batch, cube_files.METADATA))
        except FileNotFoundError:
            return False
        return True

    def discard_batch(self, kind: str, batch: str) -> bool:
        """Remove a batch: its group metadata first (so no listing sees it), then the rest."""
        present = self.has_batch(kind, batch)
        self.objects.delete([self._key(kind, batch, cube_files.METADATA)])
        self._delete_prefix(self._key(kind, batch) + "/")
        return present

    def clean_partials(self, *, older_than_s: float) -> int:
        """Remove batches without (readable) group metadata and cube versions no longer
        current, each once older than ``older_than_s`` and at least :data:`PARTIAL_AGE_S`
        (versions: :data:`GRACE_S`); return how many."""
        now = time.time()
        groups: dict[tuple[str, ...], list[Any]] = {}
        for info in self.objects.list(f"{STORE_NAME}/"):
            parts = info.key.split("/")
            if len(parts) >= 4:  # store.zarr/<kind or cubes>/<batch or name>/<...>
                groups.setdefault(tuple(parts[1:3]), []).append(info)
        removed = 0
        for (kind, name), infos in groups.items():
            if kind == CUBES:
                removed += self._clean_versions(name, infos, now, max(older_than_s, GRACE_S))
                continue
            if not index.BATCH.fullmatch(name):
                continue  # not ours to remove
            complete = any(i.key.endswith(f"{name}/{cube_files.METADATA}") for i in infos)
            if complete and self.batch_keys(kind, name):
                continue
            if now - max(i.modified_s for i in infos) < max(older_than_s, PARTIAL_AGE_S):
                continue
            self.discard_batch(kind, name)
            removed += 1
        return removed

    def _clean_versions(self, name: str, infos: list[Any], now: float, grace_s: float) -> int:
        current, _ = self._current(name)
        versions: dict[str, float] = {}
        for info in infos:
            version = info.key.split("/")[3]
            if _VERSION.fullmatch(version):
                versions[version] = max(versions.get(version, 0.0), info.modified_s)
        doomed = [v for v, t in versions.items() if v != current and now - t >= grace_s]
        for version in doomed:
            self._delete_prefix(self._key(CUBES, name, version) + "/")
        return len(doomed)

    def _ensure_group(self, kind: str) -> None:
        key = self._key(kind, cube_files.METADATA)
        try:
            self.objects.put_if_absent(key, json.dumps({**_GROUP, "attributes": {}}).encode())
        except Conflict:
            pass

    def _delete_prefix(self, prefix: str) -> None:
        self.objects.delete([info.key for info in self.objects.list(prefix)])

    # -----------------------------------------------------------------------------------------
    # Cubes

    def write_cube(
        self,
        name: str,
        cube: xr.Dataset,
        *,
        source: str | None,
        note: Mapping[str, Any] | None,
    ) -> None:
        """Write ``cube`` as a new version of ``name`` and point ``current`` at it."""
        cube_files.checked_name(name)
        cube, encoding = cube_files.prepared(name, cube)
        files: dict[str, Any] = {}
        store = zarr.storage.MemoryStore(files)

        def manifest() -> dict[str, str]:
            return cube_files.manifest_of(_bytes(files))

        cube_files.write_group(store, cube, encoding, source, note, manifest)
        version = f"{VERSION_PREFIX}{uuid.uuid4().hex}"
        etags = self.objects.publish(
            self._key(CUBES, name, version) + "/", _bytes(files), last=cube_files.METADATA
        )
        pointer = {"version": version, "etags": dict(sorted(etags.items()))}
        self.objects.put(self._key(CUBES, name, POINTER), json.dumps(pointer).encode())
        infos = self.objects.list(self._key(CUBES, name) + "/")
        self._clean_versions(name, infos, time.time(), GRACE_S)

    def cube_names(self) -> list[str]:
        """Names of the stored cubes (those with a ``current`` pointer), sorted."""
        names = set()
        for info in self.objects.list(self._key(CUBES) + "/"):
            parts = info.key.split("/")
            if len(parts) == 4 and parts[3] == POINTER and cube_files.valid_name(parts[2]):
                names.add(parts[2])
        return sorted(names)

    def read_cube(self, name: str, *, lazy: bool) -> xr.Dataset:
        """The current version of cube ``name``, checked as it is read
        (:meth:`storage.store.SweepStore.read_cube`); StoreError if there is none."""
        cube_files.checked_name(name)
        version, _ = self._current(name)
        if version is None:
            raise StoreError(f"no cube {name!r} in {self.objects.url}")
        store = self.objects.zarr_store(self._key(CUBES, name, version), read_only=True)
        return cube_files.read_group(store, f"cube {name} in {self.objects.url}", lazy=lazy)

    def current_note(self, name: str, source: str) -> dict[str, Any] | None:
        """The note of cube ``name``'s current version if it is intact and was written with
        ``source``, else None (:meth:`storage.store.SweepStore.current_note`)."""
        cube_files.checked_name(name)
        version, etags = self._current(name)
        if version is None:
            return None
        prefix = self._key(CUBES, name, version) + "/"
        listed = {info.key.removeprefix(prefix): info.etag for info in self.objects.list(prefix)}

        def intact(manifest: dict[str, str]) -> bool:
            if etags:  # every object is the one its writer PUT, none added or removed
                return listed == etags
            read = self.objects.get_many(prefix + key for key in listed)
            return manifest == cube_files.manifest_of(
                {key.removeprefix(prefix): data for key, data in read.items()}
            )

        return cube_files.note_of(
            lambda: self.objects.get(prefix + cube_files.METADATA)[0], source, intact
        )

    def _current(self, name: str) -> tuple[str | None, dict[str, str] | None]:
        """The current version of cube ``name`` (None if none) and the ETags of its objects as
        they were written (None if its pointer did not keep them)."""
        try:
            data, _ = self.objects.get(self._key(CUBES, name, POINTER))
        except FileNotFoundError:
            return None, None
        text = data.decode(errors="replace").strip()
        if _VERSION.fullmatch(text):
            return text, None  # a pointer written before ETags were kept
        try:
            pointer = json.loads(text)
            version, etags = pointer["version"], pointer["etags"]
        except (ValueError, KeyError, TypeError):
            return None, None
        if not (isinstance(version, str) and _VERSION.fullmatch(version)):
            return None, None
        valid = isinstance(etags, dict) and all(isinstance(v, str) and v for v in etags.values())
        return version, dict(etags) if valid else None

    # -----------------------------------------------------------------------------------------
    # The run log

    def append_run(self, line: bytes) -> None:
        """Add one record of the run log (:mod:`storage.runlog`) as an object of its own: an
        object root cannot append to a file."""
        # Named by the time in ns, so that a listing's order is the order of writing.
        self.objects.put(f"{RUN_LOG}{time.time_ns():020d}-{uuid.uuid4().hex}.json", line)

    def run_lines(self) -> list[bytes]:
        """Every record of the run log, in the order written."""
        keys = sorted(info.key for info in self.objects.list(RUN_LOG))
        read = self.objects.get_many(keys)
        return [read[key] for key in keys]


def _bytes(files: Mapping[str, Any]) -> dict[str, bytes]:
    """A Zarr memory store's contents as bytes by key."""
    return {key: value.to_bytes() for key, value in files.items()}
