"""Decision time and decoder energy as search objectives (per model, under early exit)."""

import math

import numpy as np
import pytest

from pipeline.design.space import Metric, Space, objective_values
from pipeline.errors import SceneError
from pipeline.results.decoder_energy import decoder_energy_j
from pipeline.results.early_exit import EXIT_CONFIDENCE, exit_objectives
from tests.latency_helpers import SPIKING_ACS, SPIKING_UPDATES, TIMES, with_decisions
from tests.report_helpers import make_cubes


def space(objectives: dict) -> dict:
    return {
        "name": "s",
        "base": "smoke",
        "space": {"readout.threshold_v": {"low": 0.02, "high": 0.3, "log": True}},
        "objectives": objectives,
    }


def test_decision_time_and_decoder_energy_are_objectives_of_a_model():
    loaded = Space.from_dict(
        space({"accuracy.ffnn": "max", "decision_s.ffnn": "min", "decoder_energy_j.cnn": "min"})
    )
    _, time, energy = loaded.objectives
    assert (time.metric, time.model, time.name) == (Metric.DECISION_TIME, "ffnn", "decision_s.ffnn")
    assert (energy.metric, energy.model, energy.sign) == (Metric.DECODER_ENERGY, "cnn", 1.0)


def test_without_a_model_they_are_refused_naming_the_known_objectives():
    with pytest.raises(SceneError) as caught:
        Space.from_dict(space({"accuracy.ffnn": "max", "decision_s": "min"}))
    (problem,) = caught.value.problems
    assert "objectives.decision_s: unknown objective" in problem
    assert "decision_s.<model>" in problem and "decoder_energy_j.<model>" in problem


def test_objective_values_are_the_early_exits_at_the_declared_confidence():
    cube = with_decisions(make_cubes({"t": {"axes": {"readout.threshold_v": [0.09, 0.2]}}})["t"])
    loaded = Space.from_dict(
        space({"decision_s.cnn": "min", "decoder_energy_j.cnn": "min", "accuracy.cnn": "max"})
    )
    values = objective_values(cube, loaded.objectives)
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


def test_a_cube_without_decisions_gives_nan_so_the_trial_fails():
    cube = make_cubes({"t": {"axes": {"readout.threshold_v": [0.09, 0.2]}}})["t"]
    time, energy = exit_objectives(cube, "cnn")
    assert np.isnan(time).all() and np.isnan(energy).all() and time.shape == (2,)
    time, energy = exit_objectives(with_decisions(cube, operations=False), "cnn")
    assert np.isfinite(time).all() and np.isnan(energy).all()
