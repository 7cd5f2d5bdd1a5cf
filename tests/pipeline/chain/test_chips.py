"""Chips as a population: common random numbers, the nominal chip, deployments, keys, entries."""

import numpy as np
import pytest

from pipeline.chain import training
from pipeline.chain.readout import level_crossings
from pipeline.chain.readout_effects import effect_rng, real_train
from pipeline.design.effects import Effect
from pipeline.design.scene import ReadoutSpec, Scene
from pipeline.run.simulate import run_scene
from pipeline.run.stages import LEVELS, RESULTS, SPIKES, cache_key


def readout(**effects) -> ReadoutSpec:
    return Scene.from_dict({"readout": {"threshold_v": 0.05, "effects": effects}}).readout


def signal() -> np.ndarray:
    t = np.arange(4000) / 2000.0
    return 0.4 * np.sin(2 * np.pi * 3.0 * t) + 0.05 * np.sin(2 * np.pi * 41.0 * t)


def test_chip_k_scales_its_own_standard_normal_by_each_designs_sigma():
    v = signal()
    for chip in (0, 1, 7):
        z = effect_rng(3, Effect.THRESHOLD_MISMATCH, 2, chip=chip).standard_normal()
        for sigma in (0.1, 0.3):
            times, polarity = real_train(
                v, 2000.0, readout(threshold_mismatch={"sigma_rel": sigma}),
                seed=3, taxel=2, recording=0, chip=chip,
            )  # fmt: skip
            expected = level_crossings(v, 2000.0, 0.05 * (1 + sigma * z))
            assert np.array_equal(times, expected[0]) and np.array_equal(polarity, expected[1])
    # Chip 0 is the stream a scene of one chip draws from; other chips and pools differ.
    draws = {
        (chip, pool): effect_rng(3, Effect.THRESHOLD_MISMATCH, 2, chip=chip, pool=pool).random()
        for chip in (0, 1, 2)
        for pool in (0, 1)
    }
    assert draws[0, 0] == effect_rng(3, Effect.THRESHOLD_MISMATCH, 2).random()
    assert len(set(draws.values())) == len(draws)


def test_the_nominal_chip_draws_no_fixed_effect_but_keeps_the_noise():
    v = signal()
    fixed = readout(
        threshold_mismatch={"sigma_rel": 0.4},
        comparator_offset={"sigma_v": 0.01},
        amplifier_noise={"sigma_v": 0.01},
    )
    noise_only = readout(amplifier_noise={"sigma_v": 0.01})
    nominal = real_train(v, 2000.0, fixed, seed=1, taxel=0, recording=4, chip=None)
    plain = real_train(v, 2000.0, noise_only, seed=1, taxel=0, recording=4)
    assert np.allclose(nominal[0], plain[0], rtol=0, atol=1e-12)
    assert np.array_equal(nominal[1], plain[1])


SMOKE = Scene.builtin("smoke").replace(
    **{
        "readout.effects": {"threshold_mismatch": {"sigma_rel": 0.5}},
        "training.models": ["ffnn"],
        "training.epochs": 2,
        "dataset.duration_s": 1.0,
    }
)


def test_default_chips_change_no_key_and_the_yield_target_none():
    scene = Scene.builtin("smoke")
    assert "chips" not in scene.canonical()
    target = scene.replace(**{"chips.yield_target": 0.9})
    assert all(cache_key(target, level.name) == cache_key(scene, level.name) for level in LEVELS)
    many = SMOKE.replace(**{"chips.count": 3})
    shared = many.replace(**{"chips.deployment": "shared"})
    keys = {cache_key(s, SPIKES.name) for s in (SMOKE, many, shared)}
    assert len(keys) == 3
    assert cache_key(shared.replace(**{"chips.yield_target": 0.9}), RESULTS.name) == cache_key(
        shared, RESULTS.name
    )


@pytest.fixture(scope="module")
def one_chip():
    return run_scene(SMOKE)


def test_per_chip_chip_0_is_the_scene_of_one_chip(one_chip):
    cv = run_scene(SMOKE.replace(**{"chips.count": 2})).accuracy
    (model,) = cv
    alone = one_chip.accuracy[model]
    assert np.array_equal(cv[model].fold_accuracy, alone.fold_accuracy)
    assert np.array_equal(cv[model].chip_accuracy[0], alone.fold_accuracy)
    assert np.array_equal(cv[model].chip_predicted[0], alone.predicted)
    assert cv[model].chip_accuracy.shape == (2, 1, SMOKE.training.folds)


@pytest.mark.parametrize("kind", ["shared", "robust"])
def test_a_deployed_classifier_trains_once_per_fold_whatever_the_chips(kind, monkeypatch, one_chip):
    calls = []
    fit = training.fit_folds
    monkeypatch.setattr(
        training, "fit_folds", lambda *a, **k: calls.append(len(a[2])) or fit(*a, **k)
    )
    scene = SMOKE.replace(**{"chips.count": 5, "chips.deployment": kind, "training.repeats": 2})
    (cv,) = run_scene(scene).accuracy.values()
    assert calls == [scene.training.folds] * 2  # one batched training of the folds per repeat
    assert cv.chip_accuracy.shape == (5, 2, scene.training.folds)
    assert cv.chip_predicted.shape == (5, 2, 48)
    assert np.array_equal(cv.fold_accuracy, cv.chip_accuracy[0])
    # Accuracy per fold is the share of the fold's recordings each chip got right.
    labels = one_chip.labels
    for k in range(5):
        for r in range(2):
            right = cv.chip_predicted[k, r] == labels
            by_fold = [right[cv.test_fold[r] == f].mean() for f in range(scene.training.folds)]
            assert np.allclose(cv.chip_accuracy[k, r], by_fold)
