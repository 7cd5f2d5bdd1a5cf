"""Readout effects: the non-ideal behaviours a scene may name, and their parameters.

A scene's ``readout.effects`` maps an :class:`Effect` to its parameters (one frozen class per
effect, :data:`EFFECT_TYPES`). An effect that is not named is not simulated and is not part of any
cache key. The parameters' values never change what a point costs, only which effects run
(:attr:`pipeline.design.fields.Cost.FREE`). Effects that draw random numbers
(:data:`RANDOM_EFFECTS`) put the scene seed into the spike-train key; :data:`FIXED_EFFECTS` are
drawn once per chip, the others per recording. What each does to the signal:
:mod:`pipeline.chain.readout_effects`.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from pipeline.design.fields import NONNEGATIVE, POSITIVE, Cost, Range, param


class Effect(enum.StrEnum):
    """Non-ideal readout effects, in the order they act on the signal."""

    AMPLIFIER_OFFSET = "amplifier_offset"
    AMPLIFIER_NOISE = "amplifier_noise"
    SATURATION = "saturation"
    COMPARATOR_OFFSET = "comparator_offset"
    COMPARATOR_NOISE = "comparator_noise"
    THRESHOLD_MISMATCH = "threshold_mismatch"


# ---------------------------------------------------------------------------------------------
# Effect parameters: their values do not change what a point costs, only which effects run.


@dataclass(frozen=True)
class AmplifierOffset:
    """Static input offset per taxel, ``N(0, sigma_v)`` V; matters through saturation."""

    sigma_v: float = param(
        0.01,
        "V",
        "standard deviation of the amplifier offset per taxel",
        within=NONNEGATIVE,
        cost=Cost.FREE,
    )


@dataclass(frozen=True)
class AmplifierNoise:
    """White Gaussian noise on every sample, ``sigma_v`` V rms."""

    sigma_v: float = param(
        0.005, "V", "rms amplifier noise per sample", within=NONNEGATIVE, cost=Cost.FREE
    )


@dataclass(frozen=True)
class Saturation:
    """Clip the amplified signal at the rails ``+-rail_v``; ``None`` means half the full scale."""

    rail_v: float | None = param(
        None, "V", "saturation rail of the amplified signal", within=POSITIVE, cost=Cost.FREE
    )


@dataclass(frozen=True)
class ComparatorOffset:
    """Static offsets of the UP and DOWN comparators per taxel, each ``N(0, sigma_v)`` V."""

    sigma_v: float = param(
        0.005,
        "V",
        "standard deviation of the comparator offsets per taxel",
        within=NONNEGATIVE,
        cost=Cost.FREE,
    )


@dataclass(frozen=True)
class ComparatorNoise:
    """Gaussian noise on each comparator decision (per sample), ``sigma_v`` V rms."""

    sigma_v: float = param(
        0.005, "V", "rms comparator noise per decision", within=NONNEGATIVE, cost=Cost.FREE
    )


@dataclass(frozen=True)
class ThresholdMismatch:
    """Fixed-pattern threshold per taxel, ``threshold_v * (1 + sigma_rel * z)``, ``z ~ N(0, 1)``.

    A draw that would push a threshold below ``floor_rel * threshold_v`` (zero or negative
    included) is clipped to that floor: a comparator cannot resolve a smaller step. For the
    decaying encoder one draw scales its whole curve, ``threshold_v`` and ``decay.theta_min_v``
    alike, and the floor is ``floor_rel * decay.theta_min_v``, so a taxel's first threshold is
    never below its lowest (equal when ``threshold_v`` is ``decay.theta_min_v``).
    """

    sigma_rel: float = param(
        0.05,
        "1",
        "relative standard deviation of the threshold per taxel",
        within=NONNEGATIVE,
        cost=Cost.FREE,
    )
    floor_rel: float = param(
        0.1,
        "1",
        "lowest threshold per taxel, relative to threshold_v",
        within=Range(0, 1, low_open=True),
        cost=Cost.FREE,
    )


#: The frozen class that holds each effect's parameters, read from the scene's table.
EFFECT_TYPES: dict[Effect, type] = {
    Effect.AMPLIFIER_OFFSET: AmplifierOffset,
    Effect.AMPLIFIER_NOISE: AmplifierNoise,
    Effect.SATURATION: Saturation,
    Effect.COMPARATOR_OFFSET: ComparatorOffset,
    Effect.COMPARATOR_NOISE: ComparatorNoise,
    Effect.THRESHOLD_MISMATCH: ThresholdMismatch,
}
#: Effects that draw random numbers (all but saturation); naming one puts the scene seed into
#: the spike-train key.
RANDOM_EFFECTS = frozenset(EFFECT_TYPES) - {Effect.SATURATION}
#: Effects drawn once per chip (fixed-pattern, the same for every recording); the others are
#: drawn per recording (noise) or draw nothing (saturation).
FIXED_EFFECTS = frozenset(
    {Effect.AMPLIFIER_OFFSET, Effect.COMPARATOR_OFFSET, Effect.THRESHOLD_MISMATCH}
)
