"""The whole report from cubes: cubes that do not describe themselves, the paper grid's sweeps,
and the edge cases (one point, one model, one class, no per-recording results)."""

import math
import re

import pytest

from pipeline.design.grid import load_grid
from pipeline.errors import EskinError
from pipeline.report import FrameReadout, Panel, build_report
from pipeline.report.document import report_files
from pipeline.report.figures import draw_report
from pipeline.run.entries import RecordingsInfo
from pipeline.run.stages import cache_key
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes, paper_like_accuracy


def test_cubes_that_do_not_describe_themselves_are_refused():
    cubes = make_cubes({"threshold": PAPER_LIKE_SWEEPS["threshold"]})
    cubes["threshold"] = cubes["threshold"].drop_vars("result_key")
    with pytest.raises(EskinError, match="threshold .*older eskin-sweep.*eskin sweep"):
        build_report(cubes)


def test_paper_grid_observation_sweep_reuses_the_operating_points_spike_trains():
    grid = load_grid("paper")
    sweep = next(s for s in grid.sweeps if s.name == "observation")
    assert sweep.axes[0].field == "coding.n_windows" and sweep.axes[0].values[0] == 1
    spikes = {cache_key(p.scene, "spikes") for p in grid.points() if p.sweep == "observation"}
    assert spikes == {cache_key(grid.base, "spikes")}
    assert paper_like_accuracy(grid.base) > 0  # the helper accepts the paper scene too


ONE_POINT = {"one": {"axes": {"readout.threshold_v": [0.09]}}}
SMALL = {k: PAPER_LIKE_SWEEPS[k] for k in ("threshold", "noise")}
ONE_CLASS = RecordingsInfo("synthetic", ("only",), 2000.0)


@pytest.mark.parametrize(
    "case",
    [
        {"sweeps": ONE_POINT},
        {"sweeps": ONE_POINT, "predictions": False},
        {"sweeps": SMALL, "models": ("cnn",)},
        {"sweeps": SMALL, "predictions": False},
        {"sweeps": SMALL, "recordings": ONE_CLASS},
        {"sweeps": SMALL, "recordings": None, "models": ("ffnn",)},
        {"sweeps": ONE_POINT, "rates": lambda scene: (math.nan, math.nan)},
    ],
    ids=[
        "one point",
        "one point, no predictions",
        "one model",
        "no predictions",
        "one class",
        "nothing stated",
        "no rates",
    ],
)
def test_edge_cases_give_a_whole_report_and_never_print_nan(case):
    report = build_report(make_cubes(**case), frame=FrameReadout(12, 2000.0))
    figures = draw_report(report)
    assert list(figures) == list(report.figure_stems)
    files = report_files(report, figures, version="t")
    for name in ("report.md", "report.html"):
        text = files[name].decode()
        words = re.sub(r"<svg.*?</svg>", "", text, flags=re.S)  # SVG path data is not text
        assert not re.search(r"\bnan\b", words, flags=re.I), name
        assert "## The answer" in words or "<h2>The answer" in words
    assert len(report.answers) == len(case.get("models", ("ffnn", "cnn")))


def test_one_point_is_the_answer_with_nothing_to_compare():
    report = build_report(make_cubes(ONE_POINT))
    for answer in report.answers:
        assert answer.best is answer.by_data_rate and answer.comparisons == 0
    assert [p.sweep for p in report.sweep_plots] == []  # a threshold sweep: Fig. 7a
    assert report.panels == (Panel.THRESHOLD,)


def test_one_class_has_chance_one():
    report = build_report(make_cubes(ONE_POINT, recordings=ONE_CLASS))
    assert report.n_classes == 1 and report.chance == 1.0
