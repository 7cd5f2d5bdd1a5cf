"""The entries of the two stored levels, ``spikes`` (:class:`~pipeline.run.entries.SpikeEntry`) and
``results`` (:class:`~pipeline.run.entries.ResultEntry`), with their codecs
(:mod:`pipeline.run.records` for the declarations).

Variables of the spike entry: ``true_times_s`` float64 (true_event) s, ``true_polarity`` int8
(true_event) +-1, ``true_start``/``true_count`` int64 (recording, taxel): train ``(r, t)`` is
``true_times_s[true_start[r, t] : true_start[r, t] + true_count[r, t]]``; the same four with
``real_`` on ``real_event`` unless attribute ``ideal`` is true (an ideal readout: REAL *is* TRUE,
stored once, and decoded so that ``real is true``); ``duration_s`` float64 (recording) s, shared
by TRUE and REAL; ``metrics`` float64 (metric) (:data:`~pipeline.run.records.METRICS_VARIABLE`);
and a scene's chips (:data:`pipeline.run.chips.CHIP_SPIKE_VARIABLES`).

Variables of the result entry: ``accuracy`` float64 (model, repeat, fold) with the strings
``model``; ``n_windows_used`` int64 () the number of rate-coding windows the point used (``auto``
resolved); where the writer kept them, the out-of-fold predictions: ``predicted`` int64 (model,
repeat, recording), ``test_fold`` int64 (repeat, recording), ``labels`` int64 (recording) and
the strings ``recording``; where the writer read decisions during the touch, those of
:data:`pipeline.run.decisions.DECISION_VARIABLES`; ``metrics`` as for spikes; and a point's chips
(:data:`pipeline.run.chips.CHIP_RESULT_VARIABLES`). Attributes ``dataset_name``,
``class_names`` and ``sampling_rate_hz`` where the writer stated them, and the seconds of
:mod:`pipeline.run.records`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.chain.chips import ChipTrains
from pipeline.chain.metrics import SpikeMetrics
from pipeline.chain.spikes import Encoded
from pipeline.recordings.recording_set import Recordings
from pipeline.run.chips import (
    CHIP_RESULT_VARIABLES,
    CHIP_SPIKE_VARIABLES,
    ChipResults,
    chip_result_values,
    chip_spike_values,
    read_chip_results,
    read_chip_trains,
)
from pipeline.run.decisions import DECISION_VARIABLES, Decisions, decision_values, read_decisions
from pipeline.run.records import (
    METRICS_VARIABLE,
    Attrs,
    Paid,
    Values,
    Variable,
    metric_values,
    paid_attr,
    read_metrics,
    read_paid,
    read_seconds,
    read_trains,
    seconds_attr,
    train_values,
    train_variables,
)

__all__ = [
    "RESULT_VARIABLES",
    "SPIKE_VARIABLES",
    "OutOfFold",
    "RecordingsInfo",
    "ResultEntry",
    "SpikeEntry",
    "decode_result_entry",
    "decode_spike_entry",
    "encode_result_entry",
    "encode_spike_entry",
]


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
    taxel_names : tuple[str, ...] or None
        The recorded taxels of a real array, in the declared order; None for one channel.
    taxel_positions_mm : tuple[tuple[float, float], ...] or None
        Each taxel's ``[x, y]`` (mm), where the dataset gives them.
    """

    dataset_name: str | None = None
    class_names: tuple[str, ...] | None = None
    sampling_rate_hz: float | None = None
    taxel_names: tuple[str, ...] | None = None
    taxel_positions_mm: tuple[tuple[float, float], ...] | None = None

    @classmethod
    def of(cls, recordings: Recordings) -> RecordingsInfo:
        """What a result says of ``recordings``."""
        positions = recordings.taxel_positions_mm
        return cls(
            recordings.name,
            recordings.class_names,
            recordings.fs_hz,
            recordings.taxel_names or None,
            None if positions is None else tuple((float(x), float(y)) for x, y in positions),
        )


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
    decisions : ~pipeline.run.decisions.Decisions or None
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


#: The variables of a spike entry (see the module docstring).
SPIKE_VARIABLES = (
    *train_variables("true"),
    *train_variables("real", optional=True),
    Variable("duration_s", ("recording",), "float64", "s", "taxel time axis length"),
    METRICS_VARIABLE,
    *CHIP_SPIKE_VARIABLES,
)
#: The variables of a result entry (see the module docstring).
RESULT_VARIABLES = (
    Variable("accuracy", ("model", "repeat", "fold"), "float64", "1", "fold accuracy"),
    Variable("model", ("model",), "str", "1", "classifier"),
    Variable(
        "n_windows_used",
        (),
        "int64",
        "1",
        "rate-coding windows the point used (coding.n_windows resolved)",
        optional=True,
    ),
    Variable(
        "predicted",
        ("model", "repeat", "recording"),
        "int64",
        "1",
        "out-of-fold predicted class",
        optional=True,
    ),
    Variable("test_fold", ("repeat", "recording"), "int64", "1", "testing fold", optional=True),
    Variable("labels", ("recording",), "int64", "1", "class index", optional=True),
    Variable("recording", ("recording",), "str", "1", "recording name", optional=True),
    *DECISION_VARIABLES,
    METRICS_VARIABLE,
    *CHIP_RESULT_VARIABLES,
)


# ---------------------------------------------------------------------------------------------
# Codecs


def encode_spike_entry(entry: SpikeEntry) -> tuple[Values, Attrs]:
    """A spike entry's arrays and attributes, checked for consistency."""
    encoded = entry.encoded
    ideal = encoded.real is encoded.true
    values = train_values("true", encoded.true)
    duration = np.asarray(encoded.true.duration_s)
    n_recordings, _ = values["true_count"].shape
    if duration.shape != (n_recordings,):
        raise ValueError(f"duration_s: shape {duration.shape}, expected ({n_recordings},)")
    if not ideal:
        values |= train_values("real", encoded.real)
        if values["real_count"].shape != values["true_count"].shape:
            raise ValueError("REAL and TRUE trains differ in (recording, taxel) shape")
        real_duration = np.asarray(encoded.real.duration_s, dtype=np.float64)
        if real_duration.tobytes() != np.asarray(duration, dtype=np.float64).tobytes():
            raise ValueError("REAL and TRUE trains differ in duration_s")
    values["duration_s"] = duration
    values["metrics"] = metric_values(entry.metrics)
    values |= chip_spike_values(entry.chips, duration)
    attrs = {"ideal": ideal, "seconds": seconds_attr(entry.seconds)}
    if entry.paid is not None:
        if entry.paid_for is None:
            raise ValueError("paid: the point it is charged to (paid_for) is missing")
        attrs |= {"paid_seconds": paid_attr(entry.paid), "paid_for": str(entry.paid_for)}
    return values, attrs


def decode_spike_entry(values: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> SpikeEntry:
    """A spike entry from its arrays and attributes (the inverse of :func:`encode_spike_entry`)."""
    duration = values["duration_s"]
    true = read_trains(values, "true", duration)
    ideal = attrs["ideal"]
    if not isinstance(ideal, bool):
        raise TypeError("attribute 'ideal' is not a bool")
    real = true if ideal else read_trains(values, "real", duration)
    paid_for = attrs.get("paid_for")
    if paid_for is not None and not isinstance(paid_for, str):
        raise TypeError("attribute 'paid_for' is not a str")
    return SpikeEntry(
        Encoded(true, real),
        read_metrics(values),
        read_seconds(attrs),
        read_paid(attrs),
        paid_for,
        read_chip_trains(values, duration),
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
        "metrics": metric_values(entry.metrics),
        **chip_result_values(entry.chips, models),
    }
    if entry.n_windows_used is not None:
        values["n_windows_used"] = np.asarray(entry.n_windows_used)
    values |= decision_values(entry.decisions, models)
    attrs = {"seconds": seconds_attr(entry.seconds), **_recordings_attrs(entry.recordings)}
    if entry.paid is not None:
        attrs["paid_seconds"] = paid_attr(entry.paid)
    return values, attrs


def decode_result_entry(values: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> ResultEntry:
    """A result entry from its arrays and attributes (inverse of :func:`encode_result_entry`)."""
    accuracy = values["accuracy"]
    models = values["model"].tolist()
    if len(models) != accuracy.shape[0]:
        raise ValueError("model coordinate does not match accuracy")
    n_windows = values.get("n_windows_used")
    return ResultEntry(
        {m: accuracy[i] for i, m in enumerate(models)},
        read_seconds(attrs),
        read_metrics(values),
        _read_recordings(attrs),
        _read_out_of_fold(values, models),
        None if n_windows is None else int(n_windows),
        read_paid(attrs),
        read_chip_results(values, models),
        read_decisions(values, models),
    )


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
    if info.taxel_names is not None:
        attrs["taxel_names"] = [str(name) for name in info.taxel_names]
    if info.taxel_positions_mm is not None:
        attrs["taxel_positions_mm"] = [[float(x), float(y)] for x, y in info.taxel_positions_mm]
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
    taxels, positions = attrs.get("taxel_names"), attrs.get("taxel_positions_mm")
    return RecordingsInfo(
        dataset_name=name,
        class_names=None if names is None else tuple(names),
        sampling_rate_hz=None if rate is None else float(rate),
        taxel_names=None if taxels is None else tuple(str(t) for t in taxels),
        taxel_positions_mm=None
        if positions is None
        else tuple((float(x), float(y)) for x, y in positions),
    )
