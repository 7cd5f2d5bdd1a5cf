r"""Front end: one linear scaling per dataset from recording units to volts.

Recordings are scaled once per dataset, not per recording, so that amplitude differences between
recordings and textures survive. Over all samples ``x`` of all recordings of the dataset:

.. math::

    \begin{aligned}
    \mathrm{offset} &= \operatorname{mean}(x)
        && \text{(recording units)} \\
    p &= \operatorname{percentile}_{99.9}(|x - \mathrm{offset}|)
        && \text{(recording units, linear interpolation)} \\
    \mathrm{gain} &= (\mathrm{full\_scale\_v} / 2) / p
        && \text{(V per recording unit)} \\
    v &= \mathrm{gain} \, (x - \mathrm{offset})
        && \text{(V)}
    \end{aligned}

so 99.9 % of the samples fall within ``+-full_scale_v / 2`` and the rest beyond it. The mean is
sample-weighted: a longer recording counts more. The fit streams over the recordings (the
percentile is selected exactly, bit for bit as ``np.percentile`` of the concatenation), so its
memory is that of one recording, not of the dataset. Clipping at the rails is *not* done here; it is
the ``saturation`` readout effect.

Degenerate datasets, never a division by zero or a NaN:

- a constant dataset (every sample equal) gets ``gain = 1.0`` V per unit and ``offset`` equal to
  that constant, so every recording maps to exactly 0 V;
- a dataset that is not constant but whose 99.9th percentile deviation is 0 (more than 99.9 % of
  the samples sit exactly on the mean) uses the largest deviation instead of the percentile.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.errors import DatasetError
from pipeline.recordings.recording_set import Recordings

__all__ = ["PERCENTILE", "FrontEnd", "fit_front_end", "streaming_percentile"]

#: Percentile of the absolute deviation that maps to half the full scale.
PERCENTILE = 99.9

#: Histogram bins that narrow the percentile down before the exact selection.
_SELECTION_BINS = 4096


@dataclass(frozen=True)
class FrontEnd:
    """Affine map from recording units to volts, ``v = gain_v_per_unit * (x - offset)``.

    Attributes
    ----------
    offset
        Dataset mean (recording units), subtracted first.
    gain_v_per_unit
        Gain (V per recording unit), finite and > 0.
    """

    offset: float
    gain_v_per_unit: float

    def __post_init__(self) -> None:
        if not math.isfinite(self.offset):
            raise ValueError(f"offset must be finite, got {self.offset!r}")
        if not (math.isfinite(self.gain_v_per_unit) and self.gain_v_per_unit > 0):
            raise ValueError(
                f"gain_v_per_unit must be finite and > 0, got {self.gain_v_per_unit!r}"
            )

    def apply(self, signal: np.ndarray) -> np.ndarray:
        """Scale a signal to volts.

        Parameters
        ----------
        signal
            Any shape, real, in recording units.

        Returns
        -------
        numpy.ndarray
            float64, same shape: ``gain_v_per_unit * (signal - offset)`` (V), not clipped.
        """
        return self.gain_v_per_unit * (np.asarray(signal, dtype=np.float64) - self.offset)


def fit_front_end(recordings: Recordings, full_scale_v: float) -> FrontEnd:
    """Fit the dataset-level front end (see the module docstring).

    Parameters
    ----------
    recordings
        The whole dataset; all samples of all recordings enter (sample-weighted).
    full_scale_v
        Full-scale range of the readout (V, finite and > 0); the 99.9th percentile of the
        absolute deviation from the mean maps to ``full_scale_v / 2``.

    Returns
    -------
    FrontEnd

    Raises
    ------
    ValueError
        ``full_scale_v`` is not a finite number > 0.
    DatasetError
        The deviations are so small that the gain would overflow (names the dataset).
    """
    full_scale_v = float(full_scale_v)
    if not (math.isfinite(full_scale_v) and full_scale_v > 0):
        raise ValueError(f"full_scale_v must be a finite number > 0, got {full_scale_v!r}")
    signals = [np.asarray(signal, dtype=np.float64) for signal in recordings.signals]
    low = min(float(signal.min()) for signal in signals)
    high = max(float(signal.max()) for signal in signals)
    if low == high:
        return FrontEnd(offset=low, gain_v_per_unit=1.0)
    n_samples = sum(signal.size for signal in signals)
    offset = math.fsum(float(signal.sum()) for signal in signals) / n_samples
    reference = streaming_percentile(signals, offset, PERCENTILE)
    if reference == 0.0:
        reference = _largest_deviation(signals, offset)
    gain = (full_scale_v / 2.0) / reference
    if not math.isfinite(gain):
        raise DatasetError(
            f"dataset {recordings.name}: sample deviations of {reference!r} "
            f"{recordings.units} are too small to scale to {full_scale_v} V"
        )
    return FrontEnd(offset=offset, gain_v_per_unit=gain)


def _largest_deviation(signals: list[np.ndarray], offset: float) -> float:
    return max(float(np.abs(signal - offset).max()) for signal in signals)


def streaming_percentile(signals: list[np.ndarray], offset: float, percentile: float) -> float:
    """``np.percentile(|concatenate(signals) - offset|, percentile)``, bit for bit, without
    concatenating: memory stays that of one recording however large the dataset.

    One pass finds the largest deviation, a second histograms the deviations up to it to find
    the bins holding the two order statistics that numpy's linear interpolation needs, and a
    third gathers just the deviations in those bins and selects them exactly.

    Parameters
    ----------
    signals
        1-D float64 arrays (recording units), at least one sample in all.
    offset
        Subtracted before taking the absolute value (recording units).
    percentile
        In ``[0, 100]``.
    """
    n = sum(signal.size for signal in signals)
    # numpy's "linear" method: virtual index (n - 1) * q, neighbours floor() and floor() + 1.
    position = (n - 1) * np.true_divide(percentile, 100)
    below = int(np.floor(position))
    ranks = (below, min(below + 1, n - 1))
    largest = _largest_deviation(signals, offset)
    if largest == 0.0:
        return 0.0
    edges = np.linspace(0.0, largest, _SELECTION_BINS + 1)  # as np.histogram makes them
    counts = np.zeros(_SELECTION_BINS, dtype=np.int64)
    for signal in signals:
        counts += np.histogram(np.abs(signal - offset), bins=_SELECTION_BINS, range=(0.0, largest))[
            0
        ]
    cumulative = np.cumsum(counts)
    first, last = (int(np.searchsorted(cumulative, rank, side="right")) for rank in ranks)
    lower, upper = edges[first], edges[last + 1]
    gathered = []
    for signal in signals:
        deviation = np.abs(signal - offset)
        inside = (deviation >= lower) & (
            (deviation <= upper) if last == _SELECTION_BINS - 1 else (deviation < upper)
        )
        gathered.append(deviation[inside])
    candidates = np.sort(np.concatenate(gathered))
    skipped = int(cumulative[first - 1]) if first > 0 else 0
    a, b = candidates[ranks[0] - skipped], candidates[ranks[1] - skipped]
    gamma = position - below
    # numpy's _lerp, so the result is the same float
    difference = b - a
    value = b - difference * (1 - gamma) if gamma >= 0.5 else a + difference * gamma
    return float(value)
