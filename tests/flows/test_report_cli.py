"""eskin report on a real smoke sweep: figures, Table I from the cube, missing sweeps, errors."""

import pytest

from flows.cli import main
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
    # Table I's numbers are the cube's, at the best threshold.
    threshold = open_results(root)["threshold"]
    best = threshold["accuracy"].mean("fold").max("model").idxmax("threshold_v")
    bits = float(threshold["equivalent_bits"].sel(threshold_v=best))
    assert f"| this run (synthetic data) | {bits:.2f} bit (best threshold {float(best):g} V" in (
        markdown
    )
    assert "| 12 |" in markdown  # classes, from the recordings


def test_a_root_that_is_not_a_store_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["report", "--root", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("eskin: error: not a sweep store") and "\n" not in err
    assert list(tmp_path.iterdir()) == []
