"""What a dataset's touches look like over time: the statistics real recordings are judged by.

Every statistic is computed per recording ``x`` with its mean removed, over ``K`` windows of
``window_s`` (0.1 s, the paper's window) that tile the first ``span_s`` (4 s) of the recording,
or as many whole windows as the shortest recording holds when it is shorter. Window ``k`` holds
the samples ``[round(k w fs), round((k + 1) w fs))`` and its RMS is the envelope sample::

    e_k = sqrt(mean(x0[window k]^2)),           x0 = x - mean(x)

From the envelopes and the whole recordings:

``envelope_corr_within`` / ``envelope_corr_between``
    Pearson correlation of the ``log e_k`` sequences of two recordings, median over all pairs of
    recordings of the same class / of different classes. A touch with a time course (contact
    transient, a sliding level that wanders the same way each time a material is touched) gives
    a within-class value well above the between-class one; stationary scans give about 0 for
    both. Pairs where either envelope is constant (or a recording is silent) are left out.
``contact_transient``
    ``rms(x0[t < 0.25 s]) / median(e_k for windows starting at 1 s or later)``, the median over
    recordings (with its 10th and 90th percentiles). NaN when no window starts at or after 1 s.
``slow_decay``
    ``mean(e_k over 3-4 s) / mean(e_k over 1-2 s)``, the median over recordings; NaN when the
    windows do not reach 4 s.
``level_spread_within``
    Median over classes of the coefficient of variation (``std(ddof=1) / mean``) of the
    recordings' RMS ``sqrt(mean(x0^2))`` over the whole recording.
``loudest_quietest_ratio``
    Ratio of the largest to the smallest class median of the recordings' RMS.
``class_centroid_hz`` / ``class_bandwidth_hz``
    Per class, the mean over its recordings of the power-weighted mean frequency of the whole
    recording's periodogram, and of the power-weighted standard deviation about it (Hz).
``modulation_share`` (and ``class_modulation_share``)
    How much the sliding level is modulated at 5-20 Hz (stick-slip cycles, texture periods at
    the scan speed). Over the sliding part ``s = x0[1 s <= t < K w]`` with its own mean removed,
    the log of its RMS over consecutive ``ENVELOPE_RMS_S`` (5 ms) blocks, its mean removed,
    ``l_b``; its power spectrum ``P(f) = |FFT(l)|^2`` at the FFT's frequencies ``f``::

        share = sum(P, 5 Hz <= f <= 20 Hz) / sum(P, f > 0.5 Hz)

    the median over recordings (and the median per class). A white (or stationary) signal gives
    about ``15 / (fs_env / 2 - 0.5)``, the band's share of a flat spectrum (0.15 at 2 kHz).
    NaN for a recording whose sliding part is shorter than ``MIN_SLIDING_S`` (1 s), whose 5 ms
    blocks hold fewer than ``MIN_BLOCK_SAMPLES`` (4) samples (a 200 Hz recording cannot show
    5-20 Hz modulation of a 5 ms RMS), or that has a silent block.
``modulation_rate_f``
    Whether the modulation's rate depends on the material: per recording the power-weighted
    mean frequency of ``P`` over 5-20 Hz, and the one-way ANOVA F statistic of it across the
    classes (classes with at least one value; NaN with fewer than two such classes or no
    within-class spread).
``floor_ratio`` (and ``class_floor_ratio``)
    Whether sliding goes quiet: ``percentile(e_k, 10) / median(e_k)`` of a recording's window
    RMS, the median over recordings (and per class). Stationary noise gives about 0.93 at
    2 kHz (the window RMS' own scatter); quiet stretches pull it down.

:data:`REAL_TOUCHES` holds the values measured on real sliding-texture recordings (its source:
:data:`REAL_SOURCE`), as reference ranges, never as targets for accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.recordings.sources import Recordings

__all__ = [
    "REAL_SOURCE",
    "REAL_TOUCHES",
    "Reference",
    "TouchStatistics",
    "touch_statistics",
]

#: Envelope window (s), the paper's rate-coding window.
WINDOW_S = 0.1
#: Span of each recording that the envelope statistics look at (s).
SPAN_S = 4.0
#: Contact phase whose RMS the contact transient compares with the sliding level (s).
CONTACT_S = 0.25
#: The sliding level is the median envelope of the windows starting at or after this time (s).
SLIDING_FROM_S = 1.0
#: ``slow_decay`` compares the mean envelope over ``LATE_S`` with that over ``EARLY_S`` (s).
EARLY_S = (1.0, 2.0)
LATE_S = (3.0, 4.0)
#: Block whose RMS samples the sliding envelope that ``modulation_share`` analyses (s).
ENVELOPE_RMS_S = 0.005
#: Band of the sliding modulation (Hz, both ends included).
MODULATION_BAND_HZ = (5.0, 20.0)
#: Envelope frequencies at or below this are drift, not modulation (Hz).
MODULATION_FLOOR_HZ = 0.5
#: Shortest sliding part (from ``SLIDING_FROM_S`` to the end of the windows) analysed (s).
MIN_SLIDING_S = 1.0
#: Fewest samples in a ``ENVELOPE_RMS_S`` block for its RMS to be an envelope sample.
MIN_BLOCK_SAMPLES = 4
#: ``floor_ratio`` is this percentile of a touch's window RMS over its median.
FLOOR_PERCENTILE = 10.0


@dataclass(frozen=True)
class Reference:
    """A statistic's value on real touches: a typical value and the range it is judged by.

    ``low`` and ``high`` bound what counts as "like real touches" (``None``: unbounded on that
    side); ``typical`` is the value measured on the real 12 x 10 set.
    """

    typical: float | tuple[float, float]
    low: float | None
    high: float | None
    description: str

    def holds(self, value: float) -> bool:
        """Whether ``value`` lies in ``[low, high]`` (NaN never does)."""
        if not math.isfinite(value):
            return False
        return (self.low is None or value >= self.low) and (self.high is None or value <= self.high)


#: Where the values of :data:`REAL_TOUCHES` come from.
REAL_SOURCE = (
    "statistics measured on a public set of real robot texture touches that the project does "
    "not ship: a robot presses a fingertip vibration sensor (sampled at about 2 kHz) on a "
    "material sample and slides it across; 20 materials x 50 touches, and its 12 x 10 subset "
    "of the paper's size (the values given are the subset's; each statistic computed as this "
    "module computes it, over 0.1 s windows of the first 4 s)"
)

#: Real touches (:data:`REAL_SOURCE`, the 12 x 10 subset; the 20 x 50 set agrees where both were
#: measured: envelope correlation within 0.59 and between 0.36, contact transient 4.1, slow decay
#: 0.92, modulation share 0.40 with class medians 0.31-0.50, modulation rate F = 59.5). Ranges:
#: the 10th-90th percentile band where one was measured (contact transient), the real sets'
#: spread otherwise, widened to the nearest round values that separate real touches from
#: stationary scans (share of a flat spectrum 0.15; floor ratio of stationary noise about 0.93).
REAL_TOUCHES: dict[str, Reference] = {
    "envelope_corr_within": Reference(
        0.59, 0.4, None, "envelope correlation between touches of one class (median)"
    ),
    "envelope_corr_between": Reference(
        0.33, None, None, "envelope correlation between touches of different classes (median)"
    ),
    "contact_transient": Reference(
        4.1, 2.0, 8.0, "RMS of the first 0.25 s over the sliding level (median over touches)"
    ),
    "slow_decay": Reference(
        0.91, 0.7, 1.0, "mean envelope over 3-4 s / over 1-2 s (median over touches)"
    ),
    "level_spread_within": Reference(
        0.09, None, 0.3, "coefficient of variation of touch RMS within a class (median)"
    ),
    "loudest_quietest_ratio": Reference(3.0, 1.5, 10.0, "loudest / quietest class median RMS"),
    "centroid_hz": Reference((8.0, 19.0), 5.0, 60.0, "spectral centroid of a class (Hz)"),
    "bandwidth_hz": Reference((24.0, 59.0), 10.0, 80.0, "spectral bandwidth of a class (Hz)"),
    "modulation_share": Reference(
        0.41,
        0.3,
        0.6,
        "share of the sliding log-envelope's power at 5-20 Hz (median over touches; real class "
        "medians 0.34-0.49)",
    ),
    "modulation_rate_f": Reference(
        16.8, 10.0, None, "ANOVA F across classes of the 5-20 Hz modulation's mean frequency"
    ),
    "floor_ratio": Reference(
        0.68,
        0.55,
        0.85,
        "10th percentile / median of a touch's window RMS (median over touches; real class "
        "medians 0.60-0.74)",
    ),
}


@dataclass(frozen=True, eq=False)
class TouchStatistics:
    """The statistics of one dataset, as :func:`touch_statistics` computes them.

    Scalars are float (NaN where undefined, as the module docstring says); arrays are float64 of
    shape ``(n_classes,)`` in class-label order.
    """

    dataset: str
    class_names: tuple[str, ...]
    fs_hz: float
    window_s: float
    n_windows: int
    envelope_corr_within: float
    envelope_corr_between: float
    contact_transient: float
    contact_transient_p10: float
    contact_transient_p90: float
    slow_decay: float
    level_spread_within: float
    loudest_quietest_ratio: float
    class_rms: np.ndarray
    class_centroid_hz: np.ndarray
    class_bandwidth_hz: np.ndarray
    modulation_share: float
    class_modulation_share: np.ndarray
    modulation_rate_f: float
    floor_ratio: float
    class_floor_ratio: np.ndarray

    @property
    def span_s(self) -> float:
        """Time the envelope windows cover (s), ``n_windows * window_s``."""
        return self.n_windows * self.window_s

    def to_dict(self) -> dict[str, Any]:
        """Plain Python values (NaN kept as float NaN), arrays as lists."""
        out: dict[str, Any] = {}
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            if isinstance(value, np.ndarray):
                value = [float(v) for v in value]
            elif isinstance(value, tuple):
                value = list(value)
            out[name] = value
        return out


def touch_statistics(
    recordings: Recordings, *, window_s: float = WINDOW_S, span_s: float = SPAN_S
) -> TouchStatistics:
    """Time course, level and spectrum statistics of a dataset's touches (module docstring).

    Parameters
    ----------
    recordings
        Any dataset. Classes without recordings get NaN class values.
    window_s
        Envelope window (s), finite and > 0.
    span_s
        At most this much of each recording is windowed (s), at least one window.

    Raises
    ------
    ValueError
        ``window_s`` or ``span_s`` not a finite positive number, ``span_s < window_s``, the
        shortest recording shorter than one window, or recordings of a taxel array.
    """
    if recordings.is_array:
        raise ValueError(
            f"dataset {recordings.name}: touch statistics are of one channel, not of "
            f"{recordings.n_taxels} taxels (judge their mean, describe_array.taxel_mean)"
        )
    if not (math.isfinite(window_s) and window_s > 0 and math.isfinite(span_s)):
        raise ValueError(f"window_s and span_s must be finite and > 0, got {window_s}, {span_s}")
    if span_s < window_s:
        raise ValueError(f"span_s ({span_s} s) is shorter than one window ({window_s} s)")
    fs = recordings.fs_hz
    shortest_s = recordings.min_samples / fs
    n_windows = math.floor(min(span_s, shortest_s) / window_s + 1e-9)
    if n_windows < 1:
        raise ValueError(
            f"dataset {recordings.name}: the shortest recording ({shortest_s:.3g} s) is shorter "
            f"than one {window_s} s window"
        )
    edges = np.round(np.arange(n_windows + 1) * window_s * fs).astype(np.int64)
    starts_s = np.arange(n_windows) * window_s
    contact_n = max(1, round(CONTACT_S * fs))
    sliding = starts_s >= SLIDING_FROM_S - 1e-9
    early = (starts_s >= EARLY_S[0] - 1e-9) & (starts_s < EARLY_S[1] - 1e-9)
    late = (starts_s >= LATE_S[0] - 1e-9) & (starts_s < LATE_S[1] - 1e-9)

    n = recordings.n_recordings
    envelopes = np.empty((n, n_windows))
    rms = np.empty(n)
    transient = np.full(n, math.nan)
    decay = np.full(n, math.nan)
    centroid = np.empty(n)
    bandwidth = np.empty(n)
    share = np.full(n, math.nan)
    rate = np.full(n, math.nan)
    floor = np.empty(n)
    block_n = round(ENVELOPE_RMS_S * fs)
    sliding_from_n = round(SLIDING_FROM_S * fs)
    modulated = (
        block_n >= MIN_BLOCK_SAMPLES and (edges[-1] - sliding_from_n) / fs >= MIN_SLIDING_S - 1e-9
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        for i, signal in enumerate(recordings.signals):
            x0 = signal - signal.mean()
            squares = x0**2
            sums = np.add.reduceat(squares[: edges[-1]], edges[:-1])
            envelopes[i] = np.sqrt(sums / np.diff(edges))
            rms[i] = math.sqrt(squares.mean())
            if sliding.any():
                transient[i] = math.sqrt(squares[:contact_n].mean()) / np.median(
                    envelopes[i][sliding]
                )
            if late.sum() == round((LATE_S[1] - LATE_S[0]) / window_s):
                decay[i] = envelopes[i][late].mean() / envelopes[i][early].mean()
            centroid[i], bandwidth[i] = _spectrum_moments(x0, fs)
            floor[i] = np.percentile(envelopes[i], FLOOR_PERCENTILE) / np.median(envelopes[i])
            if modulated:
                share[i], rate[i] = _modulation(x0[sliding_from_n : edges[-1]], block_n, fs)
        within, between = _envelope_correlations(envelopes, recordings.labels)
        classes = range(recordings.n_classes)
        members = [recordings.labels == c for c in classes]
        class_rms = np.array([np.median(rms[m]) if m.any() else math.nan for m in members])
        spreads = [np.std(rms[m], ddof=1) / rms[m].mean() for m in members if m.sum() > 1]
        spread = float(np.nanmedian(spreads)) if spreads else math.nan
        ratio = float(np.nanmax(class_rms) / np.nanmin(class_rms))
        class_centroid = np.array([centroid[m].mean() if m.any() else math.nan for m in members])
        class_bandwidth = np.array([bandwidth[m].mean() if m.any() else math.nan for m in members])
        finite_transient = transient[np.isfinite(transient)]
        p10, p50, p90 = (
            np.percentile(finite_transient, [10, 50, 90])
            if finite_transient.size
            else (math.nan,) * 3
        )
        finite_decay = decay[np.isfinite(decay)]
        class_share = np.array([_median(share[m]) for m in members])
        class_floor = np.array([_median(floor[m]) for m in members])
        rate_f = _anova_f([rate[m] for m in members])
    return TouchStatistics(
        dataset=recordings.name,
        class_names=recordings.class_names,
        fs_hz=fs,
        window_s=float(window_s),
        n_windows=n_windows,
        envelope_corr_within=within,
        envelope_corr_between=between,
        contact_transient=float(p50),
        contact_transient_p10=float(p10),
        contact_transient_p90=float(p90),
        slow_decay=float(np.median(finite_decay)) if finite_decay.size else math.nan,
        level_spread_within=spread,
        loudest_quietest_ratio=ratio,
        class_rms=class_rms,
        class_centroid_hz=class_centroid,
        class_bandwidth_hz=class_bandwidth,
        modulation_share=_median(share),
        class_modulation_share=class_share,
        modulation_rate_f=rate_f,
        floor_ratio=_median(floor),
        class_floor_ratio=class_floor,
    )


def _median(values: np.ndarray) -> float:
    """Median of the finite values (NaN when there are none)."""
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else math.nan


def _modulation(sliding: np.ndarray, block_n: int, fs_hz: float) -> tuple[float, float]:
    """``(share, mean frequency)`` of the 5-20 Hz modulation of ``sliding`` (module docstring).

    ``sliding``: float64, the sliding part of one recording; ``block_n`` samples per RMS block.
    NaN for both when a block is silent.
    """
    s = sliding - sliding.mean()
    blocks = s.size // block_n
    rms = np.sqrt((s[: blocks * block_n] ** 2).reshape(blocks, block_n).mean(axis=1))
    if not (rms > 0).all():
        return math.nan, math.nan
    log_envelope = np.log(rms)
    power = np.abs(np.fft.rfft(log_envelope - log_envelope.mean())) ** 2
    freqs = np.fft.rfftfreq(blocks, d=block_n / fs_hz)
    band = (freqs >= MODULATION_BAND_HZ[0]) & (freqs <= MODULATION_BAND_HZ[1])
    total = power[freqs > MODULATION_FLOOR_HZ].sum()
    in_band = power[band].sum()
    if not (total > 0 and in_band > 0):
        return math.nan, math.nan
    return float(in_band / total), float((freqs[band] * power[band]).sum() / in_band)


def _anova_f(groups: list[np.ndarray]) -> float:
    """One-way ANOVA F of the finite values across ``groups`` (NaN when undefined)."""
    kept = [g[np.isfinite(g)] for g in groups]
    kept = [g for g in kept if g.size]
    n = sum(g.size for g in kept)
    if len(kept) < 2 or n <= len(kept):
        return math.nan
    grand = np.concatenate(kept).mean()
    between = sum(g.size * (g.mean() - grand) ** 2 for g in kept) / (len(kept) - 1)
    within = sum(((g - g.mean()) ** 2).sum() for g in kept) / (n - len(kept))
    return float(between / within) if within > 0 else math.nan


def _spectrum_moments(x0: np.ndarray, fs_hz: float) -> tuple[float, float]:
    """Power-weighted mean and standard deviation of frequency of ``x0``'s periodogram (Hz)."""
    from scipy.signal import periodogram

    freqs, power = periodogram(x0, fs=fs_hz, detrend=False)
    total = power.sum()
    if not total > 0:
        return math.nan, math.nan
    centroid = float((freqs * power).sum() / total)
    return centroid, math.sqrt(float(((freqs - centroid) ** 2 * power).sum() / total))


def _envelope_correlations(envelopes: np.ndarray, labels: np.ndarray) -> tuple[float, float]:
    """Median Pearson correlation of ``log e_k`` over same-class and different-class pairs.

    ``envelopes``: float64 ``(n_recordings, n_windows)``. A recording whose log envelope is not
    finite everywhere (a silent window) or is constant takes part in no pair.
    """
    logs = np.log(envelopes)
    centred = logs - logs.mean(axis=1, keepdims=True)
    norms = np.sqrt((centred**2).sum(axis=1))
    usable = np.isfinite(norms) & (norms > 0)
    if envelopes.shape[1] < 3 or usable.sum() < 2:
        return math.nan, math.nan
    z = centred[usable] / norms[usable, None]
    corr = z @ z.T
    kept = labels[usable]
    upper = np.triu(np.ones(corr.shape, dtype=bool), k=1)
    same = (kept[:, None] == kept[None, :]) & upper
    other = (kept[:, None] != kept[None, :]) & upper
    within = float(np.median(corr[same])) if same.any() else math.nan
    between = float(np.median(corr[other])) if other.any() else math.nan
    return within, between
