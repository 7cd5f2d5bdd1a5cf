"""Writing a report: figures (PNG and SVG), ``report.md`` and one self-contained ``report.html``.

Layout of the output folder (``<root>/report`` by default)::

    report.html             one page, every figure inlined as SVG (no external files)
    report.md               the same text; figures linked as figures/<stem>.png
    figures/<stem>.png      150 dpi
    figures/<stem>.svg
    .eskin-report           marker: this folder is a report and may be replaced

The report is built in full under a temporary name beside the target and then swapped in (one
``renameat2(RENAME_EXCHANGE)`` where Linux offers it), so the target is always a whole report, old
or new, never half of one. A target that exists and is neither empty nor a report (no marker) is
refused: a user's own folder is never replaced.
"""

from __future__ import annotations

import html
import shutil
import uuid
from collections.abc import Iterator, Sequence
from importlib import metadata
from pathlib import Path

from matplotlib.figure import Figure

from pipeline.report import (
    PANEL_TITLES,
    PAPER_ROW,
    TABLE_COLUMNS,
    Panel,
    Report,
    cost_sentence,
    observation_sentence,
    table_row,
)
from storage.store import StoreError, _replace_dir

MARKER = ".eskin-report"
FIGURES = "figures"
PNG_DPI = 150

# A document is a list of blocks: ("h", level, text), ("p", text), ("table", header, rows),
# ("figure", stem, caption); Markdown and HTML render the same blocks.
Block = tuple


def write_report(
    out: str | Path, report: Report, figures: dict[Panel, Figure], *, show_progress: bool = False
) -> Path:
    """Write the report folder ``out`` atomically and return the path of its ``report.html``.

    Raises
    ------
    StoreError
        ``out`` is a file, or a non-empty folder that is not a report; or it cannot be written.
    """
    from tqdm import tqdm

    out = Path(out)
    _check_target(out)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.parent / f".{out.name}-partial-{uuid.uuid4().hex}"
        partial.mkdir()
    except OSError as error:
        raise StoreError(f"cannot write the report to {out}: {error}") from error
    try:
        (partial / FIGURES).mkdir()
        svgs = {}
        with tqdm(
            total=len(figures),
            unit="figure",
            desc="report",
            disable=None if show_progress else True,
        ) as bar:
            for panel, figure in figures.items():
                figure.savefig(partial / FIGURES / f"{panel.value}.png", dpi=PNG_DPI)
                svg = partial / FIGURES / f"{panel.value}.svg"
                figure.savefig(svg, metadata={"Date": None})
                svgs[panel.value] = svg.read_text(encoding="utf-8")
                bar.update(1)
        blocks = report_blocks(report, set(figures))
        (partial / "report.md").write_text(render_markdown(blocks), encoding="utf-8")
        (partial / "report.html").write_text(render_html(blocks, svgs), encoding="utf-8")
        (partial / MARKER).write_text("written by eskin report\n", encoding="utf-8")
        _replace_dir(partial, out)
    except OSError as error:
        raise StoreError(f"cannot write the report to {out}: {error}") from error
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    return out / "report.html"


def report_blocks(report: Report, drawn: set[Panel]) -> list[Block]:
    """The report's text as blocks, figures referenced by stem (only those in ``drawn``)."""
    version = metadata.version("eskin-sweep")
    blocks: list[Block] = [
        ("h", 1, "e-skin sweep report"),
        (
            "p",
            f"Grid(s) {', '.join(report.grids)} on {report.dataset} data, written by eskin-sweep "
            f"{version}. Accuracy is the fraction of test recordings classified correctly; error "
            "bars are the standard deviation over cross-validation folds.",
        ),
        ("h", 2, "Against the paper"),
        *(("p", claim.sentence) for claim in report.claims),
        ("h", 2, "Figures"),
    ]
    claims = {claim.panel: claim for claim in report.claims}
    for panel in Panel:
        blocks.append(("h", 3, PANEL_TITLES[panel]))
        if panel in report.missing or panel not in drawn:
            blocks.append(
                ("p", f"{PANEL_TITLES[panel]}: {report.missing.get(panel, 'not drawn')}.")
            )
            continue
        blocks.append(("figure", panel.value, PANEL_TITLES[panel]))
        if panel in claims:
            blocks.append(("p", claims[panel].sentence))
        elif panel is Panel.COST:
            blocks.append(("p", cost_sentence(report.cost_points)))
        elif panel is Panel.OBSERVATION:
            blocks.append(("p", observation_sentence(report.time_to_accuracy)))
    blocks += _table_blocks(report)
    blocks += _cost_blocks(report)
    return blocks


def _table_blocks(report: Report) -> Iterator[Block]:
    yield ("h", 2, "Table I")
    rows = [list(vars(PAPER_ROW).values())]
    if report.run_row is None:
        yield ("p", "Table I for this run: not in this run: it needs a sweep of the threshold.")
    else:
        rows.insert(0, list(vars(table_row(report.run_row)).values()))
    yield ("table", list(TABLE_COLUMNS), rows)
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
    yield ("p", notes + ".")
    yield (
        "p",
        "The paper's row holds only what this project states of the paper (its operating point "
        "and figures); cells marked 'not stated here' are not taken from the paper's table.",
    )


def _cost_blocks(report: Report) -> Iterator[Block]:
    yield ("h", 2, "What accuracy costs in time")
    if report.time_to_accuracy:
        yield ("h", 3, "Observation time needed")
        yield (
            "table",
            ["model", "fraction of best", "accuracy target", "seconds of touch needed"],
            [
                [
                    r.model.upper(),
                    f"{r.fraction:.0%}",
                    f"{100 * r.target:.1f} %",
                    "not reached" if r.seconds is None else f"{r.seconds:.3g}",
                ]
                for r in report.time_to_accuracy
            ],
        )
    front = sorted((p for p in report.cost_points if p.on_front), key=lambda p: p.seconds)
    if front:
        yield ("h", 3, "Pareto front: the cheapest design for each accuracy level")
        yield (
            "table",
            ["model", "point", "compute (s)", "accuracy"],
            [
                [p.model.upper(), p.label, f"{p.seconds:.3g}", f"{100 * p.mean:.1f} %"]
                for p in front
            ],
        )
    cost = report.sweep_cost
    yield ("h", 3, "The sweep's own cost")
    yield (
        "p",
        f"{cost.n_points} distinct points took {cost.total_s:.1f} s of stage compute in all (as "
        "measured when each stage was computed, summed over workers).",
    )
    yield (
        "table",
        ["stage", "seconds", "share"],
        [
            [stage, f"{s:.1f}", f"{s / cost.total_s:.0%}" if cost.total_s else "-"]
            for stage, s in cost.stage_seconds
        ],
    )
    if cost.runs:
        yield (
            "table",
            ["finished (UTC)", "grid", "points", "cache hits", "computed", "wall time (s)"],
            [
                [
                    r.finished,
                    r.grid,
                    str(r.points),
                    str(r.cache_hits),
                    str(r.computed),
                    f"{r.seconds:.1f}",
                ]
                for r in cost.runs
            ],
        )
    else:
        yield ("p", "Sweep runs and cache hits: no run log in this root (not in this run).")


def render_markdown(blocks: Sequence[Block]) -> str:
    lines: list[str] = []
    for block in blocks:
        kind = block[0]
        if kind == "h":
            lines += ["#" * block[1] + " " + block[2], ""]
        elif kind == "p":
            lines += [block[1], ""]
        elif kind == "figure":
            lines += [f"![{block[2]}]({FIGURES}/{block[1]}.png)", ""]
        elif kind == "table":
            header, rows = block[1], block[2]
            lines.append("| " + " | ".join(map(_md_cell, header)) + " |")
            lines.append("|" + " --- |" * len(header))
            lines += ["| " + " | ".join(map(_md_cell, row)) + " |" for row in rows]
            lines.append("")
    return "\n".join(lines)


def render_html(blocks: Sequence[Block], svgs: dict[str, str]) -> str:
    """One self-contained page: the figures inlined as SVG, a little CSS, no scripts."""
    body: list[str] = []
    title = "e-skin sweep report"
    for block in blocks:
        kind = block[0]
        if kind == "h":
            body.append(f"<h{block[1]}>{html.escape(block[2])}</h{block[1]}>")
        elif kind == "p":
            body.append(f"<p>{html.escape(block[1])}</p>")
        elif kind == "figure":
            svg = svgs[block[1]]
            body.append(
                f"<figure>{svg[svg.index('<svg') :]}<figcaption>"
                f"{html.escape(block[2])}</figcaption></figure>"
            )
        elif kind == "table":
            head = "".join(f"<th>{html.escape(c)}</th>" for c in block[1])
            rows = "".join(
                "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>"
                for row in block[2]
            )
            body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>")
    style = (
        "body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em}"
        "table{border-collapse:collapse;margin:1em 0}"
        "th,td{border:1px solid #ccc;padding:.3em .5em;text-align:left;vertical-align:top}"
        "figure{margin:1em 0}figure svg{max-width:100%;height:auto}"
    )
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{title}</title>'
        f"<style>{style}</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n"
    )


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|")


def _check_target(out: Path) -> None:
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise StoreError(f"refusing report folder {out}: it is not a directory")
    if out.is_dir():
        contents = sorted(p.name for p in out.iterdir())
        if contents and MARKER not in contents:
            shown = ", ".join(contents[:3]) + (", ..." if len(contents) > 3 else "")
            raise StoreError(f"refusing report folder {out}: not empty and not a report ({shown})")
