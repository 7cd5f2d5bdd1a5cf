"""Accuracy against the real taxels read: every count compared with the most by a paired test,
Holm-adjusted, the fewest taxels not significantly below the most, in the answer's section; a
real-taxel design's sensors in Table I."""

import numpy as np
import pytest
from scipy.stats import binomtest

from pipeline.report import build_report
from pipeline.report.blocks import Heading, Paragraph, Table
from pipeline.report.document import report_blocks
from pipeline.report.taxel_count import TAXEL_COUNT_TITLE, _rows
from pipeline.results.stats import holm
from pipeline.run.entries import RecordingsInfo
from tests.report_helpers import N_RECORDINGS, make_cubes, n_right

ACCURACY = {1: 0.4, 2: 0.55, 4: 0.78, 8: 0.8, 16: 0.8}
SWEEPS = {
    "taxels_read": {
        "set": {"array.rows": 1, "array.cols": 1},
        "axes": {"array.taxels": list(ACCURACY)},
    }
}


@pytest.fixture(scope="module")
def report():
    cubes = make_cubes(SWEEPS, lambda scene: ACCURACY[scene.array.taxels], models=("ffnn",))
    return build_report(cubes)


def test_every_count_is_compared_with_the_most_taxels_read(report):
    (count,) = report.taxel_counts
    assert count.curve.x.tolist() == [1, 2, 4, 8, 16]
    assert count.most == 4 and count.versus_most[4] is None
    # Nested predictions: k_16 - k_n discordant recordings, all one way (tests/report_helpers).
    discordant = [n_right(0.8) - n_right(ACCURACY[n]) for n in (1, 2, 4, 8)]
    p = [binomtest(d, d).pvalue if d else 1.0 for d in discordant]
    np.testing.assert_allclose(count.holm_p[:4], holm(p), rtol=1e-12)
    for n, comparison in zip((1, 2, 4, 8), count.versus_most[:4], strict=True):
        expected = (n_right(ACCURACY[n]) - n_right(0.8)) / N_RECORDINGS
        assert comparison.difference == pytest.approx(expected, abs=1e-12)
    # 4 taxels are 2 recordings below 16: not significant; 2 taxels are 30 below: significant.
    assert count.fewest_as_accurate == 2
    assert "the fewest taxels not significantly below them: 4 (78.3 %" in count.sentence()


def test_the_answer_holds_the_table_and_table_i_names_real_taxels(report):
    blocks = report_blocks(report, set(), version="test")
    start = blocks.index(Heading(3, TAXEL_COUNT_TITLE))
    paragraphs = [b.text for b in blocks[start:] if isinstance(b, Paragraph)]
    assert [p.stem for p in report.sweep_plots] == ["sweep_taxels_read"]  # the figure
    assert "(file sweep_taxels_read)" in paragraphs[0]
    assert "FFNN (sweep taxels_read): all 16 taxels read give 80.0 %" in paragraphs[1]
    table = next(b for b in blocks[start:] if isinstance(b, Table))
    assert [row[2] for row in table.rows] == ["1", "2", "4", "8", "16"]
    assert table.rows[-1][4] == "(the most)"
    assert "Holm p" in table.rows[0][4]
    sensors = {row.sensors for row in report.run_rows}
    assert sensors <= {
        f"{n} real taxel{'s' if n > 1 else ''} (columns of the recorded array)" for n in ACCURACY
    }
    assert sensors


def test_a_run_without_a_taxel_count_sweep_has_no_such_section():
    report = build_report(make_cubes({"t": {"axes": {"readout.threshold_v": [0.05, 0.09]}}}))
    assert report.taxel_counts == ()
    assert Heading(3, TAXEL_COUNT_TITLE) not in report_blocks(report, set(), version="test")


def test_where_the_cube_states_the_positions_each_count_has_its_pitch():
    grid = tuple((float(x), float(y)) for y in range(4) for x in range(4))  # 4 x 4 at 1 mm
    recordings = RecordingsInfo(
        "array", tuple(f"c{i}" for i in range(12)), 35.0, tuple(f"t{k}" for k in range(16)), grid
    )
    cubes = make_cubes(
        SWEEPS, lambda scene: ACCURACY[scene.array.taxels], recordings, models=("ffnn",)
    )
    (count,) = build_report(cubes).taxel_counts
    assert np.isnan(count.pitch_mm[0])
    np.testing.assert_allclose(count.pitch_mm[1:], [3 * np.sqrt(2), 3.0, 1.0, 1.0], rtol=1e-12)
    rows = list(_rows(count))
    assert [row[2] for row in rows] == [
        "1",
        "2 (pitch 4.24 mm)",
        "4 (pitch 3 mm)",
        "8 (pitch 1 mm)",
        "16 (pitch 1 mm)",
    ]
    assert "all 16 (pitch 1 mm) taxels read give" in count.sentence()


def test_a_design_that_reads_every_taxel_of_a_real_array_counts_them_all():
    recordings = RecordingsInfo("array", ("a", "b"), 35.0, tuple(f"t{k}" for k in range(16)))
    sweeps = {
        "t": {"set": {"array.rows": 1, "array.cols": 1}, "axes": {"readout.threshold_v": [0.05]}}
    }
    report = build_report(make_cubes(sweeps, lambda scene: 0.8, recordings))
    assert [d.n_taxels for d in report.designs] == [16]
    assert {row.sensors for row in report.run_rows} == {
        "16 real taxels (columns of the recorded array)"
    }
