"""The ``sweep`` Prefect flow: a plan task, one task per named sweep, an optional report task.

The flow plans the grid, submits every missing point to Dask (largest first, each shared point
once), and starts one task per named sweep of the grid (``threshold``, ``window``, ...). A sweep's
task waits for its own points, assembles its cube and publishes a table artifact of its best
point per model, so the UI shows each sweep's state as its points finish. Meanwhile the flow
follows all points: a progress bar on the terminal, a progress artifact, and run-logger lines
(points done, cache hits, failures). With ``report=True`` a last task writes the report and a
link artifact to it. :func:`flows.run.run_sweep` does the same without Prefect, on a Dask
client the caller may give.

The command line loads and checks the grid before Prefect starts and hands the checked
:class:`pipeline.design.grid.Grid` to the flow, which plans it once and hands the plan to its tasks.

Prefect runs only in this process; the Dask workers run the plain functions of
:mod:`flows.work` and never call the Prefect API (worker processes that did would each start a
temporary Prefect server of their own when no real one is configured).

No step of the sweep waits for the Prefect server or fails with it: artifacts and run-logger
lines go through the run's :class:`flows.record.PrefectRecord`, which keeps what the server could
not take and sends it when the server answers again. A sweep whose server stopped, was killed or
restarted computes, stores and writes its cubes as any other. What stops a sweep is named in
the state of every sweep task it stopped (:class:`flows.progress.StopCause`).
"""

from __future__ import annotations

import re
import sys
import time
from pathlib import Path
from typing import Any

from prefect import flow, get_run_logger, task
from prefect.cache_policies import NO_CACHE
from prefect.states import Cancelled, Failed, State
from prefect.task_runners import ThreadPoolTaskRunner
from prefect.utilities.annotations import quote

from flows.assembly import assemble, cube_location
from flows.planning import SweepPlan, checked_grid, open_root, plan_sweep
from flows.progress import (
    StopCause,
    SweepFailed,
    SweepStopped,
    completed_points,
    describe_stop,
    failure_message,
    point_failures,
    progress_bar,
    stopped_message,
    write_error,
)
from flows.record import PrefectRecord, active_record, run_recorded
from flows.report import needs_report_folder
from flows.run import log_sweep_run, sweep_summary
from flows.scheduling import submit_missing, sweep_client
from pipeline.design.grid import Grid
from pipeline.errors import EskinError
from storage import StoreWriteError

#: Seconds between progress reports to the Prefect API and its log (the bar updates per point).
REPORT_EVERY_S = 5.0
#: Threads for the sweep tasks, which only wait on Dask futures; more sweeps than this queue.
MAX_CONCURRENT_SWEEPS = 32


def flow_run_url() -> str | None:
    """The UI page of the running flow run (as Prefect's own log line gives it), if known."""
    from prefect.runtime import flow_run
    from prefect.settings import PREFECT_UI_URL

    ui, run_id = PREFECT_UI_URL.value(), flow_run.get_id()
    return f"{ui}/runs/flow-run/{run_id}" if ui and run_id else None


def artifact_key(*parts: str) -> str:
    """An artifact key from names (Prefect allows lowercase letters, digits and dashes)."""
    return re.sub(r"[^a-z0-9-]+", "-", "-".join(parts).lower()).strip("-")


@task(name="plan", cache_policy=NO_CACHE)
def plan_task(grid: Grid, root: str) -> SweepPlan:
    """Plan the checked ``grid`` in the run root ``root`` (:func:`flows.planning.plan_sweep`)
    and log how many distinct points are cached and how many are to compute."""
    plan = plan_sweep(grid, root)
    get_run_logger().info(
        "%d distinct points in %d sweeps: %d cached, %d to compute",
        len(plan.scenes),
        len(plan.grid.sweeps),
        len(plan.cached),
        len(plan.missing),
    )
    return plan


@task(name="sweep", cache_policy=NO_CACHE, task_run_name="sweep-{name}")
def sweep_task(
    plan: SweepPlan, name: str, futures: dict[str, Any], cause: StopCause
) -> dict[str, Any] | State:
    """Wait for the sweep's points, assemble its cube, publish its best points as a table;
    return the cube's summary (:func:`flows.assembly.summarize`).

    A sweep whose points were cancelled ends Cancelled, its message naming why
    (``cause``: a write that failed, an interrupt, a lost cluster); one whose cube could not
    be written ends Cancelled with the :class:`storage.errors.StoreWriteError` as its data. A
    state, not an exception, so that the terminal shows no traceback (the flow says it once).
    """
    logger = get_run_logger()
    keys = plan.sweep_keys[name]
    mine = {futures[key] for key in keys if key in futures}
    if mine:
        from distributed import wait
        from distributed.client import FuturesCancelledError

        try:
            wait(mine)
        except FuturesCancelledError:  # the sweep stopped: its work left was cancelled
            pass
    written = next(filter(None, map(write_error, mine)), None)
    if written is not None or any(f.status == "cancelled" for f in mine):
        why = describe_stop(written) if written is not None else cause.wait()
        return Cancelled(message=f"sweep {name!r} stopped: {why}")
    failed = [
        why for f in mine for why in point_failures(f, [k for k in keys if k in futures]).values()
    ]
    if failed:
        raise SweepFailed(failure_message(failed, len(keys), plan.root))
    try:
        summary = assemble(plan, name)
    except StoreWriteError as error:
        return Cancelled(message=str(error), data=error)
    rows = summary["best"]
    _record().table(
        artifact_key(plan.grid.name, name, "best"),
        [{"model": r["model"], "accuracy": round(r["accuracy"], 4), **r["at"]} for r in rows],
        f"Sweep {name!r} of grid {plan.grid.name!r}: the best point per model "
        f"(mean accuracy over folds) of {len(keys)} points. Cube: {cube_location(plan, name)}",
    )
    for r in rows:
        at = ", ".join(f"{dim}={value}" for dim, value in r["at"].items())
        logger.info("%s: best %s %.1f %% at %s", name, r["model"], 100 * r["accuracy"], at)
    return summary


@task(name="report", cache_policy=NO_CACHE)
def report_task(root: str) -> str:
    """Write the report of the run root ``root`` (:func:`flows.report.write_run_report`),
    publish a link artifact to it, and return the path of its ``report.html``."""
    from flows.report import write_run_report

    path = write_run_report(Path(root))
    _record().link(
        artifact_key(Path(root).name, "report"),
        path.absolute().as_uri(),
        str(path),
        "The sweep's report: figures, the paper's claims, Table I.",
    )
    return str(path)


def _record() -> PrefectRecord:
    """The run's record (:func:`flows.record.run_recorded` makes it active for the flow)."""
    record = active_record()
    if record is None:
        raise RuntimeError("a sweep task runs only in the sweep flow, whose record is active")
    return record


@flow(
    name="sweep",
    task_runner=ThreadPoolTaskRunner(max_workers=MAX_CONCURRENT_SWEEPS),
    log_prints=False,
)
def sweep(
    grid: str | Grid = "smoke",
    root: str | None = None,
    workers: int | None = None,
    address: str | None = None,
    dataset: str | None = None,
    report: bool = False,
    show_progress: bool = False,
) -> dict[str, Any] | State:
    """Sweep a grid into labelled cubes under ``root``.

    ``grid`` is a built-in name or a TOML file, loaded and checked here, or a
    :class:`pipeline.design.grid.Grid` its caller has checked (:func:`flows.planning.check_grid`),
    as the command line does before Prefect starts. ``root`` defaults to ``runs/<grid name>``;
    ``address`` (``tcp://HOST:PORT``) uses an existing Dask scheduler instead of a local
    cluster of ``workers`` processes (default: one per available core); ``dataset`` (a folder
    or ``synthetic``) replaces the recordings of a grid given by name or file; ``report``
    writes the report under ``<root>/report`` at the end.

    A write to the root that fails for want of space or permission stops the sweep: the work
    left is cancelled and the run ends Failed; calling the flow raises
    :class:`flows.progress.SweepStopped`, whose one line says how many points are kept. A
    Prefect server that stops answering does not stop it (:mod:`flows.record`).
    """
    start = time.perf_counter()
    logger = get_run_logger()
    if not isinstance(grid, Grid) or dataset is not None:
        grid = checked_grid(grid, dataset)
    if report and root is not None and (problem := needs_report_folder(root)):
        raise EskinError(f"report: {problem}")
    store = open_root(grid, root, dataset)

    def body(record: PrefectRecord) -> dict[str, Any] | State:
        summary: dict[str, Any] = {"flow_run_url": flow_run_url(), "dashboard": None}
        if show_progress and summary["flow_run_url"]:
            print(f"Prefect flow run: {summary['flow_run_url']}", file=sys.stderr)
        # One sweep per root: a second one is refused here (the command line takes the lock
        # before it starts Prefect, and this nests in it). The kernel drops it if this process
        # is killed (an object root's lease expires).
        with store.lock():
            plan = plan_task(grid, str(store.root))
            futures: dict[str, Any] = {}
            runs: list[Any] = []
            stop: StoreWriteError | None = None
            cause = StopCause()
            try:
                with sweep_client(plan, workers=workers, address=address) as client:
                    try:
                        if client is not None:
                            summary["dashboard"] = client.dashboard_link
                            logger.info("Dask dashboard: %s", client.dashboard_link)
                            if show_progress:
                                print(f"Dask dashboard: {client.dashboard_link}", file=sys.stderr)
                            futures = submit_missing(plan, client)
                        # Quoted: Prefect would walk the plan and the futures for each task's
                        # inputs.
                        runs = [
                            sweep_task.submit(quote(plan), s.name, quote(futures), quote(cause))
                            for s in plan.grid.sweeps
                        ]
                        if futures:
                            _follow(plan, client, futures, show_progress, record)
                        for run in runs:
                            run.wait()
                    except BaseException as error:
                        cause.note(error)  # before the cluster closes and the tasks wake
                        raise
            except StoreWriteError as error:  # the work left is cancelled, the cluster closed
                stop = error
            for run in runs:
                run.wait()
            stop = stop or next(filter(None, map(_write_failure, runs)), None)
            if stop is not None:
                # A state, not an exception: one line on the terminal, no traceback; calling
                # the flow raises its data.
                message = stopped_message(plan, stop)
                return Failed(message=message, data=SweepStopped(message))
            failed = [run.state.message for run in runs if not run.state.is_completed()]
            if failed:
                raise SweepFailed(f"{len(failed)} of {len(runs)} sweeps failed: {failed[0]}")
            sweeps = {s.name: run.result() for s, run in zip(plan.grid.sweeps, runs, strict=True)}
        summary |= sweep_summary(plan, sweeps, len(futures), time.perf_counter() - start)
        log_sweep_run(plan, summary, warn=logger.warning)  # before the report, which shows it
        if report:
            summary["report"] = report_task(plan.root)
        return summary

    return run_recorded(body, what=f"sweep {grid.name!r}", root=str(store.root))


def _write_failure(run: Any) -> StoreWriteError | None:
    """The write failure a finished sweep task's state holds, if it stopped so."""
    if not run.state.is_cancelled():
        return None
    error = run.state.result(raise_on_failure=False)
    return error if isinstance(error, StoreWriteError) else None


def _follow(
    plan: SweepPlan,
    client: Any,
    futures: dict[str, Any],
    show_progress: bool,
    record: PrefectRecord,
) -> None:
    """Follow every submitted point: the bar per point, the record and log every few seconds."""
    logger = get_run_logger()
    total, done, failures = len(plan.scenes), len(plan.cached), 0
    key = artifact_key(plan.grid.name, "progress")
    description = f"Points of grid {plan.grid.name!r} done (cached ones count as done)."
    record.progress(key, 100 * done / total, description)
    last = time.monotonic()
    with progress_bar(plan, show_progress) as bar:
        for _, failure in completed_points(client, futures):
            done += 1
            bar.update(1)
            if failure:
                failures += 1
                logger.error("point failed: %s", failure)
            if time.monotonic() - last >= REPORT_EVERY_S or done == total:
                last = time.monotonic()
                record.progress(key, 100 * done / total, description)
                logger.info(
                    "%d of %d points done (%d cached, %d failed)",
                    done,
                    total,
                    len(plan.cached),
                    failures,
                )
