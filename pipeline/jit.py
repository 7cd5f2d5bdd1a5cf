"""Numba kernels compiled on first use, with numba itself imported only then, and cached on disk.

Importing numba costs 0.15-0.5 s, which every command would pay for kernels that only a
simulation calls (a report, a dry run or a re-run with nothing to compute calls none). A kernel
is declared with :func:`kernel` instead of ``numba.njit``; the first call of any kernel of a
module imports numba, compiles every kernel of that module (``cache=True, nogil=True`` and the
kernel's own options) and puts the compiled dispatchers in the module's namespace in place of
the placeholders, so that kernels calling kernels resolve to compiled code, as with ``njit``
at import.

The compiled machine code is cached on disk (numba's ``cache=True``), so a process after the first
loads it (tens of milliseconds) instead of compiling it (seconds). Where the cache lives:
``NUMBA_CACHE_DIR`` when it is set; otherwise numba's own choice, a ``__pycache__`` folder beside
each kernel's source file when that folder is writable (an editable install, a checkout), else
the user's cache folder (``$XDG_CACHE_HOME/numba`` or ``~/.cache/numba``: a read-only install).
Entries are keyed by the source file's path, modification time and size, the kernel and its
argument types, and the CPU, so an edited or upgraded source is compiled afresh. Several worker
processes that start on an empty cache may each compile the same kernel once; numba writes
every cache file to a temporary name and renames it, so none reads a half-written file.

One-off costs are kept apart from a step's work: :func:`one_off_seconds` is the wall time the
calling thread has spent importing numba, in numba's compiler lock (loading cached kernels or
compiling them, nested calls counted once) and in blocks marked :func:`one_off` (importing torch
and scikit-learn the first time), so a timer can book it as shared by every later call
(:class:`pipeline.run.stopwatch.Stopwatch` does); :func:`once` runs a warm-up once per process.
"""

from __future__ import annotations

import functools
import sys
import threading
import time
from collections.abc import Callable, Hashable, Iterator
from contextlib import contextmanager
from typing import Any

_DEFAULTS = {"cache": True, "nogil": True}
_pending: dict[str, list[tuple[Callable[..., Any], dict[str, Any]]]] = {}
_compiling = threading.Lock()
_warmed: set[Hashable] = set()
_warming = threading.Lock()


class _CompileClock(threading.local):
    """Per thread: seconds spent importing numba and inside its compiler lock (outermost only)."""

    def __init__(self) -> None:
        self.total_s = 0.0
        self.depth = 0
        self.started = 0.0


_clock = _CompileClock()


def one_off_seconds() -> float:
    """Wall seconds the calling thread has spent so far on one-off work: importing numba,
    loading or compiling kernels, blocks marked :func:`one_off` (monotonic; take differences)."""
    return _clock.total_s


@contextmanager
def one_off() -> Iterator[None]:
    """Count the block's wall time in :func:`one_off_seconds`: for work a process does once
    whoever asks first, such as importing a library (nested one-off time counted once)."""
    outermost = _clock.depth == 0
    if outermost:
        _clock.started = time.perf_counter()
    _clock.depth += 1
    try:
        yield
    finally:
        _clock.depth -= 1
        if outermost:
            _clock.total_s += time.perf_counter() - _clock.started


class _Kernel:
    """A kernel not compiled yet: its first call compiles its module's kernels."""

    def __init__(self, function: Callable[..., Any]):
        self.function = function
        functools.update_wrapper(self, function)

    def __call__(self, *args: Any) -> Any:
        return compile_module(self.function.__module__)[self.function.__name__](*args)


def kernel(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """Declare a module-level numba kernel: ``@kernel()`` or ``@kernel(error_model="numpy")``
    stands for ``@numba.njit(cache=True, nogil=True, **options)``, compiled on first use."""

    def declare(function: Callable[..., Any]) -> _Kernel:
        _pending.setdefault(function.__module__, []).append((function, _DEFAULTS | options))
        return _Kernel(function)

    return declare


def compile_module(name: str) -> dict[str, Any]:
    """Compile the pending kernels of module ``name`` into its namespace; return the namespace."""
    namespace = vars(sys.modules[name])
    with _compiling:
        kernels = _pending.pop(name, [])
        if kernels:
            numba = _import_numba()
            for function, options in kernels:
                namespace[function.__name__] = numba.njit(**options)(function)
    return namespace


def once(key: Hashable, warm_up: Callable[[], object]) -> None:
    """Call ``warm_up()`` the first time this process sees ``key``; later calls do nothing.

    For running kernels once on tiny inputs ahead of real work, so that loading or compiling
    them is paid in one place (a warm-up that raises is not remembered, and is tried again).
    """
    if key in _warmed:
        return
    with _warming:
        if key not in _warmed:
            warm_up()
            _warmed.add(key)


def _import_numba() -> Any:
    """numba, imported (its import time counted in :func:`one_off_seconds`) with the compiler-lock
    listener registered."""
    if "numba" in sys.modules and _listening:
        return sys.modules["numba"]
    start = time.perf_counter()
    import numba
    import numba.core.event as event

    class _LockListener(event.Listener):
        # Numba announces every entry into its (re-entrant) compiler lock, cache loads and
        # compiles alike, in the thread that enters it; the outermost entry is timed.
        def on_start(self, _event: Any) -> None:
            if _clock.depth == 0:
                _clock.started = time.perf_counter()
            _clock.depth += 1

        def on_end(self, _event: Any) -> None:
            _clock.depth -= 1
            if _clock.depth == 0:
                _clock.total_s += time.perf_counter() - _clock.started

    if not _listening:
        event.register("numba:compiler_lock", _LockListener())
        _listening.append(True)
    _clock.total_s += time.perf_counter() - start
    return numba


_listening: list[bool] = []
