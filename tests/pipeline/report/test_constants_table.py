"""The report's hardware constants: a designer's A_VT moves the area front by the square of the
ratio; the report lists every constant it used and says which were overridden."""

import pytest

from pipeline.report import build_report
from pipeline.report.constants_table import CONSTANTS_COLUMNS, CONSTANTS_TITLE, constants_rows
from pipeline.report.designs import Cost, area_sentence
from pipeline.report.document import report_blocks
from pipeline.report.render import render_markdown
from pipeline.results.hardware_constants import DECLARED, Constants
from pipeline.results.matched_area import A_VT_V_M
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes

RATIO = 2.5
FOUNDRY = "foundry X, 180 nm matching report"


def area_front(report):
    return next(f for f in report.fronts if f.cost is Cost.AREA)


@pytest.fixture(scope="module")
def reports():
    cubes = make_cubes({"mismatch": PAPER_LIKE_SWEEPS["mismatch"]})
    mine = Constants().overriding("a_vt_v_m", RATIO * A_VT_V_M, FOUNDRY)
    return build_report(cubes), build_report(cubes, constants=mine)


def test_a_designers_pelgrom_coefficient_moves_the_area_front_by_the_square_of_the_ratio(reports):
    declared, mine = area_front(reports[0]), area_front(reports[1])
    assert len(declared.points) == len(mine.points) >= 3
    for before, after in zip(declared.points, mine.points, strict=True):
        assert (before.design.key, before.model) == (after.design.key, after.model)
        assert after.cost == pytest.approx(RATIO**2 * before.cost, rel=1e-12)
        assert after.on_front == before.on_front  # every area scales alike: the same front
    for model in declared.models:
        costs = [p.cost for p in mine.front(model)]
        assert costs == pytest.approx([RATIO**2 * p.cost for p in declared.front(model)])
    # Nothing else moves: the readout's power is priced by other constants.
    assert reports[0].energy == reports[1].energy and reports[0].decoder == reports[1].decoder


def test_the_area_sentence_states_the_a_vt_used_and_its_source(reports):
    assert f"A_VT = {A_VT_V_M * 1e9:g} mV um for 180 nm" in area_sentence()
    said = area_sentence(reports[1].constants)
    assert f"A_VT = {RATIO * 5:g} mV um ({FOUNDRY})" in said


def test_the_report_lists_every_constant_and_which_were_overridden(reports):
    rows = constants_rows(reports[1].constants)
    assert [r[0] for r in rows] == list(DECLARED)
    assert all(len(r) == len(CONSTANTS_COLUMNS) for r in rows)
    (overridden,) = [r for r in rows if r[2] == "yes"]
    assert overridden == (
        "a_vt_v_m",
        "12.5 mV um",
        "yes",
        DECLARED["a_vt_v_m"].parameter.what,
        FOUNDRY,
    )
    assert all(r[4] == DECLARED[r[0]].parameter.source for r in rows if r[2] == "no")
    mine = render_markdown(report_blocks(reports[1], set(), version="t"))
    section = mine.split(f"## {CONSTANTS_TITLE}")[1]
    assert "1 of 14 were overridden: a_vt_v_m = 12.5 mV um (declared 5 mV um)." in section
    plain = render_markdown(report_blocks(reports[0], set(), version="t"))
    assert "All 14 are as declared" in plain.split(f"## {CONSTANTS_TITLE}")[1]
