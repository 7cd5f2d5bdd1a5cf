"""Hardware cost fronts: accuracy against each cost of a design, per model.

For one model and one :class:`~pipeline.report.designs.Cost` (address-event data rate, event
rate, equivalent bits, compute seconds, estimated readout power, the comparators' matched area
that the design's mismatch demands), every design with a known cost
and accuracy is a point. A point is *on the front* when every cheaper-or-equal point is strictly
less accurate (:func:`pipeline.report.cost.pareto_front`): the cheapest design for each accuracy
level. A point off the front is *dominated* by the most accurate front point that costs no more
than it (the front's step at its cost). It is marked *indistinguishable* from the front when the
paired test of the two on the same recordings (:meth:`pipeline.report.evidence.Evidence.compare`,
one unadjusted test per point, alpha 0.05) finds no significant difference: a designer may prefer
it for a reason the cost axis does not show, so it is drawn and listed, not hidden.

The frame-based readout of each array size in the run is a reference on the data-rate and power
fronts: ``n * bits * rate_hz`` bit/s and :func:`pipeline.results.readout_power.frame_power_w`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pipeline.report.cost import pareto_front
from pipeline.report.designs import Accuracy, Cost, Design, FrameReadout, cost
from pipeline.report.evidence import ALPHA, Evidence
from pipeline.results.readout_constants import EnergyModel
from pipeline.results.stats import PairedComparison

MAX_REFERENCES = 4  # frame-readout reference lines per front; more array sizes are not drawn


@dataclass(frozen=True)
class FrontPoint:
    """One design of one model on one cost axis.

    ``dominated_by`` is the key of the front point that dominates it (None on the front);
    ``versus_front`` the paired comparison ``accuracy(this) - accuracy(that)`` (None when not
    made).
    """

    design: Design
    model: str
    cost: float
    accuracy: Accuracy
    on_front: bool
    dominated_by: str | None
    versus_front: PairedComparison | None

    @property
    def indistinguishable(self) -> bool:
        """Off the front, yet not significantly less accurate than the front point above it."""
        return (
            not self.on_front
            and self.versus_front is not None
            and not self.versus_front.significant(ALPHA)
        )


@dataclass(frozen=True)
class Front:
    """Accuracy against one cost: ``points`` of every model, ``references`` the frame readout of
    each array size as ``(label, cost)``."""

    cost: Cost
    points: tuple[FrontPoint, ...]
    references: tuple[tuple[str, float], ...]

    def front(self, model: str) -> tuple[FrontPoint, ...]:
        """The model's front, cheapest first."""
        return tuple(
            sorted((p for p in self.points if p.model == model and p.on_front), key=_by_cost)
        )

    @property
    def marked(self) -> tuple[FrontPoint, ...]:
        """Points off the front but indistinguishable from it, cheapest first."""
        order = {m: i for i, m in enumerate(self.models)}
        marked = (p for p in self.points if p.indistinguishable)
        return tuple(sorted(marked, key=lambda p: (order[p.model], p.cost)))

    @property
    def models(self) -> tuple[str, ...]:
        """Names of the models with points on the fronts, each once, in the order of the points."""
        return tuple(dict.fromkeys(p.model for p in self.points))


def hardware_fronts(
    designs: Sequence[Design],
    evidence: Evidence,
    energy: EnergyModel,
    frame: FrameReadout | None,
    costs: Sequence[Cost] = tuple(Cost),
) -> tuple[Front, ...]:
    """One :class:`Front` per cost that at least one design states, in ``costs`` order."""
    fronts = []
    for which in costs:
        points: list[FrontPoint] = []
        models = list(dict.fromkeys(m for d in designs for m in d.accuracy))
        for model in models:
            points += _model_points(designs, evidence, energy, model, which)
        if points:
            fronts.append(Front(which, tuple(points), _references(designs, which, frame, energy)))
    return tuple(fronts)


def _model_points(
    designs: Sequence[Design], evidence: Evidence, energy: EnergyModel, model: str, which: Cost
) -> list[FrontPoint]:
    mine = [d for d in designs if model in d.accuracy]
    costs = np.array([cost(d, model, which, energy) for d in mine], dtype=np.float64)
    means = np.array([d.accuracy[model].mean for d in mine], dtype=np.float64)
    usable = np.isfinite(costs) & np.isfinite(means)
    mine = [d for d, ok in zip(mine, usable, strict=True) if ok]
    costs, means = costs[usable], means[usable]
    on = pareto_front(costs, means)
    front = sorted(np.flatnonzero(on), key=lambda i: costs[i])
    points = []
    for i, design in enumerate(mine):
        above = None
        if not on[i]:
            cheaper = [j for j in front if costs[j] <= costs[i]]
            above = cheaper[-1] if cheaper else None
        points.append(
            FrontPoint(
                design=design,
                model=model,
                cost=float(costs[i]),
                accuracy=design.accuracy[model],
                on_front=bool(on[i]),
                dominated_by=None if above is None else mine[above].key,
                versus_front=None
                if above is None
                else evidence.compare(design.key, mine[above].key, model),
            )
        )
    return points


def _references(
    designs: Sequence[Design], which: Cost, frame: FrameReadout | None, energy: EnergyModel
) -> tuple[tuple[str, float], ...]:
    if frame is None or which not in (Cost.DATA_RATE, Cost.POWER):
        return ()
    sizes = sorted({n for d in designs if (n := d.n_taxels) is not None and n > 0})
    if len(sizes) > MAX_REFERENCES:  # the smallest and the largest arrays bound the rest
        sizes = [sizes[0], sizes[-1]]
    references = []
    for n in sizes:
        value = (
            frame.data_rate_bps(n) if which is Cost.DATA_RATE else frame.power(n, energy).total_w
        )
        if math.isfinite(value) and value > 0:
            references.append((f"frame readout, {n} taxel{'' if n == 1 else 's'}", value))
    return tuple(references)


def _by_cost(point: FrontPoint) -> float:
    return point.cost
