"""Sweep orchestration as plain functions: plan the grid, compute its misses, assemble cubes.

No Prefect here: :mod:`flows.sweep` wraps these in the Prefect flow, and the command line calls
:func:`check_grid` before Prefect is imported so that bad input writes nothing. A point's spike
trains are computed once and shared through the store by every point that needs them; a point
whose result is in the store is not computed again.
"""

from __future__ import annotations

import collections
import contextlib
import functools
import hashlib
import logging
import math
import re
import statistics
import threading
import time
import weakref
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from flows.cluster import ClusterError, check_workers, dask_client
from flows.environment import hermetic_environment
from flows.work import PointsFailed, ensure_entries
from pipeline.cube import build_cube
from pipeline.errors import EskinError
from pipeline.grid import DatasetFacts, Grid, check_fits, cost_kind, load_grid, training_cost
from pipeline.recordings import resolve_dataset_argument
from pipeline.records import ResultEntry
from pipeline.scene import CanonicalMemo, DatasetSpec, Scene
from pipeline.stages import RESULTS, SPIKES, cache_key
from storage import StoreError, SweepStore

DEFAULT_RUNS_DIR = Path("runs")
POLL_S = 2.0
#: Tasks per worker thread a sweep's missing points are split into (see
#: :func:`default_points_per_task`), and the most points one task takes.
TASKS_PER_THREAD = 8
MAX_POINTS_PER_TASK = 500
NO_WORKER_TIMEOUT_S = 120.0


class SweepFailed(EskinError):
    """Some points of a sweep failed; the others are in the store (exit status 1)."""

    exit_status = 1


@dataclass(frozen=True)
class SweepPlan:
    """What a sweep will do: its grid, its store, its distinct points and which are cached.

    ``records`` holds the result entries of the cached points as planning read (and checked)
    them, so that assembling the cubes reads from the store only the points computed since.
    """

    grid: Grid
    root: str
    scenes: dict[str, Scene]  # distinct points by result key
    records: dict[str, ResultEntry]

    @property
    def cached(self) -> frozenset[str]:
        return frozenset(self.records)

    @property
    def missing(self) -> list[str]:
        return [key for key in self.scenes if key not in self.cached]

    @functools.cached_property
    def sweep_keys(self) -> dict[str, tuple[str, ...]]:
        """The distinct result keys of each named sweep, in the order of its points."""
        keys: dict[str, dict[str, None]] = {s.name: {} for s in self.grid.sweeps}
        for point in self.grid.points():
            keys[point.sweep][point.key] = None
        return {name: tuple(found) for name, found in keys.items()}


def default_root(grid: Grid, dataset: str | None = None) -> Path:
    """``runs/<grid name>``, or ``runs/<grid name>-<dataset name>`` on other recordings.

    A grid swept on another dataset gets a root of its own, so its cubes never replace those
    of the grid's own recordings.
    """
    if dataset is None:
        return DEFAULT_RUNS_DIR / grid.name
    label = re.sub(r"[^A-Za-z0-9_-]+", "-", Path(dataset).name).strip("-") or "dataset"
    return DEFAULT_RUNS_DIR / f"{grid.name}-{label}"


def check_grid(grid: Grid) -> dict[str, DatasetFacts]:
    """Check every point against its recordings (each dataset loaded once); raise on misfits.

    Returns the facts of each dataset, by recordings cache key.
    """
    facts: dict[str, DatasetFacts] = {}
    seen: set[DatasetSpec] = set()
    for point in grid.points():
        # The recordings key is a function of the dataset alone: one key per distinct dataset.
        if point.scene.dataset in seen:
            continue
        seen.add(point.scene.dataset)
        key = cache_key(point.scene, "recordings")
        if key not in facts:
            facts[key] = DatasetFacts.describe(point.scene.dataset)
    check_fits(grid, facts)
    return facts


def load_sweep_grid(grid_ref: str, dataset: str | None = None) -> Grid:
    """The grid ``grid_ref`` (a built-in name or a TOML file), on ``dataset`` if one is given.

    Parameters
    ----------
    grid_ref
        A built-in grid name or a grid TOML file (:func:`pipeline.grid.load_grid`).
    dataset
        The command line's ``--dataset`` text (``synthetic`` or a dataset folder), resolved with
        :func:`pipeline.recordings.resolve_dataset_argument`; it replaces the base scene's
        dataset for every point (:meth:`pipeline.grid.Grid.with_dataset`). None keeps the
        grid's own.

    Raises
    ------
    SceneError
        The grid is invalid, or a sweep sets a ``dataset.*`` field while ``dataset`` is given.
    DatasetError
        ``dataset`` names no dataset.
    """
    grid = load_grid(grid_ref)
    if dataset is not None:
        grid = grid.with_dataset(resolve_dataset_argument(dataset))
    return _LAST_GRID.same(grid)


class _LastGrid:
    """The grid :func:`load_sweep_grid` gave last, held weakly.

    ``eskin sweep`` loads its grid three times: to check it before Prefect starts, to open the
    root, and to plan it. A grid equal to the last one (the same name, base scene and sweeps)
    has the same points, so the last one is given again, with the points its check built.
    Only points are shared this way; the recordings are described again at each check.
    """

    def __init__(self) -> None:
        self._ref: weakref.ref[Grid] | None = None
        self._lock = threading.Lock()

    def same(self, grid: Grid) -> Grid:
        with self._lock:
            last = self._ref() if self._ref is not None else None
            if last is not None and last == grid:
                return last
            self._ref = weakref.ref(grid)
            return grid


_LAST_GRID = _LastGrid()


def open_root(grid_ref: str, root: str | None, dataset: str | None = None) -> SweepStore:
    """The store at ``root`` (default: :func:`default_root`), created if need be.

    ``dataset`` is as for :func:`load_sweep_grid`, which checks it before anything is created.
    """
    grid = load_sweep_grid(grid_ref, dataset)
    return SweepStore.open_or_create(root or default_root(grid, dataset))


def plan_sweep(grid_ref: str, root: str, dataset: str | None = None) -> SweepPlan:
    """Load and check the grid, tidy the store, and find the cached points.

    Call it holding the root's lock (:meth:`storage.SweepStore.lock`): no other sweep writes to
    the root then, so every partial entry is a leftover of a killed run and is removed. A
    cached result that fails its checksum is discarded (with a warning) and planned again.
    ``dataset`` is as for :func:`load_sweep_grid`.
    """
    grid = load_sweep_grid(grid_ref, dataset)
    check_grid(grid)
    store = SweepStore.open(root)
    store.clean_partials()
    scenes = grid.unique_points()
    found = store.read_many(RESULTS.record, scenes, discard_corrupt=True)
    records = {key: found[key] for key in scenes if key in found}
    return SweepPlan(grid, str(store.root), scenes, records)


def submit_missing(
    plan: SweepPlan, client: Any, points_per_task: int | None = None
) -> dict[str, Any]:
    """Submit every missing point in batches; return each point's future by result key.

    Points are ordered largest first (so that no long point starts last while the other workers
    idle), points that share a spike train are kept together, and consecutive points are
    batched into one task each (:func:`flows.work.ensure_entries`): a task costs the
    scheduler and the store the same whatever its size, so cheap points are sent many at a
    time. Points of one task share its future. A spike train that points of several tasks
    share is computed first by a task of its own (before those tasks start); one already in
    the store is not computed at all. Task keys name the root as well as the work: Dask hands
    a task whose key it still holds the earlier result, so a sweep of another root on the same
    cluster would otherwise skip writing its entries.

    Parameters
    ----------
    points_per_task
        Points per task; default :func:`default_points_per_task` of the missing points and the
        cluster's worker threads.
    """
    store = SweepStore.open(plan.root)
    root = hashlib.sha256(str(Path(plan.root).resolve()).encode()).hexdigest()[:12]
    cost = {key: training_cost(plan.scenes[key]) for key in plan.missing}
    size = points_per_task or default_points_per_task(len(cost), sum(client.nthreads().values()))
    by_train: dict[str, list[str]] = {}
    memo: CanonicalMemo = {}  # the points share scene parts: each is written once
    for key in sorted(cost, key=cost.__getitem__, reverse=True):
        by_train.setdefault(SPIKES.key(plan.scenes[key], memo), []).append(key)
    batches = _batches(by_train, size)
    stored = store.complete_keys(SPIKES.name)
    spread = collections.Counter(train for batch in batches for train in {t for t, _ in batch})
    shared = [train for train, n in spread.items() if n > 1 and train not in stored]
    train_futures: dict[str, Any] = {}
    for start in range(0, len(shared), size):
        trains = shared[start : start + size]
        scenes = [plan.scenes[by_train[t][0]] for t in trains]
        future = client.submit(
            ensure_entries,
            plan.root,
            SPIKES.name,
            scenes,
            key=f"spikes-{_digest_keys(trains)}-{root}",
            pure=False,
            priority=max(cost.values()) + 1,
        )
        train_futures.update(dict.fromkeys(trains, future))
    futures: dict[str, Any] = {}
    for batch in batches:
        keys = [key for _, keys in batch for key in keys]
        after = list({id(f): f for t, _ in batch if (f := train_futures.get(t))}.values())
        future = client.submit(
            ensure_entries,
            plan.root,
            RESULTS.name,
            [plan.scenes[key] for key in keys],
            *after,
            key=f"points-{_digest_keys(keys)}-{root}",
            pure=False,
            priority=max(cost[key] for key in keys),
        )
        futures.update(dict.fromkeys(keys, future))
    return futures


def default_points_per_task(n_points: int, n_threads: int) -> int:
    """Points per task: about 8 tasks per worker thread, 1 to :data:`MAX_POINTS_PER_TASK`.

    Eight tasks per thread keep the workers evenly busy to the end when points differ in
    cost; a sweep of few, expensive points gets one point per task.
    """
    per_task = math.ceil(n_points / (TASKS_PER_THREAD * max(1, n_threads)))
    return max(1, min(MAX_POINTS_PER_TASK, per_task))


def _batches(by_train: dict[str, list[str]], size: int) -> list[list[tuple[str, list[str]]]]:
    """Points in batches of at most ``size``: (spike key, result keys) pairs, in order.

    The points of one train stay in one batch where they fit, so that the batch computes the
    train itself; a train with more points than ``size`` is spread over several batches.
    """
    batches: list[list[tuple[str, list[str]]]] = []
    current: list[tuple[str, list[str]]] = []
    room = size
    for train, keys in by_train.items():
        if len(keys) > room and current and len(keys) <= size:
            batches.append(current)
            current, room = [], size
        while keys:
            taken, keys = keys[:room], keys[room:]
            current.append((train, taken))
            room -= len(taken)
            if room == 0:
                batches.append(current)
                current, room = [], size
    if current:
        batches.append(current)
    return batches


def _digest_keys(keys: list[str]) -> str:
    return hashlib.sha256("".join(keys).encode()).hexdigest()[:32]


def progress_bar(plan: SweepPlan, show_progress: bool) -> Any:
    """A tqdm bar over the plan's distinct points, cached ones counted as done."""
    from tqdm import tqdm

    return tqdm(
        total=len(plan.scenes),
        initial=len(plan.cached),
        unit="point",
        desc=f"sweep {plan.grid.name}",
        disable=None if show_progress else True,
    )


def failure_message(failures: list[str], n_points: int, root: str) -> str:
    """One line: how many of ``n_points`` failed, the first three failures, where the rest are."""
    shown = "; ".join(failures[:3]) + (
        f"; and {len(failures) - 3} more" if len(failures) > 3 else ""
    )
    return f"{len(failures)} of {n_points} points failed (the others are kept in {root}): {shown}"


def completed_points(client: Any, futures: dict[str, Any]) -> Iterator[tuple[str, str | None]]:
    """Yield ``(key, failure)`` for every point as its task finishes (``failure`` None for a
    success).

    A task that stored some of its points and failed others (:class:`flows.work.PointsFailed`)
    counts only those as failed; a task that failed as a whole fails all its points.

    Raises :class:`SweepFailed` if the cluster has had no worker for ``NO_WORKER_TIMEOUT_S``.
    """
    from distributed import wait

    points: dict[Any, list[str]] = {}
    for key, future in futures.items():
        points.setdefault(future, []).append(key)
    pending = set(points)
    alone_since = None
    while pending:
        try:
            done = wait(pending, timeout=POLL_S, return_when="FIRST_COMPLETED").done
        except TimeoutError:
            done = set()
        for future in done:
            pending.discard(future)
            failures = point_failures(future, points[future])
            for key in points[future]:
                yield key, failures.get(key)
        if client.nthreads():
            alone_since = None
        elif alone_since is None:
            alone_since = time.monotonic()
        elif time.monotonic() - alone_since > NO_WORKER_TIMEOUT_S:
            n_left = sum(len(points[f]) for f in pending)
            raise SweepFailed(
                f"the Dask cluster has had no worker for {NO_WORKER_TIMEOUT_S:.0f} s with "
                f"{n_left} points left; finished points are kept in the store"
            )


def point_failures(future: Any, keys: list[str]) -> dict[str, str]:
    """Why each of ``keys`` failed in the finished task ``future``; empty if none failed."""
    if future.status != "error":
        return {}
    error = future.exception()
    if isinstance(error, PointsFailed):
        return {key: f"point {key}: {why}" for key, why in error.failures.items() if key in keys}
    return dict.fromkeys(keys, f"{future.key}: {error}")


def assemble_cube(plan: SweepPlan, name: str) -> xr.Dataset:
    """Build the cube of the sweep ``name`` from the store, write it and return it.

    The points cached at planning come from the plan; the others are read from the store, each
    batch once.

    Raises
    ------
    StoreError
        A point of the sweep has no result in the store (it failed, or was never computed).
    CorruptEntryError
        A result's batch fails its checksum.
    """
    store = SweepStore.open(plan.root)
    spec = next(s for s in plan.grid.sweeps if s.name == name)
    keys = plan.sweep_keys[name]
    computed = [key for key in keys if key not in plan.records]
    read = store.read_many(RESULTS.record, computed, discard_corrupt=False)
    missing = [key for key in computed if key not in read]
    if missing:
        raise StoreError(
            f"sweep {name!r}: {len(missing)} point(s) have no result in {plan.root} "
            f"(first: {missing[0]})"
        )
    records = {key: plan.records[key] if key in plan.records else read[key] for key in keys}
    cube = build_cube(plan.grid, spec, records)
    store.write_cube(name, cube)
    return cube


def assemble_cubes(plan: SweepPlan) -> dict[str, str]:
    """Build every sweep's cube from the store and write it; return where each cube is."""
    for spec in plan.grid.sweeps:
        assemble_cube(plan, spec.name)
    return {spec.name: cube_location(plan, spec.name) for spec in plan.grid.sweeps}


def cube_location(plan: SweepPlan, name: str) -> str:
    return str(Path(plan.root) / "store.zarr" / "cubes" / name)


def best_points(cube: xr.Dataset) -> list[dict[str, Any]]:
    """Per model, the best accuracy (``accuracy_mean``) of a cube and the swept values it is at.

    Returns
    -------
    list of dict
        ``{"model", "accuracy", "at"}`` per model, ``at`` mapping each swept dimension to its
        value at the best point (the first of equals, in the cube's order).
    """
    mean = cube["accuracy_mean"]
    rows = []
    for model in cube["model"].values:
        per_model = mean.sel(model=model)
        flat = int(np.nanargmax(per_model.values)) if per_model.size else 0
        index = np.unravel_index(flat, per_model.shape)
        at = {
            dim: per_model[dim].values[i].item()
            for dim, i in zip(per_model.dims, index, strict=True)
        }
        rows.append({"model": str(model), "accuracy": float(per_model.values[index]), "at": at})
    return rows


# ---------------------------------------------------------------------------------------------
# A whole sweep, without Prefect


@contextlib.contextmanager
def sweep_client(
    plan: SweepPlan,
    client: Any = None,
    workers: int | None = None,
    address: str | None = None,
) -> Iterator[Any]:
    """The Dask client that takes the plan's missing points, or None when none is missing.

    ``client``, when given, is used as it is and left open. Otherwise a fresh one is made
    (:func:`flows.cluster.dask_client` with ``workers`` or ``address``) and closed at the end.
    """
    if not plan.missing:
        yield None
    elif client is not None:
        yield client
    else:
        hermetic_environment(Path(plan.root), prefect=False)
        with dask_client(workers, address) as fresh:
            yield fresh


def sweep_summary(
    plan: SweepPlan, cubes: dict[str, str], computed: int, seconds: float
) -> dict[str, Any]:
    """A finished sweep's summary, as ``eskin sweep --json`` prints it.

    Keys: ``root``, ``cubes`` (each cube's location by sweep name), ``points`` (distinct),
    ``cache_hits``, ``computed`` and ``seconds`` (the sweep's wall time, s).
    """
    return {
        "root": plan.root,
        "cubes": cubes,
        "points": len(plan.scenes),
        "cache_hits": len(plan.cached),
        "computed": computed,
        "seconds": seconds,
    }


def log_sweep_run(
    plan: SweepPlan, summary: dict[str, Any], warn: Callable[..., Any] | None = None
) -> None:
    """Append the sweep to the root's run log, which the report shows.

    A log that cannot be written does not fail the sweep: ``warn`` (default: this module's
    logger) is called with a %-format message instead.
    """
    from storage.runlog import append_sweep_run

    try:
        append_sweep_run(plan.root, {**summary, "grid": plan.grid.name})
    except OSError as error:
        (warn or logging.getLogger(__name__).warning)(
            "sweep not logged in %s: %s", plan.root, error
        )


def run_sweep(
    grid: str | Path,
    root: str | Path | None = None,
    *,
    client: Any = None,
    workers: int | None = None,
    dataset: str | Path | None = None,
    show_progress: bool = False,
) -> dict[str, Any]:
    """Sweep a grid into labelled cubes under ``root``, on a Dask client, without Prefect.

    What the ``sweep`` flow does, as one plain call for a notebook or a script: hold the
    root's lock, plan the grid, submit its missing points, wait for them, assemble and write
    every cube, and log the sweep for the report.

    Parameters
    ----------
    grid
        A built-in grid name (``paper``, ``smoke``) or a grid TOML file.
    root
        The run root (default: :func:`default_root`), created if need be.
    client
        A ``distributed.Client`` to compute on, left open. Default: a local cluster of
        ``workers`` single-thread processes, started only if a point is missing and stopped
        at the end.
    workers
        Workers of that local cluster (default: one per available core); not with ``client``.
    dataset
        Other recordings for every point (``"synthetic"`` or a dataset folder), as
        ``eskin sweep --dataset``.
    show_progress
        Show a progress bar over the points on stderr.

    Returns
    -------
    dict
        :func:`sweep_summary`, plus ``dashboard`` (the Dask dashboard's address, or None when
        nothing was computed).

    Raises
    ------
    EskinError
        Bad input (grid, dataset, root, ``workers``), before anything is written; a root that
        another sweep holds (:class:`storage.StoreBusyError`).
    SweepFailed
        Some points failed; the cubes of the sweeps they are not in are written.
    """
    start = time.perf_counter()
    if workers is not None:
        if client is not None:
            raise ClusterError("give a client or a number of workers, not both")
        workers = check_workers(workers, name="workers")
    grid_ref = str(grid)
    data_ref = None if dataset is None else str(dataset)
    store = open_root(grid_ref, None if root is None else str(root), data_ref)
    with store.lock():
        plan = plan_sweep(grid_ref, str(store.root), data_ref)
        failed: dict[str, str] = {}
        with sweep_client(plan, client, workers) as dask:
            futures = submit_missing(plan, dask) if dask is not None else {}
            with progress_bar(plan, show_progress) as bar:
                for key, failure in completed_points(dask, futures):
                    bar.update(1)
                    if failure:
                        failed[key] = failure
            dashboard = dask.dashboard_link if dask is not None else None
        cubes = {}
        for spec in plan.grid.sweeps:
            # A sweep with a failed point has no cube: a cube never holds a hole.
            if not failed.keys() & set(plan.sweep_keys[spec.name]):
                assemble_cube(plan, spec.name)
                cubes[spec.name] = cube_location(plan, spec.name)
    if failed:
        raise SweepFailed(failure_message(list(failed.values()), len(plan.scenes), plan.root))
    summary = sweep_summary(plan, cubes, len(futures), time.perf_counter() - start)
    log_sweep_run(plan, summary)
    return summary | {"dashboard": dashboard}


# ---------------------------------------------------------------------------------------------
# Dry run


@dataclass(frozen=True)
class SweepCounts:
    """Distinct points of one named sweep, and how many of them are cached or missing."""

    name: str
    points: int
    cached: int
    missing: int


@dataclass(frozen=True)
class DryRun:
    """What a sweep would do, found without writing anything (:func:`dry_run`).

    Attributes
    ----------
    grid : str
        The grid's name.
    root : str
        The run root looked at (it need not exist).
    points, cached, missing : int
        Distinct points of the grid (a point shared by two sweeps counts once), those with a
        valid result in the store, and the rest.
    sweeps : tuple of SweepCounts
        The same counts per named sweep, in the grid's order (a shared point counts in each).
    estimated_seconds : float
        Estimated compute seconds (s) of the missing points of known kind, summed.
    unknown : int
        Missing points of unknown kind (no cached point like them): not in the estimate.
    workers : int
        Workers the wall estimate divides by.
    """

    grid: str
    root: str
    points: int
    cached: int
    missing: int
    sweeps: tuple[SweepCounts, ...]
    estimated_seconds: float
    unknown: int
    workers: int

    @property
    def wall_seconds(self) -> float:
        """``estimated_seconds / workers`` (s): the wall time if every worker stays busy."""
        return self.estimated_seconds / self.workers

    def to_json(self) -> dict[str, Any]:
        """A JSON-able dict of every attribute, plus ``wall_seconds``."""
        return {
            "grid": self.grid,
            "root": self.root,
            "points": self.points,
            "cached": self.cached,
            "missing": self.missing,
            "sweeps": {
                s.name: {"points": s.points, "cached": s.cached, "missing": s.missing}
                for s in self.sweeps
            },
            "estimated_seconds": self.estimated_seconds,
            "unknown": self.unknown,
            "workers": self.workers,
            "wall_seconds": self.wall_seconds,
        }


def dry_run(grid: Grid, root: Path, workers: int) -> DryRun:
    """Count the grid's cached and missing points and estimate the cost of the missing ones.

    Writes nothing: a ``root`` that does not exist (or holds no store yet) simply has nothing
    cached and is not created; partial entries are left alone, and a corrupt result is counted
    as missing (the sweep would recompute it) but not removed.

    The estimate: points of the same *kind* (:func:`cost_kind`) cost about the same. A missing
    point is estimated at the median, over the cached points of this grid of its kind, of the
    total of their measured stage seconds (:attr:`pipeline.records.ResultEntry.seconds`); a missing
    point whose kind has no cached point is counted in ``unknown`` and left out. Stage seconds
    are as measured when each stage ran, so a spike train or a dataset that several points
    share counts in each of them: the estimate leans high for points that will share work with
    cached ones. The wall estimate, ``estimated_seconds / workers``, assumes the workers stay
    busy to the end (a sweep with fewer missing points than workers, or one long point, takes
    longer).

    Parameters
    ----------
    grid
        The grid (already given its dataset, if overridden).
    root
        The run root a sweep of ``grid`` would use.
    workers
        Workers the sweep would run on (>= 1).

    Raises
    ------
    StoreError
        ``root`` is something a sweep would refuse (a file, a foreign store, ...).
    """
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    store = SweepStore.open_readonly(root)
    scenes = grid.unique_points()
    totals: dict[str, float] = {}
    if store is not None:
        for key, entry in store.peek_many(RESULTS.record, scenes).items():
            totals[key] = sum(entry.seconds.values())
    by_kind: dict[str, list[float]] = {}
    for key, seconds in totals.items():
        by_kind.setdefault(cost_kind(scenes[key]), []).append(seconds)
    medians = {kind: statistics.median(values) for kind, values in by_kind.items()}
    estimated = 0.0
    unknown = 0
    for key, scene in scenes.items():
        if key in totals:
            continue
        median = medians.get(cost_kind(scene))
        if median is None:
            unknown += 1
        else:
            estimated += median
    sweep_keys: dict[str, dict[str, None]] = {s.name: {} for s in grid.sweeps}
    for point in grid.points():
        sweep_keys[point.sweep][point.key] = None
    counts = []
    for name, keys in sweep_keys.items():
        n_cached = sum(key in totals for key in keys)
        counts.append(SweepCounts(name, len(keys), n_cached, len(keys) - n_cached))
    return DryRun(
        grid=grid.name,
        root=str(root),
        points=len(scenes),
        cached=len(totals),
        missing=len(scenes) - len(totals),
        sweeps=tuple(counts),
        estimated_seconds=estimated,
        unknown=unknown,
        workers=workers,
    )


def format_dry_run(d: DryRun) -> str:
    """A short table: points, cached and missing per sweep and in all, then the estimate."""
    width = max(len("all (distinct)"), *(len(s.name) for s in d.sweeps))
    rows = [(s.name, s.points, s.cached, s.missing) for s in d.sweeps]
    rows.append(("all (distinct)", d.points, d.cached, d.missing))
    lines = [
        f"dry run of grid {d.grid!r} in {d.root} (nothing written)",
        f"{'sweep':<{width}}  {'points':>6}  {'cached':>6}  {'missing':>7}",
        *(f"{n:<{width}}  {p:>6}  {c:>6}  {m:>7}" for n, p, c, m in rows),
    ]
    known = d.missing - d.unknown
    if d.missing == 0:
        lines.append("estimate: nothing to compute")
    elif known == 0:
        lines.append(
            f"estimate: unknown ({d.missing} missing points, none of a kind already measured)"
        )
    else:
        text = (
            f"estimate: {_duration(d.estimated_seconds)} of compute for {known} missing points, "
            f"~{_duration(d.wall_seconds)} wall on {d.workers} worker(s) if they stay busy"
        )
        if d.unknown:
            text += f"; {d.unknown} more of unknown kind (none like them measured)"
        lines.append(text)
    return "\n".join(lines)


def _duration(seconds: float) -> str:
    """``"42 s"``, ``"12 min"`` or ``"3.5 h"``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
