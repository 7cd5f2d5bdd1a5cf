"""Sweep orchestration as plain functions: plan the grid, compute its misses, assemble cubes.

No Prefect here: :mod:`flows.sweep` wraps these in the Prefect flow, and the command line calls
:func:`check_grid` before Prefect is imported so that bad input writes nothing. A point's spike
trains are computed once and shared through the store by every point that needs them; a point
whose result is in the store is not computed again.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flows.work import compute_point, compute_spikes
from pipeline.coding import MAX_AUTO_WINDOWS
from pipeline.errors import EskinError
from pipeline.grid import DatasetFacts, Grid, check_fits, load_grid
from pipeline.recordings import load_recordings
from pipeline.scene import Scene, cache_key
from storage import EntryKind, SweepStore
from storage.cubes import build_cube

DEFAULT_RUNS_DIR = Path("runs")
POLL_S = 2.0
NO_WORKER_TIMEOUT_S = 120.0


class SweepFailed(EskinError):
    """Some points of a sweep failed; the others are in the store."""


@dataclass(frozen=True)
class SweepPlan:
    """What a sweep will do: its grid, its store, its distinct points and which are cached."""

    grid: Grid
    root: str
    scenes: dict[str, Scene]  # distinct points by result key
    cached: frozenset[str]

    @property
    def missing(self) -> list[str]:
        return [key for key in self.scenes if key not in self.cached]


def default_root(grid: Grid) -> Path:
    return DEFAULT_RUNS_DIR / grid.name


def check_grid(grid: Grid) -> None:
    """Check every point against its recordings (each dataset loaded once); raise on misfits."""
    facts: dict[str, DatasetFacts] = {}
    for point in grid.points():
        key = cache_key(point.scene, "recordings")
        if key not in facts:
            recordings = load_recordings(point.scene.dataset)
            facts[key] = DatasetFacts(
                fs_hz=recordings.fs_hz,
                min_samples=recordings.min_samples,
                min_class_size=int(np.bincount(recordings.labels).min()),
            )
    check_fits(grid, facts)


def open_root(grid_ref: str, root: str | None) -> SweepStore:
    """The store at ``root`` (default ``runs/<grid name>``), created if need be."""
    return SweepStore.open_or_create(root or default_root(load_grid(grid_ref)))


def plan_sweep(grid_ref: str, root: str) -> SweepPlan:
    """Load and check the grid, tidy the store, and find the cached points.

    Call it holding the root's lock (:meth:`storage.SweepStore.lock`): no other sweep writes to
    the root then, so every partial entry is a leftover of a killed run and is removed. A
    cached result that fails its checksum is discarded (with a warning) and planned again.
    """
    grid = load_grid(grid_ref)
    check_grid(grid)
    store = SweepStore.open(root)
    store.clean_partials()
    scenes = grid.unique_points()
    cached = frozenset(k for k in scenes if store.read_valid(EntryKind.RESULTS, k) is not None)
    return SweepPlan(grid, str(store.root), scenes, cached)


def compute_missing(plan: SweepPlan, client: Any, *, show_progress: bool) -> int:
    """Submit every missing point (after the spike trains it needs) and wait for them all."""
    from tqdm import tqdm

    store = SweepStore.open(plan.root)
    spike_futures: dict[str, Any] = {}
    point_futures = []
    priorities = {key: training_cost(plan.scenes[key]) for key in plan.missing}
    # Largest points first, so that no long point starts last while the other workers idle.
    for key in sorted(priorities, key=priorities.__getitem__, reverse=True):
        scene = plan.scenes[key]
        data = scene.to_dict()
        priority = priorities[key]
        spikes_key = cache_key(scene, "spikes")
        if spikes_key not in spike_futures and not store.has(EntryKind.SPIKES, spikes_key):
            spike_futures[spikes_key] = client.submit(
                compute_spikes,
                plan.root,
                data,
                key=f"spikes-{spikes_key}",
                pure=False,
                priority=priority + 1,
            )
        after = [spike_futures[spikes_key]] if spikes_key in spike_futures else []
        point_futures.append(
            client.submit(
                compute_point,
                plan.root,
                data,
                *after,
                key=f"point-{key}",
                pure=False,
                priority=priority,
            )
        )
    failures = []
    with tqdm(
        total=len(plan.scenes),
        initial=len(plan.cached),
        unit="point",
        desc=f"sweep {plan.grid.name}",
        disable=None if show_progress else True,
    ) as bar:
        for future in _completed(client, point_futures):
            if future.status == "error":
                failures.append(f"{future.key}: {future.exception()}")
            bar.update(1)
    if failures:
        shown = "; ".join(failures[:3]) + (
            f"; and {len(failures) - 3} more" if len(failures) > 3 else ""
        )
        raise SweepFailed(
            f"{len(failures)} of {len(point_futures)} points failed (the others are kept in "
            f"{plan.root}): {shown}"
        )
    return len(point_futures)


def training_cost(scene: Scene) -> int:
    """A point's relative cost: the size of its frames (taxels x windows) per model trained.

    Training dominates a point, and its cost grows with the frame size; ``auto`` windows count
    as the most they can be. Only the order of points depends on it, never a result.
    """
    n_windows = scene.coding.n_windows
    windows = MAX_AUTO_WINDOWS if n_windows == "auto" else n_windows
    return scene.array.n_taxels * windows * len(scene.training.models)


def _completed(client: Any, futures: list[Any]) -> Iterator[Any]:
    """Yield futures as they finish; fail if the cluster has had no worker for too long."""
    from distributed import wait

    pending = set(futures)
    alone_since = None
    while pending:
        try:
            done = wait(pending, timeout=POLL_S, return_when="FIRST_COMPLETED").done
        except TimeoutError:
            done = set()
        for future in done:
            pending.discard(future)
            yield future
        if client.nthreads():
            alone_since = None
        elif alone_since is None:
            alone_since = time.monotonic()
        elif time.monotonic() - alone_since > NO_WORKER_TIMEOUT_S:
            raise SweepFailed(
                f"the Dask cluster has had no worker for {NO_WORKER_TIMEOUT_S:.0f} s with "
                f"{len(pending)} points left; finished points are kept in the store"
            )


def assemble_cubes(plan: SweepPlan) -> dict[str, str]:
    """Build every sweep's cube from the store and write it; return where each cube is."""
    store = SweepStore.open(plan.root)
    records = {key: store.read_result(key) for key in plan.scenes}
    locations = {}
    for sweep_spec in plan.grid.sweeps:
        store.write_cube(sweep_spec.name, build_cube(plan.grid, sweep_spec, records))
        locations[sweep_spec.name] = str(Path(plan.root) / "store.zarr" / "cubes" / sweep_spec.name)
    return locations
