"""The report as a document: its blocks in order, and the files of the report folder.

Order: the answer to the designer's question at a glance (per model, one small table of the best
design and the cheapest designs not significantly below it, by data rate and by power, with one
sentence on how sure that is; then the power front figure; then, for sweeps of a real array's
taxels read, accuracy against their number: :mod:`pipeline.report.taxel_count`), then, once and
collapsed in HTML,
the method and every comparison with the best (:mod:`pipeline.report.answer`); the paper's
claims judged by tests (:mod:`pipeline.report.claims`: a table of verdicts, the tests folded
below it), Table I with the paper's rows
(:mod:`pipeline.report.tables`), the figures (the paper's, then a curve for every other 1-D
sweep and a heat map for every 2-D one), the hardware cost fronts (:mod:`pipeline.report.fronts`;
the power front is drawn once, at the top), every search's front
(:func:`pipeline.report.trials.search_fronts`), and what accuracy costs in time (where the cubes
keep decisions, accuracy against decision time, early exit and the energy per decision first:
:mod:`pipeline.report.decision_time`).

Files of a report (``<root>/report`` by default), as :func:`report_files` returns them::

    report.html             one page, every figure inlined as SVG (no external files)
    report.md               the same text; figures linked as figures/<stem>.png
    figures/<stem>.png      150 dpi
    figures/<stem>.svg

Nothing here touches the disk: :func:`storage.report.write_report_folder` writes the files.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING

import numpy as np

from pipeline.report.analysis import Report
from pipeline.report.answer import (
    COMPARISON_COLUMNS,
    comparison_rows,
    glance_header,
    glance_rows,
    how_sure,
    method_sentences,
    yield_sentence,
)
from pipeline.report.blocks import Block, Details, Figure, Heading, Items, Paragraph, Table
from pipeline.report.chip_population import method_sentence as chips_method_sentence
from pipeline.report.claims import CLAIM_TESTS_TITLE, CLAIMS_COLUMNS, claims_table
from pipeline.report.constants_table import constants_blocks
from pipeline.report.cost import ROOT_SENTENCE, observation_sentence
from pipeline.report.decision_time import latency_blocks
from pipeline.report.designs import Cost, area_sentence
from pipeline.report.evidence import ALPHA, RESAMPLES
from pipeline.report.fronts import Front, FrontPoint
from pipeline.report.panels import PANEL_TITLES, Panel
from pipeline.report.recordings_needed import needed_sentence
from pipeline.report.render import FIGURES, TITLE, render_html, render_markdown
from pipeline.report.seeds import REPORT_SEED
from pipeline.report.sweeps import Heatmap, SweepPlot
from pipeline.report.tables import TABLE_COLUMNS, table_notes, table_rows
from pipeline.report.taxel_count import taxel_count_blocks
from pipeline.report.text import (
    NO_INTERVAL_WHY,
    area_text,
    comparison,
    pct,
    pct_interval,
    rate,
    si,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure as MplFigure


def report_files(
    report: Report,
    figures: Mapping[str, MplFigure],
    *,
    version: str,
    on_figure: Callable[[], object] | None = None,
) -> dict[str, bytes]:
    """Every file of the report folder, ``{relative POSIX path: content}``.

    Parameters
    ----------
    report, figures
        The report and its figures by file stem (:func:`pipeline.report.figures.draw_report`).
    version
        The eskin-sweep version the report names as its writer.
    on_figure
        Called after each figure is rendered to PNG and SVG (the slow part: a progress bar).
    """
    from pipeline.report.figures import figure_images

    files: dict[str, bytes] = {}
    svgs: dict[str, str] = {}
    for stem, figure in figures.items():
        png, svg = figure_images(figure)
        files[f"{FIGURES}/{stem}.png"] = png
        files[f"{FIGURES}/{stem}.svg"] = svg.encode("utf-8")
        svgs[str(stem)] = svg
        if on_figure is not None:
            on_figure()
    blocks = report_blocks(report, {str(s) for s in figures}, version=version)
    files["report.md"] = render_markdown(blocks, figure_folder=FIGURES).encode("utf-8")
    files["report.html"] = render_html(blocks, svgs).encode("utf-8")
    return files


def report_blocks(report: Report, drawn: set[str], *, version: str) -> list[Block]:
    """The report's text as blocks, figures referenced by stem (only those in ``drawn``)."""
    blocks: list[Block] = [
        Heading(1, TITLE),
        Paragraph(
            f"Grid(s) {', '.join(report.grids)} on {report.dataset} data, written by eskin-sweep "
            f"{version}."
        ),
    ]
    if report.untested:
        blocks.append(
            Paragraph(
                f"{report.untested} of {len(report.designs)} designs have {NO_INTERVAL_WHY}. "
                "They are shown, but no paired test can be made with them."
            )
        )
    blocks += _answer_blocks(report, drawn)
    blocks += [
        Heading(2, "Against the paper"),
        Table(CLAIMS_COLUMNS, claims_table(report.claims)),
        Details(CLAIM_TESTS_TITLE, tuple(Paragraph(c.sentence) for c in report.claims)),
    ]
    blocks += _table_blocks(report)
    blocks += _figure_blocks(report, drawn)
    blocks += _front_blocks(report, drawn)
    blocks += _search_blocks(report)
    blocks += _time_blocks(report, drawn)
    blocks += constants_blocks(report.constants)
    return blocks


def _accuracy_words(report: Report) -> str:
    methods = ", ".join(report.interval_methods) or "none in this run"
    chance = (
        f"Chance is 1/{report.n_classes} = {pct(1 / report.n_classes)} (dashed line)."
        if report.n_classes
        else "The class count, and so chance, is not stated in the cubes."
    )
    return (
        "Accuracy is the fraction of (recording, repeat) pairs classified correctly out of fold; "
        f"error bars and [brackets] are its 95 % interval ({methods}), not the spread over "
        f"folds, which appears only as a secondary number. {chance} Designs are compared by "
        "paired tests on the same recordings (exact McNemar for one repeat, a stratified "
        f"bootstrap otherwise; alpha {ALPHA:g}); differences are in percentage points with their "
        f"95 % interval (paired stratified bootstrap, {RESAMPLES} resamples, generators seeded "
        f"from the fixed seed {REPORT_SEED} and the compared result keys, so the report is "
        "deterministic). The p-value decides significance; near the 5 % boundary the bootstrap "
        "interval and the exact test can disagree (an interval just excluding 0 with p just "
        "above 0.05), being two methods."
    )


ANSWER_TITLE = "The answer: the cheapest design as accurate as the best"
METHOD_TITLE = "How the answer was found, and every comparison with the best"


def _answer_blocks(report: Report, drawn: set[str]) -> Iterator[Block]:
    yield Heading(2, ANSWER_TITLE)
    if not report.answers:
        yield Paragraph("No design of this run has an accuracy: there is nothing to choose from.")
        return
    by_yield = {y.model: y for y in report.yield_answers}
    needed = {n.model: n for n in report.recordings_needed}
    for answer in report.answers:
        yield Table(glance_header(answer), glance_rows(answer))
        yield Paragraph(how_sure(answer))
        if answer.model in needed:
            yield Paragraph(needed_sentence(needed[answer.model]))
        if answer.model in by_yield:
            yield Paragraph(yield_sentence(by_yield[answer.model]))
    if Cost.POWER.stem in drawn and any(f.cost is Cost.POWER for f in report.fronts):
        yield Figure(Cost.POWER.stem, _power_caption(report))
    yield from taxel_count_blocks(report.taxel_counts, report.sweep_plots)
    yield Details(
        METHOD_TITLE,
        (
            Paragraph(_accuracy_words(report)),
            *(
                Paragraph(s)
                for s in method_sentences(len(report.designs), report.frame, report.energy)
            ),
            *((Paragraph(chips_method_sentence()),) if report.yield_answers else ()),
            Items(report.energy.assumptions()),
            Table(COMPARISON_COLUMNS, tuple(r for a in report.answers for r in comparison_rows(a))),
        ),
    )


def _power_caption(report: Report) -> str:
    return _caption(
        "Accuracy against estimated readout power (static bias calibrated on the chip of Alea "
        "et al., IEEE TBioCAS 2024; stars: the front, the cheapest design per accuracy)",
        report,
    )


def _table_blocks(report: Report) -> Iterator[Block]:
    yield Heading(2, "Table I")
    yield Table(TABLE_COLUMNS, table_rows(report.run_rows))
    for note in table_notes(report.run_rows):
        yield Paragraph(note)


def _caption(title: str, report: Report) -> str:
    bars = (
        "error bars: 95 % interval of accuracy, not the fold spread"
        if report.interval_methods
        else f"no error bars: {NO_INTERVAL_WHY}"
    )
    chance = "; dashed line: chance" if report.n_classes else ""
    return f"{title}. {bars[0].upper()}{bars[1:]}{chance}."


def _figure_blocks(report: Report, drawn: set[str]) -> Iterator[Block]:
    yield Heading(2, "Figures")
    claims: dict[Panel, list[str]] = {}
    for claim in report.claims:
        claims.setdefault(claim.panel, []).append(claim.sentence)
    for panel in Panel:
        yield Heading(3, PANEL_TITLES[panel])
        if panel in report.missing or panel.value not in drawn:
            yield Paragraph(f"{PANEL_TITLES[panel]}: {report.missing.get(panel, 'not drawn')}.")
            continue
        yield Figure(panel.value, _caption(PANEL_TITLES[panel], report))
        for sentence in claims.get(panel, ()):
            yield Paragraph(sentence)
        if panel is Panel.MISMATCH and report.mismatch_note:
            yield Paragraph(report.mismatch_note)
        if panel is Panel.OBSERVATION:
            yield Paragraph(observation_sentence(report.time_to_accuracy))
    for plot in report.sweep_plots:
        yield Heading(3, plot.title)
        if plot.stem in drawn:
            yield Figure(plot.stem, _caption(plot.title, report))
        yield Paragraph(_plot_sentence(plot))
    for found in report.heatmaps:
        yield Heading(3, found.title)
        if found.stem in drawn:
            yield Figure(found.stem, f"{found.title} (accuracy in %, per model).")
        yield Paragraph(_heatmap_sentence(found))
    for note in report.undrawn:
        yield Paragraph(note)


def _plot_sentence(plot: SweepPlot) -> str:
    parts = []
    for curve in plot.curves:
        b = curve.best
        at = plot.ticks[int(curve.x[b])] if plot.ticks else f"{curve.x[b]:g}"
        parts.append(
            f"the {curve.model.upper()} is most accurate at {at} "
            f"({pct_interval(curve.mean[b], curve.low[b], curve.high[b])})"
        )
    return f"Along {plot.xlabel}: " + "; ".join(parts) + "."


def _heatmap_sentence(found: Heatmap) -> str:
    parts = []
    for model, grid in zip(found.models, found.accuracy, strict=True):
        i, j = divmod(int(np.nanargmax(grid)), grid.shape[1])
        parts.append(
            f"the {model.upper()} is most accurate at {found.rows[i]}, {found.cols[j]} "
            f"({pct(float(grid[i, j]))})"
        )
    return (
        f"Rows: {found.row_label}; columns: {found.col_label}. " + "; ".join(parts) + ". Its "
        "designs are compared with every other design of the run in the answer and the fronts."
    )


_FRONT_COLUMNS = (
    "model",
    "design",
    "cost",
    "accuracy [95 % interval]",
    "on the front?",
)


def _front_blocks(report: Report, drawn: set[str]) -> Iterator[Block]:
    yield Heading(2, "Hardware cost fronts")
    if not report.fronts:
        yield Paragraph("No design states both a cost and an accuracy.")
        return
    yield Paragraph(
        "For each cost and model, a design is on the front when every cheaper or equally cheap "
        "design is less accurate: the cheapest design for each accuracy level. A design off the "
        "front is compared with the front design that dominates it (the most accurate front "
        f"design that costs no more) by one paired test (alpha {ALPHA:g}, not corrected): where "
        "the difference is not significant it is marked (hollow diamond) and listed, since it "
        "is as accurate as far as this run can tell. The frame-based readout of each array "
        "size is a reference line on the data-rate and power fronts. Readout power rests on the "
        "energy model stated with the answer's method above."
    )
    for front in report.fronts:
        title = f"Accuracy against {front.cost.short}"
        yield Heading(3, title)
        if front.cost is Cost.POWER and front.cost.stem in drawn:
            yield Paragraph("The figure is at the top of the report, with the answer.")
        elif front.cost.stem in drawn:
            yield Figure(front.cost.stem, _caption(title, report))
        if front.cost is Cost.COMPUTE:
            yield Paragraph(
                "Compute time of a design: the work seconds of its own stages (spike train, "
                "coding, training of the model), as measured when each ran (the cubes' "
                "`work_seconds`): a spike train that several designs share counts in each, and "
                "the work a worker shares among its points (loading the recordings, fitting the "
                "front end, loading or compiling kernels) in none. What the sweep paid is below, "
                "under the sweep's own cost."
            )
        if front.cost is Cost.AREA:
            yield Paragraph(area_sentence(report.constants))
        rows = [_front_row(front, p) for m in front.models for p in front.front(m)]
        rows += [_front_row(front, p) for p in front.marked]
        yield Table(_FRONT_COLUMNS, tuple(rows))
        if front.references:
            yield Paragraph(
                "Frame-based readout of the same arrays: "
                + "; ".join(
                    f"{label}: {_cost_text(front.cost, v)}" for label, v in front.references
                )
                + "."
            )


def _front_row(front: Front, point: FrontPoint) -> tuple[str, ...]:
    if point.on_front:
        status = "on the front"
    else:
        status = (
            "off the front, not significantly less accurate than the front design "
            f"({comparison(point.versus_front)})"  # type: ignore[arg-type]
        )
    a = point.accuracy
    cost_text = _cost_text(front.cost, point.cost)
    if front.cost is Cost.AREA:
        cost_text += f" ({_cost_text(Cost.AREA, point.design.taxel_area_m2)} per taxel)"
    return (
        point.model.upper(),
        point.design.label,
        cost_text,
        pct_interval(a.mean, a.low, a.high),
        status,
    )


def _cost_text(which: Cost, value: float) -> str:
    match which:
        case Cost.DATA_RATE:
            return rate(value, "bit/s")
        case Cost.EVENT_RATE:
            return rate(value, "events/s")
        case Cost.BITS:
            return f"{value:.3g} bit"
        case Cost.COMPUTE:
            return f"{value:.3g} s"
        case Cost.AREA:
            return area_text(value)
    return si(value, "W")


def _search_blocks(report: Report) -> Iterator[Block]:
    if not report.searches:
        return
    yield Heading(2, "Searches")
    yield Paragraph(
        "The front of each search of this run (eskin optimize): its trials no other trial "
        "dominates in every objective and, beside them, those a paired test cannot tell from "
        "the front trial dominating them."
    )
    for search in report.searches:
        yield Heading(3, f"Search {search.name}")
        told = "" if search.n_trials is None else f"{search.n_trials} trials told; "
        on = sum(on_front for _, on_front, _ in search.rows)
        yield Paragraph(
            f"{told}{on} on the front, {len(search.rows) - on} beside it "
            f"(cubes {search.name}.trials and {search.name}.front)."
        )
        yield Table(
            ("trial", "on the front?", *search.objectives),
            tuple(
                (
                    str(trial),
                    "yes" if on_front else "no, not significantly worse",
                    *(f"{v:.4g}" for v in values),
                )
                for trial, on_front, values in search.rows
            ),
        )


def _time_blocks(report: Report, drawn: set[str]) -> Iterator[Block]:
    yield Heading(2, "What accuracy costs in time")
    yield from latency_blocks(report.latency, report.decoder, drawn)
    if report.time_to_accuracy:
        yield Heading(3, "Observation time needed")
        yield Table(
            ("model", "fraction of best", "accuracy target", "seconds of touch needed"),
            tuple(
                (
                    r.model.upper(),
                    f"{r.fraction:.0%}",
                    pct(r.target),
                    "not reached" if r.seconds is None else f"{r.seconds:.3g}",
                )
                for r in report.time_to_accuracy
            ),
        )
    cost = report.sweep_cost
    yield Heading(3, "The sweep's own cost")
    older = (
        f" {cost.n_unpaid} of them were computed before paid seconds were kept: their stages "
        "count as measured at each point, so their shared load and front-end fit count at "
        "every one of them."
        if cost.n_unpaid
        else ""
    )
    yield Paragraph(
        f"{cost.n_points} distinct points took {cost.total_s:.1f} s of stage compute in all, "
        f"{cost.shared_s:.1f} s of it shared: the seconds the workers paid, summed over workers, "
        "each counted once. Shared work (loading the recordings, fitting the front end, loading "
        "or compiling the kernels) is paid by the first point of a worker that needs it and "
        "reused by the others; a spike train that several points share is paid by one of them."
        + older
        + f" {ROOT_SENTENCE}"
    )
    yield Table(
        ("stage", "own (s)", "shared (s)", "share"),
        tuple(
            (
                s.stage,
                f"{s.own_s:.1f}",
                f"{s.shared_s:.1f}",
                f"{s.total_s / cost.total_s:.0%}" if cost.total_s else "-",
            )
            for s in cost.stages
        ),
    )
    if cost.runs:
        yield Table(
            ("finished (UTC)", "grid", "points", "cache hits", "computed", "wall time (s)"),
            tuple(
                (
                    r.finished,
                    r.grid,
                    str(r.points),
                    str(r.cache_hits),
                    str(r.computed),
                    f"{r.seconds:.1f}",
                )
                for r in cost.runs
            ),
        )
    else:
        yield Paragraph("Sweep runs and cache hits: no run log in this root (not in this run).")
