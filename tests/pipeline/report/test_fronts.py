"""Hardware cost fronts: which designs are on the front, which are marked as indistinguishable.

The cubes of test_answer.py: on the data-rate front (cheapest first) 0.3 V (60 %), 0.15 V (88 %),
0.09 V (90 %). Off it: 0.04 V (89 %, dominated by 0.09 V, one discordant recording: marked) and
0.05 V (80 %, twelve discordant recordings: significantly less accurate, not marked).
"""

import math

import pytest

from pipeline.report import FrameReadout, build_report
from pipeline.report.designs import Cost
from pipeline.report.document import report_blocks
from pipeline.report.figures import front_figure
from pipeline.report.render import render_markdown
from pipeline.results.readout_constants import EnergyModel
from pipeline.results.readout_power import frame_power_w
from tests.pipeline.report.test_answer import SWEEPS, by_threshold
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes


@pytest.fixture(scope="module")
def report():
    cubes = make_cubes(SWEEPS, by_threshold, models=("ffnn",))
    return build_report(cubes, frame=FrameReadout(12, 2000.0))


def front(report, cost):
    return next(f for f in report.fronts if f.cost is cost)


def threshold(point):
    return float(point.design.settings[0].value)


def test_front_and_marked_points(report):
    found = front(report, Cost.DATA_RATE)
    assert [threshold(p) for p in found.front("ffnn")] == [0.3, 0.15, 0.09]
    off = {threshold(p): p for p in found.points if not p.on_front}
    assert set(off) == {0.04, 0.05}
    at_009 = next(p for p in found.points if threshold(p) == 0.09)
    assert {p.dominated_by for p in off.values()} == {at_009.design.key}
    assert off[0.04].indistinguishable and not off[0.05].indistinguishable
    assert (off[0.04].versus_front.only_a, off[0.04].versus_front.only_b) == (0, 1)
    assert off[0.05].versus_front.p_value == pytest.approx(2 * 0.5**12)
    assert [threshold(p) for p in found.marked] == [0.04]


def test_every_cost_has_a_front_and_the_frame_readout_is_a_reference(report):
    # A threshold sweep names no mismatch: no design has an area to be on a front.
    assert [f.cost for f in report.fronts] == [c for c in Cost if c is not Cost.AREA]
    power = front(report, Cost.POWER)
    ((label, value),) = power.references
    assert label == "frame readout, 4 taxels"
    assert value == frame_power_w(4, 2000.0, 12, EnergyModel())
    assert front(report, Cost.DATA_RATE).references == (("frame readout, 4 taxels", 96000.0),)
    assert front(report, Cost.BITS).references == ()


def test_marked_points_are_drawn_with_their_own_marker_and_listed(report):
    found = front(report, Cost.DATA_RATE)
    ax = front_figure(found, report.chance).axes[0]
    labels = ax.get_legend_handles_labels()[1]
    marked = "FFNN off the front, not significantly less accurate"
    assert marked in labels and "FFNN front (cheapest design per accuracy)" in labels
    assert "frame readout, 4 taxels" in labels
    container = next(c for c in ax.containers if c.get_label() == marked)
    line = container.lines[0]
    assert line.get_marker() == "D" and line.get_markerfacecolor() == "none"
    assert [float(v) for v in line.get_xdata()] == [700.0 / 0.04]
    markdown = render_markdown(report_blocks(report, set(), version="t"))
    section = markdown.split("### Accuracy against data rate")[1].split("###")[0]
    rows = [r for r in section.splitlines() if r.startswith("| FFNN")]
    assert len(rows) == 4  # three on the front, one marked; 0.05 V is not listed
    assert "readout.threshold_v = 0.04 V" in rows[-1] and "not significantly" in rows[-1]
    assert not any("0.05 V" in r for r in rows)


def test_a_zero_event_rate_is_priced_not_divided_by():
    cubes = make_cubes(SWEEPS, by_threshold, models=("ffnn",), rates=lambda scene: (0.0, 0.0))
    report = build_report(cubes, frame=FrameReadout(12, 2000.0))
    (answer,) = report.answers
    assert answer.by_data_rate.data_rate_bps == 0.0
    assert math.isinf(answer.by_data_rate.data_rate_ratio)
    markdown = render_markdown(report_blocks(report, set(), version="t"))
    assert "nan" not in markdown.lower() and "inf" not in markdown.split("## Against")[0]


def test_the_area_front_is_the_pelgrom_area_of_the_mismatch_a_design_names():
    from pipeline.results.matched_area import array_area_m2, taxel_area_m2

    found = build_report(make_cubes({"mismatch": PAPER_LIKE_SWEEPS["mismatch"]}))
    area = front(found, Cost.AREA)
    sigmas = sorted({p.design.mismatch_sigma_rel for p in area.points})
    assert sigmas == [0.1, 0.2, 0.3]  # sigma_rel 0 asks for perfect matching: no area
    for point in area.points:
        design = point.design
        assert point.cost == pytest.approx(
            array_area_m2(design.n_taxels, design.mismatch_sigma_rel, design.threshold_v)
        )
        assert design.taxel_area_m2 == pytest.approx(
            taxel_area_m2(design.mismatch_sigma_rel, design.threshold_v)
        )
    # Less mismatch costs area and, here, buys accuracy: every design is on the front.
    assert all(p.on_front for p in area.points)
