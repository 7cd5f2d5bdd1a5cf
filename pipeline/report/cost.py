"""What accuracy costs: compute seconds per point, the Pareto front, observation time, the sweep.

Compute cost of a point for model ``m``: the seconds of its spike and coding stages plus
``train_m``, as measured when each stage was computed (a stage reused from the cache counts at
its original cost: the price of the design, not of this run). A point lies on the *Pareto front*
when every cheaper point is strictly less accurate: the cheapest design for each accuracy level.

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

from pipeline.report.cubes import is_one_dimensional, point_keys, sweeps_for
from pipeline.report.curves import Curve
from pipeline.report.panels import Panel
from pipeline.report.text import label, pct

OBSERVATION_FRACTIONS = (0.8, 0.9, 1.0)


@dataclass(frozen=True)
class CostPoint:
    """One distinct grid point for one model: compute seconds and accuracy."""

    key: str
    sweeps: tuple[str, ...]
    label: str
    model: str
    seconds: float
    mean: float
    std: float
    on_front: bool


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


def cost_points(cubes: Mapping[str, xr.Dataset]) -> tuple[CostPoint, ...]:
    """Every distinct point of every one-dimensional cube, per model, with the Pareto front."""
    found: dict[tuple[str, str], dict[str, Any]] = {}
    for name in sweeps_for(Panel.COST, cubes):
        cube = cubes[name]
        if not is_one_dimensional(cube):
            continue
        dim = cube["accuracy"].dims[0]
        stages = [str(s) for s in cube["stage"].values]
        for i, key in enumerate(point_keys(cube)):
            point = cube.isel({dim: i})
            text = f"{name}: {dim} = {label(point[dim].values)}"
            for model in cube["model"].values:
                folds = point["accuracy"].sel(model=model).values
                if np.isnan(folds).all():
                    continue
                entry = found.setdefault(
                    (key, str(model)),
                    {
                        "sweeps": [],
                        "label": text,
                        "seconds": _model_seconds(point["seconds"].values, stages, str(model)),
                        "mean": float(np.nanmean(folds)),
                        "std": float(np.nanstd(folds, ddof=0)),
                    },
                )
                entry["sweeps"].append(name)
    items = list(found.items())
    seconds = np.array([e["seconds"] for _, e in items])
    means = np.array([e["mean"] for _, e in items])
    front = pareto_front(seconds, means) if items else np.zeros(0, dtype=bool)
    return tuple(
        CostPoint(
            key=key,
            sweeps=tuple(e["sweeps"]),
            label=e["label"],
            model=model,
            seconds=e["seconds"],
            mean=e["mean"],
            std=e["std"],
            on_front=bool(on),
        )
        for ((key, model), e), on in zip(items, front, strict=True)
    )


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


def cost_sentence(points: Sequence[CostPoint]) -> str:
    """One sentence on the Pareto front of accuracy against compute time."""
    front = sorted((p for p in points if p.on_front), key=lambda p: p.seconds)
    if not front:
        return "No point has both compute seconds and accuracy."
    cheap, best = front[0], front[-1]
    return (
        f"{len(front)} of {len(points)} (point, model) pairs are on the Pareto front: the "
        f"cheapest design reaches {pct(cheap.mean)} in {cheap.seconds:.2g} s "
        f"({cheap.model.upper()}, {cheap.label}) and the most accurate {pct(best.mean)} in "
        f"{best.seconds:.2g} s ({best.model.upper()}, {best.label})."
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


def _model_seconds(row: np.ndarray, stages: list[str], model: str) -> float:
    keep = [not s.startswith("train_") or s == f"train_{model}" for s in stages]
    return float(np.nansum(row[keep]))
