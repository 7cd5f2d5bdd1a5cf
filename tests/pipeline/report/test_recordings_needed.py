"""The recordings per class that would tell the answer's designs from the best, in the answer."""

import dataclasses

import pytest

from pipeline.report import build_report
from pipeline.report.cost import SweepCost
from pipeline.report.evidence import gather_evidence
from pipeline.report.recordings_needed import LOSS, needed_sentence, recordings_needed
from pipeline.results.sample_size import recordings_per_class
from tests.report_helpers import make_cubes

SWEEPS = {"threshold": {"axes": {"readout.threshold_v": [0.03, 0.09, 0.2]}}}


def accuracy(scene):
    # 72 of 120 right at 0.09 V, 69 at 0.2 V (cheaper: fewer events), 60 at 0.03 V.
    return {0.03: 0.5, 0.09: 0.6, 0.2: 69 / 120}[scene.readout.threshold_v]


@pytest.fixture(scope="module")
def cubes():
    return make_cubes(SWEEPS, accuracy, models=("ffnn",))


def test_the_cheapest_and_the_runner_up_each_get_the_recordings_a_5_point_loss_needs(cubes):
    report = build_report(cubes)
    (answer,) = report.answers
    (found,) = report.recordings_needed
    assert answer.by_data_rate.design.label != answer.best.design.label
    (needed,) = found.needed  # the cheapest is also the runner-up: one design, both roles
    assert needed.roles == ("the cheapest by data rate", "the cheapest by power", "the runner-up")
    evidence = gather_evidence(cubes)
    d = evidence.differences(answer.by_data_rate.design.key, answer.best.design.key, "ffnn")
    assert d.shape == (120,) and d.sum() == -3  # three recordings right only in the best
    assert needed.per_class == recordings_per_class(d, LOSS, 12)
    assert found.per_class_now == 10 and found.built_in
    sentence = needed_sentence(found)
    assert sentence.startswith(
        f"FFNN: to show a loss of 5 points or more against the best, record about "
        f"{needed.per_class} touches per class for the cheapest by data rate and by power, also "
        f"the runner-up ({needed.label}) (this run has 10 per class;"
    )
    assert f"(dataset.recordings_per_class = {needed.per_class}): at this run's" in sentence


def test_the_built_in_cost_is_the_runs_seconds_per_recording_scaled():
    cost = SweepCost(n_points=3, n_unpaid=0, stages=(), runs=())
    found = recordings_needed((), gather_evidence({}), 12, "synthetic", cost)
    assert found == ()  # no answer: nothing to decide
    report = build_report(make_cubes(SWEEPS, accuracy, models=("ffnn",)))
    (found,) = report.recordings_needed
    paid = report.sweep_cost.total_s / (report.sweep_cost.n_points * 120)
    assert found.seconds_per_recording == pytest.approx(paid, rel=1e-12)
    k = found.needed[0].per_class
    assert found.seconds_for(k) == pytest.approx(report.sweep_cost.total_s * k / 10, rel=1e-12)


def test_recordings_not_built_in_are_not_offered_as_more_touches(cubes):
    (found,) = build_report(cubes).recordings_needed
    elsewhere = dataclasses.replace(found, built_in=False)
    assert "dataset.recordings_per_class" in needed_sentence(found)
    assert "dataset.recordings_per_class" not in needed_sentence(elsewhere)
    assert needed_sentence(elsewhere).endswith("this run measured).")


def test_two_designs_alike_on_every_recording_cannot_be_estimated():
    report = build_report(
        make_cubes(
            SWEEPS, lambda s: 0.6 if s.readout.threshold_v != 0.03 else 0.5, models=("ffnn",)
        )
    )
    sentences = [needed_sentence(n) for n in report.recordings_needed]
    assert any("and the best agree on every recording" in s for s in sentences), sentences
