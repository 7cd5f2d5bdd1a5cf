"""The design answer on hand-made cubes with exact predictions (see tests/report_helpers.py).

Thresholds 0.04 .. 0.3 V; data rate 700 / threshold (cheaper at higher thresholds). Of 120
recordings the FFNN gets right: 0.09 V 108 (the best, 90 %), 0.04 V 107, 0.15 V 106 (88 %, one
and two discordant recordings: not significantly below), 0.05 V 96 and 0.3 V 72 (60 %:
significantly below). The cheapest design not significantly below the best is 0.15 V.
"""

import numpy as np
import pytest
import scipy.stats

from pipeline.report import FrameReadout, build_report
from pipeline.report.answer import comparison_rows, glance_header, glance_rows, how_sure
from pipeline.report.document import report_blocks
from pipeline.report.render import render_markdown
from pipeline.results.readout_constants import EnergyModel
from pipeline.results.readout_power import frame_data_rate_bps, frame_power_w
from pipeline.results.stats import holm
from tests.report_helpers import N_RECORDINGS, make_cubes

THRESHOLDS = {0.04: 0.89, 0.05: 0.80, 0.09: 0.90, 0.15: 0.88, 0.3: 0.60}
SWEEPS = {"threshold": {"axes": {"readout.threshold_v": list(THRESHOLDS)}}}


def by_threshold(scene):
    return THRESHOLDS[scene.readout.threshold_v]


@pytest.fixture(scope="module")
def cubes():
    return make_cubes(SWEEPS, by_threshold, models=("ffnn",))


@pytest.fixture(scope="module")
def answer(cubes):
    (found,) = build_report(cubes, frame=FrameReadout(12, 2000.0)).answers
    return found


def threshold_of(candidate):
    (setting,) = candidate.design.settings
    return float(setting.value)


def test_cheapest_design_not_significantly_below_the_best_is_chosen(answer):
    assert answer.model == "ffnn"
    assert threshold_of(answer.best) == 0.09
    assert answer.best.accuracy.mean == 108 / N_RECORDINGS
    chosen = answer.by_data_rate
    assert threshold_of(chosen) == 0.15 and threshold_of(answer.by_power) == 0.15
    assert chosen.accuracy.mean == 106 / N_RECORDINGS
    assert (chosen.versus_best.only_a, chosen.versus_best.only_b) == (0, 2)
    assert chosen.versus_best.difference == pytest.approx(-2 / N_RECORDINGS, abs=1e-15)
    assert chosen.versus_best.low <= chosen.versus_best.difference <= chosen.versus_best.high
    significant = {threshold_of(c) for c in answer.candidates if c.below_best}
    assert significant == {0.05, 0.3}  # 0.3 V is cheaper still, but 60 % is significantly below
    assert {threshold_of(c) for c in answer.as_accurate} == {0.04, 0.09, 0.15}
    assert answer.comparisons == 4 and answer.untested == 0


def test_holm_adjusted_p_values_are_holm_of_the_exact_mcnemar_p_values(cubes, answer):
    cube = cubes["threshold"].sel(model="ffnn", repeat=0)
    best = cube["correct"].sel(threshold_v=0.09).values == 1
    others = [c for c in answer.candidates if c is not answer.best]
    raw = []
    for candidate in others:
        mine = cube["correct"].sel(threshold_v=threshold_of(candidate)).values == 1
        only_a, only_b = int(np.sum(mine & ~best)), int(np.sum(best & ~mine))
        raw.append(scipy.stats.binomtest(only_a, only_a + only_b, 0.5).pvalue)
        assert candidate.versus_best.p_value == pytest.approx(raw[-1], rel=1e-12)
    expected = holm(raw)
    assert [c.holm_p for c in others] == pytest.approx(list(expected), rel=1e-12)
    # 0.05 V: 12 discordant recordings, all one way; 2 * 0.5**12, times 3 (the second smallest
    # of 4 p-values).
    at_005 = next(c for c in others if threshold_of(c) == 0.05)
    assert at_005.holm_p == pytest.approx(3 * 2 * 0.5**12, rel=1e-12)


def test_the_answer_is_set_against_the_frame_readout_of_the_same_array(answer):
    chosen = answer.by_data_rate
    frame = frame_data_rate_bps(4, 2000.0, 12)  # the smoke scene's 2 x 2 taxels
    assert chosen.frame_data_rate_bps == frame
    assert chosen.data_rate_ratio == pytest.approx(frame / (700.0 / 0.15), rel=1e-12)
    assert chosen.power_ratio > 1
    rows = glance_rows(answer)
    assert glance_header(answer)[0] == "FFNN"
    assert [r[0] for r in rows] == ["best", "cheapest by data rate, by power"]
    assert rows[1][1] == "readout.threshold_v = 0.15 V"
    wilson = scipy.stats.binomtest(106, N_RECORDINGS).proportion_ci(method="wilson")
    assert rows[1][2] == f"88.3 % [{100 * wilson.low:.1f}, {100 * wilson.high:.1f}]"
    # 96 kbit/s / (700 / 0.15 bit/s) = 20.6
    assert rows[1][3] == "4.67 kbit/s"
    # 4 taxels: static 4 * (10 + 2) nW = 48 nW; dynamic 666.7 events/s * 10 pJ + 4667 bit/s *
    # 1 pJ = 11.3 nW; 59.3 nW in all, 81 % static. The frame readout: 4 * 10 nW + one ADC of
    # 100 nW, plus 8000 samples/s * (10 fJ * 4096 + 12 pJ) = 564 nW, 9.5x more.
    assert chosen.power.static_w == pytest.approx(48e-9, rel=1e-12)
    assert chosen.power_w == pytest.approx(48e-9 + 1e-8 / 1.5 + 7e-9 / 1.5, rel=1e-12)
    assert chosen.frame_power_w == pytest.approx(frame_power_w(4, 2000.0, 12), rel=1e-12)
    assert rows[1][4] == "59.3 nW (81 % static)"
    assert rows[1][6] == "21x, 9.5x"
    # 8 windows of the smoke scene's 0.1 s: 0.8 s of touch per decision.
    assert chosen.design.observation_s == pytest.approx(0.8, rel=1e-12)
    assert rows[1][5] == "47.5 nJ (0.8 s)"
    sure = how_sure(answer)
    assert sure.startswith("FFNN: 2 of the 4 other designs are not significantly below the best")
    assert f"lose up to {-100 * chosen.versus_best.low:.1f} points" in sure
    details = comparison_rows(answer)
    assert [r[4] for r in details].count("no: significantly below") == 2
    assert details[0][1] == "readout.threshold_v = 0.09 V" and details[0][4] == "the best"
    assert details[1][1] == "readout.threshold_v = 0.3 V"  # then cheapest power first


def test_data_rate_and_power_can_choose_different_designs():
    # Same accuracy; 0.05 V sends fewer bits but more events than 0.09 V.
    rates = {0.05: (1000.0, 2000.0), 0.09: (100.0, 3000.0)}
    cubes = make_cubes(
        {"threshold": {"axes": {"readout.threshold_v": [0.05, 0.09]}}},
        lambda scene: 0.9,
        models=("ffnn",),
        rates=lambda scene: rates[scene.readout.threshold_v],
    )
    energy = EnergyModel(event_energy_j=1e-9, link_energy_j_per_bit=1e-12)
    (answer,) = build_report(cubes, energy=energy).answers
    assert threshold_of(answer.by_data_rate) == 0.05
    assert threshold_of(answer.by_power) == 0.09
    static = 4 * (EnergyModel().front_end_w_per_taxel + EnergyModel().comparator_w_per_taxel)
    assert answer.by_power.power.static_w == pytest.approx(static, rel=1e-12)
    assert answer.by_power.power_w == pytest.approx(static + 100.0 * 1e-9 + 3000.0 * 1e-12)
    assert answer.by_power.frame_power_w is None  # no frame readout given: unknown, not guessed


def test_a_run_without_per_recording_results_names_the_best_and_says_why_no_more():
    cubes = make_cubes(SWEEPS, by_threshold, models=("ffnn",), predictions=False)
    report = build_report(cubes)
    (answer,) = report.answers
    assert threshold_of(answer.best) == 0.09 and answer.by_data_rate is None
    assert answer.comparisons == 0 and answer.untested == 4
    markdown = render_markdown(report_blocks(report, set(), version="t"))
    assert "no interval: this run predates per-recording results; re-run the sweep" in markdown
    assert "nan" not in markdown.lower()
