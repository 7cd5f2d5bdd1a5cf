"""The layout of a run root and opening it: which roots are refused, creating the store, setting
an older layout aside (see :mod:`storage.store` for the layout itself)."""

from __future__ import annotations

import errno
import json
import os
import shutil
import tempfile
import time
import uuid
import warnings
from pathlib import Path
from typing import Any

import zarr

from storage.errors import StoreError, StoreLayoutError, one_line

STORE_NAME = "store.zarr"
MARKER = "eskin_sweep_store"
#: The store layout this code writes and reads. Layout 3 keeps spike times as whole ticks
#: (:mod:`storage.codec`) and compresses numbers with Blosc; layout 2 kept them as float64
#: seconds, unquantised; both store entries in batches (:mod:`storage.batches`); layout 1
#: stored one group per entry.
VERSION = 3
# A store of an older layout is kept beside the new one under this name (plus a suffix).
OLD_STORE_PREFIX = "store.zarr-layout-"
CUBES = "cubes"
PARTIAL_PREFIX = ".partial-"
# A new store is built here (inside the root, so the final rename stays on one file system).
STORE_PARTIAL_PREFIX = ".store.zarr-partial-"


def create_store(root: Path) -> None:
    """Build the store under a temporary name in ``root`` and rename it into place."""
    partial = root / f"{STORE_PARTIAL_PREFIX}{uuid.uuid4().hex}"
    try:
        group = zarr.open_group(
            zarr.storage.LocalStore(partial),
            mode="w-",
            zarr_format=3,
            attributes={MARKER: VERSION},
        )
        group.create_group(CUBES)
        try:
            os.rename(partial, root / STORE_NAME)
        except OSError as error:
            # Another process created the store first: use theirs (checked below).
            if error.errno not in (errno.EEXIST, errno.ENOTEMPTY):
                raise
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    check_store_root(root, need_store=True)


def ensure_group(path: Path) -> None:
    """Make ``path`` a Zarr group if it is not one (a kind's folder, made on its first batch).

    Safe against concurrent callers: the group metadata is written under a temporary name and
    renamed into place, so nobody reads a half-written ``zarr.json``.
    """
    if (path / "zarr.json").is_file():
        return
    path.mkdir(parents=True, exist_ok=True)
    partial = path / f"{PARTIAL_PREFIX}zarr.json-{uuid.uuid4().hex}"
    partial.write_text(json.dumps({"zarr_format": 3, "node_type": "group", "attributes": {}}))
    os.replace(partial, path / "zarr.json")


def check_store_root(root: Path, *, need_store: bool) -> None:
    """Refuse ``root`` unless it is a directory that is empty (if allowed) or a sweep store."""
    if not root.is_dir():
        what = "a file" if root.is_file() else "not a directory"
        raise StoreError(f"run root {root} is {what}")
    store = root / STORE_NAME
    if not store.exists():
        try:
            contents = [p.name for p in root.iterdir()]
        except OSError as error:
            raise StoreError(f"cannot list run root {root}: {one_line(error)}") from error
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
        raise StoreError(f"not a sweep store: cannot read {metadata}: {one_line(error)}") from error
    check_metadata(meta, str(store), str(root))


def check_metadata(meta: Any, store: str, root: str) -> None:
    """Refuse the group metadata ``meta`` of the store ``store`` (of run root ``root``) unless
    it is a sweep store of this layout.

    Raises
    ------
    StoreLayoutError
        A store of an older layout.
    StoreError
        Not a Zarr v3 group, no marker (a foreign store), or an unknown version.
    """
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


def set_aside(root: Path, reason: StoreLayoutError) -> None:
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
        raise StoreError(f"cannot set aside {old}: {one_line(error)}") from error
    warnings.warn(
        f"{old} was written by an older eskin-sweep in a layout this version does not read; "
        f"kept as {kept.name}, its points are computed again",
        RuntimeWarning,
        stacklevel=3,
    )


def check_writable(root: Path) -> None:
    """Refuse a root we cannot write to, without leaving anything behind."""
    if not os.access(root, os.W_OK | os.X_OK):
        raise StoreError(f"run root {root} is not writable")
    # os.access says yes to root whatever the mode bits or mount flags (e.g. a read-only file
    # system), so also try it.
    try:
        fd, probe = tempfile.mkstemp(prefix=".eskin-probe-", dir=root)
    except OSError as error:
        raise StoreError(f"run root {root} is not writable: {one_line(error)}") from error
    os.close(fd)
    os.unlink(probe)
