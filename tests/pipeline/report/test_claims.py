"""Claims: each of the paper's claims judged by a paired or trend test, and where they disagree."""

import pytest

from pipeline.report import Panel, build_report
from pipeline.report.claims import CLAIMS_COLUMNS, Verdict, claims_table, tally
from pipeline.report.evidence import gather_evidence
from pipeline.report.paper import CLAIM_ROWS
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes


def claims(report):
    found = {}
    for claim in report.claims:
        found.setdefault(claim.panel, []).append(claim)
    return found


@pytest.fixture(scope="module")
def paper_like():
    return build_report(make_cubes())


def test_paper_like_cubes_support_every_claim(paper_like):
    assert paper_like.missing == {}
    verdicts = {c.key: c.verdict for c in paper_like.claims}
    # The optimum's location and the saturation are claims of no significant difference, every
    # other claim one of a significant difference: every test goes the claim's way.
    assert list(verdicts) == list(CLAIM_ROWS)
    assert set(verdicts.values()) == {Verdict.CONSISTENT}, verdicts
    gain, saturation = claims(paper_like)[Panel.TAXELS]
    # 44 of 120 recordings right with 1 taxel, 72 with 16: +64 %.
    assert "+64% (the paper: +63%)" in gain.finding and "a significant gain" in gain.finding
    assert "no significant change above it" in saturation.finding


def test_claims_are_judged_by_tests_never_by_the_fold_spread(paper_like):
    text = " ".join(c.sentence for c in paper_like.claims)
    assert "standard deviation" not in text and "+-" not in text
    optimum, lower = claims(paper_like)[Panel.THRESHOLD]
    assert "Holm-corrected over 2 comparisons" in optimum.finding  # best of 3 thresholds
    assert "McNemar p = " in lower.finding and "significantly less accurate" in lower.finding


def test_mismatch_is_judged_by_the_trend_of_accuracy_on_sigma_rel(paper_like):
    (claim,) = claims(paper_like)[Panel.MISMATCH]
    # 72, 66, 60, 54 of 120 right at sigma_rel 0, 0.1, 0.2, 0.3: slope -0.5 per unit.
    assert "slope -5.0 points per 10 % mismatch" in claim.finding
    (curve, _) = paper_like.curves[Panel.MISMATCH]
    evidence = gather_evidence(make_cubes({"mismatch": PAPER_LIKE_SWEEPS["mismatch"]}))
    trend = evidence.trend(curve.keys, curve.x, curve.model)
    assert trend.slope == pytest.approx(-0.5, abs=1e-12) and trend.p_value < 0.05


def test_claims_say_where_the_data_disagrees():
    def rising_with_mismatch(scene):
        mismatch = scene.readout.effects.get("threshold_mismatch")
        best_at_003 = 0.5 - 2.0 * abs(scene.readout.threshold_v - 0.03)
        return best_at_003 + (0.5 * mismatch.sigma_rel if mismatch else 0.0)

    sweeps = {k: PAPER_LIKE_SWEEPS[k] for k in ("threshold", "mismatch")}
    report = build_report(make_cubes(sweeps, rising_with_mismatch))
    found = claims(report)
    (mismatch,) = found[Panel.MISMATCH]
    assert mismatch.verdict is Verdict.CONTRADICTS and "a significant rise" in mismatch.sentence
    optimum, lower = found[Panel.THRESHOLD]
    assert optimum.verdict is Verdict.CONTRADICTS
    assert "0.03 V is significantly more accurate than 0.09 V" in optimum.sentence
    assert lower.verdict is Verdict.CONTRADICTS
    # Accuracy rises towards lower thresholds: the optimum, 0.03 V, beats 0.09 V next to it.
    assert "the optimum is the lowest value swept (0.03 V, " in lower.sentence
    assert "against 0.09 V next to it: significantly more accurate" in lower.sentence
    for panel in (Panel.WINDOW, Panel.TAXELS, Panel.SPIKE_METRICS, Panel.OBSERVATION):
        assert report.missing[panel].startswith("not in this run")
    (metrics,) = found[Panel.SPIKE_METRICS]
    assert metrics.verdict is Verdict.UNCLEAR and not metrics.in_run
    assert "no correlate sweep is in this run" in metrics.sentence


def test_a_difference_too_small_to_tell_is_cannot_tell():
    # 0.09 V right on 72 recordings, 0.2 V on 71: one discordant recording.
    def flat(scene):
        return {0.03: 0.5, 0.09: 0.6, 0.2: 71 / 120}[scene.readout.threshold_v]

    sweeps = {"threshold": {"axes": {"readout.threshold_v": [0.03, 0.09, 0.2]}}}
    report = build_report(make_cubes(sweeps, flat, models=("ffnn",)))
    optimum, lower = claims(report)[Panel.THRESHOLD]
    assert optimum.verdict is Verdict.CONSISTENT and lower.verdict is Verdict.CONSISTENT
    window = build_report(
        make_cubes(
            {"window": {"axes": {"coding.window_s": [0.05, 0.1, 0.2]}}},
            lambda s: {0.05: 0.5, 0.1: 0.6, 0.2: 71 / 120}[s.coding.window_s],
            models=("ffnn",),
        )
    )
    _, sides = claims(window)[Panel.WINDOW]
    assert sides.verdict is Verdict.PARTLY  # shorter: significant; longer: cannot tell
    assert "no significant difference (the interval includes 0)" in sides.finding


def test_an_optimum_at_the_end_that_is_not_clearly_better_is_cannot_tell():
    # 0.03 V: 72 right, 0.09 V: 71, 0.2 V: 60; the optimum is the lowest threshold, by one
    # recording.
    def edge(scene):
        return {0.03: 0.6, 0.09: 71 / 120, 0.2: 0.5}[scene.readout.threshold_v]

    sweeps = {"threshold": PAPER_LIKE_SWEEPS["threshold"]}
    report = build_report(make_cubes(sweeps, edge, models=("ffnn",)))
    _, lower = claims(report)[Panel.THRESHOLD]
    assert lower.verdict is Verdict.UNCLEAR
    assert "no significant difference (the interval includes 0)" in lower.finding


def test_runs_without_per_recording_results_cannot_tell_and_say_why():
    report = build_report(make_cubes(predictions=False))
    for claim in report.claims:
        if claim.panel is Panel.SPIKE_METRICS:
            continue  # a correlation across points needs no per-recording results
        assert claim.verdict is Verdict.UNCLEAR, claim.sentence
        assert "no interval: this run predates per-recording results; re-run the sweep" in (
            claim.finding
        )


def test_two_values_test_the_one_pair_once_for_both_sides():
    sweeps = {"window": {"axes": {"coding.window_s": [0.1, 0.2]}}}
    report = build_report(
        make_cubes(sweeps, lambda s: {0.1: 0.6, 0.2: 0.5}[s.coding.window_s], models=("ffnn",))
    )
    _, sides = claims(report)[Panel.WINDOW]
    # Shorter: the optimum is the shortest window and beats the next one (accuracy rises towards
    # shorter windows); longer: 0.2 s is significantly less accurate. One test, read twice.
    assert sides.verdict is Verdict.PARTLY
    assert sides.finding.count("one comparison") == 2 and "Holm" not in sides.finding
    assert "+10.0 points" in sides.finding and "-10.0 points" in sides.finding


@pytest.mark.parametrize(
    ("tests", "verdict"),
    [
        ((), Verdict.UNCLEAR),
        ((Verdict.CONSISTENT, Verdict.CONSISTENT), Verdict.CONSISTENT),
        ((Verdict.CONSISTENT, Verdict.UNCLEAR), Verdict.PARTLY),
        ((Verdict.CONSISTENT, Verdict.CONTRADICTS), Verdict.PARTLY),
        ((Verdict.PARTLY, Verdict.UNCLEAR), Verdict.PARTLY),
        ((Verdict.CONTRADICTS, Verdict.UNCLEAR), Verdict.CONTRADICTS),
        ((Verdict.CONTRADICTS,), Verdict.CONTRADICTS),
        ((Verdict.UNCLEAR, Verdict.UNCLEAR), Verdict.UNCLEAR),
    ],
)
def test_the_verdict_rules(tests, verdict):
    # consistent: every test the claim's way; in part: some; contradicts: one against it and
    # none for it; cannot tell: none significant where a difference is claimed, or no test.
    assert tally(tests) is verdict


def test_the_claims_table_has_a_row_per_claim_with_the_figures_and_the_verdict(paper_like):
    rows = claims_table(paper_like.claims)
    assert len(CLAIMS_COLUMNS) == 4 and all(len(r) == 4 for r in rows)
    by_claim = {r[0]: r for r in rows}
    gain = by_claim["Fig. 8: gain from 1 to 16 taxels"]
    # 44 of 120 right with 1 taxel, 72 with 16 (FFNN): +28 discordant recordings, all one way.
    assert gain[1] == "+63% (FFNN)" and gain[3] == "consistent"
    assert gain[2].startswith("FFNN +64% (16 against 1 taxels: +23.3 points [")
    optimum = by_claim["Fig. 7a: optimum threshold"]
    assert optimum[1] == "0.09 V (3.5 bits), both networks"
    assert optimum[2].startswith("FFNN best at 0.09 V (60.0 % [")
    (mismatch,) = (r for r in rows if r[0].startswith("Fig. 10"))
    assert "FFNN -5.0 points per 10 % mismatch [" in mismatch[2]
    assert {r[3] for r in rows} <= {str(v) for v in Verdict}


def test_a_claim_not_in_the_run_says_so_in_the_table():
    report = build_report(make_cubes({"threshold": PAPER_LIKE_SWEEPS["threshold"]}))
    rows = {r[0]: r for r in claims_table(report.claims)}
    row = rows["Fig. 10: accuracy falls with threshold mismatch"]
    assert row[2] == "not in this run" and row[3] == "cannot tell"
