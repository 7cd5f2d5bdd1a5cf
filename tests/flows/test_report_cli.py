"""eskin report on a real smoke sweep: figures, Table I from the cube, missing sweeps, errors."""

import re

import pytest

from flows.cli import main
from pipeline.report import build_report
from storage import open_results
from tests.flows.helpers import eskin


@pytest.mark.slow
def test_report_of_the_smoke_sweep(smoke_sweep, tmp_path):
    root, _, env = smoke_sweep
    out = tmp_path / "report"
    proc = eskin("report", "--root", str(root), "--out", str(out), env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip() == str(out / "report.html")
    markdown = (out / "report.md").read_text()
    for missing in ("Fig. 8", "Fig. 10", "observation time"):
        line = next(x for x in markdown.splitlines() if missing in x and "not in this run" in x)
        assert line
    for stem in ("fig7a_threshold", "fig7b_window", "fig9_ssnr_ste", "cost_pareto"):
        assert (out / "figures" / f"{stem}.png").stat().st_size > 1000
    # The report opens with the answer, and Table I holds this run's answer designs.
    assert markdown.index("## The answer") < markdown.index("## Against the paper")
    report = build_report(open_results(root))
    assert [a.model for a in report.answers] == ["ffnn", "cnn"]
    for answer in report.answers:
        bits = answer.by_data_rate.design.equivalent_bits
        assert f"({bits:.2f} b equivalent, variable)" in markdown
    assert "| 12 |" in markdown  # classes, from the recordings
    assert not re.search(r"\bnan\b", markdown, flags=re.IGNORECASE)


def test_a_root_that_is_not_a_store_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["report", "--root", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("eskin: error: not a sweep store") and "\n" not in err
    assert list(tmp_path.iterdir()) == []
