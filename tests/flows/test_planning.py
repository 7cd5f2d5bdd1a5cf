"""Tests of flows.planning: the dataset override, the check, the plan, and one load and one
check of a grid per sweep."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flows.planning import check_grid, load_sweep_grid, open_root, plan_sweep
from flows.run import run_sweep
from pipeline.design.grid import Grid, load_grid
from pipeline.errors import DatasetError
from pipeline.run.entries import ResultEntry
from pipeline.run.fit import DatasetLimits
from pipeline.run.grid_keys import keyed_points, unique_points
from pipeline.run.stages import RECORDINGS, RESULTS
from storage.store import SweepStore
from tests.flows.helpers import METRICS, SMALL_GRID, count_grid_loads, hermetic_env
from tests.store_helpers import write_result

REPO = Path(__file__).resolve().parents[2]


def test_load_sweep_grid_puts_every_point_on_the_given_dataset(tmp_path):
    (tmp_path / "Z.csv").write_text("")
    assert load_sweep_grid("smoke") == load_grid("smoke")
    grid = load_sweep_grid("smoke", str(tmp_path))
    assert {(p.scene.dataset.kind, p.scene.dataset.path) for p in grid.points()} == {
        ("vibtac12", str(tmp_path.resolve()))
    }


def test_a_bad_dataset_is_refused_when_the_grid_loads_before_any_root_is_made(tmp_path):
    root = tmp_path / "run"
    with pytest.raises(DatasetError, match="does not exist"):
        load_sweep_grid("smoke", str(tmp_path / "absent"))
    assert not root.exists()
    grid = load_sweep_grid("smoke", "synthetic")
    assert open_root(grid, str(root), dataset="synthetic").root == root


def test_check_grid_describes_each_distinct_dataset_once(monkeypatch):
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "a": {"axes": {"dataset.seed": [0, 1], "readout.threshold_v": [0.05, 0.1]}},
                "b": {"axes": {"dataset.seed": [1, 2]}},
            },
        }
    )
    described = []
    real = DatasetLimits.describe

    def describe(spec):
        described.append(spec.seed)
        return real(spec)

    monkeypatch.setattr(DatasetLimits, "describe", describe)
    facts = check_grid(grid)
    assert described == [0, 1, 2]
    assert list(facts) == list(dict.fromkeys(RECORDINGS.key(p.scene) for p in grid.points()))


def test_plan_reads_the_stored_results_only_and_keeps_the_points_order(tmp_path):
    grid = load_grid("smoke")
    store = SweepStore.open_or_create(tmp_path / "run")
    keys = list(unique_points(grid))
    assert not store.complete_keys(RESULTS.record) & set(keys)
    assert SweepStore(tmp_path / "absent").complete_keys(RESULTS.record) == frozenset()
    for key in (keys[2], keys[0]):
        write_result(store, key, ResultEntry({"ffnn": np.array([0.5])}, {}, METRICS))
    (store.path / "results" / ".partial-batch-0").mkdir()
    (store.path / "results" / f"batch-{keys[3]}").mkdir()  # no metadata: not a complete batch
    assert store.complete_keys(RESULTS.record) == {keys[0], keys[2]}
    plan = plan_sweep(grid, store.root)
    assert list(plan.scenes) == keys
    assert list(plan.records) == [keys[0], keys[2]]
    assert plan.missing == [k for k in keys if k not in (keys[0], keys[2])]
    assert plan.sweep_keys == {
        s.name: tuple(dict.fromkeys(p.key for p in keyed_points(grid) if p.sweep == s.name))
        for s in grid.sweeps
    }
    assert not (store.path / "results" / ".partial-batch-0").exists()


#: ``eskin sweep`` with the grid loader and the dataset check counted; the counts go to stderr.
COUNTED_SWEEP = """
import json, sys
from flows.cli import main
from tests.store_helpers import write_result
from tests.flows.helpers import count_grid_loads

calls = count_grid_loads(setattr)
status = main(sys.argv[1:])
print("counted:", json.dumps(calls), file=sys.stderr)
sys.exit(status)
"""


@pytest.mark.slow
def test_a_sweep_loads_and_checks_its_grid_once(tmp_path, client, monkeypatch):
    path = tmp_path / "once.toml"
    path.write_text(SMALL_GRID)
    calls = count_grid_loads(monkeypatch.setattr)
    root = tmp_path / "run"
    assert run_sweep(str(path), root, client=client)["computed"] == 3
    assert calls == {"load_grid": 1, "describe": 1}

    # The command line on the computed root (nothing to compute, the flow on the suite's
    # server): one load and one check, before Prefect starts and in the flow alike.
    command = [sys.executable, "-c", COUNTED_SWEEP, "sweep", "--grid", str(path)]
    command += ["--root", str(root), "--json", "--quiet"]
    env = hermetic_env(tmp_path)
    proc = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600, cwd=REPO)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads(proc.stdout)["cache_hits"] == 3
    # Prefect may still log as the process exits (its events worker draining), after the counts.
    counted = [line for line in proc.stderr.splitlines() if line.startswith("counted: ")]
    assert [json.loads(line.removeprefix("counted: ")) for line in counted] == [
        {"load_grid": 1, "describe": 1}
    ]
