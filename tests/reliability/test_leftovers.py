"""What a killed sweep leaves behind is cleaned or recomputed by the next one's plan."""

import uuid

import numpy as np
import pytest

from flows.planning import plan_sweep
from pipeline.chain.metrics import SpikeMetrics
from pipeline.design.grid import load_grid
from pipeline.run.entries import ResultEntry
from pipeline.run.grid_keys import unique_points
from pipeline.run.stages import RESULTS
from storage import SweepStore
from tests.store_helpers import write_result


def test_plan_removes_partials_and_replans_corrupt_results(tmp_path):
    store = SweepStore.open_or_create(tmp_path / "run")
    keys = list(unique_points(load_grid("smoke")))
    metrics = SpikeMetrics(*([1.0] * 6))
    for key in keys[:2]:
        write_result(store, key, ResultEntry({"ffnn": np.array([0.5, 0.5])}, {"x": 1.0}, metrics))
    partial = store.path / "spikes" / f".partial-batch-{uuid.uuid4().hex}"
    (partial / "true_times_s").mkdir(parents=True)
    batch = store.entry_location(RESULTS.record, keys[0])
    chunk = next(p for p in (batch / "accuracy").rglob("*")
                 if p.is_file() and p.name != "zarr.json")  # fmt: skip
    chunk.write_bytes(chunk.read_bytes()[::-1])

    with store.lock(), pytest.warns(RuntimeWarning, match=f"corrupt results batch .*{keys[0]}"):
        plan = plan_sweep(load_grid("smoke"), store.root)
    assert plan.cached == {keys[1]}
    assert keys[0] in plan.missing and not store.has(RESULTS.record, keys[0])
    assert not partial.exists()
