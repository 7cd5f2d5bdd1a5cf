r"""Statistics for comparing readouts: accuracy intervals, paired comparisons, Holm, trends.

Every design point of a sweep is scored by k-fold cross-validation on the same recordings and the
same folds, optionally repeated with different splits. A point's result for one model is a boolean
array ``correct`` of shape ``(repeats, n_recordings)``, True where the out-of-fold prediction of
that recording in that repeat equals its label; ``labels`` (``n_recordings``,) gives each
recording's class. Because every point sees the same recordings, comparisons between points are
*paired*: they resample recordings, never predictions independently.

Notation: ``n`` recordings, ``R`` repeats, ``s_i = sum_r correct[r, i]`` the number of repeats in
which recording ``i`` is right, and ``acc = sum_i s_i / (n R)``.

Accuracy interval (:func:`accuracy_interval`)

* ``R == 1``: the Wilson score interval for ``k = sum_i s_i`` successes in ``n`` trials,

  .. math::

      \frac{p + \frac{z^2}{2n} \pm z \sqrt{\frac{p(1-p)}{n} + \frac{z^2}{4n^2}}}{1 + \frac{z^2}{n}}

  with ``p = k/n`` and ``z`` the ``(1 + confidence)/2`` normal quantile (:func:`wilson_interval`:
  SciPy's ``scipy.stats.binomtest(k, n).proportion_ci(confidence, method="wilson")`` step for
  step, for many proportions at once, equal to it bit for bit in the tests).
* ``R > 1``: the repeats of one recording are not independent (they share the recording), so a
  binomial interval on ``n R`` trials would be too narrow. Instead, a percentile bootstrap over
  recordings: each resample draws, *within each class*, as many recordings as the class has, with
  replacement (stratified, so every resample keeps the class counts of the data), and each drawn
  recording brings all its repeats. With ``w_bi`` the number of times recording ``i`` is drawn
  in resample ``b``, ``acc*_b = sum_i w_bi s_i / (n R)``; the interval is the
  ``(1 - confidence)/2`` and ``(1 + confidence)/2`` quantiles of ``acc*`` (linear interpolation).

Paired comparison (:func:`compare_paired`) of ``a`` against ``b`` on the same recordings

* ``difference = acc(a) - acc(b) = (only_a - only_b) / (n R)``, where ``only_a`` (``only_b``)
  counts the (recording, repeat) pairs right in ``a`` only (``b`` only).
* Interval: the stratified bootstrap above, *paired*: the same resampled recordings for ``a`` and
  ``b``, ``d*_b = sum_i w_bi (s_i(a) - s_i(b)) / (n R)``, percentile interval of ``d*``.
* p-value, two-sided. ``R == 1``: the exact McNemar test, the binomial test of ``only_a``
  successes in ``only_a + only_b`` trials with probability 1/2 (:func:`scipy.stats.binomtest`);
  ``p = 1`` when no pair is discordant. ``R > 1`` (McNemar would treat the repeats as
  independent): the bootstrap p-value

  .. math::

      p = \min\left(1, \frac{2 \, (\min(\#\{d^* \le 0\}, \#\{d^* \ge 0\}) + 1)}{B + 1}\right)

  over the ``B`` resamples: about the smallest ``1 - confidence`` whose percentile interval
  excludes 0, with the usual ``+1`` so that a finite number of resamples never reports
  ``p = 0`` (the smallest p is ``2 / (B + 1)``); ``p = 1`` when the observed difference is 0.

Multiple comparisons (:func:`holm`): Holm-Bonferroni step-down adjusted p-values. With the ``m``
p-values sorted ascending, ``p_(1) <= ... <= p_(m)``,

.. math::

    \mathrm{adj}_{(j)} = \max_{i \le j} \min\bigl(1, (m - i + 1) \, p_{(i)}\bigr),

returned in the input's order; reject the hypotheses whose adjusted p-value is below ``alpha``
(family-wise error rate ``alpha``).

Trend (:func:`trend`) of accuracy along a swept value ``x`` (one design point per level ``l``):
the least-squares slope of the points' accuracies ``acc_l`` on ``x_l``,

.. math::

    \mathrm{slope} = \frac{\sum_l (x_l - \operatorname{mean} x) \, \mathrm{acc}_l}
                          {\sum_l (x_l - \operatorname{mean} x)^2}

(accuracy per unit of ``x``). Its interval and two-sided p-value come from the stratified
bootstrap, paired across levels (the same resampled recordings at every level), as for
:func:`compare_paired` with ``R > 1`` (``p = 1`` when the observed slope is 0).

Chips (:func:`compare_over_chips`). A design simulated as ``C`` chips (one fabricated chip each,
the same chip instances for every design: common random numbers) gives ``correct`` of shape
``(chips, repeats, n)``, and per chip the accuracy ``acc_c = sum_i s_ci / (n R)``. A statistic of
the chips' accuracies ``T(acc_1, ..., acc_C)`` (their mean, or their 5th percentile: the yield)
is compared between two designs by a bootstrap over both sources of chance at once: each resample
draws recordings (stratified within classes, as above, the same for both designs) and chips (with
replacement, the same chip indices for both designs when they have as many chips; independently
otherwise), ``d*_b = T(acc*_a) - T(acc*_b)`` with ``acc*_c = sum_i w_bi s_ci / (n R)`` over the
drawn chips; percentile interval and bootstrap p-value as for ``R > 1`` above. The chip spread
and the test set's noise both widen the interval; neither is mistaken for the other.

Every percentile interval is widened, if needed, to contain its estimate (a percentile interval
of a skewed bootstrap distribution can miss it by a resample), so ``low <= estimate <= high``
always holds. No function returns NaN or divides by zero: one class, one recording, 0 % or 100 %
accuracy, identical or opposite predictions all give finite, degenerate-where-due results. The
bootstraps are vectorized (no loop over resamples) and deterministic given the Generator.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.special

#: The ``method`` of an :class:`Interval` from the Wilson score (one repeat).
WILSON_METHOD = "Wilson score"


@dataclass(frozen=True)
class Interval:
    """An accuracy and its confidence interval.

    Attributes
    ----------
    estimate
        Accuracy, the fraction correct over all recordings and repeats (1 = 100 %).
    low, high
        Confidence interval bounds, ``0 <= low <= estimate <= high <= 1``.
    method
        How the interval was computed, e.g. ``"Wilson score"``.
    confidence
        Confidence level of the interval, in (0, 1).
    """

    estimate: float
    low: float
    high: float
    method: str
    confidence: float = 0.95


@dataclass(frozen=True)
class PairedComparison:
    """Accuracy of ``a`` minus accuracy of ``b`` on the same recordings, with interval and test.

    Attributes
    ----------
    difference
        ``accuracy(a) - accuracy(b)``, in [-1, 1].
    low, high
        Confidence interval of the difference, ``low <= difference <= high``.
    p_value
        Two-sided p-value of "no difference", in (0, 1].
    only_a
        Number of (recording, repeat) pairs correct in ``a`` only (discordant pairs).
    only_b
        Number of (recording, repeat) pairs correct in ``b`` only.
    method
        The interval method and the test.
    confidence
        Confidence level of the interval, in (0, 1).
    """

    difference: float
    low: float
    high: float
    p_value: float
    only_a: int
    only_b: int
    method: str
    confidence: float = 0.95

    def significant(self, alpha: float = 0.05) -> bool:
        """Whether ``p_value < alpha`` (unadjusted; use :func:`holm` for several comparisons)."""
        return self.p_value < alpha


@dataclass(frozen=True)
class Trend:
    """Least-squares slope of accuracy along a swept value, with interval and test.

    Attributes
    ----------
    slope
        Accuracy per unit of the swept value (1/unit of ``x``).
    low, high
        Confidence interval of the slope, ``low <= slope <= high``.
    p_value
        Two-sided bootstrap p-value of "slope 0", in (0, 1].
    method
        How the slope, interval and p-value were computed.
    confidence
        Confidence level of the interval, in (0, 1).
    """

    slope: float
    low: float
    high: float
    p_value: float
    method: str
    confidence: float = 0.95


def accuracy_interval(
    correct: np.ndarray,
    labels: np.ndarray,
    *,
    rng: np.random.Generator,
    confidence: float = 0.95,
    resamples: int = 2000,
) -> Interval:
    """Accuracy of one model at one design point, with its confidence interval.

    Parameters
    ----------
    correct
        bool-like (repeats, n_recordings): True (or 1) where the out-of-fold prediction is right.
    labels
        int (n_recordings,): class of each recording; the bootstrap resamples within classes.
    rng
        Source of the bootstrap's randomness; unused when ``repeats == 1``.
    confidence
        Confidence level, in (0, 1).
    resamples
        Bootstrap resamples (``repeats > 1``), at least 1.

    Returns
    -------
    Interval
        Wilson score interval when ``repeats == 1``, otherwise the stratified percentile
        bootstrap over recordings (see the module docstring).

    Raises
    ------
    ValueError
        If a shape, value, ``confidence`` or ``resamples`` is invalid.
    TypeError
        If ``rng`` is not a :class:`numpy.random.Generator`.
    """
    correct = _correct_array(correct, "correct", ndim=2)
    labels = _labels_array(labels, correct.shape[-1])
    _check_settings(rng, confidence, resamples)
    repeats, n = correct.shape
    per_recording = correct.sum(axis=0, dtype=np.int64)
    k = int(per_recording.sum())
    estimate = k / (n * repeats)
    if repeats == 1:
        low, high = (float(bound) for bound in wilson_interval(k, n, confidence))
        low, high = _contain(estimate, low, high)
        return Interval(estimate, low, high, WILSON_METHOD, confidence)
    totals = _bootstrap_totals(per_recording, labels, resamples, rng)
    boot = totals.astype(np.float64) / (n * repeats)
    low, high = _contain(estimate, *_percentile(boot, confidence))
    method = f"stratified bootstrap over recordings ({resamples} resamples, percentile)"
    return Interval(estimate, low, high, method, confidence)


def wilson_interval(
    k: np.ndarray, n: np.ndarray, confidence: float = 0.95
) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score intervals of many binomial proportions at once.

    The interval :func:`accuracy_interval` gives for one repeat, without a SciPy call per
    proportion: ``scipy.stats.binomtest(k, n).proportion_ci(confidence, method="wilson")`` also
    searches for the test's p-value, about half a millisecond each, more than a sweep's cube
    can spend on a point. The arithmetic is SciPy's, step for step (Newcombe's form; ``low = 0``
    where ``k == 0``, ``high = 1`` where ``k == n``), so the bounds agree with SciPy's to
    rounding.

    Parameters
    ----------
    k
        int (...): successes, ``0 <= k <= n``.
    n
        int (...), broadcastable with ``k``: trials, at least 1.
    confidence
        Confidence level, in (0, 1).

    Returns
    -------
    low, high : numpy.ndarray
        float64 (broadcast shape of ``k`` and ``n``): the interval bounds (fractions), not
        widened to contain ``k / n`` (``low <= k / n <= high`` holds up to rounding).

    Raises
    ------
    ValueError
        If ``k`` or ``n`` is not integer, ``n < 1``, ``k`` lies outside ``[0, n]``, the shapes
        do not broadcast, or ``confidence`` is not in (0, 1).
    """
    k, n = np.asarray(k), np.asarray(n)
    for name, values in (("k", k), ("n", n)):
        if not np.issubdtype(values.dtype, np.integer):
            raise ValueError(f"{name} must be integers, got dtype {values.dtype}")
    try:
        k, n = np.broadcast_arrays(k.astype(np.int64), n.astype(np.int64))
    except ValueError:
        raise ValueError(f"k {k.shape} and n {n.shape} do not broadcast") from None
    if np.any(n < 1):
        raise ValueError("n must be >= 1 (trials)")
    if np.any((k < 0) | (k > n)):
        raise ValueError("k must lie in [0, n] (successes)")
    if isinstance(confidence, bool) or not isinstance(confidence, int | float | np.floating):
        raise ValueError(f"confidence must be a number in (0, 1), got {confidence!r}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence}")
    # Term for term as scipy.stats._binomtest._binom_wilson_conf_int, so that the rounding is
    # the same; the integer products stay integers before they meet a float, as there.
    z = scipy.special.ndtri(0.5 + 0.5 * confidence)
    p = k / n
    denom = 2 * (n + z**2)
    center = (2 * n * p + z**2) / denom
    q = 1 - p
    delta = z / denom * np.sqrt(4 * n * p * q + z**2)
    low = np.where(k == 0, 0.0, center - delta)
    high = np.where(k == n, 1.0, center + delta)
    return low, high


def compare_paired(
    correct_a: np.ndarray,
    correct_b: np.ndarray,
    labels: np.ndarray,
    *,
    rng: np.random.Generator,
    confidence: float = 0.95,
    resamples: int = 2000,
) -> PairedComparison:
    """Compare two models or design points evaluated on the same recordings and folds.

    Parameters
    ----------
    correct_a, correct_b
        bool-like (repeats, n_recordings), same shape: right predictions of ``a`` and ``b``,
        recording ``i`` and repeat ``r`` the same recording and split in both.
    labels
        int (n_recordings,): class of each recording; the bootstrap resamples within classes.
    rng
        Source of the bootstrap's randomness.
    confidence
        Confidence level of the interval, in (0, 1).
    resamples
        Bootstrap resamples, at least 1.

    Returns
    -------
    PairedComparison
        ``accuracy(a) - accuracy(b)``, its paired stratified bootstrap interval, and the exact
        McNemar p-value (``repeats == 1``) or the bootstrap p-value (``repeats > 1``); see the
        module docstring.

    Raises
    ------
    ValueError
        If a shape, value, ``confidence`` or ``resamples`` is invalid.
    TypeError
        If ``rng`` is not a :class:`numpy.random.Generator`.
    """
    correct_a = _correct_array(correct_a, "correct_a", ndim=2)
    correct_b = _correct_array(correct_b, "correct_b", ndim=2)
    if correct_a.shape != correct_b.shape:
        raise ValueError(
            f"correct_a and correct_b must have the same shape (repeats, n_recordings), "
            f"got {correct_a.shape} and {correct_b.shape}"
        )
    labels = _labels_array(labels, correct_a.shape[-1])
    _check_settings(rng, confidence, resamples)
    repeats, n = correct_a.shape
    only_a = int(np.count_nonzero(correct_a & ~correct_b))
    only_b = int(np.count_nonzero(correct_b & ~correct_a))
    difference = (only_a - only_b) / (n * repeats)
    # Integer per-recording differences keep d* exactly 0 where a and b agree.
    per_recording = correct_a.sum(axis=0, dtype=np.int64) - correct_b.sum(axis=0, dtype=np.int64)
    totals = _bootstrap_totals(per_recording, labels, resamples, rng)
    boot = totals.astype(np.float64) / (n * repeats)
    low, high = _contain(difference, *_percentile(boot, confidence))
    interval = f"stratified paired bootstrap over recordings ({resamples} resamples, percentile)"
    if repeats == 1:
        # Imported here, not with the module: scipy.stats takes about a second to import, and
        # building a sweep's cubes (Wilson intervals, bootstraps) needs none of it.
        import scipy.stats

        discordant = only_a + only_b
        p_value = (
            1.0
            if discordant == 0
            else min(1.0, float(scipy.stats.binomtest(only_a, discordant, 0.5).pvalue))
        )
        test = "exact McNemar test"
    else:
        p_value = _bootstrap_p(difference, boot)
        test = "two-sided bootstrap test"
    return PairedComparison(
        difference, low, high, p_value, only_a, only_b, f"{interval}; {test}", confidence
    )


def holm(p_values: Sequence[float] | np.ndarray) -> np.ndarray:
    """Holm-Bonferroni step-down adjusted p-values.

    Parameters
    ----------
    p_values
        float (m,): raw p-values, each in [0, 1].

    Returns
    -------
    numpy.ndarray
        float64 (m,): adjusted p-values in the input's order, each ``>=`` its raw p-value and
        ``<= 1``, monotone in the raw p-values; empty for an empty input.

    Raises
    ------
    ValueError
        If ``p_values`` is not 1-D or holds a value outside [0, 1] (or NaN).
    """
    p = np.asarray(p_values, dtype=np.float64)
    if p.ndim != 1:
        raise ValueError(f"p_values must be 1-D, got shape {p.shape}")
    if not np.all((p >= 0.0) & (p <= 1.0)):
        raise ValueError("p_values must all lie in [0, 1] (no NaN)")
    m = p.size
    if m == 0:
        return np.empty(0, dtype=np.float64)
    order = np.argsort(p, kind="stable")
    scaled = np.minimum(1.0, (m - np.arange(m)) * p[order])
    adjusted = np.empty(m, dtype=np.float64)
    adjusted[order] = np.maximum.accumulate(scaled)
    return adjusted


def trend(
    correct: np.ndarray,
    x: np.ndarray,
    labels: np.ndarray,
    *,
    rng: np.random.Generator,
    confidence: float = 0.95,
    resamples: int = 2000,
) -> Trend:
    """Least-squares slope of accuracy along a swept value, with bootstrap interval and p-value.

    Parameters
    ----------
    correct
        bool-like (levels, repeats, n_recordings): right predictions of one design point per
        level, all on the same recordings and folds.
    x
        float (levels,): the swept value of each level (any unit), at least 2 distinct values.
    labels
        int (n_recordings,): class of each recording; the bootstrap resamples within classes.
    rng
        Source of the bootstrap's randomness.
    confidence
        Confidence level of the interval, in (0, 1).
    resamples
        Bootstrap resamples, at least 1.

    Returns
    -------
    Trend
        Slope in accuracy per unit of ``x``, its paired stratified bootstrap interval and
        two-sided bootstrap p-value; see the module docstring.

    Raises
    ------
    ValueError
        If a shape or value is invalid, ``x`` has fewer than 2 distinct values or a non-finite
        one, or ``confidence`` or ``resamples`` is invalid.
    TypeError
        If ``rng`` is not a :class:`numpy.random.Generator`.
    """
    correct = _correct_array(correct, "correct", ndim=3)
    levels, repeats, n = correct.shape
    x = np.asarray(x)
    if x.shape != (levels,):
        raise ValueError(f"x must have shape (levels,) = ({levels},), got {x.shape}")
    if not np.issubdtype(x.dtype, np.number) or np.issubdtype(x.dtype, np.complexfloating):
        raise ValueError(f"x must be real numbers, got dtype {x.dtype}")
    x = x.astype(np.float64)
    if not np.all(np.isfinite(x)):
        raise ValueError("x must be finite")
    if np.unique(x).size < 2:
        raise ValueError("x must hold at least 2 distinct values to fit a slope")
    labels = _labels_array(labels, n)
    _check_settings(rng, confidence, resamples)
    centred_x = x - x.mean()
    sxx = float(centred_x @ centred_x)
    if not (sxx > 0.0 and math.isfinite(sxx)):
        raise ValueError("x spreads too little or too much for a finite least-squares slope")
    # (n, levels) counts, taken relative to level 0: the sum of centred x is 0 only up to
    # rounding, and integer offsets make an exactly flat accuracy give an exactly zero slope.
    counts = correct.sum(axis=1, dtype=np.int64).T
    offsets = (counts - counts[:, :1]).astype(np.float64)
    scale = n * repeats * sxx
    per_recording = offsets @ centred_x
    slope = float(per_recording.sum() / scale)
    weights = _bootstrap_weights(labels, resamples, rng)
    boot = weights @ per_recording / scale
    low, high = _contain(slope, *_percentile(boot, confidence))
    method = (
        f"least-squares slope of accuracy on x; stratified paired bootstrap over recordings "
        f"({resamples} resamples, percentile interval, two-sided bootstrap test)"
    )
    return Trend(slope, low, high, _bootstrap_p(slope, boot), method, confidence)


def compare_over_chips(
    correct_a: np.ndarray,
    correct_b: np.ndarray,
    labels: np.ndarray,
    *,
    statistic: Callable[[np.ndarray], np.ndarray],
    rng: np.random.Generator,
    confidence: float = 0.95,
    resamples: int = 2000,
) -> PairedComparison:
    """Compare a statistic of the chips' accuracies of two designs, resampling chips and
    recordings together (see the module docstring).

    Parameters
    ----------
    correct_a, correct_b
        bool-like (chips, repeats, n_recordings): right predictions of each chip of ``a`` and of
        ``b``; recording ``i`` and repeat ``r`` the same recording and split in both. The chip
        counts may differ (then chips are drawn independently for each design).
    labels
        int (n_recordings,): class of each recording; recordings are resampled within classes.
    statistic
        Maps float64 chip accuracies (..., chips) to (...), along the last axis: e.g. the mean,
        or the 5th percentile over chips.
    rng, confidence, resamples
        As in :func:`compare_paired`.

    Returns
    -------
    PairedComparison
        ``statistic(acc_a) - statistic(acc_b)``, its percentile interval and two-sided bootstrap
        p-value; ``only_a``/``only_b`` count the (chip, repeat, recording) triples right in one
        design only (chip by chip; 0 when the chip counts differ).

    Raises
    ------
    ValueError
        A shape, value, ``confidence`` or ``resamples`` is invalid.
    TypeError
        ``rng`` is not a :class:`numpy.random.Generator`.
    """
    correct_a = _correct_array(correct_a, "correct_a", ndim=3)
    correct_b = _correct_array(correct_b, "correct_b", ndim=3)
    if correct_a.shape[1:] != correct_b.shape[1:]:
        raise ValueError(
            "correct_a and correct_b must share (repeats, n_recordings), got "
            f"{correct_a.shape} and {correct_b.shape}"
        )
    _, repeats, n = correct_a.shape
    labels = _labels_array(labels, n)
    _check_settings(rng, confidence, resamples)
    scale = float(n * repeats)
    # (chips, n) right predictions per recording; chip accuracies are weights @ these / (n R).
    per_a = correct_a.sum(axis=1, dtype=np.int64)
    per_b = correct_b.sum(axis=1, dtype=np.int64)
    observed = float(
        np.asarray(statistic(per_a.sum(axis=1) / scale))
        - np.asarray(statistic(per_b.sum(axis=1) / scale))
    )
    weights = _bootstrap_weights(labels, resamples, rng)
    boot_a = weights @ per_a.T.astype(np.float64) / scale  # (B, chips of a)
    boot_b = weights @ per_b.T.astype(np.float64) / scale
    chips_a = rng.integers(0, per_a.shape[0], size=(resamples, per_a.shape[0]))
    same = per_a.shape[0] == per_b.shape[0]
    chips_b = chips_a if same else rng.integers(0, per_b.shape[0], size=(resamples, per_b.shape[0]))
    boot = np.asarray(statistic(np.take_along_axis(boot_a, chips_a, axis=1))) - np.asarray(
        statistic(np.take_along_axis(boot_b, chips_b, axis=1))
    )
    low, high = _contain(observed, *_percentile(boot, confidence))
    only_a = int(np.count_nonzero(correct_a & ~correct_b)) if same else 0
    only_b = int(np.count_nonzero(correct_b & ~correct_a)) if same else 0
    method = (
        "bootstrap over chips and recordings "
        f"({'paired chips' if same else 'independent chips'}, stratified paired recordings, "
        f"{resamples} resamples, percentile); two-sided bootstrap test"
    )
    return PairedComparison(
        observed, low, high, _bootstrap_p(observed, boot), only_a, only_b, method, confidence
    )


def _stratified_draws(
    labels: np.ndarray, resamples: int, rng: np.random.Generator
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """The draws of the stratified bootstrap, one class at a time in ascending label order.

    Every bootstrap of this module draws through here, so that they all consume ``rng`` alike:
    one ``rng.integers`` call per class. The draws are made as the iterator advances; consume it
    to the end.

    Parameters
    ----------
    labels
        (n_recordings,): class of each recording.
    resamples
        Number of resamples ``B``.
    rng
        Source of the draws.

    Yields
    ------
    members : numpy.ndarray
        int64 (m,): the recordings of one class, ascending.
    picks : numpy.ndarray
        int64 (B, m): in each resample, the class's ``m`` draws with replacement, as positions
        into ``members``.
    """
    for cls in np.unique(labels):
        members = np.flatnonzero(labels == cls)
        yield members, rng.integers(0, members.size, size=(resamples, members.size))


def _bootstrap_weights(labels: np.ndarray, resamples: int, rng: np.random.Generator) -> np.ndarray:
    """How often each recording is drawn in each stratified bootstrap resample.

    Parameters
    ----------
    labels
        (n_recordings,): class of each recording.
    resamples
        Number of resamples ``B``.
    rng
        Source of the draws (:func:`_stratified_draws`).

    Returns
    -------
    numpy.ndarray
        float64 (B, n_recordings), integer-valued: within each class, every row sums to the
        class's number of recordings.
    """
    weights = np.zeros((resamples, labels.size))
    for members, picks in _stratified_draws(labels, resamples, rng):
        # Counted per class, each resample in its own run of m bins: one count over all
        # B * n_recordings bins, through several temporaries of that size, took 3-4 times longer.
        m = members.size
        slots = picks + (np.arange(resamples, dtype=np.int64) * m)[:, np.newaxis]
        counts = np.bincount(slots.ravel(), minlength=resamples * m)
        weights[:, members] = counts.reshape(resamples, m)
    return weights


def _bootstrap_totals(
    values: np.ndarray, labels: np.ndarray, resamples: int, rng: np.random.Generator
) -> np.ndarray:
    """``sum_i w_bi values_i`` for every stratified bootstrap resample ``b``, as integers.

    The same draws as :func:`_bootstrap_weights`, summed without building the weights: the
    drawn values are gathered and added directly. Converted to float64, the result equals
    ``_bootstrap_weights(labels, resamples, rng) @ values.astype(np.float64)`` bit for bit:
    every product and partial sum there is an integer of magnitude at most
    ``n_recordings * max |values|``, far below 2**53, hence exact in whatever order (and with
    whatever fused multiply-adds) the matrix product adds them.

    Parameters
    ----------
    values
        int64 (n_recordings,): the integer statistic of each recording.
    labels
        (n_recordings,): class of each recording.
    resamples
        Number of resamples ``B``.
    rng
        Source of the draws (:func:`_stratified_draws`).

    Returns
    -------
    numpy.ndarray
        int64 (B,): the resampled sums.
    """
    totals = np.zeros(resamples, dtype=np.int64)
    for members, picks in _stratified_draws(labels, resamples, rng):
        # einsum adds a class's short rows several times faster than sum(axis=1).
        totals += np.einsum("ij->i", np.take(values[members], picks))
    return totals


def _percentile(boot: np.ndarray, confidence: float) -> tuple[float, float]:
    """The equal-tailed percentile interval of bootstrap values (linear interpolation)."""
    tail = (1.0 - confidence) / 2.0
    low, high = np.quantile(boot, [tail, 1.0 - tail])
    return float(low), float(high)


def _contain(estimate: float, low: float, high: float) -> tuple[float, float]:
    """Widen ``[low, high]`` to contain ``estimate`` (a percentile interval may miss it)."""
    return min(low, estimate), max(high, estimate)


def _bootstrap_p(observed: float, boot: np.ndarray) -> float:
    """Two-sided bootstrap p-value of "the statistic is 0"; see the module docstring."""
    if observed == 0.0:
        return 1.0
    below = int(np.count_nonzero(boot <= 0.0))
    above = int(np.count_nonzero(boot >= 0.0))
    return min(1.0, 2.0 * (min(below, above) + 1) / (boot.size + 1))


def _correct_array(values: np.ndarray, name: str, *, ndim: int) -> np.ndarray:
    """Validate a bool-like array of ``ndim`` dimensions and return it as bool."""
    array = np.asarray(values)
    shape = "(repeats, n_recordings)" if ndim == 2 else "(levels or chips, repeats, n_recordings)"
    if array.ndim != ndim:
        raise ValueError(f"{name} must have shape {shape}, got {array.ndim}-D shape {array.shape}")
    if any(size < 1 for size in array.shape):
        raise ValueError(f"{name} must have every dimension >= 1, got shape {array.shape}")
    if array.dtype == np.bool_:
        return array
    if not np.issubdtype(array.dtype, np.number) or np.issubdtype(array.dtype, np.complexfloating):
        raise ValueError(f"{name} must be bool or 0/1 numbers, got dtype {array.dtype}")
    if not np.all((array == 0) | (array == 1)):
        raise ValueError(f"{name} must hold only True/False or 0/1 (missing entries dropped)")
    return array.astype(bool)


def _labels_array(labels: np.ndarray, n_recordings: int) -> np.ndarray:
    """Validate class labels for ``n_recordings`` recordings."""
    labels = np.asarray(labels)
    if labels.shape != (n_recordings,):
        raise ValueError(
            f"labels must have shape (n_recordings,) = ({n_recordings},), got {labels.shape}"
        )
    if not (np.issubdtype(labels.dtype, np.integer) or labels.dtype == np.bool_):
        raise ValueError(f"labels must be integers (class of each recording), got {labels.dtype}")
    return labels


def _check_settings(rng: np.random.Generator, confidence: float, resamples: int) -> None:
    """Validate the options shared by every function."""
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if isinstance(confidence, bool) or not isinstance(confidence, int | float | np.floating):
        raise ValueError(f"confidence must be a number in (0, 1), got {confidence!r}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence}")
    if isinstance(resamples, bool) or not isinstance(resamples, int | np.integer):
        raise ValueError(f"resamples must be an integer >= 1, got {resamples!r}")
    if resamples < 1:
        raise ValueError(f"resamples must be >= 1, got {resamples}")
