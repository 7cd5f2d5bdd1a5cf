"""Figures: one per panel with data, each drawn (not blank), labelled with units, no pyplot."""

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from pipeline.report import Panel, build_report
from pipeline.report.figures import draw_report
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes


@pytest.fixture(scope="module")
def figures():
    return draw_report(build_report(make_cubes()))


def ink(figure) -> float:
    """Fraction of pixels that are not white."""
    figure.canvas.draw()
    rgb = np.asarray(figure.canvas.buffer_rgba())[..., :3]
    return float(np.mean(np.any(rgb < 250, axis=-1)))


def test_every_panel_is_drawn_and_not_blank(figures):
    assert list(figures) == list(Panel)
    for panel, figure in figures.items():
        assert ink(figure) > 0.02, panel


def test_axes_are_labelled_with_units(figures):
    for panel, figure in figures.items():
        for ax in figure.axes:
            if ax.get_xlabel():  # secondary axes label themselves
                assert "(" in ax.get_xlabel() and ")" in ax.get_xlabel(), panel
        assert "accuracy (%" in figure.axes[0].get_ylabel()
    main = figures[Panel.THRESHOLD].axes[0]
    top = [ax for ax in main.child_axes if ax.get_xlabel().endswith("(bit)")]
    assert top, "Fig. 7a has the equivalent bit resolution on a second axis"


def test_both_models_and_error_bars_are_drawn(figures):
    labels = figures[Panel.WINDOW].axes[0].get_legend_handles_labels()[1]
    assert {"FFNN", "CNN"} <= set(labels)
    assert figures[Panel.WINDOW].axes[0].containers  # errorbar containers


def test_missing_sweeps_draw_no_figure():
    sweeps = {"threshold": PAPER_LIKE_SWEEPS["threshold"]}
    assert set(draw_report(build_report(make_cubes(sweeps)))) == {Panel.THRESHOLD, Panel.COST}


def test_figures_are_on_their_own_agg_canvas_not_pyplot(figures):
    # pyplot figures get a canvas manager (global figure registry); ours have none.
    for figure in figures.values():
        assert isinstance(figure.canvas, FigureCanvasAgg) and figure.canvas.manager is None
