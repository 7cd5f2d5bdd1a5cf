"""Spike metrics: the paper's formulas and every edge case, without NaN."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pipeline.chain.metrics import (
    bits_per_event,
    correlate_with_accuracy,
    data_rate_bps,
    equivalent_bits,
    event_rate_hz,
    pooled_ssnr_db,
    ssnr_db,
    ste_per_train,
    ste_s2,
)
from pipeline.chain.spikes import TIME_RESOLUTION_S, SpikeTrains, floor_ticks


def test_ssnr_formula_and_edge_cases():
    np.testing.assert_allclose(ssnr_db(100, 110), 20.0)
    np.testing.assert_allclose(ssnr_db(100, 90), 20.0)
    assert ssnr_db(10, 10) == math.inf  # N_real == N_true
    assert ssnr_db(0, 0) == math.inf
    assert ssnr_db(0, 5) == -math.inf  # N_true == 0: all noise
    values = ssnr_db(np.array([5, 0, 3]), np.array([5, 2, 4]))
    assert not np.isnan(values).any()


def test_pooled_ssnr_handles_exact_and_empty_sets():
    assert pooled_ssnr_db(np.array([3, 4]), np.array([3, 4])) == math.inf
    assert pooled_ssnr_db(np.array([0, 0]), np.array([0, 0])) == math.inf
    assert pooled_ssnr_db(np.array([0, 0]), np.array([1, 0])) == -math.inf
    assert pooled_ssnr_db(np.array([10, 10]), np.array([11, 9])) == pytest.approx(20.0)


def test_ste_matches_the_papers_formula():
    true = np.array([0.1, 0.5])
    real = np.array([0.11, 0.4, 0.9])
    dt = np.array([0.01, 0.1])
    expected = np.sum((dt - dt.mean()) ** 2) / 3 * (3 - 2)
    assert ste_s2(true, real) == pytest.approx(expected, rel=1e-12)
    assert ste_s2(true, real, "sign_safe") == pytest.approx(expected, rel=1e-12)


def test_ste_quirks_are_kept_and_the_sign_safe_variant_fixes_the_sign():
    true = np.array([0.1, 0.2, 0.3])
    shifted = true + np.array([0.0, 0.02, 0.05])
    assert ste_s2(true, shifted) == 0.0  # counts agree: zero however far spikes moved
    fewer = np.array([0.1, 0.35])
    assert ste_s2(true, fewer) < 0
    assert ste_s2(true, fewer, "sign_safe") == -ste_s2(true, fewer)


def test_ste_empty_trains():
    empty = np.empty(0)
    assert ste_s2(empty, empty) == 0.0
    assert ste_s2(empty, np.array([0.5])) == 0.0
    assert ste_s2(np.array([0.5]), empty) == -math.inf
    assert ste_s2(np.array([0.5]), empty, "sign_safe") == math.inf


def test_ste_nearest_real_spike_is_found_on_either_side():
    true = np.array([0.0, 1.0, 2.0, 10.0])
    real = np.array([0.9, 1.05, 2.5, 2.6, 3.0])
    gaps = np.array([0.9, 0.05, 0.5, 7.0])
    assert ste_s2(true, real) == pytest.approx(np.sum((gaps - gaps.mean()) ** 2) / 5 * 1)


def test_ste_per_train_agrees_with_single_trains():
    rng = np.random.default_rng(0)

    # Whole ticks, as every train holds them (SpikeTrains floors its times to the tick).
    def ticked(n):
        return floor_ticks(np.sort(rng.uniform(0, 1, n))) * TIME_RESOLUTION_S

    pairs = [(ticked(n), ticked(m)) for n, m in [(5, 7), (0, 3), (4, 0), (6, 6)]]
    true = SpikeTrains.concatenate([(t, np.ones(len(t))) for t, _ in pairs], 2, np.ones(2))
    real = SpikeTrains.concatenate([(r, np.ones(len(r))) for _, r in pairs], 2, np.ones(2))
    per_train = ste_per_train(true, real).ravel()
    np.testing.assert_array_equal(per_train, [ste_s2(t, r) for t, r in pairs])


def test_equivalent_bits():
    assert equivalent_bits(1.0, 0.09) == pytest.approx(3.474, abs=1e-3)
    assert equivalent_bits(1.0, 0.5) == 1.0


def test_event_and_data_rates():
    trains = SpikeTrains.concatenate(
        [
            (np.zeros(10), np.ones(10)),
            (np.zeros(30), np.ones(30)),
            (np.zeros(5), np.ones(5)),
            (np.zeros(5), np.ones(5)),
        ],
        n_taxels=2,
        duration_s=np.array([2.0, 1.0]),
    )
    assert event_rate_hz(trains) == pytest.approx((40 / 2 + 10 / 1) / 2)
    assert bits_per_event(1) == 1
    assert bits_per_event(9) == 5  # 4 address bits + polarity
    assert bits_per_event(1024) == 11
    assert data_rate_bps(trains) == pytest.approx(15.0 * 2)


def test_correlations_match_scipy_and_skip_infinite_points():
    from scipy import stats

    metric = np.array([math.inf, 30.0, 20.0, 12.0, 5.0, 1.0])
    accuracy = np.array([0.9, 0.85, 0.7, 0.72, 0.4, 0.3])
    result = correlate_with_accuracy(metric, accuracy)
    r, p, n, note = result["pearson"]
    expected = stats.pearsonr(metric[1:], accuracy[1:])
    assert (r, p, n, note) == pytest.approx((expected.statistic, expected.pvalue, 5, ""))
    assert result["spearman"][0] == pytest.approx(stats.spearmanr(metric[1:], accuracy[1:])[0])
    assert r > 0.9


# Values from a few levels (ties, as swept accuracies have), or spread over magnitudes.
correlated_values = st.one_of(
    st.lists(st.sampled_from([0.0, 0.25, 0.5, 1.0, 3.0]), min_size=3, max_size=40),
    st.lists(st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False), min_size=3, max_size=40),
)


@given(correlated_values, st.data())
def test_correlations_are_scipys_to_the_bit(metric, data):
    from scipy import stats

    n = len(metric)
    accuracy = data.draw(
        st.one_of(
            st.lists(st.integers(0, 12).map(lambda k: k / 12), min_size=n, max_size=n),
            st.just([2.0 * m + 1.0 for m in metric]),  # a perfect correlation
            st.just([-m for m in metric]),
        )
    )
    metric, accuracy = np.array(metric), np.array(accuracy)
    result = correlate_with_accuracy(metric, accuracy)
    if np.ptp(metric) == 0 or np.ptp(accuracy) == 0:
        assert "constant" in result["pearson"][3]
        return
    for method, expected in (
        ("pearson", stats.pearsonr(metric, accuracy)),
        ("spearman", stats.spearmanr(metric, accuracy)),
    ):
        r, p, n_used, note = result[method]
        assert (n_used, note) == (n, "")
        assert np.float64(r).tobytes() == np.float64(expected.statistic).tobytes(), method
        assert np.float64(p).tobytes() == np.float64(expected.pvalue).tobytes(), method


def test_correlations_are_undefined_not_errors_for_too_few_or_constant_points():
    few = correlate_with_accuracy(np.array([math.inf, 1.0, 2.0]), np.array([0.1, 0.2, 0.3]))
    assert math.isnan(few["pearson"][0]) and "2 points" in few["pearson"][3]
    flat = correlate_with_accuracy(np.array([1.0, 2.0, 3.0]), np.array([0.5, 0.5, 0.5]))
    assert math.isnan(flat["spearman"][1]) and "constant" in flat["spearman"][3]
