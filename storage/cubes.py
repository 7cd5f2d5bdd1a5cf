"""Result cubes: one labelled xarray Dataset per sweep.

Dimensions are the sweep's axes (a zipped sweep has one dimension, named after its first axis,
with the other axes as coordinates along it), plus ``model`` and ``fold`` for accuracy and
``stage`` for compute time. Variables:

``accuracy``          (axes..., model, fold)  fraction of test recordings classified correctly
``ssnr_db``           (axes...)               pooled SSNR (``+inf``: REAL trains equal TRUE)
``ste_s2``            (axes...)               the paper's STE, mean over trains
``ste_sign_safe_s2``  (axes...)               STE with ``|N_real - N_true|``
``event_rate_hz``     (axes...)               array events per second
``data_rate_bps``     (axes...)               address-event bits per second
``equivalent_bits``   (axes...)               ``log2(full_scale_v / threshold_v)``
``seconds``           (axes..., stage)        wall seconds each stage took when it was computed

A sweep with ``correlate = true`` also holds ``correlation_r``, ``correlation_p`` (model,
metric, coefficient) and ``correlation_n`` (model, metric): Pearson and Spearman correlations of
SSNR and STE with fold-averaged accuracy across the sweep's points (infinite metrics left out).

Accuracy of a model or fold a point did not train is NaN. Every variable but ``seconds`` is a
deterministic function of the grid and its seeds; ``seconds`` are measurements. Units are in
each variable's ``units`` attribute; provenance (grid, sweep, base scene, seeds, package version)
in the cube's attributes, with the versions of Python and of the libraries that shape the results
as ``version_<name>`` strings (see ``DEPENDENCY_VERSIONS``).
"""

from __future__ import annotations

import json
import platform
from collections.abc import Mapping
from importlib import metadata
from typing import Any

import numpy as np
import xarray as xr

from pipeline.grid import Grid, Sweep, sweep_points
from pipeline.metrics import CORRELATION_METHODS, correlate_with_accuracy
from pipeline.scene import Model
from storage.store import ResultEntry

METRICS = (
    "ssnr_db",
    "ste_s2",
    "ste_sign_safe_s2",
    "event_rate_hz",
    "data_rate_bps",
    "equivalent_bits",
)
CORRELATED_METRICS = ("ssnr_db", "ste_s2")
SPIKE_STAGES = ("load", "front_end", "taxels", "readout", "metrics")
UNITS = {
    "accuracy": "1 (fraction of test recordings correct)",
    "ssnr_db": "dB",
    "ste_s2": "s^2",
    "ste_sign_safe_s2": "s^2",
    "event_rate_hz": "events/s",
    "data_rate_bps": "bit/s",
    "equivalent_bits": "bit",
    "seconds": "s",
    "correlation_r": "1",
    "correlation_p": "1",
    "correlation_n": "points",
}
# One string attribute per library, not a nested mapping: netCDF and Zarr attributes are flat, and
# plain strings keep cubes comparable with xarray.testing.assert_identical. Read once, at import:
# the process runs one set of libraries.
DEPENDENCY_VERSIONS: dict[str, str] = {
    "version_python": platform.python_version(),
    **{
        f"version_{name.replace('-', '_')}": metadata.version(name)
        for name in ("torch", "numpy", "numba", "scikit-learn", "xarray", "zarr")
    },
}
_SUFFIX_UNITS = {
    "_v": "V",
    "_s": "s",
    "_hz": "Hz",
    "_mm": "mm",
    "_mm_s": "mm/s",
    "_rel": "1 (relative to threshold_v)",
}


def build_cube(grid: Grid, sweep: Sweep, records: Mapping[str, ResultEntry]) -> xr.Dataset:
    """Assemble the cube of one sweep from its points' result entries (keyed by result key)."""
    points = sweep_points(grid.base, sweep)
    models = [m.value for m in Model if any(m in p.scene.training.models for p in points)]
    n_folds = max(p.scene.training.folds for p in points)
    stages = [*SPIKE_STAGES, "coding", *(f"train_{m}" for m in models)]
    shape = sweep.shape
    accuracy = np.full((*shape, len(models), n_folds), np.nan)
    metrics = {name: np.full(shape, np.nan) for name in METRICS}
    seconds = np.full((*shape, len(stages)), np.nan)
    for point in points:
        record = records[point.key]
        for m, model in enumerate(models):
            folds = record.fold_accuracy.get(model)
            if folds is not None:
                accuracy[(*point.index, m, slice(0, len(folds)))] = folds
        for name in METRICS:
            metrics[name][point.index] = getattr(record.metrics, name)
        for s, stage in enumerate(stages):
            seconds[(*point.index, s)] = record.seconds.get(stage, np.nan)
    dims = sweep.dims
    data_vars: dict[str, Any] = {
        "accuracy": ((*dims, "model", "fold"), accuracy),
        **{name: (dims, values) for name, values in metrics.items()},
        "seconds": ((*dims, "stage"), seconds),
    }
    coords: dict[str, Any] = {
        "model": ("model", models),
        "fold": ("fold", np.arange(n_folds)),
        "stage": ("stage", stages),
    }
    for position, axis in enumerate(sweep.axes):
        dim = dims[0] if sweep.mode == "zip" else dims[position]
        attrs = {"field": axis.field, "units": _axis_units(axis.field)}
        coords[axis.dim] = (dim, _coordinate(axis.values), attrs)
    cube = xr.Dataset(data_vars, coords=coords)
    if sweep.correlate:
        cube = cube.merge(_correlations(cube, models))
    for name, variable in cube.data_vars.items():
        variable.attrs["units"] = UNITS[name]
    cube.attrs.update(_provenance(grid, sweep))
    return cube


def _correlations(cube: xr.Dataset, models: list[str]) -> xr.Dataset:
    shape = (len(models), len(CORRELATED_METRICS), len(CORRELATION_METHODS))
    r, p = np.full(shape, np.nan), np.full(shape, np.nan)
    n = np.zeros(shape[:2], dtype=np.int64)
    notes = []
    for i, model in enumerate(models):
        mean_accuracy = cube["accuracy"].sel(model=model).mean("fold").values.ravel()
        for j, metric in enumerate(CORRELATED_METRICS):
            result = correlate_with_accuracy(cube[metric].values.ravel(), mean_accuracy)
            for k, method in enumerate(CORRELATION_METHODS):
                r[i, j, k], p[i, j, k], n[i, j], note = result[method]
                if note:
                    notes.append(f"{model}/{metric}/{method}: {note}")
    dims = ("model", "metric", "coefficient")
    return xr.Dataset(
        {
            "correlation_r": (dims, r),
            "correlation_p": (dims, p),
            "correlation_n": (dims[:2], n),
        },
        coords={"metric": list(CORRELATED_METRICS), "coefficient": list(CORRELATION_METHODS)},
        attrs={"correlation_notes": "; ".join(notes)} if notes else {},
    )


def _coordinate(values: tuple[Any, ...]) -> np.ndarray:
    """Numbers stay numbers; tables (e.g. a whole effects mapping) become canonical JSON."""
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        return np.asarray(values)
    if all(isinstance(v, str | bool) for v in values):
        return np.asarray(values)
    return np.asarray([json.dumps(v, sort_keys=True) for v in values])


def _axis_units(field: str) -> str:
    last = field.split(".")[-1]
    for suffix in sorted(_SUFFIX_UNITS, key=len, reverse=True):
        if last.endswith(suffix):
            return _SUFFIX_UNITS[suffix]
    return "1"


def _provenance(grid: Grid, sweep: Sweep) -> dict[str, Any]:
    return {
        "grid": grid.name,
        "sweep": sweep.name,
        "title": sweep.title,
        "mode": sweep.mode.value,
        "axes": json.dumps({a.field: a.dim for a in sweep.axes}),
        "fixed": json.dumps(dict(sweep.fixed), sort_keys=True),
        "base_scene": grid.base.canonical(),
        "seed": grid.base.seed,
        "training_seed": grid.base.training.seed,
        "package_version": metadata.version("eskin-sweep"),
        "grid_description": json.dumps(grid.describe(), sort_keys=True),
        **DEPENDENCY_VERSIONS,
    }
