"""Each point's accuracy in one number per model, and its 95 % interval.

``accuracy_mean`` (axes..., model) is the fraction of (recording, repeat) pairs classified
correctly, from the out-of-fold predictions, or the mean over folds for points without them;
``accuracy_low`` and ``accuracy_high`` its 95 % interval: the Wilson score over recordings for
one repeat, a class-stratified bootstrap over recordings for several (attribute ``interval``
says which; :func:`pipeline.results.stats.accuracy_interval`), NaN without predictions.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from pipeline.results.stats import WILSON_METHOD, accuracy_interval, wilson_interval
from pipeline.results.variables import ACCURACY_HIGH, ACCURACY_LOW, ACCURACY_MEAN, MODEL_DIM
from pipeline.run.stages import interval_generator

__all__ = ["Cell", "accuracy_summary"]


class Cell(Protocol):
    """A cell of the summary: its index along the cube's sweep dimensions (and any more, as a
    chip) and the result key its bootstrap interval is seeded from
    (:class:`pipeline.run.grid_keys.KeyedPoint` is one)."""

    @property
    def index(self) -> tuple[int, ...]:
        """Its index along the summary's leading dimensions."""
        ...

    @property
    def key(self) -> str:
        """The result key of its point."""
        ...


def accuracy_summary(
    accuracy: np.ndarray,
    correct: np.ndarray | None,
    label: np.ndarray | None,
    dims: tuple[str, ...],
    points: Sequence[Cell],
    models: list[str],
) -> dict[str, Any]:
    """``accuracy_mean``, ``accuracy_low``, ``accuracy_high`` (axes..., model) of every point.

    With out-of-fold predictions: the fraction of (recording, repeat) pairs classified correctly
    and its 95 % interval (as :func:`pipeline.results.stats.accuracy_interval` gives it: Wilson
    score for one repeat, all at once by :func:`pipeline.results.stats.wilson_interval`; a
    class-stratified bootstrap over recordings for several, its generator seeded from the point's
    result key and the model, :func:`pipeline.run.stages.interval_generator`). Without: the mean
    over folds, and no interval (NaN).
    """
    shape = accuracy.shape[:-2]
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an untrained model: all-NaN folds
        mean = np.nanmean(accuracy.reshape(*shape, -1), axis=-1).reshape(-1)
    low, high = np.full(mean.shape, np.nan), np.full(mean.shape, np.nan)
    methods = set()
    if correct is not None and label is not None:
        n_models = shape[-1]
        # One cell per (point, model), in flat cube order: (cells, repeat, recording), -1 where
        # the cell has no prediction (a recording it did not hold, a repeat or model it did not
        # run).
        cells = correct.reshape(-1, *correct.shape[-2:])
        tested = cells >= 0
        ran = tested.any(axis=-1)  # (cells, repeat): the repeats a cell ran
        # The recordings every repeat the cell ran tested (a repeat it did not run does not
        # count against them).
        held = (tested | ~ran[..., np.newaxis]).all(axis=-2)
        n_held = held.sum(axis=-1)
        n_ran = ran.sum(axis=-1)
        scored = (n_ran > 0) & (n_held > 0)
        wilson = np.flatnonzero(scored & (n_ran == 1))
        if wilson.size:
            # With one repeat run, the held recordings are those it tested: every other entry
            # (another repeat, a recording the point did not hold) is -1 and adds no success.
            k = (cells[wilson] == 1).sum(axis=(-2, -1), dtype=np.int64)
            n = n_held[wilson].astype(np.int64)
            estimate = k / n
            ci_low, ci_high = wilson_interval(k, n)
            # Widened to contain the estimate, as accuracy_interval does.
            mean[wilson] = estimate
            low[wilson] = np.minimum(ci_low, estimate)
            high[wilson] = np.maximum(ci_high, estimate)
            methods.add(WILSON_METHOD)
        bootstrap = np.flatnonzero(scored & (n_ran > 1))
        if bootstrap.size:
            by_cell = {int(np.ravel_multi_index(p.index, shape[:-1])): p for p in points}
        for c in bootstrap:
            point, m = by_cell[int(c) // n_models], int(c) % n_models
            cell = cells[c][ran[c]]
            interval = accuracy_interval(
                cell[:, held[c]] == 1,
                label[held[c]],
                rng=interval_generator(point.key, models[m]),
            )
            mean[c], low[c], high[c] = interval.estimate, interval.low, interval.high
            methods.add(interval.method)
    attrs = {"interval": "; ".join(sorted(methods)) or "none", "confidence": 0.95}
    return {
        ACCURACY_MEAN: ((*dims, MODEL_DIM), mean.reshape(shape)),
        ACCURACY_LOW: ((*dims, MODEL_DIM), low.reshape(shape), attrs),
        ACCURACY_HIGH: ((*dims, MODEL_DIM), high.reshape(shape), attrs),
    }
