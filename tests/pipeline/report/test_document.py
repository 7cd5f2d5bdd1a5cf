"""The report document: its Markdown for fixed cubes is a committed golden file; its files.

To accept a deliberate change of the report's text, rewrite the golden file with
``.venv/bin/python -c "from tests.pipeline.report.test_document import golden_markdown as g;
g(write=True)"`` and review the diff.
"""

import html
from pathlib import Path

import pytest

from pipeline.report import FrameReadout, Panel, SweepRun, build_report
from pipeline.report.designs import Cost
from pipeline.report.document import report_blocks, report_files
from pipeline.report.figures import draw_report
from pipeline.report.recordings_needed import needed_sentence
from pipeline.report.render import render_markdown
from pipeline.results.readout_constants import EnergyModel
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes

GOLDEN = Path(__file__).parents[2] / "data" / "report_golden.md"
VERSION = "0.0.0-golden"  # not the installed version: the golden file outlives releases


def golden_markdown(write: bool = False) -> str:
    """report.md of :func:`make_cubes` with a 12-bit frame readout and one logged run."""
    runs = (SweepRun("2024-01-01T00:00:00+00:00", "t|x", 10, 2, 8, 12.5),)
    report = build_report(make_cubes(), frame=FrameReadout(12, 2000.0), runs=runs)
    text = render_markdown(report_blocks(report, set(report.figure_stems), version=VERSION))
    if write:
        GOLDEN.write_text(text, encoding="utf-8")
    return text


def test_markdown_of_fixed_cubes_equals_the_golden_file():
    assert golden_markdown() == GOLDEN.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def small():
    report = build_report(make_cubes({k: PAPER_LIKE_SWEEPS[k] for k in ("threshold", "mismatch")}))
    return report, draw_report(report)


def test_report_files_are_the_pages_and_every_figure_twice(small):
    report, figures = small
    calls = []
    files = report_files(report, figures, version=VERSION, on_figure=lambda: calls.append(1))
    stems = list(figures)
    assert stems == [Panel.THRESHOLD.value, Panel.MISMATCH.value, *(c.stem for c in Cost)]
    assert set(files) == {"report.md", "report.html"} | {
        f"figures/{s}.{ext}" for s in stems for ext in ("png", "svg")
    }
    assert len(calls) == len(figures)
    assert all(files[f"figures/{s}.png"].startswith(b"\x89PNG") for s in stems)
    html = files["report.html"].decode()
    assert html.count("<svg") == len(figures) and "<?xml" not in html
    markdown = files["report.md"].decode()
    assert f"eskin-sweep {VERSION}." in markdown


def test_a_panel_not_drawn_says_so():
    report = build_report(make_cubes({"threshold": PAPER_LIKE_SWEEPS["threshold"]}))
    markdown = render_markdown(report_blocks(report, {Cost.COMPUTE.stem}, version=VERSION))
    assert f"{Panel.THRESHOLD.value}.png" not in markdown
    assert "Fig. 7a: accuracy against the readout threshold: not drawn." in markdown
    assert f"(figures/{Cost.COMPUTE.stem}.png)" in markdown
    assert f"{Cost.DATA_RATE.stem}.png" not in markdown


def test_the_report_opens_with_the_answer_and_names_its_assumptions():
    markdown = golden_markdown()
    headings = [line for line in markdown.splitlines() if line.startswith("## ")]
    assert headings[:3] == [
        "## The answer: the cheapest design as accurate as the best",
        "## Against the paper",
        "## Table I",
    ]
    assert markdown.count("Holm-corrected over the model's comparisons") == 1
    for sentence in EnergyModel().assumptions():
        assert f"- {sentence}" in markdown
    assert "calibrated on the chip of M. D. Alea et al., IEEE TBioCAS, Dec. 2024" in markdown


def test_the_first_screen_is_the_answer_tables_one_sentence_each_and_the_power_front(small):
    report, figures = small
    page = report_files(report, figures, version=VERSION)["report.html"].decode()
    opened, closed = page.index("<details>"), page.index("</details>")
    first = page[:opened]
    # Per model one small table headed by its name, one sentence on how sure it is and one on
    # the recordings that would decide it; then the power front.
    assert first.count("<table>") == len(report.answers) == 2
    for answer in report.answers:
        name = answer.model.upper()
        assert f"<thead><tr><th>{name}</th><th>design</th>" in first
        assert first.count(f"<p>{name}: ") == 2
        needed = needed_sentence(
            next(n for n in report.recordings_needed if n.model == answer.model)
        )
        assert f"<p>{html.escape(needed)}</p>" in first
    assert first.count("<p>") == 1 + 2 * len(report.answers)  # the run's one line, then those
    assert first.count("<svg") == 1
    assert "<figcaption>Accuracy against estimated readout power" in first
    assert "Alea et al." in first
    # The method follows once, collapsed, and is not repeated per model anywhere.
    for method in (
        "Each other design is compared with the best by a paired test",
        "the p-values are Holm-corrected over the model",
        "Accuracy is the fraction of (recording, repeat) pairs",
        "front_end_w_per_taxel = ",
    ):
        assert page.count(method) == 1, method
        assert opened < page.index(method) < closed, method
    # The power front is drawn once: at the top, not again with the other fronts.
    assert page.count("<svg") == len(figures)
