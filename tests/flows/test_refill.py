"""Trials refilled as workers free (:func:`flows.refill.refill`), with a fake evaluator: no
worker waits for a batch."""

import concurrent.futures
import threading

import pytest

from flows.refill import refill


def test_a_worker_that_finishes_early_gets_a_new_trial_without_waiting():
    # Trial 0 runs until the test releases it; trial 1 finishes at once. Trial 2 must start
    # while trial 0 is still running, and trial 0 is released only once trial 2 has started.
    release = threading.Event()
    started: list[int] = []
    finished: list[int] = []
    asked = iter(range(4))

    def work(number: int) -> int:
        if number == 0:
            assert release.wait(10), "trial 0 was never released"
        return number

    with concurrent.futures.ThreadPoolExecutor(2) as pool:

        def start(number: int) -> concurrent.futures.Future:
            started.append(number)
            if number == 2:
                release.set()
            return pool.submit(work, number)

        def finish(number: int, future: concurrent.futures.Future) -> None:
            assert future.result() == number
            finished.append(number)

        refill(2, lambda running: next(asked, None), start, finish)
    assert started == [0, 1, 2, 3]
    assert finished.index(1) < finished.index(0)
    assert set(finished) == {0, 1, 2, 3}


def test_ask_sees_the_running_trials_and_stops_the_search():
    seen: list[int] = []

    def ask(running: int) -> int | None:
        seen.append(running)
        return len(seen) - 1 if len(seen) <= 3 else None

    done: list[int] = []
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        refill(2, ask, lambda n: pool.submit(lambda: n), lambda n, f: done.append(f.result()))
    assert sorted(done) == [0, 1, 2]
    assert seen[:2] == [0, 1]  # the second trial was asked with the first running
    with pytest.raises(ValueError, match="slots"):
        refill(0, ask, lambda n: None, lambda n, f: None)
