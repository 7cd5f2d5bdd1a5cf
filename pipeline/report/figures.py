"""Figures of the report, drawn with matplotlib's object API from a report's numbers.

Every function returns a new :class:`matplotlib.figure.Figure` on its own Agg canvas: no pyplot,
no global state, nothing written (:func:`figure_images` renders one to PNG and SVG in memory).
Error bars are the population standard deviation of accuracy over folds; both models are drawn
on every panel.
"""

from __future__ import annotations

import io
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

from pipeline.report.analysis import Report
from pipeline.report.claims import PAPER_THRESHOLD_V, PAPER_WINDOW_S
from pipeline.report.cost import CostPoint
from pipeline.report.curves import Curve, MetricFit
from pipeline.report.panels import PANEL_TITLES, Panel

PNG_DPI = 150

_COLORS = {"ffnn": "tab:blue", "cnn": "tab:orange"}
_MARKERS = ("o", "s", "^", "D")
_SIZE_IN = (6.4, 4.2)
_PLAIN = FuncFormatter(lambda v, _: f"{v:g}")


def draw_report(report: Report) -> dict[Panel, Figure]:
    """One figure per panel that has data, in report order."""
    draw = {
        Panel.THRESHOLD: lambda: threshold_figure(
            report.curves[Panel.THRESHOLD], report.full_scale_v
        ),
        Panel.WINDOW: lambda: curve_figure(
            Panel.WINDOW, report.curves[Panel.WINDOW], "window length (s)", PAPER_WINDOW_S
        ),
        Panel.TAXELS: lambda: curve_figure(
            Panel.TAXELS,
            report.curves[Panel.TAXELS],
            "taxel count (taxels in the array)",
            None,
            log=False,
        ),
        Panel.SPIKE_METRICS: lambda: metric_figure(report.fits),
        Panel.MISMATCH: lambda: curve_figure(
            Panel.MISMATCH,
            report.curves[Panel.MISMATCH],
            "threshold mismatch sigma_rel (% of threshold)",
            None,
            log=False,
            scale=100.0,
        ),
        Panel.COST: lambda: cost_figure(report.cost_points),
        Panel.OBSERVATION: lambda: curve_figure(
            Panel.OBSERVATION,
            report.curves[Panel.OBSERVATION],
            "observation time: windows x window length (s of touch)",
            None,
        ),
    }
    return {panel: draw[panel]() for panel in report.panels}


def figure_images(figure: Figure) -> tuple[bytes, str]:
    """``figure`` as PNG bytes (:data:`PNG_DPI`) and as an SVG document (text, no date in it)."""
    png, svg = io.BytesIO(), io.BytesIO()
    figure.savefig(png, format="png", dpi=PNG_DPI)
    figure.savefig(svg, format="svg", metadata={"Date": None})
    return png.getvalue(), svg.getvalue().decode("utf-8")


def threshold_figure(curves: Sequence[Curve], full_scale_v: float) -> Figure:
    """Fig. 7a: accuracy against threshold, equivalent bits ``log2(V_fs / theta)`` on top."""
    figure = curve_figure(Panel.THRESHOLD, curves, "readout threshold theta (V)", PAPER_THRESHOLD_V)
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
    panel: Panel,
    curves: Sequence[Curve],
    xlabel: str,
    paper_x: float | None,
    *,
    log: bool = True,
    scale: float = 1.0,
) -> Figure:
    """Accuracy (%, mean +- fold std) against one swept quantity, one line per model and sweep."""
    figure, ax = _new()
    sweeps = list(dict.fromkeys(c.sweep for c in curves))
    for curve in curves:
        marker = _MARKERS[sweeps.index(curve.sweep) % len(_MARKERS)]
        label = curve.model.upper() + (f" ({curve.sweep})" if len(sweeps) > 1 else "")
        ax.errorbar(
            curve.x * scale,
            100 * curve.mean,
            yerr=100 * curve.std,
            marker=marker,
            color=_COLORS.get(curve.model),
            capsize=3,
            label=label,
        )
    if log and all(np.all(c.x > 0) for c in curves):
        # Ticks at the swept values, in plain numbers rather than powers of ten.
        _log_x(ax, FixedLocator(np.unique(np.concatenate([c.x for c in curves])) * scale))
    if paper_x is not None:
        ax.axvline(paper_x * scale, color="grey", linestyle=":", label=f"paper: {paper_x:g}")
    _finish(ax, PANEL_TITLES[panel], xlabel)
    return figure


def metric_figure(fits: Sequence[MetricFit]) -> Figure:
    """Fig. 9: accuracy against SSNR (left) and STE (right) with least-squares lines, r and p."""
    figure = Figure(figsize=(_SIZE_IN[0] * 1.8, _SIZE_IN[1]), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(1, 2, sharey=True)
    labels = {"ssnr_db": "SSNR (dB)", "ste_s2": "STE (s$^2$)"}
    for ax, metric in zip(axes, ("ssnr_db", "ste_s2"), strict=True):
        for fit in (f for f in fits if f.metric == metric):
            color = _COLORS.get(fit.model)
            ax.errorbar(fit.x, 100 * fit.mean, yerr=100 * fit.std, fmt="o", color=color, capsize=3)
            if np.isfinite(fit.slope) and fit.x.size:
                xs = np.linspace(fit.x.min(), fit.x.max(), 50)
                ax.plot(
                    xs,
                    100 * (fit.intercept + fit.slope * xs),
                    color=color,
                    label=f"{fit.model.upper()}: r = {fit.r:+.2f}, p = {fit.p:.2g}, "
                    f"n = {fit.x.size}",
                )
        left_out = max((f.left_out for f in fits if f.metric == metric), default=0)
        note = f" ({left_out} infinite left out)" if left_out else ""
        _finish(ax, f"accuracy against {labels[metric].split()[0]}{note}", labels[metric])
    figure.suptitle(PANEL_TITLES[Panel.SPIKE_METRICS])
    return figure


def cost_figure(points: Sequence[CostPoint]) -> Figure:
    """Accuracy against compute seconds of every distinct point, the Pareto front as a step."""
    figure, ax = _new()
    for model in dict.fromkeys(p.model for p in points):
        mine = [p for p in points if p.model == model]
        ax.errorbar(
            [p.seconds for p in mine],
            [100 * p.mean for p in mine],
            yerr=[100 * p.std for p in mine],
            fmt="o",
            alpha=0.6,
            color=_COLORS.get(model),
            capsize=2,
            label=f"{model.upper()} points",
        )
    front = sorted((p for p in points if p.on_front), key=lambda p: p.seconds)
    if front:
        ax.step(
            [p.seconds for p in front],
            [100 * p.mean for p in front],
            where="post",
            color="black",
            marker="*",
            markersize=10,
            label="Pareto front (cheapest design per accuracy)",
        )
    if points and min(p.seconds for p in points) > 0:
        _log_x(ax, LogLocator(subs=(1.0, 2.0, 5.0)))
    _finish(ax, PANEL_TITLES[Panel.COST], "compute time per point: all stages (s)")
    return figure


def _new() -> tuple[Figure, Axes]:
    figure = Figure(figsize=_SIZE_IN, layout="constrained")
    FigureCanvasAgg(figure)
    return figure, figure.add_subplot()


def _log_x(ax: Axes, ticks: Locator) -> None:
    ax.set_xscale("log")
    ax.xaxis.set_major_locator(ticks)
    ax.xaxis.set_major_formatter(_PLAIN)
    ax.xaxis.set_minor_formatter(NullFormatter())


def _finish(ax: Axes, title: str, xlabel: str) -> None:
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("accuracy (%, mean ± std over folds)")
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small")
