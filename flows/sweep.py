"""The ``sweep`` Prefect flow: three coarse tasks around :mod:`flows.orchestrate`.

Prefect runs only in this process (``plan``, ``compute``, ``assemble``); the Dask workers run
the plain functions of :mod:`flows.work` and never call the Prefect API (worker processes that
did would each start their own temporary Prefect server on one SQLite file).
"""

from __future__ import annotations

import atexit
import subprocess
import time
from pathlib import Path
from typing import Any

from prefect import flow, task
from prefect.cache_policies import NO_CACHE

from flows import watchdog
from flows.cluster import dask_client
from flows.environment import hermetic_environment
from flows.orchestrate import SweepPlan, assemble_cubes, compute_missing, open_root, plan_sweep


def guard_temporary_server() -> None:
    """Start Prefect's temporary server (when no server is configured) under a watchdog.

    Prefect starts that server as a plain subprocess and stops it at interpreter exit; a sweep
    killed by SIGKILL would leave it running, holding the root's Prefect database. Starting it
    here first (Prefect's client then reuses it) gives its PID to :mod:`flows.watchdog`, which
    stops it as soon as this process is gone. On a normal exit Prefect stops it first, after
    flushing its logs and events; the watchdog then finds it gone.
    """
    from prefect.settings import PREFECT_API_URL

    if PREFECT_API_URL.value():
        return
    from prefect.server.api.server import SubprocessASGIServer

    guards: list[subprocess.Popen] = []
    atexit.register(_release, guards)  # atexit runs last-in first-out: after Prefect's stop
    server = SubprocessASGIServer()
    server.start()
    guards.append(watchdog.start(server.server_process.pid, "prefect.server.api.server:create_app"))


def _release(guards: list[subprocess.Popen]) -> None:
    for guard in guards:
        guard.stdin.close()  # end of file: the watchdog stops the server if it still runs
        guard.wait()


@task(name="plan", cache_policy=NO_CACHE)
def plan_task(grid: str, root: str) -> SweepPlan:
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
    store = open_root(grid, root)
    # One sweep per root: a second one is refused here (the command line takes the lock before
    # it starts Prefect, and this nests in it). The kernel drops it if this process is killed.
    with store.lock():
        plan = plan_task(grid, str(store.root))
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
