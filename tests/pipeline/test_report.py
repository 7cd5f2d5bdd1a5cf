"""Report analysis: claims computed from cubes, Table I numbers, Pareto front, observation time."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pipeline.grid import load_grid
from pipeline.report import (
    FrameReadout,
    Panel,
    RecordingFacts,
    Verdict,
    build_report,
    pareto_front,
    table_row,
    time_to_accuracy,
)
from pipeline.scene import cache_key
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes, paper_like_accuracy

FACTS = RecordingFacts("synthetic", n_classes=12, n_recordings=48, fs_hz=2000.0)


def claims(report):
    return {claim.panel: claim for claim in report.claims}


def test_paper_like_cubes_agree_with_every_claim():
    report = build_report(make_cubes(), facts=FACTS)
    assert report.missing == {}
    verdicts = {panel: claim.verdict for panel, claim in claims(report).items()}
    assert set(verdicts.values()) == {Verdict.AGREES}, verdicts
    assert "(+63%)" in claims(report)[Panel.TAXELS].finding


def test_claims_say_where_the_data_disagrees():
    def rising_with_mismatch(scene):
        mismatch = scene.readout.effects.get("threshold_mismatch")
        best_at_003 = 0.5 - 2.0 * abs(scene.readout.threshold_v - 0.03)
        return best_at_003 + (0.5 * mismatch.sigma_rel if mismatch else 0.0)

    sweeps = {k: PAPER_LIKE_SWEEPS[k] for k in ("threshold", "mismatch")}
    report = build_report(make_cubes(sweeps, rising_with_mismatch))
    found = claims(report)
    assert found[Panel.MISMATCH].verdict is Verdict.DISAGREES
    assert "rises" in found[Panel.MISMATCH].sentence
    assert found[Panel.THRESHOLD].verdict is Verdict.DISAGREES
    assert "best at 0.03 V" in found[Panel.THRESHOLD].sentence
    for panel in (Panel.WINDOW, Panel.TAXELS, Panel.SPIKE_METRICS, Panel.OBSERVATION):
        assert report.missing[panel].startswith("not in this run")
    assert found[Panel.SPIKE_METRICS].verdict is Verdict.ABSENT


def test_table_numbers_equal_the_cube():
    cubes = make_cubes()
    report = build_report(cubes, facts=FACTS, frame=FrameReadout(bits=12, rate_hz=2000.0))
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


def test_cost_points_are_distinct_and_priced_per_model():
    cubes = make_cubes()
    report = build_report(cubes)
    keys = [(p.key, p.model) for p in report.cost_points]
    assert len(keys) == len(set(keys))
    shared = [p for p in report.cost_points if len(p.sweeps) > 1]
    assert shared, "the operating point is in several sweeps and must be counted once"
    one = next(p for p in report.cost_points if p.model == "ffnn" and p.label.startswith("taxels"))
    # load + readout (per taxel) + coding + train_ffnn; train_cnn is not the FFNN's cost.
    assert one.seconds == 0.1 + 0.01 * 1 + 0.02 + 0.5
    cost = report.sweep_cost
    assert cost.n_points == len({p.key for p in report.cost_points})
    assert dict(cost.stage_seconds)["load"] == pytest.approx(0.1 * cost.n_points)


@given(st.lists(st.tuples(st.integers(0, 20), st.integers(0, 20)), min_size=1, max_size=30))
def test_pareto_front_is_the_cheapest_design_per_accuracy(pairs):
    seconds = np.array([float(s) for s, _ in pairs])
    accuracy = np.array([a / 20 for _, a in pairs])
    front = pareto_front(seconds, accuracy)
    for i in range(len(pairs)):
        cheaper_or_equal = (seconds <= seconds[i]) & (np.arange(len(pairs)) != i)
        beaten = np.any(cheaper_or_equal & (accuracy >= accuracy[i]) & front)
        if front[i]:
            assert not np.any(cheaper_or_equal & (accuracy > accuracy[i]))
        else:
            assert beaten  # every point off the front has a front point as good and as cheap
    assert front[np.argmax(accuracy)] or np.sum(accuracy == accuracy.max()) > 1


def test_time_to_accuracy_finds_the_first_swept_time():
    report = build_report(make_cubes())
    (curve, *_) = report.curves[Panel.OBSERVATION]
    # n_windows 1, 2, 5 of 0.1 s; accuracy 0.6 - 0.2 / n: 0.4, 0.5, 0.56.
    np.testing.assert_allclose(curve.x, [0.1, 0.2, 0.5])
    rows = {r.fraction: r.seconds for r in time_to_accuracy([curve], (0.7, 0.85, 1.0, 1.1))}
    assert rows == {0.7: 0.1, 0.85: 0.2, 1.0: 0.5, 1.1: None}


def test_paper_grid_observation_sweep_reuses_the_operating_points_spike_trains():
    grid = load_grid("paper")
    sweep = next(s for s in grid.sweeps if s.name == "observation")
    assert sweep.axes[0].field == "coding.n_windows" and sweep.axes[0].values[0] == 1
    spikes = {cache_key(p.scene, "spikes") for p in grid.points() if p.sweep == "observation"}
    assert spikes == {cache_key(grid.base, "spikes")}
    assert paper_like_accuracy(grid.base) > 0  # the helper accepts the paper scene too
