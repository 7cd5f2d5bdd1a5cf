"""Inputs of the hardware models checked once, and results given back in the inputs' shape.

The power, area and energy functions (:mod:`pipeline.results.readout_power`,
:mod:`pipeline.results.matched_area`, :mod:`pipeline.results.decoder_energy`) broadcast:
scalars, numpy arrays and ``xarray.DataArray`` inputs work alike, and a DataArray keeps its
dimensions and coordinates, since after :func:`non_negative` only numpy arithmetic is applied to
the inputs. A scalar result is a Python float (:func:`plain`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["keep", "non_negative", "plain"]


def non_negative(name: str, value: Any) -> Any:
    """``value`` checked to be numeric, finite and >= 0 everywhere; returned for arithmetic.

    Scalars, arrays and DataArrays are returned as they are, so that the caller's arithmetic keeps
    their coordinates; lists and tuples become float64 arrays.

    Raises
    ------
    ValueError
        ``value`` is not numeric, or is NaN, infinite or negative somewhere; the message names
        ``name``, the first bad value and how many there are.
    """
    values = np.asarray(value)
    if values.dtype.kind not in "iuf":
        raise ValueError(
            f"{name} must be a number or an array of numbers, got {type(value).__name__} "
            f"of dtype {values.dtype}"
        )
    bad = ~(np.isfinite(values) & (values >= 0))
    if bad.any():
        first = values[np.unravel_index(np.argmax(bad), values.shape)] if values.ndim else values
        where = f" ({np.count_nonzero(bad)} of {values.size} values)" if values.ndim else ""
        raise ValueError(f"{name} must be finite and >= 0, got {first.item()!r}{where}")
    if isinstance(value, list | tuple):
        return values.astype(np.float64)
    return value


def plain(result: Any) -> Any:
    """A 0-d numpy result as a Python float; arrays and DataArrays unchanged."""
    if isinstance(result, np.generic | np.ndarray) and np.ndim(result) == 0:
        return float(result)
    return result


def keep(like: Any, values: np.ndarray) -> Any:
    """``values`` shaped as ``like``: a DataArray keeps its coordinates, a 0-d one is a float."""
    if hasattr(like, "copy") and hasattr(like, "dims"):
        return like.copy(data=values)
    return plain(values)
