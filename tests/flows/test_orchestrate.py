"""Tests of flows.orchestrate's pure parts: the order in which points are submitted, the
dataset override, and the dry run (counts, estimate, and that it writes nothing)."""

import hashlib
import json
import math
import os
import pickle
from pathlib import Path

import numpy as np
import pytest

from flows import orchestrate
from flows.orchestrate import (
    SweepCounts,
    SweepPlan,
    assemble_cube,
    check_grid,
    cost_kind,
    default_points_per_task,
    dry_run,
    format_dry_run,
    load_sweep_grid,
    open_root,
    plan_sweep,
    point_failures,
    training_cost,
)
from flows.work import PointsFailed
from pipeline.coding import MAX_AUTO_WINDOWS
from pipeline.errors import DatasetError
from pipeline.grid import DatasetFacts, Grid, load_grid
from pipeline.metrics import SpikeMetrics
from pipeline.records import RecordingsInfo, ResultEntry
from pipeline.scene import Scene
from pipeline.stages import RESULTS, cache_key
from storage import StoreError
from storage.store import SweepStore
from tests.store_helpers import write_result


def test_training_cost_is_frame_size_per_model_with_auto_windows_at_their_most():
    paper = Scene.paper()  # 3x3 taxels, auto windows, FFNN and CNN
    assert training_cost(paper) == 9 * MAX_AUTO_WINDOWS * 2
    assert training_cost(paper.replace(**{"coding.n_windows": 160})) == 9 * 160 * 2
    assert training_cost(paper.replace(**{"array.rows": 5, "array.cols": 5})) == 25 * 40 * 2
    assert training_cost(paper.replace(**{"training.models": ["ffnn"]})) == 9 * 40


# ---------------------------------------------------------------------------------------------
# Dataset override and dry run

METRICS = SpikeMetrics(
    ssnr_db=math.inf,
    ste_s2=0.0,
    ste_sign_safe_s2=0.0,
    event_rate_hz=100.0,
    data_rate_bps=300.0,
    equivalent_bits=3.0,
)


def test_load_sweep_grid_puts_every_point_on_the_given_dataset(tmp_path):
    (tmp_path / "Z.csv").write_text("")
    assert load_sweep_grid("smoke") == load_grid("smoke")
    grid = load_sweep_grid("smoke", str(tmp_path))
    assert {(p.scene.dataset.kind, p.scene.dataset.path) for p in grid.points()} == {
        ("vibtac12", str(tmp_path.resolve()))
    }


def test_open_root_checks_the_dataset_before_creating_the_root(tmp_path):
    root = tmp_path / "run"
    with pytest.raises(DatasetError, match="does not exist"):
        open_root("smoke", str(root), dataset=str(tmp_path / "absent"))
    assert not root.exists()
    assert open_root("smoke", str(root), dataset="synthetic").root == root


def test_cost_kind_ignores_threshold_effect_values_and_seeds_but_not_effect_names():
    base = Scene.builtin("smoke")
    noisy = base.replace(**{"readout.effects.amplifier_noise.sigma_v": 0.01})
    same = [
        base.replace(**{"readout.threshold_v": 0.05}),
        base.replace(**{"seed": 3, "dataset.seed": 4, "training.seed": 5}),
    ]
    assert all(cost_kind(s) == cost_kind(base) for s in same)
    assert cost_kind(noisy) != cost_kind(base)
    assert cost_kind(noisy.replace(**{"readout.effects.amplifier_noise.sigma_v": 0.5})) == (
        cost_kind(noisy)
    )
    for change in ({"coding.window_s": 0.2}, {"array.rows": 1}, {"training.models": ["ffnn"]}):
        assert cost_kind(base.replace(**change)) != cost_kind(base)


def dry_run_grid() -> Grid:
    return Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "threshold": {"axes": {"readout.threshold_v": [0.03, 0.05, 0.09, 0.2]}},
                # 0.1 s is the base point, shared with threshold 0.09.
                "window": {"axes": {"coding.window_s": [0.1, 0.2]}},
                "noise": {
                    "mode": "zip",
                    "axes": {
                        "readout.effects.amplifier_noise.sigma_v": [0.01, 0.02],
                        "seed": [1, 2],
                    },
                },
            },
        }
    )


def point_key(grid: Grid, sweep: str, i: int) -> str:
    return next(p.key for p in grid.points() if p.sweep == sweep and p.index == (i,))


def tree(root: Path) -> dict[str, tuple]:
    """Every path under ``root`` with its size, mtime and (for files) content digest."""
    found = {}
    for folder, dirs, files in os.walk(root):
        for name in dirs + files:
            path = Path(folder, name)
            stat = path.lstat()
            digest = hashlib.sha256(path.read_bytes()).hexdigest() if name in files else None
            found[str(path.relative_to(root))] = (stat.st_size, stat.st_mtime_ns, digest)
    stat = root.lstat()
    found["."] = (stat.st_size, stat.st_mtime_ns, None)
    return found


def test_dry_run_counts_cached_points_and_estimates_the_rest_writing_nothing(tmp_path):
    grid = dry_run_grid()
    root = tmp_path / "run"
    store = SweepStore.open_or_create(root)
    measured = {
        ("threshold", 0): {"readout": 0.25, "train_ffnn": 0.75},  # 1.0 s in all
        ("threshold", 1): {"readout": 1.0, "train_ffnn": 2.0},  # 3.0 s
        ("threshold", 2): {"readout": 5.0, "train_ffnn": 15.0},  # 20.0 s
        ("noise", 0): {"train_ffnn": 7.0},
    }
    for (sweep, i), seconds in measured.items():
        entry = ResultEntry({"ffnn": np.array([0.5, 0.75])}, seconds, METRICS)
        write_result(store, point_key(grid, sweep, i), entry)
    # A corrupt result (its attributes edited) counts as missing, and the dry run leaves it.
    corrupt = point_key(grid, "window", 1)
    write_result(store, corrupt, ResultEntry({"ffnn": np.array([0.5])}, {"a": 1.0}, METRICS))
    meta = store.entry_location(RESULTS.record, corrupt) / "zarr.json"
    data = json.loads(meta.read_text())
    data["attributes"]["entries"][0]["attrs"]["seconds"] = {"a": 100.0}
    meta.write_text(json.dumps(data))
    # So does a partial batch, as a killed writer leaves it.
    (root / "store.zarr" / "results" / ".partial-batch-0").mkdir()
    before = tree(root)

    d = dry_run(grid, root, workers=2)

    assert tree(root) == before
    assert (d.grid, d.root, d.points, d.cached, d.missing) == ("grid", str(root), 7, 4, 3)
    assert d.sweeps == (
        SweepCounts("threshold", 4, 3, 1),
        SweepCounts("window", 2, 1, 1),
        SweepCounts("noise", 2, 1, 1),
    )
    # threshold 0.2: median of 1, 3 and 20 s (its kind); noise[1]: 7 s; window 0.2: unknown.
    assert d.estimated_seconds == pytest.approx(3.0 + 7.0)
    assert (d.unknown, d.workers, d.wall_seconds) == (1, 2, pytest.approx(5.0))
    assert json.loads(json.dumps(d.to_json())) == d.to_json()
    assert d.to_json()["sweeps"]["window"] == {"points": 2, "cached": 1, "missing": 1}
    text = format_dry_run(d)
    assert "10 s of compute for 2 missing points" in text
    assert "5 s wall on 2 worker(s) if they stay busy" in text
    assert "1 more of unknown kind" in text
    assert "\nthreshold            4       3        1\n" in text
    assert "\nall (distinct)       7       4        3\n" in text


def test_dry_run_of_a_missing_root_has_nothing_cached_and_creates_nothing(tmp_path):
    root = tmp_path / "absent" / "run"
    d = dry_run(dry_run_grid(), root, workers=1)
    assert (d.cached, d.missing, d.unknown, d.estimated_seconds) == (0, 7, 7, 0.0)
    assert not (tmp_path / "absent").exists()
    assert "estimate: unknown (7 missing points" in format_dry_run(d)
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError, match="is a file"):
        dry_run(dry_run_grid(), tmp_path / "file", workers=1)


# ---------------------------------------------------------------------------------------------
# Assembling cubes


def test_cubes_state_the_recordings_their_results_state_and_refuse_a_missing_point(tmp_path):
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"t": {"axes": {"readout.threshold_v": [0.05, 0.1]}}}}
    )
    store = SweepStore.open_or_create(tmp_path / "run")
    scenes = grid.unique_points()
    first, second = scenes
    plan = SweepPlan(grid, str(store.root), scenes, {})
    own = RecordingsInfo("mine", ("bark", "cloth"), 250.0)
    write_result(store, first, ResultEntry({"ffnn": np.array([0.5])}, {}, METRICS, own))
    with pytest.raises(StoreError, match=f"1 point.*no result.*first: {second}"):
        assemble_cube(plan, "t")
    assert store.cube_names() == []
    write_result(store, second, ResultEntry({"ffnn": np.array([0.5])}, {}, METRICS, own))
    cube = assemble_cube(plan, "t")
    stated = {k: cube.attrs.get(k) for k in ("dataset_name", "sampling_rate_hz", "class_names")}
    assert stated == {
        "dataset_name": "mine",
        "sampling_rate_hz": 250.0,
        "class_names": ["bark", "cloth"],
    }
    assert store.read_cube("t").attrs["n_classes"] == 2
    # Nothing known anywhere: the facts stay unknown, and out of the cube.
    bare = SweepPlan(grid, str(tmp_path / "other"), scenes, {})
    empty = SweepStore.open_or_create(bare.root)
    for key in scenes:
        write_result(empty, key, ResultEntry({"ffnn": np.array([0.5])}, {}, METRICS))
    cube = assemble_cube(bare, "t")
    assert not {"dataset_name", "sampling_rate_hz", "class_names", "n_classes"} & set(cube.attrs)


# ---------------------------------------------------------------------------------------------
# Planning


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
    real = DatasetFacts.describe

    def describe(spec):
        described.append(spec.seed)
        return real(spec)

    monkeypatch.setattr(DatasetFacts, "describe", describe)
    facts = check_grid(grid)
    assert described == [0, 1, 2]
    assert list(facts) == list(
        dict.fromkeys(cache_key(p.scene, "recordings") for p in grid.points())
    )


def test_plan_reads_the_stored_results_only_and_keeps_the_points_order(tmp_path):
    grid = load_grid("smoke")
    store = SweepStore.open_or_create(tmp_path / "run")
    keys = list(grid.unique_points())
    assert not store.complete_keys(RESULTS.record) & set(keys)
    assert SweepStore(tmp_path / "absent").complete_keys(RESULTS.record) == frozenset()
    for key in (keys[2], keys[0]):
        write_result(store, key, ResultEntry({"ffnn": np.array([0.5])}, {}, METRICS))
    (store.path / "results" / ".partial-batch-0").mkdir()
    (store.path / "results" / f"batch-{keys[3]}").mkdir()  # no metadata: not a complete batch
    assert store.complete_keys(RESULTS.record) == {keys[0], keys[2]}
    plan = plan_sweep("smoke", str(store.root))
    assert list(plan.scenes) == keys
    assert list(plan.records) == [keys[0], keys[2]]
    assert plan.missing == [k for k in keys if k not in (keys[0], keys[2])]
    assert plan.sweep_keys == {
        s.name: tuple(dict.fromkeys(p.key for p in grid.points() if p.sweep == s.name))
        for s in grid.sweeps
    }
    assert not (store.path / "results" / ".partial-batch-0").exists()


def test_an_equal_grid_loaded_again_is_the_last_one_with_its_points(tmp_path):
    path = tmp_path / "g.toml"
    text = '[sweeps.t]\naxes = {{ "readout.threshold_v" = {} }}\n'
    path.write_text(text.format("[0.05, 0.1]"))
    first = load_sweep_grid(str(path))
    points = first.points()
    again = load_sweep_grid(str(path))
    assert again is first and again.points() == points
    path.write_text(text.format("[0.05, 0.2]"))
    changed = load_sweep_grid(str(path))
    assert changed != first
    assert [p.scene.readout.threshold_v for p in changed.points()] == [0.05, 0.2]
    (tmp_path / "Z.csv").write_text("")
    moved = load_sweep_grid(str(path), str(tmp_path))
    assert {p.scene.dataset.kind for p in moved.points()} == {"vibtac12"}


# ---------------------------------------------------------------------------------------------
# Batching points into tasks


@pytest.mark.parametrize(
    ("n_points", "n_threads", "expected"),
    [(0, 2, 1), (1, 2, 1), (48, 2, 3), (10_000, 2, 500), (10_000, 64, 20), (7, 0, 1)],
)
def test_default_points_per_task_is_about_eight_tasks_per_thread(n_points, n_threads, expected):
    assert default_points_per_task(n_points, n_threads) == expected


def test_batches_keep_a_trains_points_together_where_they_fit_and_spread_big_ones():
    by_train = {"a": ["a1", "a2"], "b": ["b1", "b2", "b3"], "c": ["c1"], "d": list("dddddddd")}
    batches = orchestrate._batches({t: list(k) for t, k in by_train.items()}, 4)
    flat = [[(train, tuple(keys)) for train, keys in batch] for batch in batches]
    assert flat == [
        [("a", ("a1", "a2"))],  # b does not fit beside a: it starts a batch of its own
        [("b", ("b1", "b2", "b3")), ("c", ("c1",))],
        [("d", tuple("dddd"))],  # d has more points than a batch: spread, full batches
        [("d", tuple("dddd"))],
    ]
    # Every point once, in order, and no batch above the size.
    points = [k for batch in batches for _, keys in batch for k in keys]
    assert points == [k for keys in by_train.values() for k in keys]
    assert max(sum(len(keys) for _, keys in batch) for batch in batches) == 4
    assert orchestrate._batches(by_train, 1) == [
        [(t, [k])] for t, ks in by_train.items() for k in ks
    ]


class _Finished:
    """A finished Dask future, as far as :func:`point_failures` looks at it."""

    def __init__(self, error=None):
        self.status = "error" if error else "finished"
        self.key = "points-abc"
        self._error = error

    def exception(self):
        return self._error


def test_point_failures_name_only_the_failed_points_of_a_partly_failed_task():
    assert point_failures(_Finished(), ["a", "b"]) == {}
    partly = PointsFailed({"b": "ValueError: bad"})
    assert point_failures(_Finished(partly), ["a", "b"]) == {"b": "point b: ValueError: bad"}
    whole = point_failures(_Finished(MemoryError("killed")), ["a", "b"])
    assert whole == {"a": "points-abc: killed", "b": "points-abc: killed"}
    again = pickle.loads(pickle.dumps(partly))  # Dask ships it back to the coordinator
    assert isinstance(again, PointsFailed) and again.failures == partly.failures
    assert "1 point(s) failed: b: ValueError: bad" in str(again)
