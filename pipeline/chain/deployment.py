"""Deploying a classifier onto the chips of a design: accuracy per chip, fold and recording.

``chips.deployment`` (:class:`pipeline.design.scene.Deployment`) says how:

``per_chip``
    every chip is calibrated: the cross-validation of :func:`pipeline.chain.training.cross_validate`
    runs on each chip's own frames (a scene of one chip is exactly today's procedure).
``shared`` and ``robust``
    one classifier per fold, trained once on the training recordings as the *reference*
    encodes them (the nominal chip, or one training chip per recording:
    :mod:`pipeline.chain.chips`), and tested on the fold's held-out recordings as each of the
    ``N`` chips encodes them (``cross_validate``'s ``tested``). Training runs once per fold
    whatever ``N`` is; the test frames of every chip of a fold go through the trained net as
    one batch.

Either way it is the one cross-validation of :mod:`pipeline.chain.training`, for every model
(:mod:`pipeline.chain.decoders`): the same stratified folds (seeded by ``training.seed`` and the
repeat) for every chip and every design, inputs prepared with the statistics of the fold's
training frames (the reference's, for a deployed classifier: a chip is standardized as the
classifier was trained), the same fold-batched training, and decisions along the touch read,
when asked, on chip 0.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import numpy as np

from pipeline.chain.decoders import DecoderInput
from pipeline.chain.training import CrossValidation, cross_validate
from pipeline.design.scene import Model, TrainingSpec

__all__ = ["validate_chips", "validate_input"]


def validate_chips(
    chip_frames: np.ndarray,
    reference_frames: np.ndarray | None,
    labels: np.ndarray,
    model: Model,
    training: TrainingSpec,
    *,
    class_names: Sequence[str] | None = None,
    frame_s: float | None = None,
) -> CrossValidation:
    """Cross-validated accuracy of one classifier on every chip of a design.

    Parameters
    ----------
    chip_frames
        ``(n_chips, n_recordings, C, H, W)`` spike counts of every chip, the frames the
        model's decoder reads.
    reference_frames
        ``(n_recordings, C, H, W)`` counts a deployed (``shared``, ``robust``) classifier trains
        on; None: ``per_chip``, each chip trained on its own frames.
    labels
        int ``(n_recordings,)`` class of each recording.
    model, training, class_names
        As for :func:`pipeline.chain.training.cross_validate`.
    frame_s
        Seconds of touch per frame column: when given, chip 0's decisions are read along the
        touch (as :func:`~pipeline.chain.training.cross_validate` reads them).

    Returns
    -------
    CrossValidation
        Chip 0's ``fold_accuracy``, ``predicted``, ``test_fold`` (and decisions), and every
        chip's in ``chip_accuracy`` float64 ``(n_chips, repeats, folds)`` and ``chip_predicted``
        int64 ``(n_chips, repeats, n_recordings)``.
    """
    start = time.perf_counter()
    chip_frames = np.asarray(chip_frames)
    if chip_frames.ndim != 5:
        raise ValueError(f"chip_frames must be (chips, n, C, H, W), got {chip_frames.shape}")
    if reference_frames is not None:
        return cross_validate(
            reference_frames,
            labels,
            model,
            training,
            class_names=class_names,
            frame_s=frame_s,
            tested=chip_frames,
        )
    per_chip = [
        cross_validate(
            frames,
            labels,
            model,
            training,
            class_names=class_names,
            frame_s=frame_s if chip == 0 else None,
        )
        for chip, frames in enumerate(chip_frames)
    ]
    return dataclasses.replace(
        per_chip[0],
        seconds=time.perf_counter() - start,
        chip_accuracy=np.stack([cv.fold_accuracy for cv in per_chip]),
        chip_predicted=np.stack([cv.predicted for cv in per_chip]),
    )


def validate_input(
    inputs: DecoderInput,
    labels: np.ndarray,
    model: Model,
    training: TrainingSpec,
    *,
    class_names: Sequence[str] | None = None,
) -> CrossValidation:
    """Cross-validated accuracy of ``model`` on what its decoder reads of a scene
    (:class:`~pipeline.chain.decoders.DecoderInput`): on its one chip, with its decisions
    along the touch; or on every chip of a scene of chips, deployed as the scene says
    (:func:`validate_chips`; a point of chips keeps no decisions)."""
    if inputs.chips is None:
        return cross_validate(
            inputs.frames,
            labels,
            model,
            training,
            class_names=class_names,
            frame_s=inputs.column_s,
        )
    return validate_chips(
        inputs.chips, inputs.reference, labels, model, training, class_names=class_names
    )
