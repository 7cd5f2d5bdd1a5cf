"""What a result cube reads of one point (:class:`~pipeline.results.point.PointResult`): the result
entry's fields that the cube and its feature modules (:mod:`pipeline.results.chip_cube`,
:mod:`pipeline.results.decision_cube`) turn into variables."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol

import numpy as np

from pipeline.chain.metrics import SpikeMetrics
from pipeline.run.chips import ChipResults
from pipeline.run.decisions import Decisions
from pipeline.run.entries import OutOfFold, RecordingsInfo
from pipeline.run.records import Paid

__all__ = ["PointResult"]


class PointResult(Protocol):
    """What the cube needs of one point (:class:`pipeline.run.entries.ResultEntry` is one)."""

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

    @property
    def chips(self) -> ChipResults | None:
        """Every chip's accuracy, predictions and spike metrics, for a point that simulates chips
        (:mod:`pipeline.results.chip_cube`); None for a point of one chip."""
        ...

    @property
    def decisions(self) -> Decisions | None:
        """Every model's decisions read during the touch (:mod:`pipeline.results.decision_cube`);
        None where the point kept none."""
        ...
