"""The cube's decisions during the touch: accuracy and cost against decision time.

From the points' :class:`~pipeline.run.decisions.Decisions` (and their out-of-fold recordings),
:func:`decision_variables` builds, on the ``decision_s`` dimension (the union of every point's
decision times, s of touch) and the cube's ``model``, ``repeat`` and ``recording`` dimensions:

``decision_correct`` (axes..., model, decision_s, repeat, recording) int8
    1 where the model's decision read at that time is the recording's class, 0 where not, -1
    where the model gives no decision at that time (the FFNN and CNN between window
    boundaries) or the point has none.
``decision_confidence`` (same dims) float32
    softmax probability of the decided class; NaN where none.
``decoder_acs``, ``decoder_macs``, ``decoder_neuron_updates`` (axes..., model, decision_s)
    float64: mean over the test recordings of the operations a decision read at that time has
    cost since the touch began (:mod:`pipeline.chain.operations`); NaN where none.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pipeline.chain.operation_kinds import OPERATIONS
from pipeline.results.point import PointResult
from pipeline.results.variables import MODEL_DIM, RECORDING_DIM, REPEAT_DIM

__all__ = [
    "DECISION_CONFIDENCE",
    "DECISION_CORRECT",
    "DECISION_CUBE_VARIABLES",
    "DECISION_DIM",
    "DECODER_VARIABLES",
    "decision_variables",
]

#: The dimension of decision times (s of touch).
DECISION_DIM = "decision_s"
DECISION_CORRECT = "decision_correct"
DECISION_CONFIDENCE = "decision_confidence"
#: The cube variable of each kind of operation, in
#: :data:`~pipeline.chain.operation_kinds.OPERATIONS` order.
DECODER_VARIABLES = tuple(f"decoder_{kind}" for kind in OPERATIONS)
#: ``units`` and ``long_name`` of the decision dimension and variables.
DECISION_CUBE_VARIABLES: dict[str, dict[str, str]] = {
    DECISION_DIM: {"units": "s", "long_name": "seconds of touch at which a decision is read"},
    DECISION_CORRECT: {
        "units": "1",
        "long_name": "decision read at that time correct (1, 0; -1: no decision)",
    },
    DECISION_CONFIDENCE: {
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


def decision_variables(
    results: Sequence[PointResult],
    flat: np.ndarray,
    models: list[str],
    n_repeats: int,
    dims: tuple[str, ...],
    shape: tuple[int, ...],
    recordings: np.ndarray | None,
) -> tuple[dict[str, Any], dict[str, Any]] | None:
    """The decision variables and the ``decision_s`` coordinate of a sweep's cube.

    ``results`` are the points' results (their ``decisions`` and ``out_of_fold``), ``flat``
    their positions in the flattened sweep dimensions, ``recordings`` the cube's ``recording``
    coordinate (names). None when no point kept decisions.
    """
    having = [
        i
        for i, result in enumerate(results)
        if result.decisions is not None and result.out_of_fold is not None
    ]
    if not having or recordings is None:
        return None
    times = np.unique(np.concatenate([results[i].decisions.decision_s for i in having]))
    column = {str(name): k for k, name in enumerate(recordings.tolist())}
    size = int(np.prod(shape))
    n_times, n_recordings = len(times), len(column)
    correct = np.full((size, len(models), n_times, n_repeats, n_recordings), -1, dtype=np.int8)
    confidence = np.full(correct.shape, np.nan, dtype=np.float32)
    operations = np.full((size, len(models), n_times, len(OPERATIONS)), np.nan)
    for i in having:
        decisions, oof = results[i].decisions, results[i].out_of_fold
        at = np.searchsorted(times, decisions.decision_s)
        columns = np.array([column[name] for name in oof.recording_names], dtype=np.int64)
        labels = np.asarray(oof.labels)
        row = flat[i]
        for m, model in enumerate(models):
            if model not in decisions.predicted:
                continue
            guess = np.asarray(decisions.predicted[model])  # (repeats, D, n)
            repeats = guess.shape[0]
            mark = np.where(guess >= 0, (guess == labels).astype(np.int8), np.int8(-1))
            index = (row, m, at[:, None, None], np.arange(repeats)[None, :, None], columns)
            correct[index] = mark.transpose(1, 0, 2)
            confidence[index] = np.asarray(decisions.confidence[model]).transpose(1, 0, 2)
            operations[row, m, at] = decisions.operations[model]
    along = (*dims, MODEL_DIM, DECISION_DIM, REPEAT_DIM, RECORDING_DIM)
    variables: dict[str, Any] = {
        DECISION_CORRECT: (along, correct.reshape(*shape, *correct.shape[1:])),
        DECISION_CONFIDENCE: (along, confidence.reshape(*shape, *confidence.shape[1:])),
    }
    for k, name in enumerate(DECODER_VARIABLES):
        variables[name] = (
            (*dims, MODEL_DIM, DECISION_DIM),
            operations[..., k].reshape(*shape, len(models), n_times),
        )
    return variables, {DECISION_DIM: (DECISION_DIM, times)}
