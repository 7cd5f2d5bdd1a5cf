"""Accuracy curves along a sweep and Fig. 9's least-squares lines against the spike metrics.

Accuracy of a point for one model, over its ``K`` folds (population standard deviation, as in
:mod:`pipeline.training`)::

    a = (1/K) sum_k a_k,    s = sqrt((1/K) sum_k (a_k - a)^2)

Fig. 9's fitted lines are the least-squares lines of ``a`` on SSNR (finite values only) and on
STE; their ``r`` and ``p`` are the cube's Pearson ``correlation_r`` and ``correlation_p``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr


@dataclass(frozen=True)
class Curve:
    """Accuracy of one model along one sweep, sorted by ``x``.

    Attributes
    ----------
    sweep, model : str
        Cube name and model (``ffnn``, ``cnn``).
    x : float64 (n,)
        The panel's abscissa (threshold V, window s, taxel count, sigma_rel, touch s).
    mean, std : float64 (n,)
        Accuracy (fraction) mean and population standard deviation over folds.
    """

    sweep: str
    model: str
    x: np.ndarray
    mean: np.ndarray
    std: np.ndarray

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
    """Fig. 9: fold-mean accuracy against one spike metric along a correlate sweep.

    ``x`` float64 (n,) holds the metric (dB or s^2) of the points used (finite), ``mean``/``std``
    their accuracy; ``slope`` (1/unit) and ``intercept`` are the least-squares line; ``r``/``p``
    the cube's Pearson coefficient and two-sided p; ``left_out`` counts non-finite metrics.
    """

    sweep: str
    model: str
    metric: str
    x: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    slope: float
    intercept: float
    r: float
    p: float
    left_out: int


def sweep_curves(name: str, cube: xr.Dataset, x: np.ndarray) -> tuple[Curve, ...]:
    """One :class:`Curve` per model a one-dimensional cube trained (models all-NaN are left out)."""
    order = np.argsort(x, kind="stable")
    curves = []
    for model in cube["model"].values:
        folds = cube["accuracy"].sel(model=model).values[order]  # (n, folds)
        if np.isnan(folds).all():
            continue
        curves.append(
            Curve(
                sweep=name,
                model=str(model),
                x=np.asarray(x, dtype=np.float64)[order],
                mean=np.nanmean(folds, axis=1),
                std=np.nanstd(folds, axis=1, ddof=0),
            )
        )
    return tuple(curves)


def metric_fits(name: str, cube: xr.Dataset) -> tuple[MetricFit, ...]:
    """Fig. 9 lines of one correlate cube: every model against SSNR and against STE."""
    from scipy import stats

    fits = []
    for model in cube["model"].values:
        folds = cube["accuracy"].sel(model=model).values.reshape(-1, cube.sizes["fold"])
        if np.isnan(folds).all():
            continue
        mean, std = np.nanmean(folds, axis=1), np.nanstd(folds, axis=1, ddof=0)
        for metric in cube["metric"].values:
            x = cube[str(metric)].values.ravel().astype(np.float64)
            usable = np.isfinite(x) & np.isfinite(mean)
            xs, ys = x[usable], mean[usable]
            slope = intercept = math.nan
            if xs.size >= 2 and np.ptp(xs) > 0:
                line = stats.linregress(xs, ys)
                slope, intercept = float(line.slope), float(line.intercept)
            where = {"model": model, "metric": metric, "coefficient": "pearson"}
            fits.append(
                MetricFit(
                    sweep=name,
                    model=str(model),
                    metric=str(metric),
                    x=xs,
                    mean=ys,
                    std=std[usable],
                    slope=slope,
                    intercept=intercept,
                    r=float(cube["correlation_r"].sel(where)),
                    p=float(cube["correlation_p"].sel(where)),
                    left_out=int(np.sum(~usable)),
                )
            )
    return tuple(fits)
