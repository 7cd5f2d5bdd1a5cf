"""Rate coding: spike counts in fixed windows, and the frames the classifiers see.

Windows are half-open, ``[k * w, (k + 1) * w)`` for ``k = 0 .. K - 1``, with explicit edges
``e_k = k * w`` computed once from the window length and never from the data, each the nearest
whole tick of :data:`~pipeline.chain.spikes.TIME_RESOLUTION_S` (spike times are whole ticks,
floored: a floored time lies on the same side of such an edge as the time it came from, which
``k * w`` in floating point, an ulp off the tick, would not guarantee). A spike at time
``t`` falls in window ``k`` when ``e_k <= t < e_{k+1}``; a spike exactly on an edge belongs to the
window that starts there. Spikes before 0 or at or after ``e_K`` are outside and counted as
dropped. Counts are int64: they cannot overflow for any train that fits in memory.

The frame of one recording is ``(channels, taxels, windows)``: taxels in raster order so that
neighbours stay neighbours, one channel with both polarities merged (the paper) or two channels
(+1 spikes, then -1 spikes).

``n_windows = "auto"`` takes as many whole windows as every recording's taxel signal holds, at
most :data:`~pipeline.design.windows.MAX_AUTO_WINDOWS` (the paper's 40 x 0.1 s = 4 s).
"""

from __future__ import annotations

import math

import numpy as np

from pipeline.chain.spikes import TIME_RESOLUTION_S, SpikeTrains
from pipeline.design.scene import CodingSpec, Polarity
from pipeline.design.windows import MAX_AUTO_WINDOWS, whole_windows
from pipeline.errors import SimulationError
from pipeline.jit import kernel

#: The last window edge, in ticks, below which every edge is a whole tick exactly in float64.
MAX_EXACT_TICKS = 2**53


def window_edges_s(window_s: float, n_windows: int) -> np.ndarray:
    """float64 (n_windows + 1,): the explicit edges ``k * window_s``, each the nearest whole
    tick of :data:`~pipeline.chain.spikes.TIME_RESOLUTION_S` (see the module docstring)."""
    edges = np.arange(n_windows + 1, dtype=np.float64) * window_s
    return np.rint(edges / TIME_RESOLUTION_S) * TIME_RESOLUTION_S


def resolve_n_windows(coding: CodingSpec, durations_s: np.ndarray) -> int:
    """The number of windows a scene uses on recordings of these taxel-axis durations.

    Raises
    ------
    SimulationError
        If the shortest recording holds no whole window, or a fixed ``n_windows`` does not fit.
    """
    shortest = float(np.min(durations_s))
    fit = whole_windows(shortest, coding.window_s)
    if fit < 1:
        raise SimulationError(
            f"coding.window_s: {coding.window_s} s is longer than the shortest recording's "
            f"usable length ({shortest:.4g} s after taxel delays)"
        )
    if coding.n_windows == "auto":
        return min(fit, MAX_AUTO_WINDOWS)
    if coding.n_windows > fit:
        raise SimulationError(
            f"coding.n_windows: {coding.n_windows} windows of {coding.window_s} s do not fit the "
            f"shortest recording ({shortest:.4g} s after taxel delays holds {fit})"
        )
    return coding.n_windows


@kernel()
def _count_sorted(times, edges, counts, row):  # pragma: no cover - compiled
    """Add the sorted ``times`` into ``counts[row]``; return how many fall outside the edges."""
    n_windows = edges.shape[0] - 1
    k = 0
    dropped = 0
    for t in times:
        if t < edges[0]:
            dropped += 1
            continue
        while k < n_windows and t >= edges[k + 1]:
            k += 1
        if k == n_windows:
            dropped += 1
        else:
            counts[row, k] += 1
    return dropped


def rate_code(times_s: np.ndarray, window_s: float, n_windows: int) -> tuple[np.ndarray, int]:
    """Count one train's spikes in ``n_windows`` windows of ``window_s`` seconds.

    The frame of a set of one train (:func:`frames`, polarities merged): the contract runs the
    coder every sweep runs.

    Parameters
    ----------
    times_s : float64 (n,)
        Spike times in seconds; any order (sorted trains skip the sort).
    window_s : float
        Window length, > 0.
    n_windows : int
        Number of windows, >= 1.

    Returns
    -------
    counts : int64 (n_windows,)
        Spikes per window, polarities merged.
    dropped : int
        Spikes outside ``[0, n_windows * window_s)``.

    Raises
    ------
    ValueError
        ``window_s`` or ``n_windows`` out of range, or a spike time is NaN.
    """
    times_s = np.asarray(times_s, dtype=np.float64)
    if np.isnan(times_s).any():
        raise ValueError("spike times contain NaN")
    if np.any(times_s[1:] < times_s[:-1]):
        times_s = np.sort(times_s)
    one_train = SpikeTrains(
        times_s=times_s,
        polarity=np.ones(times_s.shape, dtype=np.int8),
        count=np.array([[times_s.size]], dtype=np.int64),
        duration_s=np.array([np.nan]),  # the recording's length: unknown, and not read
    )
    counts, dropped = frames(one_train, window_s, n_windows)
    return counts[0, 0, 0], int(dropped[0, 0])


@kernel()
def _count_trains(times, polarity, counts_flat, split, edges, out, dropped):  # pragma: no cover
    """Rate-code every train of a ragged set; ``out`` is (n_trains * channels, n_windows)."""
    start = 0
    for train in range(counts_flat.shape[0]):
        end = start + counts_flat[train]
        if split:
            up = times[start:end][polarity[start:end] > 0]
            down = times[start:end][polarity[start:end] < 0]
            dropped[train] = _count_sorted(up, edges, out, 2 * train)
            dropped[train] += _count_sorted(down, edges, out, 2 * train + 1)
        else:
            dropped[train] = _count_sorted(times[start:end], edges, out, train)
        start = end


def frames(
    trains: SpikeTrains, window_s: float, n_windows: int, polarity: Polarity = Polarity.MERGED
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-code every train of a dataset into per-recording frames.

    ``trains`` holds each train's times sorted (as the readout emits them); ``window_s`` > 0 and
    ``n_windows`` >= 1 as in :func:`rate_code`.

    Returns
    -------
    counts : int64 (n_recordings, channels, n_taxels, n_windows)
        ``channels`` is 1 for merged polarity, 2 for split (+1 first).
    dropped : int64 (n_recordings, n_taxels)
        Spikes of each train outside the windows.

    Raises
    ------
    ValueError
        ``window_s`` is not a finite number of at least one tick, ``n_windows`` is < 1, or the
        last edge lies past :data:`MAX_EXACT_TICKS` ticks.
    """
    if not (math.isfinite(window_s) and window_s >= TIME_RESOLUTION_S):
        raise ValueError(
            f"window_s must be a finite number of at least one tick ({TIME_RESOLUTION_S:g} s), "
            f"got {window_s!r}"
        )
    if n_windows < 1:
        raise ValueError(f"n_windows must be >= 1, got {n_windows!r}")
    if n_windows * window_s / TIME_RESOLUTION_S > MAX_EXACT_TICKS:
        # Past 2**53 ticks an edge is no longer a whole tick in float64 (and soon not finite).
        raise ValueError(
            f"{n_windows} windows of {window_s!r} s end past {MAX_EXACT_TICKS:.3g} ticks of "
            f"{TIME_RESOLUTION_S:g} s, where float64 edges are no longer whole ticks"
        )
    channels = 2 if polarity == Polarity.SPLIT else 1
    n_rec, n_tax = trains.count.shape
    out = np.zeros((n_rec * n_tax * channels, n_windows), dtype=np.int64)
    dropped = np.zeros(n_rec * n_tax, dtype=np.int64)
    _count_trains(
        trains.times_s,
        trains.polarity,
        trains.count.ravel(),
        channels == 2,
        window_edges_s(window_s, n_windows),
        out,
        dropped,
    )
    counts = out.reshape(n_rec, n_tax, channels, n_windows).transpose(0, 2, 1, 3)
    return np.ascontiguousarray(counts), dropped.reshape(n_rec, n_tax)
