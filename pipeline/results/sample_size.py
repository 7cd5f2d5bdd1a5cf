r"""How many recordings would tell two designs apart: the sample size of a paired test.

Two designs ``a`` and ``b`` scored on the same ``n`` recordings (``R`` repeats each) give, per
recording ``i``, the paired difference

.. math::

    d_i = \frac{s_i(a) - s_i(b)}{R} \in [-1, 1],

``s_i`` the repeats in which recording ``i`` is right; their mean is ``accuracy(a) -
accuracy(b)``. The recordings are the unit of chance (:mod:`pipeline.results.stats`), so the
question "how many recordings would show a difference ``delta``" is the sample size of the
two-sided paired t-test of ``mean(d) = 0`` at level ``alpha``: with ``sigma`` the standard
deviation of ``d_i`` (estimated from the run's recordings, ``ddof = 1``), ``n`` recordings give
the power

.. math::

    \mathrm{power}(n) = P\bigl(|T| > t_{1 - \alpha/2,\, n - 1}\bigr), \qquad
    T \sim t_{n - 1}\Bigl(\mathrm{nc} = \frac{\delta \sqrt{n}}{\sigma}\Bigr),

``T`` noncentral t with ``n - 1`` degrees of freedom (:data:`scipy.stats.nct`), and the answer
is the smallest whole number of recordings per class ``k`` whose ``n = k C`` (``C`` classes,
every class recorded alike, as the stratified folds keep them) reaches the target power
(:func:`recordings_per_class`). Starting from the normal approximation
``n_0 = ((z_{1-\alpha/2} + z_{power}) \sigma / \delta)^2``, ``k`` is stepped down while the power
still holds and up until it does, so the result is the exact smallest ``k``.

Why a t-test and not the report's exact McNemar (one repeat) or bootstrap (several): the sample
size needs a test whose power has a closed form; on ``d_i`` in ``{-1, 0, 1}`` the paired t-test
and McNemar's test ask the same question of the same discordant recordings, and a simulation
(the tests) finds both near the target at the stated ``k``. Two things it does not include: the
answer's Holm correction over its ``m`` comparisons (a design compared alone is tested at
``alpha``; with Holm the smallest p-value is held to ``alpha / m``, which needs more recordings),
and a change of ``sigma`` with ``n`` (the discordance rate is taken as the run measured it).
Where the discordant recordings go nearly all one way (under one in ten the other way), the
t-test's approximation is conservative: fewer recordings than stated already reach the power.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.stats

__all__ = ["ALPHA", "POWER", "paired_power", "recordings_per_class"]

#: Two-sided level of the test the sample size is for.
ALPHA = 0.05
#: The power the sample size reaches.
POWER = 0.8


def paired_power(n: int | np.ndarray, delta: float, sigma: float, alpha: float = ALPHA):
    """Power of the two-sided paired t-test on ``n`` recordings (``n >= 2``) against a mean
    difference ``delta`` with per-recording standard deviation ``sigma`` > 0 (both in the same
    unit: fractions of accuracy); broadcasts over ``n``."""
    n = np.asarray(n, dtype=np.float64)
    df = n - 1.0
    critical = scipy.stats.t.ppf(1.0 - alpha / 2.0, df)
    nc = delta * np.sqrt(n) / sigma
    return scipy.stats.nct.sf(critical, df, nc) + scipy.stats.nct.cdf(-critical, df, nc)


def recordings_per_class(
    differences: np.ndarray,
    delta: float,
    n_classes: int,
    *,
    alpha: float = ALPHA,
    power: float = POWER,
) -> int | None:
    """The fewest recordings per class at which a paired t-test finds a difference ``delta``.

    Parameters
    ----------
    differences
        float (n,): the run's paired differences per recording, ``d_i`` above (fractions).
    delta
        The difference to find (a fraction, e.g. 0.05 for 5 points), non-zero; its sign does not
        matter (the test is two-sided).
    n_classes
        Classes ``C``: the answer ``k`` gives ``k C`` recordings in all.
    alpha, power
        Two-sided level and the power to reach.

    Returns
    -------
    int or None
        ``k`` >= 1 (with ``k C`` >= 2); None when the differences do not vary (fewer than two
        recordings, or every recording alike in both designs: no spread to scale from).

    Raises
    ------
    ValueError
        ``delta`` zero or not finite, ``n_classes`` < 1, ``alpha`` or ``power`` outside (0, 1).
    """
    if not (math.isfinite(delta) and delta != 0):
        raise ValueError(f"delta must be finite and non-zero, got {delta}")
    if n_classes < 1:
        raise ValueError(f"n_classes must be at least 1, got {n_classes}")
    if not (0 < alpha < 1 and 0 < power < 1):
        raise ValueError(f"alpha and power must lie in (0, 1), got {alpha} and {power}")
    d = np.asarray(differences, dtype=np.float64)
    if d.size < 2:
        return None
    sigma = float(np.std(d, ddof=1))
    if not sigma > 0:
        return None
    delta = abs(delta)
    z = scipy.stats.norm.ppf(1.0 - alpha / 2.0) + scipy.stats.norm.ppf(power)
    first = max(1, math.ceil(2 / n_classes), math.ceil((z * sigma / delta) ** 2 / n_classes))

    def enough(k: int) -> bool:
        return float(paired_power(k * n_classes, delta, sigma, alpha)) >= power

    k = first
    while k > 1 and (k - 1) * n_classes >= 2 and enough(k - 1):
        k -= 1
    while not enough(k):
        k += 1
    return k
