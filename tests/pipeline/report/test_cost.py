"""What accuracy costs: distinct designs priced per model, the Pareto front, observation time."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pipeline.report import Panel, build_report
from pipeline.report.cost import pareto_front, time_to_accuracy
from pipeline.report.designs import Cost, cost
from pipeline.results.readout_constants import EnergyModel
from tests.report_helpers import make_cubes


def test_designs_are_distinct_and_priced_per_model():
    cubes = make_cubes()
    report = build_report(cubes)
    keys = [d.key for d in report.designs]
    assert len(keys) == len(set(keys))
    shared = [d for d in report.designs if len(d.sweeps) > 1]
    assert shared, "the operating point is in several sweeps and must be counted once"
    (base,) = shared
    assert set(base.sweeps) == {"threshold", "window"}
    assert base.label == "readout.threshold_v = 0.09 V, coding.window_s = 0.1 s"
    one = next(d for d in report.designs if d.label == "array.rows = 1, array.cols = 1")
    # readout (per taxel) + coding + train_ffnn: neither train_cnn, which is not the FFNN's
    # cost, nor the load, which the worker shares among its points.
    assert cost(one, "ffnn", Cost.COMPUTE, EnergyModel()) == 0.01 * 1 + 0.02 + 0.5
    compute = next(f for f in report.fronts if f.cost is Cost.COMPUTE)
    assert compute.front("ffnn")[0].design is one
    total = report.sweep_cost
    assert total.n_points == len(report.designs) and total.n_unpaid == 0
    # The load, shared by every point, was paid once: it counts once.
    (load,) = [s for s in total.stages if s.stage == "load"]
    assert (load.own_s, load.shared_s) == (0.0, pytest.approx(0.1))
    assert total.shared_s == pytest.approx(0.1)


def test_the_sweeps_cost_of_older_cubes_counts_their_work_seconds():
    """Cubes of results that predate paid seconds: each point's load counts, as measured."""
    total = build_report(make_cubes(paid=False)).sweep_cost
    assert total.n_unpaid == total.n_points > 1
    (load,) = [s for s in total.stages if s.stage == "load"]
    assert load.shared_s == pytest.approx(0.1 * total.n_points)


def test_the_sweeps_cost_reads_the_layout_before_paid_seconds():
    """A stored cube of the older layout: ``seconds`` (axes..., stage) of work seconds."""
    cubes = make_cubes()
    paid_total = build_report(cubes).sweep_cost
    old = {
        name: cube.drop_vars(["seconds", "charge"]).rename({"work_seconds": "seconds"})
        for name, cube in cubes.items()
    }
    total = build_report(old).sweep_cost
    assert total.n_unpaid == total.n_points == paid_total.n_points
    assert total.total_s == pytest.approx(paid_total.total_s + 0.1 * (total.n_points - 1))


@given(st.lists(st.tuples(st.integers(0, 20), st.integers(0, 20)), min_size=1, max_size=30))
def test_pareto_front_is_the_cheapest_design_per_accuracy(pairs):
    seconds = np.array([float(s) for s, _ in pairs])
    accuracy = np.array([a / 20 for _, a in pairs])
    front = pareto_front(seconds, accuracy)
    for i in range(len(pairs)):
        cheaper_or_equal = (seconds <= seconds[i]) & (np.arange(len(pairs)) != i)
        beaten = np.any(cheaper_or_equal & (accuracy >= accuracy[i]) & front)
        if front[i]:
            assert not np.any(cheaper_or_equal & (accuracy > accuracy[i]))
        else:
            assert beaten  # every point off the front has a front point as good and as cheap
    assert front[np.argmax(accuracy)] or np.sum(accuracy == accuracy.max()) > 1


def test_time_to_accuracy_finds_the_first_swept_time():
    report = build_report(make_cubes())
    (curve, *_) = report.curves[Panel.OBSERVATION]
    # n_windows 1, 2, 5 of 0.1 s; accuracy 0.6 - 0.2 / n: 0.4, 0.5, 0.56.
    np.testing.assert_allclose(curve.x, [0.1, 0.2, 0.5])
    rows = {r.fraction: r.seconds for r in time_to_accuracy([curve], (0.7, 0.85, 1.0, 1.1))}
    assert rows == {0.7: 0.1, 0.85: 0.2, 1.0: 0.5, 1.1: None}
