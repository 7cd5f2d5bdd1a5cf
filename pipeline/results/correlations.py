"""Correlations of spike metrics with accuracy across a sweep's points (``correlate = true``).

For each model, metric (SSNR and STE: :data:`CORRELATED_METRICS`) and coefficient (Pearson and
Spearman, as :func:`pipeline.chain.metrics.correlate_with_accuracy` names them), the correlation of
the metric with ``accuracy_mean`` over the sweep's points, infinite metrics left out
(:func:`pipeline.chain.metrics.correlate_with_accuracy`): ``correlation_r``, its two-sided p-value
``correlation_p`` and the number of points ``correlation_n``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from pipeline.chain.metrics import CORRELATION_METHODS, correlate_with_accuracy
from pipeline.results.variables import (
    ACCURACY_MEAN,
    COEFFICIENT_DIM,
    CORRELATION_N,
    CORRELATION_P,
    CORRELATION_R,
    METRIC_DIM,
    MODEL_DIM,
)

__all__ = ["CORRELATED_METRICS", "correlations"]

#: The spike metrics correlated with accuracy.
CORRELATED_METRICS = ("ssnr_db", "ste_s2")


def correlations(cube: xr.Dataset, models: list[str]) -> xr.Dataset:
    """``correlation_r``, ``correlation_p`` (model, metric, coefficient) and ``correlation_n``
    (model, metric) of ``cube``'s points (see the module docstring), and attribute
    ``correlation_notes`` where a correlation could not be computed."""
    shape = (len(models), len(CORRELATED_METRICS), len(CORRELATION_METHODS))
    r, p = np.full(shape, np.nan), np.full(shape, np.nan)
    n = np.zeros(shape[:2], dtype=np.int64)
    notes = []
    for i, model in enumerate(models):
        mean_accuracy = cube[ACCURACY_MEAN].sel({MODEL_DIM: model}).values.ravel()
        for j, metric in enumerate(CORRELATED_METRICS):
            result = correlate_with_accuracy(cube[metric].values.ravel(), mean_accuracy)
            for k, method in enumerate(CORRELATION_METHODS):
                r[i, j, k], p[i, j, k], n[i, j], note = result[method]
                if note:
                    notes.append(f"{model}/{metric}/{method}: {note}")
    dims = (MODEL_DIM, METRIC_DIM, COEFFICIENT_DIM)
    return xr.Dataset(
        {
            CORRELATION_R: (dims, r),
            CORRELATION_P: (dims, p),
            CORRELATION_N: (dims[:2], n),
        },
        coords={METRIC_DIM: list(CORRELATED_METRICS), COEFFICIENT_DIM: list(CORRELATION_METHODS)},
        attrs={"correlation_notes": "; ".join(notes)} if notes else {},
    )
