"""Figures: one per stem with data, drawn (not blank), labelled with units, chance on every
accuracy axis, 95 % intervals as error bars, a curve for any 1-D sweep, a heat map for 2-D."""

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from pipeline.report import Panel, build_report
from pipeline.report.designs import Cost
from pipeline.report.figures import YLABEL, draw_report
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes

CHANCE_PERCENT = 100 / 12


@pytest.fixture(scope="module")
def cubes():
    return make_cubes()


@pytest.fixture(scope="module")
def figures(cubes):
    return draw_report(build_report(cubes))


def ink(figure) -> float:
    """Fraction of pixels that are not white."""
    figure.canvas.draw()
    rgb = np.asarray(figure.canvas.buffer_rgba())[..., :3]
    return float(np.mean(np.any(rgb < 250, axis=-1)))


def accuracy_axes(figure):
    return [ax for ax in figure.axes if ax.get_ylabel() == YLABEL]


def chance_lines(ax):
    return [
        line
        for line in ax.get_lines()
        if np.allclose(line.get_ydata(), CHANCE_PERCENT) and line.get_linestyle() == "--"
    ]


def test_every_figure_is_drawn_and_not_blank(figures):
    panels = [p.value for p in Panel]
    fronts = [c.stem for c in Cost]
    assert list(figures) == [*panels, "sweep_noise", *fronts]
    for stem, figure in figures.items():
        assert ink(figure) > 0.02, stem


def test_axes_are_labelled_with_units(figures):
    for stem, figure in figures.items():
        for ax in figure.axes:
            if ax.get_xlabel():  # secondary axes label themselves
                assert "(" in ax.get_xlabel() and ")" in ax.get_xlabel(), stem
        assert accuracy_axes(figure), stem
    main = figures[Panel.THRESHOLD.value].axes[0]
    top = [ax for ax in main.child_axes if ax.get_xlabel().endswith("(bit)")]
    assert top, "Fig. 7a has the equivalent bit resolution on a second axis"


def test_every_accuracy_axis_has_a_chance_line(figures):
    for stem, figure in figures.items():
        for ax in accuracy_axes(figure):
            assert len(chance_lines(ax)) == 1, stem
            assert "chance (8.33 %)" in ax.get_legend_handles_labels()[1], stem


def test_error_bars_are_the_95_percent_interval(cubes, figures):
    ax = figures[Panel.WINDOW.value].axes[0]
    labels = ax.get_legend_handles_labels()[1]
    assert {"FFNN", "CNN"} <= set(labels)
    container = next(c for c in ax.containers if c.get_label() == "FFNN")
    (bars,) = container.lines[2]
    ends = np.array([segment[:, 1] for segment in bars.get_segments()])  # (points, 2) in %
    window = cubes["window"].sel(model="ffnn").sortby("window_s")
    np.testing.assert_allclose(ends[:, 0], 100 * window["accuracy_low"].values)
    np.testing.assert_allclose(ends[:, 1], 100 * window["accuracy_high"].values)


def test_missing_sweeps_draw_no_figure():
    sweeps = {"threshold": PAPER_LIKE_SWEEPS["threshold"]}
    stems = set(draw_report(build_report(make_cubes(sweeps))))
    # No design names a threshold mismatch: none has an area, and there is no area front.
    assert stems == {Panel.THRESHOLD.value} | {c.stem for c in Cost if c is not Cost.AREA}


def test_any_one_dimensional_sweep_gets_its_own_curve_titled_from_its_field():
    sweeps = {
        "amp": {"axes": {"readout.effects.amplifier_noise.sigma_v": [0.01, 0.02, 0.04]}},
        "per_class": {"axes": {"dataset.recordings_per_class": [4, 6]}},
        "polarity": {"axes": {"coding.polarity": ["merged", "split"]}},
    }
    cubes = make_cubes(sweeps)
    report = build_report(cubes)
    plots = {p.sweep: p for p in report.sweep_plots}
    assert set(plots) == set(sweeps)
    amp = cubes["amp"]["sigma_v"].attrs
    assert plots["amp"].xlabel == (
        f"{amp['long_name']} (readout.effects.amplifier_noise.sigma_v, {amp['units']})"
    )
    assert plots["amp"].title.startswith(f"Accuracy against {amp['long_name']}")
    assert plots["polarity"].ticks == ("merged", "split")
    figures = draw_report(report)
    ax = figures["sweep_amp"].axes[0]
    assert ax.get_xlabel().replace("\n", " ") == plots["amp"].xlabel and chance_lines(ax)
    assert [t.get_text() for t in figures["sweep_polarity"].axes[0].get_xticklabels()] == [
        "merged",
        "split",
    ]
    per_class = figures["sweep_per_class"].axes[0]
    assert "dataset.recordings_per_class" in per_class.get_xlabel().replace("\n", " ")


def test_a_two_axis_sweep_gets_an_annotated_heat_map_per_model():
    sweeps = {
        "mismatch_by_size": {
            "axes": {
                "readout.effects.threshold_mismatch.sigma_rel": [0.0, 0.1, 0.3],
                "array.rows": [2, 4],
            }
        }
    }
    cubes = make_cubes(sweeps)
    report = build_report(cubes)
    (found,) = report.heatmaps
    assert found.models == ("ffnn", "cnn") and found.accuracy.shape == (2, 3, 2)
    expected = cubes["mismatch_by_size"]["accuracy_mean"].transpose("model", "sigma_rel", "rows")
    np.testing.assert_array_equal(found.accuracy, expected.values)
    figure = draw_report(report)["heatmap_mismatch_by_size"]
    panels = [ax for ax in figure.axes if ax.get_title() in ("FFNN", "CNN")]
    assert len(panels) == 2
    for ax, values in zip(panels, 100 * expected.values, strict=True):
        texts = [t.get_text() for t in ax.texts]
        assert texts == [f"{v:.1f}" for v in values.ravel()]
        assert [t.get_text() for t in ax.get_yticklabels()] == ["0", "0.1", "0.3"]
        assert "array.rows" in ax.get_xlabel() and "sigma_rel" in ax.get_ylabel().replace("\n", "")
    assert ink(figure) > 0.05


def test_figures_are_on_their_own_agg_canvas_not_pyplot(figures):
    # pyplot figures get a canvas manager (global figure registry); ours have none.
    for figure in figures.values():
        assert isinstance(figure.canvas, FigureCanvasAgg) and figure.canvas.manager is None


def legend_texts(ax):
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_every_figure_draws_its_models_in_their_declared_order():
    # A cube that trained the CNN alone comes first (cubes are read by name): the designs meet
    # the CNN first, yet every panel, front and heat map puts the FFNN first, as the Model enum
    # declares them.
    cnn_only = make_cubes({"threshold": PAPER_LIKE_SWEEPS["threshold"]}, models=("cnn",))
    both = make_cubes(
        {
            "window": PAPER_LIKE_SWEEPS["window"],
            "noise": PAPER_LIKE_SWEEPS["noise"],
            "grid2": {"axes": {"readout.threshold_v": [0.05, 0.2], "coding.window_s": [0.1, 0.2]}},
        }
    )
    report = build_report({"a_threshold": cnn_only["threshold"], **both})
    assert [a.model for a in report.answers] == ["cnn", "ffnn"]  # as met
    drawn = draw_report(report)
    window = legend_texts(drawn[Panel.WINDOW.value].axes[0])
    assert [t for t in window if t in ("FFNN", "CNN")] == ["FFNN", "CNN"]
    for front in report.fronts:
        assert front.models[0] == "cnn"  # the points' order
        # matplotlib lists lines before error bars: within each kind of entry, FFNN first.
        labels = legend_texts(drawn[front.cost.stem].axes[0])
        kinds = {}
        for label in labels:
            model, _, kind = label.partition(" ")
            if model in ("FFNN", "CNN"):
                kinds.setdefault(kind, []).append(model)
        assert any(len(models) == 2 for models in kinds.values()), labels
        assert all(
            models == ["FFNN", "CNN"][-len(models) :] or models == ["FFNN"]
            for models in kinds.values()
        ), labels
    (heat,) = report.heatmaps
    titles = [ax.get_title() for ax in drawn[heat.stem].axes if ax.get_title()]
    assert titles == ["FFNN", "CNN"]
    for ax in drawn[Panel.SPIKE_METRICS.value].axes:
        assert [t.split(":")[0] for t in legend_texts(ax) if ":" in t] == ["FFNN", "CNN"]


def test_deployments_are_panels_in_their_declared_order_whatever_the_curves_order():
    import dataclasses

    from pipeline.report.figures import grouped_figure

    report = build_report(make_cubes({"threshold": PAPER_LIKE_SWEEPS["threshold"]}))
    cnn, ffnn = sorted(report.curves[Panel.THRESHOLD], key=lambda c: c.model)
    shuffled = [
        dataclasses.replace(curve, group=group)
        for group in ("shared", "robust", "per_chip")  # neither declared nor alphabetical
        for curve in (cnn, ffnn)
    ]
    figure = grouped_figure("t", shuffled, "x", None)
    assert [ax.get_title() for ax in figure.axes] == ["per_chip", "shared", "robust"]
    assert legend_texts(figure.axes[0])[:2] == ["FFNN", "CNN"]


def test_the_svg_keeps_the_pngs_layout_and_the_figure_its_layout_engine(figures, monkeypatch):
    from pipeline.report.figures import figure_images

    figure = next(iter(figures.values()))
    engine = figure.get_layout_engine()
    layouts = []
    execute = engine.execute
    monkeypatch.setattr(engine, "execute", lambda fig: layouts.append(fig) or execute(fig))
    png, svg = figure_images(figure)
    assert png.startswith(b"\x89PNG") and svg.lstrip().startswith("<?xml")
    assert layouts == [figure]  # laid out for the PNG only: the SVG keeps that layout
    assert figure.get_layout_engine() is engine  # and the next save lays it out again
