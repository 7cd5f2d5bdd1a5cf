"""Planning a sweep: its grid loaded and checked once, its root, its distinct and cached points.

A command loads its grid once (:func:`load_sweep_grid`) and checks it once against its
recordings (:func:`check_grid`) before anything is written or Prefect imported; the checked
:class:`pipeline.design.grid.Grid` is then handed on, and :func:`plan_sweep` turns it into the
:class:`SweepPlan` that every later step takes (scheduling, progress, assembly).

A stored cube is *current* when it was built from what a sweep of this grid would build it
from now, its *source* (:func:`cube_source`): the grid's base scene and the sweep, the names of
the batches that hold its points' results (a batch never changes once in place, and a result
computed again lands in a new one), and the code and dependency versions; and when every file
of it is as written (:meth:`storage.store.SweepStore.current_note`). Planning reads the cached
results of the other sweeps only: a re-run with every cube current reads none.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import re
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import pipeline
import storage
from flows.environment import machine_memory_bytes
from pipeline.design.grid import Grid, load_grid
from pipeline.design.grid_cost import plannable_points
from pipeline.design.scene import DatasetSpec, Scene
from pipeline.recordings.sources import resolve_dataset_argument
from pipeline.run.entries import ResultEntry
from pipeline.run.fit import DatasetLimits, check_fits
from pipeline.run.grid_keys import distinct_scenes, keyed_points, keys_by_sweep
from pipeline.run.stages import RECORDINGS, RESULTS
from storage import SweepStore

DEFAULT_RUNS_DIR = Path("runs")


@dataclass(frozen=True)
class SweepPlan:
    """What a sweep will do: its grid, its store, its distinct points and which are cached.

    ``records`` holds the result entries of the cached points as planning read (and checked)
    them, so that assembling the cubes reads from the store only the points computed since.
    ``current`` holds the stored summary of each sweep whose cube is current (see the module
    docstring): its points count as cached, and their results are read only where another
    sweep needs them.
    """

    grid: Grid
    root: str
    scenes: dict[str, Scene]  # distinct points by result key
    records: dict[str, ResultEntry]
    current: Mapping[str, dict[str, Any]] = dataclasses.field(default_factory=dict)

    @functools.cached_property
    def cached(self) -> frozenset[str]:
        """Result keys of the points whose result is already stored. These are the results
        planning read, and every point of a sweep whose cube is current."""
        return frozenset(self.records).union(*(self.sweep_keys[name] for name in self.current))

    @property
    def missing(self) -> list[str]:
        """Result keys of the distinct points still to compute (not :attr:`cached`), in the
        grid's order."""
        return [key for key in self.scenes if key not in self.cached]

    @functools.cached_property
    def sweep_keys(self) -> dict[str, tuple[str, ...]]:
        """The distinct result keys of each named sweep, in the order of its points."""
        return sweep_keys(self.grid)


def sweep_keys(grid: Grid) -> dict[str, tuple[str, ...]]:
    """The distinct result keys of each named sweep of ``grid``, in the order of its points."""
    return keys_by_sweep(keyed_points(grid), grid.sweeps)


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
        (:func:`pipeline.design.grid_cost.plannable_points`), or a sweep sets a ``dataset.*`` field
        while ``dataset`` is given.
    DatasetError
        ``dataset`` names no dataset.
    """
    # A grid larger than this machine can plan is refused from its axis sizes.
    grid = load_grid(grid_ref, plannable_points(machine_memory_bytes()))
    if dataset is not None:
        grid = grid.with_dataset(resolve_dataset_argument(str(dataset)))
    return grid


def check_grid(grid: Grid) -> dict[str, DatasetLimits]:
    """Check every point against its recordings (each dataset described once); raise on misfits.

    Returns the limits of each dataset, by recordings cache key.
    """
    limits: dict[str, DatasetLimits] = {}
    seen: set[DatasetSpec] = set()
    for point in grid.points():
        # The recordings key is a function of the dataset alone: one key per distinct dataset.
        if point.scene.dataset in seen:
            continue
        seen.add(point.scene.dataset)
        key = RECORDINGS.key(point.scene)
        if key not in limits:
            limits[key] = DatasetLimits.describe(point.scene.dataset)
    check_fits(grid, limits)
    return limits


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


def plan_sweep(grid: Grid, root: str | Path, tidy: bool = True) -> SweepPlan:
    """Tidy the store at ``root``, find which of the (checked) grid's points are cached and
    which stored cubes are current.

    Call it holding the root's lock (:meth:`storage.store.SweepStore.lock`): no other sweep writes
    to the root then, so every partial entry is a leftover of a killed run and is removed
    (``tidy``; a search planning one trial while its other trials' points are being written
    passes False, having tidied once at its start). A
    cached result that fails its checksum is discarded (with a warning) and planned again, and
    the cubes built from its batch are no longer current.
    """
    store = SweepStore.open(root)
    if tidy:
        store.clean_partials()
    points = keyed_points(grid)  # each key computed once
    scenes = distinct_scenes(points)
    keys = keys_by_sweep(points, grid.sweeps)
    del points  # not kept while the store is read: a point each, as many as the grid has
    records: dict[str, ResultEntry] = {}
    while True:
        batches = store.entry_batches(RESULTS.record)
        current = {
            name: note
            for name, own in keys.items()
            if (source := cube_source(grid, name, own, batches)) is not None
            and (note := store.current_note(name, source)) is not None
        }
        needed = {key for name, own in keys.items() if name not in current for key in own}
        wanted = [key for key in scenes if key in needed and key in batches]
        records |= store.read_many(
            RESULTS.record, [key for key in wanted if key not in records], discard_corrupt=True
        )
        after = store.entry_batches(RESULTS.record)
        if after == batches:  # nothing discarded: what was found current still is
            break
        records = {key: entry for key, entry in records.items() if key in after}
    return SweepPlan(
        grid,
        str(store.root),
        scenes,
        {key: records[key] for key in scenes if key in records},
        current,
    )


def cube_source(
    grid: Grid, name: str, keys: tuple[str, ...], batches: Mapping[str, str]
) -> str | None:
    """The digest of what the cube of sweep ``name`` of ``grid`` is built from, or None while
    one of its points (result ``keys``) has no stored result.

    ``batches`` maps result keys to the batches holding them
    (:meth:`storage.store.SweepStore.entry_batches`).
    """
    if any(key not in batches for key in keys):
        return None
    spec = next(s for s in grid.sweeps if s.name == name)
    described = {
        "grid": grid.name,
        "base": repr(grid.base),
        "sweep": repr(spec),
        "results": [[key, batches[key]] for key in keys],
        "code": _code_digest(),
    }
    return hashlib.sha256(json.dumps(described).encode()).hexdigest()


@functools.cache
def _code_digest() -> str:
    """sha256 of this package's version, its dependencies' versions and the source of the
    packages that build and store a cube (an edited module changes it)."""
    from pipeline.results.provenance import DEPENDENCY_VERSIONS

    found = hashlib.sha256(
        json.dumps([metadata.version("eskin-sweep"), DEPENDENCY_VERSIONS]).encode()
    )
    for package in (pipeline, storage):
        folder = Path(next(iter(package.__path__)))
        for path in sorted(folder.rglob("*.py")):
            found.update(path.relative_to(folder).as_posix().encode() + b"\0")
            found.update(path.read_bytes())
    return found.hexdigest()
