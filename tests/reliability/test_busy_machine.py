"""A sweep on a busy machine: the Prefect server's start waits as long as the machine needs, and
the run's Prefect record is complete at its end.

Three CPU-bound processes on two cores made Prefect's temporary server miss its 20 s limit and
the sweep die with a traceback. The local server (``flows.server``) has no such limit. The
server state here is fresh, so its start includes setting up the database, the slowest case.
Such a cold server on a busy machine is slow to answer (3 s for a health check), which the run's
record (:mod:`flows.record`) must not take for a gone server: the record is complete at the end.
"""

import contextlib
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator

import pytest

from flows import server
from tests.flows.helpers import assert_same_cubes, eskin, hermetic_env, stop

pytestmark = pytest.mark.slow

#: Busy-loop processes: one per core, so that every core is busy while the server starts (in the
#: suite, the other tests' processes load the cores beyond that).
BURNERS = os.cpu_count() or 1
#: Seconds a busy loop runs before it ends by itself (should the test die before it stops them).
BURN_S = 900
BURN = f"import time\nend = time.monotonic() + {BURN_S}\nwhile time.monotonic() < end:\n    pass\n"
#: The smoke grid's threshold sweep alone: two points, enough to run a cluster's tasks and
#: assemble a cube while the busy loops hold every core (they slow the rest of the suite too).
BUSY_GRID = """
name = "smoke"
base = "smoke"

[sweeps.threshold]
axes = { "readout.threshold_v" = [0.05, 0.09] }
"""


@contextlib.contextmanager
def busy_machine() -> Iterator[None]:
    """:data:`BURNERS` busy loops for the ``with`` block, stopped by PID at its end."""
    burners = [subprocess.Popen([sys.executable, "-c", BURN]) for _ in range(BURNERS)]
    try:
        yield
    finally:
        stop(*burners)


def test_a_sweep_survives_a_busy_machine_and_the_next_reuses_its_server(smoke_sweep, tmp_path):
    state = tmp_path / "server-state"
    env = hermetic_env(tmp_path, ESKIN_SERVER_DIR=str(state))
    grid = tmp_path / "busy.toml"
    grid.write_text(BUSY_GRID)
    try:
        # The cold start under load is what is tested; the second sweep runs unloaded, so that
        # the busy loops take from the rest of the suite no more than they must.
        with busy_machine():
            first = eskin(
                "sweep",
                "--grid",
                str(grid),
                "--root",
                str(tmp_path / "a"),
                "--workers",
                "1",
                "--json",
                env=env,
            )
        assert first.returncode == 0, first.stderr[-3000:]
        assert json.loads(first.stdout)["computed"] == 2
        assert json.loads(first.stdout)["prefect_record"] == "complete", first.stderr[-3000:]
        assert "Prefect record of this run is incomplete" not in first.stderr
        started = json.loads((state / "server.json").read_text())["pid"]
        assert server.status(state).pid == started

        # Another root, everything cached there: it must find the running server, not start one.
        shutil.copytree(tmp_path / "a" / "store.zarr", tmp_path / "b" / "store.zarr")
        second = eskin(
            "sweep", "--grid", str(grid), "--root", str(tmp_path / "b"), "--json", env=env
        )
        assert second.returncode == 0, second.stderr[-3000:]
        summary = json.loads(second.stdout)
        assert summary["cache_hits"] == 2 and summary["computed"] == 0
        assert summary["flow_run_url"].startswith(server.status(state).ui_url)
        assert server.status(state).pid == started, "the second sweep started another server"
    finally:
        server.stop(state)
    assert_same_cubes(smoke_sweep[0], tmp_path / "a", cubes=["threshold"])
