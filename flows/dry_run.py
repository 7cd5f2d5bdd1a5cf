"""The dry run: what a sweep would do, counted and estimated without writing anything.

:func:`dry_run` counts a grid's cached and missing points in a root (which need not exist) and
estimates the missing points' cost from the measured seconds of cached points of the same kind
(:func:`pipeline.design.grid_cost.cost_kind`); :func:`format_dry_run` is the table ``eskin sweep
--dry-run`` prints.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pipeline.design.grid import Grid
from pipeline.design.grid_cost import cost_kind
from pipeline.run.grid_keys import distinct_scenes, keyed_points, keys_by_sweep
from pipeline.run.stages import RESULTS
from storage import SweepStore


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

    The estimate: points of the same *kind* (:func:`pipeline.design.grid_cost.cost_kind`) cost
    about the same. A missing point is estimated at the median, over the cached points of this
    grid of its kind, of the total of their measured stage seconds
    (:attr:`pipeline.run.entries.ResultEntry.seconds`); a missing point whose kind has no cached
    point is counted in ``unknown`` and left out. Stage seconds are as measured when each stage ran,
    so a spike train or a dataset that several points share counts in each of them: the estimate
    leans high for points that will share work with cached ones. The wall estimate,
    ``estimated_seconds / workers``, assumes the workers stay busy to the end (a sweep with fewer
    missing points than workers, or one long point, takes longer).

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
    points = keyed_points(grid)  # each key computed once
    scenes = distinct_scenes(points)
    totals: dict[str, float] = {}
    if store is not None:
        for key, entry in store.peek_many(RESULTS.record, scenes).items():
            totals[key] = sum(entry.seconds.values())
    by_kind: dict[str, list[float]] = {}
    for key, seconds in totals.items():
        by_kind.setdefault(cost_kind(scenes[key]), []).append(seconds)
    medians = {kind: statistics.median(values) for kind, values in by_kind.items()}
    estimated = 0.0
    unknown = 0 if medians else len(scenes) - len(totals)
    # A point's kind is looked up only where some kind has a cached point to go by.
    for key, scene in scenes.items() if medians else ():
        if key in totals:
            continue
        median = medians.get(cost_kind(scene))
        if median is None:
            unknown += 1
        else:
            estimated += median
    counts = []
    for name, keys in keys_by_sweep(points, grid.sweeps).items():
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
