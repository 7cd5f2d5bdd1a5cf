"""The result cache keys of a grid's points: which points are the same scene.

A grid (:mod:`pipeline.design.grid`) says which scenes its sweeps hold; the run layer says what
each one's result is stored under, ``cache_key(scene, "results")``
(:func:`pipeline.run.stages.cache_key`).
Two points with equal keys are one design, computed once: :func:`unique_points`. The points of a
sweep share their scene parts, so the keys of a sweep's points are written with one canonical
memo (:meth:`pipeline.design.scene.Scene.canonical`) and each shared part is serialised once.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from pipeline.design.grid import Grid, GridPoint, Sweep
from pipeline.design.scene import CanonicalMemo, Scene
from pipeline.run.stages import RESULTS


@dataclass(frozen=True)
class KeyedPoint(GridPoint):
    """A grid point and its scene's result cache key (``cache_key(scene, "results")``)."""

    key: str = field(compare=False, repr=False)


def keyed_points(grid: Grid, sweep: Sweep | None = None) -> list[KeyedPoint]:
    """The points of ``grid`` (every point of every sweep, as :meth:`Grid.points
    <pipeline.design.grid.Grid.points>`), or of ``sweep`` (:meth:`Grid.points_of
    <pipeline.design.grid.Grid.points_of>`), each with its result key."""
    sweeps = grid.sweeps if sweep is None else (sweep,)
    keyed = []
    for one in sweeps:
        memo: CanonicalMemo = {}
        keyed.extend(
            KeyedPoint(p.sweep, p.index, p.scene, RESULTS.key(p.scene, memo))
            for p in grid.points_of(one)
        )
    return keyed


def unique_points(grid: Grid) -> dict[str, Scene]:
    """The distinct scenes of ``grid`` by result key, in first-seen order."""
    return distinct_scenes(keyed_points(grid))


def distinct_scenes(points: Iterable[KeyedPoint]) -> dict[str, Scene]:
    """The distinct scenes of keyed ``points`` by result key, in first-seen order (for a caller
    that holds the points already: their keys are not computed again)."""
    unique: dict[str, Scene] = {}
    for point in points:
        unique.setdefault(point.key, point.scene)
    return unique


def keys_by_sweep(
    points: Iterable[KeyedPoint], sweeps: Iterable[Sweep]
) -> dict[str, tuple[str, ...]]:
    """The distinct result keys of each of ``sweeps`` among keyed ``points``, in the order of
    its points."""
    keys: dict[str, dict[str, None]] = {s.name: {} for s in sweeps}
    for point in points:
        keys[point.sweep][point.key] = None
    return {name: tuple(found) for name, found in keys.items()}
