"""Monotone transforms of objective values: what a search's sampler is told instead of the raw
value.

A sampler models the objectives it is told (a Gaussian process fits them, TPE splits trials by
them); a data rate that spans four decades, told raw, is a flat plain with one cliff, and the
model spends its trials on the cliff. Each objective therefore declares a transform
(:data:`pipeline.design.space.TRANSFORMS`), applied to its values before they are told, never
to what is stored or reported:

* linear: ``y = x`` (a fraction such as accuracy);
* logarithmic: ``y = log10(floor + x)`` for a quantity that is never negative and spans decades
  (a rate, a power, an area, seconds). ``floor`` (in the objective's own unit) is the value
  below which differences stop mattering, so ``x = 0`` stays finite: ``log10(1 + rate)`` for a
  data rate in bit/s.

Both are strictly increasing over the values an objective takes (``x > -floor``), so a
transform never changes which trial dominates which: the front and every direction are the
sampler's as they are the report's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Transform:
    """``y = x`` (``floor`` None), or ``y = log10(floor + x)`` (``floor > 0``, the objective's
    unit)."""

    floor: float | None = None

    def __post_init__(self) -> None:
        if self.floor is not None and not self.floor > 0:
            raise ValueError(f"a logarithmic transform needs floor > 0, got {self.floor!r}")

    @classmethod
    def linear(cls) -> Transform:
        """The identity, ``y = x``."""
        return cls(None)

    @classmethod
    def log(cls, floor: float) -> Transform:
        """``y = log10(floor + x)``, ``floor > 0`` in the objective's unit."""
        return cls(float(floor))

    def apply(self, values: np.ndarray | float) -> np.ndarray:
        """float64, the shape of ``values``: transformed; NaN where the transform is not
        defined (``x <= -floor``) or ``x`` is NaN."""
        x = np.asarray(values, dtype=np.float64)
        if self.floor is None:
            return x.copy()
        shifted = self.floor + x
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(shifted > 0, np.log10(np.where(shifted > 0, shifted, 1.0)), np.nan)

    def describe(self) -> str:
        """``"x"`` or ``"log10(<floor> + x)"``, as the docs write it."""
        return "x" if self.floor is None else f"log10({self.floor:g} + x)"
