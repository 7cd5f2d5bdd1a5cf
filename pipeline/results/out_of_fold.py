"""The cube's out-of-fold predictions: every recording's predicted class per model and repeat.

From the points' :class:`~pipeline.run.entries.OutOfFold` predictions,
:func:`out_of_fold_variables` builds, on the ``recording`` dimension (the union of the points'
recordings, in the order first met; coordinate: names, ``label`` along it: class index):

``predicted`` (axes..., model, repeat, recording) int16
    out-of-fold predicted class; -1 where the point has no prediction (a model, repeat or
    recording it did not run)
``correct`` (axes..., model, repeat, recording) int8
    1 where ``predicted`` is the recording's ``label``, 0 where not, -1 where no prediction
``test_fold`` (axes..., repeat, recording) int16
    the fold that tested the recording; -1 where none
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pipeline.results.variables import (
    CORRECT,
    LABEL,
    MODEL_DIM,
    PREDICTED,
    RECORDING_DIM,
    REPEAT_DIM,
    TEST_FOLD,
)
from pipeline.run.entries import OutOfFold

__all__ = ["out_of_fold_variables"]


def out_of_fold_variables(
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
    along = (*dims, MODEL_DIM, REPEAT_DIM, RECORDING_DIM)
    variables = {
        PREDICTED: (along, predicted),
        CORRECT: (along, correct),
        TEST_FOLD: ((*dims, REPEAT_DIM, RECORDING_DIM), test_fold),
    }
    coordinates = {
        RECORDING_DIM: (RECORDING_DIM, np.asarray(list(position), dtype=str)),
        LABEL: (RECORDING_DIM, label),
    }
    return variables, coordinates
