"""The whole report's numbers and sentences from a run root's cubes (:func:`build_report`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import xarray as xr

from pipeline.errors import EskinError
from pipeline.report.claims import (
    PAPER_THRESHOLD_V,
    PAPER_WINDOW_S,
    Claim,
    metric_claim,
    mismatch_claim,
    optimum_claim,
    taxel_claim,
)
from pipeline.report.cost import (
    CostPoint,
    SweepCost,
    SweepRun,
    TimeToAccuracy,
    cost_points,
    sweep_cost,
    time_to_accuracy,
)
from pipeline.report.cubes import base_value, dataset_kind, panel_x, sweeps_for
from pipeline.report.curves import Curve, MetricFit, metric_fits, sweep_curves
from pipeline.report.panels import PANEL_FIELDS, Panel, absent
from pipeline.report.tables import FrameReadout, RunRow, run_row


@dataclass(frozen=True)
class Report:
    """Everything the report shows, as numbers and sentences.

    ``curves`` and ``fits`` hold the figures' data by panel; ``missing`` says, for every panel
    without data, why it is "not in this run".
    """

    grids: tuple[str, ...]
    dataset: str
    curves: Mapping[Panel, tuple[Curve, ...]]
    fits: tuple[MetricFit, ...]
    full_scale_v: float
    claims: tuple[Claim, ...]
    run_row: RunRow | None
    cost_points: tuple[CostPoint, ...]
    sweep_cost: SweepCost
    time_to_accuracy: tuple[TimeToAccuracy, ...]
    missing: Mapping[Panel, str]

    @property
    def panels(self) -> tuple[Panel, ...]:
        """Panels with data, in report order."""
        return tuple(p for p in Panel if p not in self.missing)


def build_report(
    cubes: Mapping[str, xr.Dataset],
    *,
    frame: FrameReadout | None = None,
    runs: Sequence[SweepRun] = (),
) -> Report:
    """All the report's numbers and sentences from a run root's cubes.

    Parameters
    ----------
    cubes
        ``{sweep name: cube}`` as :func:`storage.open_results` returns them.
    frame
        The frame-based ADC readout Table I compares with; None leaves that cell unknown.
    runs
        The run log's sweeps of this root (the sweep's own cost).

    Raises
    ------
    EskinError
        A cube was written by a version whose cubes did not describe themselves.
    """
    older = [name for name, cube in cubes.items() if "result_key" not in cube.coords]
    if older:
        raise EskinError(
            f"cube(s) {', '.join(older)} were written by an older eskin-sweep and do not "
            "describe themselves: run 'eskin sweep' on this root again to rebuild them (points "
            "already in the store are not recomputed)"
        )
    curves: dict[Panel, tuple[Curve, ...]] = {}
    missing: dict[Panel, str] = {}
    for panel in PANEL_FIELDS:
        names = sweeps_for(panel, cubes)
        found = tuple(c for n in names for c in sweep_curves(n, cubes[n], panel_x(panel, cubes[n])))
        if found:
            curves[panel] = found
        else:
            missing[panel] = absent(panel)
    fits = tuple(
        f for n in sweeps_for(Panel.SPIKE_METRICS, cubes) for f in metric_fits(n, cubes[n])
    )
    if not fits:
        missing[Panel.SPIKE_METRICS] = absent(Panel.SPIKE_METRICS)
    points = cost_points(cubes)
    if not points:
        missing[Panel.COST] = "not in this run: no cube holds compute seconds"
    threshold = sweeps_for(Panel.THRESHOLD, cubes)
    row = run_row(threshold[0], cubes[threshold[0]], frame) if threshold else None
    claims = (
        optimum_claim(
            Panel.THRESHOLD,
            curves.get(Panel.THRESHOLD, ()),
            PAPER_THRESHOLD_V,
            "V",
            f"the optimum threshold near {PAPER_THRESHOLD_V:g} V (3.47 bits)",
        ),
        optimum_claim(
            Panel.WINDOW,
            curves.get(Panel.WINDOW, ()),
            PAPER_WINDOW_S,
            "s",
            f"the optimum window near {PAPER_WINDOW_S:g} s",
        ),
        taxel_claim(curves.get(Panel.TAXELS, ())),
        metric_claim(fits),
        mismatch_claim(curves.get(Panel.MISMATCH, ())),
    )
    full_scale = 1.0
    if threshold:
        full_scale = float(base_value(cubes[threshold[0]], "readout.full_scale_v"))
    return Report(
        grids=tuple(dict.fromkeys(str(c.attrs.get("grid", "?")) for c in cubes.values())),
        dataset=dataset_kind(cubes),
        curves=curves,
        fits=fits,
        full_scale_v=full_scale,
        claims=claims,
        run_row=row,
        cost_points=points,
        sweep_cost=sweep_cost(cubes, runs),
        time_to_accuracy=time_to_accuracy(curves.get(Panel.OBSERVATION, ())),
        missing=missing,
    )
