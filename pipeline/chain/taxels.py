r"""A taxel array from one recorded channel, by fractional time shifts.

A texture scanned at speed ``v`` (mm/s) along the unit direction ``(d_x, d_y)`` reaches taxel
``(i, j)`` of a grid with pitch ``p`` (mm) after the delay

.. math::

    \tau_{ij} = (i \, d_y + j \, d_x) \, p / v \qquad [\mathrm{s}]

so taxel ``(i, j)`` sees ``x(t - tau_ij)``. All taxels share one output time axis
``t_n = tau_max + n / fs`` (re-zeroed so spike times start at 0): the part of the recording
that the most delayed taxel has not yet seen is cut, never zero-filled or wrapped around.
Between samples the signal is the straight line through them (the readout is continuous-time),
so a fractional delay is a linear interpolation; a delay of a whole number of samples is an exact
copy.

Taxels with equal delays (e.g. the columns of a grid scanned along y) see the same signal; it is
stored once (:class:`TaxelSignals` keeps one row per distinct delay and an index per taxel).

Recordings of a real array (one column per taxel) need no delays: each taxel read is its own
column, one row each (:mod:`pipeline.chain.real_taxels` chooses which).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager
from dataclasses import dataclass

import numpy as np

from pipeline.chain.frontend import FrontEnd
from pipeline.chain.real_taxels import taxel_rows, taxels_read
from pipeline.design.scene import ArraySpec
from pipeline.recordings.recording_set import Recordings

# A delay within this many samples of a whole number is that whole number: decimal pitches and
# speeds (0.05 s * 2 kHz = 100.00000000000001) must not turn an exact shift into an interpolation.
_WHOLE_SAMPLE_TOLERANCE = 1e-9


@dataclass(frozen=True, eq=False)
class TaxelSignals:
    """Signals of every taxel of one recording on a common time axis.

    Attributes
    ----------
    signals : float64 (n_distinct, n_samples)
        One row per distinct delay, in increasing order of delay.
    taxel_row : int64 (n_taxels,)
        Row of ``signals`` that each taxel (raster order) sees.
    """

    signals: np.ndarray
    taxel_row: np.ndarray

    @property
    def n_taxels(self) -> int:
        """Number of taxels (length of ``taxel_row``), distinct delays or not."""
        return len(self.taxel_row)

    @property
    def n_samples(self) -> int:
        """Number of samples of the common time axis (columns of ``signals``)."""
        return self.signals.shape[1]

    def taxel(self, index: int) -> np.ndarray:
        """float64 (n_samples,): the signal taxel ``index`` sees."""
        return self.signals[self.taxel_row[index]]


def taxel_delays_s(array: ArraySpec) -> np.ndarray:
    """float64 (rows * cols,): delay of each taxel in raster order, seconds, all >= 0."""
    d_x, d_y = array.direction.vector
    i, j = np.meshgrid(np.arange(array.rows), np.arange(array.cols), indexing="ij")
    return ((i * d_y + j * d_x) * array.pitch_mm / array.speed_mm_s).ravel().astype(np.float64)


def cut_samples(delays_s: np.ndarray, fs_hz: float) -> int:
    """Samples cut from the start of the common axis: ``ceil(max delay * fs)`` (whole-aware)."""
    shift = float(np.max(delays_s) - np.min(delays_s)) * fs_hz
    nearest = round(shift)
    return nearest if abs(shift - nearest) <= _WHOLE_SAMPLE_TOLERANCE else int(np.ceil(shift))


def taxel_signals(signal: np.ndarray, fs_hz: float, delays_s: np.ndarray) -> TaxelSignals:
    """Delay one channel to every taxel of the array.

    Parameters
    ----------
    signal : float64 (n,)
        The recorded channel (volts, after the front end).
    fs_hz : float
        Sampling rate.
    delays_s : float64 (n_taxels,)
        Per-taxel delays, e.g. from :func:`taxel_delays_s`.

    Returns
    -------
    TaxelSignals
        ``n - cut_samples(delays_s, fs_hz)`` samples per taxel. A single taxel, or all delays
        equal, returns the signal itself (no copy, no interpolation).

    Raises
    ------
    ValueError
        If the delays leave fewer than 2 samples.
    """
    signal = np.asarray(signal, dtype=np.float64)
    distinct, taxel_row = np.unique(delays_s, return_inverse=True)
    if len(distinct) == 1:
        return TaxelSignals(signal[np.newaxis, :], np.zeros(len(delays_s), dtype=np.int64))
    n_out = len(signal) - cut_samples(delays_s, fs_hz)
    if n_out < 2:
        raise ValueError(
            f"taxel delays up to {np.max(delays_s):.4g} s leave {max(n_out, 0)} samples of a "
            f"{len(signal)}-sample recording"
        )
    # Row k of the output reads the input from fractional index n + (tau_max - tau_k) * fs.
    offsets = (distinct.max() - distinct) * fs_hz
    rows = np.empty((len(distinct), n_out), dtype=np.float64)
    for k, offset in enumerate(offsets):
        whole = round(offset)
        if abs(offset - whole) <= _WHOLE_SAMPLE_TOLERANCE:
            rows[k] = signal[whole : whole + n_out]
            continue
        q = int(np.floor(offset))
        frac = offset - q
        np.multiply(signal[q : q + n_out], 1.0 - frac, out=rows[k])
        rows[k] += frac * signal[q + 1 : q + 1 + n_out]
    return TaxelSignals(rows, taxel_row.astype(np.int64))


def recording_taxels(
    recordings: Recordings,
    front_end: FrontEnd,
    array: ArraySpec,
    stage: Callable[[str], AbstractContextManager[object]],
) -> Iterator[tuple[int, TaxelSignals]]:
    """Each recording's index and the signals of every taxel of ``array`` on it, scaled by
    ``front_end``, one recording at a time (a recording's taxel signals are as large as it times
    the taxels: they are made when asked for and never kept); ``stage("taxels")`` times making
    them. The taxels are time-shifted copies of one channel, or the columns of a real array that
    ``array`` reads (:func:`pipeline.chain.real_taxels.taxels_read`)."""
    make = _taxel_maker(recordings, array)
    for index, signal in enumerate(recordings.signals):
        with stage("taxels"):
            taxels = make(front_end.apply(signal))
        yield index, taxels


def _taxel_maker(recordings: Recordings, array: ArraySpec) -> Callable[[np.ndarray], TaxelSignals]:
    """Taxel signals from one scaled recording: the columns read of a real array, else the
    delayed copies of its one channel."""
    columns = taxels_read(recordings, array)
    if columns is not None:
        return lambda signal: TaxelSignals(taxel_rows(signal, columns), np.arange(len(columns)))
    return functools.partial(taxel_signals, fs_hz=recordings.fs_hz, delays_s=taxel_delays_s(array))
