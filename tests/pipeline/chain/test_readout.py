"""Level-crossing readout: contract, hard cases, invariants."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pipeline.chain.readout import level_crossings, reference_level_crossings
from pipeline.errors import SimulationError
from tests.readout_helpers import walk

FS = 1000.0


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
