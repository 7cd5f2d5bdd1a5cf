"""Checks of the numbers a user gives: in data files, function arguments and command-line options.

Both checks return the accepted value, or ``None`` for the caller to report in its own words
(which file, key or option). Booleans are not numbers here, although Python counts ``True`` as 1,
and neither are strings: ``sampling_rate_hz = "100"`` in a TOML file is a mistake to report, not
a value to coerce. Python and numpy integers and floats are accepted alike.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["positive_number", "whole_number"]


def positive_number(value: Any) -> float | None:
    """``value`` as a finite float > 0, or ``None`` if it is not one.

    Parameters
    ----------
    value
        Any object.

    Returns
    -------
    float or None
        ``float(value)`` for an integer or floating-point number that is finite and > 0;
        ``None`` for anything else (0, negatives, NaN, infinities, booleans, strings, ``None``).
    """
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        return None
    value = float(value)
    return value if math.isfinite(value) and value > 0 else None


def whole_number(value: Any, minimum: int) -> int | None:
    """``value`` as an int >= ``minimum``, or ``None`` if it is not one.

    Parameters
    ----------
    value
        Any object.
    minimum
        The smallest accepted value.

    Returns
    -------
    int or None
        ``int(value)`` for a Python or numpy integer >= ``minimum``; ``None`` for anything else
        (smaller integers, floats even when whole, booleans, strings, ``None``).
    """
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        return None
    return int(value)
