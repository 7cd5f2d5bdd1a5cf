"""Determinism: the same grid and seed give the same cubes with 1, 2 and 4 workers, and in any
completion order. The session run (``smoke_sweep``) uses 2 workers; the external scheduler and
the Prefect deployment are compared with it in tests/flows/test_distributed.py. One worker is
compared with it by the sweeps of tests/reliability/test_server_gone.py (a whole ``--workers 1``
sweep: all 7 points computed, identical cubes), test_interruption.py and test_busy_machine.py,
so it is not swept once more here.

Identical means every variable and attribute but the measured wall times (``seconds``).
"""

import json

import pytest

from flows.assembly import assemble_cubes
from flows.planning import load_sweep_grid, plan_sweep
from flows.scheduling import point_keys
from flows.work import ensure_entries
from storage import SweepStore
from tests.flows.helpers import assert_same_cubes, eskin

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("workers", [4])
def test_worker_count_does_not_change_the_cubes(smoke_sweep, tmp_path, workers):
    _, _, env = smoke_sweep
    root = tmp_path / "run"
    proc = eskin(
        "sweep", "--grid", "smoke", "--root", str(root), "--workers", str(workers), "--json",
        env=env,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads(proc.stdout)["computed"] == 7
    assert_same_cubes(smoke_sweep[0], root)


def test_reversed_completion_order_gives_the_same_cubes(smoke_sweep, tmp_path):
    """Compute the points in this process, last first, with no Dask and no Prefect."""
    store = SweepStore.open_or_create(tmp_path / "run")
    with store.lock():
        plan = plan_sweep(load_sweep_grid("smoke"), store.root)
        for key in reversed(plan.missing):
            scene = plan.scenes[key]
            ensure_entries(plan.root, "results", [(scene, point_keys(scene))])
        assemble_cubes(plan)
    assert_same_cubes(smoke_sweep[0], store.root)
