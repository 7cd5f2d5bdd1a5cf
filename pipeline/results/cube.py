"""Result cubes: one labelled, self-describing xarray Dataset per sweep, from its points' results.

Pure: the cube is a function of the grid, the sweep and the results of its points (no store, no
recordings); :mod:`storage.store` persists it. Dimensions are the sweep's axes (a zipped sweep has
one dimension, named after its first axis), plus ``model``, ``repeat``, ``fold`` and
``recording`` for accuracy, ``stage`` for compute time and ``metric``, ``coefficient`` for
correlations.

Data variables

``accuracy`` (axes..., model, repeat, fold)
    fraction of a fold's test recordings classified correctly
``accuracy_mean`` (axes..., model)
    fraction of (recording, repeat) pairs classified correctly (the mean over folds for points
    without predictions)
``accuracy_low``, ``accuracy_high`` (axes..., model)
    95 % interval of ``accuracy_mean``: Wilson score over recordings for one repeat,
    class-stratified bootstrap over recordings for several (attribute ``interval`` says which)
``predicted`` (axes..., model, repeat, recording)
    int16 out-of-fold predicted class
``correct`` (axes..., model, repeat, recording)
    int8 1 where ``predicted`` is the recording's ``label``, 0 where not
``test_fold`` (axes..., repeat, recording)
    int16 fold that tested the recording
``ssnr_db`` (axes...)
    pooled SSNR (``+inf``: REAL trains equal TRUE)
``ste_s2`` (axes...)
    the paper's STE, mean over trains
``ste_sign_safe_s2`` (axes...)
    STE with ``|N_real - N_true|``
``event_rate_hz`` (axes...)
    array events per second
``data_rate_bps`` (axes...)
    address-event bits per second
``equivalent_bits`` (axes...)
    ``log2(full_scale_v / threshold_v)``
``seconds`` (axes..., stage, charge)
    wall seconds a worker paid computing the point, by stage and by ``charge``: ``own`` (work
    for the point itself) or ``shared`` (work its worker's later points reused without paying
    again: the recordings' load, the front-end fit, and under stage ``setup`` a worker's
    one-off work: importing numba, torch and scikit-learn, loading or compiling the numba
    kernels). Each second a worker spent is charged to exactly one point (the one whose
    computation paid it), so that summed over a sweep's distinct points they give the workers'
    busy time but for the tasks' store reads and writes; a stage whose output the point found
    made (a kept recording set, a stored spike train) is 0. NaN for points stored before paid
    seconds were kept.
``work_seconds`` (axes..., stage)
    wall seconds of the stage's work for the point, as measured when it ran, wherever and for
    whichever point (a spike train or a load that several points share counts in each of them;
    one-off work left out): what the design costs to compute, as the compute-time front plots
    it
``n_windows_used`` (axes...)
    int64 rate-coding windows the point used (``coding.n_windows`` resolved; -1 where its result
    does not say)
``decision_correct``, ``decision_confidence`` (axes..., model, decision_s, repeat, recording)
    and ``decoder_acs``, ``decoder_macs``, ``decoder_neuron_updates`` (axes..., model,
    decision_s): every model's decisions read during the touch and what each cost, on the
    ``decision_s`` coordinate (s of touch), where points kept them
    (:mod:`pipeline.results.decision_cube`)

Where some point simulates chips, the cube has a ``chip`` dimension along which accuracy,
predictions and spike metrics lie, and the yield statistics over each point's chips
(:mod:`pipeline.results.chip_cube`).

A sweep with ``correlate = true`` also holds ``correlation_r``, ``correlation_p`` (model, metric,
coefficient) and ``correlation_n`` (model, metric): Pearson and Spearman correlations of SSNR and
STE with ``accuracy_mean`` across the sweep's points (infinite metrics left out;
:mod:`pipeline.results.correlations`). Accuracy of a model or fold a point did not train is NaN; so
are the work seconds of a stage a point did not measure; ``predicted``, ``correct`` and
``test_fold`` are -1 where a point has no prediction (a model, repeat or recording it did not run;
no out-of-fold variables at all when no point kept its predictions). The ``recording`` dimension is
the union of the points' recordings (coordinate: names; ``label`` along it: class index). Every
variable but ``seconds`` and ``work_seconds`` is a deterministic function of the grid and its seeds;
those two are measurements (:data:`~pipeline.results.variables.MEASURED`). A cube written before
paid seconds were kept has ``seconds`` (axes..., stage) holding work seconds and no
``work_seconds``: :func:`paid_seconds` and :func:`work_seconds` read either layout.

Coordinates

* One per swept axis, named by its dimension (``threshold_v``), attribute ``field`` its dotted
  scene field, its values as the points' scenes read them (``[0, 1]`` given for a float field
  are the floats 0.0 and 1.0; a table has its defaults filled in); the other axes of a zipped
  sweep lie along the first one's dimension.
* ``result_key`` (axes...): each point's result cache key (a point two sweeps share has one key).
* Every other scene field by its dotted name (``array.rows``,
  ``readout.effects.amplifier_noise.sigma_v``, the base scene's fields and the sweep's fixed
  ``set`` ones alike): a scalar where every point has the same value, otherwise along the
  dimensions it varies with. A swept field is its axis's coordinate alone
  (:func:`field_coordinate` finds a field's coordinate either way). Lists and tables are
  canonical JSON strings (an ideal readout's ``readout.effects`` is ``"{}"``); a field left unset
  (its default applies, e.g. ``dataset.path`` of the built-in data) has none, and neither has
  ``name``.

Every variable and coordinate has CF ``units`` ("1" for dimensionless numbers and labels) and a
prose ``long_name``, declared once: on the scene's fields (:func:`pipeline.design.fields.param`), on
:class:`~pipeline.chain.metrics.SpikeMetrics`, on the results record
(:data:`pipeline.run.stages.RESULTS`) for :data:`~pipeline.results.variables.RESULT_VALUES`, and
beside the names for the cube's own (:mod:`pipeline.results.variables` and each feature's cube
module; :data:`CUBE_VARIABLES` gathers them). The ``stage`` coordinate is every step of the
stage registry (:func:`pipeline.run.stages.steps_of`).

Attributes: ``grid``, ``sweep``, ``title``, ``mode``, ``seed``, ``training_seed`` (the base
scene's), ``package_version`` and the versions of Python and of the libraries that shape the results
as ``version_<name>`` strings (:mod:`pipeline.results.provenance`); ``correlation_notes`` where a
correlation could not be computed; and, where every point's result states the same, what the
recordings were: ``dataset_name``, ``sampling_rate_hz``, ``class_names`` and ``n_classes``, and
for a real array ``taxel_names`` and ``taxel_positions_mm`` (where the dataset gives them).
"""

from __future__ import annotations

import dataclasses
import operator
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from pipeline.chain.metrics import SpikeMetrics
from pipeline.design import fields
from pipeline.design.grid import Grid, Sweep
from pipeline.design.scene import Model, Scene
from pipeline.results.accuracy_summary import accuracy_summary
from pipeline.results.chip_cube import CHIP_CUBE_VARIABLES, chip_variables
from pipeline.results.correlations import correlations
from pipeline.results.decision_cube import DECISION_CUBE_VARIABLES, decision_variables
from pipeline.results.out_of_fold import out_of_fold_variables
from pipeline.results.point import PointResult
from pipeline.results.provenance import provenance, recordings_attrs
from pipeline.results.scene_coordinates import axis_coordinates, scene_coordinates
from pipeline.results.variables import (
    ACCURACY,
    CHARGE_DIM,
    CORRECT,
    FOLD_DIM,
    LABEL,
    METRICS,
    MODEL_DIM,
    RECORDING_DIM,
    REPEAT_DIM,
    RESULT_KEY,
    RESULT_VALUES,
    SECONDS,
    SHARED_VARIABLES,
    STAGE_DIM,
    WORK_SECONDS,
)
from pipeline.run.grid_keys import keyed_points
from pipeline.run.records import Charge, Paid
from pipeline.run.stages import RESULTS, steps_of

__all__ = [
    "CUBE_VARIABLES",
    "build_cube",
    "declared_names",
    "describe",
    "field_attrs",
    "field_coordinate",
    "metric_attrs",
    "paid_seconds",
    "work_seconds",
]


def _gathered(*declarations: Mapping[str, dict[str, str]]) -> dict[str, dict[str, str]]:
    """The declarations as one mapping, refused at import if two declare the same name."""
    gathered: dict[str, dict[str, str]] = {}
    for declared in declarations:
        twice = sorted(set(gathered) & set(declared))
        if twice:
            raise ValueError(f"cube variables declared twice: {twice}")
        gathered |= declared
    return gathered


#: ``units`` and ``long_name`` of the cube's own variables and coordinates: the shared ones
#: (:data:`pipeline.results.variables.SHARED_VARIABLES`) and each feature's.
CUBE_VARIABLES: dict[str, dict[str, str]] = _gathered(
    SHARED_VARIABLES, CHIP_CUBE_VARIABLES, DECISION_CUBE_VARIABLES
)


def build_cube(
    grid: Grid,
    sweep: Sweep,
    records: Mapping[str, PointResult],
) -> xr.Dataset:
    """Assemble the cube of one sweep from its points' results.

    Parameters
    ----------
    grid, sweep
        The grid and one of its sweeps.
    records
        Result of every point of the sweep, by result key. The ``stage`` coordinate is every
        step of the stage registry, in order (:func:`pipeline.run.stages.steps_of`).

    Raises
    ------
    KeyError
        A point of the sweep has no record.

    Notes
    -----
    The points' results are gathered into arrays and written at once (and scene coordinates
    read once per distinct scene part), so a cube costs some tens of microseconds per point;
    only a point with several repeats is still visited alone, for its bootstrap interval.
    """
    points = keyed_points(grid, sweep)
    results = [records[point.key] for point in points]
    shape = sweep.shape
    # Where each point sits in the cube's flattened sweep dimensions: every per-point value is
    # gathered into one array and scattered at once, rather than written point by point.
    flat = np.ravel_multi_index(tuple(np.array([p.index for p in points]).T), shape)
    # Points share their scene parts: read each distinct training part once.
    trainings = list({id(p.scene.training): p.scene.training for p in points}.values())
    models = [m.value for m in Model if any(m in t.models for t in trainings)]
    n_folds = max(t.folds for t in trainings)
    n_repeats = max(t.repeats for t in trainings)
    stages = list(steps_of(models))
    size = int(np.prod(shape))
    accuracy = _fold_accuracy(results, flat, size, models, n_repeats, n_folds)
    accuracy = accuracy.reshape(*shape, *accuracy.shape[1:])
    by_point = np.full((size, len(METRICS)), np.nan)
    by_point[flat] = [operator.attrgetter(*METRICS)(result.metrics) for result in results]
    metrics = {name: by_point[:, i].reshape(shape) for i, name in enumerate(METRICS)}
    work = np.full((size, len(stages)), np.nan)
    work[flat] = [[result.seconds.get(stage, np.nan) for stage in stages] for result in results]
    work = work.reshape(*shape, len(stages))
    paid = np.full((size, len(stages), len(Charge)), np.nan)
    paid[flat] = [_paid_row(result.paid, stages) for result in results]
    paid = paid.reshape(*shape, len(stages), len(Charge))
    dims = sweep.dims
    data_vars: dict[str, Any] = {
        ACCURACY: ((*dims, MODEL_DIM, REPEAT_DIM, FOLD_DIM), accuracy),
        **{name: (dims, values) for name, values in metrics.items()},
        SECONDS: ((*dims, STAGE_DIM, CHARGE_DIM), paid),
        WORK_SECONDS: ((*dims, STAGE_DIM), work),
    }
    for name, unknown in RESULT_VALUES.items():
        values = np.full(size, unknown, dtype=np.int64)
        stated = [getattr(result, name) for result in results]
        values[flat] = [unknown if value is None else value for value in stated]
        data_vars[name] = (dims, values.reshape(shape))
    coords: dict[str, Any] = {
        MODEL_DIM: (MODEL_DIM, models),
        REPEAT_DIM: (REPEAT_DIM, np.arange(n_repeats)),
        FOLD_DIM: (FOLD_DIM, np.arange(n_folds)),
        STAGE_DIM: (STAGE_DIM, stages),
        CHARGE_DIM: (CHARGE_DIM, [str(charge) for charge in Charge]),
    }
    oofs = [result.out_of_fold for result in results]
    out_of_fold = out_of_fold_variables(oofs, flat, models, n_repeats, dims, shape)
    correct = label = None
    if out_of_fold is not None:
        predictions, recording_coords = out_of_fold
        data_vars.update(predictions)
        coords.update(recording_coords)
        correct, label = predictions[CORRECT][1], recording_coords[LABEL][1]
        decided = decision_variables(
            results, flat, models, n_repeats, dims, shape, recording_coords[RECORDING_DIM][1]
        )
        if decided is not None:
            data_vars.update(decided[0])
            coords.update(decided[1])
    data_vars.update(accuracy_summary(accuracy, correct, label, dims, points, models))
    coords.update(axis_coordinates(sweep, points))
    chips = chip_variables(results, points, flat, shape, dims, models, data_vars, coords)
    if chips is not None:
        data_vars.update(chips[0])
        coords.update(chips[1])
    cube = xr.Dataset(data_vars, coords=coords)
    if sweep.correlate:
        correlated = correlations(cube, models)
        cube = cube.merge(correlated)
        cube.attrs.update(correlated.attrs)
    keys = np.empty(size, dtype=object)
    keys[flat] = [point.key for point in points]
    keys = keys.reshape(shape)
    # A swept field is its axis's coordinate, not a second one by its dotted name. A top-level
    # field's name has no dot: a dimension named after another ``*.seed`` leaves the scene seed
    # to the attributes.
    swept = {axis.field for axis in sweep.axes}
    scene_fields = {
        name: variable
        for name, variable in scene_coordinates(points, flat, sweep).items()
        if name not in swept and name not in cube.variables and name not in cube.dims
    }
    cube = cube.assign_coords({RESULT_KEY: (dims, keys.astype(str)), **scene_fields})
    for name, variable in cube.variables.items():
        variable.attrs.update(describe(str(name), variable.attrs.get("field")))
    cube.attrs.update(provenance(grid, sweep))
    cube.attrs.update(recordings_attrs([result.recordings for result in results]))
    return cube


def _paid_row(paid: Paid | None, stages: Sequence[str]) -> np.ndarray:
    """float64 (stage, charge): a point's paid seconds, 0 for a stage it paid nothing for, NaN
    throughout when its result does not say."""
    if paid is None:
        return np.full((len(stages), len(Charge)), np.nan)
    return np.array(
        [[paid.get(charge, {}).get(stage, 0.0) for charge in Charge] for stage in stages]
    )


def paid_seconds(cube: xr.Dataset) -> xr.DataArray | None:
    """The cube's paid seconds (axes..., stage, charge); None when it has none: no ``seconds``,
    or the layout written before they were kept (whose ``seconds`` are work seconds)."""
    if SECONDS not in cube or CHARGE_DIM not in cube[SECONDS].dims:
        return None
    return cube[SECONDS]


def work_seconds(cube: xr.Dataset) -> xr.DataArray | None:
    """The cube's work seconds (axes..., stage), of either layout; None when it has none."""
    if WORK_SECONDS in cube:
        return cube[WORK_SECONDS]
    if SECONDS in cube and CHARGE_DIM not in cube[SECONDS].dims:
        return cube[SECONDS]
    return None


def _fold_accuracy(
    results: Sequence[PointResult],
    flat: np.ndarray,
    size: int,
    models: list[str],
    n_repeats: int,
    n_folds: int,
) -> np.ndarray:
    """float64 (points, model, repeat, fold) accuracy, points in flat cube order: NaN where a
    point did not train a model, repeat or fold."""
    accuracy = np.full((size, len(models), n_repeats, n_folds), np.nan)
    for m, model in enumerate(models):
        # Points with the same (repeats, folds) are written together.
        groups: dict[tuple[int, ...], tuple[list[int], list[np.ndarray]]] = {}
        for i, result in enumerate(results):
            folds = result.fold_accuracy.get(model)
            if folds is not None:
                folds = np.atleast_2d(folds)
                rows, values = groups.setdefault(folds.shape, ([], []))
                rows.append(i)
                values.append(folds)
        for (repeats, n), (rows, values) in groups.items():
            accuracy[flat[rows], m, :repeats, :n] = np.stack(values)
    return accuracy


def describe(name: str, field: str | None = None) -> dict[str, str]:
    """``units`` and ``long_name`` of a cube variable or coordinate, from their one declaration.

    Parameters
    ----------
    name
        A name of :data:`CUBE_VARIABLES`, a spike metric, one of
        :data:`~pipeline.results.variables.RESULT_VALUES` or a dotted scene field.
    field
        The dotted scene field of a swept axis's coordinate (its name is a dimension name).

    Raises
    ------
    KeyError
        ``name`` is none of those.
    """
    if field is not None:
        return field_attrs(field)
    if name in CUBE_VARIABLES:
        return dict(CUBE_VARIABLES[name])
    if name in METRICS:
        return metric_attrs(name)
    if name in RESULT_VALUES:
        return RESULTS.record.variable(name).attrs()
    return field_attrs(name)


def declared_names() -> tuple[str, ...]:
    """Every variable and coordinate name a cube declares with :func:`describe`, swept scene
    fields aside: the cube's own (:data:`CUBE_VARIABLES`), the spike metrics and
    :data:`~pipeline.results.variables.RESULT_VALUES`, in that order."""
    return (*CUBE_VARIABLES, *METRICS, *RESULT_VALUES)


def metric_attrs(name: str) -> dict[str, str]:
    """``units`` and ``long_name`` of a :class:`~pipeline.chain.metrics.SpikeMetrics` field."""
    found = {f.name: f for f in dataclasses.fields(SpikeMetrics)}
    return _declared(found[name], name)


def field_attrs(field: str) -> dict[str, str]:
    """``units`` and ``long_name`` of a dotted scene field, as its declaration states them.

    A whole effect table (``readout.effects.saturation``) is a dimensionless JSON label.

    Raises
    ------
    KeyError
        ``field`` names no scene field (:class:`pipeline.design.fields.UnknownField`).
    """
    found = fields.resolve(Scene, field)
    return {"units": found.units, "long_name": found.long_name}


def field_coordinate(cube: xr.Dataset, field: str) -> str | None:
    """The name of the coordinate of ``cube`` that holds dotted scene ``field``: the field's
    own name, or the swept axis's coordinate whose ``field`` attribute it is; None if the cube
    has none (a field left unset)."""
    if field in cube.coords:
        return field
    for name, coordinate in cube.coords.items():
        if coordinate.attrs.get("field") == field:
            return str(name)
    return None


def _declared(found: dataclasses.Field, name: str) -> dict[str, str]:
    if "units" not in found.metadata or "long_name" not in found.metadata:
        raise KeyError(f"{name!r} declares no units and long_name")
    return {"units": found.metadata["units"], "long_name": found.metadata["long_name"]}
