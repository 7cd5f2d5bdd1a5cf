"""Errors of the sweep store: each message is one line naming the root and, where there is one,
the entry."""

from __future__ import annotations

import errno
import os
from typing import Any

from pipeline.errors import EskinError

__all__ = ["CorruptEntryError", "StoreBusyError", "StoreError", "StoreLayoutError", "one_line"]
__all__ += ["StoreWriteError", "write_failure"]

#: The errors of a write that no retry can fix until the user acts, and how a message names
#: them: the device or the quota is full, or the root is not (or no longer) writable.
STOPPING_ERRNOS = {
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.EROFS: "read-only file system",
}


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


class StoreWriteError(StoreError):
    """A write to the run root failed in a way that every later write would too (no space, no
    quota, no permission: ``STOPPING_ERRNOS``); what was written before is kept.

    ``root`` is the run root and ``cause`` the failure in a few words. A sweep stops at the
    first one (exit status 1): its message is one line naming both.
    """

    exit_status = 1

    def __init__(self, root: str | os.PathLike, cause: str):
        super().__init__(f"cannot write to run root {root}: {cause}")
        self.root = str(root)
        self.cause = cause

    def __reduce__(self) -> tuple[Any, ...]:  # Dask pickles it back from a worker
        return (type(self), (self.root, self.cause))


def write_failure(error: BaseException, root: str | os.PathLike) -> StoreWriteError | None:
    """``error`` (or an error it was raised from) as a :class:`StoreWriteError` on ``root`` if
    it is one of ``STOPPING_ERRNOS``; else None (the caller re-raises ``error``)."""
    seen: set[int] = set()
    while error is not None and id(error) not in seen:
        seen.add(id(error))
        if isinstance(error, StoreWriteError):
            return error
        if isinstance(error, OSError) and error.errno in STOPPING_ERRNOS:
            return StoreWriteError(root, STOPPING_ERRNOS[error.errno])
        error = error.__cause__ or error.__context__
    return None


def one_line(error: BaseException) -> str:
    """``error`` as ``Type: message`` on one line."""
    text = " ".join(str(error).split()) or type(error).__name__
    return f"{type(error).__name__}: {text}"
