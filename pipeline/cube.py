"""Result cubes: one labelled, self-describing xarray Dataset per sweep, from its points' results.

Pure: the cube is a function of the grid, the sweep and the results of its points (no store, no
recordings); :mod:`storage.store` persists it. Dimensions are the sweep's axes (a zipped sweep has
one dimension, named after its first axis), plus ``model``, ``repeat``, ``fold`` and
``recording`` for accuracy, ``stage`` for compute time and ``metric``, ``coefficient`` for
correlations.

Data variables

``accuracy``          (axes..., model, repeat, fold)  fraction of a fold's test recordings
                      classified correctly
``accuracy_mean``     (axes..., model)        fraction of (recording, repeat) pairs classified
                      correctly (the mean over folds for points without predictions)
``accuracy_low``,     (axes..., model)        95 % interval of ``accuracy_mean``: Wilson score
``accuracy_high``                             over recordings for one repeat, class-stratified
                      bootstrap over recordings for several (attribute ``interval`` says which)
``predicted``         (axes..., model, repeat, recording)  int16 out-of-fold predicted class
``correct``           (axes..., model, repeat, recording)  int8 1 where ``predicted`` is the
                      recording's ``label``, 0 where not
``test_fold``         (axes..., repeat, recording)  int16 fold that tested the recording
``ssnr_db``           (axes...)               pooled SSNR (``+inf``: REAL trains equal TRUE)
``ste_s2``            (axes...)               the paper's STE, mean over trains
``ste_sign_safe_s2``  (axes...)               STE with ``|N_real - N_true|``
``event_rate_hz``     (axes...)               array events per second
``data_rate_bps``     (axes...)               address-event bits per second
``equivalent_bits``   (axes...)               ``log2(full_scale_v / threshold_v)``
``seconds``           (axes..., stage)        wall seconds each stage took when it was computed

A sweep with ``correlate = true`` also holds ``correlation_r``, ``correlation_p`` (model,
metric, coefficient) and ``correlation_n`` (model, metric): Pearson and Spearman correlations of
SSNR and STE with ``accuracy_mean`` across the sweep's points (infinite metrics left out).
Accuracy of a model or fold a point did not train is NaN; so are the seconds of a stage a point
did not measure; ``predicted``, ``correct`` and ``test_fold`` are -1 where a point has no
prediction (a model, repeat or recording it did not run; no out-of-fold variables at all when no
point kept its predictions). The ``recording`` dimension is the union of the points' recordings
(coordinate: names; ``label`` along it: class index). Every variable but ``seconds`` is a
deterministic function of the grid and its seeds; ``seconds`` are measurements.

Coordinates

* One per swept axis, named by its dimension (``threshold_v``), attribute ``field`` its dotted
  scene field; the other axes of a zipped sweep lie along the first one's dimension.
* ``result_key`` (axes...): each point's result cache key (a point two sweeps share has one key).
* Every scene field by its dotted name (``array.rows``, ``readout.effects.amplifier_noise.sigma_v``,
  the base scene's fields and the sweep's fixed ``set`` ones alike), and ``readout.equivalent_bits``
  derived from threshold and full scale: a scalar where every point has the same value, otherwise
  along the dimensions it varies with (a swept field along its own). Lists and tables are
  canonical JSON strings (an ideal readout's ``readout.effects`` is ``"{}"``); a field left unset
  (its default applies, e.g. ``dataset.path`` of the built-in data) has none, and neither has
  ``name``.

Every variable and coordinate has CF ``units`` ("1" for dimensionless numbers and labels) and a
prose ``long_name``, declared once: on the scene's spec dataclasses (:mod:`pipeline.scene`), on
:class:`~pipeline.metrics.SpikeMetrics`, and here (:data:`CUBE_VARIABLES`) for the cube's own.

Attributes: ``grid``, ``sweep``, ``title``, ``mode``, ``seed``, ``training_seed`` (the base
scene's), ``package_version`` and the versions of Python and of the libraries that shape the
results as ``version_<name>`` strings (:data:`DEPENDENCY_VERSIONS`); ``correlation_notes`` where a
correlation could not be computed; and, where every point's result states the same, what the
recordings were: ``dataset_name``, ``sampling_rate_hz``, ``class_names`` and ``n_classes``.
"""

from __future__ import annotations

import dataclasses
import json
import platform
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from typing import Any, Protocol

import numpy as np
import xarray as xr

from pipeline.grid import Grid, GridPoint, Sweep, sweep_points
from pipeline.metrics import CORRELATION_METHODS, SpikeMetrics, correlate_with_accuracy
from pipeline.scene import EFFECT_TYPES, Effect, Model, Scene

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
    "seconds": {"units": "s", "long_name": "wall time of the stage, as measured when computed"},
    "correlation_r": {"units": "1", "long_name": "correlation of the metric with mean accuracy"},
    "correlation_p": {"units": "1", "long_name": "two-sided p-value of the correlation"},
    "correlation_n": {"units": "1", "long_name": "sweep points in the correlation"},
    "model": {"units": "1", "long_name": "classifier"},
    "fold": {"units": "1", "long_name": "cross-validation fold"},
    "stage": {"units": "1", "long_name": "pipeline stage"},
    "metric": {"units": "1", "long_name": "spike metric correlated with accuracy"},
    "coefficient": {"units": "1", "long_name": "correlation coefficient"},
    "result_key": {"units": "1", "long_name": "result cache key of the point"},
}
#: Coordinates derived from scene fields: dotted name -> (value of a scene, metric declaring it).
DERIVED: dict[str, tuple[Callable[[Scene], Any], str]] = {
    "readout.equivalent_bits": (lambda scene: scene.readout.equivalent_bits, "equivalent_bits"),
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


@dataclass(frozen=True)
class RecordingsInfo:
    """What a point's result says of the recordings it was computed on; None where unknown.

    Attributes
    ----------
    dataset_name : str or None
        :attr:`pipeline.recordings.Recordings.name`.
    class_names : tuple[str, ...] or None
        Class names, in label order.
    sampling_rate_hz : float or None
        Sampling rate of the recordings (Hz).
    """

    dataset_name: str | None = None
    class_names: tuple[str, ...] | None = None
    sampling_rate_hz: float | None = None


@dataclass(frozen=True, eq=False)
class OutOfFold:
    """Every recording's out-of-fold prediction of one point, per model and repeat.

    Attributes
    ----------
    recording_names : tuple[str, ...]
        ``n`` distinct recording names (:attr:`pipeline.recordings.Recordings.names`).
    labels : int64 (n,)
        Class index of each recording.
    predicted : dict[str, int64 (repeats, n)]
        Model name -> the class index each recording got from the fold that tested it.
    test_fold : int64 (repeats, n)
        The fold that tested each recording, per repeat (the same for every model).
    """

    recording_names: tuple[str, ...]
    labels: np.ndarray
    predicted: Mapping[str, np.ndarray]
    test_fold: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.recording_names)
        labels = np.asarray(self.labels)
        test_fold = np.asarray(self.test_fold)
        problems = []
        if len(set(self.recording_names)) != n:
            problems.append("recording names repeat")
        if labels.shape != (n,):
            problems.append(f"labels {labels.shape} do not match {n} recordings")
        if test_fold.ndim != 2 or test_fold.shape[1] != n:
            problems.append(f"test_fold {test_fold.shape} is not (repeats, {n})")
        for model, values in self.predicted.items():
            if np.shape(values) != test_fold.shape:
                problems.append(f"predicted[{model!r}] {np.shape(values)} != {test_fold.shape}")
        if problems:
            raise ValueError("out-of-fold predictions: " + "; ".join(problems))


class PointResult(Protocol):
    """What the cube needs of one point (:class:`storage.ResultEntry` is one)."""

    @property
    def fold_accuracy(self) -> Mapping[str, np.ndarray]: ...

    @property
    def seconds(self) -> Mapping[str, float]: ...

    @property
    def metrics(self) -> SpikeMetrics: ...

    @property
    def recordings(self) -> RecordingsInfo | None: ...

    @property
    def out_of_fold(self) -> OutOfFold | None: ...


def build_cube(
    grid: Grid,
    sweep: Sweep,
    records: Mapping[str, PointResult],
    *,
    spike_stages: Sequence[str],
) -> xr.Dataset:
    """Assemble the cube of one sweep from its points' results.

    Parameters
    ----------
    grid, sweep
        The grid and one of its sweeps.
    records
        Result of every point of the sweep, by result key.
    spike_stages
        Names of the stages before coding, in order; the ``stage`` coordinate is these, then
        ``coding`` and ``train_<model>`` per model.

    Raises
    ------
    KeyError
        A point of the sweep has no record.
    """
    points = sweep_points(grid.base, sweep)
    models = [m.value for m in Model if any(m in p.scene.training.models for p in points)]
    n_folds = max(p.scene.training.folds for p in points)
    n_repeats = max(p.scene.training.repeats for p in points)
    stages = [*spike_stages, "coding", *(f"train_{m}" for m in models)]
    shape = sweep.shape
    accuracy = np.full((*shape, len(models), n_repeats, n_folds), np.nan)
    metrics = {name: np.full(shape, np.nan) for name in METRICS}
    seconds = np.full((*shape, len(stages)), np.nan)
    for point in points:
        record = records[point.key]
        for m, model in enumerate(models):
            folds = record.fold_accuracy.get(model)
            if folds is not None:
                folds = np.atleast_2d(folds)
                accuracy[(*point.index, m, slice(0, folds.shape[0]), slice(0, folds.shape[1]))] = (
                    folds
                )
        for name in METRICS:
            metrics[name][point.index] = getattr(record.metrics, name)
        for s, stage in enumerate(stages):
            seconds[(*point.index, s)] = record.seconds.get(stage, np.nan)
    dims = sweep.dims
    data_vars: dict[str, Any] = {
        "accuracy": ((*dims, "model", "repeat", "fold"), accuracy),
        **{name: (dims, values) for name, values in metrics.items()},
        "seconds": ((*dims, "stage"), seconds),
    }
    coords: dict[str, Any] = {
        "model": ("model", models),
        "repeat": ("repeat", np.arange(n_repeats)),
        "fold": ("fold", np.arange(n_folds)),
        "stage": ("stage", stages),
    }
    out_of_fold = _out_of_fold_variables(points, records, models, n_repeats, dims, shape)
    correct = label = None
    if out_of_fold is not None:
        predictions, recording_coords = out_of_fold
        data_vars.update(predictions)
        coords.update(recording_coords)
        correct, label = predictions["correct"][1], recording_coords["label"][1]
    data_vars.update(_accuracy_summary(accuracy, correct, label, dims, points))
    for position, axis in enumerate(sweep.axes):
        dim = dims[0] if sweep.mode == "zip" else dims[position]
        coords[axis.dim] = (dim, _coordinate(axis.values), {"field": axis.field})
    cube = xr.Dataset(data_vars, coords=coords)
    if sweep.correlate:
        correlations = _correlations(cube, models)
        cube = cube.merge(correlations)
        cube.attrs.update(correlations.attrs)
    keys = np.empty(shape, dtype=object)
    for point in points:
        keys[point.index] = point.key
    # A top-level field's name has no dot: a swept ``seed`` is already its dimension's coordinate,
    # and a dimension named after another ``*.seed`` leaves the scene seed to the attributes.
    fields = {
        name: variable
        for name, variable in _scene_coordinates(points, sweep).items()
        if name not in cube.variables and name not in cube.dims
    }
    cube = cube.assign_coords(result_key=(dims, keys.astype(str)), **fields)
    for name, variable in cube.variables.items():
        variable.attrs.update(describe(str(name), variable.attrs.get("field")))
    cube.attrs.update(_provenance(grid, sweep))
    cube.attrs.update(_recordings_attrs([records[p.key].recordings for p in points]))
    return cube


def describe(name: str, field: str | None = None) -> dict[str, str]:
    """``units`` and ``long_name`` of a cube variable or coordinate, from their one declaration.

    Parameters
    ----------
    name
        A name of :data:`CUBE_VARIABLES`, a spike metric, a dotted scene field or one of
        :data:`DERIVED`.
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
    if name in DERIVED:
        return metric_attrs(DERIVED[name][1])
    return field_attrs(name)


def metric_attrs(name: str) -> dict[str, str]:
    """``units`` and ``long_name`` of a :class:`~pipeline.metrics.SpikeMetrics` field."""
    found = {f.name: f for f in dataclasses.fields(SpikeMetrics)}
    return _declared(found[name], name)


def field_attrs(field: str) -> dict[str, str]:
    """``units`` and ``long_name`` of a dotted scene field, as its dataclass field declares them.

    A whole effect table (``readout.effects.saturation``) is a dimensionless JSON label.

    Raises
    ------
    KeyError
        ``field`` names no scene field.
    """
    parts = field.split(".")
    owner: Any = Scene
    i = 0
    while True:
        found = {f.name: f for f in dataclasses.fields(owner)}
        if parts[i] not in found or parts[i] == "name":
            raise KeyError(f"{field!r} is not a scene field")
        if i == len(parts) - 1:
            return _declared(found[parts[i]], field)
        if parts[i] == "effects":
            try:
                owner = EFFECT_TYPES[Effect(parts[i + 1])]
            except ValueError:
                raise KeyError(f"{field!r} names no effect") from None
            if i + 1 == len(parts) - 1:
                return {"units": "1", "long_name": f"parameters of the {parts[i + 1]} effect"}
            i += 2
        else:
            owner = type(getattr(owner(), parts[i]))
            i += 1


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
    points: list[GridPoint],
    records: Mapping[str, PointResult],
    models: list[str],
    n_repeats: int,
    dims: tuple[str, ...],
    shape: tuple[int, ...],
) -> tuple[dict[str, Any], dict[str, Any]] | None:
    """``predicted``, ``correct``, ``test_fold`` and the ``recording`` coordinates of a sweep.

    The ``recording`` dimension is the union of the points' recordings, in the order first met
    (points of a ``dataset.recordings_per_class`` sweep hold different numbers of recordings);
    None when no point kept its predictions.
    """
    kept = [(p, records[p.key].out_of_fold) for p in points]
    kept = [(p, oof) for p, oof in kept if oof is not None]
    if not kept:
        return None
    position: dict[str, int] = {}
    labels: list[int] = []
    for _, oof in kept:
        for name, label in zip(oof.recording_names, np.asarray(oof.labels), strict=True):
            if name not in position:
                position[name] = len(position)
                labels.append(int(label))
    n = len(position)
    predicted = np.full((*shape, len(models), n_repeats, n), -1, dtype=np.int16)
    test_fold = np.full((*shape, n_repeats, n), -1, dtype=np.int16)
    for point, oof in kept:
        columns = np.array([position[name] for name in oof.recording_names], dtype=np.int64)
        repeats = np.asarray(oof.test_fold).shape[0]
        test_fold[(*point.index, slice(0, repeats))][:, columns] = oof.test_fold
        for m, model in enumerate(models):
            if model in oof.predicted:
                predicted[(*point.index, m, slice(0, repeats))][:, columns] = oof.predicted[model]
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
    points: list[GridPoint],
) -> dict[str, Any]:
    """``accuracy_mean``, ``accuracy_low``, ``accuracy_high`` (axes..., model) of every point.

    With out-of-fold predictions: the fraction of (recording, repeat) pairs classified correctly
    and its 95 % interval (:func:`pipeline.stats.accuracy_interval`: Wilson score for one repeat,
    a class-stratified bootstrap over recordings for several, its generator seeded from the
    point's training seed and index). Without: the mean over folds, and no interval (NaN).
    """
    from pipeline.stats import accuracy_interval

    shape = accuracy.shape[:-2]
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an untrained model: all-NaN folds
        mean = np.nanmean(accuracy.reshape(*shape, -1), axis=-1)
    low, high = np.full(shape, np.nan), np.full(shape, np.nan)
    methods = set()
    if correct is not None and label is not None:
        for point in points:
            for m in range(shape[-1]):
                # (repeat, recording) of this point and model: -1 where it has no prediction
                # (a recording it did not hold, a repeat or model it did not run).
                cell = correct[(*point.index, m)]
                cell = cell[(cell >= 0).any(axis=1)]
                held = (cell >= 0).all(axis=0)
                if cell.size == 0 or not held.any():
                    continue
                interval = accuracy_interval(
                    cell[:, held] == 1,
                    label[held],
                    rng=np.random.default_rng([point.scene.training.seed, *point.index, m]),
                )
                mean[(*point.index, m)] = interval.estimate
                low[(*point.index, m)] = interval.low
                high[(*point.index, m)] = interval.high
                methods.add(interval.method)
    attrs = {"interval": "; ".join(sorted(methods)) or "none", "confidence": 0.95}
    return {
        "accuracy_mean": ((*dims, "model"), mean),
        "accuracy_low": ((*dims, "model"), low, attrs),
        "accuracy_high": ((*dims, "model"), high, attrs),
    }


def _coordinate(values: Sequence[Any]) -> np.ndarray:
    """Numbers stay numbers; tables (e.g. a whole effects mapping) become canonical JSON."""
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        return np.asarray(values)
    if all(isinstance(v, str | bool) for v in values):
        return np.asarray(values)
    return np.asarray([json.dumps(v, sort_keys=True) for v in values])


def _scene_coordinates(points: list[GridPoint], sweep: Sweep) -> dict[str, xr.Variable]:
    """Every scene field (and derived one) that every point has, along the dims it varies with."""
    flat = []
    for point in points:
        fields = _flatten({k: v for k, v in point.scene.to_dict().items() if k != "name"})
        fields |= {name: value(point.scene) for name, (value, _) in DERIVED.items()}
        flat.append(fields)
    coords = {}
    for field in flat[0]:
        if not all(field in fields for fields in flat):
            continue  # some points do not have it: a swept table's coordinate describes them
        values = np.empty(sweep.shape, dtype=object)
        for point, fields in zip(points, flat, strict=True):
            values[point.index] = fields[field]
        coords[field] = _along_varied(values, sweep.dims)
    return coords


def _flatten(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """``{"array": {"rows": 3}}`` as ``{"array.rows": 3}``; an empty table is a leaf."""
    flat: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, Mapping) and value:
            flat |= _flatten(value, f"{prefix}{key}.")
        else:
            flat[f"{prefix}{key}"] = value
    return flat


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
