"""Decisions during the touch, as a point's result keeps them (the run layer of the feature whose
cube variables are :mod:`pipeline.results.decision_cube`).

A model that reads its decision along the touch (after each window, or each step of the spiking
decoder) gives, per repeat and recording, the class and its probability at each decision time,
and what a decision at that time cost (:mod:`pipeline.chain.operations`). :class:`Decisions`
holds every model's on the union of their times; the result entry stores them in
:data:`DECISION_VARIABLES`: ``decision_s`` float64 (decision) s, ``decision_predicted`` int16
(model, repeat, decision, recording) (-1: no decision), ``decision_confidence`` float32 (same
dims; NaN: none) and ``decoder_operations`` float64 (model, decision, operation).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pipeline.run.records import Values, Variable

if TYPE_CHECKING:
    from pipeline.chain.training import CrossValidation

__all__ = ["DECISION_VARIABLES", "Decisions", "decision_values", "decisions_of", "read_decisions"]


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


def decisions_of(accuracy: Mapping[str, CrossValidation]) -> Decisions | None:
    """The decisions every model of a point's cross-validation (model name -> its result) read
    during the touch; None when none read any."""
    return Decisions.of(
        {
            model: (cv.decision_s, cv.decision_predicted, cv.decision_confidence)
            for model, cv in accuracy.items()
            if cv.decision_s is not None
        },
        {model: cv.operations for model, cv in accuracy.items() if cv.operations is not None},
    )


def decision_values(decisions: Decisions | None, models: list[str]) -> Values:
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


def read_decisions(values: Mapping[str, np.ndarray], models: list[str]) -> Decisions | None:
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
