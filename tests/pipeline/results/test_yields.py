"""Yield statistics over chips: order-statistic ranks, their coverage, the per-design table."""

import math

import numpy as np
import pytest
from scipy.stats import binom

from pipeline.results.yields import (
    RANKS_EXAMPLES,
    binomial_cdf,
    quantile_estimate_rank,
    quantile_interval_ranks,
    rank_coverage,
    spread,
    yield_statistics,
)


@pytest.mark.parametrize("n", [1, 7, 59, 100, 200, 1000])
def test_binomial_cdf_is_scipys(n):
    assert np.allclose(binomial_cdf(n, 0.05), binom.cdf(np.arange(n + 1), n, 0.05), atol=1e-12)


def test_ranks_are_those_the_docstring_states_and_59_is_the_least_with_a_lower_bound():
    for n, ranks in RANKS_EXAMPLES.items():
        assert quantile_interval_ranks(n) == ranks
    assert quantile_interval_ranks(58)[0] is None
    assert quantile_interval_ranks(59)[0] == 1
    assert 0.95**58 > 0.05 > 0.95**59


@pytest.mark.parametrize("n", [1, 2, 10, 58, 59, 60, 100, 200])
def test_every_interval_has_at_least_95_percent_coverage_and_no_pair_is_narrower(n):
    low, high = quantile_interval_ranks(n)
    assert rank_coverage(n, low, high) >= 0.95
    if low is not None:
        narrower = [
            (lo, hi)
            for lo in range(1, n + 1)
            for hi in range(lo + 1, min(n, lo + high - low - 1) + 1)
        ]
        assert all(rank_coverage(n, lo, hi) < 0.95 for lo, hi in narrower)


@pytest.mark.parametrize("n", [59, 100, 200])
def test_the_interval_covers_a_known_5th_percentile_in_at_least_95_percent_of_draws(n):
    # Chips from a normal distribution of accuracy: its 5th percentile is known exactly.
    rng = np.random.default_rng(20261127)
    draws = 4000
    true_p05 = 0.6 + 0.05 * -1.6448536269514722
    values = 0.6 + 0.05 * rng.standard_normal((draws, n))
    stats = yield_statistics(values, 0.5)
    covered = (stats["accuracy_p05_low"] <= true_p05) & (true_p05 <= stats["accuracy_p05_high"])
    assert covered.mean() >= 0.95
    # And the estimate is the order statistic ceil(0.05 n).
    rank = quantile_estimate_rank(n)
    assert np.array_equal(stats["accuracy_p05"], np.sort(values, axis=1)[:, rank - 1])


def test_yield_statistics_skip_missing_chips_and_count_the_target_inclusively():
    accuracy = np.array([[0.5, 0.7, 0.9, np.nan], [0.4, np.nan, np.nan, np.nan]])
    stats = yield_statistics(accuracy, np.array([0.7, 0.5]))
    assert stats["accuracy_chip_mean"] == pytest.approx([0.7, 0.4])
    assert stats["yield_share"] == pytest.approx([2 / 3, 0.0])
    assert stats["accuracy_p05"] == pytest.approx([0.5, 0.4])
    assert np.isnan(stats["accuracy_p05_low"]).all()  # too few chips for a lower bound
    # One-sided upper bounds: X_(2) of 3 (F(1) = 0.993), X_(1) of 1 (F(0) = 0.95).
    assert stats["accuracy_p05_high"] == pytest.approx([0.7, 0.4])
    empty = yield_statistics(np.full((1, 3), np.nan), 0.5)
    assert all(np.isnan(v).all() for v in empty.values())


def test_spread_takes_the_binomial_noise_out():
    rng = np.random.default_rng(3)
    alike = rng.binomial(120, 0.6, size=400) / 120  # chips all alike: only test-set noise
    chips, noise = spread(alike, 120)
    assert noise == pytest.approx(0.6 * 0.4 / 120, rel=0.05)
    assert chips < 0.2 * noise
    differ = rng.binomial(120, rng.uniform(0.4, 0.8, size=400)) / 120
    chips, noise = spread(differ, 120)
    assert chips == pytest.approx(0.4**2 / 12, rel=0.25)
    assert all(math.isnan(v) for v in spread(np.array([0.5]), 120))
