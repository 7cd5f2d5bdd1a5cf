"""What accuracy costs in time: the Pareto front rule, observation time, the sweep's own cost.

A point lies on the *Pareto front* of accuracy against a cost when every cheaper point is strictly
less accurate: the cheapest design for each accuracy level (:func:`pareto_front`; the fronts
themselves are in :mod:`pipeline.report.fronts`).

Observation time of a point: ``T = n_windows * window_s`` seconds of touch; the time needed to
reach accuracy ``L`` is the smallest swept ``T`` with ``a(T) >= L`` (grid points, no
interpolation), with ``L`` a fraction of the model's best accuracy along the sweep.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from pipeline.report.cubes import point_keys
from pipeline.report.curves import Curve
from pipeline.report.text import pct

OBSERVATION_FRACTIONS = (0.8, 0.9, 1.0)


@dataclass(frozen=True)
class SweepRun:
    """One ``eskin sweep`` of this root, as its run log recorded it."""

    finished: str
    grid: str
    points: int
    cache_hits: int
    computed: int
    seconds: float


@dataclass(frozen=True)
class SweepCost:
    """The sweep's own cost: stage seconds summed over its distinct points, and its runs."""

    n_points: int
    stage_seconds: tuple[tuple[str, float], ...]
    runs: tuple[SweepRun, ...]

    @property
    def total_s(self) -> float:
        """Stage seconds summed over every stage (s)."""
        return float(sum(s for _, s in self.stage_seconds))


@dataclass(frozen=True)
class TimeToAccuracy:
    """Seconds of touch a model needs to reach ``fraction`` of its best accuracy (None: never)."""

    model: str
    fraction: float
    target: float
    seconds: float | None


def pareto_front(seconds: np.ndarray, accuracy: np.ndarray) -> np.ndarray:
    """Mask of the points no cheaper-or-equal point beats: the cheapest design per accuracy.

    Parameters
    ----------
    seconds, accuracy : float64 (n,)
        Cost and accuracy of each point (NaN never on the front).

    Returns
    -------
    bool (n,)
        True where every point with ``seconds <= s_i`` (other than i) has accuracy ``< a_i``,
        or, among equal costs and accuracies, only the first such point.
    """
    seconds = np.asarray(seconds, dtype=np.float64)
    accuracy = np.asarray(accuracy, dtype=np.float64)
    front = np.zeros(seconds.shape, dtype=bool)
    usable = np.flatnonzero(np.isfinite(seconds) & np.isfinite(accuracy))
    # Cheapest first; among equal costs the most accurate first.
    order = usable[np.lexsort((-accuracy[usable], seconds[usable]))]
    best = -np.inf
    for i in order:
        if accuracy[i] > best:
            front[i] = True
            best = accuracy[i]
    return front


def sweep_cost(cubes: Mapping[str, xr.Dataset], runs: Iterable[SweepRun]) -> SweepCost:
    """Stage seconds summed over the distinct points of all cubes, and the logged runs."""
    per_point: dict[str, dict[str, float]] = {}
    for cube in cubes.values():
        if "seconds" not in cube:
            continue
        seconds = cube["seconds"]
        flat = seconds.values.reshape(-1, seconds.sizes["stage"])
        for key, row in zip(point_keys(cube), flat, strict=True):
            per_point.setdefault(
                key, {str(s): float(v) for s, v in zip(cube["stage"].values, row, strict=True)}
            )
    totals: dict[str, float] = {}
    for stages in per_point.values():
        for stage, value in stages.items():
            if math.isfinite(value):
                totals[stage] = totals.get(stage, 0.0) + value
    return SweepCost(len(per_point), tuple(totals.items()), tuple(runs))


def time_to_accuracy(
    curves: Sequence[Curve], fractions: Sequence[float] = OBSERVATION_FRACTIONS
) -> tuple[TimeToAccuracy, ...]:
    """For each model and fraction of its best accuracy, the least touch time that reaches it."""
    rows = []
    for curve in curves:
        best = float(curve.mean[curve.best])
        for fraction in fractions:
            target = fraction * best
            # Exact comparison: fraction 1.0 must find the best point itself.
            reached = np.flatnonzero(curve.mean >= target - 1e-12)
            seconds = float(curve.x[reached[0]]) if reached.size else None
            rows.append(TimeToAccuracy(curve.model, fraction, target, seconds))
    return tuple(rows)


def sweep_runs(records: Iterable[Mapping[str, Any]]) -> list[SweepRun]:
    """The run log's records (JSON objects) as :class:`SweepRun`, skipping any that lacks a
    field or holds a value of the wrong kind."""
    runs = []
    for record in records:
        try:
            runs.append(sweep_run_from_record(record))
        except (KeyError, ValueError, TypeError):
            continue
    return runs


def sweep_run_from_record(record: Mapping[str, Any]) -> SweepRun:
    """A run-log record (a JSON object) as a :class:`SweepRun`; raises KeyError/ValueError."""
    return SweepRun(
        finished=str(record["finished"]),
        grid=str(record["grid"]),
        points=int(record["points"]),
        cache_hits=int(record["cache_hits"]),
        computed=int(record["computed"]),
        seconds=float(record["seconds"]),
    )


def observation_sentence(rows: Sequence[TimeToAccuracy]) -> str:
    """One sentence on the touch time each model needs for 90 % of its best accuracy."""
    parts = [
        f"the {r.model.upper()} reaches 90 % of its best ({pct(r.target / 0.9)}) after "
        + (f"{r.seconds:.3g} s of touch" if r.seconds is not None else "no swept time")
        for r in rows
        if math.isclose(r.fraction, 0.9)
    ]
    return ("Along the observation sweep " + "; ".join(parts) + ".") if parts else ""
