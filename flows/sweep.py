"""The ``sweep`` Prefect flow: three coarse tasks around :mod:`flows.orchestrate`.

Prefect runs only in this process (``plan``, ``compute``, ``assemble``); the Dask workers run
the plain functions of :mod:`flows.work` and never call the Prefect API (worker processes that
did would each start their own temporary Prefect server on one SQLite file).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from prefect import flow, task
from prefect.cache_policies import NO_CACHE

from flows.cluster import dask_client
from flows.environment import hermetic_environment
from flows.orchestrate import SweepPlan, assemble_cubes, compute_missing, plan_sweep


@task(name="plan", cache_policy=NO_CACHE)
def plan_task(grid: str, root: str | None) -> SweepPlan:
    return plan_sweep(grid, root)


@task(name="compute", cache_policy=NO_CACHE)
def compute_task(plan: SweepPlan, workers: int, address: str | None, show_progress: bool) -> int:
    hermetic_environment(Path(plan.root), prefect=False)
    with dask_client(workers, address) as client:
        return compute_missing(plan, client, show_progress=show_progress)


@task(name="assemble", cache_policy=NO_CACHE)
def assemble_task(plan: SweepPlan) -> dict[str, str]:
    return assemble_cubes(plan)


@flow(name="sweep")
def sweep(
    grid: str = "smoke",
    root: str | None = None,
    workers: int = 2,
    address: str | None = None,
    show_progress: bool = False,
) -> dict[str, Any]:
    """Sweep a grid (a built-in name or a TOML file) into labelled cubes under ``root``.

    ``root`` defaults to ``runs/<grid name>``; ``address`` (``tcp://HOST:PORT``) uses an
    existing Dask scheduler instead of a local cluster of ``workers`` processes.
    """
    start = time.perf_counter()
    plan = plan_task(grid, root)
    computed = compute_task(plan, workers, address, show_progress) if plan.missing else 0
    cubes = assemble_task(plan)
    return {
        "root": plan.root,
        "cubes": cubes,
        "points": len(plan.scenes),
        "cache_hits": len(plan.cached),
        "computed": computed,
        "seconds": time.perf_counter() - start,
    }
