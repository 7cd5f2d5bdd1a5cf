"""Numba kernels compiled on first use, with numba itself imported only then.

Importing numba costs 0.15-0.4 s, which every command would pay for kernels that only a
simulation calls (a report, a dry run or a re-run with nothing to compute calls none). A kernel
is declared with :func:`kernel` instead of ``numba.njit``; the first call of any kernel of a
module imports numba, compiles every kernel of that module (``cache=True, nogil=True`` and the
kernel's own options) and puts the compiled dispatchers in the module's namespace in place of
the placeholders, so that kernels calling kernels resolve to compiled code, as with ``njit``
at import. Numba's on-disk cache works as with ``njit``.
"""

from __future__ import annotations

import functools
import sys
import threading
from collections.abc import Callable
from typing import Any

_DEFAULTS = {"cache": True, "nogil": True}
_pending: dict[str, list[tuple[Callable[..., Any], dict[str, Any]]]] = {}
_compiling = threading.Lock()


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
            import numba

            for function, options in kernels:
                namespace[function.__name__] = numba.njit(**options)(function)
    return namespace
