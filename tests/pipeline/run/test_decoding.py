"""The decoding levels: the trains coded as the scene's decoders read them (every chip's too),
and every model cross-validated on what its decoder reads."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.chain.decoders import Reads
from pipeline.design.scene import Model, Scene
from pipeline.run.decoding import classify, reads_steps
from pipeline.run.stages import LEVELS, RATES, Stopwatch

SMOKE = Scene.builtin("smoke").replace(
    **{
        "readout.effects": {"threshold_mismatch": {"sigma_rel": 0.3}},
        "training.epochs": 2,
        "training.snn.epochs": 2,
        "dataset.duration_s": 1.0,
    }
)


def _rates(scene: Scene):
    outputs, watch = {}, Stopwatch(None)
    for level in LEVELS[: LEVELS.index(RATES) + 1]:
        outputs[level.name] = level.run(scene, outputs, watch)
    return outputs[RATES.name], watch


def test_a_scene_codes_steps_only_when_a_decoder_reads_them():
    rates, _ = _rates(SMOKE.replace(**{"training.models": ["ffnn", "cnn"]}))
    assert set(rates.inputs) == {Reads.WINDOWS} and not reads_steps(SMOKE)
    windows = rates.inputs[Reads.WINDOWS]
    assert windows.frames is rates.counts and windows.column_s == SMOKE.coding.window_s
    assert windows.chips is None and windows.reference is None
    assert rates.dropped.shape == (rates.counts.shape[0], rates.counts.shape[2])


@pytest.mark.parametrize("deployment", ["per_chip", "shared"])
def test_the_snn_reads_every_chips_steps_and_is_deployed_on_them(deployment):
    scene = SMOKE.replace(
        **{"training.models": ["ffnn", "snn"], "chips.count": 2, "chips.deployment": deployment}
    )
    assert reads_steps(scene)
    rates, watch = _rates(scene)
    n, _, taxels, n_windows = rates.counts.shape
    steps = rates.inputs[Reads.STEPS]
    n_steps = round(n_windows * scene.coding.window_s / scene.training.snn.step_s)
    assert steps.frames.shape == (n, 2, taxels, n_steps)
    assert steps.column_s == scene.training.snn.step_s
    assert steps.chips.shape == (2, n, 2, taxels, n_steps)
    assert (steps.reference is None) == (deployment == "per_chip")
    assert rates.inputs[Reads.WINDOWS].chips.shape == (2, *rates.counts.shape)
    accuracy = classify(rates=rates, training=scene.training, watch=watch)
    assert list(accuracy) == [Model.FFNN, Model.SNN]
    for cv in accuracy.values():
        assert cv.chip_accuracy.shape == (2, 1, scene.training.folds)
        assert np.array_equal(cv.fold_accuracy, cv.chip_accuracy[0])
        assert cv.decision_s is None  # a point of chips keeps no decisions
