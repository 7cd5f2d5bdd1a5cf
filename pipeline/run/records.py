"""Stored records: what each stored level (:mod:`pipeline.run.stages`) keeps of one scene.

A level whose output the sweep store keeps declares a :class:`Record`: its variables (name,
entry-level dims, dtype, units, long name; a variable may be optional), its entry type and three
functions: ``make`` turns the level's output (and what the levels before it made) into its
entry, ``encode`` turns an entry into named arrays plus JSON attributes, ``decode`` turns them back.
The store (:mod:`storage`) writes and reads any declared record by its declaration alone: it casts
each array to the declared dtype, checks its dims, refuses undeclared or missing variables and
JSON attributes that are not finite, and knows no record by name.

This module holds the declaration types and the entries of the two stored levels, ``spikes``
(:class:`SpikeEntry`) and ``results`` (:class:`ResultEntry`), with their codecs.

Variables of the spike entry: ``true_times_s`` float64 (true_event) s, ``true_polarity`` int8
(true_event) +-1, ``true_start``/``true_count`` int64 (recording, taxel): train ``(r, t)`` is
``true_times_s[true_start[r, t] : true_start[r, t] + true_count[r, t]]``; the same four with
``real_`` on ``real_event`` unless attribute ``ideal`` is true (an ideal readout: REAL *is* TRUE,
stored once, and decoded so that ``real is true``); ``duration_s`` float64 (recording) s, shared
by TRUE and REAL; ``metrics`` float64 (metric), one value per
:class:`~pipeline.chain.metrics.SpikeMetrics` field in its order (they may be +-inf or NaN, which
JSON attributes cannot hold).

Variables of the result entry: ``accuracy`` float64 (model, repeat, fold) with the strings
``model``; ``n_windows_used`` int64 () the number of rate-coding windows the point used (``auto``
resolved); where the writer kept them, the out-of-fold predictions: ``predicted`` int64 (model,
repeat, recording), ``test_fold`` int64 (repeat, recording), ``labels`` int64 (recording) and
the strings ``recording``; where the writer read decisions during the touch
(:class:`Decisions`), ``decision_s`` float64 (decision) s, ``decision_predicted`` int16 (model,
repeat, decision, recording) (-1: no decision), ``decision_confidence`` float32 (same dims; NaN:
none) and ``decoder_operations`` float64 (model, decision, operation); and ``metrics`` as for
spikes. Attributes ``dataset_name``,
``class_names`` and ``sampling_rate_hz`` where the writer stated them.

Every entry's attributes hold ``seconds`` (step name -> wall seconds of the step's work for the
entry's point, as measured when each step ran, one-off work (imports, kernel loads) left out;
finite floats)
and, in entries written since they were kept apart, ``paid_seconds`` (charge, ``own`` or
``shared``, -> step name -> wall seconds): what the worker spent computing the entry, each second
charged to one point only (:class:`Charge`); a spike entry also holds ``paid_for``, the result key
of the point its paid seconds are charged to.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.chain.chips import ChipTrains
from pipeline.chain.metrics import SpikeMetrics
from pipeline.chain.spikes import TIME_RESOLUTION_S, Encoded, SpikeTrains, train_starts

__all__ = [
    "CHIP_RESULT_VARIABLES",
    "CHIP_SPIKE_VARIABLES",
    "DECISION_VARIABLES",
    "Charge",
    "ChipResults",
    "Decisions",
    "OutOfFold",
    "Record",
    "RecordingsInfo",
    "ResultEntry",
    "SpikeEntry",
    "StepSeconds",
    "Ticks",
    "Variable",
]

#: Arrays and JSON attributes of one entry, as :attr:`Record.encode` gives and
#: :attr:`Record.decode` takes them.
Values = dict[str, np.ndarray]
Attrs = dict[str, Any]


class Charge(enum.StrEnum):
    """Whom the seconds a worker paid were for (the ``charge`` dimension of a cube's ``seconds``).

    ``own``: work for the point itself (its spike train, frames, training). ``shared``: work
    that later points of the same worker reuse without paying it again: loading the recordings,
    fitting the front end (the steps :attr:`pipeline.run.stages.Level.shared` declares) and a
    worker's one-off work, importing numba, torch and scikit-learn and loading or compiling the
    numba kernels (step :data:`pipeline.run.stages.SETUP_STEP`, wherever it happens). Either is
    charged to the point whose computation paid it, and to no other: a point that found the
    work done pays nothing for it.
    """

    OWN = "own"
    SHARED = "shared"


# Paid wall seconds by charge, then step name.
Paid = dict[Charge, dict[str, float]]


@dataclass(frozen=True)
class StepSeconds:
    """The seconds a new entry accounts for, as :attr:`Record.make` gets them.

    Attributes
    ----------
    work : dict[str, float]
        Wall seconds of each step's work for the point, as measured when the step ran (one-off
        work, imports and kernel loads, left out): of its own level's steps and of the levels
        upstream that the entry accounts for.
    paid : dict[Charge, dict[str, float]]
        Wall seconds the worker spent computing the entry for the point, by charge and step:
        what the point's own computation ran (nothing for an output it found made).
    point : str
        The result key of the point the paid seconds are charged to.
    """

    work: dict[str, float]
    paid: Paid
    point: str


@dataclass(frozen=True)
class Ticks:
    """How the store keeps a variable of event times: as whole ticks of ``resolution_s``
    (the values must be such multiples), delta-coded within each train (the trains' lengths are
    the variable ``runs``, in order), with the +-1 variable ``sign`` folded into each delta's
    low bit (``2 * delta + (sign > 0)``) instead of stored apart."""

    resolution_s: float
    runs: str
    sign: str


@dataclass(frozen=True)
class Variable:
    """One stored variable of a record.

    Attributes
    ----------
    name : str
        Its name in the entry (and in the store).
    dims : tuple of str
        Entry-level dimension names (``()`` for a scalar).
    dtype : str
        A numpy dtype name (``"float64"``, ``"int8"``) or ``"str"`` for strings.
    units, long_name : str
        CF ``units`` ("1" for dimensionless numbers and labels) and a prose description.
    optional : bool
        Whether an entry may lack it.
    ticks : Ticks or None
        For event times: how the store keeps them (:class:`Ticks`); None: as ``dtype``.
    """

    name: str
    dims: tuple[str, ...]
    dtype: str
    units: str
    long_name: str
    optional: bool = False
    ticks: Ticks | None = None

    def attrs(self) -> dict[str, str]:
        """``units`` and ``long_name``."""
        return {"units": self.units, "long_name": self.long_name}


@dataclass(frozen=True, eq=False)
class Record:
    """What a stored level keeps of one scene: see the module docstring.

    Attributes
    ----------
    name : str
        The level's name: the kind of its entries in the store.
    entry_type : type
        The type of its entries; every entry has ``seconds`` (dict[str, float]).
    variables : tuple of Variable
        Every variable an entry may hold.
    make : callable
        ``make(output, seconds, made) -> entry``: the level's output as its entry, given the
        :class:`StepSeconds` the entry accounts for and ``made(level_name)``, the output (or
        entry) of an upstream level of the same scene.
    encode : callable
        ``encode(entry) -> (values, attrs)``: named arrays (the declared variables; optional
        ones may be left out) and JSON attributes; raises ValueError for inconsistent entries.
    decode : callable
        ``decode(values, attrs) -> entry``: the inverse, given arrays already checked against
        the declaration (strings as ``<U``); raises for inconsistent ones.
    """

    name: str
    entry_type: type
    variables: tuple[Variable, ...]
    make: Callable[[Any, StepSeconds, Callable[[str], Any]], Any]
    encode: Callable[[Any], tuple[Values, Attrs]]
    decode: Callable[[Mapping[str, np.ndarray], Mapping[str, Any]], Any]

    def variable(self, name: str) -> Variable:
        """The declared variable ``name``."""
        for variable in self.variables:
            if variable.name == name:
                return variable
        raise KeyError(f"record {self.name!r} declares no variable {name!r}")


# ---------------------------------------------------------------------------------------------
# Entries


@dataclass(frozen=True)
class RecordingsInfo:
    """What a point's result says of the recordings it was computed on; None where unknown.

    Attributes
    ----------
    dataset_name : str or None
        :attr:`pipeline.recordings.recording_set.Recordings.name`.
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
        ``n`` distinct recording names (:attr:`pipeline.recordings.recording_set.Recordings.names`).
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


@dataclass(frozen=True, eq=False)
class Decisions:
    """Every model's decisions read during the touch at one point, on one time grid.

    Attributes
    ----------
    decision_s : float64
        ``(D,)``: decision times (s of touch), increasing: the union of the models' own.
    predicted : dict[str, numpy.ndarray]
        Model name -> int64 ``(repeats, D, n)``: the class index each recording got from the
        model of its fold read at each time; -1 where the model gives no decision at that time.
    confidence : dict[str, numpy.ndarray]
        float32 ``(repeats, D, n)``: softmax probability of that class; NaN where no decision.
    operations : dict[str, numpy.ndarray]
        float64 ``(D, 3)``: mean operations per recording of a decision at each time (accumulates,
        multiply-accumulates, neuron updates: :data:`pipeline.chain.operation_kinds.OPERATIONS`);
        NaN where no decision.
    """

    decision_s: np.ndarray
    predicted: Mapping[str, np.ndarray]
    confidence: Mapping[str, np.ndarray]
    operations: Mapping[str, np.ndarray]

    @classmethod
    def of(
        cls,
        read: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]],
        operations: Mapping[str, np.ndarray],
    ) -> Decisions | None:
        """Put each model's own decisions, ``read[model] = (decision_s (D_m,), predicted
        (repeats, D_m, n), confidence (repeats, D_m, n))`` with ``operations[model]`` (D_m, 3),
        on the union of their times; None when no model read any."""
        if not read:
            return None
        times = np.unique(np.concatenate([np.asarray(t) for t, _, _ in read.values()]))
        predicted, confidence, counted = {}, {}, {}
        for model, (own, guess, probability) in read.items():
            at = np.searchsorted(times, own)
            guess = np.asarray(guess)
            predicted[model] = np.full((guess.shape[0], len(times), guess.shape[2]), -1, np.int64)
            predicted[model][:, at] = guess
            confidence[model] = np.full(predicted[model].shape, np.nan, np.float32)
            confidence[model][:, at] = probability
            counted[model] = np.full((len(times), 3), np.nan)
            counted[model][at] = operations[model]
        return cls(times, predicted, confidence, counted)


#: The variables a result entry holds its :class:`Decisions` in.
DECISION_VARIABLES = (
    Variable(
        "decision_s",
        ("decision",),
        "float64",
        "s",
        "seconds of touch at which a decision is read",
        optional=True,
    ),
    Variable(
        "decision_predicted",
        ("model", "repeat", "decision", "recording"),
        "int16",
        "1",
        "class decided at the decision time (-1: none)",
        optional=True,
    ),
    Variable(
        "decision_confidence",
        ("model", "repeat", "decision", "recording"),
        "float32",
        "1",
        "softmax probability of the decided class",
        optional=True,
    ),
    Variable(
        "decoder_operations",
        ("model", "decision", "operation"),
        "float64",
        "1",
        "mean accumulates, multiply-accumulates and neuron updates of a decision",
        optional=True,
    ),
)


@dataclass(frozen=True, eq=False)
class SpikeEntry:
    """Stored output of the ``spikes`` level.

    Attributes
    ----------
    encoded : Encoded
        TRUE and REAL trains; ``encoded.real is encoded.true`` for an ideal readout (kept so).
        Both share ``duration_s`` float64 (n_recordings,) s.
    metrics : SpikeMetrics
        Scene-level metrics; any field may be +-inf or NaN and round trips bit for bit.
    seconds : dict[str, float]
        Wall seconds of each step's work (finite), e.g. ``{"taxels": 1.0, "readout": 2.5}``.
    paid : dict[Charge, dict[str, float]] or None
        Wall seconds the worker spent computing the entry, by charge and step (finite); None in
        entries written before they were kept.
    paid_for : str or None
        The result key of the point ``paid`` is charged to (the point whose computation made
        the train); None with ``paid``.
    """

    encoded: Encoded
    metrics: SpikeMetrics
    seconds: dict[str, float]
    paid: Paid | None = None
    paid_for: str | None = None
    chips: ChipTrains | None = None


@dataclass(frozen=True, eq=False)
class ChipResults:
    """Every chip's results of a point that simulates chips (:mod:`pipeline.chain.deployment`).

    Attributes
    ----------
    fold_accuracy : dict[str, np.ndarray]
        Model name -> float64 (chip, repeats, folds) accuracy in [0, 1].
    predicted : dict[str, np.ndarray]
        Model name -> int64 (chip, repeats, n_recordings) out-of-fold predicted class.
    metrics : tuple of SpikeMetrics
        Each chip's spike metrics.
    """

    fold_accuracy: Mapping[str, np.ndarray]
    predicted: Mapping[str, np.ndarray]
    metrics: tuple[SpikeMetrics, ...]

    @property
    def n_chips(self) -> int:
        """Number of chips."""
        return len(self.metrics)


@dataclass(frozen=True, eq=False)
class ResultEntry:
    """Everything a result cube needs of one point: accuracy, spike metrics, step seconds.

    Attributes
    ----------
    fold_accuracy : dict[str, np.ndarray]
        Model name (e.g. ``"ffnn"``) -> float64 (repeats, folds) accuracy in [0, 1] (a 1-D
        ``(folds,)`` array is one repeat); every model has the same shape; insertion order is
        kept.
    seconds : dict[str, float]
        Wall seconds of every step of the point (finite), as measured when each was computed,
        e.g. ``{"load": 0.3, ..., "coding": 0.01, "train_ffnn": 1.2, "train_cnn": 5.0}``.
    metrics : SpikeMetrics
        The point's spike metrics (copied from its spike entry, so a cube reads results only).
    recordings : RecordingsInfo or None
        What the point was computed on (dataset name, class names, sampling rate), for the
        cube's attributes; None in entries written before results stated it.
    out_of_fold : OutOfFold or None
        Every recording's out-of-fold prediction per model and repeat (models as in
        ``fold_accuracy``), for paired comparisons; None in entries written before results kept
        them.
    n_windows_used : int or None
        The number of rate-coding windows the point used (``coding.n_windows = "auto"``
        resolved for its recordings); None in entries written before results stated it.
    paid : dict[Charge, dict[str, float]] or None
        Wall seconds a worker spent computing for this point, by charge and step (finite): the
        steps its own computation ran, plus the paid seconds of a spike entry charged to it
        (``paid_for``); a step whose output it found made is not there. None in entries
        written before they were kept.
    chips : ChipResults or None
        Every chip's accuracy, predictions and spike metrics, for a point that simulates chips
        (``fold_accuracy``, ``out_of_fold`` and ``metrics`` are then chip 0's); else None.
    decisions : Decisions or None
        Every model's decisions read during the touch (models as in ``fold_accuracy``, or
        some of them); None in entries written before they were kept.
    """

    fold_accuracy: dict[str, np.ndarray]
    seconds: dict[str, float]
    metrics: SpikeMetrics
    recordings: RecordingsInfo | None = None
    out_of_fold: OutOfFold | None = None
    n_windows_used: int | None = None
    paid: Paid | None = None
    chips: ChipResults | None = None
    decisions: Decisions | None = None


# ---------------------------------------------------------------------------------------------
# Codecs of the two stored entries

_METRICS = tuple(f.name for f in dataclasses.fields(SpikeMetrics))
METRICS_VARIABLE = Variable(
    "metrics", ("metric",), "float64", "1", "spike metrics in SpikeMetrics field order"
)


def train_variables(
    prefix: str, optional: bool = False, grid: tuple[str, str] = ("recording", "taxel")
) -> tuple[Variable, ...]:
    """The four variables of one set of ragged trains (``true`` or ``real``), trains on
    ``grid``; the times stored as ticks of :data:`~pipeline.chain.spikes.TIME_RESOLUTION_S`."""
    event = (f"{prefix}_event",)
    what = prefix.upper()
    ticks = Ticks(TIME_RESOLUTION_S, f"{prefix}_count", f"{prefix}_polarity")
    return (
        Variable(
            f"{prefix}_times_s", event, "float64", "s", f"{what} spike times", optional, ticks
        ),
        Variable(f"{prefix}_polarity", event, "int8", "1", f"{what} spike polarity", optional),
        Variable(f"{prefix}_start", grid, "int64", "1", f"first {what} event", optional),
        Variable(f"{prefix}_count", grid, "int64", "1", f"{what} spikes per train", optional),
    )


_CHIP_METRICS = Variable(
    "chips_metrics", ("chip", "metric"), "float64", "1", "each chip's spike metrics", True
)
#: The spike entry's variables of a scene that simulates chips (every chip's REAL trains, rows
#: chip-major ``(chip, recording)`` pairs as in :class:`~pipeline.chain.chips.ChipTrains`, the
#: reference a deployed classifier trains on, and each chip's metrics).
CHIP_SPIKE_VARIABLES = (
    *train_variables("chips", optional=True, grid=("chip_recording", "taxel")),
    *train_variables("reference", optional=True),
    _CHIP_METRICS,
)
#: The result entry's variables of a point that simulates chips (every chip's accuracy and
#: out-of-fold predictions, and each chip's metrics).
CHIP_RESULT_VARIABLES = (
    Variable(
        "chip_accuracy", ("model", "chip", "repeat", "fold"), "float64", "1",
        "each chip's fold accuracy", True,
    ),
    Variable(
        "chip_predicted", ("model", "chip", "repeat", "recording"), "int64", "1",
        "each chip's out-of-fold predicted class", True,
    ),
    _CHIP_METRICS,
)  # fmt: skip


def _chip_spike_values(chips: ChipTrains | None, duration: np.ndarray) -> Values:
    """The arrays of a spike entry's chips; none for a scene of one chip."""
    if chips is None:
        return {}
    values = _train_values("chips", chips.real)
    if chips.real.count.shape[0] != chips.n_chips * len(duration):
        raise ValueError("chips: rows are not chips times recordings")
    if chips.reference is not None:
        values |= _train_values("reference", chips.reference)
    values["chips_metrics"] = np.stack([_metric_values(m) for m in chips.metrics])
    return values


def _read_chip_trains(values: Mapping[str, np.ndarray], duration: np.ndarray) -> ChipTrains | None:
    if "chips_metrics" not in values:
        return None
    metrics = tuple(_read_metrics({"metrics": row}) for row in values["chips_metrics"])
    real = _read_trains(values, "chips", np.tile(duration, len(metrics)))
    reference = None
    if "reference_count" in values:
        reference = _read_trains(values, "reference", duration)
    return ChipTrains(real, len(metrics), metrics, reference)


def _chip_result_values(chips: ChipResults | None, models: list[str]) -> Values:
    """The arrays of a result entry's chips; none for a point of one chip."""
    if chips is None:
        return {}
    if list(chips.fold_accuracy) != models or list(chips.predicted) != models:
        raise ValueError(f"chips: models {list(chips.fold_accuracy)}, accuracy of {models}")
    return {
        "chip_accuracy": np.stack([np.asarray(v) for v in chips.fold_accuracy.values()]),
        "chip_predicted": np.stack([np.asarray(v) for v in chips.predicted.values()]),
        "chips_metrics": np.stack([_metric_values(m) for m in chips.metrics]),
    }


def _read_chip_results(values: Mapping[str, np.ndarray], models: list[str]) -> ChipResults | None:
    if "chip_accuracy" not in values:
        return None
    accuracy, predicted = values["chip_accuracy"], values["chip_predicted"]
    return ChipResults(
        {m: accuracy[i] for i, m in enumerate(models)},
        {m: predicted[i] for i, m in enumerate(models)},
        tuple(_read_metrics({"metrics": row}) for row in values["chips_metrics"]),
    )


def encode_spike_entry(entry: SpikeEntry) -> tuple[Values, Attrs]:
    """A spike entry's arrays and attributes, checked for consistency."""
    encoded = entry.encoded
    ideal = encoded.real is encoded.true
    values = _train_values("true", encoded.true)
    duration = np.asarray(encoded.true.duration_s)
    n_recordings, _ = values["true_count"].shape
    if duration.shape != (n_recordings,):
        raise ValueError(f"duration_s: shape {duration.shape}, expected ({n_recordings},)")
    if not ideal:
        values |= _train_values("real", encoded.real)
        if values["real_count"].shape != values["true_count"].shape:
            raise ValueError("REAL and TRUE trains differ in (recording, taxel) shape")
        real_duration = np.asarray(encoded.real.duration_s, dtype=np.float64)
        if real_duration.tobytes() != np.asarray(duration, dtype=np.float64).tobytes():
            raise ValueError("REAL and TRUE trains differ in duration_s")
    values["duration_s"] = duration
    values["metrics"] = _metric_values(entry.metrics)
    values |= _chip_spike_values(entry.chips, duration)
    attrs = {"ideal": ideal, "seconds": seconds_attr(entry.seconds)}
    if entry.paid is not None:
        if entry.paid_for is None:
            raise ValueError("paid: the point it is charged to (paid_for) is missing")
        attrs |= {"paid_seconds": paid_attr(entry.paid), "paid_for": str(entry.paid_for)}
    return values, attrs


def decode_spike_entry(values: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> SpikeEntry:
    duration = values["duration_s"]
    true = _read_trains(values, "true", duration)
    ideal = attrs["ideal"]
    if not isinstance(ideal, bool):
        raise TypeError("attribute 'ideal' is not a bool")
    real = true if ideal else _read_trains(values, "real", duration)
    paid_for = attrs.get("paid_for")
    if paid_for is not None and not isinstance(paid_for, str):
        raise TypeError("attribute 'paid_for' is not a str")
    return SpikeEntry(
        Encoded(true, real),
        _read_metrics(values),
        read_seconds(attrs),
        read_paid(attrs),
        paid_for,
        _read_chip_trains(values, duration),
    )


def encode_result_entry(entry: ResultEntry) -> tuple[Values, Attrs]:
    """A result entry's arrays and attributes, checked for consistency."""
    if not entry.fold_accuracy:
        raise ValueError("fold_accuracy: no model")
    models = [str(model) for model in entry.fold_accuracy]
    rows = [np.atleast_2d(np.asarray(values)) for values in entry.fold_accuracy.values()]
    if any(row.ndim != 2 or row.shape != rows[0].shape for row in rows):
        shapes = {m: r.shape for m, r in zip(models, rows, strict=True)}
        raise ValueError(
            f"fold_accuracy: every model needs the same (repeats, folds) shape: {shapes}"
        )
    values: Values = {
        "accuracy": np.stack(rows),
        "model": np.array(models, dtype=str),
        **_out_of_fold_values(entry.out_of_fold, models, rows[0].shape[0]),
        "metrics": _metric_values(entry.metrics),
        **_chip_result_values(entry.chips, models),
    }
    if entry.n_windows_used is not None:
        values["n_windows_used"] = np.asarray(entry.n_windows_used)
    values |= _decision_values(entry.decisions, models)
    attrs = {"seconds": seconds_attr(entry.seconds), **_recordings_attrs(entry.recordings)}
    if entry.paid is not None:
        attrs["paid_seconds"] = paid_attr(entry.paid)
    return values, attrs


def decode_result_entry(values: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> ResultEntry:
    accuracy = values["accuracy"]
    models = values["model"].tolist()
    if len(models) != accuracy.shape[0]:
        raise ValueError("model coordinate does not match accuracy")
    n_windows = values.get("n_windows_used")
    return ResultEntry(
        {m: accuracy[i] for i, m in enumerate(models)},
        read_seconds(attrs),
        _read_metrics(values),
        _read_recordings(attrs),
        _read_out_of_fold(values, models),
        None if n_windows is None else int(n_windows),
        read_paid(attrs),
        _read_chip_results(values, models),
        _read_decisions(values, models),
    )


def _decision_values(decisions: Decisions | None, models: list[str]) -> Values:
    """The arrays of a result's decisions, every model of the entry in its order (a model that
    read none: -1, NaN); none when it kept none."""
    if decisions is None:
        return {}
    times = np.asarray(decisions.decision_s, dtype=np.float64)
    known = [m for m in models if m in decisions.predicted]
    if not known or set(decisions.predicted) - set(models):
        raise ValueError(f"decisions: of {sorted(decisions.predicted)}, accuracy of {models}")
    shape = np.shape(decisions.predicted[known[0]])
    if len(shape) != 3 or shape[1] != len(times):
        raise ValueError(f"decisions: predicted {shape} is not (repeats, {len(times)}, n)")
    predicted = np.full((len(models), *shape), -1, dtype=np.int64)
    confidence = np.full((len(models), *shape), np.nan, dtype=np.float32)
    operations = np.full((len(models), len(times), 3), np.nan)
    for i, model in enumerate(models):
        if model in decisions.predicted:
            predicted[i] = decisions.predicted[model]
            confidence[i] = decisions.confidence[model]
            operations[i] = decisions.operations[model]
    return {
        "decision_s": times,
        "decision_predicted": predicted,
        "decision_confidence": confidence,
        "decoder_operations": operations,
    }


def _read_decisions(values: Mapping[str, np.ndarray], models: list[str]) -> Decisions | None:
    """The decisions of a result entry; None for an entry that kept none."""
    if "decision_s" not in values:
        return None
    predicted = values["decision_predicted"]
    if predicted.shape[0] != len(models):
        raise ValueError("model coordinate does not match decision_predicted")
    return Decisions(
        values["decision_s"],
        {m: predicted[i].astype(np.int64) for i, m in enumerate(models)},
        {m: values["decision_confidence"][i] for i, m in enumerate(models)},
        {m: values["decoder_operations"][i] for i, m in enumerate(models)},
    )


def _train_values(prefix: str, trains: SpikeTrains) -> Values:
    """Flat arrays of one set of ragged trains, checked for consistency."""
    times, polarity = np.asarray(trains.times_s), np.asarray(trains.polarity)
    count = np.asarray(trains.count)
    if count.ndim != 2:
        raise ValueError(f"{prefix} count: {count.ndim} dimensions, expected (recording, taxel)")
    if times.ndim != 1 or polarity.shape != times.shape:
        raise ValueError(f"{prefix} times_s and polarity must be 1-D of equal length")
    if (count < 0).any() or int(count.sum()) != times.size:
        raise ValueError(f"{prefix} count: must be >= 0 and sum to the {times.size} events")
    return {
        f"{prefix}_times_s": times,
        f"{prefix}_polarity": polarity,
        f"{prefix}_start": train_starts(count),
        f"{prefix}_count": count,
    }


def _read_trains(
    values: Mapping[str, np.ndarray], prefix: str, duration: np.ndarray
) -> SpikeTrains:
    times, polarity = values[f"{prefix}_times_s"], values[f"{prefix}_polarity"]
    count, start = values[f"{prefix}_count"], values[f"{prefix}_start"]
    flat = count.ravel()
    if (flat < 0).any() or int(flat.sum()) != times.size:
        raise ValueError(f"{prefix}_count does not match {prefix}_times_s")
    if not np.array_equal(start, train_starts(count)):
        raise ValueError(f"{prefix}_start is not the running sum of {prefix}_count")
    return SpikeTrains(times_s=times, polarity=polarity, count=count, duration_s=duration)


def seconds_attr(seconds: Mapping[str, float]) -> dict[str, float]:
    """Step seconds as an entry attribute; refused unless finite (JSON cannot hold others)."""
    out = {str(stage): float(value) for stage, value in seconds.items()}
    bad = [stage for stage, value in out.items() if not math.isfinite(value)]
    if bad:
        raise ValueError(f"seconds: not finite for {bad} (JSON attributes cannot hold them)")
    return out


def read_seconds(attrs: Mapping[str, Any]) -> dict[str, float]:
    seconds = attrs["seconds"]
    if not isinstance(seconds, dict):
        raise TypeError("attribute 'seconds' is not a mapping")
    return {str(stage): float(value) for stage, value in seconds.items()}


def paid_attr(paid: Paid) -> dict[str, dict[str, float]]:
    """Paid seconds as an entry attribute: every charge, each refused unless finite."""
    return {str(charge): seconds_attr(paid.get(charge, {})) for charge in Charge}


def read_paid(attrs: Mapping[str, Any]) -> Paid | None:
    """The paid seconds of an entry; None for one written before they were kept."""
    paid = attrs.get("paid_seconds")
    if paid is None:
        return None
    if not isinstance(paid, dict) or set(paid) - {str(c) for c in Charge}:
        raise TypeError("attribute 'paid_seconds' is not a mapping of charges")
    return {charge: read_seconds({"seconds": paid.get(str(charge), {})}) for charge in Charge}


def _metric_values(metrics: SpikeMetrics) -> np.ndarray:
    """The metrics as one float64 array (attributes are JSON, which cannot hold +-inf)."""
    return np.array([np.asarray(getattr(metrics, name)) for name in _METRICS])


def _read_metrics(values: Mapping[str, np.ndarray]) -> SpikeMetrics:
    metrics = values["metrics"]
    if metrics.shape != (len(_METRICS),):
        raise ValueError(f"metrics: {metrics.shape[0]} values, expected {len(_METRICS)}")
    return SpikeMetrics(*(float(value) for value in metrics))


def _out_of_fold_values(out_of_fold: OutOfFold | None, models: list[str], repeats: int) -> Values:
    """The arrays of a result's out-of-fold predictions; none when it kept none."""
    if out_of_fold is None:
        return {}
    if list(out_of_fold.predicted) != models:
        raise ValueError(
            f"out_of_fold: predictions of {list(out_of_fold.predicted)}, accuracy of {models}"
        )
    test_fold = np.asarray(out_of_fold.test_fold)
    if test_fold.shape[0] != repeats:
        raise ValueError(f"out_of_fold: {test_fold.shape[0]} repeats, accuracy has {repeats}")
    return {
        "predicted": np.stack([np.asarray(v) for v in out_of_fold.predicted.values()]),
        "test_fold": test_fold,
        "labels": np.asarray(out_of_fold.labels),
        "recording": np.array(out_of_fold.recording_names, dtype=str),
    }


def _read_out_of_fold(values: Mapping[str, np.ndarray], models: list[str]) -> OutOfFold | None:
    """The out-of-fold predictions of a result entry; None for an entry that kept none."""
    if "predicted" not in values:
        return None
    predicted = values["predicted"]
    if predicted.shape[0] != len(models):
        raise ValueError("model coordinate does not match predicted")
    return OutOfFold(
        recording_names=tuple(values["recording"].tolist()),
        labels=values["labels"],
        predicted={m: predicted[i] for i, m in enumerate(models)},
        test_fold=values["test_fold"],
    )


def _recordings_attrs(info: RecordingsInfo | None) -> Attrs:
    """A result's recordings facts as entry attributes; a fact not known is not written."""
    if info is None:
        return {}
    attrs: Attrs = {}
    if info.dataset_name is not None:
        attrs["dataset_name"] = str(info.dataset_name)
    if info.class_names is not None:
        names = list(info.class_names)
        if not all(isinstance(name, str) for name in names):
            raise ValueError("recordings.class_names: every name must be a str")
        attrs["class_names"] = names
    if info.sampling_rate_hz is not None:
        rate = float(info.sampling_rate_hz)
        if not (math.isfinite(rate) and rate > 0):
            raise ValueError(f"recordings.sampling_rate_hz: {rate!r} is not a rate > 0")
        attrs["sampling_rate_hz"] = rate
    return attrs


def _read_recordings(attrs: Mapping[str, Any]) -> RecordingsInfo | None:
    """The recordings facts of a result entry; None for an entry that states none (older)."""
    name, names, rate = (attrs.get(k) for k in ("dataset_name", "class_names", "sampling_rate_hz"))
    if name is None and names is None and rate is None:
        return None
    if name is not None and not isinstance(name, str):
        raise TypeError("attribute 'dataset_name' is not a str")
    if names is not None and (
        not isinstance(names, list) or not all(isinstance(n, str) for n in names)
    ):
        raise TypeError("attribute 'class_names' is not a list of str")
    if rate is not None and (isinstance(rate, bool) or not isinstance(rate, int | float)):
        raise TypeError("attribute 'sampling_rate_hz' is not a number")
    return RecordingsInfo(
        dataset_name=name,
        class_names=None if names is None else tuple(names),
        sampling_rate_hz=None if rate is None else float(rate),
    )
