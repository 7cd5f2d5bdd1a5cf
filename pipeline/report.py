"""Report analysis: the numbers behind the paper's Figs. 7-10 and Table I, and what accuracy costs.

Pure functions from result cubes (the layout of :mod:`storage.cubes`) to frozen dataclasses;
:mod:`pipeline.figures` draws them and :mod:`storage.report` writes them. Which figure a cube
feeds is decided by the scene fields its one dimension sweeps (``readout.threshold_v`` for
Fig. 7a, ``coding.window_s`` for 7b, ``array.rows``/``array.cols`` for 8, a ``correlate`` sweep
for 9, ``readout.effects.threshold_mismatch.sigma_rel`` for 10, ``coding.n_windows`` alone for the
observation time), not by its name; a figure with no such cube is "not in this run".

Equations
---------
Accuracy of a point for one model, over its ``K`` folds (population standard deviation, as in
:mod:`pipeline.training`)::

    a = (1/K) sum_k a_k,    s = sqrt((1/K) sum_k (a_k - a)^2)

Equivalent bits ``b = log2(V_fs / theta)``. Along a sweep the optimum is ``x* = argmax a(x)``;
the paper's value ``x_p`` *holds* when ``a(x_p) >= a(x*) - s(x*)``, i.e. it is within one fold
standard deviation of the best (differences smaller than that are fold-to-fold noise).

Taxel gain from ``n1`` to ``n2`` taxels: ``g = a(n2) / a(n1) - 1`` (the paper: +63 % from 1 to 16,
then saturation); the array *rises* when ``a(n2) - a(n1) > s(n2)`` and *saturates* after 16 when
``|a(25) - a(16)| <= s(25)``.

Trend with mismatch: the least-squares line of ``a`` on ``sigma_rel`` over the sweep's points
(:func:`scipy.stats.linregress`), its slope and two-sided p-value. Fig. 9's fitted lines are the
least-squares lines of ``a`` on SSNR (finite values only) and on STE; their ``r`` and ``p`` are the
cube's Pearson ``correlation_r`` and ``correlation_p``.

Compute cost of a point for model ``m``: the seconds of its spike and coding stages plus
``train_m``, as measured when each stage was computed (a stage reused from the cache counts at
its original cost: the price of the design, not of this run). A point lies on the *Pareto front*
when every cheaper point is strictly less accurate: the cheapest design for each accuracy level.

Observation time of a point: ``T = n_windows * window_s`` seconds of touch; the time needed to
reach accuracy ``L`` is the smallest swept ``T`` with ``a(T) >= L`` (grid points, no
interpolation), with ``L`` a fraction of the model's best accuracy along the sweep.

Data rates (Table I): the event readout's rate is the cube's ``data_rate_bps`` (address-event
bits per second) at the best threshold; a frame-based ADC readout of the same array sends
``taxels * bits * rate_hz`` bits per second.
"""

from __future__ import annotations

import enum
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from pipeline.errors import SceneError
from pipeline.grid import Grid, sweep_points

PAPER_THRESHOLD_V = 0.09
PAPER_WINDOW_S = 0.1
PAPER_TAXEL_GAIN = 0.63  # from 1 to 16 taxels
PAPER_TAXELS = (1, 16)
SATURATION_TAXELS = 25
SIGNIFICANCE = 0.05
OBSERVATION_FRACTIONS = (0.8, 0.9, 1.0)
NOT_STATED = "not stated here"


class Panel(enum.StrEnum):
    """One figure of the report; the value is its file stem."""

    THRESHOLD = "fig7a_threshold"
    WINDOW = "fig7b_window"
    TAXELS = "fig8_taxels"
    SPIKE_METRICS = "fig9_ssnr_ste"
    MISMATCH = "fig10_mismatch"
    COST = "cost_pareto"
    OBSERVATION = "observation_time"


PANEL_TITLES = {
    Panel.THRESHOLD: "Fig. 7a: accuracy against the readout threshold",
    Panel.WINDOW: "Fig. 7b: accuracy against the window length",
    Panel.TAXELS: "Fig. 8: accuracy against the taxel count",
    Panel.SPIKE_METRICS: "Fig. 9: accuracy against SSNR and STE",
    Panel.MISMATCH: "Fig. 10: accuracy against threshold mismatch",
    Panel.COST: "Accuracy against compute time (Pareto front)",
    Panel.OBSERVATION: "Accuracy against observation time",
}

# The swept fields (as sets) that make a one-dimensional cube feed a panel.
_PANEL_FIELDS = {
    Panel.THRESHOLD: ({"readout.threshold_v"},),
    Panel.WINDOW: ({"coding.window_s"}, {"coding.window_s", "coding.n_windows"}),
    Panel.TAXELS: ({"array.rows"}, {"array.cols"}, {"array.rows", "array.cols"}),
    Panel.MISMATCH: ({"readout.effects.threshold_mismatch.sigma_rel"},),
    Panel.OBSERVATION: ({"coding.n_windows"},),
}


class Verdict(enum.StrEnum):
    """How this run's cube compares with one of the paper's claims."""

    AGREES = "agrees"
    PARTLY = "agrees only in part"
    DISAGREES = "disagrees"
    UNCLEAR = "can neither confirm nor refute it"
    ABSENT = "not in this run"


@dataclass(frozen=True)
class Curve:
    """Accuracy of one model along one sweep, sorted by ``x``.

    Attributes
    ----------
    sweep, model : str
        Cube name and model (``ffnn``, ``cnn``).
    x : float64 (n,)
        The panel's abscissa (threshold V, window s, taxel count, sigma_rel, touch s).
    mean, std : float64 (n,)
        Accuracy (fraction) mean and population standard deviation over folds.
    """

    sweep: str
    model: str
    x: np.ndarray
    mean: np.ndarray
    std: np.ndarray

    def index(self, x: float) -> int | None:
        """Index of the point at ``x`` (relative tolerance 1e-9), or None if not swept."""
        hits = np.flatnonzero(np.isclose(self.x, x, rtol=1e-9, atol=0.0))
        return int(hits[0]) if hits.size else None

    @property
    def best(self) -> int:
        """Index of the most accurate point (the first one on ties)."""
        return int(np.nanargmax(self.mean))


@dataclass(frozen=True)
class MetricFit:
    """Fig. 9: fold-mean accuracy against one spike metric along a correlate sweep.

    ``x`` float64 (n,) holds the metric (dB or s^2) of the points used (finite), ``mean``/``std``
    their accuracy; ``slope`` (1/unit) and ``intercept`` are the least-squares line; ``r``/``p``
    the cube's Pearson coefficient and two-sided p; ``left_out`` counts non-finite metrics.
    """

    sweep: str
    model: str
    metric: str
    x: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    slope: float
    intercept: float
    r: float
    p: float
    left_out: int


@dataclass(frozen=True)
class Claim:
    """One of the paper's claims beside what this run's cube says about it."""

    panel: Panel
    paper: str
    finding: str
    verdict: Verdict

    @property
    def sentence(self) -> str:
        if self.verdict is Verdict.ABSENT:
            return f"The paper finds {self.paper}; {self.finding}."
        return f"The paper finds {self.paper}; here {self.finding}, so this run {self.verdict}."


@dataclass(frozen=True)
class FrameReadout:
    """A frame-based readout of the same array: one ``bits``-bit ADC sample per taxel per frame."""

    bits: int
    rate_hz: float

    def data_rate_bps(self, n_taxels: int) -> float:
        return float(n_taxels * self.bits * self.rate_hz)


@dataclass(frozen=True)
class RecordingFacts:
    """What Table I needs of the recordings: dataset kind, classes, recordings, sampling rate."""

    dataset: str
    n_classes: int
    n_recordings: int
    fs_hz: float


@dataclass(frozen=True)
class RunRow:
    """Table I for this run: the threshold sweep's best point (numbers, not text).

    The best threshold is the one where the most accurate model peaks; ``accuracy`` holds
    ``(model, mean, std)`` of every model at that threshold. ``frame_data_rate_bps`` is None when
    no frame readout is given; ``n_classes`` None when the recordings could not be read.
    """

    sweep: str
    threshold_v: float
    full_scale_v: float
    equivalent_bits: float
    rows: int
    cols: int
    event_rate_hz: float
    data_rate_bps: float
    frame: FrameReadout | None
    frame_data_rate_bps: float | None
    window_s: float
    n_windows: int | str
    polarity: str
    hidden_units: int
    accuracy: tuple[tuple[str, float, float], ...]
    dataset: str
    n_classes: int | None

    @property
    def n_taxels(self) -> int:
        return self.rows * self.cols


@dataclass(frozen=True)
class TableRow:
    """One row of Table I as text, in the order of :data:`TABLE_COLUMNS`."""

    source: str
    resolution: str
    taxels: str
    event_rate: str
    data_rate: str
    frame_data_rate: str
    preprocessing: str
    classifier: str
    classes: str
    accuracy: str


TABLE_COLUMNS = (
    "source",
    "readout resolution",
    "taxels",
    "event rate",
    "data rate (event readout)",
    "data rate (frame ADC readout)",
    "pre-processing",
    "classifier",
    "classes",
    "accuracy (chance)",
)

# Only what this project's issue and design state of the paper; every other cell says so.
PAPER_ROW = TableRow(
    source="paper (the paper's figures)",
    resolution="3.47 bit (threshold 0.09 V of 1 V)",
    taxels="9 (3 x 3)",
    event_rate=NOT_STATED,
    data_rate=NOT_STATED,
    frame_data_rate=NOT_STATED,
    preprocessing="rate coding, 40 windows x 0.1 s",
    classifier="FFNN (100 hidden ReLU), CNN (2 conv)",
    classes="12 (VibTac-12)",
    accuracy=NOT_STATED,
)


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


# ---------------------------------------------------------------------------------------------
# Reading cubes


def swept_fields(cube: xr.Dataset) -> frozenset[str]:
    """The scene fields a cube sweeps (from its ``axes`` provenance attribute)."""
    return frozenset(json.loads(cube.attrs.get("axes", "{}")))


def is_one_dimensional(cube: xr.Dataset) -> bool:
    return "accuracy" in cube and cube["accuracy"].ndim == 3


def sweeps_for(panel: Panel, cubes: Mapping[str, xr.Dataset]) -> list[str]:
    """Names of the cubes that feed ``panel``, in the mapping's order."""
    if panel is Panel.COST:
        return [name for name, cube in cubes.items() if "seconds" in cube]
    if panel is Panel.SPIKE_METRICS:
        return [name for name, cube in cubes.items() if "correlation_r" in cube]
    wanted = _PANEL_FIELDS[panel]
    return [
        name
        for name, cube in cubes.items()
        if is_one_dimensional(cube) and set(swept_fields(cube)) in wanted
    ]


def field_values(cube: xr.Dataset, field: str) -> np.ndarray:
    """The value of scene ``field`` at every point of a one-dimensional cube, shape (n,).

    A swept field comes from its coordinate; otherwise the sweep's fixed value (``set``) or the
    base scene's value applies to every point.
    """
    dim = cube["accuracy"].dims[0]
    n = cube.sizes[dim]
    for coord in cube.coords.values():
        if coord.attrs.get("field") == field:
            return np.asarray(coord.values)
    fixed = json.loads(cube.attrs.get("fixed", "{}"))
    if field in fixed:
        return np.full(n, fixed[field])
    value: Any = json.loads(cube.attrs["base_scene"])
    for part in field.split("."):
        value = value[part]
    return np.full(n, value, dtype=object if isinstance(value, str) else None)


def base_value(cube: xr.Dataset, field: str) -> Any:
    """Scene ``field`` of the cube's base scene (with the sweep's fixed values applied)."""
    fixed = json.loads(cube.attrs.get("fixed", "{}"))
    if field in fixed:
        return fixed[field]
    value: Any = json.loads(cube.attrs["base_scene"])
    for part in field.split("."):
        value = value[part]
    return value


def panel_x(panel: Panel, cube: xr.Dataset) -> np.ndarray:
    """The abscissa of ``panel`` at every point of a one-dimensional cube, float64 (n,)."""
    if panel is Panel.THRESHOLD:
        return field_values(cube, "readout.threshold_v").astype(np.float64)
    if panel is Panel.WINDOW:
        return field_values(cube, "coding.window_s").astype(np.float64)
    if panel is Panel.TAXELS:
        rows = field_values(cube, "array.rows").astype(np.float64)
        return rows * field_values(cube, "array.cols").astype(np.float64)
    if panel is Panel.MISMATCH:
        return field_values(cube, "readout.effects.threshold_mismatch.sigma_rel").astype(np.float64)
    if panel is Panel.OBSERVATION:
        windows = field_values(cube, "coding.n_windows").astype(np.float64)
        return windows * field_values(cube, "coding.window_s").astype(np.float64)
    raise ValueError(f"panel {panel} has no single abscissa")


def sweep_curves(name: str, cube: xr.Dataset, x: np.ndarray) -> tuple[Curve, ...]:
    """One :class:`Curve` per model a one-dimensional cube trained (models all-NaN are left out)."""
    order = np.argsort(x, kind="stable")
    curves = []
    for model in cube["model"].values:
        folds = cube["accuracy"].sel(model=model).values[order]  # (n, folds)
        if np.isnan(folds).all():
            continue
        curves.append(
            Curve(
                sweep=name,
                model=str(model),
                x=np.asarray(x, dtype=np.float64)[order],
                mean=np.nanmean(folds, axis=1),
                std=np.nanstd(folds, axis=1, ddof=0),
            )
        )
    return tuple(curves)


def point_keys(cube: xr.Dataset) -> list[str]:
    """Result cache keys of a cube's points in C order, from its grid provenance.

    Points shared by two sweeps have one key. Where the grid cannot be rebuilt (a cube from an
    older version), the keys are ``<sweep>/<index>`` and shared points are counted once per sweep.
    """
    name = cube.attrs.get("sweep", "?")
    try:
        grid = Grid.from_dict(json.loads(cube.attrs["grid_description"]))
        sweep = next(s for s in grid.sweeps if s.name == name)
    except (KeyError, ValueError, StopIteration, SceneError):
        n = int(np.prod([cube.sizes[d] for d in cube["seconds"].dims[:-1]]))
        return [f"{name}/{i}" for i in range(n)]
    return [point.key for point in sweep_points(grid.base, sweep)]


# ---------------------------------------------------------------------------------------------
# Claims


def optimum_claim(
    panel: Panel, curves: Sequence[Curve], reference: float, unit: str, paper: str
) -> Claim:
    """Is the paper's optimum ``reference`` within one fold std of each model's best?"""
    if not curves:
        return Claim(panel, paper, f"{PANEL_TITLES[panel]} is not in this run", Verdict.ABSENT)
    parts, holds = [], []
    for curve in curves:
        b = curve.best
        at = f"{curve.model.upper()} is best at {curve.x[b]:g} {unit} ({_pct_pm(curve, b)})"
        ref = curve.index(reference)
        close = int(np.sum(curve.mean >= curve.mean[b] - curve.std[b]))
        if ref is None:
            parts.append(f"{at}, {reference:g} {unit} was not swept")
            continue
        holds.append(bool(curve.mean[ref] >= curve.mean[b] - curve.std[b]))
        within = "within" if holds[-1] else "outside"
        parts.append(
            f"{at} and {reference:g} {unit} ({_pct(curve.mean[ref])}) is {within} one fold "
            f"standard deviation of it, as are {close} of {curve.x.size} points"
        )
    return Claim(panel, paper, "; ".join(parts), _tally(holds))


def taxel_claim(curves: Sequence[Curve]) -> Claim:
    """The paper's +63 % from 1 to 16 taxels and the saturation after it."""
    paper = "accuracy rising by 63 % from 1 to 16 taxels, then saturating"
    usable = [c for c in curves if all(c.index(n) is not None for n in PAPER_TAXELS)]
    if not usable:
        swept = sorted({int(x) for c in curves for x in c.x})
        what = f"only {swept} taxels were swept" if curves else "no taxel sweep is in this run"
        return Claim(Panel.TAXELS, paper, what, Verdict.ABSENT if not curves else Verdict.UNCLEAR)
    parts, rises, saturates = [], [], []
    for curve in usable:
        i1, i16 = (curve.index(n) for n in PAPER_TAXELS)
        gain = curve.mean[i16] / curve.mean[i1] - 1.0
        rises.append(bool(curve.mean[i16] - curve.mean[i1] > curve.std[i16]))
        text = (
            f"{curve.model.upper()} ({curve.sweep}) goes from {_pct(curve.mean[i1])} to "
            f"{_pct_pm(curve, i16)} ({gain:+.0%})"
        )
        i25 = curve.index(SATURATION_TAXELS)
        if i25 is not None:
            saturates.append(bool(abs(curve.mean[i25] - curve.mean[i16]) <= curve.std[i25]))
            text += f" and then {_pct(curve.mean[i25])} at {SATURATION_TAXELS}"
        parts.append(text)
    verdict = _tally([r and s for r, s in zip(rises, saturates, strict=False)] or rises)
    if not any(rises):
        verdict = Verdict.DISAGREES
    return Claim(Panel.TAXELS, paper, "; ".join(parts), verdict)


def metric_claim(fits: Sequence[MetricFit]) -> Claim:
    """SSNR should correlate positively with accuracy and STE negatively (Pearson, p < 0.05)."""
    paper = "SSNR correlating positively and STE negatively with accuracy"
    if not fits:
        return Claim(
            Panel.SPIKE_METRICS, paper, "no correlate sweep is in this run", Verdict.ABSENT
        )
    parts, ok = [], []
    for fit in fits:
        sign = 1.0 if fit.metric == "ssnr_db" else -1.0
        ok.append(bool(sign * fit.r > 0 and fit.p < SIGNIFICANCE))
        parts.append(
            f"{_METRIC_NAMES[fit.metric]} gives r = {fit.r:+.2f} (p = {fit.p:.2g}) for the "
            f"{fit.model.upper()}"
        )
    return Claim(Panel.SPIKE_METRICS, paper, "; ".join(parts), _tally(ok))


def mismatch_claim(curves: Sequence[Curve]) -> Claim:
    """Does accuracy fall with threshold mismatch (least-squares slope < 0, p < 0.05)?"""
    from scipy import stats

    paper = "accuracy falling as threshold mismatch grows"
    if not curves:
        return Claim(Panel.MISMATCH, paper, "no mismatch sweep is in this run", Verdict.ABSENT)
    parts, verdicts = [], []
    for curve in curves:
        if curve.x.size < 3:
            parts.append(f"{curve.model.upper()} has only {curve.x.size} mismatch levels")
            verdicts.append(Verdict.UNCLEAR)
            continue
        fit = stats.linregress(curve.x, curve.mean)
        direction = "falls" if fit.slope < 0 else "rises"
        parts.append(
            f"{curve.model.upper()} accuracy {direction} ({_pct(curve.mean[0])} at "
            f"{curve.x[0]:.0%} to {_pct(curve.mean[-1])} at {curve.x[-1]:.0%}; slope "
            f"{fit.slope * 0.1:+.1%} per 10 % mismatch, p = {fit.pvalue:.2g})"
        )
        if fit.pvalue >= SIGNIFICANCE:
            verdicts.append(Verdict.UNCLEAR)
        else:
            verdicts.append(Verdict.AGREES if fit.slope < 0 else Verdict.DISAGREES)
    if len(set(verdicts)) == 1:
        verdict = verdicts[0]
    elif Verdict.AGREES in verdicts:
        verdict = Verdict.PARTLY
    else:
        verdict = Verdict.DISAGREES if Verdict.DISAGREES in verdicts else Verdict.UNCLEAR
    return Claim(Panel.MISMATCH, paper, "; ".join(parts), verdict)


def metric_fits(name: str, cube: xr.Dataset) -> tuple[MetricFit, ...]:
    """Fig. 9 lines of one correlate cube: every model against SSNR and against STE."""
    from scipy import stats

    fits = []
    for model in cube["model"].values:
        folds = cube["accuracy"].sel(model=model).values.reshape(-1, cube.sizes["fold"])
        if np.isnan(folds).all():
            continue
        mean, std = np.nanmean(folds, axis=1), np.nanstd(folds, axis=1, ddof=0)
        for metric in cube["metric"].values:
            x = cube[str(metric)].values.ravel().astype(np.float64)
            usable = np.isfinite(x) & np.isfinite(mean)
            xs, ys = x[usable], mean[usable]
            slope = intercept = math.nan
            if xs.size >= 2 and np.ptp(xs) > 0:
                line = stats.linregress(xs, ys)
                slope, intercept = float(line.slope), float(line.intercept)
            where = {"model": model, "metric": metric, "coefficient": "pearson"}
            fits.append(
                MetricFit(
                    sweep=name,
                    model=str(model),
                    metric=str(metric),
                    x=xs,
                    mean=ys,
                    std=std[usable],
                    slope=slope,
                    intercept=intercept,
                    r=float(cube["correlation_r"].sel(where)),
                    p=float(cube["correlation_p"].sel(where)),
                    left_out=int(np.sum(~usable)),
                )
            )
    return tuple(fits)


# ---------------------------------------------------------------------------------------------
# Table I


def run_row(
    name: str,
    cube: xr.Dataset,
    facts: RecordingFacts | None,
    frame: FrameReadout | None,
) -> RunRow:
    """Table I for a threshold cube: its best threshold, where the most accurate model peaks."""
    curves = sweep_curves(name, cube, panel_x(Panel.THRESHOLD, cube))
    leader = max(curves, key=lambda c: c.mean[c.best])
    threshold = float(leader.x[leader.best])
    x = panel_x(Panel.THRESHOLD, cube)
    point = cube.isel({cube["accuracy"].dims[0]: int(np.flatnonzero(x == threshold)[0])})
    rows, cols = int(base_value(cube, "array.rows")), int(base_value(cube, "array.cols"))
    return RunRow(
        sweep=name,
        threshold_v=threshold,
        full_scale_v=float(base_value(cube, "readout.full_scale_v")),
        equivalent_bits=float(point["equivalent_bits"]),
        rows=rows,
        cols=cols,
        event_rate_hz=float(point["event_rate_hz"]),
        data_rate_bps=float(point["data_rate_bps"]),
        frame=frame,
        frame_data_rate_bps=None if frame is None else frame.data_rate_bps(rows * cols),
        window_s=float(base_value(cube, "coding.window_s")),
        n_windows=base_value(cube, "coding.n_windows"),
        polarity=str(base_value(cube, "coding.polarity")),
        hidden_units=int(base_value(cube, "training.hidden_units")),
        accuracy=tuple(
            (c.model, float(c.mean[c.index(threshold)]), float(c.std[c.index(threshold)]))
            for c in curves
        ),
        dataset=facts.dataset if facts else str(base_value(cube, "dataset.kind")),
        n_classes=facts.n_classes if facts else None,
    )


def table_row(row: RunRow) -> TableRow:
    """This run's row of Table I as text."""
    chance = f" (chance {1 / row.n_classes:.1%})" if row.n_classes else ""
    frame = NOT_STATED
    if row.frame is not None and row.frame_data_rate_bps is not None:
        frame = (
            f"{_rate(row.frame_data_rate_bps)}it/s ({row.n_taxels} taxels x {row.frame.bits} bit "
            f"x {row.frame.rate_hz:g} Hz)"
        )
        frame += f", {row.frame_data_rate_bps / row.data_rate_bps:.0f}x the event readout"
    return TableRow(
        source=f"this run ({row.dataset} data)",
        resolution=f"{row.equivalent_bits:.2f} bit (best threshold {row.threshold_v:g} V of "
        f"{row.full_scale_v:g} V)",
        taxels=f"{row.n_taxels} ({row.rows} x {row.cols})",
        event_rate=f"{_rate(row.event_rate_hz)}events/s",
        data_rate=f"{_rate(row.data_rate_bps)}it/s (address-event)",
        frame_data_rate=frame,
        preprocessing=f"rate coding, {row.n_windows} windows x {row.window_s:g} s, "
        f"polarity {row.polarity}",
        classifier=", ".join(
            _CLASSIFIERS[m].format(h=row.hidden_units) for m, _, _ in row.accuracy
        ),
        classes=str(row.n_classes) if row.n_classes else "unknown (recordings not readable)",
        accuracy="; ".join(
            f"{m.upper()} {100 * a:.1f} % +- {100 * s:.1f} %" for m, a, s in row.accuracy
        )
        + chance,
    )


# ---------------------------------------------------------------------------------------------
# Cost


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
            label = f"{name}: {dim} = {_label(point[dim].values)}"
            for model in cube["model"].values:
                folds = point["accuracy"].sel(model=model).values
                if np.isnan(folds).all():
                    continue
                entry = found.setdefault(
                    (key, str(model)),
                    {
                        "sweeps": [],
                        "label": label,
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


# ---------------------------------------------------------------------------------------------
# The whole report


def build_report(
    cubes: Mapping[str, xr.Dataset],
    *,
    facts: RecordingFacts | None = None,
    frame: FrameReadout | None = None,
    runs: Sequence[SweepRun] = (),
) -> Report:
    """All the report's numbers and sentences from a run root's cubes.

    Parameters
    ----------
    cubes
        ``{sweep name: cube}`` as :func:`storage.open_results` returns them.
    facts
        The recordings' classes and rate (Table I's classes and chance); None if unreadable.
    frame
        The frame-based ADC readout Table I compares with; None leaves that cell unknown.
    runs
        The run log's sweeps of this root (the sweep's own cost).
    """
    curves: dict[Panel, tuple[Curve, ...]] = {}
    missing: dict[Panel, str] = {}
    for panel in _PANEL_FIELDS:
        names = sweeps_for(panel, cubes)
        found = tuple(c for n in names for c in sweep_curves(n, cubes[n], panel_x(panel, cubes[n])))
        if found:
            curves[panel] = found
        else:
            missing[panel] = _absent(panel)
    fits = tuple(
        f for n in sweeps_for(Panel.SPIKE_METRICS, cubes) for f in metric_fits(n, cubes[n])
    )
    if not fits:
        missing[Panel.SPIKE_METRICS] = _absent(Panel.SPIKE_METRICS)
    points = cost_points(cubes)
    if not points:
        missing[Panel.COST] = "not in this run: no cube holds compute seconds"
    threshold = sweeps_for(Panel.THRESHOLD, cubes)
    row = run_row(threshold[0], cubes[threshold[0]], facts, frame) if threshold else None
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
        dataset=facts.dataset if facts else _dataset_kind(cubes),
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


# ---------------------------------------------------------------------------------------------
# Helpers

_METRIC_NAMES = {"ssnr_db": "SSNR", "ste_s2": "STE"}
_CLASSIFIERS = {"ffnn": "FFNN ({h} hidden ReLU)", "cnn": "CNN (2 conv, 16/32 channels)"}


def _tally(holds: Sequence[bool]) -> Verdict:
    if not holds:
        return Verdict.UNCLEAR
    if all(holds):
        return Verdict.AGREES
    return Verdict.PARTLY if any(holds) else Verdict.DISAGREES


def _absent(panel: Panel) -> str:
    needs = {
        Panel.THRESHOLD: "a sweep of readout.threshold_v",
        Panel.WINDOW: "a sweep of coding.window_s",
        Panel.TAXELS: "a sweep of array.rows / array.cols",
        Panel.SPIKE_METRICS: "a sweep with correlate = true",
        Panel.MISMATCH: "a sweep of readout.effects.threshold_mismatch.sigma_rel",
        Panel.OBSERVATION: "a sweep of coding.n_windows alone",
    }
    return f"not in this run: it needs {needs[panel]}"


def _dataset_kind(cubes: Mapping[str, xr.Dataset]) -> str:
    kinds = {json.loads(c.attrs["base_scene"])["dataset"]["kind"] for c in cubes.values()}
    return ", ".join(sorted(kinds)) or "unknown"


def _model_seconds(row: np.ndarray, stages: list[str], model: str) -> float:
    keep = [not s.startswith("train_") or s == f"train_{model}" for s in stages]
    return float(np.nansum(row[keep]))


def _label(value: Any) -> str:
    return f"{value:g}" if isinstance(value, int | float | np.number) else str(value)


def _pct(value: float) -> str:
    return f"{100 * value:.1f} %"


def _pct_pm(curve: Curve, i: int) -> str:
    return f"{100 * curve.mean[i]:.1f} % +- {100 * curve.std[i]:.1f} %"


def _rate(value: float) -> str:
    for factor, prefix in ((1e6, "M"), (1e3, "k")):
        if abs(value) >= factor:
            return f"{value / factor:.3g} {prefix}"
    return f"{value:.3g} "


def cost_sentence(points: Sequence[CostPoint]) -> str:
    """One sentence on the Pareto front of accuracy against compute time."""
    front = sorted((p for p in points if p.on_front), key=lambda p: p.seconds)
    if not front:
        return "No point has both compute seconds and accuracy."
    cheap, best = front[0], front[-1]
    return (
        f"{len(front)} of {len(points)} (point, model) pairs are on the Pareto front: the "
        f"cheapest design reaches {_pct(cheap.mean)} in {cheap.seconds:.2g} s "
        f"({cheap.model.upper()}, {cheap.label}) and the most accurate {_pct(best.mean)} in "
        f"{best.seconds:.2g} s ({best.model.upper()}, {best.label})."
    )


def observation_sentence(rows: Sequence[TimeToAccuracy]) -> str:
    """One sentence on the touch time each model needs for 90 % of its best accuracy."""
    parts = [
        f"the {r.model.upper()} reaches 90 % of its best ({_pct(r.target / 0.9)}) after "
        + (f"{r.seconds:.3g} s of touch" if r.seconds is not None else "no swept time")
        for r in rows
        if math.isclose(r.fraction, 0.9)
    ]
    return ("Along the observation sweep " + "; ".join(parts) + ".") if parts else ""


def recording_facts(cube: xr.Dataset) -> RecordingFacts:
    """Classes, recordings and sampling rate of the recordings of a cube's base scene.

    Loads the recordings (the built-in data is generated, a folder is read); raises what
    :func:`pipeline.recordings.load_recordings` raises when they are no longer there.
    """
    from pipeline.recordings import load_recordings
    from pipeline.scene import Scene

    scene = Scene.from_dict(json.loads(cube.attrs["base_scene"]))
    recordings = load_recordings(scene.dataset)
    return RecordingFacts(
        dataset=scene.dataset.kind.value,
        n_classes=len(recordings.class_names),
        n_recordings=int(recordings.labels.size),
        fs_hz=float(recordings.fs_hz),
    )
