"""Writing reports: self-contained HTML, Markdown, figures; atomic replacement; the run log."""

import pytest

from pipeline.figures import draw_report
from pipeline.report import Panel, build_report
from storage import StoreError
from storage.report import MARKER, write_report
from storage.runlog import RUN_LOG, append_sweep_run, read_sweep_runs
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


def test_run_log_round_trip_skips_torn_lines(tmp_path):
    assert read_sweep_runs(tmp_path) == []
    summary = {"grid": "smoke", "points": 7, "cache_hits": 2, "computed": 5, "seconds": 12.5}
    append_sweep_run(tmp_path, summary)
    with open(tmp_path / RUN_LOG, "a") as log:
        log.write('{"grid": "torn"\n')
    append_sweep_run(tmp_path, {**summary, "cache_hits": 7, "computed": 0})
    runs = read_sweep_runs(tmp_path)
    assert [(r.grid, r.points, r.cache_hits, r.computed, r.seconds) for r in runs] == [
        ("smoke", 7, 2, 5, 12.5),
        ("smoke", 7, 7, 0, 12.5),
    ]
