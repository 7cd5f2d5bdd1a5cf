"""Killed workers, killed sweeps, concurrent sweeps and corrupted chunks, end to end.

Each test runs the real command line on the smoke grid in a subprocess and compares its cubes
with the uninterrupted session run (``smoke_sweep``): every variable but the measured wall times
(``seconds``) must be identical, values and attributes (provenance included).
"""

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from flows import server
from pipeline.run.grid_keys import unique_points
from storage import SweepStore
from storage.batches import BATCH_PREFIX, read_batch_keys
from tests.flows.helpers import assert_same_cubes, eskin, live_tree, stop, wait_for

pytestmark = pytest.mark.slow

POINTS = 7  # distinct points of the smoke grid


def results(root: Path) -> dict[str, int]:
    """Complete result entries of a root, each with its batch's metadata mtime in ns."""
    folder = root / "store.zarr" / "results"
    if not folder.is_dir():
        return {}
    found = {}
    for batch in folder.iterdir():
        if not batch.name.startswith(BATCH_PREFIX):  # the group's own zarr.json, a partial
            continue
        try:
            mtime = (batch / "zarr.json").stat().st_mtime_ns
            found |= dict.fromkeys(read_batch_keys(batch), mtime)
        except FileNotFoundError:
            continue
    return found


def start_sweep(root: Path, env: dict[str, str], *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "flows.cli",
            "sweep",
            "--grid",
            "smoke",
            "--root",
            str(root),
            *extra,
            "--json",
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )


def dask_workers(pid: int) -> list[psutil.Process]:
    """The local cluster's worker processes of the sweep ``pid`` (multiprocessing children)."""
    found = []
    for child in psutil.Process(pid).children(recursive=True):
        try:
            if "spawn_main" in " ".join(child.cmdline()):
                found.append(child)
        except psutil.NoSuchProcess:
            continue
    return found


def children_after_first_point(
    sweep: subprocess.Popen, root: Path, workers: int, interval: float = 0.5
) -> list[psutil.Process]:
    """Wait for the sweep's first finished point; return the processes it started for itself.

    The shared Prefect server is left out: a sweep that found none starts it, but it serves
    later sweeps too and is meant to outlive this one (it stops when idle).
    """
    wait_for(lambda: results(root), 300, "the first finished point", interval=interval)
    children = [
        p
        for p in psutil.Process(sweep.pid).children(recursive=True)
        if server.MARKER not in " ".join(p.cmdline())
    ]
    assert len(dask_workers(sweep.pid)) == workers
    return children


def kill_by_pid(processes: list[psutil.Process]) -> None:
    for process in processes:
        try:
            process.kill()
        except psutil.NoSuchProcess:
            continue
    psutil.wait_procs(processes, timeout=20)


def finish(process: subprocess.Popen, timeout: float = 600) -> dict:
    out, err = process.communicate(timeout=timeout)
    assert process.returncode == 0, err[-3000:]
    return json.loads(out)


def test_killed_worker_mid_sweep_gives_identical_cubes(smoke_sweep, tmp_path):
    _, _, env = smoke_sweep
    root = tmp_path / "run"
    sweep = start_sweep(root, env)
    try:
        wait_for(lambda: results(root), 300, "the first finished point")
        workers = dask_workers(sweep.pid)
        assert len(workers) == 2
        victim = workers[0]
        victim.send_signal(signal.SIGKILL)  # both workers are busy: points are left for each
        victim.wait(timeout=20)
        summary = finish(sweep)
    finally:
        stop(sweep)
    assert summary["points"] == POINTS and summary["computed"] == POINTS
    assert_same_cubes(smoke_sweep[0], root)


def test_killed_sweep_resumes_with_only_unfinished_points(smoke_sweep, tmp_path):
    _, _, env = smoke_sweep
    root = tmp_path / "run"
    # One worker and a fast poll: once numba's cache is warm a smoke point takes about 0.1 s,
    # and two workers polled every 0.5 s could finish all 7 before the kill.
    sweep = start_sweep(root, env, "--workers", "1")
    left: list[psutil.Process] = []
    try:
        children = children_after_first_point(sweep, root, workers=1, interval=0.01)
        os.kill(sweep.pid, signal.SIGKILL)
        sweep.wait(timeout=20)
        # Nothing of its own outlives the killed sweep: Dask workers watch their parent
        # (distributed does this).
        _, left = psutil.wait_procs(children, timeout=30)
        assert left == [], f"outlived the killed sweep: {left}"
    finally:
        stop(sweep)
        kill_by_pid(left)
    finished = results(root)
    assert 1 <= len(finished) < POINTS, "the sweep was not killed mid-run"

    summary = finish(start_sweep(root, env, "--workers", "1"))
    assert summary["cache_hits"] == len(finished)
    assert summary["computed"] == POINTS - len(finished)
    after = results(root)
    assert len(after) == POINTS
    assert {k: after[k] for k in finished} == finished, "a finished point was recomputed"
    assert_same_cubes(smoke_sweep[0], root)
    # Partial entries of the killed run are gone: the resumed sweep removed them.
    assert not list((root / "store.zarr").glob("*/.partial-*"))


def test_sigterm_stops_the_sweep_and_everything_it_started(smoke_sweep, tmp_path):
    _, _, env = smoke_sweep
    root = tmp_path / "run"
    sweep = start_sweep(root, env, "--workers", "1")
    children: list[psutil.Process] = []
    try:
        children = children_after_first_point(sweep, root, workers=1)
        sent = time.monotonic()
        sweep.send_signal(signal.SIGTERM)
        _, err = sweep.communicate(timeout=120)
        took = time.monotonic() - sent
        assert sweep.returncode == 130 and took < 10, (took, err[-3000:])
        assert err.strip().splitlines()[-1].startswith("eskin: interrupted")
        assert "a write to the run root failed" not in err
        _, alive = psutil.wait_procs(children, timeout=10)
        assert alive == [], f"left running 10 s after SIGTERM: {alive}"
    finally:
        stop(sweep)
        kill_by_pid(children)


def test_second_sweep_on_a_busy_root_is_refused(smoke_sweep, tmp_path):
    _, _, env = smoke_sweep
    root = tmp_path / "run"
    first = start_sweep(root, env, "--workers", "1")
    try:
        wait_for(lambda: (root / "store.lock").exists(), 120, "the first sweep's lock")
        wait_for(lambda: results(root), 300, "the first finished point", interval=0.01)
        # A warm smoke sweep can finish, and release its lock, in the seconds the second one
        # takes to start. Stopped, it keeps the lock, and its workers finish the points they
        # hold, writing into the store as the walks below go.
        os.kill(first.pid, signal.SIGSTOP)
        try:
            assert first.poll() is None, "the first sweep finished before it could be stopped"
            before = {p for p in live_tree(root) if ".state" not in p.parts}
            second = eskin("sweep", "--grid", "smoke", "--root", str(root), "--json", env=env)
            assert second.returncode == 2 and second.stdout == ""
            lines = second.stderr.strip().splitlines()
            assert len(lines) == 1, second.stderr
            assert f"run root {root} is in use by another sweep (PID {first.pid} on" in lines[0]
            after = live_tree(root)
        finally:
            os.kill(first.pid, signal.SIGCONT)
        finished = {p for p in before if "results" in p.parts and ".partial" not in str(p)}
        assert finished <= after, "the refused sweep removed a finished entry"
        summary = finish(first)
    finally:
        stop(first)
    assert summary["computed"] == POINTS
    assert_same_cubes(smoke_sweep[0], root)


def first_file(folder: Path) -> Path:
    return next(p for p in sorted(folder.rglob("*")) if p.is_file() and p.name != "zarr.json")


def test_corrupted_chunks_are_detected_and_recomputed_with_a_warning(smoke_sweep, tmp_path):
    """Flip bytes in one point's cached result and truncate its spike train, then re-run a
    sweep that needs them: its cubes are gone, so it reads every result to build them."""
    import shutil

    from pipeline.design.grid import load_grid
    from pipeline.run.stages import RESULTS, SPIKES, cache_key

    _, _, env = smoke_sweep
    root = tmp_path / "run"
    shutil.copytree(smoke_sweep[0] / "store.zarr", root / "store.zarr")
    store = SweepStore.open(root)
    for name in store.cube_names():
        shutil.rmtree(store.path / "cubes" / name)
    scene = next(iter(unique_points(load_grid("smoke")).values()))
    result_key, spikes_key = cache_key(scene, "results"), cache_key(scene, "spikes")
    chunk = first_file(store.entry_location(RESULTS.record, result_key) / "accuracy")
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))
    train = first_file(store.entry_location(SPIKES.record, spikes_key) / "true_times_s")
    train.write_bytes(train.read_bytes()[:3])

    proc = eskin(
        "sweep", "--grid", "smoke", "--root", str(root), "--workers", "1", "--json", env=env
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert summary["cache_hits"] == POINTS - 1 and summary["computed"] == 1
    assert re.search(f"corrupt results batch [^\\n]*{result_key}", proc.stderr)
    assert re.search(f"corrupt spikes batch [^\\n]*{spikes_key}", proc.stderr)
    assert proc.stderr.count("RuntimeWarning") >= 2
    assert store.read_valid(SPIKES.record, spikes_key) is not None
    assert_same_cubes(smoke_sweep[0], root)


#: A command stuck where no interrupt reaches it: it swallows KeyboardInterrupt, and has started
#: a process of its own.
STUCK = """
import subprocess, sys, time
from flows import interrupts
interrupts.as_program(True)
interrupts.handle_interrupts()
child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(300)"])
print(child.pid, flush=True)
while True:
    try:
        time.sleep(100)
    except KeyboardInterrupt:
        pass
"""


def test_an_interrupted_command_that_cannot_unwind_exits_within_10_s():
    """The deadline: whatever the command is stuck in, it stops what it started and exits
    with status 130 within 10 s of SIGTERM."""
    from flows.interrupts import EXIT_INTERRUPTED, UNWIND_S

    assert UNWIND_S < 10
    stuck = subprocess.Popen(
        [sys.executable, "-c", STUCK], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    child = None
    try:
        child = psutil.Process(int(stuck.stdout.readline()))
        time.sleep(0.5)
        sent = time.monotonic()
        stuck.send_signal(signal.SIGTERM)
        _, err = stuck.communicate(timeout=30)
        took = time.monotonic() - sent
        assert stuck.returncode == EXIT_INTERRUPTED and took < 10, (took, err)
        assert err.strip().splitlines()[-1].startswith("eskin: interrupted")
        assert not child.is_running() or child.status() == psutil.STATUS_ZOMBIE
    finally:
        stop(stuck)
        if child is not None and child.is_running():
            child.kill()
