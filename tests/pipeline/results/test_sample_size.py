"""Recordings needed for a paired test: the stated number reaches the power it claims."""

import numpy as np
import pytest
import scipy.stats

from pipeline.results.sample_size import paired_power, recordings_per_class

CLASSES = 12
SIMULATIONS = 4000
# Binomial standard error of a power of 0.8 over 4000 simulated runs: 0.0063. The tolerance is
# 3 of them plus what one more recording per class adds to the power (under 0.01 here).
TOLERANCE = 0.03


def _differences(rng, shape, better, worse):
    """Paired differences per recording: +1 with probability ``better``, -1 with ``worse``."""
    return rng.choice([-1.0, 0.0, 1.0], size=shape, p=[worse, 1.0 - better - worse, better])


@pytest.mark.parametrize(("better", "worse"), [(0.10, 0.15), (0.05, 0.10), (0.25, 0.30)])
def test_the_stated_recordings_reach_80_percent_power_on_synthetic_paired_data(better, worse):
    rng = np.random.default_rng(20261202)
    run = _differences(rng, 120, better, worse)  # what one run of 10 per class measured
    k = recordings_per_class(run, 0.05, CLASSES)
    n = k * CLASSES
    # The run's spread, not the population's, sets k: simulate at the run's own sigma.
    sigma = float(np.std(run, ddof=1))
    assert paired_power(n, 0.05, sigma) >= 0.8 > paired_power(n - CLASSES, 0.05, sigma)
    # Synthetic runs of k per class whose discordance has that spread and a loss of 5 points.
    spread = (sigma**2 + 0.05**2) / 2  # P(+1) + P(-1) = sigma^2 + delta^2, P(-1) - P(+1) = delta
    sims = _differences(rng, (SIMULATIONS, n), spread - 0.025, spread + 0.025)
    t = sims.mean(axis=1) / (sims.std(axis=1, ddof=1) / np.sqrt(n))
    p = 2 * scipy.stats.t.sf(np.abs(t), n - 1)
    assert abs((p < 0.05).mean() - 0.8) < TOLERANCE
    # The report's own test on one repeat, the exact McNemar test, finds it as often (it is a
    # little conservative: a wider tolerance below).
    up, down = (sims == 1).sum(axis=1), (sims == -1).sum(axis=1)
    mcnemar = np.minimum(1.0, 2 * scipy.stats.binom.cdf(np.minimum(up, down), up + down, 0.5))
    assert abs((mcnemar < 0.05).mean() - 0.8) < 2 * TOLERANCE


def test_more_spread_or_a_smaller_loss_needs_more_recordings():
    rng = np.random.default_rng(3)
    narrow = _differences(rng, 120, 0.05, 0.10)
    wide = _differences(rng, 120, 0.20, 0.25)
    assert recordings_per_class(wide, 0.05, CLASSES) > recordings_per_class(narrow, 0.05, CLASSES)
    assert recordings_per_class(narrow, 0.02, CLASSES) > recordings_per_class(narrow, 0.05, CLASSES)
    assert recordings_per_class(narrow, -0.05, CLASSES) == recordings_per_class(
        narrow, 0.05, CLASSES
    )


def test_no_spread_gives_no_estimate_and_bad_input_raises():
    assert recordings_per_class(np.zeros(120), 0.05, CLASSES) is None
    assert recordings_per_class(np.ones(1), 0.05, CLASSES) is None
    for delta in (0.0, float("nan")):
        with pytest.raises(ValueError, match="delta"):
            recordings_per_class(np.arange(4.0), delta, CLASSES)
    with pytest.raises(ValueError, match="n_classes"):
        recordings_per_class(np.arange(4.0), 0.05, 0)


def test_power_matches_the_normal_approximation_for_many_recordings():
    # For large n the noncentral t is normal: power = Phi(delta sqrt(n) / sigma - z_0.975) + ...
    n, delta, sigma = 10_000, 0.02, 0.5
    nc = delta * np.sqrt(n) / sigma
    z = scipy.stats.norm.ppf(0.975)
    normal = scipy.stats.norm.sf(z - nc) + scipy.stats.norm.cdf(-z - nc)
    assert paired_power(n, delta, sigma) == pytest.approx(normal, abs=1e-3)
