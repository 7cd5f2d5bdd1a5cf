"""Chips, the run layer: the spikes level's chips and what a point's entries keep of them (the
chain's part is :mod:`pipeline.chain.chips`, the cube's :mod:`pipeline.results.chip_cube`).

A scene simulates chips when :attr:`pipeline.design.scene.ChipsSpec.simulated`: the spikes level
then encodes every chip and the deployment's reference (:func:`encode_chips`), and the results
level cross-validates the deployment over them (:func:`chip_results`).

Variables of the spike entry (:data:`CHIP_SPIKE_VARIABLES`): every chip's REAL trains as the four
``chips_`` train variables on ``(chip_recording, taxel)``, rows chip-major ``(chip, recording)``
pairs as in :class:`~pipeline.chain.chips.ChipTrains`; the reference a deployed classifier trains
on as the four ``reference_`` ones (recording, taxel); and ``chips_metrics`` float64 (chip,
metric), each chip's spike metrics, whose length is the chip count. Variables of the result entry
(:data:`CHIP_RESULT_VARIABLES`): ``chip_accuracy`` float64 (model, chip, repeat, fold),
``chip_predicted`` int64 (model, chip, repeat, recording) and ``chips_metrics``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pipeline.chain.chips import ChipTrains
from pipeline.chain.metrics import SpikeMetrics
from pipeline.design.scene import Deployment
from pipeline.run.records import (
    Values,
    Variable,
    metric_values,
    read_metrics,
    read_trains,
    train_values,
    train_variables,
)

if TYPE_CHECKING:
    from pipeline.chain.training import CrossValidation

__all__ = [
    "CHIP_RESULT_VARIABLES",
    "CHIP_SPIKE_VARIABLES",
    "ChipResults",
    "chip_result_values",
    "chip_results",
    "chip_spike_values",
    "encode_chips",
    "read_chip_results",
    "read_chip_trains",
]


def encode_chips(
    count: int | None,
    deployment: Deployment | None,
    encode: Callable[[int, Deployment], ChipTrains],
) -> ChipTrains | None:
    """Every chip's REAL trains and metrics and the deployment's reference, for a scene that
    simulates chips (``chips.count`` and ``chips.deployment`` read, as ``count`` and
    ``deployment``): ``encode(count, deployment)``, the scene's encoding bound to
    :func:`pipeline.chain.chips.encode_chips`; None for a scene of one chip (neither read)."""
    if count is None or deployment is None:
        return None
    return encode(count, deployment)


def chip_results(
    accuracy: Mapping[str, CrossValidation], chips: ChipTrains | None
) -> ChipResults | None:
    """Every chip's accuracy, predictions and spike metrics from a point's cross-validation
    (model name -> its result); None for a scene of one chip."""
    if chips is None:
        return None
    return ChipResults(
        fold_accuracy={model: cv.chip_accuracy for model, cv in accuracy.items()},
        predicted={model: cv.chip_predicted for model, cv in accuracy.items()},
        metrics=chips.metrics,
    )


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


def chip_spike_values(chips: ChipTrains | None, duration: np.ndarray) -> Values:
    """The arrays of a spike entry's chips; none for a scene of one chip."""
    if chips is None:
        return {}
    values = train_values("chips", chips.real)
    if chips.real.count.shape[0] != chips.n_chips * len(duration):
        raise ValueError("chips: rows are not chips times recordings")
    if chips.reference is not None:
        values |= train_values("reference", chips.reference)
    values["chips_metrics"] = np.stack([metric_values(m) for m in chips.metrics])
    return values


def read_chip_trains(values: Mapping[str, np.ndarray], duration: np.ndarray) -> ChipTrains | None:
    """The chips of a spike entry; None for a scene of one chip."""
    if "chips_metrics" not in values:
        return None
    metrics = tuple(read_metrics({"metrics": row}) for row in values["chips_metrics"])
    real = read_trains(values, "chips", np.tile(duration, len(metrics)))
    reference = None
    if "reference_count" in values:
        reference = read_trains(values, "reference", duration)
    return ChipTrains(real, metrics, reference)


def chip_result_values(chips: ChipResults | None, models: list[str]) -> Values:
    """The arrays of a result entry's chips; none for a point of one chip."""
    if chips is None:
        return {}
    if list(chips.fold_accuracy) != models or list(chips.predicted) != models:
        raise ValueError(f"chips: models {list(chips.fold_accuracy)}, accuracy of {models}")
    return {
        "chip_accuracy": np.stack([np.asarray(v) for v in chips.fold_accuracy.values()]),
        "chip_predicted": np.stack([np.asarray(v) for v in chips.predicted.values()]),
        "chips_metrics": np.stack([metric_values(m) for m in chips.metrics]),
    }


def read_chip_results(values: Mapping[str, np.ndarray], models: list[str]) -> ChipResults | None:
    """The chips of a result entry, models in ``models`` order; None for a point of one chip."""
    if "chip_accuracy" not in values:
        return None
    accuracy, predicted = values["chip_accuracy"], values["chip_predicted"]
    return ChipResults(
        {m: accuracy[i] for i, m in enumerate(models)},
        {m: predicted[i] for i, m in enumerate(models)},
        tuple(read_metrics({"metrics": row}) for row in values["chips_metrics"]),
    )
