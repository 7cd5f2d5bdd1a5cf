"""Deploying a classifier onto the chips of a design: accuracy per chip, fold and recording.

``chips.deployment`` (:class:`pipeline.design.scene.Deployment`) says how:

``per_chip``
    every chip is calibrated: the cross-validation of :func:`pipeline.chain.training.cross_validate`
    runs on each chip's own frames (a scene of one chip is exactly today's procedure).
``shared`` and ``robust``
    one classifier per fold, trained once on the training recordings as the *reference*
    encodes them (the nominal chip, or one training chip per recording:
    :mod:`pipeline.chain.chips`), and tested on the fold's held-out recordings as each of the
    ``N`` chips encodes them. Training runs once per fold whatever ``N`` is; the test frames of
    every chip of a fold go through the trained net as one batch.

Everything else is the cross-validation of :mod:`pipeline.chain.training`, unchanged: the same
stratified folds (seeded by ``training.seed`` and the repeat, :func:`repeat_seed`) for every chip
and every design, inputs standardized with the statistics of the fold's training frames (the
reference's, for a deployed classifier: a chip is standardized as the classifier was trained),
the same fold-batched training (:func:`pipeline.chain.training.fit_folds`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from pipeline.chain.training import (
    CrossValidation,
    cross_validate,
    fit_folds,
    predict_folds,
    repeat_seed,
    standardize,
    stratified_folds,
)
from pipeline.design.scene import Model, TrainingSpec

__all__ = ["validate_chips"]


def validate_chips(
    chip_frames: np.ndarray,
    reference_frames: np.ndarray | None,
    labels: np.ndarray,
    model: Model,
    training: TrainingSpec,
    *,
    class_names: Sequence[str] | None = None,
) -> CrossValidation:
    """Cross-validated accuracy of one classifier on every chip of a design.

    Parameters
    ----------
    chip_frames
        ``(n_chips, n_recordings, C, H, W)`` spike counts of every chip.
    reference_frames
        ``(n_recordings, C, H, W)`` counts a deployed (``shared``, ``robust``) classifier trains
        on; None: ``per_chip``, each chip trained on its own frames.
    labels
        int ``(n_recordings,)`` class of each recording.
    model, training, class_names
        As for :func:`pipeline.chain.training.cross_validate`.

    Returns
    -------
    CrossValidation
        Chip 0's ``fold_accuracy``, ``predicted`` and ``test_fold``, and every chip's in
        ``chip_accuracy`` float64 ``(n_chips, repeats, folds)`` and ``chip_predicted`` int64
        ``(n_chips, repeats, n_recordings)``.
    """
    start = time.perf_counter()
    chip_frames = np.asarray(chip_frames)
    if chip_frames.ndim != 5:
        raise ValueError(f"chip_frames must be (chips, n, C, H, W), got {chip_frames.shape}")
    if reference_frames is None:
        per_chip = [
            cross_validate(frames, labels, model, training, class_names=class_names)
            for frames in chip_frames
        ]
        first = per_chip[0]
        return CrossValidation(
            first.model,
            first.fold_accuracy,
            time.perf_counter() - start,
            first.train_loss,
            first.predicted,
            first.test_fold,
            chip_accuracy=np.stack([cv.fold_accuracy for cv in per_chip]),
            chip_predicted=np.stack([cv.predicted for cv in per_chip]),
        )
    return _deployed(chip_frames, np.asarray(reference_frames), labels, model, training, start)


def _deployed(
    chip_frames: np.ndarray,
    reference: np.ndarray,
    labels: np.ndarray,
    model: Model,
    training: TrainingSpec,
    start: float,
) -> CrossValidation:
    """One classifier per fold trained on ``reference``, tested on every chip's held-out frames."""
    if reference.shape != chip_frames.shape[1:]:
        raise ValueError(f"reference {reference.shape} and chips {chip_frames.shape} disagree")
    if not (np.all(np.isfinite(reference)) and np.all(np.isfinite(chip_frames))):
        raise ValueError("frames hold non-finite values")
    model = Model(model)
    classes, y = np.unique(np.asarray(labels), return_inverse=True)
    n_chips, n = chip_frames.shape[:2]
    sample = chip_frames.shape[2:]
    accuracy = np.zeros((n_chips, training.repeats, training.folds))
    predicted = np.zeros((n_chips, training.repeats, n), dtype=np.int64)
    test_fold = np.zeros((training.repeats, n), dtype=np.int64)
    losses = []
    for repeat in range(training.repeats):
        seed = repeat_seed(training.seed, repeat)
        splits = stratified_folds(y, training.folds, seed)
        # Every chip's held-out frames of a fold, standardized as its training frames were.
        train_x, test_x = zip(
            *(
                standardize(reference[tr], chip_frames[:, te].reshape(-1, *sample))
                for tr, te in splits
            ),
            strict=True,
        )
        folds = list(range(len(splits)))
        net, loss = fit_folds(
            train_x, [y[tr] for tr, _ in splits], folds, model, len(classes), training, seed
        )
        losses.append(loss)
        guesses = predict_folds(net, test_x)
        for f, (_, te) in enumerate(splits):
            guess = guesses[f].reshape(n_chips, len(te))
            accuracy[:, repeat, f] = (guess == y[te]).mean(axis=1)
            predicted[:, repeat, te] = classes[guess]
            test_fold[repeat, te] = f
    return CrossValidation(
        model,
        accuracy[0],
        time.perf_counter() - start,
        np.stack(losses),
        predicted[0],
        test_fold,
        chip_accuracy=accuracy,
        chip_predicted=predicted,
    )
