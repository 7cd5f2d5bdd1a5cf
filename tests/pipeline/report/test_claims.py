"""Claims: what the cubes say about each of the paper's claims, and where they disagree."""

from pipeline.report import Panel, build_report
from pipeline.report.claims import Verdict
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes


def claims(report):
    return {claim.panel: claim for claim in report.claims}


def test_paper_like_cubes_agree_with_every_claim():
    report = build_report(make_cubes())
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
