"""A sweep on an ``s3://`` root served by a loopback moto server, computed by ``dask worker``
processes that each run in a scratch folder of their own: nothing of the store is on a file
system, and the coordinator and the workers share none."""

import json
import os
import subprocess
import time

import pytest

from flows.environment import state_folder
from flows.run import run_sweep
from storage import SweepStore
from storage.locking import LOCK_NAME
from storage.runlog import read_sweep_records
from tests.flows.helpers import (
    BIN,
    assert_same_cubes,
    eskin,
    hermetic_env,
    start_cluster,
    stop,
    stop_pids,
    wait_for,
)
from tests.object_store import bucket, s3_env, s3_server  # noqa: F401  (fixtures)

POINTS = 7  # the smoke grid's distinct points


def test_tool_state_of_an_object_root_is_in_the_users_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    folder = state_folder("s3://bucket/run")
    assert folder.parent == tmp_path / "cache" / "eskin-sweep" / "state"
    assert len(folder.name) == 12 and state_folder("s3://bucket/other") != folder
    assert state_folder(tmp_path / "run") == tmp_path / "run" / ".state"


@pytest.mark.slow
def test_a_sweep_on_an_object_root_cannot_write_its_report_there(tmp_path):
    env = hermetic_env(tmp_path)
    root = "s3://nowhere/run"
    proc = eskin("sweep", "--grid", "smoke", "--root", root, "--report", env=env)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip().splitlines() == [
        f"eskin: error: --report: run root {root} is on object storage: write its report to a "
        f"local folder with eskin report --root {root} --out DIR"
    ]


@pytest.mark.slow
def test_a_sweep_on_an_object_root(smoke_sweep, bucket, s3_server, tmp_path):  # noqa: F811
    env = hermetic_env(tmp_path, **s3_env(s3_server), XDG_CACHE_HOME=str(tmp_path / "cache"))
    root = f"{bucket}/runs/smoke"
    store = SweepStore.open_or_create(root)
    # The workers write to the bucket: they need its endpoint and keys, in their environment.
    cluster, pids = start_cluster(tmp_path / "cluster", env)
    try:
        sweep = ["sweep", "--grid", "smoke", "--root", root, *cluster, "--json"]
        # A second sweep is refused while another process holds the root's lease.
        with store.lock():
            refused = eskin(*sweep, env=env)
        assert refused.returncode == 2 and refused.stdout == ""
        (line,) = refused.stderr.strip().splitlines()
        assert f"run root {root} is in use by another sweep (PID {os.getpid()} on" in line

        # Killed mid-run: its lease (3 s here) expires and the next sweep resumes.
        first = subprocess.Popen(
            [BIN / "eskin", *sweep],
            env={**env, "ESKIN_LEASE_S": "3"},
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            stdin=subprocess.DEVNULL,
        )
        try:
            wait_for(lambda: store.complete_keys("results"), 600, "a first point", interval=0.1)
            assert first.poll() is None, "the first sweep finished before it could be killed"
            first.kill()
            first.wait()
        finally:
            stop(first)
        lease = json.loads(store._objects.objects.get(LOCK_NAME)[0])
        assert lease["holder"].startswith(f"PID {first.pid} on")  # left by the killed sweep
        # Try again once it has expired (each try is a command's start-up).
        time.sleep(max(0.0, lease["expires_s"] - time.time()))

        def resumed() -> subprocess.CompletedProcess | None:
            proc = eskin(*sweep, env=env)
            assert proc.returncode == 0 or "is in use by another sweep" in proc.stderr, proc.stderr
            return proc if proc.returncode == 0 else None

        results: list[subprocess.CompletedProcess] = []
        wait_for(lambda: results.append(resumed()) or results[-1], 120, "the lease to expire")
        summary = json.loads(results[-1].stdout)
        assert summary["cache_hits"] >= 1 and summary["cache_hits"] + summary["computed"] == POINTS

        again = eskin(*sweep, env=env)
        assert again.returncode == 0, again.stderr[-3000:]
        assert json.loads(again.stdout)["computed"] == 0
    finally:
        stop_pids(pids)
    assert_same_cubes(smoke_sweep[0], root)
    in_process = run_sweep("smoke", root)  # all cached: no cluster
    assert (in_process["cache_hits"], in_process["computed"]) == (POINTS, 0)
    assert [r["computed"] for r in read_sweep_records(root)][1:] == [0, 0]  # the killed one: none
    assert not list(tmp_path.rglob("store.zarr")), "the store was written to a file system"

    no_folder = eskin("report", "--root", root, env=env)
    assert no_folder.returncode == 2 and no_folder.stdout == ""
    assert no_folder.stderr.strip().splitlines() == [
        f"eskin: error: run root {root} is on object storage: write its report to a local "
        f"folder with eskin report --root {root} --out DIR"
    ]
    report = eskin("report", "--root", root, "--out", str(tmp_path / "report"), "-q", env=env)
    assert report.returncode == 0, report.stderr[-3000:]
    assert (tmp_path / "report" / "report.html").is_file()
