"""Tests of flows.assembly: cubes state what their results state, refuse a missing point, and
are written only when they change."""

import numpy as np
import pytest

from flows.assembly import assemble, assemble_cube, summarize
from flows.planning import SweepPlan, plan_sweep
from pipeline.design.grid import Grid
from pipeline.run.entries import RecordingsInfo, ResultEntry
from pipeline.run.grid_keys import unique_points
from pipeline.run.stages import RESULTS
from storage import StoreError
from storage.store import SweepStore
from tests.flows.helpers import METRICS
from tests.store_helpers import write_result


def test_cubes_state_the_recordings_their_results_state_and_refuse_a_missing_point(tmp_path):
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"t": {"axes": {"readout.threshold_v": [0.05, 0.1]}}}}
    )
    store = SweepStore.open_or_create(tmp_path / "run")
    scenes = unique_points(grid)
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


def test_a_cube_equal_to_the_stored_one_is_not_written_again(tmp_path, monkeypatch):
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"t": {"axes": {"readout.threshold_v": [0.05, 0.1]}}}}
    )
    store = SweepStore.open_or_create(tmp_path / "run")
    scenes = unique_points(grid)
    for key in scenes:
        write_result(store, key, ResultEntry({"ffnn": np.array([0.5])}, {"x": 1.0}, METRICS))
    plan = SweepPlan(grid, str(store.root), scenes, {})
    first = assemble_cube(plan, "t")
    written = []
    write_cube = SweepStore.write_cube
    monkeypatch.setattr(
        SweepStore,
        "write_cube",
        lambda self, *a, **k: written.append(a[0]) or write_cube(self, *a, **k),
    )
    assert assemble_cube(plan, "t").identical(first)
    assert written == []
    # A changed result changes the cube: it is written.
    changed = {next(iter(scenes)): ResultEntry({"ffnn": np.array([0.75])}, {"x": 1.0}, METRICS)}
    assert not assemble_cube(SweepPlan(grid, plan.root, scenes, changed), "t").identical(first)
    assert written == ["t"]
    # So is a cube whose stored copy fails its checksum.
    cube = store.path / "cubes" / "t"
    chunk = next(p for p in (cube / "accuracy").rglob("*") if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes()[::-1])
    assemble_cube(plan, "t")
    assert written == ["t", "t"]
    assert store.read_cube("t").identical(assemble_cube(plan, "t"))


def test_a_re_run_keeps_a_current_cube_and_takes_its_summary_without_building_it(
    tmp_path, monkeypatch
):
    """The stored cube is kept, unread, only while its results' batches, its sweep and the code
    are those it was built from and every file of it is as written; otherwise it is built
    again."""
    from pipeline.results import cube as cube_module

    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"t": {"axes": {"readout.threshold_v": [0.05, 0.1]}}}}
    )
    store = SweepStore.open_or_create(tmp_path / "run")
    scenes = unique_points(grid)
    first_key = next(iter(scenes))
    for i, key in enumerate(scenes):
        write_result(store, key, ResultEntry({"ffnn": np.array([0.25 + i / 2])}, {}, METRICS))

    def planned() -> SweepPlan:
        return plan_sweep(grid, store.root)

    built = []
    build_cube = cube_module.build_cube
    monkeypatch.setattr(
        cube_module, "build_cube", lambda *a: built.append(a[1].name) or build_cube(*a)
    )
    summary = assemble(planned(), "t")
    assert summary == {
        "dims": {"threshold_v": 2},
        "best": [{"model": "ffnn", "accuracy": 0.75, "at": {"threshold_v": 0.1}}],
    }
    assert summarize(store.read_cube("t")) == summary
    plan = planned()
    assert plan.current == {"t": summary} and plan.records == {} and plan.missing == []
    assert assemble(plan, "t") == summary
    assert built == ["t"]
    # A point computed since planning: built again.
    assemble(SweepPlan(grid, str(store.root), scenes, {}), "t")
    assert built == ["t", "t"]
    # A damaged file: built again, and the stored cube repaired.
    folder = store.path / "cubes" / "t" / "accuracy"
    chunk = next(p for p in folder.rglob("*") if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes()[::-1])
    assert assemble(planned(), "t") == summary
    assert built == ["t", "t", "t"]
    assert summarize(store.read_cube("t")) == summary
    assert assemble(planned(), "t") == summary
    assert built == ["t", "t", "t"]
    # A result stored again (a new batch) changes what the cube is built from.
    store.discard(RESULTS.record, first_key)
    write_result(store, first_key, ResultEntry({"ffnn": np.array([0.9])}, {}, METRICS))
    changed = assemble(planned(), "t")
    assert built == ["t", "t", "t", "t"]
    assert changed["best"] == [{"model": "ffnn", "accuracy": 0.9, "at": {"threshold_v": 0.05}}]
    # Another sweep over the same results is another source.
    other = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {"t": {"axes": {"readout.threshold_v": [0.05, 0.1]}, "title": "renamed"}},
        }
    )
    assemble(SweepPlan(other, str(store.root), scenes, planned().records), "t")
    assert built == ["t", "t", "t", "t", "t"]
    assert store.read_cube("t").attrs["title"] == "renamed"
    # A damaged result batch is not read while the cubes built from it are current; once it is
    # needed, planning discards it and plans its points again.
    assemble(planned(), "t")
    assert set(planned().current) == {"t"}
    batch = store.entry_location(RESULTS.record, first_key)
    chunk = next(p for p in batch.rglob("*") if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes()[::-1])
    assert set(planned().current) == {"t"}
    with pytest.warns(RuntimeWarning, match="recomputing its entries"):
        plan = plan_sweep(other, store.root)
    assert plan.current == {} and plan.missing == [first_key]
    assert set(plan.records) == set(scenes) - {first_key}
