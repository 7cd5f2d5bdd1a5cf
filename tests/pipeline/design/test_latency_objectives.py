"""Decision time and decoder energy as search objectives (per model, under early exit)."""

import numpy as np
import pytest

from pipeline.design.scene import Scene
from pipeline.design.space import Metric, Space
from pipeline.errors import SceneError
from pipeline.results.early_exit import exit_objectives
from tests.latency_helpers import with_decisions
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


def test_they_need_decoders_trained_along_the_touch():
    """The default trains along the touch; a base trained for the full touch is refused unless
    the search varies what the decoders are trained for."""
    assert Space.from_dict(space({"accuracy.ffnn": "max", "decision_s.ffnn": "min"}))
    full = space({"accuracy.ffnn": "max", "decision_s.ffnn": "min", "decoder_energy_j.cnn": "min"})
    full["base"] = Scene.builtin("smoke").replace(**{"training.decisions": "full_touch"}).to_dict()
    with pytest.raises(SceneError) as caught:
        Space.from_dict(full)
    assert [p.split(":")[0] for p in caught.value.problems] == [
        "objectives.decision_s.ffnn",
        "objectives.decoder_energy_j.cnn",
    ]
    assert all('training.decisions = "along_touch"' in p for p in caught.value.problems)
    full["space"]["training.decisions"] = {"choices": ["full_touch", "along_touch"]}
    assert Space.from_dict(full).fields == ("readout.threshold_v", "training.decisions")


def test_a_cube_without_decisions_gives_nan_so_the_trial_fails():
    cube = make_cubes({"t": {"axes": {"readout.threshold_v": [0.09, 0.2]}}})["t"]
    time, energy = exit_objectives(cube, "cnn")
    assert np.isnan(time).all() and np.isnan(energy).all() and time.shape == (2,)
    time, energy = exit_objectives(with_decisions(cube, operations=False), "cnn")
    assert np.isfinite(time).all() and np.isnan(energy).all()
