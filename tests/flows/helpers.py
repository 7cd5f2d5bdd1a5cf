"""End-to-end test helpers: run the real command line and servers in a hermetic environment."""

import base64
import contextlib
import json
import math
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Collection, Iterator
from pathlib import Path
from typing import Any

import xarray as xr

from pipeline.chain.metrics import SpikeMetrics
from pipeline.results.variables import MEASURED
from storage import open_results

BIN = Path(sys.executable).parent

#: A grid of two sweeps on ``smoke`` with 3 distinct points (the window sweep's 0.1 s point is the
#: threshold sweep's 0.09 V one).
SMALL_GRID = """
name = "api"
base = "smoke"

[sweeps.threshold]
axes = { "readout.threshold_v" = [0.05, 0.09] }

[sweeps.window]
axes = { "coding.window_s" = [0.1, 0.2] }
"""

#: Spike metrics of a hand-made result entry.
METRICS = SpikeMetrics(
    ssnr_db=math.inf,
    ste_s2=0.0,
    ste_sign_safe_s2=0.0,
    event_rate_hz=100.0,
    data_rate_bps=300.0,
    equivalent_bits=3.0,
)


def count_grid_loads(patch) -> dict[str, int]:
    """Count the grid loads and dataset checks from now on: calls of
    :func:`pipeline.design.grid.load_grid` (as :mod:`flows.planning` calls it) and of
    :meth:`pipeline.run.fit.DatasetLimits.describe`, patched with ``patch(owner, name, value)``
    (``monkeypatch.setattr``, or ``setattr`` in a subprocess). Returns the live counts."""
    from flows import planning
    from pipeline.run.fit import DatasetLimits

    calls = {"load_grid": 0, "describe": 0}
    load, describe = planning.load_grid, DatasetLimits.describe

    def counted_load(*args):
        calls["load_grid"] += 1
        return load(*args)

    def counted_describe(spec):
        calls["describe"] += 1
        return describe(spec)

    patch(planning, "load_grid", counted_load)
    patch(DatasetLimits, "describe", counted_describe)
    return calls


@contextlib.contextmanager
def in_process_client(threads: int = 1) -> Iterator[Any]:
    """A Dask client on an in-process cluster of one worker with ``threads`` threads."""
    from distributed import Client, LocalCluster

    # No dashboard; the scheduler's HTTP routes (health, metrics) on a free loopback port, not on
    # 8787, which another pytest-xdist worker's cluster may hold.
    with (
        LocalCluster(
            n_workers=1,
            threads_per_worker=threads,
            processes=False,
            dashboard_address=None,
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client


#: Seconds a cluster started by :func:`start_cluster` waits without a client before its
#: scheduler stops, and its workers without a scheduler before they stop: a backstop should the
#: suite die before stopping it.
CLUSTER_IDLE_S = 900


def write_credentials(folder: Path, security: Any) -> dict[str, str]:
    """A Dask ``Security``'s in-memory CA, certificate and key as files only their owner
    reads, by the ``eskin sweep`` option that takes each (``folder`` is made)."""
    folder.mkdir()
    files = {}
    for option, pem in (
        ("--tls-ca-file", security.tls_ca_file),
        ("--tls-cert", security.tls_client_cert),
        ("--tls-key", security.tls_client_key),
    ):
        path = folder / option.removeprefix("--")
        path.touch(mode=0o600)
        path.write_text(pem)
        files[option] = str(path)
    return files


def start_cluster(
    folder: Path, env: dict[str, str], workers: int = 2
) -> tuple[list[str], list[int]]:
    """A ``dask scheduler`` and ``workers`` single-thread ``dask worker`` processes on
    127.0.0.1, speaking TLS with credentials made for them (in ``folder/credentials``); each
    process runs in a scratch folder of its own under ``folder`` (made). Returns the arguments
    that send an ``eskin sweep`` or ``eskin optimize`` there (``--address`` and the ``--tls-*``
    files) and the processes' PIDs, the scheduler's first (:func:`stop_pids` stops them)."""
    from distributed.security import Security

    folder.mkdir(parents=True, exist_ok=True)
    files = write_credentials(folder / "credentials", Security.temporary())
    tls = [*("--tls-ca-file", files["--tls-ca-file"]), *("--tls-cert", files["--tls-cert"])]
    tls += ["--tls-key", files["--tls-key"]]
    scheduler_file = folder / "scheduler" / "scheduler.json"
    scheduler_file.parent.mkdir()
    pids = []

    def started(command: list[str | Path], scratch: Path) -> None:
        pids.append(
            subprocess.Popen(
                command,
                env={**env, "DASK_TEMPORARY_DIRECTORY": str(scratch)},
                cwd=scratch,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,  # stopped by PID, not by a signal to the test's group
            ).pid
        )

    started(
        [
            *(BIN / "dask", "scheduler", "--protocol", "tls", "--host", "127.0.0.1", "--port", "0"),
            *("--no-dashboard", "--scheduler-file", str(scheduler_file), *tls),
            *("--idle-timeout", f"{CLUSTER_IDLE_S}s"),
        ],
        scheduler_file.parent,
    )
    try:
        wait_for(lambda: scheduler_file.exists() and scheduler_file.read_text(), 120, "a scheduler")
        address = json.loads(scheduler_file.read_text())["address"]
        for i in range(workers):
            scratch = folder / f"worker-{i}"
            scratch.mkdir()
            command = [BIN / "dask", "worker", address, "--nthreads", "1", "--host", "127.0.0.1"]
            command += ["--no-dashboard", "--local-directory", str(scratch), *tls]
            started([*command, "--death-timeout", f"{CLUSTER_IDLE_S}s"], scratch)
    except BaseException:
        stop_pids(pids)
        raise
    return ["--address", address, *tls], pids


def stop_pids(pids: Collection[int]) -> None:
    """Stop processes started by any process of the suite, by PID, with every process they
    started (a nanny's worker: stopped alone, a nanny waits seconds for it): SIGTERM to all at
    once, then SIGKILL after 20 s. A process that is gone, or only a zombie, counts as stopped."""
    import psutil

    processes = []
    for pid in pids:
        with contextlib.suppress(psutil.NoSuchProcess):
            process = psutil.Process(pid)
            processes += [process, *process.children(recursive=True)]
    for process in processes:
        with contextlib.suppress(psutil.NoSuchProcess):
            process.terminate()

    def gone(process: psutil.Process) -> bool:
        try:
            return process.status() == psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return True

    deadline = time.monotonic() + 20
    while not all(map(gone, processes)) and time.monotonic() < deadline:
        time.sleep(0.1)
    for process in processes:
        with contextlib.suppress(psutil.NoSuchProcess):
            if not gone(process):
                process.kill()


def hermetic_env(base: Path, **extra: str) -> dict[str, str]:
    """The test's environment without the user's Prefect settings, state under ``base``."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PREFECT_", "DASK_"))}
    env.update(
        {
            "PREFECT_HOME": str(base / "prefect-home"),
            "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
            "DO_NOT_TRACK": "1",
            "DASK_TEMPORARY_DIRECTORY": str(base / "dask-tmp"),
            "MPLCONFIGDIR": str(base / "mpl"),
            **extra,
        }
    )
    return env


def server_state_with_db(state: Path, database: Path) -> Path:
    """Make ``state``, a local server's state folder, as the server makes it (mode 0700), with a
    copy of ``database`` (a Prefect database already set up) as the server's; return it."""
    state.mkdir(mode=0o700, parents=True)
    shutil.copyfile(database, state / "prefect.db")
    return state


def api_headers(auth: str | None) -> dict[str, str]:
    """Headers of a JSON request to the Prefect API, with ``auth`` as its basic-auth string."""
    headers = {"Content-Type": "application/json"}
    if auth is not None:
        headers["Authorization"] = f"Basic {base64.b64encode(auth.encode()).decode()}"
    return headers


def eskin(*args: str, env: dict[str, str], timeout: float = 900) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "flows.cli", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        stdin=subprocess.DEVNULL,
    )


def stop(*processes: subprocess.Popen) -> None:
    """Stop processes we started, by PID: SIGTERM, then SIGKILL after 20 s."""
    for process in processes:
        if process.poll() is None:
            process.terminate()
    deadline = time.monotonic() + 20
    for process in processes:
        try:
            process.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def wait_for(predicate, timeout: float, what: str, interval: float = 0.5) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(interval)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


def live_tree(root: Path) -> set[Path]:
    """Every entry below ``root`` (relative paths) while a sweep may be writing under it.

    A running sweep renames ``.partial-*`` entries into place and removes others, so a folder
    listed a moment ago may be gone before it is entered; ``Path.rglob`` then raises
    FileNotFoundError. Here a folder that vanished is skipped, and an entry counts if it was
    listed: the snapshot is of what existed during the walk, not of one instant.
    """
    found = set()
    for folder, dirs, files in os.walk(root, onerror=lambda error: None):
        here = Path(folder).relative_to(root)
        found.update(here / name for name in (*dirs, *files))
    return found


def assert_same_cubes(root_a: Path, root_b: Path, cubes: Collection[str] | None = None) -> None:
    """The cubes of two roots (or those named ``cubes``, which both hold) are identical but for
    the measured wall times (``seconds``, ``work_seconds``:
    :data:`pipeline.results.variables.MEASURED`)."""
    a, b = open_results(root_a), open_results(root_b)
    if cubes is None:
        assert a and set(a) == set(b)
    else:
        assert set(cubes) and set(cubes) <= set(a) & set(b), (set(a), set(b))
    for name in a if cubes is None else cubes:
        # Everything but the measured seconds is a function of the grid and its seeds.
        assert set(MEASURED) <= set(a[name].data_vars) and set(MEASURED) <= set(b[name].data_vars)
        xr.testing.assert_identical(a[name].drop_vars(MEASURED), b[name].drop_vars(MEASURED))
