"""Objectives of a design search read from trial cubes: over chips, the comparator area, and
decision time and decoder energy under early exit."""

import math

import numpy as np
import xarray as xr

from pipeline.design.space import MISMATCH_FIELD, Direction, Metric, Objective
from pipeline.results.decoder_energy import decoder_energy_j
from pipeline.results.early_exit import EXIT_CONFIDENCE, exit_objectives
from pipeline.results.matched_area import array_area_m2
from pipeline.results.objectives import objective_values
from tests.latency_helpers import SPIKING_ACS, SPIKING_UPDATES, TIMES, with_decisions
from tests.report_helpers import make_cubes


def _chip_trials():
    """A hand-made trial cube of two trials, each of three chips, as the contract lays it out."""
    per_chip = np.array([[[0.5, 0.6, 0.7]], [[0.8, 0.8, 0.2]]])  # (trial, model, chip)
    return xr.Dataset(
        {
            "accuracy_mean": (("trial", "model", "chip"), per_chip),
            "accuracy_chip_mean": (("trial", "model"), per_chip.mean(axis=-1)),
            "accuracy_p05": (("trial", "model"), per_chip.min(axis=-1)),
            "data_rate_bps": (("trial", "chip"), [[10.0, 20.0, 30.0], [1.0, 2.0, 3.0]]),
        },
        coords={
            "trial": [0, 1],
            "model": ["ffnn"],
            "chip": [0, 1, 2],
            "result_key": ("trial", ["a", "b"]),
            "sigma_rel": ("trial", [0.1, 0.2], {"field": f"{MISMATCH_FIELD}.sigma_rel"}),
            "readout.threshold_v": 0.09,
            "array.rows": ("trial", [1, 3]),
            "array.cols": 3,
        },
    )


def test_area_and_yield_objectives_read_the_cube_over_chips():
    objectives = [
        Objective(Metric.ACCURACY, Direction.MAX, "ffnn"),
        Objective(Metric.YIELD, Direction.MAX, "ffnn"),
        Objective(Metric.AREA, Direction.MIN),
        Objective(Metric.DATA_RATE, Direction.MIN),
    ]
    found = objective_values(_chip_trials(), objectives)
    np.testing.assert_allclose(found[:, 0], [0.6, 0.6])  # the mean over chips
    np.testing.assert_allclose(found[:, 1], [0.5, 0.2])  # the cube's accuracy_p05
    expected = [array_area_m2(3, 0.1, 0.09), array_area_m2(9, 0.2, 0.09)]
    np.testing.assert_allclose(found[:, 2], expected, rtol=1e-12)
    np.testing.assert_allclose(found[:, 3], [20.0, 2.0])
    assert [o.name for o in objectives[:3]] == [
        "accuracy.ffnn",
        "accuracy_p05.ffnn",
        "array_area_m2",
    ]
    # No mismatch stated: no area; no chips: no yield.
    plain = _chip_trials().drop_vars(["sigma_rel", "accuracy_p05"])
    assert np.isnan(objective_values(plain, objectives[1:3])).all()


def test_objective_values_are_the_early_exits_at_the_declared_confidence():
    cube = with_decisions(make_cubes({"t": {"axes": {"readout.threshold_v": [0.09, 0.2]}}})["t"])
    objectives = [
        Objective(Metric.DECISION_TIME, Direction.MIN, "cnn"),
        Objective(Metric.DECODER_ENERGY, Direction.MIN, "cnn"),
        Objective(Metric.ACCURACY, Direction.MAX, "cnn"),
    ]
    values = objective_values(cube, objectives)
    assert values.shape == (2, 3)
    # At 0.9 a right CNN decision exits at 0.75 s (confidence 0.92), a wrong one at the full
    # touch: at 0.09 V 76 of 78 right recordings are right at 0.75 s, 2 more at 1 s, 42 wrong.
    assert EXIT_CONFIDENCE == 0.9
    n_early = 76
    expected_s = (n_early * 0.75 + (120 - n_early) * 1.0) / 120
    assert math.isclose(values[0, 0], expected_s)
    high = decoder_energy_j(SPIKING_ACS * TIMES, 0.0, SPIKING_UPDATES * TIMES).high_j
    assert math.isclose(values[0, 1], (n_early * high[2] + (120 - n_early) * high[3]) / 120)
    assert np.array_equal(values[:, 0], exit_objectives(cube, "cnn")[0])
