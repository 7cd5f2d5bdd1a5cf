"""The whole report's numbers and sentences from a run root's cubes
(:func:`~pipeline.report.analysis.build_report`)."""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import xarray as xr

from pipeline.errors import EskinError
from pipeline.report import paper
from pipeline.report.answer import ModelAnswer, YieldAnswer, design_answers, yield_answers
from pipeline.report.chip_population import chip_curves, fill_groups, pooled
from pipeline.report.claims import (
    Claim,
    deployment_note,
    metric_claim,
    mismatch_claim,
    optimum_claim,
    sides_claim,
    taxel_gain_claim,
    taxel_saturation_claim,
)
from pipeline.report.cost import SweepCost, SweepRun, TimeToAccuracy, sweep_cost, time_to_accuracy
from pipeline.report.cubes import (
    base_value,
    dataset_kind,
    n_classes,
    panel_x,
    sweep_dims,
    sweeps_for,
)
from pipeline.report.curves import Curve, MetricFit, metric_fits
from pipeline.report.decision_time import (
    LATENCY_STEM,
    LatencyCurve,
    earliest_decisions,
    full_touch_energies,
    gather_decisions,
    latency_curves,
)
from pipeline.report.designs import Design, FrameReadout, gather_designs
from pipeline.report.evidence import Evidence, gather_evidence
from pipeline.report.fronts import Front, hardware_fronts
from pipeline.report.panels import FULL_SCALE_V, PANEL_FIELDS, Panel, absent
from pipeline.report.paper import TableRow
from pipeline.report.recordings_needed import RecordingsNeeded, recordings_needed
from pipeline.report.sweeps import Heatmap, SweepPlot, heatmap, sweep_plot
from pipeline.report.tables import run_rows
from pipeline.report.taxel_count import TaxelCount, taxel_counts
from pipeline.report.trials import SearchFront, search_fronts
from pipeline.results.decoder_energy import DecoderEnergyModel
from pipeline.results.hardware_constants import Constants
from pipeline.results.readout_constants import EnergyModel
from pipeline.results.variables import ACCURACY_LOW, ACCURACY_MEAN, RESULT_KEY


@dataclass(frozen=True)
class Report:
    """Everything the report shows, as numbers and sentences.

    ``curves`` and ``fits`` hold the paper's figures' data by panel; ``missing`` says, for every
    panel without data, why it is "not in this run". ``sweep_plots`` and ``heatmaps`` picture the
    other sweeps; ``undrawn`` says which cubes get no picture and why. ``designs`` are the run's
    distinct points; ``untested`` counts those without per-recording results (no interval, no
    paired test). ``searches`` are the run's searches, each by its front. ``latency`` holds,
    per model, accuracy against decision time at its best design and what a decision costs
    (empty for cubes that keep no decisions); ``decoder`` prices the decoder's operations.
    ``mismatch_note`` sets
    Fig. 10's deployments side by side over chips, ``yield_answers`` answer by yield
    (:func:`~pipeline.report.answer.yield_answers`); both only for runs of several chips per
    design. ``recordings_needed`` says, per model, how many recordings per class would tell the
    answer's designs from the best (:mod:`pipeline.report.recordings_needed`). ``taxel_counts``
    holds accuracy against the real taxels read, per model, of every sweep of ``array.taxels``
    (:mod:`pipeline.report.taxel_count`).
    """

    grids: tuple[str, ...]
    dataset: str
    n_classes: int | None
    interval_methods: tuple[str, ...]
    designs: tuple[Design, ...]
    untested: int
    curves: Mapping[Panel, tuple[Curve, ...]]
    fits: tuple[MetricFit, ...]
    full_scale_v: float
    claims: tuple[Claim, ...]
    answers: tuple[ModelAnswer, ...]
    frame: FrameReadout | None
    energy: EnergyModel
    run_rows: tuple[TableRow, ...]
    fronts: tuple[Front, ...]
    sweep_plots: tuple[SweepPlot, ...]
    heatmaps: tuple[Heatmap, ...]
    undrawn: tuple[str, ...]
    sweep_cost: SweepCost
    time_to_accuracy: tuple[TimeToAccuracy, ...]
    missing: Mapping[Panel, str]
    searches: tuple[SearchFront, ...] = ()
    latency: tuple[LatencyCurve, ...] = ()
    decoder: DecoderEnergyModel = field(default_factory=DecoderEnergyModel)
    mismatch_note: str | None = None
    yield_answers: tuple[YieldAnswer, ...] = ()
    constants: Constants = field(default_factory=Constants)
    recordings_needed: tuple[RecordingsNeeded, ...] = ()
    taxel_counts: tuple[TaxelCount, ...] = ()

    @property
    def panels(self) -> tuple[Panel, ...]:
        """The paper's panels with data, in report order."""
        return tuple(p for p in Panel if p not in self.missing)

    @property
    def figure_stems(self) -> tuple[str, ...]:
        """File stems of every figure the report has data for, in report order."""
        return (
            *(p.value for p in self.panels),
            *(s.stem for s in self.sweep_plots),
            *(h.stem for h in self.heatmaps),
            *(f.cost.stem for f in self.fronts),
            *((LATENCY_STEM,) if self.latency else ()),
        )

    @property
    def chance(self) -> float | None:
        """Accuracy of guessing, ``1 / n_classes`` (None when the class count is unknown)."""
        return 1.0 / self.n_classes if self.n_classes else None


def build_report(
    cubes: Mapping[str, xr.Dataset],
    *,
    frame: FrameReadout | None = None,
    energy: EnergyModel | None = None,
    runs: Sequence[SweepRun] = (),
    decoder: DecoderEnergyModel | None = None,
    constants: Constants | None = None,
) -> Report:
    """All the report's numbers and sentences from a run root's cubes.

    Parameters
    ----------
    cubes
        ``{sweep name: cube}`` as :func:`~storage.store.open_results` returns them.
    frame
        The frame-based ADC readout the answer, Table I and the fronts compare with; None leaves
        that comparison unknown.
    energy
        Constants of the readout power estimate (default: ``constants.energy_model()``).
    runs
        The run log's sweeps of this root (the sweep's own cost).
    decoder
        Per-operation energies of the decoder (default: ``constants.decoder_model()``).
    constants
        The hardware constants (:class:`~pipeline.results.hardware_constants.Constants`: the
        declared ones, with a designer's overrides), which size the matched area and, unless
        ``energy`` or ``decoder`` is given, price the readout and the decoder; the report lists
        them. Default: every constant as declared.

    Raises
    ------
    EskinError
        A cube was written by a version whose cubes did not describe themselves or hold no
        ``accuracy_mean``.
    """
    older = [
        name
        for name, cube in cubes.items()
        if RESULT_KEY not in cube.coords or ACCURACY_MEAN not in cube
    ]
    if older:
        raise EskinError(
            f"cube(s) {', '.join(older)} were written by an older eskin-sweep and do not "
            "describe themselves: run 'eskin sweep' on this root again to rebuild them (points "
            "already in the store are not recomputed)"
        )
    constants = constants if constants is not None else Constants()
    energy = energy if energy is not None else constants.energy_model()
    # Points of several chips as one design each (mean over chips), the chips kept beside.
    cubes = {name: pooled(cube) for name, cube in cubes.items()}
    evidence = gather_evidence(cubes)
    designs = gather_designs(cubes, constants.a_vt_v_m)
    curves: dict[Panel, tuple[Curve, ...]] = {}
    missing: dict[Panel, str] = {}
    for panel in PANEL_FIELDS:
        names = sweeps_for(panel, cubes)
        found = fill_groups(
            [c for n in names for c in chip_curves(n, cubes[n], functools.partial(panel_x, panel))]
        )
        if found:
            curves[panel] = found
        else:
            missing[panel] = absent(panel)
    fits = tuple(
        f for n in sweeps_for(Panel.SPIKE_METRICS, cubes) for f in metric_fits(n, cubes[n])
    )
    if not fits:
        missing[Panel.SPIKE_METRICS] = absent(Panel.SPIKE_METRICS)
    plots, maps, undrawn = _other_pictures(cubes)
    threshold = sweeps_for(Panel.THRESHOLD, cubes)
    full_scale = 1.0
    if threshold:
        full_scale = float(base_value(cubes[threshold[0]], FULL_SCALE_V))
    decoder = decoder if decoder is not None else constants.decoder_model()
    decisions = gather_decisions(cubes)
    earliest = earliest_decisions(decisions)
    decides_after = {found: e.decision_s for found, e in earliest.items()}
    answers = design_answers(
        designs, evidence, energy, frame, full_touch_energies(decisions, decoder), decides_after
    )
    dataset = dataset_kind(cubes)
    classes = n_classes(cubes)
    cost = sweep_cost(cubes, runs)
    return Report(
        grids=tuple(dict.fromkeys(str(c.attrs.get("grid", "?")) for c in cubes.values())),
        dataset=dataset,
        n_classes=classes,
        interval_methods=_interval_methods(cubes),
        designs=designs,
        untested=sum(1 for d in designs if not any(evidence.has(d.key, m) for m in d.accuracy)),
        curves=curves,
        fits=fits,
        full_scale_v=full_scale,
        claims=_claims(curves, fits, evidence),
        answers=answers,
        frame=frame,
        energy=energy,
        run_rows=run_rows(answers, dataset, classes),
        fronts=hardware_fronts(designs, evidence, energy, frame),
        sweep_plots=plots,
        heatmaps=maps,
        undrawn=undrawn,
        sweep_cost=cost,
        time_to_accuracy=time_to_accuracy(curves.get(Panel.OBSERVATION, ())),
        missing=missing,
        searches=search_fronts(cubes),
        latency=latency_curves(decisions, answers, decoder, earliest),
        decoder=decoder,
        mismatch_note=deployment_note(curves.get(Panel.MISMATCH, ()), evidence),
        yield_answers=yield_answers(designs, evidence, energy),
        constants=constants,
        recordings_needed=recordings_needed(answers, evidence, classes, dataset, cost),
        taxel_counts=taxel_counts(cubes, evidence),
    )


def _claims(
    curves: Mapping[Panel, tuple[Curve, ...]], fits: Sequence[MetricFit], evidence: Evidence
) -> tuple[Claim, ...]:
    threshold = curves.get(Panel.THRESHOLD, ())
    window = curves.get(Panel.WINDOW, ())
    taxels = curves.get(Panel.TAXELS, ())
    return (
        optimum_claim(Panel.THRESHOLD, threshold, evidence, paper.THRESHOLD_V, "V", "threshold"),
        sides_claim(Panel.THRESHOLD, threshold, evidence, ("lower",), "V", "threshold_lower"),
        optimum_claim(Panel.WINDOW, window, evidence, paper.WINDOW_S, "s", "window"),
        sides_claim(Panel.WINDOW, window, evidence, ("lower", "higher"), "s", "window_sides"),
        taxel_gain_claim(taxels, evidence),
        taxel_saturation_claim(taxels, evidence),
        metric_claim(fits),
        mismatch_claim(curves.get(Panel.MISMATCH, ()), evidence),
    )


def _other_pictures(
    cubes: Mapping[str, xr.Dataset],
) -> tuple[tuple[SweepPlot, ...], tuple[Heatmap, ...], tuple[str, ...]]:
    """A curve for every 1-D cube no paper panel plots against its axis, a heat map per 2-D
    cube, and why any other cube has no picture."""
    plotted = {n for panel in PANEL_FIELDS for n in sweeps_for(panel, cubes)}
    plots, maps, undrawn = [], [], []
    for name, cube in cubes.items():
        dims = sweep_dims(cube)
        if len(dims) == 2 and name in plotted:
            continue  # a panel's field by deployment: the panel draws a curve per deployment
        if len(dims) == 1 and name not in plotted:
            if (plot := sweep_plot(name, cube)) is not None:
                plots.append(plot)
        elif len(dims) == 2:
            if (found := heatmap(name, cube)) is not None:
                maps.append(found)
        elif len(dims) > 2:
            undrawn.append(
                f"Sweep {name} has {len(dims)} dimensions ({', '.join(dims)}): no picture; its "
                "designs are in the answer and the fronts, and its cube holds every number."
            )
    return tuple(plots), tuple(maps), tuple(undrawn)


def _interval_methods(cubes: Mapping[str, xr.Dataset]) -> tuple[str, ...]:
    methods = {
        part.strip()
        for cube in cubes.values()
        for part in str(cube[ACCURACY_LOW].attrs.get("interval", "none")).split(";")
    }
    return tuple(sorted(methods - {"none", ""}))
