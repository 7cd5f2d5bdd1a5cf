"""The REAL train: the readout's effects, each simulated only when named, drawn from its own
stream."""

import numpy as np
import pytest
import scipy.stats

import pipeline.chain.readout as readout
import pipeline.chain.readout_effects as readout_effects
from pipeline.chain.readout import level_crossings
from pipeline.chain.readout_effects import THRESHOLD_FLOOR_REL, effect_rng, real_train, true_train
from pipeline.design.effects import Effect
from tests.readout_helpers import readout_with, walk

FS = 1000.0


# -- the REAL train: effects simulated only when named ------------------------------------------


@pytest.fixture
def rng_calls(monkeypatch):
    """Record every generator the readout asks for: (effect, taxel, recording)."""
    calls = []

    def spy(seed, effect, taxel, recording=None):
        calls.append((effect, taxel, recording))
        return effect_rng(seed, effect, taxel, recording)

    monkeypatch.setattr(readout_effects, "effect_rng", spy)
    return calls


def test_ideal_readout_draws_nothing_and_real_equals_true(rng_calls):
    v = walk()
    real = real_train(v, FS, readout_with(), seed=1, taxel=3, recording=2)
    true = level_crossings(v, FS, 0.1)
    assert rng_calls == []
    np.testing.assert_array_equal(real[0], true[0])
    np.testing.assert_array_equal(real[1], true[1])


def test_only_mismatch_draws_one_number_per_taxel_and_no_noise_arrays(rng_calls, monkeypatch):
    sizes = []
    original = np.random.Generator.standard_normal

    real_train(walk(), FS, readout_with(threshold_mismatch={}), seed=1, taxel=3, recording=2)
    assert rng_calls == [(Effect.THRESHOLD_MISMATCH, 3, None)]

    class Recording:
        def __init__(self, gen):
            self.gen = gen

        def standard_normal(self, size=None):
            sizes.append(size)
            return original(self.gen, size)

    monkeypatch.setattr(readout_effects, "effect_rng", lambda *a: Recording(effect_rng(*a)))
    real_train(walk(), FS, readout_with(threshold_mismatch={}), seed=1, taxel=3, recording=2)
    assert sizes == [None]


def test_each_effect_draws_from_its_own_stream(rng_calls):
    effects = {e.value: {} for e in Effect}
    real_train(walk(), FS, readout_with(**effects), seed=1, taxel=3, recording=2)
    static = {Effect.AMPLIFIER_OFFSET, Effect.THRESHOLD_MISMATCH, Effect.COMPARATOR_OFFSET}
    noise = {Effect.AMPLIFIER_NOISE, Effect.COMPARATOR_NOISE}
    assert set(rng_calls) == {(e, 3, None) for e in static} | {(e, 3, 2) for e in noise}


@pytest.mark.parametrize(
    "effect",
    [
        {"amplifier_noise": {"sigma_v": 0.05}},
        {"comparator_offset": {"sigma_v": 0.03}},
        {"comparator_noise": {"sigma_v": 0.03}},
        {"threshold_mismatch": {"sigma_rel": 0.3}},
        {"saturation": {"rail_v": 0.2}},
    ],
)
@pytest.mark.parametrize("encoder", ["lcs", "decaying"])
def test_each_effect_changes_the_train(effect, encoder):
    v = walk()
    readout = readout_with(encoder, **effect)
    real = real_train(v, FS, readout, seed=0, taxel=0, recording=0)
    true = true_train(v, FS, readout)
    assert not (len(real[0]) == len(true[0]) and np.array_equal(real[0], true[0]))
    assert np.all(np.diff(real[0]) >= 0) and np.all(np.isfinite(real[0]))


def test_amplifier_offset_matters_only_through_saturation():
    v = walk(seed=3)
    v = 0.45 * v / np.max(np.abs(v))
    offset_only = readout_with(amplifier_offset={"sigma_v": 0.2})
    true = level_crossings(v, FS, 0.1)
    alone = real_train(v, FS, offset_only, seed=0, taxel=0, recording=0)
    # A constant offset is invisible to a level-crossing encoder (up to float rounding).
    np.testing.assert_array_equal(alone[1], true[1])
    np.testing.assert_allclose(alone[0], true[0], atol=1e-9)
    both = readout_with(amplifier_offset={"sigma_v": 0.2}, saturation={})
    saturated = real_train(v, FS, both, seed=0, taxel=0, recording=0)
    assert len(saturated[0]) < len(true[0])


def test_static_effects_are_per_taxel_and_noise_is_per_recording():
    v = walk()
    mismatch = readout_with(threshold_mismatch={"sigma_rel": 0.3})
    same = [real_train(v, FS, mismatch, seed=5, taxel=1, recording=r)[0] for r in (0, 1)]
    np.testing.assert_array_equal(same[0], same[1])
    other_taxel = real_train(v, FS, mismatch, seed=5, taxel=2, recording=0)[0]
    assert not np.array_equal(same[0], other_taxel)
    noise = readout_with(amplifier_noise={"sigma_v": 0.05})
    a, b = (real_train(v, FS, noise, seed=5, taxel=1, recording=r)[0] for r in (0, 1))
    assert not np.array_equal(a, b)
    again = real_train(v, FS, noise, seed=5, taxel=1, recording=0)[0]
    np.testing.assert_array_equal(a, again)


def test_mismatch_pushing_thresholds_below_zero_is_clipped_to_the_floor():
    v = walk()
    huge = readout_with(threshold_mismatch={"sigma_rel": 100.0})
    floor_count = len(level_crossings(v, FS, 0.1 * THRESHOLD_FLOOR_REL)[0])
    counts = []
    for taxel in range(20):
        times, _ = real_train(v, FS, huge, seed=0, taxel=taxel, recording=0)
        assert np.all(np.isfinite(times))
        counts.append(len(times))
    # About half the draws are negative; those taxels run at the floor, never below it.
    assert max(counts) == floor_count
    assert sum(c == floor_count for c in counts) >= 5


def test_the_scene_sets_the_threshold_floor():
    v = walk()
    spec = readout_with(threshold_mismatch={"sigma_rel": 100.0, "floor_rel": 0.3})
    floor_count = len(level_crossings(v, FS, 0.1 * 0.3)[0])
    counts = [len(real_train(v, FS, spec, seed=0, taxel=t, recording=0)[0]) for t in range(20)]
    assert max(counts) == floor_count
    assert sum(c == floor_count for c in counts) >= 5


def test_noise_far_above_the_threshold_stays_finite_and_ordered():
    v = walk()
    noisy = readout_with(amplifier_noise={"sigma_v": 2.0}, comparator_noise={"sigma_v": 1.0})
    times, polarity = real_train(v, FS, noisy, seed=0, taxel=0, recording=0)
    assert len(times) > len(level_crossings(v, FS, 0.1)[0])
    assert np.all(np.isfinite(times)) and np.all(np.diff(times) >= 0)
    assert set(np.unique(polarity)) <= {-1, 1}


def test_comparator_offsets_make_up_and_down_steps_unequal():
    # Five rises and falls of 1 V: a rise emits up to 1 V / UP spikes, a fall 1 V / DOWN,
    # with UP = 0.1 + 0.04 c_up and DOWN = 0.1 + 0.04 c_down from the taxel's own stream.
    v = np.tile(np.concatenate([np.linspace(0, 1, 200), np.linspace(1, 0, 200)]), 5)
    readout_spec = readout_with(comparator_offset={"sigma_v": 0.04})
    for taxel in range(10):
        _, polarity = real_train(v, FS, readout_spec, seed=0, taxel=taxel, recording=0)
        c_up, c_down = effect_rng(0, Effect.COMPARATOR_OFFSET, taxel).standard_normal(2)
        up_v = max(0.1 + 0.04 * c_up, 0.1 * THRESHOLD_FLOOR_REL)
        down_v = max(0.1 + 0.04 * c_down, 0.1 * THRESHOLD_FLOOR_REL)
        # Each rise starts within DOWN of 0 and ends within UP of 1 (and each fall alike).
        span = 1 - up_v - down_v
        assert 5 * span / up_v - 1 <= (polarity > 0).sum() <= 5 / up_v + 1
        assert 5 * span / down_v - 1 <= (polarity < 0).sum() <= 5 / down_v + 1


def two_comparator_model(v, up_v, down_v, floor_v, e_up, e_down):
    """The module docstring's REAL encoder with independent UP and DOWN noise on every sample:
    the number of spikes (the kernel draws one value per sample, for the comparator that can
    fire, which must give the same distribution)."""
    r, count = v[0], 0
    for i in range(1, len(v)):
        up = max(up_v + e_up[i], floor_v)
        down = max(down_v + e_down[i], floor_v)
        while v[i] - r >= up:
            r, count = r + up, count + 1
        while r - v[i] >= down:
            r, count = r - down, count + 1
    return count


@pytest.mark.parametrize("sigma_v", [0.02, 0.2])
def test_comparator_noise_has_the_distribution_of_two_independent_comparators(sigma_v):
    v = walk(400, seed=4)
    spec = readout_with(comparator_noise={"sigma_v": sigma_v})
    kernel = [len(real_train(v, FS, spec, seed=9, taxel=0, recording=r)[0]) for r in range(300)]
    rng = np.random.default_rng(123)
    model = [
        two_comparator_model(v, 0.1, 0.1, 0.01, *(sigma_v * rng.standard_normal((2, len(v)))))
        for _ in range(300)
    ]
    # Same law: a two-sample KS test on the spike counts must not reject at the 0.1 % level
    # (deterministic here: both sides are seeded).
    assert scipy.stats.ks_2samp(kernel, model).pvalue > 1e-3
    assert abs(np.mean(kernel) - np.mean(model)) < 4 * np.std(model) / np.sqrt(300) * np.sqrt(2)


def test_a_train_longer_than_the_first_buffer_is_encoded_again_with_the_same_noise(monkeypatch):
    v = walk(4000)
    spec = readout_with(comparator_noise={"sigma_v": 0.05}, amplifier_noise={"sigma_v": 0.05})
    expected = real_train(v, FS, spec, seed=2, taxel=1, recording=3)
    assert len(expected[0]) > 1024  # longer than the smallest first buffer
    monkeypatch.setattr(readout, "_TYPICAL_SAMPLES_PER_SPIKE", 10**9)  # first buffer: 1024
    again = real_train(v, FS, spec, seed=2, taxel=1, recording=3)
    np.testing.assert_array_equal(again[0], expected[0])
    np.testing.assert_array_equal(again[1], expected[1])
