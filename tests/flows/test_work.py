"""What workers time: every second a worker spends is charged to one point (the one whose
computation paid it), shared work (a load, a front-end fit, a kernel compile) under ``shared``,
so that a sweep's summed paid seconds count it once."""

import time

import pytest

import flows.work as work
from flows.scheduling import point_keys
from flows.work import ensure_entries
from pipeline.design.grid import Grid
from pipeline.run import stages
from pipeline.run.grid_keys import keyed_points
from pipeline.run.records import Charge
from storage import SweepStore

GRID = Grid.from_dict(
    {
        "base": "smoke",
        "sweeps": {
            "w": {
                "set": {
                    "training.models": ["ffnn"],
                    "training.epochs": 1,
                    "training.folds": 2,
                    "dataset.recordings_per_class": 2,
                },
                # Two windows share one spike train; the other threshold has its own.
                "axes": {"readout.threshold_v": [0.05, 0.09], "coding.window_s": [0.1, 0.2]},
            }
        },
    }
)
POINTS = keyed_points(GRID, GRID.sweeps[0])
SPIKE_STEPS = ("taxels", "readout", "metrics")


@pytest.fixture
def fresh_worker(monkeypatch):
    """A worker process that has kept no recordings, front end or rate matrices yet."""
    monkeypatch.setattr(work, "_kept", {})


def results(root, keys):
    return SweepStore.open(root).read_many(stages.RESULTS.record, keys, discard_corrupt=False)


def test_a_sweeps_paid_seconds_count_a_shared_load_once(fresh_worker, tmp_path):
    root = str(SweepStore.open_or_create(tmp_path / "run").root)
    start = time.perf_counter()
    keys = ensure_entries(root, "results", [(p.scene, point_keys(p.scene)) for p in POINTS])
    busy_s = time.perf_counter() - start
    entries = results(root, keys)
    paid = [entries[key].paid for key in keys]
    # The recordings were loaded and scaled once, by the first point, and charged as shared.
    loads = [p[Charge.SHARED].get("load", 0.0) for p in paid]
    assert loads[0] > 0 and loads[1:] == [0.0] * (len(keys) - 1)
    assert all("front_end" not in p[Charge.SHARED] for p in paid[1:])
    assert all("load" not in p[Charge.OWN] for p in paid)
    # Each spike train was paid by one of the points sharing it: two trains, two payers.
    payers = [i for i, p in enumerate(paid) if "readout" in p[Charge.OWN]]
    assert len(payers) == 2
    assert {POINTS[i].scene.readout.threshold_v for i in payers} == {0.05, 0.09}
    # Every point paid its own coding and training.
    assert all(p[Charge.OWN]["coding"] > 0 and p[Charge.OWN]["train_ffnn"] > 0 for p in paid)
    # Summed, the paid seconds are part of the task's time, nothing counted twice.
    total = sum(v for p in paid for steps in p.values() for v in steps.values())
    assert total <= busy_s
    # The work seconds still say what each point's stages took, wherever they ran.
    assert all(entries[key].seconds["load"] > 0 for key in keys)
    assert all(entries[key].seconds["readout"] > 0 for key in keys)


def test_a_train_made_by_another_task_is_charged_to_the_point_it_was_made_for(
    fresh_worker, tmp_path
):
    root = str(SweepStore.open_or_create(tmp_path / "run").root)
    first, second = POINTS[0], POINTS[1]  # threshold 0.05, windows 0.1 and 0.2: one train
    assert stages.SPIKES.key(first.scene) == stages.SPIKES.key(second.scene)
    # As the scheduler does for a train that points of several tasks share: a task of its own,
    # for the first of its points.
    ensure_entries(root, "spikes", [(first.scene, point_keys(first.scene))])
    train = SweepStore.open(root).read_many(
        stages.SPIKES.record, [stages.SPIKES.key(first.scene)], discard_corrupt=False
    )
    (train,) = train.values()
    assert train.paid_for == first.key
    assert train.paid[Charge.OWN]["readout"] > 0 and train.paid[Charge.SHARED]["load"] > 0
    work._kept.clear()  # the results run on another worker
    both = [(p.scene, point_keys(p.scene)) for p in (second, first)]
    keys = ensure_entries(root, "results", both)
    entries = results(root, keys)
    mine, other = entries[first.key].paid, entries[second.key].paid
    assert mine[Charge.OWN]["readout"] == train.paid[Charge.OWN]["readout"]
    assert "readout" not in other[Charge.OWN]
    # The second worker loaded the recordings again, for the point it ran first.
    assert other[Charge.SHARED]["load"] > 0
    assert mine[Charge.SHARED]["load"] == train.paid[Charge.SHARED]["load"]
