"""Accuracy curves along a sweep and Fig. 9's least-squares lines against the spike metrics.

Accuracy of a point for one model is the cube's ``accuracy_mean`` ``a``: the fraction of
(recording, repeat) pairs classified correctly out of fold. Its 95 % interval
``[accuracy_low, accuracy_high]`` (Wilson score for one repeat, stratified bootstrap over
recordings for several; NaN for points that predate per-recording results) gives the error bars.
The spread over the ``K`` folds of all repeats (population standard deviation, as in
:mod:`pipeline.chain.training`), ``s = sqrt((1/K) sum_k (a_k - mean_k a_k)^2)``, is kept as a
secondary number; nothing is judged by it.

Fig. 9's fitted lines are the least-squares lines of ``a`` on SSNR (finite values only) and on
STE; their ``r`` and ``p`` are the cube's Pearson ``correlation_r`` and ``correlation_p``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.report.cubes import point_keys, sweep_dims
from pipeline.results.variables import (
    ACCURACY,
    ACCURACY_HIGH,
    ACCURACY_LOW,
    ACCURACY_MEAN,
    COEFFICIENT_DIM,
    CORRELATION_P,
    CORRELATION_R,
    METRIC_DIM,
    MODEL_DIM,
)


@dataclass(frozen=True)
class Curve:
    """Accuracy of one model along one sweep, sorted by ``x``.

    Attributes
    ----------
    sweep, model : str
        Cube name and model (``ffnn``, ``cnn``).
    x : float64 (n,)
        The abscissa (threshold V, window s, taxel count, sigma_rel, touch s, any swept field;
        positions 0, 1, ... for a field that is not a number).
    keys : tuple[str, ...] (n,)
        Result keys of the points, for paired tests (:mod:`pipeline.report.evidence`).
    mean, low, high : float64 (n,)
        Accuracy (fraction) and its 95 % interval (NaN: no interval).
    std : float64 (n,)
        Population standard deviation of the fold accuracies (secondary).
    group : str
        What sets the curve apart from others of its sweep: the chips' deployment ("" for none).
    chip_low, chip_median, chip_high : float64 (n,) or None
        The 5th, 50th and 95th percentile of the chips' accuracies at each point, for points
        of several chips (:mod:`pipeline.report.chip_population`); None for points of one chip.
    """

    sweep: str
    model: str
    x: np.ndarray
    keys: tuple[str, ...]
    mean: np.ndarray
    low: np.ndarray
    high: np.ndarray
    std: np.ndarray
    group: str = ""
    chip_low: np.ndarray | None = None
    chip_median: np.ndarray | None = None
    chip_high: np.ndarray | None = None

    @property
    def label(self) -> str:
        """The model and the curve's group, e.g. ``"FFNN"`` or ``"FFNN, shared"``."""
        return self.model.upper() + (f", {self.group}" if self.group else "")

    @property
    def has_interval(self) -> bool:
        """Whether every point has its 95 % interval."""
        return bool(np.all(np.isfinite(self.low) & np.isfinite(self.high)))

    def index(self, x: float) -> int | None:
        """Index of the point at ``x`` (relative tolerance 1e-9), or None if not swept."""
        hits = np.flatnonzero(np.isclose(self.x, x, rtol=1e-9, atol=0.0))
        return int(hits[0]) if hits.size else None

    @property
    def best(self) -> int:
        """Index of the most accurate point (the first one on ties)."""
        return int(np.nanargmax(self.mean))


@dataclass(frozen=True)
class MetricFit:
    """Fig. 9: accuracy against one spike metric along a correlate sweep.

    ``x`` float64 (n,) holds the metric (dB or s^2) of the points used (finite), ``mean``,
    ``low``, ``high`` their accuracy and its 95 % interval; ``slope`` (1/unit) and ``intercept``
    are the least-squares line; ``r``/``p`` the cube's Pearson coefficient and two-sided p;
    ``left_out`` counts non-finite metrics.
    """

    sweep: str
    model: str
    metric: str
    x: np.ndarray
    mean: np.ndarray
    low: np.ndarray
    high: np.ndarray
    slope: float
    intercept: float
    r: float
    p: float
    left_out: int


def sweep_curves(name: str, cube: xr.Dataset, x: np.ndarray) -> tuple[Curve, ...]:
    """One :class:`Curve` per model of a one-dimensional cube (models all-NaN are left out).

    ``x`` float (n,) is the abscissa of each point in cube order; the curve is sorted by it.
    """
    dim = sweep_dims(cube)[0]
    order = np.argsort(x, kind="stable")
    keys = np.asarray(point_keys(cube))[order]
    folds = cube[ACCURACY].transpose(dim, MODEL_DIM, ...).values
    folds = folds.reshape(folds.shape[0], folds.shape[1], -1)[order]
    curves = []
    for m, model in enumerate(cube[MODEL_DIM].values):
        mean = cube[ACCURACY_MEAN].transpose(dim, MODEL_DIM).values[order, m]
        if np.isnan(mean).all():
            continue
        curves.append(
            Curve(
                sweep=name,
                model=str(model),
                x=np.asarray(x, dtype=np.float64)[order],
                keys=tuple(str(k) for k in keys),
                mean=mean.astype(np.float64),
                low=cube[ACCURACY_LOW].transpose(dim, MODEL_DIM).values[order, m],
                high=cube[ACCURACY_HIGH].transpose(dim, MODEL_DIM).values[order, m],
                std=_fold_std(folds[:, m]),
            )
        )
    return tuple(curves)


def metric_fits(name: str, cube: xr.Dataset) -> tuple[MetricFit, ...]:
    """Fig. 9 lines of one correlate cube: every model against SSNR and against STE."""
    from scipy import stats

    dims = sweep_dims(cube)
    fits = []
    for model in cube[MODEL_DIM].values:
        where = {MODEL_DIM: model}
        mean = cube[ACCURACY_MEAN].sel(where).transpose(*dims).values.ravel()
        if np.isnan(mean).all():
            continue
        low = cube[ACCURACY_LOW].sel(where).transpose(*dims).values.ravel()
        high = cube[ACCURACY_HIGH].sel(where).transpose(*dims).values.ravel()
        for metric in cube[METRIC_DIM].values:
            x = cube[str(metric)].transpose(*dims).values.ravel().astype(np.float64)
            usable = np.isfinite(x) & np.isfinite(mean)
            xs, ys = x[usable], mean[usable]
            slope = intercept = math.nan
            if xs.size >= 2 and np.ptp(xs) > 0:
                line = stats.linregress(xs, ys)
                slope, intercept = float(line.slope), float(line.intercept)
            at = {MODEL_DIM: model, METRIC_DIM: metric, COEFFICIENT_DIM: "pearson"}
            fits.append(
                MetricFit(
                    sweep=name,
                    model=str(model),
                    metric=str(metric),
                    x=xs,
                    mean=ys,
                    low=low[usable],
                    high=high[usable],
                    slope=slope,
                    intercept=intercept,
                    r=float(cube[CORRELATION_R].sel(at)),
                    p=float(cube[CORRELATION_P].sel(at)),
                    left_out=int(np.sum(~usable)),
                )
            )
    return tuple(fits)


def _fold_std(folds: np.ndarray) -> np.ndarray:
    """Population std of each row's finite fold accuracies, float64 (n,); NaN where none."""
    out = np.full(folds.shape[0], np.nan)
    for i, row in enumerate(folds):
        finite = row[np.isfinite(row)]
        if finite.size:
            out[i] = float(np.std(finite))
    return out
