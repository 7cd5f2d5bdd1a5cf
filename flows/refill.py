"""Trials refilled as workers free: a new trial is asked the moment one finishes.

A search that asked its trials in batches (as many as the cluster's worker threads) waited for
the batch's slowest trial before asking the next: a worker whose trial finished early idled,
and with trials of a threshold and of a 32x32 array in one batch, most of the batch's time.
:func:`refill` keeps ``slots`` trials running instead: it asks while a slot is free, starts the
trial, waits for the first running one to finish, tells it, and asks again. The trials still
running stay pending in the sampler while it asks (:class:`flows.samplers.Proposer`).

The loop knows nothing of Dask, Optuna or clocks: ``start`` gives a future, ``wait`` (by
default :func:`concurrent.futures.wait`) says which finished, so the benchmark replays searches
on a simulated clock with the same loop.
"""

from __future__ import annotations

import concurrent.futures
from collections.abc import Callable, Iterable
from typing import Any

#: ``wait(futures, return_when=FIRST_COMPLETED)`` -> (done, not done), as concurrent.futures'.
Wait = Callable[..., tuple[Iterable[Any], Iterable[Any]]]


def refill(
    slots: int,
    ask: Callable[[int], int | None],
    start: Callable[[int], Any],
    finish: Callable[[int, Any], None],
    wait: Wait = concurrent.futures.wait,
) -> None:
    """Run trials, ``slots`` at a time, until ``ask`` gives no more and none is running.

    ``ask(running)`` gives the next trial's number, or None for none now (the budget is spent;
    ``running`` is how many trials are still running); ``start(number)`` starts it and gives a
    future (hashable); ``finish(number, future)`` tells it, once it is done. Trials that finish
    together are told in the order they were asked.
    """
    if slots < 1:
        raise ValueError(f"slots must be at least 1, got {slots}")
    running: dict[Any, int] = {}
    while True:
        while len(running) < slots:
            number = ask(len(running))
            if number is None:
                break
            running[start(number)] = number
        if not running:
            return
        done, _ = wait(list(running), return_when=concurrent.futures.FIRST_COMPLETED)
        for future in sorted(done, key=running.__getitem__):
            finish(running.pop(future), future)
