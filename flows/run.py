"""A whole sweep as one plain call, without Prefect: :func:`~flows.run.run_sweep`, and what it
reports.

What the ``sweep`` flow (:mod:`flows.sweep`) does, step by step, for a notebook or a script:
load and check the grid (:mod:`flows.planning`), hold the root's lock, plan, submit the missing
points (:mod:`flows.scheduling`), follow them (:mod:`flows.progress`), assemble the cubes
(:mod:`flows.assembly`) and log the sweep for the report. :func:`sweep_summary` and
:func:`log_sweep_run` serve the flow as well.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from flows.assembly import assemble, cube_location
from flows.cluster import ClusterError, check_workers
from flows.planning import SweepPlan, checked_grid, open_root, plan_sweep
from flows.progress import (
    SweepFailed,
    SweepStopped,
    completed_points,
    failure_message,
    progress_bar,
    stopped_message,
)
from flows.scheduling import submit_missing, sweep_client
from pipeline.design.grid import Grid
from storage import StoreWriteError


def sweep_summary(
    plan: SweepPlan, sweeps: dict[str, dict[str, Any]], computed: int, seconds: float
) -> dict[str, Any]:
    """A finished sweep's summary, as ``eskin sweep --json`` prints it.

    ``sweeps`` holds the summary of each assembled cube by sweep name
    (:func:`flows.assembly.summarize`). Keys: ``root``, ``cubes`` (each cube's location by sweep
    name), ``sweeps`` (``sweeps``), ``points`` (distinct), ``cache_hits``, ``computed`` and
    ``seconds`` (the sweep's wall time, s).
    """
    return {
        "root": plan.root,
        "cubes": {name: cube_location(plan, name) for name in sweeps},
        "sweeps": sweeps,
        "points": len(plan.scenes),
        "cache_hits": len(plan.cached),
        "computed": computed,
        "seconds": seconds,
    }


def log_sweep_run(
    plan: SweepPlan, summary: dict[str, Any], warn: Callable[..., Any] | None = None
) -> None:
    """Append the sweep to the root's run log, which the report shows.

    A log that cannot be written does not fail the sweep: ``warn`` (default: this module's
    logger) is called with a %-format message instead.
    """
    from storage import StoreError
    from storage.runlog import append_sweep_run

    try:
        append_sweep_run(plan.root, {**summary, "grid": plan.grid.name})
    except (OSError, StoreError) as error:
        (warn or logging.getLogger(__name__).warning)(
            "sweep not logged in %s: %s", plan.root, error
        )


def run_sweep(
    grid: str | Path | Grid,
    root: str | Path | None = None,
    *,
    client: Any = None,
    workers: int | None = None,
    dataset: str | Path | None = None,
    show_progress: bool = False,
) -> dict[str, Any]:
    """Sweep a grid into labelled cubes under ``root``, on a Dask client, without Prefect.

    What the ``sweep`` flow does, as one plain call for a notebook or a script: hold the
    root's lock, plan the grid, submit its missing points, wait for them, assemble and write
    every cube, and log the sweep for the report.

    Parameters
    ----------
    grid
        A built-in grid name (``paper``, ``smoke``), a grid TOML file or a
        :class:`pipeline.design.grid.Grid`; loaded (if need be) and checked once.
    root
        The run root (default: :func:`flows.planning.default_root`), created if need be.
    client
        A ``distributed.Client`` to compute on, left open. Default: a local cluster of
        ``workers`` single-thread processes, started only if a point is missing and stopped
        at the end.
    workers
        Workers of that local cluster (default: one per available core); not with ``client``.
    dataset
        Other recordings for every point (``"synthetic"`` or a dataset folder), as
        ``eskin sweep --dataset``; only with a grid name or file.
    show_progress
        Show a progress bar over the points on stderr.

    Returns
    -------
    dict
        :func:`sweep_summary`, plus ``dashboard`` (the Dask dashboard's address, or None when
        nothing was computed).

    Raises
    ------
    EskinError
        Bad input (grid, dataset, root, ``workers``), before anything is written; a root that
        another sweep holds (:class:`storage.errors.StoreBusyError`).
    SweepFailed
        Some points failed; the cubes of the sweeps they are not in are written.
    SweepStopped
        A write to the root failed for want of space or permission: the work left was
        cancelled, what was written is kept, and a re-run resumes from it.
    """
    start = time.perf_counter()
    if workers is not None:
        if client is not None:
            raise ClusterError("give a client or a number of workers, not both")
        workers = check_workers(workers, name="workers")
    checked = checked_grid(grid, dataset)
    store = open_root(checked, root, dataset)
    with store.lock():
        plan = plan_sweep(checked, store.root)
        failed: dict[str, str] = {}
        try:
            with sweep_client(plan, client, workers) as dask:
                futures = submit_missing(plan, dask) if dask is not None else {}
                with progress_bar(plan, show_progress) as bar:
                    for key, failure in completed_points(dask, futures):
                        bar.update(1)
                        if failure:
                            failed[key] = failure
                dashboard = dask.dashboard_link if dask is not None else None
            sweeps = {
                spec.name: assemble(plan, spec.name)
                for spec in plan.grid.sweeps
                # A sweep with a failed point has no cube: a cube never holds a hole.
                if not failed.keys() & set(plan.sweep_keys[spec.name])
            }
        except StoreWriteError as error:
            raise SweepStopped(stopped_message(plan, error)) from None
    if failed:
        raise SweepFailed(failure_message(list(failed.values()), len(plan.scenes), plan.root))
    summary = sweep_summary(plan, sweeps, len(futures), time.perf_counter() - start)
    log_sweep_run(plan, summary)
    return summary | {"dashboard": dashboard}
