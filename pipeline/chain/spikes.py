"""Spike trains of a whole dataset, stored ragged.

All trains of a dataset live in two flat event arrays (``times_s``, ``polarity``); train
``(recording r, taxel t)`` is the slice ``start[r, t] : start[r, t] + count[r, t]``. Trains are
laid out recording by recording, taxels in raster order, so ``start`` is the exclusive cumulative
sum of ``count``. Times are float64 seconds from the first sample of the recording's common taxel
time axis, non-decreasing within a train.

Times are whole ticks of :data:`TIME_RESOLUTION_S` (1 us), as an address-event chip timestamps
its events: :meth:`SpikeTrains.concatenate`, which every encoder's trains pass through, floors
each time to the tick at or before it, ``t = k * TIME_RESOLUTION_S`` with
``k = max{k : k * TIME_RESOLUTION_S <= t_encoder}`` (:func:`floor_ticks`, float64 arithmetic, so
that a quantised time quantises to itself). A train is the same whether it was just encoded or
read back from the sweep store, which keeps the ticks. One microsecond is far below any window
(milliseconds) and below the encoder's own timing error, a linear interpolation between samples
500 us (2 kHz) or 5 ms (200 Hz) apart.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: Every spike train's time resolution in seconds; its times are whole multiples of it.
TIME_RESOLUTION_S = 1e-6


def floor_ticks(times_s: np.ndarray, resolution_s: float = TIME_RESOLUTION_S) -> np.ndarray:
    """int64, ``times_s``'s shape: the largest ``k`` with ``k * resolution_s <= t`` for each
    time ``t >= 0`` (float64 products, so a time ``k * resolution_s`` gives ``k`` back)."""
    times = np.asarray(times_s, dtype=np.float64)
    ticks = np.floor(times / resolution_s).astype(np.int64)
    ticks += (ticks + 1) * resolution_s <= times  # the division rounded down across a tick
    ticks -= ticks * resolution_s > times  # ... or up
    return ticks


def train_starts(count: np.ndarray) -> np.ndarray:
    """int64, ``count``'s shape: index of each train's first event (exclusive cumulative sum).

    Works for any number of trains, none included.
    """
    flat = np.asarray(count, dtype=np.int64).ravel()
    return (np.cumsum(flat) - flat).reshape(np.shape(count))


@dataclass(frozen=True, eq=False)
class SpikeTrains:
    """Ragged spike trains of ``n_recordings x n_taxels`` taxels.

    Attributes
    ----------
    times_s : float64 (n_events,)
        Spike times in seconds from the first sample of each recording's taxel time axis,
        whole ticks of :data:`TIME_RESOLUTION_S` where made by :meth:`concatenate`.
    polarity : int8 (n_events,)
        +1 (signal rose by one threshold) or -1 (fell).
    count : int64 (n_recordings, n_taxels)
        Number of spikes per train.
    duration_s : float64 (n_recordings,)
        Length of each recording's common taxel time axis, ``(n_samples - 1) / fs_hz``.
    """

    times_s: np.ndarray
    polarity: np.ndarray
    count: np.ndarray
    duration_s: np.ndarray

    @property
    def start(self) -> np.ndarray:
        """int64 (n_recordings, n_taxels): index of each train's first event."""
        return train_starts(self.count)

    @property
    def n_recordings(self) -> int:
        """Number of recordings (rows of ``count``)."""
        return self.count.shape[0]

    @property
    def n_taxels(self) -> int:
        """Number of taxels per recording (columns of ``count``), in raster order."""
        return self.count.shape[1]

    def train(self, recording: int, taxel: int) -> tuple[np.ndarray, np.ndarray]:
        """``(times_s, polarity)`` of one train (views, not copies)."""
        begin = int(self.start[recording, taxel])
        end = begin + int(self.count[recording, taxel])
        return self.times_s[begin:end], self.polarity[begin:end]

    @classmethod
    def concatenate(
        cls,
        trains: Sequence[tuple[np.ndarray, np.ndarray]],
        n_taxels: int,
        duration_s: np.ndarray,
    ) -> SpikeTrains:
        """Build from a flat sequence of ``(times_s, polarity)``, recording-major, raster order,
        each time floored to its tick (:func:`floor_ticks`)."""
        counts = np.array([len(t) for t, _ in trains], dtype=np.int64)
        if trains:
            times = floor_ticks(np.concatenate([t for t, _ in trains])) * TIME_RESOLUTION_S
            polarity = np.concatenate([p for _, p in trains]).astype(np.int8, copy=False)
        else:
            times, polarity = np.empty(0, np.float64), np.empty(0, np.int8)
        return cls(
            times_s=times,
            polarity=polarity,
            count=counts.reshape(-1, n_taxels),
            duration_s=np.asarray(duration_s, dtype=np.float64),
        )


@dataclass(frozen=True, eq=False)
class Encoded:
    """TRUE and REAL spike trains of a dataset (the same object when the readout is ideal)."""

    true: SpikeTrains
    real: SpikeTrains
