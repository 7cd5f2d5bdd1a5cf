"""Table I: every row of the paper's table, beside this run's answer designs with the cube's
numbers; facts the cubes do not state are unknown, never guessed."""

import pytest

from pipeline.report import build_report, sampling_rate_hz
from pipeline.report import paper as paper_numbers
from pipeline.report.document import report_blocks
from pipeline.report.render import render_markdown
from pipeline.report.tables import TABLE_COLUMNS, table_rows
from pipeline.run.entries import RecordingsInfo
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes

# The paper's Table I, as the paper gives it: reference, sensors, data rate, accuracy.
PAPER_TABLE = (
    ("the paper", "9", "51.32 Hz", "90 % (8.33 %)"),
    ("ref. [16]", "4 (multi-modal)", "96 kHz", "79 % (8.33 %)"),
    ("ref. [17]", "6", "100 Hz", "92 % (10 %)"),
    ("ref. [11]", "4", "9.12 kHz (estimated)", "94.2 % (10 %)"),
    ("ref. [18]", "2 (multi-modal)", "115.2 kHz (link baud rate)", "99.45 % (50 %)"),
    ("ref. [19]", "4", "28.8 kHz (estimated)", "97.6 % (33.33 %)"),
)


@pytest.fixture(scope="module")
def report():
    return build_report(make_cubes())


def test_table_holds_every_row_of_the_papers_table(report):
    markdown = render_markdown(report_blocks(report, set(), version="t"))
    rows = table_rows(report.run_rows)
    assert len(rows) == len(report.run_rows) + len(PAPER_TABLE)
    paper_rows = rows[len(report.run_rows) :]
    for (reference, sensors, rate, accuracy), row in zip(PAPER_TABLE, paper_rows, strict=True):
        assert row[0].endswith(reference)
        cells = dict(zip(TABLE_COLUMNS, row, strict=True))
        assert (cells["sensors"], cells["estimated data rate"]) == (sensors, rate)
        assert cells["accuracy (chance)"] == accuracy
        assert "| " + " | ".join(row) + " |" in markdown
    assert paper_numbers.DATA_RATE_HZ == 51.32


def test_run_rows_are_the_answer_designs_with_the_cubes_numbers(report):
    cubes = make_cubes()
    assert [r.classifier for r in report.run_rows] == ["FFNN", "CNN"]
    # The threshold sweep's optimum is both the best and the cheapest as accurate as it.
    point = cubes["threshold"].sel(threshold_v=0.09)
    ffnn = report.run_rows[0]
    assert "the best: readout.threshold_v = 0.09 V" in ffnn.reference
    mean, low, high = (
        float(point[v].sel(model="ffnn"))
        for v in ("accuracy_mean", "accuracy_low", "accuracy_high")
    )
    folds = point["accuracy"].sel(model="ffnn").values.ravel()
    assert ffnn.accuracy == (
        f"{100 * mean:.1f} % [{100 * low:.1f}, {100 * high:.1f}] (8.33 %); fold std "
        f"{100 * folds.std():.1f} %"
    )
    assert ffnn.readout.startswith(
        f"level-crossing spikes ({float(point['equivalent_bits']):.2f} b"
    )
    events, bits = float(point["event_rate_hz"]), float(point["data_rate_bps"])
    assert ffnn.data_rate == (
        f"{events / 1e3:.3g} kevents/s (event rate); {bits / 1e3:.3g} kbit/s (address-event data "
        "rate)"
    )
    assert (ffnn.sensors, ffnn.classes) == ("4 (2 x 2 taxels)", "12")


def test_table_notes_say_which_figure_meets_the_papers_51_hz(report):
    markdown = render_markdown(report_blocks(report, set(), version="t"))
    note = next(line for line in markdown.splitlines() if line.startswith("The paper's 51.32 Hz"))
    assert "events per second" in note and "bits per second" in note and "event rate" in note


def test_facts_the_cubes_do_not_state_are_unknown_never_guessed():
    sweeps = {"threshold": PAPER_LIKE_SWEEPS["threshold"]}
    stated = RecordingsInfo("synthetic", ("a", "b", "c", "d"), 250.0)
    assert sampling_rate_hz(make_cubes(sweeps, recordings=stated)) == 250.0
    rows = build_report(make_cubes(sweeps, recordings=stated)).run_rows
    assert "(25.00 %); fold std" in rows[0].accuracy
    cubes = make_cubes(sweeps, recordings=None)
    assert sampling_rate_hz(cubes) is None
    (row, _) = build_report(cubes).run_rows
    assert row.classes.startswith("unknown") and "(chance unknown)" in row.accuracy
