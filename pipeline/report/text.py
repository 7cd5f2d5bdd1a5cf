"""Number formatting shared by the report's sentences and tables (percent, rates, labels)."""

from __future__ import annotations

from typing import Any

import numpy as np

from pipeline.report.curves import Curve


def label(value: Any) -> str:
    """A coordinate value as text: numbers in ``%g``, anything else as ``str``."""
    return f"{value:g}" if isinstance(value, int | float | np.number) else str(value)


def pct(value: float) -> str:
    """A fraction as a percentage with one decimal, e.g. ``60.0 %``."""
    return f"{100 * value:.1f} %"


def pct_pm(curve: Curve, i: int) -> str:
    """Point ``i`` of ``curve`` as ``mean % +- std %``."""
    return f"{100 * curve.mean[i]:.1f} % +- {100 * curve.std[i]:.1f} %"


def rate(value: float) -> str:
    """A rate with an SI prefix and a trailing space for the unit, e.g. ``7.78 k``."""
    for factor, prefix in ((1e6, "M"), (1e3, "k")):
        if abs(value) >= factor:
            return f"{value / factor:.3g} {prefix}"
    return f"{value:.3g} "
