"""The report's time section on cubes that keep decisions (by hand: tests/latency_helpers.py).

On the hand-made decisions, a model's accuracy at the earlier times loses 50, 20, 3 and 0 % of
its right recordings (nested), so against the full touch the losses are 60, 24, 2 and 0 of
the best point's recordings: 0.75 s loses 2 (McNemar p = 0.5, not significant), 0.5 s loses 13
(FFNN 12; p far below 0.05).
"""

import math
import re

import numpy as np
import pytest

from pipeline.design.scene import DecisionTraining
from pipeline.report import FrameReadout, build_report
from pipeline.report.answer import DECIDES_COLUMN, DECODER_COLUMN, glance_header, glance_rows
from pipeline.report.decision_time import (
    DECISIONS_FIELD,
    LATENCY_STEM,
    TRAINED_TEXT,
    DesignDecisions,
    earliest_not_below,
    gather_decisions,
)
from pipeline.report.document import report_blocks
from pipeline.report.figures import draw_report
from pipeline.report.render import render_markdown
from pipeline.results.decoder_energy import decoder_energy_j
from tests.latency_helpers import FFNN_MACS, FFNN_UPDATES, SPIKING_ACS, TIMES, with_decisions
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes

SWEEPS = {"threshold": PAPER_LIKE_SWEEPS["threshold"]}


@pytest.fixture(scope="module")
def report():
    cubes = {n: with_decisions(c) for n, c in make_cubes(SWEEPS).items()}
    return build_report(cubes, frame=FrameReadout(12, 2000.0))


def test_each_model_gets_its_curve_at_its_best_design_at_the_times_it_decides(report):
    curves = {c.model: c for c in report.latency}
    assert set(curves) == {"ffnn", "cnn"}
    for answer in report.answers:
        assert curves[answer.model].key == answer.best.design.key
    assert curves["ffnn"].decision_s.tolist() == [0.5, 1.0]  # window boundaries only
    assert curves["cnn"].decision_s.tolist() == TIMES.tolist()
    cnn = curves["cnn"]
    # The best CNN point gets 78 of 120 right at the full touch (0.6 + 0.05 bonus).
    assert np.allclose(cnn.mean * 120, [39, 62, 76, 78])
    assert np.all((cnn.low <= cnn.mean) & (cnn.mean <= cnn.high))
    assert cnn.interval == "Wilson score"


def test_the_earliest_decision_not_below_the_full_touch_is_found_by_paired_tests(report):
    curves = {c.model: c for c in report.latency}
    cnn = curves["cnn"].earliest
    assert (cnn.decision_s, cnn.full_s, cnn.tested, cnn.stopped_by) == (0.75, 1.0, 2, 0.5)
    assert (cnn.versus_full.only_a, cnn.versus_full.only_b) == (0, 2)
    assert math.isclose(cnn.versus_full.p_value, 0.5)  # exact McNemar, 2 discordant
    ffnn = curves["ffnn"].earliest
    assert (ffnn.decision_s, ffnn.versus_full, ffnn.stopped_by) == (1.0, None, 0.5)


# The rule as docs/model.md and the module docstring state it, on decisions made by hand: 120
# recordings (12 classes of 10), one repeat, all right at the full touch (the last of 5 times).
# At each earlier time the first ``WRONG[k]`` recordings are wrong, the rest right, so that the
# paired test against the full touch has ``WRONG[k]`` discordant pairs, all losses: two-sided
# exact McNemar p = 0.5 for 2, 2 * 0.5**20 for 20.
N = 120
TIMES_S = np.array([1.0, 2.0, 3.0, 4.0, 5.0])


def made(wrong: list[int | None], repeats: int = 1) -> DesignDecisions:
    """Decisions right at every time but on the first ``wrong[k]`` recordings at time ``k``
    (``None``: no decision at all at that time; the last time, the full touch, all right)."""
    correct = np.ones((TIMES_S.size, repeats, N), dtype=np.int8)
    for k, n_wrong in enumerate(wrong):
        if n_wrong is None:
            correct[k] = -1
        else:
            correct[k, :, :n_wrong] = 0
    return DesignDecisions(
        decision_s=TIMES_S,
        correct=correct,
        confidence=np.where(correct >= 0, 0.9, np.nan),
        labels=np.repeat(np.arange(12), 10),
        operations=np.full((3, TIMES_S.size), np.nan),
        trained=DecisionTraining.ALONG_TOUCH,
    )


def test_the_earliest_decision_is_the_one_tested_before_the_first_significantly_below():
    # From the full touch (5 s) backwards: 4 s loses 2 (p = 0.5), 3 s loses 20 (p < 0.05) and
    # ends the sequence; 2 s, which loses none, is after the end and never chosen.
    found = earliest_not_below(made([50, 0, 20, 2, 0]), "k", "ffnn")
    assert (found.decision_s, found.index, found.full_s) == (4.0, 3, 5.0)
    assert (found.tested, found.stopped_by) == (2, 3.0)
    assert (found.versus_full.only_a, found.versus_full.only_b) == (0, 2)
    assert math.isclose(found.versus_full.p_value, 0.5)
    assert math.isclose(found.versus_full.difference, -2 / N)


def test_the_full_touch_is_the_earliest_when_the_time_just_before_is_significantly_below():
    found = earliest_not_below(made([0, 0, 0, 20, 0]), "k", "ffnn")
    assert (found.decision_s, found.versus_full, found.tested, found.stopped_by) == (
        5.0,
        None,
        1,
        4.0,
    )


def test_a_loss_not_significant_at_alpha_and_a_significant_gain_do_not_end_the_sequence():
    # 6 losses of 6 discordant pairs: p = 2 * 0.5**6 = 0.031 < 0.05, ends; 5 losses: p = 0.0625,
    # does not. A time significantly above the full touch (the full touch wrong on 30 that
    # the earlier time gets right) is not below it.
    assert earliest_not_below(made([6, 5, 5, 5, 0]), "k", "ffnn").decision_s == 2.0
    gaining = made([0, 0, 0, 0, 0])
    gaining.correct[-1, :, :30] = 0
    found = earliest_not_below(gaining, "k", "ffnn")
    assert (found.decision_s, found.tested, found.stopped_by) == (1.0, 4, None)
    assert found.versus_full.difference > 0 and found.versus_full.p_value < 0.05


def test_a_time_with_no_recording_in_common_ends_the_sequence_without_a_verdict():
    found = earliest_not_below(made([0, 0, None, 0, 0]), "k", "ffnn")
    assert (found.decision_s, found.tested, found.stopped_by) == (4.0, 1, None)


def test_with_several_repeats_the_paired_bootstrap_decides():
    # Two repeats alike: 20 losses in each are far outside the bootstrap's 95 %; 1 is not.
    found = earliest_not_below(made([0, 20, 1, 1, 0], repeats=2), "k", "ffnn")
    assert (found.decision_s, found.stopped_by) == (3.0, 2.0)
    assert "McNemar" not in found.versus_full.method and found.versus_full.p_value >= 0.05


def test_early_exit_rows_and_energies_follow_the_hand_made_confidences(report):
    cnn = next(c for c in report.latency if c.model == "cnn")
    rows = {row.threshold: row for row in cnn.exits}
    # At 0.99 no right decision passes before the full touch (0.99 there): all at 1 s.
    assert rows[0.99].mean_decision_s == 1.0 and math.isclose(rows[0.99].accuracy, 78 / 120)
    # At 0.5 a recording right at 0.25 s exits there (39), at 0.5 s (23), 0.75 s (14), 1 s (2);
    # the 42 wrong at the full touch never pass (0.4) and decide at 1 s.
    expected = (39 * 0.25 + 23 * 0.5 + 14 * 0.75 + 2 * 1.0 + 42 * 1.0) / 120
    assert math.isclose(rows[0.5].mean_decision_s, expected)
    assert math.isclose(rows[0.5].readout_j, cnn.readout_power_w * expected)
    full = decoder_energy_j(SPIKING_ACS * 1.0, 0.0, 400.0 * 1.0)
    assert math.isclose(cnn.energy_at(cnn.full).low_j, full.low_j)
    ffnn = next(a for a in report.answers if a.model == "ffnn")
    band = ffnn.best.decoder_energy
    assert math.isclose(band.low_j, decoder_energy_j(0, FFNN_MACS, FFNN_UPDATES).low_j)


def test_the_answer_table_gains_the_decoder_energy_and_the_report_its_section(report):
    answer = report.answers[0]
    header = glance_header(answer)
    assert header[header.index("energy per decision") + 1] == DECODER_COLUMN
    assert all(len(row) == len(header) for row in glance_rows(answer))
    # "decides after" beside the accuracy: the best design's earliest decision, as its curve's
    decides = header.index(DECIDES_COLUMN)
    assert header[decides - 1] == "accuracy [95 % interval]"
    curve = next(c for c in report.latency if c.model == answer.model)
    best = next(row for row in glance_rows(answer) if "best" in row[0])
    assert best[decides] == f"{curve.earliest.decision_s:.3g} s"
    assert report.figure_stems[-1] == LATENCY_STEM
    text = render_markdown(report_blocks(report, set(report.figure_stems), version="t"))
    time_section = text[text.index("## What accuracy costs in time") :]
    for title in ("Accuracy against decision time", "Early exit", "Energy per decision"):
        assert f"### {title}" in time_section
    assert "figures/latency.png" in time_section and "ODIN" in time_section
    assert not re.search(r"\bnan\b", text, flags=re.I)
    assert "decoder and readout together" in time_section


def test_the_section_says_which_training_the_decoders_had():
    """The cubes of tests.report_helpers were trained for the full touch; a cube written before
    the choice (no coordinate) was too; one trained along the touch says so."""
    cubes = {n: with_decisions(c) for n, c in make_cubes(SWEEPS).items()}
    old = {n: c.drop_vars(DECISIONS_FIELD) for n, c in cubes.items()}
    along = {n: c.assign_coords({DECISIONS_FIELD: "along_touch"}) for n, c in cubes.items()}
    for made_by, trained in ((cubes, "full_touch"), (old, "full_touch"), (along, "along_touch")):
        report = build_report(made_by)
        assert {c.trained for c in report.latency} == {DecisionTraining(trained)}
        text = render_markdown(report_blocks(report, set(), version="t"))
        assert f"The decoders were {TRAINED_TEXT[DecisionTraining(trained)]}." in text


def test_the_latency_figure_is_drawn():
    cubes = {n: with_decisions(c) for n, c in make_cubes(SWEEPS, models=("cnn",)).items()}
    report = build_report(cubes)
    figures = draw_report(report)
    assert list(figures) == list(report.figure_stems) and LATENCY_STEM in figures
    axes = figures[LATENCY_STEM].axes[0]
    assert axes.get_xlabel() == "decision time (s of touch)"


def test_cubes_without_decisions_or_operations_add_what_they_hold():
    plain = build_report(make_cubes(SWEEPS))
    assert plain.latency == () and LATENCY_STEM not in plain.figure_stems
    assert DECODER_COLUMN not in glance_header(plain.answers[0])
    assert DECIDES_COLUMN not in glance_header(plain.answers[0])
    cubes = {n: with_decisions(c, operations=False) for n, c in make_cubes(SWEEPS).items()}
    assert all(np.isnan(d.operations).all() for d in gather_decisions(cubes).values())
    report = build_report(cubes)
    assert len(report.latency) == 2
    assert DECODER_COLUMN not in glance_header(report.answers[0])
    text = render_markdown(report_blocks(report, set(report.figure_stems), version="t"))
    assert "unknown" in text[text.index("### Early exit") :]


def test_curves_of_both_trainings_say_which_model_had_which():
    from types import SimpleNamespace

    from pipeline.report.decision_time import training_sentence

    along, full = DecisionTraining.ALONG_TOUCH, DecisionTraining.FULL_TOUCH
    curves = [
        SimpleNamespace(model="ffnn", trained=along),
        SimpleNamespace(model="cnn", trained=full),
        SimpleNamespace(model="snn", trained=along),
    ]
    assert training_sentence(curves) == (
        f"FFNN, SNN: {TRAINED_TEXT[along]}. CNN: {TRAINED_TEXT[full]}."
    )
