"""The batch index: which keys a kind's batches hold, from one listing of its folder.

Which keys a kind holds is one directory listing plus, per batch not seen before, one read of
its small ``zarr.json`` (batches never change once in place, so a process remembers their
keys). A batch being written (``.partial-batch-<hex>``) is never listed.
"""

from __future__ import annotations

import os
import re
import shutil
import threading
import uuid
from collections import OrderedDict
from collections.abc import Callable, Iterable
from pathlib import Path

from storage.batches import BATCH_PREFIX, read_batch_keys
from storage.errors import StoreError
from storage.layout import PARTIAL_PREFIX

KEY = re.compile(r"[0-9a-f]{32}")
BATCH = re.compile(BATCH_PREFIX + r"[0-9a-f]{32}")


def checked_key(kind: str, key: str) -> str:
    """``key`` if it is a cache key (32 lowercase hex characters); else ValueError."""
    if not isinstance(key, str) or not KEY.fullmatch(key):
        raise ValueError(f"invalid {kind} key {key!r}: expected 32 lowercase hex characters")
    return key


def index(folder: Path) -> dict[str, str]:
    """Key -> name of a complete batch holding it, from one listing of a kind's ``folder``."""
    try:
        with os.scandir(folder) as found:
            names = sorted(e.name for e in found if BATCH.fullmatch(e.name))
    except FileNotFoundError:
        return {}
    keys: dict[str, str] = {}
    for name in names:
        for key in batch_keys(folder / name):
            keys.setdefault(key, name)
    return keys


def discard_batch(path: Path) -> bool:
    """Remove the batch at ``path``: renamed to a partial name first, so that no listing sees a
    half-deleted batch. Returns whether it was there."""
    doomed = path.parent / f"{PARTIAL_PREFIX}{path.name}-{uuid.uuid4().hex}"
    try:
        os.rename(path, doomed)
    except FileNotFoundError:
        return False
    shutil.rmtree(doomed, ignore_errors=True)
    return True


# Keys of the batches this process has listed, by batch path. A batch never changes once
# renamed into place (and a removed one's name never comes back), so its keys are read once.
_BATCH_KEYS: OrderedDict[str, tuple[str, ...]] = OrderedDict()
_BATCH_KEYS_LIMIT = 100_000
_BATCH_KEYS_GUARD = threading.Lock()


def batch_keys(path: Path) -> tuple[str, ...]:
    """The keys of the complete batch at ``path``; none if its metadata is unreadable."""
    return cached_keys(str(path), lambda: read_batch_keys(path))


def cached_keys(name: str, read: Callable[[], Iterable[str]]) -> tuple[str, ...]:
    """The keys of the complete batch ``name`` (a path or URL), from ``read()`` the first time
    (remembered while the process lives); none if its metadata is unreadable."""
    with _BATCH_KEYS_GUARD:
        if name in _BATCH_KEYS:
            _BATCH_KEYS.move_to_end(name)
            return _BATCH_KEYS[name]
    try:
        keys = tuple(key for key in read() if KEY.fullmatch(key))
    except (OSError, StoreError, ValueError, KeyError, TypeError):
        # Unreadable metadata: its entries count as absent and are recomputed; reading the
        # batch would report it corrupt.
        return ()
    with _BATCH_KEYS_GUARD:
        _BATCH_KEYS[name] = keys
        while len(_BATCH_KEYS) > _BATCH_KEYS_LIMIT:
            _BATCH_KEYS.popitem(last=False)
    return keys
