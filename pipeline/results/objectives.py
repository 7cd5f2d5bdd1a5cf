"""The objectives of a design search, evaluated on a trial cube.

Each objective of a space (:class:`pipeline.design.space.Objective`; the metrics and their
equations are in :mod:`pipeline.design.space`) is read per point from the cube of its results:
``accuracy_mean``, ``accuracy_p05`` and ``data_rate_bps`` as stored, ``readout_power_w =
event_rate_hz * E_event + data_rate_bps * E_link``
(:func:`pipeline.results.readout_power.event_power_w`), ``compute_s`` the sum of the point's
stage seconds, the decision time and decoder energy under early exit
(:func:`pipeline.results.early_exit.exit_objectives`) and the array's comparator area by
Pelgrom's law (:func:`pipeline.results.matched_area.array_area_m2`). A point simulated as
several chips is read as one: accuracy is the mean over chips (``accuracy_chip_mean``), every
other variable along ``chip`` its mean over the chips.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from pipeline.design.scene import scene_field
from pipeline.design.space import MISMATCH_FIELD, Metric, Objective
from pipeline.results.chip_cube import CHIP_DIM
from pipeline.results.cube import field_coordinate
from pipeline.results.early_exit import exit_objectives
from pipeline.results.matched_area import array_area_m2
from pipeline.results.readout_power import event_power_w
from pipeline.results.variables import ACCURACY_MEAN, MODEL_DIM, RESULT_KEY, SECONDS, STAGE_DIM
from pipeline.results.yields import ACCURACY_CHIP_MEAN, ACCURACY_P05


def objective_values(cube: xr.Dataset, objectives: Sequence[Objective]) -> np.ndarray:
    """float64 (points, objectives): each objective of every point of a cube with one sweep
    dimension (a trial cube), NaN where the point does not state it."""
    (dim,) = [d for d in cube[RESULT_KEY].dims]
    cube = _over_chips(cube)
    columns = []
    for objective in objectives:
        match objective.metric:
            case Metric.ACCURACY:
                values = cube[ACCURACY_MEAN].sel({MODEL_DIM: objective.model})
            case Metric.YIELD:
                values = (
                    cube[ACCURACY_P05].sel({MODEL_DIM: objective.model})
                    if ACCURACY_P05 in cube
                    else xr.DataArray(np.full(cube.sizes[dim], np.nan), dims=(dim,))
                )
            case Metric.AREA:
                values = xr.DataArray(_array_area(cube, dim), dims=(dim,))
            case Metric.DATA_RATE:
                values = cube["data_rate_bps"]
            case Metric.POWER:
                rates = (cube["event_rate_hz"].values, cube["data_rate_bps"].values)
                ok = np.all([np.isfinite(r) & (r >= 0) for r in rates], axis=0)
                power = event_power_w(*(np.where(ok, r, 0.0) for r in rates))
                values = xr.DataArray(np.where(ok, power, np.nan), dims=(dim,))
            case Metric.COMPUTE:
                values = cube[SECONDS].sum(STAGE_DIM, min_count=1)
            case Metric.DECISION_TIME | Metric.DECODER_ENERGY:
                time_s, energy_j = exit_objectives(cube, objective.model)
                chosen = time_s if objective.metric is Metric.DECISION_TIME else energy_j
                values = xr.DataArray(chosen, dims=cube[RESULT_KEY].dims)
        columns.append(np.asarray(values.transpose(dim).values, dtype=np.float64))
    return np.stack(columns, axis=-1) if columns else np.empty((cube.sizes[dim], 0))


def _over_chips(cube: xr.Dataset) -> xr.Dataset:
    """A cube of several chips per point as one of one: ``accuracy_mean`` the mean over chips
    (``accuracy_chip_mean``), every other variable along ``chip`` its mean over the chips."""
    if CHIP_DIM not in cube.dims:
        return cube
    chipped = [name for name, v in cube.data_vars.items() if CHIP_DIM in v.dims]
    means = {name: cube[name].mean(CHIP_DIM, skipna=True) for name in chipped}
    if ACCURACY_CHIP_MEAN in cube:
        means[ACCURACY_MEAN] = cube[ACCURACY_CHIP_MEAN]
    return cube.assign(means)


def _array_area(cube: xr.Dataset, dim: str) -> np.ndarray:
    """float64 (points,): each point's :func:`~pipeline.results.matched_area.array_area_m2`, NaN
    where the cube does not state its mismatch."""

    def values(field: str) -> np.ndarray:
        name = field_coordinate(cube, field)
        if name is None:
            return np.full(cube.sizes[dim], np.nan)
        found = cube[name].broadcast_like(cube[RESULT_KEY]).transpose(dim).values
        return np.asarray(found, dtype=np.float64)

    rows, cols = values(scene_field("array.rows")), values(scene_field("array.cols"))
    sigma_rel = values(f"{MISMATCH_FIELD}.sigma_rel")
    threshold_v = values(scene_field("readout.threshold_v"))
    known = np.isfinite(rows * cols * sigma_rel * threshold_v)
    area = np.full(known.shape, np.nan)
    if known.any():
        area[known] = array_area_m2((rows * cols)[known], sigma_rel[known], threshold_v[known])
    return area
