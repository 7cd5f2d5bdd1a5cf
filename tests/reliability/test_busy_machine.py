"""A sweep on a busy machine: the Prefect server's start waits as long as the machine needs.

Three CPU-bound processes on two cores made Prefect's temporary server miss its 20 s limit and
the sweep die with a traceback. The local server (``flows.server``) has no such limit. The
server state here is fresh, so its start includes setting up the database, the slowest case.
"""

import json
import shutil
import subprocess
import sys

import pytest

from flows import server
from tests.flows.helpers import assert_same_cubes, eskin, hermetic_env, stop

pytestmark = pytest.mark.slow

BURNERS = 3  # busy processes on a 2-core machine


def test_a_sweep_survives_a_busy_machine_and_the_next_reuses_its_server(smoke_sweep, tmp_path):
    state = tmp_path / "server-state"
    env = hermetic_env(tmp_path, ESKIN_SERVER_DIR=str(state))
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(BURNERS)]
    try:
        first = eskin(
            "sweep",
            "--grid",
            "smoke",
            "--root",
            str(tmp_path / "a"),
            "--workers",
            "1",
            "--json",
            env=env,
        )
        assert first.returncode == 0, first.stderr[-3000:]
        assert json.loads(first.stdout)["computed"] == 7
        started = json.loads((state / "server.json").read_text())["pid"]
        assert server.status(state).pid == started

        # Another root, everything cached there: it must find the running server, not start one.
        shutil.copytree(tmp_path / "a" / "store.zarr", tmp_path / "b" / "store.zarr")
        second = eskin("sweep", "--grid", "smoke", "--root", str(tmp_path / "b"), "--json", env=env)
        assert second.returncode == 0, second.stderr[-3000:]
        summary = json.loads(second.stdout)
        assert summary["cache_hits"] == 7 and summary["computed"] == 0
        assert summary["flow_run_url"].startswith(server.status(state).ui_url)
        assert server.status(state).pid == started, "the second sweep started another server"
    finally:
        stop(*burners)
        server.stop(state)
    assert_same_cubes(smoke_sweep[0], tmp_path / "a")
