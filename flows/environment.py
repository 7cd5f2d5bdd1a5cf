"""Keep runs hermetic and offline: tool state under the run root, no telemetry.

An object root (``s3://...``) holds no tool state: its state goes to a local folder of the user's
cache instead (:func:`state_folder`).

Settings the user already made win (``setdefault``): a user with a real Prefect server keeps
``PREFECT_API_URL`` and their ``PREFECT_HOME``.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import functools
import gc
import hashlib
import os
from collections.abc import Iterable, Iterator
from pathlib import Path

from storage.errors import write_failure
from storage.objects import is_object_url

STATE_DIR = ".state"


def state_folder(root: str | Path) -> Path:
    """Where the tools keep their state for the run root ``root``: ``<root>/.state`` for a
    folder; for an object root, ``<cache>/eskin-sweep/state/<12 hex of its URL>`` in the user's
    cache (``XDG_CACHE_HOME``, default ``~/.cache``)."""
    if not is_object_url(root):
        return Path(root) / STATE_DIR
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "eskin-sweep" / "state" / hashlib.sha256(str(root).encode()).hexdigest()[:12]


def hermetic_environment(root: str | Path, *, prefect: bool = True) -> None:
    """Point Prefect, Dask and matplotlib at folders under :func:`state_folder` of ``root``;
    keep them offline.

    Must run before Prefect is imported (it reads its settings at import). A root where those
    folders cannot be made for want of space or permission raises
    :class:`storage.errors.StoreWriteError`.
    """
    state = state_folder(root)
    defaults = {
        "DASK_TEMPORARY_DIRECTORY": state / "dask",
        "MPLCONFIGDIR": state / "matplotlib",
        "DO_NOT_TRACK": "1",
    }
    if prefect:
        defaults |= {
            "PREFECT_HOME": state / "prefect",
            "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
            "PREFECT_SERVER_API_HOST": "127.0.0.1",
        }
    for name, value in defaults.items():
        if name in os.environ:
            continue
        if isinstance(value, Path):  # the tools do not create their folders' parents
            try:
                value.mkdir(parents=True, exist_ok=True)
            except OSError as error:  # a root without space or permission: one line
                failure = write_failure(error, root)
                if failure is None:
                    raise
                raise failure from error
        os.environ[name] = str(value)


#: glibc ``mallopt`` parameters (``malloc.h``).
_M_TRIM_THRESHOLD, _M_MMAP_MAX = -1, -4
TRIM_THRESHOLD_BYTES = 256 * 2**20


@functools.cache
def tune_allocator() -> bool:
    """Keep training's tensors on the heap instead of fresh ``mmap`` pages (glibc only).

    Training allocates and frees tensors of a few MiB (CNN activations) to hundreds of MiB
    (the first layer of a 32x32 array's FFNN) every step. By default glibc serves the large ones
    with a fresh ``mmap`` each time, whose pages fault in again; under Dask's nanny default
    (``MALLOC_TRIM_THRESHOLD_=65536``) that goes for everything over 128 KiB, and a third of a
    CNN cross-validation's time went to the kernel. With no ``mmap`` and a high trim threshold
    the heap keeps its pages: RSS stays at its peak instead of shrinking between steps. A thread
    other than the main one still maps allocations larger than its arena's heap (64 MiB) unless
    the process started with ``MALLOC_ARENA_MAX=1`` (the local cluster's workers do). Returns
    whether the settings took effect (False on a C library without ``mallopt``); runs once.
    """
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    return bool(mallopt(_M_MMAP_MAX, 0) and mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES))


@functools.cache
def skip_exit_collection() -> None:
    """Spare the process the garbage collector's passes over its objects as it exits.

    The interpreter collects garbage as it tears its modules down at exit, walking every object
    the process still holds: seconds for a Dask worker that trained (torch, numba and the
    training's objects), about a second for a command that swept. The memory goes back to the
    system either way, so an exit handler freezes every object first (``gc.freeze()``: the
    passes leave frozen objects alone); a worker's nanny otherwise waited 4 s for its exit and
    then killed it, which skips the rest of the teardown too. Registered once per process.
    Every other exit handler still runs, before or after this one, and objects freed by
    reference counting are still finalized; only objects in reference cycles are left
    unfinalized, as Python allows at exit.
    """
    atexit.register(gc.freeze)


@contextlib.contextmanager
def restored_environment(names: Iterable[str]) -> Iterator[None]:
    """Give the environment variables ``names`` back their values (or absence) on leaving."""
    saved = {name: os.environ.get(name) for name in names}
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def machine_memory_bytes() -> int:
    """The machine's physical memory (bytes)."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
