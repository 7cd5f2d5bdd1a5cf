"""What accuracy costs in time: the Pareto front rule, observation time, the sweep's own cost.

The sweep's own cost (:func:`sweep_cost`) sums the seconds its workers *paid*, over its distinct
points, by stage and charge (the cube's ``seconds``, :mod:`pipeline.results.cube`): a load, a
front-end fit or a kernel compile that a worker shares among its points is counted once, at the
point that paid it (``shared``), so that the total is the workers' busy time. Points stored
before paid seconds were kept count their work seconds instead (a shared load at every such
point), and the report says how many there are.

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

from pipeline.report.cubes import point_keys, sweep_dims
from pipeline.report.curves import Curve
from pipeline.report.text import pct
from pipeline.results.cube import paid_seconds, work_seconds
from pipeline.results.variables import CHARGE_DIM, STAGE_DIM
from pipeline.run.records import Charge
from pipeline.run.stages import step_charge

OBSERVATION_FRACTIONS = (0.8, 0.9, 1.0)

#: What a run root holds, how large and why (:attr:`pipeline.run.stages.Level.kept`).
ROOT_SENTENCE = (
    "The run root keeps every point's result (all its cubes read) and the spike trains of the "
    "points without chips, as microsecond ticks in about 2 bytes per event (a train is read "
    "back faster than it is encoded); the trains of simulated chips are not kept (about 35 MB "
    "per 100-chip point, 5 s to encode again), their results are."
)


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
class StageCost:
    """Seconds the workers paid for one stage, summed over the distinct points, by charge."""

    stage: str
    own_s: float
    shared_s: float

    @property
    def total_s(self) -> float:
        """Both charges (s)."""
        return self.own_s + self.shared_s


@dataclass(frozen=True)
class SweepCost:
    """The sweep's own cost: paid seconds summed over its distinct points, and its runs.

    ``n_unpaid`` of the ``n_points`` were stored before paid seconds were kept: their work
    seconds are counted instead (under the charge of each stage,
    :func:`pipeline.run.stages.step_charge`).
    """

    n_points: int
    stages: tuple[StageCost, ...]
    runs: tuple[SweepRun, ...]
    n_unpaid: int = 0

    @property
    def stage_seconds(self) -> tuple[tuple[str, float], ...]:
        """(stage, seconds of both charges) of every stage that cost any."""
        return tuple((s.stage, s.total_s) for s in self.stages)

    @property
    def total_s(self) -> float:
        """Paid seconds summed over every stage and charge (s)."""
        return float(sum(s.total_s for s in self.stages))

    @property
    def shared_s(self) -> float:
        """Of :attr:`total_s`, the seconds of shared work (s)."""
        return float(sum(s.shared_s for s in self.stages))


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
    """Paid seconds summed over the distinct points of all cubes by stage and charge, and the
    logged runs (see the module docstring)."""
    per_point: dict[str, dict[tuple[str, Charge], float]] = {}
    unpaid: set[str] = set()
    for cube in cubes.values():
        paid, work = paid_seconds(cube), work_seconds(cube)
        if paid is None and work is None:
            continue
        stages = [str(s) for s in cube[STAGE_DIM].values]
        dims = sweep_dims(cube)
        charges = list(Charge) if paid is None else [Charge(c) for c in cube[CHARGE_DIM].values]
        # (points, stage, charge) paid seconds and (points, stage) work seconds, in point order.
        paid_rows = (
            None
            if paid is None
            else paid.transpose(*dims, STAGE_DIM, CHARGE_DIM).values.reshape(
                -1, len(stages), len(charges)
            )
        )
        work_rows = (
            None
            if work is None
            else work.transpose(*dims, STAGE_DIM).values.reshape(-1, len(stages))
        )
        for i, key in enumerate(point_keys(cube)):
            if key in per_point:
                continue
            row = None if paid_rows is None else paid_rows[i]
            if row is not None and np.isfinite(row).all():
                per_point[key] = {
                    (stage, charge): float(row[s, c])
                    for s, stage in enumerate(stages)
                    for c, charge in enumerate(charges)
                }
            elif work_rows is not None:
                unpaid.add(key)
                values = work_rows[i]
                per_point[key] = {
                    (stage, step_charge(stage)): float(values[s])
                    for s, stage in enumerate(stages)
                    if math.isfinite(values[s])
                }
    totals: dict[str, dict[Charge, float]] = {}
    for seconds in per_point.values():
        for (stage, charge), value in seconds.items():
            by_charge = totals.setdefault(stage, dict.fromkeys(Charge, 0.0))
            by_charge[charge] += value
    rows = tuple(
        StageCost(stage, by_charge[Charge.OWN], by_charge[Charge.SHARED])
        for stage, by_charge in totals.items()
        if by_charge[Charge.OWN] or by_charge[Charge.SHARED]
    )
    return SweepCost(len(per_point), rows, tuple(runs), len(unpaid))


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
