"""``flows.api`` and ``flows.run.run_sweep``: a sweep on a given Dask client, no Prefect."""

import subprocess
import sys

import pytest
import xarray as xr

import flows.api
from flows import planning, scheduling, work
from flows.api import SweepFailed, open_results, run_sweep
from flows.cluster import ClusterError
from flows.progress import SweepStopped
from storage.runlog import RUN_LOG
from tests.flows.helpers import SMALL_GRID


@pytest.fixture
def grid(tmp_path):
    path = tmp_path / "api.toml"
    path.write_text(SMALL_GRID)
    return str(path)


def test_every_name_of_the_api_resolves_without_importing_prefect():
    assert all(getattr(flows.api, name) is not None for name in flows.api.__all__)
    code = "import sys, flows.api; sys.exit('prefect' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"workers": 0}, r"^workers 0: need a whole number"),
        ({"workers": 1, "client": object()}, r"not both"),
    ],
)
def test_bad_workers_are_refused_before_the_root_is_made(tmp_path, grid, kwargs, message):
    with pytest.raises(ClusterError, match=message):
        run_sweep(grid, tmp_path / "run", **kwargs)
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_a_sweep_on_a_given_client_writes_cubes_and_leaves_the_client_open(
    tmp_path, grid, client, monkeypatch
):
    root = tmp_path / "run"
    summary = run_sweep(grid, root, client=client)
    assert client.status == "running"
    assert {k: summary[k] for k in ("points", "cache_hits", "computed")} == {
        "points": 3,  # the window sweep's 0.1 s point is the threshold sweep's 0.09 V one
        "cache_hits": 0,
        "computed": 3,
    }
    cubes = open_results(root)
    assert list(summary["cubes"]) == ["threshold", "window"] == sorted(cubes)
    assert cubes["window"]["accuracy"].dims == ("window_s", "model", "repeat", "fold")
    assert len((root / RUN_LOG).read_text().splitlines()) == 1

    def no_cluster(*args, **kwargs):
        raise AssertionError("a cluster started with nothing to compute")

    monkeypatch.setattr(scheduling, "dask_client", no_cluster)
    again = run_sweep(grid, root)
    assert (again["cache_hits"], again["computed"], again["dashboard"]) == (3, 0, None)
    xr.testing.assert_identical(open_results(root)["threshold"], cubes["threshold"])


ENSURE_ENTRIES = work.ensure_entries


def failing_at_5_mv(root, level, points, *after):
    if any(scene.readout.threshold_v == 0.05 for scene, _ in points):
        raise RuntimeError("broken point")
    return ENSURE_ENTRIES(root, level, points, *after)


@pytest.mark.slow
def test_a_failed_point_fails_the_sweep_but_keeps_the_other_cubes(
    tmp_path, grid, client, monkeypatch
):
    monkeypatch.setattr(work, "ensure_entries", failing_at_5_mv)
    with pytest.raises(SweepFailed, match=r"^1 of 3 points failed .*broken point"):
        run_sweep(grid, tmp_path / "run", client=client)
    assert sorted(open_results(tmp_path / "run")) == ["window"]


@pytest.mark.slow
def test_a_write_without_space_stops_the_sweep_and_a_rerun_resumes(
    tmp_path, grid, client, monkeypatch
):
    """The third batch written finds the disk full: the sweep stops with one line saying how
    many points the root keeps, writes no cube, and a re-run computes only the others."""
    from pipeline.run.stages import RESULTS
    from storage import StoreWriteError, SweepStore

    root = tmp_path / "run"
    write = SweepStore.write_entries
    writes = []

    def filling(self, kind, entries):
        writes.append(kind.name)
        if len(writes) > 2:
            raise StoreWriteError(self.root, "no space left on the device")
        write(self, kind, entries)

    monkeypatch.setattr(SweepStore, "write_entries", filling)
    with pytest.raises(SweepStopped) as caught:
        run_sweep(grid, root, client=client)
    kept = SweepStore.open(root).complete_keys(RESULTS.name)
    assert str(caught.value) == (
        f"cannot write to run root {root}: no space left on the device; the sweep stopped, "
        f"{len(kept)} of 3 points are kept, and running it again resumes from them"
    )
    assert caught.value.exit_status == 1 and len(kept) < 3
    assert open_results(root) == {}

    monkeypatch.setattr(SweepStore, "write_entries", write)
    summary = run_sweep(grid, root, client=client)
    assert (summary["cache_hits"], summary["computed"]) == (len(kept), 3 - len(kept))


def test_two_roots_swept_on_one_client_each_get_every_entry(tmp_path, grid, client):
    """Dask hands a task whose key it still holds the earlier result: keys must name the root."""
    from distributed import wait

    from pipeline.run.stages import RESULTS
    from storage import SweepStore

    plans = []
    for name in ("a", "b"):
        store = SweepStore.open_or_create(tmp_path / name)
        with store.lock():
            plans.append(planning.plan_sweep(planning.load_sweep_grid(grid), store.root))
    held = [scheduling.submit_missing(plan, client) for plan in plans]  # both held at once
    assert {f.key for f in held[0].values()}.isdisjoint(f.key for f in held[1].values())
    wait([f for futures in held for f in futures.values()])
    for plan in plans:
        store = SweepStore.open(plan.root)
        assert all(store.has(RESULTS.record, key) for key in plan.scenes)
