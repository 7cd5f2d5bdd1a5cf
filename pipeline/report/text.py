"""Number formatting shared by the report's sentences and tables (percent, intervals, rates).

Nothing here prints NaN: a missing number is said in words.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pipeline.results.stats import PairedComparison

NO_INTERVAL = "no interval"
NO_INTERVAL_WHY = "no interval: this run predates per-recording results; re-run the sweep"


def label(value: Any) -> str:
    """A coordinate value as text: numbers in ``%g``, anything else as ``str``."""
    if isinstance(value, bool | np.bool_):
        return str(bool(value)).lower()
    return f"{value:g}" if isinstance(value, int | float | np.number) else str(value)


def pct(value: float) -> str:
    """A fraction as a percentage with one decimal, e.g. ``60.0 %``; "unknown" for NaN."""
    return f"{100 * value:.1f} %" if math.isfinite(value) else "unknown"


def pct_interval(mean: float, low: float, high: float) -> str:
    """``60.0 % [51.1, 68.3]``: a fraction and its 95 % interval, in percent."""
    if not (math.isfinite(low) and math.isfinite(high)):
        return f"{pct(mean)} ({NO_INTERVAL})"
    return f"{pct(mean)} [{100 * low:.1f}, {100 * high:.1f}]"


def signed_points(value: float) -> str:
    """A difference of fractions in percentage points, e.g. ``-2.5``."""
    return f"{100 * value:+.1f}"


def p_value(p: float) -> str:
    """A p-value in two significant digits, e.g. ``0.038``, ``1``, ``3.1e-09``."""
    return f"{p:.2g}"


def comparison(c: PairedComparison, holm_p: float | None = None) -> str:
    """``-2.5 points [-6.7, +1.7], McNemar p = 0.38`` (and the Holm-adjusted p if given)."""
    test = "McNemar p" if "McNemar" in c.method else "bootstrap p"
    text = (
        f"{signed_points(c.difference)} points [{signed_points(c.low)}, {signed_points(c.high)}]"
        f", {test} = {p_value(c.p_value)}"
    )
    if holm_p is not None:
        text += f", Holm p = {p_value(holm_p)}"
    return text


def rate(value: float, unit: str) -> str:
    """A rate with an SI prefix, e.g. ``7.78 kbit/s``; "unknown" for NaN."""
    if not math.isfinite(value):
        return "unknown"
    return _prefixed(value) + unit


def _prefixed(value: float) -> str:
    for factor, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if abs(value) >= factor:
            return f"{value / factor:.3g} {prefix}"
    return f"{value:.3g} "


def si(value: float, unit: str) -> str:
    """``value`` with an SI prefix, e.g. ``18.9 nW``; "unknown" for NaN."""
    if not math.isfinite(value):
        return "unknown"
    if value == 0:
        return f"0 {unit}"
    for factor, prefix in (
        (1e9, "G"),
        (1e6, "M"),
        (1e3, "k"),
        (1.0, ""),
        (1e-3, "m"),
        (1e-6, "µ"),
        (1e-9, "n"),
        (1e-12, "p"),
        (1e-15, "f"),
    ):
        if abs(value) >= factor:
            return f"{value / factor:.3g} {prefix}{unit}"
    return f"{value:.3g} {unit}"


def area_text(value_m2: float) -> str:
    """An area in m^2 as ``1.23 um^2``; "unknown" for NaN."""
    return f"{value_m2 * 1e12:.3g} um^2" if math.isfinite(value_m2) else "unknown"


def times(ratio: float) -> str:
    """A ratio as ``12x`` (``1.5x`` below 10); "unknown" when not finite."""
    if not math.isfinite(ratio):
        return "unknown"
    return f"{ratio:.0f}x" if ratio >= 10 else f"{ratio:.2g}x"


def fold_spread(std: float) -> str:
    """The secondary spread over folds, e.g. ``2.6 %``; "-" when unknown."""
    return f"{100 * std:.1f} %" if math.isfinite(std) else "-"
