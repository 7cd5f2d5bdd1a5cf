"""Figures of the report, drawn with matplotlib's object API from a report's numbers.

Every function returns a new :class:`matplotlib.figure.Figure` on its own Agg canvas: no pyplot,
no global state, nothing written (:func:`figure_images` renders one to PNG and SVG in memory).
Error bars are the 95 % interval of accuracy (``accuracy_low``/``accuracy_high``), not the spread
over folds; points without an interval (runs that predate per-recording results) have none.
Every accuracy axis has a dashed line at chance, ``1 / n_classes``, when the class count is known.
Every model is drawn on every panel. Points of several chips
(:mod:`pipeline.report.chip_population`) draw the spread of their chips' accuracies (5th to 95th
percentile) as a shaded band around the curve, apart from the error bars; one line style per
deployment. Panels and series come in their declared order
(:func:`~pipeline.report.panels.declared_rank`): the models as
:class:`~pipeline.design.scene.Model` declares them, the deployments as
:class:`~pipeline.design.scene.Deployment` does, whatever the order of the cubes' names or of a
cube's models.
"""

from __future__ import annotations

import io
import math
import textwrap
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import (
    FixedLocator,
    FuncFormatter,
    Locator,
    LogLocator,
    MaxNLocator,
    NullFormatter,
)

from pipeline.report import paper
from pipeline.report.analysis import Report
from pipeline.report.curves import Curve, MetricFit
from pipeline.report.decision_time import LATENCY_STEM, LATENCY_TITLE, LatencyCurve
from pipeline.report.designs import Cost
from pipeline.report.fronts import Front
from pipeline.report.panels import PANEL_TITLES, THRESHOLD_V, WINDOW_S, Panel, declared_rank
from pipeline.report.sweeps import Heatmap, SweepPlot
from pipeline.report.text import si
from pipeline.results.cube import field_attrs

#: Resolution of the PNG figures (dots per inch).
PNG_DPI = 150
YLABEL = "accuracy (%; bars: 95 % interval)"

_COLORS = {"ffnn": "tab:blue", "cnn": "tab:orange"}
_OTHER_COLORS = ("tab:green", "tab:red", "tab:purple", "tab:brown")
_MARKERS = ("o", "s", "^", "D")
_LINES = ("-", "--", ":", "-.")
_SIZE_IN = (6.4, 4.2)
_PLAIN = FuncFormatter(lambda v, _: f"{v:g}")


def draw_report(report: Report) -> dict[str, Figure]:
    """One figure per stem of :attr:`~pipeline.report.analysis.Report.figure_stems`, in that
    order."""
    chance = report.chance
    curves = report.curves
    draw = {
        Panel.THRESHOLD.value: lambda: threshold_figure(
            curves[Panel.THRESHOLD], report.full_scale_v, chance
        ),
        Panel.WINDOW.value: lambda: curve_figure(
            PANEL_TITLES[Panel.WINDOW],
            curves[Panel.WINDOW],
            f"window length ({WINDOW_S}, {field_attrs(WINDOW_S)['units']})",
            chance,
            paper_x=paper.WINDOW_S,
        ),
        Panel.TAXELS.value: lambda: curve_figure(
            PANEL_TITLES[Panel.TAXELS],
            curves[Panel.TAXELS],
            "taxel count (taxels in the array)",
            chance,
            log=False,
        ),
        Panel.SPIKE_METRICS.value: lambda: metric_figure(report.fits, chance),
        Panel.MISMATCH.value: lambda: (
            grouped_figure if any(c.group for c in curves[Panel.MISMATCH]) else curve_figure
        )(
            PANEL_TITLES[Panel.MISMATCH],
            curves[Panel.MISMATCH],
            "threshold mismatch sigma_rel (% of threshold)",
            chance,
            log=False,
            scale=100.0,
        ),
        Panel.OBSERVATION.value: lambda: curve_figure(
            PANEL_TITLES[Panel.OBSERVATION],
            curves[Panel.OBSERVATION],
            "observation time: windows x window length (s of touch)",
            chance,
        ),
    }
    for plot in report.sweep_plots:
        draw[plot.stem] = lambda plot=plot: sweep_figure(plot, chance)
    for found in report.heatmaps:
        draw[found.stem] = lambda found=found: heatmap_figure(found)
    for front in report.fronts:
        draw[front.cost.stem] = lambda front=front: front_figure(front, chance)
    if report.latency:
        draw[LATENCY_STEM] = lambda: latency_figure(report.latency, chance)
    return {stem: draw[stem]() for stem in report.figure_stems}


def figure_images(figure: Figure) -> tuple[bytes, str]:
    """``figure`` as PNG bytes (:data:`PNG_DPI`) and as an SVG document (text, no date in it).

    The SVG keeps the layout the PNG's rendering computed: a layout engine lays the figure out
    again, in a draw of its own, at every save, the larger part of a save's time."""
    png, svg = io.BytesIO(), io.BytesIO()
    figure.savefig(png, format="png", dpi=PNG_DPI)
    engine = figure.get_layout_engine()
    figure.set_layout_engine("none")
    try:
        figure.savefig(svg, format="svg", metadata={"Date": None})
    finally:
        figure.set_layout_engine(engine)
    return png.getvalue(), svg.getvalue().decode("utf-8")


def threshold_figure(curves: Sequence[Curve], full_scale_v: float, chance: float | None) -> Figure:
    """Fig. 7a: accuracy against threshold, equivalent bits ``log2(V_fs / theta)`` on top."""
    figure = curve_figure(
        PANEL_TITLES[Panel.THRESHOLD],
        curves,
        f"readout threshold theta ({THRESHOLD_V}, {field_attrs(THRESHOLD_V)['units']})",
        chance,
        paper_x=paper.THRESHOLD_V,
    )
    ax = figure.axes[0]
    top = ax.secondary_xaxis(
        "top",
        functions=(
            lambda v: np.log2(full_scale_v / np.clip(v, 1e-12, None)),
            lambda b: full_scale_v / np.exp2(b),
        ),
    )
    top.xaxis.set_major_locator(MaxNLocator(6))
    top.xaxis.set_major_formatter(FuncFormatter(lambda b, _: f"{b:.3g}"))
    top.xaxis.set_minor_formatter(NullFormatter())
    top.set_xlabel(f"equivalent resolution log2({full_scale_v:g} V / theta) (bit)")
    return figure


def curve_figure(
    title: str,
    curves: Sequence[Curve],
    xlabel: str,
    chance: float | None,
    *,
    paper_x: float | None = None,
    log: bool = True,
    scale: float = 1.0,
    ticks: Sequence[str] | None = None,
) -> Figure:
    """Accuracy (%, 95 % interval bars) against one swept quantity, one line per model and sweep.

    ``ticks`` labels the positions 0, 1, ... of a swept field that is not a number.
    """
    figure, ax = _new()
    curves = _declared(curves)
    sweeps = list(dict.fromkeys(c.sweep for c in curves))
    groups = list(dict.fromkeys(c.group for c in curves))
    for curve in curves:
        marker = _MARKERS[(sweeps.index(curve.sweep) + groups.index(curve.group)) % len(_MARKERS)]
        label = curve.label + (f" ({curve.sweep})" if len(sweeps) > 1 else "")
        style = _LINES[groups.index(curve.group) % len(_LINES)]
        _draw_curve(ax, curve, scale, marker=marker, style=style, label=label)
    if ticks is not None:
        ax.set_xticks(range(len(ticks)), list(ticks), rotation=30 if len(ticks) > 4 else 0)
    elif log and all(np.all(c.x > 0) for c in curves):
        # Ticks at the swept values, in plain numbers rather than powers of ten.
        _log_x(ax, FixedLocator(np.unique(np.concatenate([c.x for c in curves])) * scale))
    if paper_x is not None:
        ax.axvline(paper_x * scale, color="grey", linestyle=":", label=f"paper: {paper_x:g}")
    _chance(ax, chance)
    _finish(ax, title, xlabel)
    return figure


def grouped_figure(
    title: str,
    curves: Sequence[Curve],
    xlabel: str,
    chance: float | None,
    *,
    log: bool = False,
    scale: float = 1.0,
) -> Figure:
    """One panel per group of curves (the chips' deployments), side by side on one accuracy
    axis: each model's accuracy with its 95 % interval bars and, for designs of several chips,
    the chips' 5th-95th percentile band. Panels and curves come in their declared order."""
    curves = _declared(curves)
    groups = list(dict.fromkeys(c.group for c in curves))
    figure = Figure(
        figsize=(max(_SIZE_IN[0], 3.6 * len(groups)), _SIZE_IN[1] + 0.4), layout="constrained"
    )
    FigureCanvasAgg(figure)
    axes = np.atleast_1d(figure.subplots(1, len(groups), sharey=True, squeeze=False)[0])
    for ax, group in zip(axes, groups, strict=True):
        mine = [c for c in curves if c.group == group]
        sweeps = list(dict.fromkeys(c.sweep for c in mine))
        for curve in mine:
            marker = _MARKERS[sweeps.index(curve.sweep) % len(_MARKERS)]
            label = curve.model.upper() + (f" ({curve.sweep})" if len(sweeps) > 1 else "")
            _draw_curve(ax, curve, scale, marker=marker, style="-", label=label)
        if log and all(np.all(c.x > 0) for c in mine):
            _log_x(ax, FixedLocator(np.unique(np.concatenate([c.x for c in mine])) * scale))
        _chance(ax, chance)
        _finish(ax, group or "-", xlabel)
        if ax is not axes[0]:
            ax.set_ylabel("")
            if ax.get_legend() is not None:
                ax.get_legend().remove()
    figure.suptitle(_wrap(title, 90))
    return figure


def sweep_figure(plot: SweepPlot, chance: float | None) -> Figure:
    """Accuracy along any one-dimensional sweep (:class:`~pipeline.report.sweeps.SweepPlot`)."""
    return curve_figure(
        plot.title, plot.curves, plot.xlabel, chance, log=plot.log, ticks=plot.ticks
    )


def heatmap_figure(found: Heatmap) -> Figure:
    """Accuracy (%) of a two-dimensional sweep, one annotated panel per model, in the models'
    declared order."""
    order = sorted(range(len(found.models)), key=lambda m: declared_rank("model", found.models[m]))
    n = len(found.models)
    width = max(_SIZE_IN[0], (0.7 * len(found.cols) + 2.5) * n + 1.0)
    figure = Figure(figsize=(width, _SIZE_IN[1] + 0.25 * len(found.rows)), layout="constrained")
    FigureCanvasAgg(figure)
    axes = np.atleast_1d(figure.subplots(1, n, squeeze=False)[0])
    values = 100 * found.accuracy
    finite = values[np.isfinite(values)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 100.0)
    if high - low < 1e-9:
        low, high = low - 0.5, high + 0.5
    image = None
    models = [found.models[m] for m in order]
    for ax, model, grid in zip(axes, models, values[order], strict=True):
        image = ax.imshow(
            np.ma.masked_invalid(grid), cmap="viridis", vmin=low, vmax=high, aspect="auto"
        )
        for (i, j), v in np.ndenumerate(grid):
            text = f"{v:.1f}" if math.isfinite(v) else "-"
            dark = math.isfinite(v) and v < (low + high) / 2
            ax.text(j, i, text, ha="center", va="center", color="white" if dark else "black")
        ax.set_xticks(range(len(found.cols)), list(found.cols))
        ax.set_yticks(range(len(found.rows)), list(found.rows))
        ax.set_xlabel(_wrap(found.col_label, 40))
        ax.set_ylabel(_wrap(found.row_label, 40))
        ax.set_title(model.upper())
    if image is not None:
        figure.colorbar(image, ax=list(axes), label="accuracy (%)")
    figure.suptitle(_wrap(found.title, 90))
    return figure


def metric_figure(fits: Sequence[MetricFit], chance: float | None) -> Figure:
    """Fig. 9: accuracy against SSNR (left) and STE (right) with least-squares lines, r and p."""
    figure = Figure(figsize=(_SIZE_IN[0] * 1.8, _SIZE_IN[1]), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(1, 2, sharey=True)
    labels = {"ssnr_db": "SSNR (dB)", "ste_s2": "STE (s$^2$)"}
    fits = sorted(fits, key=lambda f: declared_rank("model", f.model))
    for ax, metric in zip(axes, ("ssnr_db", "ste_s2"), strict=True):
        for fit in (f for f in fits if f.metric == metric):
            color = _color(fit.model)
            ax.errorbar(
                fit.x,
                100 * fit.mean,
                yerr=_interval_bars(fit.mean, fit.low, fit.high),
                fmt="o",
                color=color,
                capsize=3,
            )
            if np.isfinite(fit.slope) and fit.x.size:
                xs = np.linspace(fit.x.min(), fit.x.max(), 50)
                stated = math.isfinite(fit.r) and math.isfinite(fit.p)
                ax.plot(
                    xs,
                    100 * (fit.intercept + fit.slope * xs),
                    color=color,
                    label=f"{fit.model.upper()}: "
                    + (f"r = {fit.r:+.2f}, p = {fit.p:.2g}, " if stated else "")
                    + f"n = {fit.x.size}",
                )
        left_out = max((f.left_out for f in fits if f.metric == metric), default=0)
        note = f" ({left_out} infinite left out)" if left_out else ""
        _chance(ax, chance)
        _finish(ax, f"accuracy against {labels[metric].split()[0]}{note}", labels[metric])
    figure.suptitle(_wrap(PANEL_TITLES[Panel.SPIKE_METRICS], 90))
    return figure


def front_figure(front: Front, chance: float | None) -> Figure:
    """Accuracy against one cost: every design, each model's front as a step, the designs off
    the front but indistinguishable from it marked, the frame readout as reference lines."""
    figure, ax = _new(width=_SIZE_IN[0] * 1.6)
    for model in sorted(front.models, key=lambda m: declared_rank("model", m)):
        color = _color(model)
        mine = [p for p in front.points if p.model == model]
        plain = [p for p in mine if not p.on_front and not p.indistinguishable]
        if plain:
            ax.errorbar(
                [p.cost for p in plain],
                [100 * p.accuracy.mean for p in plain],
                yerr=_point_bars(plain),
                fmt="o",
                alpha=0.5,
                color=color,
                capsize=2,
                label=f"{model.upper()} designs",
            )
        marked = [p for p in mine if p.indistinguishable]
        if marked:
            ax.errorbar(
                [p.cost for p in marked],
                [100 * p.accuracy.mean for p in marked],
                yerr=_point_bars(marked),
                fmt="D",
                markerfacecolor="none",
                markersize=7,
                color=color,
                capsize=2,
                label=f"{model.upper()} off the front, not significantly less accurate",
            )
        line = front.front(model)
        if line:
            ax.step(
                [p.cost for p in line],
                [100 * p.accuracy.mean for p in line],
                where="post",
                color=color,
                marker="*",
                markersize=11,
                label=f"{model.upper()} front (cheapest design per accuracy)",
            )
    for (label, value), style in zip(
        front.references, ("--", "-.", ":", (0, (5, 5))), strict=False
    ):
        ax.axvline(value, color="black", linestyle=style, linewidth=1, label=label)
    costs = [p.cost for p in front.points] + [v for _, v in front.references]
    if front.cost is not Cost.BITS and costs and min(costs) > 0:
        _log_x(ax, LogLocator(subs=(1.0, 2.0, 5.0)))
        if front.cost is Cost.POWER:
            ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: si(v, "W")))
        if front.cost is Cost.AREA:  # m^2 on the axis, um^2 in its labels
            ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v * 1e12:g}"))
    _chance(ax, chance)
    _finish(ax, f"Accuracy against {front.cost.short}", front.cost.axis, legend_outside=True)
    return figure


def latency_figure(curves: Sequence[LatencyCurve], chance: float | None) -> Figure:
    """Accuracy against decision time, one line per model (its best design) with its 95 %
    interval as a band, and a dotted line at the earliest decision not significantly below the
    full touch."""
    figure, ax = _new()
    for curve in sorted(curves, key=lambda c: declared_rank("model", c.model)):
        color = _color(curve.model)
        many = curve.decision_s.size > 40  # a spiking decoder's steps: a line, no markers
        ax.plot(
            curve.decision_s,
            100 * curve.mean,
            marker=None if many else "o",
            markersize=4,
            color=color,
            label=f"{curve.model.upper()} ({curve.label})",
        )
        ok = np.isfinite(curve.low) & np.isfinite(curve.high)
        if ok.any():
            ax.fill_between(
                curve.decision_s,
                100 * np.where(ok, curve.low, np.nan),
                100 * np.where(ok, curve.high, np.nan),
                color=color,
                alpha=0.2,
                linewidth=0,
            )
        if curve.earliest is not None:
            ax.axvline(curve.earliest.decision_s, color=color, linestyle=":", linewidth=1.5)
    _chance(ax, chance)
    _finish(ax, LATENCY_TITLE, "decision time (s of touch)")
    ax.set_ylabel("accuracy (%; band: 95 % interval)")
    return figure


def _draw_curve(
    ax: Axes, curve: Curve, scale: float, *, marker: str, style: str, label: str
) -> None:
    """One curve: accuracy with its 95 % interval bars and, for designs of several chips, the
    chips' 5th-95th percentile as a band, apart from the bars (the test set's noise)."""
    ax.errorbar(
        curve.x * scale,
        100 * curve.mean,
        yerr=_interval_bars(curve.mean, curve.low, curve.high),
        marker=marker,
        color=_color(curve.model),
        linestyle=style,
        capsize=3,
        label=label,
    )
    if curve.chip_low is not None and curve.chip_high is not None:
        ax.fill_between(
            curve.x * scale,
            100 * curve.chip_low,
            100 * curve.chip_high,
            color=_color(curve.model),
            alpha=0.15,
            linestyle=style,
            label=f"{label}: chips, 5th-95th percentile",
        )


def _declared(curves: Sequence[Curve]) -> list[Curve]:
    """Curves by deployment, then sweep (as met), then model, deployments and models in their
    declared order (:func:`~pipeline.report.panels.declared_rank`), never alphabetically."""
    sweeps = list(dict.fromkeys(c.sweep for c in curves))
    return sorted(
        curves,
        key=lambda c: (
            declared_rank("deployment", c.group),
            sweeps.index(c.sweep),
            declared_rank("model", c.model),
        ),
    )


def _interval_bars(mean: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray | None:
    """Asymmetric error bars (2, n) in percent from a 95 % interval; None when there is none."""
    ok = np.isfinite(low) & np.isfinite(high)
    if not ok.any():
        return None
    below = np.where(ok, np.clip(mean - low, 0.0, None), 0.0)
    above = np.where(ok, np.clip(high - mean, 0.0, None), 0.0)
    return 100 * np.vstack([below, above])


def _point_bars(points) -> np.ndarray | None:
    return _interval_bars(
        np.array([p.accuracy.mean for p in points]),
        np.array([p.accuracy.low for p in points]),
        np.array([p.accuracy.high for p in points]),
    )


def _color(model: str) -> str:
    if model in _COLORS:
        return _COLORS[model]
    return _OTHER_COLORS[sum(map(ord, model)) % len(_OTHER_COLORS)]


def _chance(ax: Axes, chance: float | None) -> None:
    if chance is not None and math.isfinite(chance):
        ax.axhline(
            100 * chance,
            color="dimgrey",
            linestyle="--",
            linewidth=1,
            label=f"chance ({100 * chance:.3g} %)",
        )


def _new(width: float = _SIZE_IN[0]) -> tuple[Figure, Axes]:
    figure = Figure(figsize=(width, _SIZE_IN[1]), layout="constrained")
    FigureCanvasAgg(figure)
    return figure, figure.add_subplot()


def _log_x(ax: Axes, ticks: Locator) -> None:
    ax.set_xscale("log")
    ax.xaxis.set_major_locator(ticks)
    ax.xaxis.set_major_formatter(_PLAIN)
    ax.xaxis.set_minor_formatter(NullFormatter())


def _wrap(text: str, width: int) -> str:
    """Long titles and labels broken into lines (a figure is a few inches wide)."""
    return textwrap.fill(text, width, break_long_words=False, break_on_hyphens=False)


def _finish(ax: Axes, title: str, xlabel: str, *, legend_outside: bool = False) -> None:
    ax.set_title(_wrap(title, 70), fontsize="medium")
    ax.set_xlabel(_wrap(xlabel, 80))
    ax.set_ylabel(YLABEL)
    ax.grid(True, alpha=0.3)
    if not ax.get_legend_handles_labels()[0]:
        return
    if legend_outside:
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0))
    else:
        ax.legend(fontsize="small")
