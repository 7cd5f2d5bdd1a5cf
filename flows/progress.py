"""Following a sweep's submitted points: each point as its task finishes, failures, the bar.

:func:`completed_points` yields every point once its task is done, with the reason it failed
(:func:`point_failures`), and gives up on a cluster left without workers; a sweep whose points
failed ends with :class:`SweepFailed` (:func:`failure_message`).

A write that failed for want of space or permission (:class:`storage.errors.StoreWriteError`) is not
a failed point: every later write would fail alike. The first one cancels the work left and
stops the sweep, which ends with :class:`SweepStopped`, one line saying what the root keeps
(:func:`stopped_message`).

Whatever stops a sweep, what sees its work cancelled names the real cause (:class:`StopCause`):
a write that failed, an interrupt (Ctrl-C, SIGTERM), a cluster that was lost, or the error
that stopped it. A Prefect server that stops answering never stops a sweep
(:mod:`flows.record`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from typing import Any

from flows.planning import SweepPlan
from pipeline.errors import EskinError
from pipeline.run.stages import RESULTS
from storage import StoreWriteError, SweepStore

POLL_S = 2.0
NO_WORKER_TIMEOUT_S = 120.0


class SweepFailed(EskinError):
    """Some points of a sweep failed; the others are in the store (exit status 1)."""

    exit_status = 1


class SweepStopped(SweepFailed):
    """A write to the run root failed for want of space or permission: the sweep stopped early,
    keeping the points written before (exit status 1)."""


class StopCause:
    """Why a sweep stopped, for the tasks that find their points cancelled.

    Whatever stops the sweep notes the cause (:meth:`StopCause.note`) before the work is
    cancelled or the cluster closed; a task that finds its points cancelled reads it
    (:meth:`StopCause.wait`). Points cancelled when nothing noted a cause were cancelled by the
    cluster: it was lost.
    """

    #: The cause of points cancelled when nothing noted one.
    CLUSTER_LOST = "the Dask cluster was lost (its scheduler or workers went away)"

    def __init__(self) -> None:
        self._why: str | None = None
        self._noted = threading.Event()

    def note(self, error: BaseException) -> None:
        """Note ``error`` as the cause (the first one noted stays)."""
        if not self._noted.is_set():
            self._why = describe_stop(error)
            self._noted.set()

    def wait(self, timeout_s: float = 10.0) -> str:
        """The cause, waiting up to ``timeout_s`` for it to be noted (the work is cancelled
        just before), else :attr:`StopCause.CLUSTER_LOST`."""
        return self._why if self._noted.wait(timeout_s) and self._why else self.CLUSTER_LOST


def describe_stop(error: BaseException) -> str:
    """The cause of a stop, as the sweep's tasks say it."""
    if isinstance(error, StoreWriteError):
        return f"a write to the run root failed ({error})"
    if not isinstance(error, Exception):  # KeyboardInterrupt, Prefect's TerminationSignal
        return "it was interrupted (Ctrl-C or SIGTERM)"
    if isinstance(error, EskinError):
        return str(error)
    return f"{type(error).__name__}: {error}"


def stopped_message(plan: SweepPlan, error: StoreWriteError) -> str:
    """One line: the root and the cause of ``error``, how many points the root keeps, and that
    a re-run resumes."""
    try:
        stored = SweepStore.open(plan.root).complete_keys(RESULTS.name)
    except OSError:  # a root we may no longer read: what planning found
        stored = frozenset()
    kept = len(plan.cached | (stored & plan.scenes.keys()))
    return (
        f"{error}; the sweep stopped, {kept} of {len(plan.scenes)} points are kept, "
        f"and running it again resumes from them"
    )


def write_error(future: Any) -> StoreWriteError | None:
    """The finished task ``future``'s :class:`storage.errors.StoreWriteError`, if that is how it
    failed."""
    if future.status != "error":
        return None
    error = future.exception()
    return error if isinstance(error, StoreWriteError) else None


def progress_bar(plan: SweepPlan, show_progress: bool) -> Any:
    """A tqdm bar over the plan's distinct points, cached ones counted as done."""
    from tqdm import tqdm

    return tqdm(
        total=len(plan.scenes),
        initial=len(plan.cached),
        unit="point",
        desc=f"sweep {plan.grid.name}",
        disable=None if show_progress else True,
    )


def failure_message(failures: list[str], n_points: int, root: str) -> str:
    """One line: how many of ``n_points`` failed, the first three failures, where the rest are."""
    shown = "; ".join(failures[:3]) + (
        f"; and {len(failures) - 3} more" if len(failures) > 3 else ""
    )
    return f"{len(failures)} of {n_points} points failed (the others are kept in {root}): {shown}"


def completed_points(client: Any, futures: dict[str, Any]) -> Iterator[tuple[str, str | None]]:
    """Yield ``(key, failure)`` for every point as its task finishes (``failure`` None for a
    success).

    A task that stored some of its points and failed others (:class:`flows.work.PointsFailed`)
    counts only those as failed; a task that failed as a whole fails all its points.

    Raises
    ------
    StoreWriteError
        A task could not write to the root (no space, no permission); the tasks left are
        cancelled first.
    SweepFailed
        The cluster has had no worker for ``NO_WORKER_TIMEOUT_S``.
    """
    if not futures:
        return
    from distributed import wait

    points: dict[Any, list[str]] = {}
    for key, future in futures.items():
        points.setdefault(future, []).append(key)
    pending = set(points)
    alone_since = None
    while pending:
        try:
            done = wait(pending, timeout=POLL_S, return_when="FIRST_COMPLETED").done
        except TimeoutError:
            done = set()
        for future in done:
            pending.discard(future)
            if (error := write_error(future)) is not None:
                # Every later write would fail alike: keep what is written and stop now. The
                # failed tasks go too: a re-run on this client would be handed their errors.
                client.cancel(list(points))
                raise error
            failures = point_failures(future, points[future])
            for key in points[future]:
                yield key, failures.get(key)
        if client.nthreads():
            alone_since = None
        elif alone_since is None:
            alone_since = time.monotonic()
        elif time.monotonic() - alone_since > NO_WORKER_TIMEOUT_S:
            n_left = sum(len(points[f]) for f in pending)
            raise SweepFailed(
                f"the Dask cluster has had no worker for {NO_WORKER_TIMEOUT_S:.0f} s with "
                f"{n_left} points left; finished points are kept in the store"
            )


def point_failures(future: Any, keys: list[str]) -> dict[str, str]:
    """Why each of ``keys`` failed in the finished task ``future``; empty if none failed.

    A task that failed some of its own points names them (:class:`flows.work.PointsFailed`);
    one whose error names none of its points never ran: a task it waited for (a spike train
    its points share with other tasks) failed, and so did every one of its points.
    """
    if future.status != "error":
        return {}
    from flows.work import PointsFailed

    error = future.exception()
    if isinstance(error, PointsFailed):
        mine = {key: f"point {key}: {why}" for key, why in error.failures.items() if key in keys}
        if mine:
            return mine
        return dict.fromkeys(keys, f"{future.key}: the spike train it needs failed: {error}")
    return dict.fromkeys(keys, f"{future.key}: {error}")
