r"""Decisions along the touch: early exit on the output's confidence.

A model that can be read at several times of one touch (the spiking decoder at every step, the
rate-coded networks at every window boundary) gives, per recording ``i`` and cross-validation
repeat ``r``, at each decision time ``t_k`` (seconds of touch, ascending) a decided class, whether
it is right (``correct[k, r, i]``: 1, 0, or -1 where the model decides nothing at ``t_k``) and its
confidence ``c[k, r, i]``, the softmax probability of the decided class (NaN where no decision).

Early exit at confidence threshold ``theta`` decides each (repeat, recording) at the first time
its confidence reaches the threshold, else at the last time the model decides:

.. math::

    k^*_{ri} = \begin{cases}
        \min \{k : \mathrm{correct}_{kri} \ge 0,\ c_{kri} \ge \theta\} & \text{if any} \\
        \max \{k : \mathrm{correct}_{kri} \ge 0\} & \text{otherwise}
    \end{cases}

Its mean decision time is ``mean_{ri} t_{k*}`` and its accuracy ``mean_{ri} correct[k*, r, i]``,
both over the (repeat, recording) pairs that have any decision. The decoder's energy under the
rule is that of the operations counted up to each pair's exit time, averaged the same way
(:func:`exit_energy_j`).

Pure numpy; every function takes any leading dimensions (design points, models) before the
``(time, repeat, recording)`` ones.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.chain.operation_kinds import OPERATIONS
from pipeline.results.decision_cube import (
    DECISION_CONFIDENCE,
    DECISION_CORRECT,
    DECISION_DIM,
    DECODER_VARIABLES,
)
from pipeline.results.decoder_energy import DecoderEnergyModel, EnergyBand, decoder_energy_j
from pipeline.results.variables import MODEL_DIM, RECORDING_DIM, REPEAT_DIM, RESULT_KEY

#: Confidence thresholds of the report's early-exit table.
EXIT_THRESHOLDS = (0.5, 0.7, 0.8, 0.9, 0.95, 0.99)
#: The confidence threshold of the search objectives ``decision_s`` and ``decoder_energy_j``: a
#: softmax probability of 0.9 for the decided class.
EXIT_CONFIDENCE = 0.9


@dataclass(frozen=True)
class EarlyExit:
    """Early exit at one confidence threshold (see the module docstring).

    Attributes
    ----------
    threshold : float
        The confidence threshold, in [0, 1].
    index : numpy.ndarray
        int64 (..., repeats, recordings): the exit time's index ``k*`` along the decision
        times, -1 where the pair has no decision at all.
    decision_s : numpy.ndarray
        float64 (..., repeats, recordings): the exit time (s of touch), NaN where none.
    correct : numpy.ndarray
        int8 (..., repeats, recordings): the exit decision right (1), wrong (0), none (-1).
    mean_decision_s, accuracy : numpy.ndarray or float
        float64 (...): mean exit time (s) and fraction right over the pairs with a decision;
        NaN where there is none.
    n : numpy.ndarray or int
        int64 (...): pairs with a decision.
    """

    threshold: float
    index: np.ndarray
    decision_s: np.ndarray
    correct: np.ndarray
    mean_decision_s: np.ndarray | float
    accuracy: np.ndarray | float
    n: np.ndarray | int


def early_exit(
    confidence: np.ndarray, correct: np.ndarray, decision_s: np.ndarray, threshold: float
) -> EarlyExit:
    """Early exit at ``threshold`` (see the module docstring).

    Parameters
    ----------
    confidence
        float (..., times, repeats, recordings): softmax probability of the decided class, NaN
        where no decision.
    correct
        int (..., times, repeats, recordings): 1 right, 0 wrong, -1 no decision.
    decision_s
        float (times,): the decision times (s of touch), ascending.
    threshold
        Confidence threshold in [0, 1]; 0 exits at the first decision, above 1 at the last.

    Returns
    -------
    EarlyExit
        Scalars (Python numbers) where there are no leading dimensions.

    Raises
    ------
    ValueError
        Shapes that disagree, decision times not strictly ascending, a threshold that is not a
        number in [0, 1] (NaN included), or ``correct`` outside {-1, 0, 1}.
    """
    confidence = np.asarray(confidence, dtype=np.float64)
    correct = np.asarray(correct)
    times = np.asarray(decision_s, dtype=np.float64)
    if confidence.shape != correct.shape or confidence.ndim < 3:
        raise ValueError(
            "confidence and correct must have one shape (..., times, repeats, recordings), got "
            f"{confidence.shape} and {correct.shape}"
        )
    if times.shape != (confidence.shape[-3],):
        raise ValueError(f"decision_s must have shape ({confidence.shape[-3]},), got {times.shape}")
    if times.size > 1 and not np.all(np.diff(times) > 0):
        raise ValueError("decision_s must be strictly ascending")
    if (
        isinstance(threshold, bool)
        or not isinstance(threshold, int | float | np.floating)
        or not 0.0 <= threshold <= 1.0
    ):
        raise ValueError(f"threshold must be a number in [0, 1], got {threshold!r}")
    if not np.all(np.isin(correct, (-1, 0, 1))):
        raise ValueError("correct must hold only 1, 0 and -1 (no decision)")
    decided = correct >= 0
    # NaN confidence never passes (a comparison with NaN is False).
    passes = decided & (confidence >= threshold)
    n_times = times.size
    first = np.argmax(passes, axis=-3)
    last = n_times - 1 - np.argmax(decided[..., ::-1, :, :], axis=-3)
    any_decided = decided.any(axis=-3)
    index = np.where(passes.any(axis=-3), first, np.where(any_decided, last, -1)).astype(np.int64)
    at = np.maximum(index, 0)
    exit_correct = np.take_along_axis(correct, at[..., np.newaxis, :, :], axis=-3)[..., 0, :, :]
    exit_correct = np.where(index >= 0, exit_correct, -1).astype(np.int8)
    exit_s = np.where(index >= 0, times[at], np.nan)
    n = any_decided.sum(axis=(-2, -1))
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_s = np.where(n > 0, np.nansum(exit_s, axis=(-2, -1)) / n, np.nan)
        accuracy = np.where(n > 0, (exit_correct == 1).sum(axis=(-2, -1)) / n, np.nan)
    return EarlyExit(
        float(threshold),
        index,
        exit_s,
        exit_correct,
        _scalar(mean_s),
        _scalar(accuracy),
        int(n) if np.ndim(n) == 0 else n,
    )


def exit_energy_j(
    exit: EarlyExit,
    acs: np.ndarray,
    macs: np.ndarray,
    neuron_updates: np.ndarray,
    model: DecoderEnergyModel | None = None,
) -> EnergyBand:
    """The decoder's mean energy per decision under an early exit, low and high (J).

    Parameters
    ----------
    exit
        An :func:`early_exit` result.
    acs, macs, neuron_updates
        float (..., times): mean cumulative operations per decision read at each time, with
        the leading dimensions of ``exit``.
    model
        The per-operation energies (:class:`~pipeline.results.decoder_energy.DecoderEnergyModel`).

    Returns
    -------
    EnergyBand
        float64 (...): the energy at each pair's exit time
        (:func:`~pipeline.results.decoder_energy.decoder_energy_j`), averaged over the pairs with a
        decision; NaN where there is none or a count at an exit time is unknown.
    """
    band = decoder_energy_j(acs, macs, neuron_updates, model)
    index = exit.index
    ends = []
    for energy in (band.low_j, band.high_j):
        energy = np.asarray(energy, dtype=np.float64)
        if energy.shape[:-1] != index.shape[:-2]:
            raise ValueError(
                f"operation counts {energy.shape} do not match the exit's leading shape "
                f"{index.shape[:-2]} plus the decision times"
            )
        per_pair = np.take_along_axis(
            energy[..., np.newaxis, np.newaxis, :],
            np.maximum(index, 0)[..., np.newaxis],
            axis=-1,
        )[..., 0]
        per_pair = np.where(index >= 0, per_pair, np.nan)
        n = (index >= 0).sum(axis=(-2, -1))
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = np.where(n > 0, per_pair.sum(axis=(-2, -1), where=index >= 0) / n, np.nan)
        ends.append(_scalar(mean))
    return EnergyBand(*ends)


def exit_objectives(
    cube: xr.Dataset,
    model: str,
    confidence: float = EXIT_CONFIDENCE,
    energy: DecoderEnergyModel | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The search objectives of ``model`` at every point of a cube, under early exit at
    ``confidence``: the mean decision time (s) and the decoder's mean energy per decision at the
    high end of its band (J).

    Parameters
    ----------
    cube
        A result cube with ``decision_s``, ``decision_correct`` and ``decision_confidence``
        (axes..., model, decision_s, repeat, recording) and the operation counts
        ``decoder_acs``, ``decoder_macs``, ``decoder_neuron_updates`` (axes..., model,
        decision_s).
    model
        The model, a ``model`` coordinate of the cube.
    confidence, energy
        The early exit's threshold and the per-operation energies.

    Returns
    -------
    decision_s, energy_j : numpy.ndarray
        float64 (the cube's sweep shape, ``result_key``'s dimensions): NaN throughout where the
        cube keeps no decisions (or no operation counts, for the energy) or does not hold the
        model.
    """
    dims = cube[RESULT_KEY].dims
    shape = cube[RESULT_KEY].shape
    nan = np.full(shape, np.nan)
    names = (DECISION_DIM, DECISION_CORRECT, DECISION_CONFIDENCE)
    if not all(name in cube for name in names) or model not in cube[MODEL_DIM].values:
        return nan, nan.copy()
    at = cube.sel({MODEL_DIM: model})
    order = (*dims, DECISION_DIM, REPEAT_DIM, RECORDING_DIM)
    found = early_exit(
        at[DECISION_CONFIDENCE].transpose(*order).values,
        at[DECISION_CORRECT].transpose(*order).values,
        cube[DECISION_DIM].values,
        confidence,
    )
    if not all(name in cube for name in DECODER_VARIABLES):
        return np.asarray(found.mean_decision_s, dtype=np.float64), nan
    counts = {  # each kind of operation by its name, as exit_energy_j takes it
        kind: at[name].transpose(*dims, DECISION_DIM).values
        for kind, name in zip(OPERATIONS, DECODER_VARIABLES, strict=True)
    }
    band = exit_energy_j(found, **counts, model=energy)
    return (
        np.asarray(found.mean_decision_s, dtype=np.float64),
        np.asarray(band.high_j, dtype=np.float64),
    )


def _scalar(values: np.ndarray) -> np.ndarray | float:
    """A 0-d result as a Python float, arrays as they are."""
    values = np.asarray(values, dtype=np.float64)
    return float(values) if values.ndim == 0 else values


def decides(correct: np.ndarray) -> np.ndarray:
    """bool (..., times): whether the model decides at each time for any (repeat, recording).

    ``correct`` int (..., times, repeats, recordings) as in :func:`early_exit`.
    """
    return (np.asarray(correct) >= 0).any(axis=(-2, -1))


def full_touch(correct: np.ndarray) -> int | None:
    """Index of the last time the model decides (``correct`` (times, repeats, recordings)),
    None if it never does."""
    found = np.flatnonzero(decides(correct))
    return int(found[-1]) if found.size else None


__all__ = [
    "EXIT_CONFIDENCE",
    "EXIT_THRESHOLDS",
    "EarlyExit",
    "decides",
    "early_exit",
    "exit_energy_j",
    "exit_objectives",
    "full_touch",
]
