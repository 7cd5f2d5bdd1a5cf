r"""The non-ideal readout: the scene's effects on the level-crossing encoders, the REAL train.

The ideal encoders and their equations are :mod:`pipeline.chain.readout`; this module applies
the effects a scene names around them (:func:`real_train`) and runs the scene's encoder at its
nominal thresholds (:func:`true_train`, the TRUE train).

Non-ideal encoder (the REAL train)
----------------------------------
The scene's effects act in this order (each only when the scene names it):

.. math::

    \begin{aligned}
    v_t &= x_t + o_t + n_t[i]
        && \text{($o_t$ amplifier\_offset, per taxel; $n_t$ amplifier\_noise, per sample)} \\
    v_t &= \operatorname{clip}(v_t, -\mathrm{rail}, +\mathrm{rail})
        && \text{(saturation)} \\
    \theta_t &= \theta \, (1 + \sigma_\mathrm{rel} \, z_t)
        && \text{(threshold\_mismatch, per taxel)} \\
    \mathrm{up}, \mathrm{down} &= \theta_t + c^\mathrm{up}_t, \; \theta_t + c^\mathrm{down}_t
        && \text{(comparator\_offset, per taxel)} \\
    \text{decision at sample } i\text{:} \quad
        & \begin{cases}
          v[i] - r \ge \mathrm{up} + e[i] & \text{if } v[i] \ge r, \\
          r - v[i] \ge \mathrm{down} + e[i] & \text{else}
          \end{cases}
        && \text{(comparator\_noise, per sample)}
    \end{aligned}

For the decaying encoder ``theta_t`` is the taxel's curve: one mismatch draw scales both
``theta_0`` and ``theta_min``, a comparator offset shifts both ends of its comparator's curve,
and a sample's decision noise shifts both ends of both curves in its segment.

Every effective threshold is clipped below at ``floor_rel * theta_min`` (``theta_min`` is
``theta`` for the fixed encoder; ``floor_rel`` is ``threshold_mismatch``'s when the scene names
it, else :data:`THRESHOLD_FLOOR_REL`): mismatch or offsets
that would push a threshold to zero or below leave the comparator at the smallest step it can
resolve, so the train stays finite. With equal UP and DOWN thresholds and no comparator noise
the REAL train is the ideal encoder run with ``theta_t`` on ``v_t``. Otherwise the reference
follows the DVS-style rule: on a spike it resets to the level that was crossed (``r +- up/down``
including the decision noise), and a sample's noise applies to every level crossed in its segment.

The UP and DOWN comparators have independent noise, but at any sample only the one on the
signal's side of the reference can fire: the other's threshold is at least the floor (> 0) away.
So one draw ``e[i]`` per sample, given to that comparator, has exactly the distribution of two
independent draws of which one is never looked at.

Randomness
----------
Static effects (offsets, mismatch) are properties of the chip: they are drawn from
``effect_rng(seed, effect, taxel)``, the same for every recording. Chip ``k`` of a design
(``chips.count``) draws them from ``effect_rng(seed, effect, taxel, chip=k)``: chip 0 is that
same stream, any other chip a stream of its own (:func:`effect_rng`), and every draw is a
standard normal scaled by the effect's sigma, so chip ``k`` of two designs shares its draws
(common random numbers) whatever their sigmas. The *nominal* chip (``chip=None``) draws no
static effect at all (every one is 0) but keeps the noise. Noise is drawn from
``effect_rng(seed, effect, taxel, recording)``, one value per sample in time order, drawn inside
the compiled loops (the same numbers as ``standard_normal(n_samples)``, without the array). No
generator is created for an effect that is not named, so an ideal scene draws no random numbers
and its REAL train is its TRUE train.
"""

from __future__ import annotations

import math

import numpy as np

from pipeline.chain.readout import (
    MAX_SPIKES_PER_TRAIN,
    checked_signal,
    decaying_train,
    level_crossings,
    level_crossings_rows,
    run_noisy,
)
from pipeline.design.effects import (
    AmplifierNoise,
    AmplifierOffset,
    Effect,
    Saturation,
    ThresholdMismatch,
)
from pipeline.design.scene import Encoder, ReadoutSpec
from pipeline.jit import kernel

THRESHOLD_FLOOR_REL = 0.1
"""Smallest effective threshold, as a fraction of the nominal one, unless the scene's
``threshold_mismatch`` sets its own ``floor_rel``."""

_EFFECT_STREAM = {effect: index for index, effect in enumerate(Effect)}
_AMPLIFIER_EFFECTS = {Effect.AMPLIFIER_OFFSET, Effect.AMPLIFIER_NOISE, Effect.SATURATION}


# The tag of the chip streams' spawn keys: five entries, never the length of an effect's key
# (two) or a noise key (three), so no chip stream is another stream.
_CHIP_TAG = 0xC41B


def effect_rng(
    seed: int,
    effect: Effect,
    taxel: int,
    recording: int | None = None,
    *,
    chip: int = 0,
    pool: int = 0,
):
    """The generator of one effect for one taxel (and one recording, for noise).

    Streams are independent across effects, taxels and recordings, and do not depend on which
    other effects a scene names or on the array size, so taxel 0 of a 3x3 and of a 5x5 scene see
    the same draws. A static effect of ``chip`` ``k > 0`` of chip ``pool`` ``p`` (0: the chips
    a design is tested on; 1: the training chips of a ``robust`` deployment) has the stream
    ``(effect, taxel, tag, p, k)``; chip 0 of pool 0 is the effect's own stream, so a scene of one
    chip draws what it drew before chips existed. Noise (``recording`` given) ignores the chip:
    it belongs to the recording, the same on every chip.
    """
    key: tuple[int, ...] = (_EFFECT_STREAM[effect], taxel)
    if recording is not None:
        key += (recording,)
    elif chip or pool:
        key += (_CHIP_TAG, pool, chip)
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


# ---------------------------------------------------------------------------------------------
# General (non-ideal) encoder


@kernel()
def _general_kernel(
    v, up_v, down_v, floor_v, noise_rng, noise_sigma_v, limit, times, polarity
):  # pragma: no cover - compiled
    """Reference-reset encoder with separate UP/DOWN thresholds and per-sample decision noise.

    Only the comparator on the signal's side of the reference can fire (the other one's
    threshold is at least ``floor_v`` > 0 away), so each sample draws one decision-noise value
    from ``noise_rng`` (``None``: no comparator noise) for that comparator. The two directions
    share one code path: ``(r - a) / (b - a)`` and ``r + (-down)`` are bit for bit
    ``(a - r) / (a - b)`` and ``r - down``. Writes while the buffers have room and returns the
    full count, as ``_ideal_kernel``, or stops at the first count above ``limit`` (a step
    far below the signal, or too small to move ``r`` at all, would otherwise loop for ever).
    """
    n = v.shape[0]
    capacity = times.shape[0]
    r = v[0]
    out = 0
    for i in range(1, n):
        a = v[i - 1]
        b = v[i]
        rising = b >= r
        sign = 1.0 if rising else -1.0
        step = up_v if rising else down_v
        if noise_rng is not None:
            step = max(step + noise_sigma_v * noise_rng.standard_normal(), floor_v)
        while sign * (b - r) >= step:
            r += sign * step
            if out < capacity:
                frac = (r - a) / (b - a) if b != a else 1.0
                times[out] = (i - 1) + min(max(frac, 0.0), 1.0)
                polarity[out] = np.int8(sign)
            out += 1
            if out > limit:
                return out
    return out


@kernel()
def _amplified(x, offset_v, noise_rng, noise_sigma_v, rail_v):  # pragma: no cover - compiled
    """``clip(x + offset_v + noise_sigma_v * z, -rail_v, rail_v)`` with ``z`` drawn from
    ``noise_rng`` sample by sample (none when it is ``None``); the same numbers, in the same
    order, as ``noise_rng.standard_normal(len(x))``, without the noise array."""
    v = np.empty_like(x)
    for i in range(x.shape[0]):
        a = x[i] + offset_v
        if noise_rng is not None:
            a = a + noise_sigma_v * noise_rng.standard_normal()
        v[i] = min(max(a, -rail_v), rail_v)
    return v


def real_train(
    v: np.ndarray,
    fs_hz: float,
    readout: ReadoutSpec,
    *,
    seed: int,
    taxel: int,
    recording: int,
    max_spikes: int = MAX_SPIKES_PER_TRAIN,
    chip: int | None = 0,
    pool: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """The REAL train of one taxel: the readout's effects applied to ``v``, then encoded.

    Parameters
    ----------
    v : float64 (n,)
        The taxel's signal in volts (after the front end and the taxel delay).
    fs_hz : float
        Sampling rate.
    readout : ReadoutSpec
        Threshold, full scale and the effects to simulate (only those named are).
    seed, taxel, recording : int
        Scene seed and indices from which every random draw is derived.
    chip, pool : int
        The chip whose static effects are drawn (:func:`effect_rng`); ``chip=None`` the
        nominal chip, whose static effects are all 0.

    Returns
    -------
    times_s : float64 (n_spikes,), polarity : int8 (n_spikes,)
        As :func:`~pipeline.chain.readout.level_crossings`. For an ideal readout, exactly its
        TRUE train.
    """
    effects = readout.effects
    if not effects:
        return true_train(v, fs_hz, readout, max_spikes=max_spikes)
    v = checked_signal(v)
    theta, theta_min = readout.threshold_v, readout.theta_min_v
    nominal = (theta, theta_min)

    def draw(effect: Effect, static: bool):
        if static and chip is None:
            return _NOMINAL
        if static and (chip or pool):
            return effect_rng(seed, effect, taxel, chip=chip, pool=pool)
        return effect_rng(seed, effect, taxel, None if static else recording)

    offset_v, amplifier_sigma_v, amplifier_rng, rail_v = 0.0, 0.0, None, math.inf
    if Effect.AMPLIFIER_OFFSET in effects:
        offset: AmplifierOffset = effects[Effect.AMPLIFIER_OFFSET]
        offset_v = offset.sigma_v * draw(Effect.AMPLIFIER_OFFSET, True).standard_normal()
    if Effect.AMPLIFIER_NOISE in effects:
        noise: AmplifierNoise = effects[Effect.AMPLIFIER_NOISE]
        amplifier_sigma_v, amplifier_rng = noise.sigma_v, draw(Effect.AMPLIFIER_NOISE, False)
    if Effect.SATURATION in effects:
        saturation: Saturation = effects[Effect.SATURATION]
        rail_v = saturation.rail_v if saturation.rail_v is not None else readout.full_scale_v / 2
    if effects.keys() & _AMPLIFIER_EFFECTS:
        v = _amplified(v, offset_v, amplifier_rng, amplifier_sigma_v, rail_v)

    mismatch: ThresholdMismatch | None = effects.get(Effect.THRESHOLD_MISMATCH)
    # The floor is relative to the smallest nominal threshold (threshold_v for a fixed one).
    floor_v = (THRESHOLD_FLOOR_REL if mismatch is None else mismatch.floor_rel) * theta_min
    scale = 1.0
    if mismatch is not None:  # one draw scales the whole threshold curve of the taxel
        scale = 1.0 + mismatch.sigma_rel * draw(Effect.THRESHOLD_MISMATCH, True).standard_normal()
    curve = nominal
    if mismatch is not None:
        # Both ends by the same product: rounding is monotone, so theta_0 >= theta_min holds for
        # the taxel too (equal when threshold_v is theta_min_v), with the floor as well.
        curve = (max(theta * scale, floor_v), max(theta_min * scale, floor_v))

    comparator_offset = effects.get(Effect.COMPARATOR_OFFSET)
    comparator_noise = effects.get(Effect.COMPARATOR_NOISE)
    if comparator_offset is None and comparator_noise is None:
        return _encode(v, fs_hz, readout, curve, None, floor_v, None, max_spikes)
    up = down = curve
    if comparator_offset is not None:
        c_up, c_down = comparator_offset.sigma_v * draw(
            Effect.COMPARATOR_OFFSET, True
        ).standard_normal(2)
        up = (max(curve[0] + c_up, floor_v), max(curve[1] + c_up, floor_v))
        down = (max(curve[0] + c_down, floor_v), max(curve[1] + c_down, floor_v))
    decision_noise = None
    if comparator_noise is not None:
        decision_noise = (comparator_noise.sigma_v, lambda: draw(Effect.COMPARATOR_NOISE, False))
    return _encode(v, fs_hz, readout, up, down, floor_v, decision_noise, max_spikes)


class _Nominal:
    """The draws of the nominal chip: every static effect at exactly 0."""

    @staticmethod
    def standard_normal(size: int | None = None):
        return 0.0 if size is None else np.zeros(size)


_NOMINAL = _Nominal()


def true_train(
    v: np.ndarray, fs_hz: float, readout: ReadoutSpec, *, max_spikes: int = MAX_SPIKES_PER_TRAIN
) -> tuple[np.ndarray, np.ndarray]:
    """The TRUE train of ``v`` by the readout's ideal encoder
    (:func:`~pipeline.chain.readout.level_crossings` or
    :func:`~pipeline.chain.readout.decaying_crossings`, by ``readout.encoder``) at its nominal
    thresholds."""
    nominal = (readout.threshold_v, readout.theta_min_v)
    return _encode(v, fs_hz, readout, nominal, None, 0.0, None, max_spikes)


def true_trains(
    rows: np.ndarray, fs_hz: float, readout: ReadoutSpec
) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`true_train` of every row of ``rows`` (float64 ``(n_rows, n)``, the taxels of one
    recording); the fixed encoder encodes them all in one kernel call
    (:func:`~pipeline.chain.readout.level_crossings_rows`)."""
    if readout.encoder is Encoder.LCS:
        return level_crossings_rows(rows, fs_hz, readout.threshold_v)
    return [true_train(row, fs_hz, readout) for row in rows]


def _encode(v, fs_hz, readout, up, down, floor_v, noise, max_spikes):
    """Encode ``v`` with the readout's encoder at UP and DOWN ``(theta_0, theta_min)``
    thresholds (equal for a fixed encoder), floor ``floor_v`` and decision ``noise``
    (``(sigma_v, rng factory)`` or None). ``down=None`` (no comparator effect): both
    comparators at ``up`` without noise, which :func:`~pipeline.chain.readout.level_crossings`
    computes for the fixed encoder."""
    if readout.encoder is Encoder.DECAYING:
        v = checked_signal(v)  # the decaying kernel does not look for non-finite samples
        down = up if down is None else down
        return decaying_train(v, fs_hz, up, down, readout.decay.tau_s, max_spikes, floor_v, noise)
    if down is None:
        return level_crossings(v, fs_hz, up[0], max_spikes=max_spikes)

    def call(rng, sigma_v, times, polarity):
        return _general_kernel(
            v, up[0], down[0], floor_v, rng, sigma_v, max_spikes, times, polarity
        )

    return run_noisy(call, noise, fs_hz, max_spikes, v)
