"""Level-crossing readout: contract, hard cases, invariants, effects simulated only when named."""

import numpy as np
import pytest
import scipy.stats
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import pipeline.chain.readout as readout
from pipeline.chain.readout import (
    THRESHOLD_FLOOR_REL,
    effect_rng,
    level_crossings,
    real_train,
    reference_level_crossings,
    true_train,
)
from pipeline.design.scene import Effect, Scene
from pipeline.errors import SimulationError

FS = 1000.0


def readout_with(encoder="lcs", **effects):
    readout = {"threshold_v": 0.1, "encoder": encoder, "effects": effects}
    return Scene.from_dict({"readout": readout}).readout


def walk(n=4000, seed=0, step=0.02):
    return np.cumsum(np.random.default_rng(seed).standard_normal(n)) * step


# -- contract and exact cases -----------------------------------------------------------------


def test_contract_types():
    times, polarity = level_crossings(walk(), FS, 0.1)
    assert times.dtype == np.float64 and polarity.dtype == np.int8
    assert set(np.unique(polarity)) <= {-1, 1}
    assert len(times) == len(polarity) > 0


def test_ramp_crosses_each_level_at_its_interpolated_time():
    # 0 -> 1 V in one sample, 0.25 V levels: four +1 spikes at 1/4, 2/4, 3/4 and 4/4 of the step.
    times, polarity = level_crossings(np.array([0.0, 1.0, 1.0]), FS, 0.25)
    np.testing.assert_allclose(times, np.array([0.25, 0.5, 0.75, 1.0]) / FS, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(polarity, [1, 1, 1, 1])


def test_reaching_the_level_counts():
    times, polarity = level_crossings(np.array([0.0, 0.5, 0.0]), FS, 0.5)
    np.testing.assert_array_equal(polarity, [1, -1])
    np.testing.assert_allclose(times, [1 / FS, 2 / FS], rtol=1e-15)


def test_a_step_spanning_many_levels_emits_one_spike_per_level_in_time_order():
    times, polarity = level_crossings(np.array([0.0, -0.8, 0.0]), FS, 0.1)
    assert list(polarity) == [-1] * 8 + [1] * 8
    assert np.all(np.diff(times) > 0)
    np.testing.assert_allclose(times[:8], np.arange(1, 9) / 8 / FS, rtol=1e-12)
    # Going back up from -8 the first level crossed is -7, 1/8 of the way.
    np.testing.assert_allclose(times[8:], (1 + np.arange(1, 9) / 8) / FS, rtol=1e-12)


def test_constant_signal_gives_no_spikes():
    times, polarity = level_crossings(np.full(1000, 0.3), FS, 0.01)
    assert len(times) == len(polarity) == 0


def test_threshold_above_the_signal_range_gives_no_spikes():
    v = 0.4 * np.sin(np.linspace(0, 20, 2000))
    times, _ = level_crossings(v, FS, 0.9)
    assert times.shape == (0,)


def test_tiny_threshold_is_a_clear_error_not_an_explosion():
    v = np.sin(np.linspace(0, 200, 20_000))
    with pytest.raises(SimulationError, match=r"would emit at least [\d,]+ spikes .*limit 1,000"):
        level_crossings(v, FS, 1e-6, max_spikes=1000)


def test_non_finite_samples_are_rejected_with_their_index():
    v = walk(100)
    v[37] = np.nan
    with pytest.raises(ValueError, match="non-finite sample .* at index 37"):
        level_crossings(v, FS, 0.1)
    v[37] = np.inf
    with pytest.raises(ValueError, match="index 37"):
        level_crossings(v, FS, 0.1)


@pytest.mark.parametrize("threshold", [0.0, -0.1, float("nan")])
def test_non_positive_threshold_is_rejected(threshold):
    with pytest.raises(ValueError, match="threshold_v must be a finite number > 0"):
        level_crossings(walk(10), FS, threshold)


def test_hours_long_recordings_keep_sub_microsecond_spike_times():
    # Two hours at 1 kHz; u alternates 0, 1.5, 0, 1.5 ... so spikes fall exactly at
    # (2j + 2/3) / fs (up) and (2j + 2) / fs (down) for every j.
    n = 2 * 3600 * 1000
    v = np.zeros(n)
    v[1::2] = 0.15
    times, polarity = level_crossings(v, FS, 0.1)
    assert len(times) == n - 1
    j = np.arange(n // 2)
    expected = np.empty(n)
    expected[0::2] = (2 * j + 2 / 3) / FS
    expected[1::2] = (2 * j + 2) / FS
    assert times[-1] > 7199.0
    assert np.max(np.abs(times - expected[: n - 1])) < 1e-9
    np.testing.assert_array_equal(polarity[:4], [1, -1, 1, -1])


# -- invariants (hypothesis) --------------------------------------------------------------------

# Dyadic values keep every operation exact, so the invariants can be checked for equality.
dyadic_signals = hnp.arrays(
    np.float64,
    st.integers(2, 200),
    elements=st.integers(-4096, 4096).map(lambda k: k / 64),
)
powers_of_two = st.integers(-6, 3).map(lambda e: 2.0**e)


@settings(max_examples=200, deadline=None)
@given(v=dyadic_signals, theta=powers_of_two, shift=st.integers(-4096, 4096).map(lambda k: k / 64))
def test_adding_a_constant_leaves_the_train_unchanged(v, theta, shift):
    a = level_crossings(v, FS, theta)
    b = level_crossings(v + shift, FS, theta)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


@settings(max_examples=200, deadline=None)
@given(v=dyadic_signals, theta=powers_of_two, scale=st.integers(-4, 4).map(lambda e: 2.0**e))
def test_scaling_signal_and_threshold_together_leaves_the_train_unchanged(v, theta, scale):
    a = level_crossings(v, FS, theta)
    b = level_crossings(v * scale, FS, theta * scale)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


finite_signals = hnp.arrays(
    np.float64, st.integers(1, 300), elements=st.floats(-1e3, 1e3, allow_nan=False)
)


@settings(max_examples=200, deadline=None)
@given(v=finite_signals, theta=st.floats(1e-2, 1e3), delay=st.integers(1, 500))
def test_whole_sample_delay_shifts_spikes_by_exactly_that_time(v, theta, delay):
    times, polarity = level_crossings(v, FS, theta)
    delayed = np.concatenate([np.full(delay, v[0]), v])
    d_times, d_polarity = level_crossings(delayed, FS, theta)
    np.testing.assert_array_equal(d_polarity, polarity)
    np.testing.assert_allclose(d_times, times + delay / FS, rtol=1e-12, atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(v=finite_signals, theta=st.floats(1e-2, 1e3))
def test_compiled_encoder_equals_the_pure_python_specification(v, theta):
    times, polarity = level_crossings(v, FS, theta)
    ref_times, ref_polarity = reference_level_crossings(v, FS, theta)
    np.testing.assert_array_equal(polarity, ref_polarity)
    np.testing.assert_array_equal(times, ref_times)  # same IEEE operations, same bits


@pytest.mark.parametrize("theta", [0.01, 0.09, 0.7])
@pytest.mark.parametrize("seed", [0, 1])
def test_long_signals_equal_the_specification_across_blocks_and_quarters(seed, theta):
    # The kernel encodes blocks of 2**16 samples, four quarters of each at once from guessed
    # levels; long walks make quarters start away from their true level and merge later.
    v = walk(140_001, seed=seed, step=0.05)
    times, polarity = level_crossings(v, FS, theta)
    ref_times, ref_polarity = reference_level_crossings(v, FS, theta)
    np.testing.assert_array_equal(polarity, ref_polarity)
    np.testing.assert_array_equal(times, ref_times)


def test_quarters_that_start_off_their_true_level():
    # A ramp to 3.1 thresholds emits three +1 spikes; the signal then settles at 2.99, so the
    # true level stays 3 while the later quarters guess floor(2.99) = 2. The last quarter falls
    # to 1.5: from the true level that is a -1 spike at 2, from the guess no spike at all.
    v = np.concatenate(
        [
            np.linspace(0, 0.31, 50),
            np.linspace(0.31, 0.299, 50),
            np.full(250, 0.299),
            np.linspace(0.299, 0.15, 50),
        ]
    )
    times, polarity = level_crossings(v, FS, 0.1)
    ref_times, ref_polarity = reference_level_crossings(v, FS, 0.1)
    np.testing.assert_array_equal(polarity, ref_polarity)
    np.testing.assert_array_equal(times, ref_times)


@settings(max_examples=200, deadline=None)
@given(
    v=finite_signals,
    bad=st.lists(st.tuples(st.integers(0, 299), st.sampled_from([np.nan, np.inf, -np.inf]))),
)
def test_the_first_non_finite_sample_is_reported_wherever_it_is(v, bad):
    v = v.copy()
    for index, value in bad:
        if index < len(v):
            v[index] = value
    first = np.flatnonzero(~np.isfinite(v))
    if len(first) == 0:
        level_crossings(v, FS, 0.1)
        return
    with pytest.raises(ValueError, match=rf"at index {first[0]}$"):
        level_crossings(v, FS, 0.1)


@settings(max_examples=300, deadline=None)
@given(v=finite_signals, theta=st.floats(1e-2, 1e3))
def test_train_invariants_on_arbitrary_finite_signals(v, theta):
    times, polarity = level_crossings(v, FS, theta)
    assert np.all(np.isfinite(times))
    assert np.all(np.diff(times) >= 0)
    if len(times):
        assert times[0] > 0 and times[-1] <= (len(v) - 1) / FS * (1 + 1e-12)
    # The reference ends within one threshold of the last sample.
    net = polarity.astype(np.int64).sum()
    assert abs((v[-1] - v[0]) / theta - net) < 1 + 1e-9


# -- the REAL train: effects simulated only when named ------------------------------------------


@pytest.fixture
def rng_calls(monkeypatch):
    """Record every generator the readout asks for: (effect, taxel, recording)."""
    calls = []

    def spy(seed, effect, taxel, recording=None):
        calls.append((effect, taxel, recording))
        return effect_rng(seed, effect, taxel, recording)

    monkeypatch.setattr(readout, "effect_rng", spy)
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

    monkeypatch.setattr(readout, "effect_rng", lambda *a: Recording(effect_rng(*a)))
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
