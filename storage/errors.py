"""Errors of the sweep store: each message is one line naming the root and, where there is one,
the entry."""

from __future__ import annotations

from pipeline.errors import EskinError

__all__ = ["CorruptEntryError", "StoreBusyError", "StoreError", "StoreLayoutError", "one_line"]


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


def one_line(error: BaseException) -> str:
    """``error`` as ``Type: message`` on one line."""
    text = " ".join(str(error).split()) or type(error).__name__
    return f"{type(error).__name__}: {text}"
