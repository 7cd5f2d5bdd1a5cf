"""Front end: one linear scaling per dataset from recording units to volts.

Recordings are scaled once per dataset, not per recording, so that amplitude differences between
recordings and textures survive. Over all samples ``x`` of all recordings of the dataset::

    offset = mean(x)                                  (recording units)
    p      = percentile_99.9(|x - offset|)            (recording units, linear interpolation)
    gain   = (full_scale_v / 2) / p                   (V per recording unit)
    v      = gain * (x - offset)                      (V)

so 99.9 % of the samples fall within ``+-full_scale_v / 2`` and the rest beyond it. The mean is
sample-weighted: a longer recording counts more. Clipping at the rails is *not* done here; it is
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
from pipeline.recordings import Recordings

__all__ = ["PERCENTILE", "FrontEnd", "fit_front_end"]

#: Percentile of the absolute deviation that maps to half the full scale.
PERCENTILE = 99.9


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
    samples = np.concatenate(recordings.signals)
    low, high = float(samples.min()), float(samples.max())
    if low == high:
        return FrontEnd(offset=low, gain_v_per_unit=1.0)
    offset = float(samples.mean())
    deviation = np.abs(samples - offset)
    reference = float(np.percentile(deviation, PERCENTILE))
    if reference == 0.0:
        reference = float(deviation.max())
    gain = (full_scale_v / 2.0) / reference
    if not math.isfinite(gain):
        raise DatasetError(
            f"dataset {recordings.name}: sample deviations of {reference!r} "
            f"{recordings.units} are too small to scale to {full_scale_v} V"
        )
    return FrontEnd(offset=offset, gain_v_per_unit=gain)
