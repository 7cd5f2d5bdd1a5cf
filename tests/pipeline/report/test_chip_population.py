"""Chips as a population in the report: pooled cubes, Fig. 10 by deployment with the spread over
chips, the mismatch claim on ``shared``, the answer by yield (hand-made cubes of the contract's
layout, :func:`tests.report_helpers.with_chips`)."""

import functools

import numpy as np
import pytest

from pipeline.design.scene import Deployment
from pipeline.report import Panel, build_report
from pipeline.report.answer import yield_sentence
from pipeline.report.chip_population import PER_CHIP, chip_curves, fill_groups, pooled
from pipeline.report.claims import Verdict
from pipeline.report.cubes import panel_x
from pipeline.report.document import report_blocks
from pipeline.report.evidence import gather_evidence
from pipeline.report.figures import draw_report
from pipeline.report.render import render_markdown
from tests.report_helpers import (
    PAPER_LIKE_SWEEPS,
    deployment_sweep,
    make_cubes,
    n_right,
    with_chips,
)


def _rates(scene):
    """Event and data rates that fall as the mismatch grows (a cheaper design, for the test)."""
    effect = scene.readout.effects.get("threshold_mismatch")
    sigma = 0.0 if effect is None else effect.sigma_rel
    return 100.0 * (1.5 - sigma), 700.0 * (1.5 - sigma)


@pytest.fixture(scope="module")
def plain():
    return make_cubes({"mismatch": PAPER_LIKE_SWEEPS["mismatch"]}, rates=_rates)["mismatch"]


@pytest.fixture(scope="module")
def report(plain):
    return build_report({"mismatch": deployment_sweep(plain)})


def test_a_cube_of_one_chip_is_read_as_it_is(plain):
    assert pooled(plain) is plain


def test_a_cube_of_chips_is_one_design_per_point_with_its_chips_kept(plain):
    cube = with_chips(plain, "shared")
    view = pooled(cube)
    assert view["accuracy_mean"].dims == ("sigma_rel", "model")
    np.testing.assert_array_equal(view["accuracy_mean"], cube["accuracy_chip_mean"])
    assert (view["accuracy_low"] <= view["accuracy_mean"]).all()
    assert (view["accuracy_mean"] <= view["accuracy_high"]).all()
    assert view["correct"].sizes["repeat"] == 20 and view["test_fold"].sizes["repeat"] == 20
    np.testing.assert_array_equal(view["accuracy_per_chip"], cube["accuracy_mean"])
    np.testing.assert_allclose(view["data_rate_bps"], cube["data_rate_bps"].mean("chip"))
    assert view[PER_CHIP].dims[-3:] == ("chip", "chip_repeat", "recording")
    assert "bootstrap over recordings" in view["accuracy_low"].attrs["interval"]


def test_designs_of_chips_are_compared_over_chips_and_with_one_chip(plain):
    chips = with_chips(plain, "shared")
    evidence = gather_evidence({"one": plain, "many": chips})
    one, many = str(plain["result_key"][-1].item()), str(chips["result_key"][-1].item())
    mean = float(chips["accuracy_chip_mean"].isel(sigma_rel=-1).sel(model="ffnn"))
    single = n_right(float(plain["accuracy_mean"].isel(sigma_rel=-1).sel(model="ffnn"))) / 120
    test = evidence.compare(many, one, "ffnn")
    assert test.difference == pytest.approx(mean - single, abs=1e-12)
    first = str(chips["result_key"][0].item())
    over_chips = evidence.compare(many, first, "ffnn")
    assert "over chips and recordings" in over_chips.method and over_chips.difference < 0
    found = evidence.compare_yield(many, first, "ffnn")
    p05 = chips["accuracy_p05"].sel(model="ffnn").values
    assert found.difference == pytest.approx(p05[-1] - p05[0], abs=1e-12)
    assert evidence.compare_yield(one, first, "ffnn") is None


def test_fig10_sets_the_deployments_side_by_side_with_their_spread(report):
    curves = report.curves[Panel.MISMATCH]
    assert [(c.model, c.group) for c in curves] == [
        (m, d) for d in ("per_chip", "shared", "robust") for m in ("ffnn", "cnn")
    ]
    for curve in curves:
        assert curve.chip_low is not None and curve.chip_high is not None
        assert np.all(curve.chip_low <= curve.chip_median) and np.all(
            curve.chip_median <= curve.chip_high
        )
    shared = next(c for c in curves if c.group == "shared" and c.model == "ffnn")
    stated = deployment_sweep_p05(report, shared)
    np.testing.assert_allclose(shared.chip_low, stated)
    assert not report.heatmaps  # the 2-D sweep is Fig. 10, not a heat map
    from matplotlib.collections import PolyCollection

    figure = draw_report(report)[Panel.MISMATCH.value]
    assert [ax.get_title() for ax in figure.axes] == ["per_chip", "shared", "robust"]
    for ax in figure.axes:  # a band per model beside its error bars
        bands = [c for c in ax.collections if isinstance(c, PolyCollection)]
        assert len(bands) == 2


def test_fig10_draws_the_deployments_in_their_declared_order(plain):
    # Sweeps whose names put their cubes in alphabetical order (per_chip, robust, shared), and a
    # swept deployment listed backwards: the panels follow the declaration all the same.
    declared = [d.value for d in Deployment]
    found = build_report({f"mismatch_{d}": with_chips(plain, d) for d in sorted(declared)})
    groups = [c.group for c in found.curves[Panel.MISMATCH]]
    assert list(dict.fromkeys(groups)) == declared
    figure = draw_report(found)[Panel.MISMATCH.value]
    assert [ax.get_title() for ax in figure.axes] == declared
    backwards = pooled(deployment_sweep(plain, tuple(reversed(declared))))
    x_of = functools.partial(panel_x, Panel.MISMATCH)
    groups = [c.group for c in fill_groups(chip_curves("mismatch", backwards, x_of))]
    assert list(dict.fromkeys(groups)) == declared


def deployment_sweep_p05(report, curve):
    """The yields the designs of ``curve`` state, in its order."""
    by_key = {d.key: d for d in report.designs}
    return [by_key[k].yields[curve.model].p05 for k in curve.keys]


def test_the_mismatch_claim_is_judged_on_shared_and_said_under_fig10(report):
    (claim,) = [c for c in report.claims if c.panel is Panel.MISMATCH]
    assert claim.verdict is Verdict.CONSISTENT
    assert "judged on the shared deployment" in claim.sentence
    assert "per_chip" not in claim.sentence
    assert "at 30% against 0%: significantly below" in claim.sentence
    markdown = render_markdown(report_blocks(report, set(report.figure_stems), version="x"))
    fig10 = markdown[markdown.index("### Fig. 10") : markdown.index("### Accuracy against obs")]
    assert "judged on the shared deployment" in fig10
    assert "FFNN, robust:" in fig10 and "over chips and recordings" in fig10


def test_one_mismatch_sweep_per_deployment_is_grouped_alike(plain):
    cubes = {f"mismatch_{d}": with_chips(plain, d) for d in ("per_chip", "shared")}
    found = build_report(cubes)
    groups = {(c.sweep, c.group) for c in found.curves[Panel.MISMATCH]}
    assert groups == {("mismatch_per_chip", "per_chip"), ("mismatch_shared", "shared")}
    (claim,) = [c for c in found.claims if c.panel is Panel.MISMATCH]
    assert "FFNN, shared 60.0 %" in claim.sentence and "per_chip" not in claim.sentence


def test_the_answer_by_yield_is_the_cheapest_not_significantly_below_the_best(report):
    assert {a.model for a in report.yield_answers} == {"ffnn", "cnn"}
    for answer in report.yield_answers:
        assert answer.best.chips.p05 == max(c.chips.p05 for c in answer.candidates)
        assert len(answer.candidates) == 12 and answer.comparisons == 11
        chosen = answer.by_data_rate
        assert chosen is answer.best or not chosen.below_best
        # Every design cheaper than the choice is significantly below the best by yield.
        cheaper = [c for c in answer.candidates if c.data_rate_bps < chosen.data_rate_bps]
        assert cheaper and all(c.below_best for c in cheaper)
        assert all(c.versus_best.difference < 0 for c in cheaper)
        sentence = yield_sentence(answer)
        assert sentence.startswith(f"{answer.model.upper()} by yield (the 5th percentile")
        assert "20 chips" in sentence and "bootstrap over chips and recordings" in sentence
    markdown = render_markdown(report_blocks(report, set(report.figure_stems), version="x"))
    answer_part = markdown[: markdown.index("## Against the paper")]
    assert "FFNN by yield" in answer_part and "CNN by yield" in answer_part
    assert "Designs simulated as several chips" in answer_part


def test_a_plain_mismatch_sweep_beside_a_shared_one_is_the_default_deployment(plain):
    found = build_report({"mismatch": plain, "mismatch_shared": with_chips(plain, "shared")})
    curves = found.curves[Panel.MISMATCH]
    assert [(c.sweep, c.group, c.chip_low is None) for c in curves] == [
        ("mismatch", "per_chip", True),
        ("mismatch", "per_chip", True),
        ("mismatch_shared", "shared", False),
        ("mismatch_shared", "shared", False),
    ]
    (claim,) = [c for c in found.claims if c.panel is Panel.MISMATCH]
    assert "at 30% against 0%: significantly below" in claim.sentence
    assert "FFNN, per_chip" not in claim.sentence
    assert "FFNN, per_chip" not in found.mismatch_note and "FFNN, shared" in found.mismatch_note


def test_the_yield_answer_names_the_smallest_array_never_one_without_an_area():
    # Perfect matching is the best by yield; with the per_chip chips' loss and spread made up
    # for, 10 % and 20 % mismatch are a recording below it (not significantly), 30 % far below.
    def accuracy(scene):
        effect = scene.readout.effects.get("threshold_mismatch")
        sigma = 0.0 if effect is None else effect.sigma_rel
        made_up = 0.6 + 0.19 * sigma - 1 / 120
        return {0.0: 0.6, 0.1: made_up, 0.2: made_up, 0.3: 0.3}[sigma]

    plain = make_cubes({"mismatch": PAPER_LIKE_SWEEPS["mismatch"]}, accuracy, rates=_rates)
    report = build_report({"mismatch": with_chips(plain["mismatch"], "per_chip")})
    assert report.yield_answers
    for answer in report.yield_answers:
        assert answer.best.design.mismatch_sigma_rel == 0.0
        assert np.isnan(answer.best.area_m2)  # perfect matching: no finite area gives it
        eligible = [c for c in answer.candidates if c is answer.best or not c.below_best]
        sized = [c for c in eligible if np.isfinite(c.area_m2)]
        assert sized and answer.by_area is min(sized, key=lambda c: c.area_m2)
        # Pelgrom: the area falls as 1 / sigma_rel^2, so the smallest array is the eligible
        # design of the largest mismatch.
        assert answer.by_area.design.mismatch_sigma_rel == max(
            c.design.mismatch_sigma_rel for c in sized
        )
        sentence = yield_sentence(answer)
        assert (
            f"the smallest array and the cheapest by power is {answer.by_area.design.label} ("
            in (sentence)
        )
        assert "um^2 of matched comparator gate area)" in sentence
        assert sentence.endswith("so it is never the smallest array.")
        assert "by data rate" not in sentence
