"""Median wall time of a callable, interleaved with its baseline so noise hits both alike."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def median_seconds(
    *functions: Callable[[], object], repeat: int = 5, warm_up: bool = True
) -> list[float]:
    """Median seconds of each function; runs are interleaved (a, b, a, b, ...) after a warm-up
    (an uncounted run of each; none without ``warm_up``)."""
    for function in functions if warm_up else ():
        function()
    samples: list[list[float]] = [[] for _ in functions]
    for _ in range(repeat):
        for function, times in zip(functions, samples, strict=True):
            start = time.perf_counter()
            function()
            times.append(time.perf_counter() - start)
    return [statistics.median(times) for times in samples]
