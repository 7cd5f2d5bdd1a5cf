"""Table I: the numbers of this run's row are the cube's; facts not stated are unknown."""

import pytest

from pipeline.cube import RecordingsInfo
from pipeline.report import FrameReadout, build_report, sampling_rate_hz
from pipeline.report.tables import table_row
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes


def test_table_numbers_equal_the_cube():
    cubes = make_cubes()
    report = build_report(cubes, frame=FrameReadout(bits=12, rate_hz=2000.0))
    row = report.run_row
    point = cubes["threshold"].sel(threshold_v=0.09)
    assert row.threshold_v == 0.09
    assert row.equivalent_bits == float(point["equivalent_bits"])
    assert row.event_rate_hz == float(point["event_rate_hz"])
    assert row.data_rate_bps == float(point["data_rate_bps"])
    assert row.frame_data_rate_bps == 4 * 12 * 2000.0
    folds = point["accuracy"].sel(model="cnn").values
    cnn = next(entry for entry in row.accuracy if entry[0] == "cnn")
    assert cnn[1:] == pytest.approx((folds.mean(), folds.std()), rel=1e-12)
    text = table_row(row)
    assert text.resolution.startswith(f"{float(point['equivalent_bits']):.2f} bit")
    assert "chance 8.3%" in text.accuracy
    assert (text.classes, row.dataset) == ("12", "synthetic")  # the cube's n_classes, dataset.kind


def test_facts_the_cubes_do_not_state_are_unknown_never_guessed():
    sweeps = {"threshold": PAPER_LIKE_SWEEPS["threshold"]}
    stated = RecordingsInfo("synthetic", ("a", "b", "c", "d"), 250.0)
    assert sampling_rate_hz(make_cubes(sweeps, recordings=stated)) == 250.0
    row = build_report(make_cubes(sweeps, recordings=stated)).run_row
    assert "chance 25.0%" in table_row(row).accuracy
    cubes = make_cubes(sweeps, recordings=None)
    assert sampling_rate_hz(cubes) is None
    text = table_row(build_report(cubes).run_row)
    assert text.classes.startswith("unknown") and "chance" not in text.accuracy
