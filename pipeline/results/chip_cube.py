"""The cube's chips: every chip's accuracy, predictions and metrics, and the yield over them.

Where some point simulates chips (``chips.count`` above 1, or a ``shared`` or ``robust``
deployment: :mod:`pipeline.chain.chips`, :mod:`pipeline.run.chips`), :func:`chip_variables`
gives the cube a ``chip`` dimension (:data:`CHIP_DIM`, coordinate 0..N-1, N the most chips of
any point; a point's missing chips are NaN, or -1 for the integer variables) along which
``accuracy`` (axes..., model, chip, repeat, fold), ``accuracy_mean``, ``accuracy_low``,
``accuracy_high`` (axes..., model, chip), ``predicted`` and ``correct`` (axes..., model, chip,
repeat, recording) and the spike metrics but ``equivalent_bits`` (axes..., chip) lie, and the
yield statistics over each point's chips (:func:`pipeline.results.yields.yield_statistics`), all
(axes..., model):

``accuracy_chip_mean``
    mean of ``accuracy_mean`` over the chips
``accuracy_p05``, ``accuracy_p05_low``, ``accuracy_p05_high``
    5th percentile of ``accuracy_mean`` over the chips and its distribution-free 95 % interval
    from order statistics (NaN for a bound the point's chips are too few to give)
``yield_share``
    share of the chips whose ``accuracy_mean`` is at or above the point's
    ``chips.yield_target``

A point of one chip without chip results has its own accuracy, predictions and metrics as chip 0.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from pipeline.results.accuracy_summary import accuracy_summary
from pipeline.results.point import PointResult
from pipeline.results.variables import (
    ACCURACY,
    ACCURACY_MEAN,
    CORRECT,
    FOLD_DIM,
    LABEL,
    METRICS,
    MODEL_DIM,
    PREDICTED,
    RECORDING_DIM,
    REPEAT_DIM,
)
from pipeline.results.yields import (
    ACCURACY_CHIP_MEAN,
    ACCURACY_P05,
    ACCURACY_P05_HIGH,
    ACCURACY_P05_LOW,
    YIELD_SHARE,
    yield_statistics,
)
from pipeline.run.grid_keys import KeyedPoint

__all__ = ["CHIP_CUBE_VARIABLES", "CHIP_DIM", "CHIP_METRICS", "chip_variables"]

#: The dimension along which a design's chips lie.
CHIP_DIM = "chip"
#: The spike metrics a cube holds per chip (``equivalent_bits`` is the design's alone).
CHIP_METRICS = tuple(name for name in METRICS if name != "equivalent_bits")
#: ``units`` and ``long_name`` of the chip dimension and the yield statistics.
CHIP_CUBE_VARIABLES: dict[str, dict[str, str]] = {
    CHIP_DIM: {"units": "1", "long_name": "simulated chip of the design"},
    ACCURACY_CHIP_MEAN: {"units": "1", "long_name": "mean over the chips of their accuracy"},
    ACCURACY_P05: {"units": "1", "long_name": "5th percentile over the chips of their accuracy"},
    ACCURACY_P05_LOW: {
        "units": "1",
        "long_name": "lower end of the distribution-free 95 % interval of accuracy_p05",
    },
    ACCURACY_P05_HIGH: {
        "units": "1",
        "long_name": "upper end of the distribution-free 95 % interval of accuracy_p05",
    },
    YIELD_SHARE: {
        "units": "1",
        "long_name": "share of the chips whose accuracy reaches chips.yield_target",
    },
}


@dataclasses.dataclass(frozen=True)
class _ChipCell:
    """A point's chip as :func:`~pipeline.results.accuracy_summary.accuracy_summary` sees it: one
    more sweep index."""

    index: tuple[int, ...]
    key: str


def chip_variables(
    results: Sequence[PointResult],
    points: list[KeyedPoint],
    flat: np.ndarray,
    shape: tuple[int, ...],
    dims: tuple[str, ...],
    models: list[str],
    data_vars: Mapping[str, Any],
    coords: Mapping[str, Any],
) -> tuple[dict[str, Any], dict[str, Any]] | None:
    """The chip variables and the ``chip`` coordinate of a sweep where some point simulates
    chips (see the module docstring); None where none does.

    A point of one chip without chip results has its own accuracy, predictions and metrics
    (``data_vars``) as chip 0.
    """
    chips = [result.chips for result in results]
    if all(c is None for c in chips):
        return None
    n_chips = max(1 if c is None else c.n_chips for c in chips)
    size = int(np.prod(shape))
    base = data_vars[ACCURACY][1].reshape(size, *data_vars[ACCURACY][1].shape[len(shape) :])
    n_models, n_repeats, n_folds = base.shape[1:]
    accuracy = np.full((size, n_chips, n_models, n_repeats, n_folds), np.nan)
    accuracy[:, 0] = base
    metrics = {name: np.full((size, n_chips), np.nan) for name in CHIP_METRICS}
    for name in CHIP_METRICS:
        metrics[name][:, 0] = np.asarray(data_vars[name][1]).reshape(size)
    predicted = None
    if PREDICTED in data_vars:
        old = data_vars[PREDICTED][1]
        old = old.reshape(size, *old.shape[len(shape) :])
        predicted = np.full((size, n_chips, *old.shape[1:]), -1, dtype=np.int16)
        predicted[:, 0] = old
        position = {str(name): i for i, name in enumerate(coords[RECORDING_DIM][1])}
    for i, chip in zip(flat.tolist(), chips, strict=True):
        if chip is None:
            continue
        for m, model in enumerate(models):
            if model in chip.fold_accuracy:
                values = np.asarray(chip.fold_accuracy[model])
                accuracy[i, : values.shape[0], m, : values.shape[1], : values.shape[2]] = values
        for k, found in enumerate(chip.metrics):
            for name in CHIP_METRICS:
                metrics[name][i, k] = getattr(found, name)
    if predicted is not None:
        for p, (i, chip) in enumerate(zip(flat.tolist(), chips, strict=True)):
            oof = results[p].out_of_fold
            if chip is None or oof is None:
                continue
            columns = np.array([position[name] for name in oof.recording_names])
            for m, model in enumerate(models):
                if model in chip.predicted:
                    values = np.asarray(chip.predicted[model])
                    ran = np.arange(values.shape[1])[np.newaxis, :, np.newaxis]
                    kept = np.arange(values.shape[0])[:, np.newaxis, np.newaxis]
                    predicted[i, kept, m, ran, columns] = values
    chip_dims = (*dims, CHIP_DIM)
    cells = [_ChipCell((*p.index, k), p.key) for p in points for k in range(n_chips)]
    correct = label = None
    if predicted is not None:
        label = coords[LABEL][1]
        correct = np.where(predicted >= 0, (predicted == label).astype(np.int8), np.int8(-1))
    summary = accuracy_summary(
        accuracy.reshape(*shape, *accuracy.shape[1:]),
        None if correct is None else correct.reshape(*shape, *correct.shape[1:]),
        label,
        chip_dims,
        cells,
        models,
    )
    # Chips lie after the model: (axes..., chip, model, ...) -> (axes..., model, chip, ...).
    n = len(shape)

    variables: dict[str, Any] = {}
    for name, (_, values, *attrs) in summary.items():
        variables[name] = ((*dims, MODEL_DIM, CHIP_DIM), np.swapaxes(values, n, n + 1), *attrs)
    accuracy = np.swapaxes(accuracy.reshape(*shape, *accuracy.shape[1:]), n, n + 1)
    variables[ACCURACY] = ((*dims, MODEL_DIM, CHIP_DIM, REPEAT_DIM, FOLD_DIM), accuracy)
    for name, values in metrics.items():
        variables[name] = (chip_dims, values.reshape(*shape, n_chips))
    if predicted is not None and correct is not None:
        for name, values in ((PREDICTED, predicted), (CORRECT, correct)):
            values = np.swapaxes(values.reshape(*shape, *values.shape[1:]), n, n + 1)
            variables[name] = ((*dims, MODEL_DIM, CHIP_DIM, REPEAT_DIM, RECORDING_DIM), values)
    targets = np.full(size, np.nan)
    targets[flat] = [p.scene.chips.yield_target for p in points]
    per_chip = variables[ACCURACY_MEAN][1]  # (axes..., model, chip)
    stats = yield_statistics(per_chip, targets.reshape(*shape, 1))
    for name, values in stats.items():
        variables[name] = ((*dims, MODEL_DIM), values)
    return variables, {CHIP_DIM: (CHIP_DIM, np.arange(n_chips))}
