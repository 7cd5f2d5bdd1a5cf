"""Is a real taxel array informative? Its taxels, and what they say beyond each other.

:func:`describe_array` looks at the span of each recording a scene codes (the first
``span_s``, the paper's 40 windows of 0.1 s, or the shortest recording's whole windows) of a
dataset whose recordings hold one column per taxel (``Recordings.is_array``):

per taxel ``j``
    its position (when declared); its *level*, the median over recordings of the taxel's mean;
    its *activity*, the median over recordings of its standard deviation ``std(x_j)`` (the
    variation a level-crossing readout turns into spikes; a constant level gives none); its
    range (lowest and highest sample in the dataset) and its *rail share*, the fraction of its
    samples that sit at that lowest or highest value.
``envelope_corr_taxels``
    How alike the taxels' time courses are: per recording, the window RMS envelope of every
    taxel (as :mod:`pipeline.recordings.touch_statistics` defines it, over ``window_s``
    windows), the Pearson correlation of every pair of active taxels' envelopes, the median over
    pairs; then the median over recordings. Near 1 the taxels move together (one taxel's time
    course says what the others' do); near 0 each has its own. NaN with fewer than 3 windows or
    2 active taxels.
accuracy against taxels read
    A plain classifier: logistic regression (``C = 1``, inputs standardised on the training folds)
    on four statistics per taxel over the coded span: mean, standard deviation, mean absolute
    first difference times ``fs`` (units/s) and the range (max - min), stratified k-fold
    cross-validation with ``k = min(folds, fewest recordings of a class)`` (shuffled, seed 0).
    It is run on each taxel alone (the lowest, median and highest accuracy are kept with their
    taxels), on ``1, 2, 4, ...`` taxels chosen as a design's ``array.taxels`` chooses them
    (:mod:`pipeline.recordings.taxel_choice`: over the positions when given, else over the
    declared order), and on all. This measures what the recordings hold,
    not what a readout keeps of it: a taxel that helps here and not in a sweep loses its
    information in the readout. With fewer than 2 recordings in some class the accuracies are
    NaN.

Warnings:

* a dead taxel: its activity is 0 in every recording (constant: it never spikes), or below
  :data:`QUIET_SHARE` of the median taxel's activity (barely moves);
* a saturated taxel: a rail share of at least :data:`RAIL_SHARE` (its samples pile up at its
  lowest or highest value: clipped at a rail);
* taxels that say the same: ``envelope_corr_taxels >= SAME_CORR``.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.recordings.recording_set import Recordings, listed
from pipeline.recordings.taxel_choice import chosen_taxels

__all__ = [
    "QUIET_SHARE",
    "RAIL_SHARE",
    "SAME_CORR",
    "ArrayDescription",
    "SubsetAccuracy",
    "TaxelFacts",
    "describe_array",
    "taxel_mean",
]

#: A taxel whose activity is below this fraction of the median taxel's is (nearly) dead.
QUIET_SHARE = 0.01
#: A taxel with at least this fraction of its samples at its lowest or highest value is saturated.
RAIL_SHARE = 0.01
#: Taxels whose envelopes correlate at least this much (median) say the same over time.
SAME_CORR = 0.9
#: The classifier's statistics per taxel.
FEATURES = ("mean", "std", "mean |diff| * fs", "range")


@dataclass(frozen=True)
class TaxelFacts:
    """One taxel: name, ``[x, y]`` position (mm) or ``None``, level and activity (units), the
    lowest and highest sample, the share of samples at either, whether it is dead."""

    name: str
    position_mm: tuple[float, float] | None
    level: float
    activity: float
    low: float
    high: float
    rail_share: float
    dead: bool


@dataclass(frozen=True)
class SubsetAccuracy:
    """The classifier's cross-validated accuracy (fraction) on ``taxels`` (names)."""

    taxels: tuple[str, ...]
    accuracy: float


@dataclass(frozen=True)
class ArrayDescription:
    """What :func:`describe_array` found (module docstring).

    ``single`` holds each taxel alone, in the declared order; ``subsets`` the subsets a design
    reads of 1, 2, 4, ... taxels and all of them; ``chance`` the largest class's share;
    ``folds`` the cross-validation used (0 when none could be).
    """

    taxels: tuple[TaxelFacts, ...]
    span_s: float
    envelope_corr_taxels: float
    single: tuple[SubsetAccuracy, ...]
    subsets: tuple[SubsetAccuracy, ...]
    chance: float
    folds: int
    warnings: tuple[str, ...]

    def to_json(self) -> dict[str, Any]:
        """Plain values (NaN stays NaN: the caller's JSON conversion turns it into null)."""
        return {
            "taxels": [
                {
                    "name": t.name,
                    "position_mm": list(t.position_mm) if t.position_mm else None,
                    "level": t.level,
                    "activity": t.activity,
                    "low": t.low,
                    "high": t.high,
                    "rail_share": t.rail_share,
                    "dead": t.dead,
                }
                for t in self.taxels
            ],
            "span_s": self.span_s,
            "envelope_corr_taxels": self.envelope_corr_taxels,
            "accuracy": {
                "chance": self.chance,
                "folds": self.folds,
                "features": list(FEATURES),
                "single": {s.taxels[0]: s.accuracy for s in self.single},
                "subsets": [
                    {"n_taxels": len(s.taxels), "taxels": list(s.taxels), "accuracy": s.accuracy}
                    for s in self.subsets
                ],
            },
            "warnings": list(self.warnings),
        }


def taxel_mean(recordings: Recordings) -> Recordings:
    """``recordings`` with each array recording replaced by its mean over taxels (1-D): the
    reading of one sensor as large as the array, which the touch statistics judge."""
    if not recordings.is_array:
        return recordings
    return dataclasses.replace(
        recordings,
        signals=tuple(s.mean(axis=1) for s in recordings.signals),
        taxel_names=(),
        taxel_positions_mm=None,
    )


def describe_array(
    recordings: Recordings, *, span_s: float, window_s: float, folds: int
) -> ArrayDescription:
    """The taxels of an array dataset and what they say beyond each other (module docstring).

    Parameters
    ----------
    recordings
        An array dataset (``recordings.is_array``).
    span_s
        Seconds of each recording to look at from its start (> 0; the coded span).
    window_s
        Envelope window (s), at most ``span_s``.
    folds
        Cross-validation folds at most (>= 2).

    Raises
    ------
    ValueError
        ``recordings`` is not an array.
    """
    if not recordings.is_array:
        raise ValueError(f"dataset {recordings.name} holds one channel, not a taxel array")
    n_span = max(2, math.floor(span_s * recordings.fs_hz + 1e-9))
    spans = [s[:n_span] for s in recordings.signals]
    facts = _taxel_facts(recordings, spans)
    corr = _envelope_corr(spans, round(window_s * recordings.fs_hz), facts)
    features = np.stack([_features(s, recordings.fs_hz) for s in spans])
    counts = np.bincount(recordings.labels, minlength=recordings.n_classes)
    k = int(min(folds, counts.min()))
    n = recordings.n_taxels
    names = recordings.taxel_names

    def accuracy(indices: np.ndarray) -> SubsetAccuracy:
        chosen = tuple(names[i] for i in indices)
        if k < 2:
            return SubsetAccuracy(chosen, math.nan)
        return SubsetAccuracy(
            chosen, _cross_validated(features[:, indices, :], recordings.labels, k)
        )

    single = tuple(accuracy(np.array([j])) for j in range(n))
    sizes = sorted({*(2**p for p in range(int(math.log2(n)) + 1)), n})
    subsets = tuple(accuracy(chosen_taxels(n, m, recordings.taxel_positions_mm)) for m in sizes)
    return ArrayDescription(
        taxels=facts,
        span_s=n_span / recordings.fs_hz,
        envelope_corr_taxels=corr,
        single=single,
        subsets=subsets,
        chance=float(counts.max() / counts.sum()),
        folds=k if k >= 2 else 0,
        warnings=_warnings(facts, corr),
    )


def _taxel_facts(recordings: Recordings, spans: list[np.ndarray]) -> tuple[TaxelFacts, ...]:
    every = np.concatenate(spans)
    low, high = every.min(axis=0), every.max(axis=0)
    at_rail = ((every == low) | (every == high)).mean(axis=0)
    levels = np.median([s.mean(axis=0) for s in spans], axis=0)
    stds = np.stack([s.std(axis=0) for s in spans])
    activity = np.median(stds, axis=0)
    typical = float(np.median(activity))
    positions = recordings.taxel_positions_mm
    out = []
    for j, name in enumerate(recordings.taxel_names):
        constant = bool((stds[:, j] == 0).all())
        out.append(
            TaxelFacts(
                name=name,
                position_mm=None if positions is None else (positions[j, 0], positions[j, 1]),
                level=float(levels[j]),
                activity=float(activity[j]),
                low=float(low[j]),
                high=float(high[j]),
                rail_share=0.0 if constant else float(at_rail[j]),
                dead=bool(constant or activity[j] < QUIET_SHARE * typical),
            )
        )
    return tuple(out)


def _envelope_corr(spans: list[np.ndarray], window_n: int, facts: tuple[TaxelFacts, ...]) -> float:
    alive = np.array([not t.dead for t in facts])
    per_recording = []
    for span in spans:
        n_windows = span.shape[0] // max(window_n, 1)
        if n_windows < 3 or alive.sum() < 2:
            continue
        x0 = span[: n_windows * window_n, alive] - span[:, alive].mean(axis=0)
        envelope = np.sqrt((x0**2).reshape(n_windows, window_n, -1).mean(axis=1))
        moving = envelope.std(axis=0) > 0
        if moving.sum() < 2:
            continue
        with np.errstate(divide="ignore"):
            logs = np.log(envelope[:, moving])
        if not np.isfinite(logs).all():
            logs = envelope[:, moving]
        corr = np.corrcoef(logs, rowvar=False)
        per_recording.append(np.median(corr[np.triu_indices_from(corr, k=1)]))
    return float(np.median(per_recording)) if per_recording else math.nan


def _features(span: np.ndarray, fs_hz: float) -> np.ndarray:
    """float64 ``(n_taxels, 4)``: :data:`FEATURES` of each taxel."""
    return np.stack(
        [
            span.mean(axis=0),
            span.std(axis=0),
            np.abs(np.diff(span, axis=0)).mean(axis=0) * fs_hz,
            np.ptp(span, axis=0),
        ],
        axis=1,
    )


def _cross_validated(features: np.ndarray, labels: np.ndarray, folds: int) -> float:
    """Mean accuracy over stratified folds of a standardised logistic regression."""
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import StratifiedKFold, cross_val_score
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from threadpoolctl import threadpool_limits

    model = make_pipeline(StandardScaler(), LogisticRegression(C=1.0, max_iter=2000))
    splitter = StratifiedKFold(n_splits=folds, shuffle=True, random_state=0)
    # Such small fits gain nothing from threads, and their spinning made them 30x slower on a
    # busy 2-core machine.
    with warnings.catch_warnings(), threadpool_limits(1):
        # A fold that does not converge in 2000 steps is still a fair plain classifier.
        warnings.simplefilter("ignore")
        scores = cross_val_score(model, features.reshape(len(labels), -1), labels, cv=splitter)
    return float(scores.mean())


def _warnings(facts: tuple[TaxelFacts, ...], corr: float) -> tuple[str, ...]:
    out = []
    dead = [t.name for t in facts if t.dead]
    if dead:
        out.append(
            f"{_count(len(dead))} dead (constant, or moving less than {QUIET_SHARE:.0%} of the "
            f"median taxel's activity, so the readout hardly ever spikes on it): {listed(dead)}"
        )
    railed = [f"{t.name} ({t.rail_share:.0%})" for t in facts if t.rail_share >= RAIL_SHARE]
    if railed:
        out.append(
            f"{_count(len(railed))} saturated (at least {RAIL_SHARE:.0%} of the samples at the "
            f"taxel's lowest or highest value, as when clipped at a rail): {listed(railed)}"
        )
    if math.isfinite(corr) and corr >= SAME_CORR:
        out.append(
            f"the taxels' envelopes correlate {corr:.2f} (median): they move together, and more "
            "taxels may add little"
        )
    return tuple(out)


def _count(n: int) -> str:
    return "1 taxel is" if n == 1 else f"{n} taxels are"
