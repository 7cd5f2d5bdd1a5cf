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

Where some point simulates chips (``chips.count`` above 1, or a ``shared`` or ``robust``
deployment: :mod:`pipeline.chain.chips`), the cube has a ``chip`` dimension (coordinate
0..N-1, N the most chips of any point; a point's missing chips are NaN, or -1 for the integer
variables) along which ``accuracy`` (axes..., model, chip, repeat, fold), ``accuracy_mean``,
``accuracy_low``, ``accuracy_high`` (axes..., model, chip), ``predicted`` and ``correct``
(axes..., model, chip, repeat, recording) and the spike metrics but ``equivalent_bits``
(axes..., chip) lie, and the yield statistics over each point's chips
(:func:`pipeline.results.yields.yield_statistics`), all (axes..., model):

``accuracy_chip_mean``
    mean of ``accuracy_mean`` over the chips
``accuracy_p05``, ``accuracy_p05_low``, ``accuracy_p05_high``
    5th percentile of ``accuracy_mean`` over the chips and its distribution-free 95 % interval
    from order statistics (NaN for a bound the point's chips are too few to give)
``yield_share``
    share of the chips whose ``accuracy_mean`` is at or above the point's
    ``chips.yield_target``

A sweep with ``correlate = true`` also holds ``correlation_r``, ``correlation_p`` (model,
metric, coefficient) and ``correlation_n`` (model, metric): Pearson and Spearman correlations of
SSNR and STE with ``accuracy_mean`` across the sweep's points (infinite metrics left out).
Accuracy of a model or fold a point did not train is NaN; so are the work seconds of a stage a
point did not measure; ``predicted``, ``correct`` and ``test_fold`` are -1 where a point has no
prediction (a model, repeat or recording it did not run; no out-of-fold variables at all when no
point kept its predictions). The ``recording`` dimension is the union of the points' recordings
(coordinate: names; ``label`` along it: class index). Every variable but ``seconds`` and
``work_seconds`` is a deterministic function of the grid and its seeds; those two are
measurements (:data:`MEASURED`). A cube written before paid seconds were kept has ``seconds``
(axes..., stage) holding work seconds and no ``work_seconds``: :func:`paid_seconds` and
:func:`work_seconds` read either layout.

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
(:data:`pipeline.run.stages.RESULTS`) for :data:`RESULT_VALUES`, and here (:data:`CUBE_VARIABLES`)
for the cube's own. The ``stage`` coordinate is every step of the stage registry
(:func:`pipeline.run.stages.steps_of`).

Attributes: ``grid``, ``sweep``, ``title``, ``mode``, ``seed``, ``training_seed`` (the base
scene's), ``package_version`` and the versions of Python and of the libraries that shape the
results as ``version_<name>`` strings (:data:`DEPENDENCY_VERSIONS`); ``correlation_notes`` where a
correlation could not be computed; and, where every point's result states the same, what the
recordings were: ``dataset_name``, ``sampling_rate_hz``, ``class_names`` and ``n_classes``.
"""

from __future__ import annotations

import dataclasses
import json
import operator
import platform
import warnings
from collections.abc import Mapping, Sequence
from importlib import metadata
from typing import Any, Protocol

import numpy as np
import xarray as xr

from pipeline.chain.metrics import CORRELATION_METHODS, SpikeMetrics, correlate_with_accuracy
from pipeline.design import fields
from pipeline.design.grid import Grid, Sweep
from pipeline.design.scene import Model, Scene, canonical_parts, part_left_out
from pipeline.results.decision_cube import decision_variables
from pipeline.run.grid_keys import KeyedPoint, keyed_points
from pipeline.run.records import Charge, OutOfFold, Paid, RecordingsInfo
from pipeline.run.stages import RESULTS, interval_generator, steps_of

METRICS = tuple(f.name for f in dataclasses.fields(SpikeMetrics))
CORRELATED_METRICS = ("ssnr_db", "ste_s2")
#: ``units`` and ``long_name`` of the cube's own variables and coordinates.
CUBE_VARIABLES: dict[str, dict[str, str]] = {
    "accuracy": {"units": "1", "long_name": "fraction of test recordings classified correctly"},
    "accuracy_mean": {"units": "1", "long_name": "fraction of recordings classified correctly"},
    "accuracy_low": {"units": "1", "long_name": "lower end of the 95 % interval of accuracy"},
    "accuracy_high": {"units": "1", "long_name": "upper end of the 95 % interval of accuracy"},
    "predicted": {"units": "1", "long_name": "out-of-fold predicted class (-1: none)"},
    "correct": {"units": "1", "long_name": "out-of-fold prediction correct (1, 0; -1: none)"},
    "test_fold": {"units": "1", "long_name": "fold that tested the recording (-1: none)"},
    "repeat": {"units": "1", "long_name": "cross-validation repeat"},
    "recording": {"units": "1", "long_name": "recording"},
    "label": {"units": "1", "long_name": "class index of the recording"},
    "seconds": {
        "units": "s",
        "long_name": "wall time a worker paid computing the point, by stage and charge",
    },
    "work_seconds": {
        "units": "s",
        "long_name": "wall time of the stage's work for the point, as measured when it ran",
    },
    "charge": {
        "units": "1",
        "long_name": "whom paid seconds were for: the point (own) or its worker's later points",
    },
    "correlation_r": {"units": "1", "long_name": "correlation of the metric with mean accuracy"},
    "correlation_p": {"units": "1", "long_name": "two-sided p-value of the correlation"},
    "correlation_n": {"units": "1", "long_name": "sweep points in the correlation"},
    "model": {"units": "1", "long_name": "classifier"},
    "fold": {"units": "1", "long_name": "cross-validation fold"},
    "stage": {"units": "1", "long_name": "pipeline stage"},
    "metric": {"units": "1", "long_name": "spike metric correlated with accuracy"},
    "coefficient": {"units": "1", "long_name": "correlation coefficient"},
    "result_key": {"units": "1", "long_name": "result cache key of the point"},
    "chip": {"units": "1", "long_name": "simulated chip of the design"},
    "accuracy_chip_mean": {"units": "1", "long_name": "mean over the chips of their accuracy"},
    "accuracy_p05": {"units": "1", "long_name": "5th percentile over the chips of their accuracy"},
    "accuracy_p05_low": {
        "units": "1",
        "long_name": "lower end of the distribution-free 95 % interval of accuracy_p05",
    },
    "accuracy_p05_high": {
        "units": "1",
        "long_name": "upper end of the distribution-free 95 % interval of accuracy_p05",
    },
    "yield_share": {
        "units": "1",
        "long_name": "share of the chips whose accuracy reaches chips.yield_target",
    },
    "decision_s": {"units": "s", "long_name": "seconds of touch at which a decision is read"},
    "decision_correct": {
        "units": "1",
        "long_name": "decision read at that time correct (1, 0; -1: no decision)",
    },
    "decision_confidence": {
        "units": "1",
        "long_name": "softmax probability of the class decided at that time (NaN: none)",
    },
    "decoder_acs": {
        "units": "1",
        "long_name": "mean accumulates (spike inputs) a decision read at that time cost",
    },
    "decoder_macs": {
        "units": "1",
        "long_name": "mean multiply-accumulates (real inputs) a decision read at that time cost",
    },
    "decoder_neuron_updates": {
        "units": "1",
        "long_name": "mean neuron state updates a decision read at that time cost",
    },
}
#: Per-point values the results store beside accuracy and metrics, as cube variables (axes...):
#: name -> the value where a point's result does not state it. Units and long names are those
#: of the results record's declaration (:data:`pipeline.run.stages.RESULTS`).
RESULT_VALUES: dict[str, int] = {"n_windows_used": -1}
#: The dimension of ``seconds`` that says whom they were paid for
#: (:class:`~pipeline.run.records.Charge`).
CHARGE_DIM = "charge"
#: The cube's measured variables, wall times; every other one is a deterministic function of
#: the grid and its seeds.
MEASURED = ("seconds", "work_seconds")
# One string attribute per library, not a nested mapping: netCDF and Zarr attributes are flat, and
# plain strings keep cubes comparable with xarray.testing.assert_identical. Read once, at import:
# the process runs one set of libraries.
#: The versions of Python and of the libraries that shape the results, as the cube's string
#: attributes ``version_<name>`` (``version_python``, ``version_torch``, ``version_scikit_learn``,
#: ...), read at import.
#:
#: :meta hide-value:
DEPENDENCY_VERSIONS: dict[str, str] = {
    "version_python": platform.python_version(),
    **{
        f"version_{name.replace('-', '_')}": metadata.version(name)
        for name in ("torch", "numpy", "numba", "scikit-learn", "xarray", "zarr")
    },
}


class PointResult(Protocol):
    """What the cube needs of one point (:class:`pipeline.run.records.ResultEntry` is one)."""

    @property
    def fold_accuracy(self) -> Mapping[str, np.ndarray]:
        """Model name -> float64 (repeats, folds) accuracy in [0, 1] (a ``(folds,)`` array is one
        repeat)."""
        ...

    @property
    def seconds(self) -> Mapping[str, float]:
        """Wall seconds of every step's work for the point, by step name."""
        ...

    @property
    def paid(self) -> Paid | None:
        """Wall seconds a worker paid computing the point, by charge and step name; None where
        its result does not say."""
        ...

    @property
    def metrics(self) -> SpikeMetrics:
        """The point's spike metrics."""
        ...

    @property
    def recordings(self) -> RecordingsInfo | None:
        """What the point was computed on; None where its result does not say."""
        ...

    @property
    def out_of_fold(self) -> OutOfFold | None:
        """Every recording's out-of-fold prediction per model and repeat; None where the point
        kept none."""
        ...

    @property
    def n_windows_used(self) -> int | None:
        """Rate-coding windows the point used (``coding.n_windows`` resolved); None where its
        result does not say."""
        ...


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
        "accuracy": ((*dims, "model", "repeat", "fold"), accuracy),
        **{name: (dims, values) for name, values in metrics.items()},
        "seconds": ((*dims, "stage", CHARGE_DIM), paid),
        "work_seconds": ((*dims, "stage"), work),
    }
    for name, unknown in RESULT_VALUES.items():
        values = np.full(size, unknown, dtype=np.int64)
        stated = [getattr(result, name) for result in results]
        values[flat] = [unknown if value is None else value for value in stated]
        data_vars[name] = (dims, values.reshape(shape))
    coords: dict[str, Any] = {
        "model": ("model", models),
        "repeat": ("repeat", np.arange(n_repeats)),
        "fold": ("fold", np.arange(n_folds)),
        "stage": ("stage", stages),
        CHARGE_DIM: (CHARGE_DIM, [str(charge) for charge in Charge]),
    }
    oofs = [result.out_of_fold for result in results]
    out_of_fold = _out_of_fold_variables(oofs, flat, models, n_repeats, dims, shape)
    correct = label = None
    if out_of_fold is not None:
        predictions, recording_coords = out_of_fold
        data_vars.update(predictions)
        coords.update(recording_coords)
        correct, label = predictions["correct"][1], recording_coords["label"][1]
        decided = decision_variables(
            results, flat, models, n_repeats, dims, shape, recording_coords["recording"][1]
        )
        if decided is not None:
            data_vars.update(decided[0])
            coords.update(decided[1])
    data_vars.update(_accuracy_summary(accuracy, correct, label, dims, points, models))
    coords.update(_axis_coordinates(sweep, points))
    chip_variables = _chip_variables(results, points, flat, shape, dims, models, data_vars, coords)
    if chip_variables is not None:
        data_vars.update(chip_variables[0])
        coords.update(chip_variables[1])
    cube = xr.Dataset(data_vars, coords=coords)
    if sweep.correlate:
        correlations = _correlations(cube, models)
        cube = cube.merge(correlations)
        cube.attrs.update(correlations.attrs)
    keys = np.empty(size, dtype=object)
    keys[flat] = [point.key for point in points]
    keys = keys.reshape(shape)
    # A swept field is its axis's coordinate, not a second one by its dotted name. A top-level
    # field's name has no dot: a dimension named after another ``*.seed`` leaves the scene seed
    # to the attributes.
    swept = {axis.field for axis in sweep.axes}
    scene_fields = {
        name: variable
        for name, variable in _scene_coordinates(points, flat, sweep).items()
        if name not in swept and name not in cube.variables and name not in cube.dims
    }
    cube = cube.assign_coords(result_key=(dims, keys.astype(str)), **scene_fields)
    for name, variable in cube.variables.items():
        variable.attrs.update(describe(str(name), variable.attrs.get("field")))
    cube.attrs.update(_provenance(grid, sweep))
    cube.attrs.update(_recordings_attrs([result.recordings for result in results]))
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
    if "seconds" not in cube or CHARGE_DIM not in cube["seconds"].dims:
        return None
    return cube["seconds"]


def work_seconds(cube: xr.Dataset) -> xr.DataArray | None:
    """The cube's work seconds (axes..., stage), of either layout; None when it has none."""
    if "work_seconds" in cube:
        return cube["work_seconds"]
    if "seconds" in cube and CHARGE_DIM not in cube["seconds"].dims:
        return cube["seconds"]
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
        A name of :data:`CUBE_VARIABLES`, a spike metric, one of :data:`RESULT_VALUES` or a
        dotted scene field.
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
    :data:`RESULT_VALUES`, in that order."""
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


def _correlations(cube: xr.Dataset, models: list[str]) -> xr.Dataset:
    shape = (len(models), len(CORRELATED_METRICS), len(CORRELATION_METHODS))
    r, p = np.full(shape, np.nan), np.full(shape, np.nan)
    n = np.zeros(shape[:2], dtype=np.int64)
    notes = []
    for i, model in enumerate(models):
        mean_accuracy = cube["accuracy_mean"].sel(model=model).values.ravel()
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


def _out_of_fold_variables(
    oofs: Sequence[OutOfFold | None],
    flat: np.ndarray,
    models: list[str],
    n_repeats: int,
    dims: tuple[str, ...],
    shape: tuple[int, ...],
) -> tuple[dict[str, Any], dict[str, Any]] | None:
    """``predicted``, ``correct``, ``test_fold`` and the ``recording`` coordinates of a sweep.

    ``oofs`` are the points' predictions and ``flat`` their positions in the flattened sweep
    dimensions. The ``recording`` dimension is the union of the points' recordings, in the
    order first met (points of a ``dataset.recordings_per_class`` sweep hold different numbers
    of recordings); None when no point kept its predictions.
    """
    # Points holding the same recordings in the same order share one column index, and are
    # written together; typically every point of a sweep is one group.
    groups: dict[tuple[str, ...], list[int]] = {}
    for i, oof in enumerate(oofs):
        if oof is not None:
            groups.setdefault(tuple(oof.recording_names), []).append(i)
    if not groups:
        return None
    position: dict[str, int] = {}
    labels: list[int] = []
    # A recording's label is that of the first point holding it: the first of its group.
    for names, members in groups.items():
        for name, label in zip(names, np.asarray(oofs[members[0]].labels), strict=True):
            if name not in position:
                position[name] = len(position)
                labels.append(int(label))
    n = len(position)
    size = int(np.prod(shape))
    predicted = np.full((size, len(models), n_repeats, n), -1, dtype=np.int16)
    test_fold = np.full((size, n_repeats, n), -1, dtype=np.int16)
    for names, members in groups.items():
        columns = np.array([position[name] for name in names], dtype=np.int64)
        by_repeats: dict[int, list[int]] = {}
        for i in members:
            by_repeats.setdefault(np.shape(oofs[i].test_fold)[0], []).append(i)
        for repeats, same in by_repeats.items():
            # (points, 1, 1), (1, repeats, 1) and (1, 1, recordings): each point's block.
            rows = flat[same][:, np.newaxis, np.newaxis]
            ran = np.arange(repeats)[np.newaxis, :, np.newaxis]
            test_fold[rows, ran, columns] = np.stack([np.asarray(oofs[i].test_fold) for i in same])
            for m, model in enumerate(models):
                having = [i for i in same if model in oofs[i].predicted]
                if having:
                    values = np.stack([np.asarray(oofs[i].predicted[model]) for i in having])
                    predicted[flat[having][:, np.newaxis, np.newaxis], m, ran, columns] = values
    predicted = predicted.reshape(*shape, *predicted.shape[1:])
    test_fold = test_fold.reshape(*shape, *test_fold.shape[1:])
    label = np.asarray(labels, dtype=np.int16)
    tested = predicted >= 0
    correct = np.where(tested, (predicted == label).astype(np.int8), np.int8(-1))
    variables = {
        "predicted": ((*dims, "model", "repeat", "recording"), predicted),
        "correct": ((*dims, "model", "repeat", "recording"), correct),
        "test_fold": ((*dims, "repeat", "recording"), test_fold),
    }
    coordinates = {
        "recording": ("recording", np.asarray(list(position), dtype=str)),
        "label": ("recording", label),
    }
    return variables, coordinates


def _accuracy_summary(
    accuracy: np.ndarray,
    correct: np.ndarray | None,
    label: np.ndarray | None,
    dims: tuple[str, ...],
    points: list[KeyedPoint],
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
    from pipeline.results.stats import WILSON_METHOD, accuracy_interval, wilson_interval

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
        "accuracy_mean": ((*dims, "model"), mean.reshape(shape)),
        "accuracy_low": ((*dims, "model"), low.reshape(shape), attrs),
        "accuracy_high": ((*dims, "model"), high.reshape(shape), attrs),
    }


def _coordinate(values: Sequence[Any]) -> np.ndarray:
    """Numbers stay numbers; tables (e.g. a whole effects mapping) become canonical JSON."""
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        return np.asarray(values)
    if all(isinstance(v, str | bool) for v in values):
        return np.asarray(values)
    return np.asarray([json.dumps(v, sort_keys=True) for v in values])


def _axis_coordinates(sweep: Sweep, points: list[KeyedPoint]) -> dict[str, Any]:
    """The coordinate of each swept axis, named by its dimension (attribute ``field``), along
    the first dimension of a zipped sweep: each value as the points' parsed scenes hold it (as
    :meth:`pipeline.design.scene.Scene.to_dict` writes it), read once per value."""
    dims = sweep.dims
    coords: dict[str, Any] = {}
    for position, axis in enumerate(sweep.axes):
        along = 0 if sweep.mode == "zip" else position
        # The first point (C order) at each index along the axis's dimension.
        first: dict[int, KeyedPoint] = {}
        for point in points:
            first.setdefault(point.index[along], point)
        values = [
            fields.plain(fields.get(first[i].scene, axis.field)) for i in range(len(axis.values))
        ]
        coords[axis.dim] = (dims[along], _coordinate(values), {"field": axis.field})
    return coords


def _scene_coordinates(
    points: list[KeyedPoint], flat: np.ndarray, sweep: Sweep
) -> dict[str, xr.Variable]:
    """Every scene field that every point has, along the dims it varies with.

    ``flat`` gives each point's position in the flattened sweep dimensions. A field's values are
    read once per distinct object of the scene part holding it (the points of a sweep share
    their parts).
    """
    size = int(np.prod(sweep.shape))
    tops = [
        top
        for top in canonical_parts(type(points[0].scene))
        if not all(part_left_out(top, getattr(p.scene, top)) for p in points)
    ]
    # Per top-level field: each point's part as an index into that part's distinct objects,
    # and each distinct object's flattened fields.
    owner = {top: np.empty(size, dtype=np.int64) for top in tops}
    distinct: dict[str, dict[int, int]] = {top: {} for top in tops}
    flattened: dict[str, list[dict[str, Any]]] = {top: [] for top in tops}
    for i, point in zip(flat.tolist(), points, strict=True):
        scene = point.scene
        new = [top for top in tops if id(getattr(scene, top)) not in distinct[top]]
        if new:
            data = scene.to_dict()
            for top in new:
                distinct[top][id(getattr(scene, top))] = len(flattened[top])
                flattened[top].append(fields.flatten({top: data[top]} if top in data else {}))
        for top in tops:
            owner[top][i] = distinct[top][id(getattr(scene, top))]
    # A field with its owners, as above.
    columns: dict[str, tuple[np.ndarray, list[dict[str, Any]]]] = {}
    first = points[0].scene
    for top in tops:
        for field in flattened[top][distinct[top][id(getattr(first, top))]]:
            columns[field] = (owner[top], flattened[top])
    coords = {}
    for field, (owners, values) in columns.items():
        if not all(field in found for found in values):
            continue  # some points do not have it: a swept table's coordinate describes them
        coords[field] = _along_varied_owned(
            owners.reshape(sweep.shape), [found[field] for found in values], sweep.dims
        )
    return coords


def _along_varied_owned(
    owners: np.ndarray, values: list[Any], dims: tuple[str, ...]
) -> xr.Variable:
    """:func:`_along_varied` of ``values[owners]`` (owners: int, sweep shape), comparing the
    distinct ``values`` once rather than every point's."""
    codes: dict[Any, int] = {}
    try:
        equal = np.array([codes.setdefault(label, len(codes)) for label in map(_label, values)])
        comparable = all(label == label for label in codes)
    except TypeError:  # an unhashable value: compared point by point instead
        comparable = False
    if not comparable:  # a value unequal to itself (NaN) differs even from itself
        gathered = np.empty(owners.shape, dtype=object)
        for index, i in np.ndenumerate(owners):
            gathered[index] = values[i]
        return _along_varied(gathered, dims)
    labels = equal[owners]
    varied = [k for k in range(labels.ndim) if np.any(labels != np.take(labels, [0], axis=k))]
    if not varied:
        return xr.Variable((), _coordinate([values[owners.flat[0]]]).reshape(()))
    kept = owners[tuple(slice(None) if k in varied else 0 for k in range(owners.ndim))]
    data = _coordinate([values[i] for i in kept.ravel().tolist()]).reshape(kept.shape)
    return xr.Variable(tuple(dims[k] for k in varied), data)


def _along_varied(values: np.ndarray, dims: tuple[str, ...]) -> xr.Variable:
    """A coordinate over only the dims along which ``values`` (object, sweep shape) change."""
    labels = np.vectorize(_label, otypes=[object])(values)
    varied = [k for k in range(labels.ndim) if np.any(labels != np.take(labels, [0], axis=k))]
    if not varied:
        return xr.Variable((), _coordinate([values.flat[0]]).reshape(()))
    kept = values[tuple(slice(None) if k in varied else 0 for k in range(values.ndim))]
    data = _coordinate(kept.ravel().tolist()).reshape(kept.shape)
    return xr.Variable(tuple(dims[k] for k in varied), data)


def _label(value: Any) -> Any:
    """A value comparable with ``==``: tables and lists as canonical JSON."""
    return json.dumps(value, sort_keys=True) if isinstance(value, list | dict) else value


def _recordings_attrs(infos: Sequence[RecordingsInfo | None]) -> dict[str, Any]:
    """What every point says alike of its recordings; a fact any point lacks or contradicts is
    left out rather than guessed."""
    attrs: dict[str, Any] = {}
    for name in ("dataset_name", "sampling_rate_hz", "class_names"):
        values = {None if info is None else getattr(info, name) for info in infos}
        if len(values) == 1 and None not in values:
            attrs[name] = values.pop()
    if "sampling_rate_hz" in attrs:
        attrs["sampling_rate_hz"] = float(attrs["sampling_rate_hz"])
    if "class_names" in attrs:
        # A list, not a tuple: attributes come back from Zarr as lists.
        attrs["class_names"] = [str(c) for c in attrs["class_names"]]
        attrs["n_classes"] = len(attrs["class_names"])
    return attrs


def _provenance(grid: Grid, sweep: Sweep) -> dict[str, Any]:
    return {
        "grid": grid.name,
        "sweep": sweep.name,
        "title": sweep.title,
        "mode": sweep.mode.value,
        "seed": grid.base.seed,
        "training_seed": grid.base.training.seed,
        "package_version": metadata.version("eskin-sweep"),
        **DEPENDENCY_VERSIONS,
    }


#: The spike metrics a cube holds per chip (``equivalent_bits`` is the design's alone).
CHIP_METRICS = tuple(name for name in METRICS if name != "equivalent_bits")


@dataclasses.dataclass(frozen=True)
class _ChipCell:
    """A point's chip as :func:`_accuracy_summary` sees it: one more sweep index."""

    index: tuple[int, ...]
    key: str


def _chip_variables(
    results: Sequence[PointResult],
    points: list[KeyedPoint],
    flat: np.ndarray,
    shape: tuple[int, ...],
    dims: tuple[str, ...],
    models: list[str],
    data_vars: Mapping[str, Any],
    coords: Mapping[str, Any],
) -> tuple[dict[str, Any], dict[str, Any]] | None:
    """The chip variables and the ``chip`` coordinate of a sweep where some point simulates
    chips (see the module docstring); None where none does.

    A point of one chip without chip results has its own accuracy, predictions and metrics
    (``data_vars``) as chip 0.
    """
    from pipeline.results.yields import yield_statistics

    chips = [getattr(result, "chips", None) for result in results]
    if all(c is None for c in chips):
        return None
    n_chips = max(1 if c is None else c.n_chips for c in chips)
    size = int(np.prod(shape))
    base = data_vars["accuracy"][1].reshape(size, *data_vars["accuracy"][1].shape[len(shape) :])
    n_models, n_repeats, n_folds = base.shape[1:]
    accuracy = np.full((size, n_chips, n_models, n_repeats, n_folds), np.nan)
    accuracy[:, 0] = base
    metrics = {name: np.full((size, n_chips), np.nan) for name in CHIP_METRICS}
    for name in CHIP_METRICS:
        metrics[name][:, 0] = np.asarray(data_vars[name][1]).reshape(size)
    predicted = None
    if "predicted" in data_vars:
        old = data_vars["predicted"][1]
        old = old.reshape(size, *old.shape[len(shape) :])
        predicted = np.full((size, n_chips, *old.shape[1:]), -1, dtype=np.int16)
        predicted[:, 0] = old
        position = {str(name): i for i, name in enumerate(coords["recording"][1])}
    for i, chip in zip(flat.tolist(), chips, strict=True):
        if chip is None:
            continue
        for m, model in enumerate(models):
            if model in chip.fold_accuracy:
                values = np.asarray(chip.fold_accuracy[model])
                accuracy[i, : values.shape[0], m, : values.shape[1], : values.shape[2]] = values
        for k, found in enumerate(chip.metrics):
            for name in CHIP_METRICS:
                metrics[name][i, k] = getattr(found, name)
    if predicted is not None:
        for p, (i, chip) in enumerate(zip(flat.tolist(), chips, strict=True)):
            oof = results[p].out_of_fold
            if chip is None or oof is None:
                continue
            columns = np.array([position[name] for name in oof.recording_names])
            for m, model in enumerate(models):
                if model in chip.predicted:
                    values = np.asarray(chip.predicted[model])
                    ran = np.arange(values.shape[1])[np.newaxis, :, np.newaxis]
                    kept = np.arange(values.shape[0])[:, np.newaxis, np.newaxis]
                    predicted[i, kept, m, ran, columns] = values
    chip_dims = (*dims, "chip")
    cells = [_ChipCell((*p.index, k), p.key) for p in points for k in range(n_chips)]
    correct = label = None
    if predicted is not None:
        label = coords["label"][1]
        correct = np.where(predicted >= 0, (predicted == label).astype(np.int8), np.int8(-1))
    summary = _accuracy_summary(
        accuracy.reshape(*shape, *accuracy.shape[1:]),
        None if correct is None else correct.reshape(*shape, *correct.shape[1:]),
        label,
        chip_dims,
        cells,  # type: ignore[arg-type]
        models,
    )
    # Chips lie after the model: (axes..., chip, model, ...) -> (axes..., model, chip, ...).
    n = len(shape)

    variables: dict[str, Any] = {}
    for name, (_, values, *attrs) in summary.items():
        variables[name] = ((*dims, "model", "chip"), np.swapaxes(values, n, n + 1), *attrs)
    accuracy = np.swapaxes(accuracy.reshape(*shape, *accuracy.shape[1:]), n, n + 1)
    variables["accuracy"] = ((*dims, "model", "chip", "repeat", "fold"), accuracy)
    for name, values in metrics.items():
        variables[name] = (chip_dims, values.reshape(*shape, n_chips))
    if predicted is not None and correct is not None:
        for name, values in (("predicted", predicted), ("correct", correct)):
            values = np.swapaxes(values.reshape(*shape, *values.shape[1:]), n, n + 1)
            variables[name] = ((*dims, "model", "chip", "repeat", "recording"), values)
    targets = np.full(size, np.nan)
    targets[flat] = [p.scene.chips.yield_target for p in points]
    per_chip = variables["accuracy_mean"][1]  # (axes..., model, chip)
    stats = yield_statistics(per_chip, targets.reshape(*shape, 1))
    for name, values in stats.items():
        variables[name] = ((*dims, "model"), values)
    return variables, {"chip": ("chip", np.arange(n_chips))}
