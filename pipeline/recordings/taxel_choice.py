r"""Which taxels of a real array a reader takes: ``k`` of ``N``, spread evenly over the array.

* With taxel positions :math:`p_1 \dots p_N` (mm, ``taxel_positions_mm``): one taxel is the one
  nearest the array's centre :math:`\bar p`; more are chosen by farthest-point sampling, which
  starts from the taxel farthest from the centre and adds, each time, the taxel farthest from
  those already chosen

  .. math::

      c_{m+1} = \arg\max_i \min_{j \le m} \lVert p_i - p_{c_j} \rVert

  (ties go to the taxel declared first; distances rounded to 1 nm), so fewer taxels stand
  farther apart. Their *pitch* is the smallest distance between two of them,
  :math:`\min_{a \ne b} \lVert p_{c_a} - p_{c_b} \rVert` (mm; undefined for one taxel);
* without positions: evenly over the declared order, taxel
  :math:`\lfloor (2m + 1) N / (2k) \rfloor` for :math:`m = 0 \dots k - 1` (the middle of each of
  ``k`` equal stretches of the order).

The chosen taxels keep the declared order. A design's ``array.taxels``
(:mod:`pipeline.chain.real_taxels`) and ``eskin describe``'s classifier on some of the taxels
(:mod:`pipeline.recordings.describe_array`) both choose this way, so what describe says of
``k`` taxels is said of the taxels a design of ``k`` reads.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["chosen_taxels", "taxel_pitch_mm"]

# Distances equal to this many decimals of a millimetre (1 nm) are ties: a grid's equal
# spacings must not be told apart by rounding.
_DISTANCE_DECIMALS = 6


def chosen_taxels(
    n_total: int, n_read: int | None, positions_mm: np.ndarray | None = None
) -> np.ndarray:
    """The taxels read of an array of ``n_total`` (see the module docstring).

    Parameters
    ----------
    n_total : int
        Taxels of the array, >= 1.
    n_read : int or None
        Taxels read, ``1 <= n_read <= n_total``; None for all.
    positions_mm : float64 (n_total, 2), optional
        Each taxel's ``[x, y]`` (mm).

    Returns
    -------
    numpy.ndarray
        int64 (n_read,): indices of the taxels read, increasing.

    Raises
    ------
    ValueError
        ``n_read`` outside ``1..n_total``, or positions not of shape ``(n_total, 2)``.
    """
    k = n_total if n_read is None else int(n_read)
    if not 1 <= k <= n_total:
        raise ValueError(f"cannot read {k} of {n_total} taxels")
    if k == n_total:
        return np.arange(n_total, dtype=np.int64)
    if positions_mm is None:
        m = np.arange(k, dtype=np.int64)
        return (2 * m + 1) * n_total // (2 * k)
    positions = np.asarray(positions_mm, dtype=np.float64)
    if positions.shape != (n_total, 2):
        raise ValueError(f"positions must be ({n_total}, 2), got {positions.shape}")
    from_centre = _distances(positions, positions.mean(axis=0))
    if k == 1:
        return np.array([np.argmin(from_centre)], dtype=np.int64)
    chosen = [int(np.argmax(from_centre))]
    nearest = _distances(positions, positions[chosen[0]])
    for _ in range(k - 1):
        chosen.append(int(np.argmax(nearest)))
        nearest = np.minimum(nearest, _distances(positions, positions[chosen[-1]]))
    return np.sort(np.array(chosen, dtype=np.int64))


def _distances(positions: np.ndarray, point: np.ndarray) -> np.ndarray:
    return np.round(np.hypot(*(positions - point).T), _DISTANCE_DECIMALS)


def taxel_pitch_mm(positions_mm: np.ndarray, chosen: np.ndarray) -> float:
    """The smallest distance between two of the ``chosen`` taxels (mm); NaN for one taxel.

    Parameters
    ----------
    positions_mm : float64 (n_total, 2)
        Each taxel's ``[x, y]`` (mm).
    chosen : int64 (k,)
        Indices of the taxels read (:func:`chosen_taxels`).
    """
    points = np.asarray(positions_mm, dtype=np.float64)[np.asarray(chosen)]
    if len(points) < 2:
        return math.nan
    gaps = np.hypot(*(points[:, np.newaxis, :] - points[np.newaxis, :, :]).transpose(2, 0, 1))
    return float(gaps[np.triu_indices(len(points), k=1)].min())
