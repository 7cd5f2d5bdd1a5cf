"""A sweep outlives its Prefect server: stopped, killed or restarted mid-sweep, it computes on,
writes the same cubes as an uninterrupted run and says in one line what Prefect lacks.

The sweeps here use a Prefect server state of this module's own (so that stopping it leaves the
suite's shared server alone); the first sweep starts it, later ones restart it.
"""

import json
import os
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import psutil
import pytest

from flows import server
from tests.flows.helpers import api_headers, assert_same_cubes, eskin, hermetic_env, stop, wait_for
from tests.reliability.test_interruption import results

pytestmark = pytest.mark.slow

#: Six points of a few seconds each: long enough to stop a server under.
GRID = """
name = "outlive"
base = "smoke"

[sweeps.threshold]
set = { "training.epochs" = 100 }
axes = { "readout.threshold_v" = [0.04, 0.05, 0.06, 0.07, 0.08, 0.09] }
"""
POINTS = 6


@pytest.fixture(scope="module")
def setting(tmp_path_factory):
    """(grid file, environment with this module's server state, that state folder)."""
    base = tmp_path_factory.mktemp("server-gone")
    grid = base / "outlive.toml"
    grid.write_text(GRID)
    state = base / "server-state"
    env = hermetic_env(base, ESKIN_SERVER_DIR=str(state))
    yield grid, env, state
    server.stop(state)


@pytest.fixture(scope="module")
def reference(setting, tmp_path_factory):
    """The grid swept without interruption: its root."""
    grid, env, _ = setting
    root = tmp_path_factory.mktemp("reference") / "run"
    proc = eskin("sweep", "--grid", str(grid), "--root", str(root), "--json", env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert summary["computed"] == POINTS and summary["prefect_record"] == "complete"
    return root


def start_sweep(grid: Path, root: Path, env: dict[str, str], *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "flows.cli", "sweep", "--grid", str(grid), "--root", str(root)]
        + list(extra),
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )


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


def first_point(root: Path) -> None:
    wait_for(lambda: results(root), 300, "the first finished point", interval=0.1)


def test_a_sweep_whose_server_is_stopped_finishes_and_says_its_record_is_incomplete(
    setting, reference, tmp_path
):
    """The sweep is registered as a run of its server (so ``server stop`` refuses); the server
    is stopped as ``server stop --force`` does; the sweep computes on, writes identical cubes,
    exits 0 and ends with one line about its record."""
    grid, env, state = setting
    root = tmp_path / "run"
    sweep = start_sweep(grid, root, env, "--json", "--workers", "1")
    children: list[psutil.Process] = []
    try:
        first_point(root)
        children = started_processes(sweep)
        assert server.running_runs(state) == [
            server.RunningRun(sweep.pid, "sweep 'outlive'", str(root))
        ]
        with pytest.raises(server.ServerBusyError, match=f"sweep 'outlive' of {root}"):
            server.check_stoppable(state)
        server.stop(state)
        assert len(results(root)) < POINTS, "the sweep ended before its server was stopped"
        out, err = sweep.communicate(timeout=600)
    finally:
        stop(sweep)
    assert sweep.returncode == 0, err[-3000:]
    summary = json.loads(out)
    assert summary["computed"] == POINTS and summary["prefect_record"] == "incomplete"
    last = err.strip().splitlines()[-1]
    assert last.startswith("eskin: note: the Prefect record of this run is incomplete (its")
    assert "stopped answering" in last and "the results in the run root are complete" in last
    assert "Traceback" not in err and "a write to the run root failed" not in err
    assert_same_cubes(reference, root)
    assert_none_left(children)


def flow_run_state(api_url: str, auth: str, url: str) -> str:
    """The state type of the flow run whose UI page is ``url``."""
    run_id = url.rsplit("/", 1)[-1]
    request = urllib.request.Request(f"{api_url}/flow_runs/{run_id}", headers=api_headers(auth))
    with urllib.request.urlopen(request, timeout=60) as response:
        return json.load(response)["state"]["type"]


def test_a_sweep_whose_server_is_killed_and_restarted_reconnects(setting, reference, tmp_path):
    """The server is killed (SIGKILL) mid-sweep and started again: it comes back on its port,
    the sweep sends what it held, and its flow run ends Completed; identical cubes, exit 0."""
    grid, env, state = setting
    root = tmp_path / "run"
    sweep = start_sweep(grid, root, env, "--json", "--workers", "1")
    children: list[psutil.Process] = []
    try:
        first_point(root)
        children = started_processes(sweep)
        before = server.status(state)
        os.kill(before.pid, signal.SIGKILL)
        psutil.Process(before.pid).wait(timeout=20) if psutil.pid_exists(before.pid) else None
        time.sleep(1)  # the sweep finds it gone
        started = eskin("server", "start", "--json", env=env, timeout=600)
        assert started.returncode == 0, started.stderr
        assert json.loads(started.stdout)["api_url"] == before.api_url, "not on its old port"
        assert len(results(root)) < POINTS, "the sweep ended before its server came back"
        out, err = sweep.communicate(timeout=600)
    finally:
        stop(sweep)
    assert sweep.returncode == 0, err[-3000:]
    summary = json.loads(out)
    assert summary["computed"] == POINTS
    assert "Traceback" not in err
    auth = (state / server.AUTH_FILE).read_text().strip()
    assert flow_run_state(before.api_url, auth, summary["flow_run_url"]) == "COMPLETED"
    assert_same_cubes(reference, root)
    assert_none_left(children)


def test_sigterm_with_the_server_gone_unwinds_within_10_s(setting, tmp_path):
    """SIGTERM to a sweep whose server was stopped: exit 130 within 10 s, the sweep tasks
    cancelled as interrupted (not as a failed write), nothing it started left 10 s later."""
    grid, env, _ = setting
    root = tmp_path / "run"
    sweep = start_sweep(grid, root, env)
    children: list[psutil.Process] = []
    try:
        first_point(root)
        children = started_processes(sweep)
        assert eskin("server", "stop", "--force", env=env).returncode == 0
        time.sleep(1)
        sent = time.monotonic()
        sweep.send_signal(signal.SIGTERM)
        _, err = sweep.communicate(timeout=60)
        took = time.monotonic() - sent
    finally:
        stop(sweep)
    assert sweep.returncode == 130, err[-3000:]
    assert took < 10, f"took {took:.1f} s to unwind"
    assert err.strip().splitlines()[-1] == "eskin: interrupted"
    assert "a write to the run root failed" not in err
    assert_none_left(children)
