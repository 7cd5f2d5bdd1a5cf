"""A stored level is declared in the stage registry alone: registered here, in the test only, it
is computed on the workers' code path, stored, read back and timed in the cube."""

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

import pipeline.run.stages as stages
from flows.scheduling import point_keys
from flows.work import ensure_entries
from pipeline.chain.coding import resolve_n_windows
from pipeline.design.grid import Grid
from pipeline.results.cube import build_cube
from pipeline.run.grid_keys import keyed_points
from pipeline.run.records import Record, Variable, read_seconds, seconds_attr
from storage import SweepStore


@dataclasses.dataclass(frozen=True, eq=False)
class CountEntry:
    """REAL spikes per recording of one scene."""

    per_recording: np.ndarray
    seconds: dict[str, float]


@dataclasses.dataclass(frozen=True, eq=False)
class Counts:
    """Output of the test's level: what its entry holds but the seconds."""

    per_recording: np.ndarray


def count_spikes(*, spikes, watch):
    with watch.stage("count"):
        return Counts(spikes.encoded.real.count.sum(axis=1))


def encode_counts(entry):
    return {"per_recording": entry.per_recording}, {"seconds": seconds_attr(entry.seconds)}


def decode_counts(values, attrs):
    return CountEntry(values["per_recording"], read_seconds(attrs))


COUNTS = stages.Level(
    name="counts",
    reads=(),
    after=(stages.SPIKES,),
    compute=count_spikes,
    steps=("count",),
    # What it stores: one variable, and how its output becomes an entry and back.
    record=Record(
        "counts",
        CountEntry,
        (Variable("per_recording", ("recording",), "int64", "1", "REAL spikes per recording"),),
        lambda output, seconds, made: CountEntry(output.per_recording, seconds.work),
        encode_counts,
        decode_counts,
    ),
)


def classify_quickly(*, rates, counts, training, watch):
    """A stand-in for training: every recording right, in no time."""
    labels = rates.labels
    with watch.stage("train_ffnn"):
        cv = SimpleNamespace(
            fold_accuracy=np.full((1, training.folds), 1.0),
            predicted=labels[np.newaxis],
            test_fold=(np.arange(labels.size) % training.folds)[np.newaxis],
            decision_s=None,  # it reads no decisions during the touch
            operations=None,
        )
    # The new level's output (or its entry, as read back) reaches the level after it.
    assert counts.per_recording.shape == (labels.size,)
    return {stages.Model.FFNN: cv}


RESULTS = dataclasses.replace(
    stages.RESULTS, after=(stages.RATES, COUNTS), compute=classify_quickly
)


@pytest.fixture
def registry(monkeypatch):
    levels = stages._checked(
        stages.RECORDINGS, stages.FRONT_END, stages.SPIKES, COUNTS, stages.RATES, RESULTS
    )
    monkeypatch.setattr(stages, "LEVELS", levels)
    return levels


def test_a_level_registered_in_a_test_is_computed_stored_read_back_and_timed(registry, tmp_path):
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "t": {
                    "set": {"training.models": ["ffnn"], "dataset.recordings_per_class": 2},
                    "axes": {"readout.threshold_v": [0.05, 0.09]},
                }
            },
        }
    )
    sweep = grid.sweeps[0]
    points = keyed_points(grid, sweep)
    store = SweepStore.open_or_create(tmp_path / "run")
    with_keys = [(p.scene, point_keys(p.scene)) for p in points]
    keys = ensure_entries(str(store.root), "results", with_keys)
    assert keys == [p.key for p in points]

    count_keys = [COUNTS.key(p.scene) for p in points]
    assert store.complete_keys("counts") == set(count_keys)  # stored in a group of its own
    counts = store.read_many(COUNTS.record, count_keys, discard_corrupt=False)
    spikes = store.read_many(
        stages.SPIKES.record, [stages.SPIKES.key(p.scene) for p in points], discard_corrupt=False
    )
    results = store.read_many(RESULTS.record, keys, discard_corrupt=False)
    for point, count_key in zip(points, count_keys, strict=True):
        trains = spikes[stages.SPIKES.key(point.scene)].encoded.real
        entry = counts[count_key]
        assert entry.per_recording.dtype == np.int64
        np.testing.assert_array_equal(entry.per_recording, trains.count.sum(axis=1))
        assert set(entry.seconds) == {
            "load",
            "front_end",
            "setup",
            "taxels",
            "readout",
            "metrics",
            "count",
        }
        result = results[point.key]
        assert set(result.seconds) == set(stages.steps_of(["ffnn"]))  # every step, "count" too
        assert result.n_windows_used == resolve_n_windows(point.scene.coding, trains.duration_s)

    cube = build_cube(grid, sweep, results)
    assert cube["stage"].values.tolist() == [
        "load",
        "front_end",
        "setup",
        "taxels",
        "readout",
        "metrics",
        "count",
        "coding",
        "train_ffnn",
    ]
    assert np.all(cube["seconds"].sel(stage="count").values >= 0)  # paid: own, shared
    expected = [results[p.key].seconds["count"] for p in points]
    np.testing.assert_array_equal(cube["work_seconds"].sel(stage="count").values, expected)
    np.testing.assert_array_equal(
        cube["n_windows_used"].values, [results[p.key].n_windows_used for p in points]
    )
    assert cube["n_windows_used"].attrs == RESULTS.record.variable("n_windows_used").attrs()

    # A second task finds everything stored and computes nothing.
    before = {name: store.complete_keys(name) for name in ("spikes", "counts", "results")}
    assert ensure_entries(str(store.root), "results", with_keys) == keys
    assert {name: store.complete_keys(name) for name in before} == before
    assert len(list((store.path / "counts").glob("batch-*"))) == 1
