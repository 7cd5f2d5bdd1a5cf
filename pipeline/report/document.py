"""The report as a document: its blocks in order, and the files of the report folder.

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

from pipeline.report.analysis import Report
from pipeline.report.blocks import Block, Figure, Heading, Paragraph, Table
from pipeline.report.cost import cost_sentence, observation_sentence
from pipeline.report.panels import PANEL_TITLES, Panel
from pipeline.report.render import FIGURES, TITLE, render_html, render_markdown
from pipeline.report.tables import PAPER_ROW, TABLE_COLUMNS, table_row

if TYPE_CHECKING:
    from matplotlib.figure import Figure as MplFigure


def report_files(
    report: Report,
    figures: Mapping[Panel, MplFigure],
    *,
    version: str,
    on_figure: Callable[[], object] | None = None,
) -> dict[str, bytes]:
    """Every file of the report folder, ``{relative POSIX path: content}``.

    Parameters
    ----------
    report, figures
        The report and its figures (:func:`pipeline.report.figures.draw_report`).
    version
        The eskin-sweep version the report names as its writer.
    on_figure
        Called after each figure is rendered to PNG and SVG (the slow part: a progress bar).
    """
    from pipeline.report.figures import figure_images

    files: dict[str, bytes] = {}
    svgs: dict[str, str] = {}
    for panel, figure in figures.items():
        png, svg = figure_images(figure)
        files[f"{FIGURES}/{panel.value}.png"] = png
        files[f"{FIGURES}/{panel.value}.svg"] = svg.encode("utf-8")
        svgs[panel.value] = svg
        if on_figure is not None:
            on_figure()
    blocks = report_blocks(report, set(figures), version=version)
    files["report.md"] = render_markdown(blocks, figure_folder=FIGURES).encode("utf-8")
    files["report.html"] = render_html(blocks, svgs).encode("utf-8")
    return files


def report_blocks(report: Report, drawn: set[Panel], *, version: str) -> list[Block]:
    """The report's text as blocks, figures referenced by stem (only those in ``drawn``)."""
    blocks: list[Block] = [
        Heading(1, TITLE),
        Paragraph(
            f"Grid(s) {', '.join(report.grids)} on {report.dataset} data, written by eskin-sweep "
            f"{version}. Accuracy is the fraction of test recordings classified correctly; error "
            "bars are the standard deviation over cross-validation folds."
        ),
        Heading(2, "Against the paper"),
        *(Paragraph(claim.sentence) for claim in report.claims),
        Heading(2, "Figures"),
    ]
    claims = {claim.panel: claim for claim in report.claims}
    for panel in Panel:
        blocks.append(Heading(3, PANEL_TITLES[panel]))
        if panel in report.missing or panel not in drawn:
            blocks.append(
                Paragraph(f"{PANEL_TITLES[panel]}: {report.missing.get(panel, 'not drawn')}.")
            )
            continue
        blocks.append(Figure(panel.value, PANEL_TITLES[panel]))
        if panel in claims:
            blocks.append(Paragraph(claims[panel].sentence))
        elif panel is Panel.COST:
            blocks.append(Paragraph(cost_sentence(report.cost_points)))
        elif panel is Panel.OBSERVATION:
            blocks.append(Paragraph(observation_sentence(report.time_to_accuracy)))
    blocks += _table_blocks(report)
    blocks += _cost_blocks(report)
    return blocks


def _table_blocks(report: Report) -> Iterator[Block]:
    yield Heading(2, "Table I")
    rows = [tuple(vars(PAPER_ROW).values())]
    if report.run_row is None:
        yield Paragraph("Table I for this run: not in this run: it needs a sweep of the threshold.")
    else:
        rows.insert(0, tuple(vars(table_row(report.run_row)).values()))
    yield Table(TABLE_COLUMNS, tuple(rows))
    notes = (
        "This run's row is the threshold sweep's best point (where the most accurate model "
        "peaks). The event readout's data rate is address-event bits per second at that point"
    )
    frame = report.run_row.frame if report.run_row else None
    if frame is not None:
        notes += (
            f"; the frame-based readout is an assumption for comparison: one {frame.bits}-bit ADC "
            f"sample per taxel at {frame.rate_hz:g} Hz (the recordings' sampling rate unless "
            "given)"
        )
    yield Paragraph(notes + ".")
    yield Paragraph(
        "The paper's row holds only what this project states of the paper (its operating point "
        "and figures); cells marked 'not stated here' are not taken from the paper's table."
    )


def _cost_blocks(report: Report) -> Iterator[Block]:
    yield Heading(2, "What accuracy costs in time")
    if report.time_to_accuracy:
        yield Heading(3, "Observation time needed")
        yield Table(
            ("model", "fraction of best", "accuracy target", "seconds of touch needed"),
            tuple(
                (
                    r.model.upper(),
                    f"{r.fraction:.0%}",
                    f"{100 * r.target:.1f} %",
                    "not reached" if r.seconds is None else f"{r.seconds:.3g}",
                )
                for r in report.time_to_accuracy
            ),
        )
    front = sorted((p for p in report.cost_points if p.on_front), key=lambda p: p.seconds)
    if front:
        yield Heading(3, "Pareto front: the cheapest design for each accuracy level")
        yield Table(
            ("model", "point", "compute (s)", "accuracy"),
            tuple(
                (p.model.upper(), p.label, f"{p.seconds:.3g}", f"{100 * p.mean:.1f} %")
                for p in front
            ),
        )
    cost = report.sweep_cost
    yield Heading(3, "The sweep's own cost")
    yield Paragraph(
        f"{cost.n_points} distinct points took {cost.total_s:.1f} s of stage compute in all (as "
        "measured when each stage was computed, summed over workers)."
    )
    yield Table(
        ("stage", "seconds", "share"),
        tuple(
            (stage, f"{s:.1f}", f"{s / cost.total_s:.0%}" if cost.total_s else "-")
            for stage, s in cost.stage_seconds
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
