"""Planning a sweep: its grid loaded and checked once, its root, its distinct and cached points.

A command loads its grid once (:func:`load_sweep_grid`) and checks it once against its
recordings (:func:`check_grid`) before anything is written or Prefect imported; the checked
:class:`pipeline.design.grid.Grid` is then handed on, and :func:`plan_sweep` turns it into the
:class:`SweepPlan` that every later step takes (scheduling, progress, assembly).
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from pathlib import Path

from flows.environment import machine_memory_bytes
from pipeline.design.grid import DatasetFacts, Grid, check_fits, load_grid, plannable_points
from pipeline.design.scene import DatasetSpec, Scene
from pipeline.recordings.sources import resolve_dataset_argument
from pipeline.run.records import ResultEntry
from pipeline.run.stages import RECORDINGS, RESULTS
from storage import SweepStore

DEFAULT_RUNS_DIR = Path("runs")


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
        return [key for key in self.scenes if key not in self.records]

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


def load_sweep_grid(grid_ref: str | Path, dataset: str | Path | None = None) -> Grid:
    """The grid ``grid_ref`` (a built-in name or a TOML file), on ``dataset`` if one is given.

    Parameters
    ----------
    grid_ref
        A built-in grid name or a grid TOML file (:func:`pipeline.design.grid.load_grid`).
    dataset
        The command line's ``--dataset`` text (``synthetic`` or a dataset folder), resolved with
        :func:`pipeline.recordings.sources.resolve_dataset_argument`; it replaces the base scene's
        dataset for every point (:meth:`pipeline.design.grid.Grid.with_dataset`). None keeps the
        grid's own.

    Raises
    ------
    SceneError
        The grid is invalid, larger than this machine can plan
        (:func:`pipeline.design.grid.plannable_points`), or a sweep sets a ``dataset.*`` field
        while ``dataset`` is given.
    DatasetError
        ``dataset`` names no dataset.
    """
    # A grid larger than this machine can plan is refused from its axis sizes.
    grid = load_grid(grid_ref, plannable_points(machine_memory_bytes()))
    if dataset is not None:
        grid = grid.with_dataset(resolve_dataset_argument(str(dataset)))
    return grid


def check_grid(grid: Grid) -> dict[str, DatasetFacts]:
    """Check every point against its recordings (each dataset described once); raise on misfits.

    Returns the facts of each dataset, by recordings cache key.
    """
    facts: dict[str, DatasetFacts] = {}
    seen: set[DatasetSpec] = set()
    for point in grid.points():
        # The recordings key is a function of the dataset alone: one key per distinct dataset.
        if point.scene.dataset in seen:
            continue
        seen.add(point.scene.dataset)
        key = RECORDINGS.key(point.scene)
        if key not in facts:
            facts[key] = DatasetFacts.describe(point.scene.dataset)
    check_fits(grid, facts)
    return facts


def checked_grid(grid: str | Path | Grid, dataset: str | Path | None = None) -> Grid:
    """``grid`` loaded (:func:`load_sweep_grid`, unless it is a Grid already) and checked.

    Raises
    ------
    ValueError
        ``dataset`` given with a Grid (give the Grid its dataset with
        :meth:`pipeline.design.grid.Grid.with_dataset`).
    EskinError
        As :func:`load_sweep_grid` and :func:`check_grid`.
    """
    if isinstance(grid, Grid):
        if dataset is not None:
            raise ValueError("give a dataset with a grid name or file, not with a Grid")
    else:
        grid = load_sweep_grid(grid, dataset)
    check_grid(grid)
    return grid


def open_root(grid: Grid, root: str | Path | None, dataset: str | Path | None = None) -> SweepStore:
    """The store at ``root`` (default: :func:`default_root` of ``grid`` and ``dataset``),
    created if need be."""
    data = None if dataset is None else str(dataset)
    return SweepStore.open_or_create(root or default_root(grid, data))


def plan_sweep(grid: Grid, root: str | Path) -> SweepPlan:
    """Tidy the store at ``root`` and find which of the (checked) grid's points are cached.

    Call it holding the root's lock (:meth:`storage.SweepStore.lock`): no other sweep writes to
    the root then, so every partial entry is a leftover of a killed run and is removed. A
    cached result that fails its checksum is discarded (with a warning) and planned again.
    """
    store = SweepStore.open(root)
    store.clean_partials()
    scenes = grid.unique_points()
    found = store.read_many(RESULTS.record, scenes, discard_corrupt=True)
    records = {key: found[key] for key in scenes if key in found}
    return SweepPlan(grid, str(store.root), scenes, records)
