"""write_report: a report and its figures rendered into a whole folder (self-contained HTML,
Markdown, PNG and SVG figures), replacing an old report but never a user's folder."""

import pytest

from flows.report import write_report
from pipeline.report import Panel, build_report
from pipeline.report.figures import draw_report
from storage import StoreError
from storage.report import MARKER
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes


@pytest.fixture(scope="module")
def small_report():
    sweeps = {k: PAPER_LIKE_SWEEPS[k] for k in ("threshold", "mismatch")}
    report = build_report(make_cubes(sweeps))
    return report, draw_report(report)


def test_report_folder_holds_every_output(tmp_path, small_report):
    report, figures = small_report
    page = write_report(tmp_path / "out", report, figures)
    assert page == tmp_path / "out" / "report.html"
    for panel in figures:
        for ext in ("png", "svg"):
            assert (tmp_path / "out" / "figures" / f"{panel.value}.{ext}").stat().st_size > 1000
    html = page.read_text()
    assert html.count("<svg") == len(figures) and "src=" not in html and "<script" not in html
    markdown = (tmp_path / "out" / "report.md").read_text()
    assert f"(figures/{Panel.THRESHOLD.value}.png)" in markdown
    assert "Fig. 8: accuracy against the taxel count: not in this run" in markdown
    assert "| paper (the paper's figures) |" in markdown
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no partial left behind


def test_a_report_replaces_an_old_report_but_never_a_users_folder(tmp_path, small_report):
    report, figures = small_report
    out = tmp_path / "out"
    write_report(out, report, figures)
    (out / "stale.txt").write_text("old")
    write_report(out, report, figures)
    assert not (out / "stale.txt").exists() and (out / MARKER).is_file()
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    with pytest.raises(StoreError, match="not a report"):
        write_report(mine, report, figures)
    assert [p.name for p in mine.iterdir()] == ["thesis.tex"]
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError, match="not a directory"):
        write_report(tmp_path / "file", report, figures)
