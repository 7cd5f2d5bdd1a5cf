"""A sweep outlives its Prefect server: stopped, killed or restarted mid-sweep, it computes on,
writes the same cubes as an uninterrupted run and says in one line what Prefect lacks.

The sweeps here sweep the smoke grid with a Prefect server state of this module's own (so that
stopping it leaves the suite's shared server alone; the first sweep starts it, later ones
restart it) and compare their cubes with the suite's uninterrupted smoke sweep. A smoke point
takes a fraction of a second once numba's cache is warm: the sweep's workers are paused
(SIGSTOP) while its server goes, so that it cannot end before, and the sweep has points left.
"""

import contextlib
import json
import os
import signal
import subprocess
import time
import urllib.request
from collections.abc import Callable, Iterator
from pathlib import Path

import psutil
import pytest

from flows import server
from tests.flows.helpers import (
    api_headers,
    assert_same_cubes,
    eskin,
    hermetic_env,
    server_state_with_db,
    stop,
    wait_for,
)
from tests.reliability.test_interruption import dask_workers, results, start_sweep

pytestmark = pytest.mark.slow

POINTS = 7  # distinct points of the smoke grid


@pytest.fixture(scope="module")
def setting(tmp_path_factory, migrated_prefect_db):
    """(environment with this module's server state, that state folder); the state holds a
    database already set up, as after the server's first start."""
    base = tmp_path_factory.mktemp("server-gone")
    state = server_state_with_db(base / "server-state", migrated_prefect_db)
    yield hermetic_env(base, ESKIN_SERVER_DIR=str(state)), state
    server.stop(state)


def started_processes(sweep: subprocess.Popen) -> list[psutil.Process]:
    """What the sweep started for itself (the shared Prefect server left out)."""
    found = []
    for child in psutil.Process(sweep.pid).children(recursive=True):
        try:
            if server.MARKER not in " ".join(child.cmdline()):
                found.append(child)
        except psutil.NoSuchProcess:
            continue
    return found


def assert_none_left(processes: list[psutil.Process], within_s: float = 10.0) -> None:
    _, alive = psutil.wait_procs(processes, timeout=within_s)
    for process in alive:  # ours: stop them before failing
        process.kill()
    assert alive == [], f"left running {within_s:.0f} s after the sweep exited: {alive}"


@contextlib.contextmanager
def paused_after_first_point(sweep: subprocess.Popen, root: Path) -> Iterator[None]:
    """Pause the sweep's workers once its first point is stored, for the block."""
    wait_for(lambda: results(root), 300, "the first finished point", interval=0.01)
    workers = dask_workers(sweep.pid)
    for worker in workers:
        worker.suspend()
    try:
        assert len(results(root)) < POINTS, "the sweep ended before it could be paused"
        yield
    finally:
        for worker in workers:
            with contextlib.suppress(psutil.NoSuchProcess):
                worker.resume()


def sweep_around(
    env: dict[str, str], root: Path, act: Callable[[subprocess.Popen], None], *extra: str
) -> tuple[subprocess.Popen, str, str, list[psutil.Process]]:
    """Sweep the smoke grid into ``root`` (``--json``), calling ``act(sweep)`` while its
    workers are paused after its first point; return the ended sweep, its stdout and stderr,
    and the processes it had started."""
    sweep = start_sweep(root, env, *extra)
    children: list[psutil.Process] = []
    try:
        with paused_after_first_point(sweep, root):
            children = started_processes(sweep)
            act(sweep)
        out, err = sweep.communicate(timeout=600)
    finally:
        stop(sweep)
    return sweep, out, err, children


def test_a_sweep_whose_server_is_stopped_finishes_and_says_its_record_is_incomplete(
    setting, smoke_sweep, tmp_path
):
    """The sweep is registered as a run of its server (so ``server stop`` refuses); the server
    is stopped as ``server stop --force`` does; the sweep computes on, writes identical cubes,
    exits 0 and ends with one line about its record."""
    env, state = setting
    root = tmp_path / "run"

    def stop_server(sweep: subprocess.Popen) -> None:
        assert server.running_runs(state) == [
            server.RunningRun(sweep.pid, "sweep 'smoke'", str(root))
        ]
        with pytest.raises(server.ServerBusyError, match=f"sweep 'smoke' of {root}"):
            server.check_stoppable(state)
        server.stop(state)

    sweep, out, err, children = sweep_around(env, root, stop_server, "--workers", "1")
    assert sweep.returncode == 0, err[-3000:]
    summary = json.loads(out)
    assert summary["computed"] == POINTS and summary["prefect_record"] == "incomplete"
    last = err.strip().splitlines()[-1]
    assert last.startswith("eskin: note: the Prefect record of this run is incomplete (its")
    assert "stopped answering" in last and "the results in the run root are complete" in last
    assert "Traceback" not in err and "a write to the run root failed" not in err
    assert_same_cubes(smoke_sweep[0], root)
    assert_none_left(children)


def flow_run_state(api_url: str, auth: str, url: str) -> str:
    """The state type of the flow run whose UI page is ``url``."""
    run_id = url.rsplit("/", 1)[-1]
    request = urllib.request.Request(f"{api_url}/flow_runs/{run_id}", headers=api_headers(auth))
    with urllib.request.urlopen(request, timeout=60) as response:
        return json.load(response)["state"]["type"]


def test_a_sweep_whose_server_is_killed_and_restarted_reconnects(setting, smoke_sweep, tmp_path):
    """The server is killed (SIGKILL) mid-sweep and started again: it comes back on its port,
    the sweep sends what it held, and its flow run ends Completed; identical cubes, exit 0."""
    env, state = setting
    killed: list[server.ServerInfo] = []

    def restart_server(sweep: subprocess.Popen) -> None:
        killed.append(server.status(state))  # the one the sweep started
        os.kill(killed[0].pid, signal.SIGKILL)
        time.sleep(3)  # the sweep finds it gone
        started = eskin("server", "start", "--json", env=env, timeout=600)
        assert started.returncode == 0, started.stderr
        assert json.loads(started.stdout)["api_url"] == killed[0].api_url, "not on its old port"

    sweep, out, err, children = sweep_around(
        env, tmp_path / "run", restart_server, "--workers", "1"
    )
    assert sweep.returncode == 0, err[-3000:]
    summary = json.loads(out)
    assert summary["computed"] == POINTS
    assert "Traceback" not in err
    auth = (state / server.AUTH_FILE).read_text().strip()
    assert flow_run_state(killed[0].api_url, auth, summary["flow_run_url"]) == "COMPLETED"
    assert_same_cubes(smoke_sweep[0], tmp_path / "run")
    assert_none_left(children)


def test_sigterm_with_the_server_gone_unwinds_within_10_s(setting, tmp_path):
    """SIGTERM to a sweep whose server was stopped and whose workers hang (paused): exit 130
    within 10 s, the sweep task cancelled as interrupted (not as a failed write), nothing it
    started left 10 s later."""
    env, state = setting
    sent: list[float] = []

    def stop_server_then_sigterm(sweep: subprocess.Popen) -> None:
        server.stop(state)
        time.sleep(1)
        sent.append(time.monotonic())
        sweep.send_signal(signal.SIGTERM)
        sweep.wait(timeout=60)

    sweep, _, err, children = sweep_around(
        env, tmp_path / "run", stop_server_then_sigterm, "--workers", "1"
    )
    took = time.monotonic() - sent[0]
    assert sweep.returncode == 130, err[-3000:]
    assert took < 10, f"took {took:.1f} s to unwind"
    assert err.strip().splitlines()[-1].startswith("eskin: interrupted")
    assert "stopped: it was interrupted (Ctrl-C or SIGTERM)" in err
    assert "a write to the run root failed" not in err
    assert_none_left(children)
