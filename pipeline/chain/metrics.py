r"""Spike-train metrics: SSNR, STE, equivalent resolution, event and data rates.

Spike signal-to-noise ratio, per train, from the TRUE and REAL spike counts:

.. math::

    \mathrm{ssnr\_db} = 20 \log_{10} \frac{N_\mathrm{true}}{|N_\mathrm{real} - N_\mathrm{true}|}

* ``N_real == N_true`` (including both 0): ``+inf`` (no count error).
* ``N_true == 0 < N_real``: ``-inf`` (the limit of the formula: all spikes are noise).

Over a dataset the counts are pooled (:func:`pooled_ssnr_db`):
``20 * log10(sum N_true / sum |N_real - N_true|)``, which is ``+inf`` only when every train is
exact and never NaN.

Spike timing error, per train, as the paper writes it:

.. math::

    \mathrm{ste\_s2} = \frac{\sum_i (dt_i - \operatorname{mean}(dt))^2}{N_\mathrm{real}}
        \, (N_\mathrm{real} - N_\mathrm{true})

with ``dt_i`` the time from TRUE spike ``i`` to the nearest REAL spike. Its quirks, kept on
purpose: it is 0 whenever the counts agree however far the spikes moved, and it is negative when
the REAL train has fewer spikes. The sign-safe variant uses ``|N_real - N_true|``. Edge cases:

* ``N_true == 0``: no TRUE spike to time, both variants give 0.
* ``N_real == 0 < N_true``: no nearest REAL spike; the paper variant gives ``-inf`` (its sign),
  the sign-safe one ``+inf``.

Over a dataset the STE is the mean over trains (``+-inf`` propagates; no NaN can arise because a
variant's infinities all have one sign).

Equivalent bit resolution: ``log2(full_scale_v / threshold_v)`` (0.09 V of 1 V: 3.47 bits).

Event rate of the array: spikes per second summed over taxels, averaged over recordings. Data
rate with address-event representation: each event carries the taxel address and its polarity,
``ceil(log2(n_taxels)) + 1`` bits (1 bit for a single taxel); time is implicit in the
asynchronous bus.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from pipeline.chain.spikes import SpikeTrains
from pipeline.jit import kernel


def _about(units: str, long_name: str) -> dict[str, str]:
    """Field metadata: CF ``units`` and a prose name, declared once for stores and cubes."""
    return {"units": units, "long_name": long_name}


@dataclass(frozen=True, eq=False)
class SpikeMetrics:
    """Scene-level spike metrics; see :mod:`pipeline.chain.metrics` for definitions and edge cases.

    Each field's ``metadata`` holds its ``units`` and ``long_name``.
    """

    ssnr_db: float = field(metadata=_about("dB", "spike signal-to-noise ratio, pooled counts"))
    ste_s2: float = field(metadata=_about("s^2", "spike timing error, mean over trains"))
    ste_sign_safe_s2: float = field(
        metadata=_about("s^2", "sign-safe spike timing error, mean over trains")
    )
    event_rate_hz: float = field(metadata=_about("Hz", "array events per second"))
    data_rate_bps: float = field(metadata=_about("bit/s", "address-event data rate"))
    equivalent_bits: float = field(
        metadata=_about("bit", "equivalent resolution log2(full_scale_v / threshold_v)")
    )


SteVariant = Literal["paper", "sign_safe"]


def ssnr_db(n_true: np.ndarray | int, n_real: np.ndarray | int) -> np.ndarray:
    """Per-train SSNR in dB (float64, same shape as the inputs); see the module docstring."""
    n_true = np.asarray(n_true, dtype=np.float64)
    return _ssnr_from_error(n_true, np.abs(np.asarray(n_real, dtype=np.float64) - n_true))


def pooled_ssnr_db(n_true: np.ndarray, n_real: np.ndarray) -> float:
    """SSNR of a set of trains with counts pooled: ``+inf`` only if every train is exact."""
    n_true = np.asarray(n_true, dtype=np.int64)
    error = np.abs(np.asarray(n_real, dtype=np.int64) - n_true).sum()
    return float(_ssnr_from_error(np.float64(n_true.sum()), np.float64(error)))


def _ssnr_from_error(n_true: np.ndarray, error: np.ndarray) -> np.ndarray:
    exact = error == 0
    with np.errstate(divide="ignore"):
        return np.where(exact, np.inf, 20.0 * np.log10(n_true / np.where(exact, 1.0, error)))


@kernel()
def _nearest_gaps(true_t, real_t, out):  # pragma: no cover - compiled
    """``out[i]`` = distance from ``true_t[i]`` to the nearest of the sorted ``real_t``."""
    j = 0
    n_real = real_t.shape[0]
    for i in range(true_t.shape[0]):
        t = true_t[i]
        while j + 1 < n_real and real_t[j + 1] <= t:
            j += 1
        best = abs(t - real_t[j])
        if j + 1 < n_real:
            best = min(best, abs(real_t[j + 1] - t))
        out[i] = best


@kernel()
def _ste_kernel(true_t, real_t, sign_safe):  # pragma: no cover - compiled
    n_true = true_t.shape[0]
    n_real = real_t.shape[0]
    if n_true == 0:
        return 0.0
    if n_real == 0:
        return np.inf if sign_safe else -np.inf
    gaps = np.empty(n_true)
    _nearest_gaps(true_t, real_t, gaps)
    spread = np.sum((gaps - gaps.mean()) ** 2)
    difference = abs(n_real - n_true) if sign_safe else n_real - n_true
    return spread / n_real * difference


def ste_s2(true_times_s: np.ndarray, real_times_s: np.ndarray, variant: SteVariant = "paper"):
    """STE of one train pair in s^2 (float); both trains sorted, float64 seconds."""
    true_t = np.ascontiguousarray(true_times_s, dtype=np.float64)
    real_t = np.ascontiguousarray(real_times_s, dtype=np.float64)
    return float(_ste_kernel(true_t, real_t, variant == "sign_safe"))


@kernel()
def _ste_trains(true_t, true_count, real_t, real_count, sign_safe, out):  # pragma: no cover
    a = 0
    b = 0
    for k in range(true_count.shape[0]):
        out[k] = _ste_kernel(
            true_t[a : a + true_count[k]], real_t[b : b + real_count[k]], sign_safe
        )
        a += true_count[k]
        b += real_count[k]


def ste_per_train(
    true: SpikeTrains, real: SpikeTrains, variant: SteVariant = "paper"
) -> np.ndarray:
    """float64 (n_recordings, n_taxels): STE of every train pair."""
    out = np.empty(true.count.size, dtype=np.float64)
    _ste_trains(
        true.times_s,
        true.count.ravel(),
        real.times_s,
        real.count.ravel(),
        variant == "sign_safe",
        out,
    )
    return out.reshape(true.count.shape)


def equivalent_bits(full_scale_v: float, threshold_v: float) -> float:
    """``log2(full_scale_v / threshold_v)``: the resolution of an ADC with this step."""
    return math.log2(full_scale_v / threshold_v)


def event_rate_hz(trains: SpikeTrains) -> float:
    """Spikes per second of the whole array, averaged over recordings."""
    per_recording = trains.count.sum(axis=1) / trains.duration_s
    return float(per_recording.mean())


def bits_per_event(n_taxels: int) -> int:
    """Address-event size: ``ceil(log2(n_taxels))`` address bits plus one polarity bit."""
    return math.ceil(math.log2(n_taxels)) + 1 if n_taxels > 1 else 1


def data_rate_bps(trains: SpikeTrains) -> float:
    """Bits per second of the array's address-event stream."""
    return event_rate_hz(trains) * bits_per_event(trains.n_taxels)


CORRELATION_METHODS = ("pearson", "spearman")


def correlate_with_accuracy(metric: np.ndarray, accuracy: np.ndarray) -> dict[str, tuple]:
    """Pearson and Spearman correlation of a spike metric with accuracy across sweep points.

    Points whose metric is not finite (an SSNR of +inf where REAL equals TRUE) are left out: a
    rank or a line through infinity means nothing. With fewer than 3 usable points, or a
    constant input, the correlation is undefined and reported as NaN with its reason.
    Otherwise the coefficients and two-sided p-values are ``scipy.stats.pearsonr`` and
    ``scipy.stats.spearmanr``, computed step for step with :mod:`scipy.special` (equal to them
    bit for bit in the tests): importing :mod:`scipy.stats` takes about a second, more than a
    warm re-run spends on its cubes otherwise.

    Parameters
    ----------
    metric, accuracy : float64 (n_points,)
        One value per sweep point (accuracy averaged over folds).

    Returns
    -------
    dict
        ``{method: (r, p_value, n_used, note)}`` for ``pearson`` and ``spearman``.
    """
    metric = np.asarray(metric, dtype=np.float64)
    accuracy = np.asarray(accuracy, dtype=np.float64)
    usable = np.isfinite(metric) & np.isfinite(accuracy)
    x, y = metric[usable], accuracy[usable]
    note = ""
    if len(x) < 3:
        note = f"undefined: {len(x)} points with a finite metric (3 needed)"
    elif np.ptp(x) == 0 or np.ptp(y) == 0:
        note = "undefined: constant input"
    if note:
        return {method: (math.nan, math.nan, len(x), note) for method in CORRELATION_METHODS}
    return {
        "pearson": (*_pearson(x, y), len(x), ""),
        "spearman": (*_spearman(x, y), len(x), ""),
    }


def _pearson(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """``scipy.stats.pearsonr(x, y)`` (two-sided) of float64 (n,), n >= 3, neither constant.

    SciPy's arithmetic term for term: the centred values scaled by their largest magnitude
    before the norm, ``r`` clipped to [-1, 1], and ``p = 2 * betaincc(n/2 - 1, n/2 - 1,
    (|r| + 1) / 2)``, the tail of ``r``'s null distribution, a beta on (-1, 1).
    """
    from scipy import special  # imported here: see correlate_with_accuracy

    xm = x - np.mean(x, axis=-1, keepdims=True)
    ym = y - np.mean(y, axis=-1, keepdims=True)
    xmax = np.max(np.abs(xm), axis=-1, keepdims=True)
    ymax = np.max(np.abs(ym), axis=-1, keepdims=True)
    normxm = xmax * np.linalg.norm(xm / xmax, ord=2, axis=-1, keepdims=True)
    normym = ymax * np.linalg.norm(ym / ymax, ord=2, axis=-1, keepdims=True)
    r = np.clip(np.vecdot(xm / normxm, ym / normym, axis=-1), -1.0, 1.0)
    ab = np.asarray(x.shape[-1] / 2 - 1, dtype=np.float64)
    p = 2 * special.betaincc(ab, ab, (np.abs(r) - -1) / 2)
    return float(r), float(p)


def _spearman(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """``scipy.stats.spearmanr(x, y)`` (two-sided) of float64 (n,), n >= 3, neither constant.

    SciPy's arithmetic term for term: the Pearson correlation of the average ranks
    (``numpy.corrcoef``), ``t = rs sqrt((n - 2) / ((rs + 1)(1 - rs)))`` and ``p`` twice
    Student's t tail with ``n - 2`` degrees of freedom.
    """
    from scipy import special  # imported here: see correlate_with_accuracy

    rs = np.corrcoef(np.column_stack((_average_ranks(x), _average_ranks(y))), rowvar=False)
    dof = x.size - 2
    with np.errstate(divide="ignore"):  # rs is 1 on the diagonal
        t = rs * np.sqrt((dof / ((rs + 1.0) * (1.0 - rs))).clip(0))
    p = 2 * special.stdtr(dof, -np.abs(t))
    return float(rs[1, 0]), float(p[1, 0])


def _average_ranks(values: np.ndarray) -> np.ndarray:
    """float64 (n,): 1-based ranks, ties sharing their mean rank (``scipy.stats.rankdata``).

    Every rank is a whole or half number, exact in float64, however it is computed.
    """
    order = np.argsort(values, kind="stable")
    ordered = values[order]
    first = np.r_[True, ordered[1:] != ordered[:-1]]  # where each run of equal values starts
    run = np.cumsum(first) - 1  # the run of each sorted value
    starts = np.r_[np.flatnonzero(first), values.size]  # 0-based bounds of the runs
    ranks = np.empty(values.size, dtype=np.float64)
    ranks[order] = 0.5 * (starts[run] + starts[run + 1] + 1)
    return ranks
