r"""Yield statistics of a design's chips: mean, 5th percentile with its interval, yield share.

Declared in one place and used by the result cube (:func:`pipeline.results.cube.build_cube`)
for every design and model whose point simulates chips. Inputs are each chip's accuracy
(``accuracy_mean`` of the cube, a fraction of recordings classified correctly).

5th percentile and its distribution-free interval
-------------------------------------------------
The estimate is the order statistic ``X_(r)`` of rank ``r = ceil(q N)`` (at least 1) of the
``N`` chips' accuracies (the inverted empirical distribution function, ``q = 0.05``).

Its 95 % interval uses order statistics only, so it holds whatever the distribution of chip
accuracy is. For the ``q``-quantile ``xi`` of the chip population, the number ``B`` of the
``N`` chips at or below ``xi`` is binomial, ``B ~ Bin(N, q)`` (for a continuous distribution;
ties, as accuracies on a finite test set have, only make the closed intervals below cover
more). Since ``X_(l) <= xi`` exactly when ``B >= l`` and ``X_(u) >= xi`` when ``B <= u - 1``,

.. math::

    P\left(X_{(l)} \le \xi \le X_{(u)}\right) \ge F(u - 1) - F(l - 1),
    \qquad F \text{ the } \mathrm{Bin}(N, q) \text{ distribution function}.

:func:`quantile_interval_ranks` takes, among the ranks ``1 <= l < u <= N`` whose bound is at
least 95 %, the narrowest (fewest ranks between them; the higher coverage on a tie). A lower
bound needs ``F(0) = (1 - q)^N <= 0.05``: the worst chip ``X_(1)`` is below the 5th percentile
with probability ``1 - 0.95^N``, which reaches 95 % first at ``N = 59`` (``0.95^58 = 0.051``,
``0.95^59 = 0.0485``). So 59 chips is the least that gives a bound from below, and it is the
worst chip: "with 95 % confidence, at least 95 % of chips are as good as the worst of 59".
With fewer chips the lower bound is NaN and only the upper bound stands (one-sided, the smallest
``u`` with ``F(u - 1) >= 0.95``). With 59 chips the interval is ``[X_(1), X_(10)]``
(coverage 0.951), with 100 chips ``[X_(1), X_(10)]`` (0.966), with 200 chips ``[X_(4), X_(17)]``
(0.967): from 107 chips on the lower bound moves off the single worst chip, so one outlier no
longer sets it (``RANKS_EXAMPLES`` is checked against these).

Yield share
-----------
The share of chips whose accuracy is at or above ``chips.yield_target``.

Chip-to-chip spread against the test set's noise
------------------------------------------------
A chip's measured accuracy ``p_k`` over ``n`` test recordings holds binomial sampling noise of
variance about ``p_k (1 - p_k) / n``, which is there even when every chip is alike. The spread
of the chips (:func:`spread`) is the variance of ``p_k`` over chips less the mean of that
noise, floored at 0: what the chips differ by beyond what the test set can resolve.
"""

from __future__ import annotations

import functools
import math

import numpy as np

__all__ = [
    "ACCURACY_CHIP_MEAN",
    "ACCURACY_P05",
    "ACCURACY_P05_HIGH",
    "ACCURACY_P05_LOW",
    "CONFIDENCE",
    "QUANTILE",
    "YIELD_SHARE",
    "binomial_cdf",
    "quantile_estimate_rank",
    "quantile_interval_ranks",
    "rank_coverage",
    "spread",
    "yield_statistics",
]

#: The quantile of chip accuracy the yield reports (the 5th percentile).
QUANTILE = 0.05
#: Confidence of its interval.
CONFIDENCE = 0.95
#: The cube variables of the yield statistics (their units and long names are declared with the
#: chip dimension, :data:`pipeline.results.chip_cube.CHIP_CUBE_VARIABLES`).
ACCURACY_CHIP_MEAN = "accuracy_chip_mean"
ACCURACY_P05 = "accuracy_p05"
ACCURACY_P05_LOW = "accuracy_p05_low"
ACCURACY_P05_HIGH = "accuracy_p05_high"
YIELD_SHARE = "yield_share"
#: ``N -> (l, u)`` of :func:`quantile_interval_ranks` as the module docstring states them.
RANKS_EXAMPLES = {58: (None, 7), 59: (1, 10), 100: (1, 10), 200: (4, 17)}


def quantile_estimate_rank(n: int, q: float = QUANTILE) -> int:
    """The rank (1-based) of the order statistic that estimates the ``q``-quantile of ``n``
    values: ``ceil(q n)``, at least 1."""
    return max(1, math.ceil(q * n - 1e-9))


def rank_coverage(n: int, low: int | None, high: int | None, q: float = QUANTILE) -> float:
    """The least probability that ``[X_(low), X_(high)]`` of ``n`` values holds the
    ``q``-quantile: ``F(high - 1) - F(low - 1)`` of ``Bin(n, q)``; a missing bound (None) is
    an open end."""
    cdf = binomial_cdf(n, q)
    upper = 1.0 if high is None else float(cdf[high - 1])
    lower = 0.0 if low is None else float(cdf[low - 1])
    return upper - lower


@functools.lru_cache(maxsize=256)
def binomial_cdf(n: int, q: float) -> np.ndarray:
    """float64 ``(n + 1,)``: ``F(k)`` of ``Bin(n, q)`` for ``k = 0 .. n``, from the log pmf
    (``lgamma``; no overflow for any chip count), capped at 1. Plain numpy: building a cube
    does not import scipy.stats."""
    k = np.arange(n + 1)
    lgamma = np.vectorize(math.lgamma, otypes=[np.float64])
    log_pmf = (
        lgamma(n + 1.0) - lgamma(k + 1.0) - lgamma(n - k + 1.0)
        + k * math.log(q) + (n - k) * math.log1p(-q)
    )  # fmt: skip
    cdf = np.minimum(np.cumsum(np.exp(log_pmf)), 1.0)
    cdf.setflags(write=False)  # cached: shared by every caller
    return cdf


@functools.lru_cache(maxsize=256)
def quantile_interval_ranks(
    n: int, q: float = QUANTILE, confidence: float = CONFIDENCE
) -> tuple[int | None, int | None]:
    """Ranks ``(l, u)`` (1-based) of the distribution-free interval ``[X_(l), X_(u)]`` of the
    ``q``-quantile of ``n`` values, of at least ``confidence`` coverage: the narrowest such
    pair (the higher coverage on a tie); ``l`` is None when no lower bound reaches
    ``confidence`` (fewer than 59 values for the 5th percentile at 95 %), and ``u`` None when
    even ``X_(n)`` is not an upper bound."""
    if n < 1:
        return None, None
    cdf = binomial_cdf(n, q)  # cdf[k] = F(k)
    best: tuple[int, float, int, int] | None = None
    for low in range(1, n + 1):
        need = confidence + cdf[low - 1]
        if need > 1.0:
            break
        # The smallest u > low with F(u - 1) >= need.
        above = np.flatnonzero(cdf[low:n] >= need - 1e-12)
        if not above.size:
            continue
        high = low + int(above[0]) + 1
        coverage = float(cdf[high - 1] - cdf[low - 1])
        candidate = (high - low, -coverage, low, high)
        if best is None or candidate < best:
            best = candidate
    if best is not None:
        return best[2], best[3]
    above = np.flatnonzero(cdf[:n] >= confidence - 1e-12)
    return None, (int(above[0]) + 1 if above.size else None)


def yield_statistics(
    accuracy: np.ndarray, target: np.ndarray | float, q: float = QUANTILE
) -> dict[str, np.ndarray]:
    """Yield statistics over the last axis (chips) of ``accuracy``.

    Parameters
    ----------
    accuracy
        float ``(..., chip)`` each chip's accuracy; NaN for a chip a design does not have
        (fewer chips than the cube's chip dimension), left out.
    target
        ``chips.yield_target``, a float or an array broadcasting to ``accuracy.shape[:-1]``.

    Returns
    -------
    dict of float64 ``accuracy.shape[:-1]`` arrays
        ``accuracy_chip_mean`` (mean over the chips), ``accuracy_p05`` (the ``q``-quantile's
        order statistic), ``accuracy_p05_low``, ``accuracy_p05_high`` (its 95 % interval; NaN
        for a bound that ``N`` chips cannot give) and ``yield_share`` (share of chips at or
        above ``target``); NaN throughout where no chip has an accuracy.
    """
    accuracy = np.asarray(accuracy, dtype=np.float64)
    shape = accuracy.shape[:-1]
    targets = np.broadcast_to(np.asarray(target, dtype=np.float64), shape)
    names = (ACCURACY_CHIP_MEAN, ACCURACY_P05, ACCURACY_P05_LOW, ACCURACY_P05_HIGH, YIELD_SHARE)
    out = {name: np.full(shape, np.nan) for name in names}
    for index in np.ndindex(shape):
        values = np.sort(accuracy[index][~np.isnan(accuracy[index])])
        n = len(values)
        if n == 0:
            continue
        low, high = quantile_interval_ranks(n, q)
        out[ACCURACY_CHIP_MEAN][index] = values.mean()
        out[ACCURACY_P05][index] = values[quantile_estimate_rank(n, q) - 1]
        out[ACCURACY_P05_LOW][index] = np.nan if low is None else values[low - 1]
        out[ACCURACY_P05_HIGH][index] = np.nan if high is None else values[high - 1]
        out[YIELD_SHARE][index] = np.mean(values >= targets[index])
    return out


def spread(accuracy: np.ndarray, n_tested: int) -> tuple[float, float]:
    """Chip-to-chip variance of accuracy beyond the test set's binomial noise.

    Parameters
    ----------
    accuracy
        float ``(chips,)`` each chip's accuracy over ``n_tested`` recordings (NaN left out).
    n_tested
        Recordings each chip was tested on.

    Returns
    -------
    (chip_variance, noise_variance)
        ``max(var_k(p_k) - noise, 0)`` (sample variance, ``ddof=1``) and the binomial noise
        ``mean_k(p_k (1 - p_k)) / n_tested``; NaN with fewer than two chips.
    """
    p = np.asarray(accuracy, dtype=np.float64)
    p = p[~np.isnan(p)]
    if p.size < 2:
        return math.nan, math.nan
    noise = float(np.mean(p * (1 - p)) / n_tested)
    return max(float(np.var(p, ddof=1)) - noise, 0.0), noise
