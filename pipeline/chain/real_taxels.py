r"""The taxels a design reads of a real array: recordings with one column per taxel.

A dataset of a real array (:attr:`pipeline.recordings.recording_set.Recordings.is_array`) holds
``N`` taxels; a design reads ``k = array.taxels`` of them (all when unset), chosen to spread
evenly over the array (:mod:`pipeline.recordings.taxel_choice` states how, and the pitch of the
taxels read).

The chosen taxels keep the declared order (rows of a frame follow it), and taxel ``m`` of the
readout is the ``m``-th chosen one: its mismatch, offsets and noise are drawn for readout
taxel ``m`` (:func:`pipeline.chain.readout_effects.effect_rng`), as taxel ``m`` of a time-shift
grid. No taxel is delayed: each sees its own recorded column.
"""

from __future__ import annotations

import numpy as np

from pipeline.design.scene import ArraySpec
from pipeline.recordings.recording_set import Recordings
from pipeline.recordings.taxel_choice import chosen_taxels

__all__ = ["array_misfits", "taxel_rows", "taxels_read"]


def taxels_read(recordings: Recordings, array: ArraySpec) -> np.ndarray | None:
    """int64 (k,): the columns of ``recordings`` that ``array`` reads (:func:`chosen_taxels`);
    None for one-channel recordings, whose array is made by time shifts."""
    if not recordings.is_array:
        return None
    return chosen_taxels(recordings.n_taxels, array.taxels, recordings.taxel_positions_mm)


def taxel_rows(signal: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """float64 (k, n_samples), C-contiguous: the ``chosen`` columns of one recording
    ``signal`` (float64 (n_samples, n_taxels)), one row per taxel read."""
    return np.ascontiguousarray(np.asarray(signal, dtype=np.float64)[:, chosen].T)


def array_misfits(
    array: ArraySpec, n_taxels: int, is_array: bool, dataset: str
) -> list[tuple[str, str]]:
    """``(scene field, problem)`` for an ``array`` that does not fit a dataset whose recordings
    hold ``n_taxels`` taxels (``is_array``: named columns of a real array; else one channel):
    more taxels read than recorded, or a time-shift grid on a real array (time shifts make an
    array of one channel; a real array has its own taxels)."""
    problems: list[tuple[str, str]] = []
    of = f"dataset {dataset!r}" if dataset else "the dataset"
    if array.taxels is not None and array.taxels > n_taxels:
        held = f"{n_taxels} taxel{'s' if n_taxels > 1 else ''}" if is_array else "one channel"
        problems.append(
            (
                "array.taxels",
                f"{array.taxels} taxels asked by array.taxels of {of}, "
                f"whose recordings hold {held}",
            )
        )
    if is_array and array.n_taxels > 1:
        problems.append(
            (
                "array",
                f"a {array.rows}x{array.cols} grid of time-shifted copies asked of {of}, whose "
                f"recordings hold {n_taxels} real taxel{'s' if n_taxels > 1 else ''}: set "
                "array.rows = array.cols = 1 and choose how many are read with array.taxels",
            )
        )
    return problems
