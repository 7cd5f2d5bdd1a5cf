r"""Continuous-time level-crossing readout: the TRUE (ideal) and REAL (non-ideal) spike trains.

Ideal encoder (the TRUE train)
------------------------------
Between samples the signal is the straight line through them. With ``u(t) = (v(t) - v_0) / theta``
the signal in units of the threshold (computed as ``(v - v_0) * (1 / theta)`` in float64, the
same way in every code path), the reference sits on the lattice of integers ``k`` and
starts at ``k = 0``. Whenever ``u`` reaches ``k + 1`` a +1 spike is emitted and ``k`` grows by
one; whenever it reaches ``k - 1`` a -1 spike is emitted and ``k`` shrinks by one. Reaching a level
counts (``>=``). Sample by sample this is the play (backlash) operator

    k_n = clip(k_{n-1}, floor(u_n), ceil(u_n))

and a segment from ``u_{n-1}`` to ``u_n`` emits one spike per level it crosses, each at its own
interpolated time ``t = (n - 1 + (m - u_{n-1}) / (u_n - u_{n-1})) / fs``, in time order. Times are
computed from the integer sample index, so they keep sub-nanosecond precision for hours of
recording at kHz rates.

Non-ideal encoder (the REAL train)
----------------------------------
The scene's effects act in this order (each only when the scene names it)::

    v_t      = x_t + o_t (amplifier_offset, per taxel)  + n_t[i] (amplifier_noise, per sample)
    v_t      = clip(v_t, -rail, +rail)                                          (saturation)
    theta_t  = theta * (1 + sigma_rel * z_t)                     (threshold_mismatch, per taxel)
    up, down = theta_t + c_up_t, theta_t + c_down_t              (comparator_offset, per taxel)
    decision at sample i: v[i] - r >= up + e_up[i]   /   r - v[i] >= down + e_down[i]
                                                        (comparator_noise, per sample)

Every effective threshold is clipped below at ``THRESHOLD_FLOOR_REL * theta``: mismatch or
offsets that would push a threshold to zero or below leave the comparator at the smallest step it
can resolve, so the train stays finite. With equal UP and DOWN thresholds and no comparator noise
the REAL train is the ideal encoder run with ``theta_t`` on ``v_t``. Otherwise the reference
follows the DVS-style rule: on a spike it resets to the level that was crossed (``r +- up/down``
including the decision noise), and a sample's noise applies to every level crossed in its segment.

Randomness
----------
Static effects (offsets, mismatch) are properties of the chip: they are drawn from
``effect_rng(seed, effect, taxel)``, the same for every recording. Noise is drawn from
``effect_rng(seed, effect, taxel, recording)``. No generator is created for an effect that is not
named, so an ideal scene draws no random numbers and its REAL train is its TRUE train.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from pipeline.errors import SimulationError
from pipeline.scene import (
    AmplifierNoise,
    AmplifierOffset,
    Effect,
    ReadoutSpec,
    Saturation,
    ThresholdMismatch,
)

THRESHOLD_FLOOR_REL = 0.1
"""Smallest effective threshold, as a fraction of the nominal one."""

MAX_SPIKES_PER_TRAIN = 20_000_000
"""Default cap on one train's length (180 MB of events); more is an error, not an explosion."""

_EFFECT_STREAM = {effect: index for index, effect in enumerate(Effect)}

# First-pass buffer size: one spike per this many samples covers the trains of ordinary scenes
# (the paper's operating point emits about one per 16); longer trains cost a second pass.
_TYPICAL_SAMPLES_PER_SPIKE = 4


def effect_rng(seed: int, effect: Effect, taxel: int, recording: int | None = None):
    """The generator of one effect for one taxel (and one recording, for noise).

    Streams are independent across effects, taxels and recordings, and do not depend on which
    other effects a scene names or on the array size, so taxel 0 of a 3x3 and of a 5x5 scene see
    the same draws.
    """
    key = (_EFFECT_STREAM[effect], taxel) + (() if recording is None else (recording,))
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


# ---------------------------------------------------------------------------------------------
# Ideal encoder


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _ideal_kernel(v, inv_threshold, times, polarity):  # pragma: no cover - compiled
    """Emit the ideal train into ``times``/``polarity`` while it fits; return the full count.

    Spikes beyond the buffers' capacity are counted, not written, so an empty buffer makes a
    cheap counting pass. Times are in samples; ``u`` uses the same arithmetic in every pass.
    A non-finite sample ``i`` returns ``-(i + 1)`` instead of a count.
    """
    n = v.shape[0]
    capacity = times.shape[0]
    v0 = v[0]
    if v0 - v0 != 0.0:  # NaN or +-inf
        return -1
    k = 0.0
    above = 1.0  # the next levels up and down: k + 1 and k - 1
    below = -1.0
    u_prev = 0.0
    out = 0
    for i in range(1, n):
        u = (v[i] - v0) * inv_threshold
        if u < above and u > below:  # the common case: no level reached
            u_prev = u
            continue
        if u - u != 0.0:  # NaN fails both comparisons above; +-inf lands here too
            return -(i + 1)
        if u >= above:
            top = np.floor(u)
            if out + (top - k) <= capacity:
                m = above
                while m <= top:
                    times[out] = (i - 1) + (m - u_prev) / (u - u_prev)
                    polarity[out] = 1
                    out += 1
                    m += 1.0
            else:
                out += int(top - k)
            k = top
        else:
            bottom = np.ceil(u)
            if out + (k - bottom) <= capacity:
                m = below
                while m >= bottom:
                    times[out] = (i - 1) + (u_prev - m) / (u_prev - u)
                    polarity[out] = -1
                    out += 1
                    m -= 1.0
            else:
                out += int(k - bottom)
            k = bottom
        above = k + 1.0
        below = k - 1.0
        u_prev = u
    return out


def level_crossings(
    v: np.ndarray,
    fs_hz: float,
    threshold_v: float,
    *,
    max_spikes: int = MAX_SPIKES_PER_TRAIN,
) -> tuple[np.ndarray, np.ndarray]:
    """Ideal continuous-time level-crossing encoder (the TRUE train).

    Parameters
    ----------
    v : float64 (n,)
        Signal samples in volts, finite.
    fs_hz : float
        Sampling rate, > 0.
    threshold_v : float
        Level spacing theta in volts, > 0.
    max_spikes : int
        Cap on the train's length; see :data:`MAX_SPIKES_PER_TRAIN`.

    Returns
    -------
    times_s : float64 (n_spikes,)
        Crossing times in seconds from the first sample, non-decreasing.
    polarity : int8 (n_spikes,)
        +1 for an upward crossing, -1 for a downward one.

    Raises
    ------
    ValueError
        For a non-positive threshold or sampling rate, or a non-finite sample.
    SimulationError
        If the train would hold more than ``max_spikes`` spikes (threshold tiny against the
        signal); the message gives the count.
    """
    v = _as_signal(v)
    _check_positive(fs_hz=fs_hz, threshold_v=threshold_v)
    return _run(_ideal_kernel, fs_hz, max_spikes, v, 1.0 / threshold_v)


def reference_level_crossings(
    v: np.ndarray, fs_hz: float, threshold_v: float
) -> tuple[np.ndarray, np.ndarray]:
    """The ideal encoder as a per-sample pure-Python loop: the specification, slowly.

    Same arithmetic as :func:`level_crossings` (which must agree with it exactly); kept as the
    test oracle and as the benchmark's baseline.
    """
    v0 = float(v[0])
    inv_threshold = 1.0 / threshold_v
    k = 0.0
    u_prev = 0.0
    times: list[float] = []
    polarity: list[int] = []
    for i in range(1, len(v)):
        u = (float(v[i]) - v0) * inv_threshold
        while u >= k + 1.0:
            k += 1.0
            times.append(((i - 1) + (k - u_prev) / (u - u_prev)) / fs_hz)
            polarity.append(1)
        while u <= k - 1.0:
            k -= 1.0
            times.append(((i - 1) + (u_prev - k) / (u_prev - u)) / fs_hz)
            polarity.append(-1)
        u_prev = u
    return np.array(times, dtype=np.float64), np.array(polarity, dtype=np.int8)


# ---------------------------------------------------------------------------------------------
# General (non-ideal) encoder


@numba.njit(cache=True, nogil=True)
def _general_kernel(
    v, up_v, down_v, up_noise, down_noise, floor_v, times, polarity
):  # pragma: no cover - compiled
    """Reference-reset encoder with separate UP/DOWN thresholds and per-sample decision noise.

    ``up_noise``/``down_noise`` are empty when the scene has no comparator noise. Writes while
    the buffers have room and returns the full count, as :func:`_ideal_kernel`.
    """
    n = v.shape[0]
    capacity = times.shape[0]
    noisy = up_noise.shape[0] > 0
    r = v[0]
    out = 0
    for i in range(1, n):
        up = up_v + up_noise[i] if noisy else up_v
        down = down_v + down_noise[i] if noisy else down_v
        up = max(up, floor_v)
        down = max(down, floor_v)
        a = v[i - 1]
        b = v[i]
        while b - r >= up:
            r += up
            if out < capacity:
                frac = (r - a) / (b - a) if b != a else 1.0
                times[out] = (i - 1) + min(max(frac, 0.0), 1.0)
                polarity[out] = 1
            out += 1
        while r - b >= down:
            r -= down
            if out < capacity:
                frac = (a - r) / (a - b) if b != a else 1.0
                times[out] = (i - 1) + min(max(frac, 0.0), 1.0)
                polarity[out] = -1
            out += 1
    return out


def _run(kernel, fs_hz: float, max_spikes: int, v: np.ndarray, *params) -> tuple:
    """Encode in one pass into a buffer sized for typical trains; if the train is longer, check
    the cap and encode again into buffers of the exact size. Times become seconds."""
    capacity = min(max(len(v) // _TYPICAL_SAMPLES_PER_SPIKE, 1024), max_spikes)
    times = np.empty(capacity, dtype=np.float64)
    polarity = np.empty(capacity, dtype=np.int8)
    n = kernel(v, *params, times, polarity)
    if n < 0:
        _raise_non_finite(v, -n - 1)
    if n > max_spikes:
        raise SimulationError(
            f"the readout would emit {n:,} spikes in one taxel's train (limit {max_spikes:,}): "
            "the threshold is too small for this signal"
        )
    if n > capacity:
        times = np.empty(n, dtype=np.float64)
        polarity = np.empty(n, dtype=np.int8)
        kernel(v, *params, times, polarity)
    else:
        times, polarity = times[:n].copy(), polarity[:n].copy()
    times /= fs_hz
    return times, polarity


def _as_signal(v: np.ndarray) -> np.ndarray:
    v = np.ascontiguousarray(v, dtype=np.float64)
    if v.ndim != 1:
        raise ValueError(f"signal must be 1-D, got shape {v.shape}")
    return v


def _raise_non_finite(v: np.ndarray, index: int) -> None:
    raise ValueError(f"signal has a non-finite sample ({v[index]}) at index {index}")


def _checked_signal(v: np.ndarray) -> np.ndarray:
    """A 1-D float64 signal whose samples are all finite (for paths without the kernel check)."""
    v = _as_signal(v)
    if not np.all(np.isfinite(v)):
        _raise_non_finite(v, int(np.flatnonzero(~np.isfinite(v))[0]))
    return v


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def real_train(
    v: np.ndarray,
    fs_hz: float,
    readout: ReadoutSpec,
    *,
    seed: int,
    taxel: int,
    recording: int,
    max_spikes: int = MAX_SPIKES_PER_TRAIN,
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

    Returns
    -------
    times_s : float64 (n_spikes,), polarity : int8 (n_spikes,)
        As :func:`level_crossings`. For an ideal readout, exactly its TRUE train.
    """
    effects = readout.effects
    theta = readout.threshold_v
    if not effects:
        return level_crossings(v, fs_hz, theta, max_spikes=max_spikes)
    v = _checked_signal(v)

    def draw(effect: Effect, static: bool):
        return effect_rng(seed, effect, taxel, None if static else recording)

    if Effect.AMPLIFIER_OFFSET in effects:
        offset: AmplifierOffset = effects[Effect.AMPLIFIER_OFFSET]
        v = v + offset.sigma_v * draw(Effect.AMPLIFIER_OFFSET, True).standard_normal()
    if Effect.AMPLIFIER_NOISE in effects:
        noise: AmplifierNoise = effects[Effect.AMPLIFIER_NOISE]
        v = v + noise.sigma_v * draw(Effect.AMPLIFIER_NOISE, False).standard_normal(len(v))
    if Effect.SATURATION in effects:
        saturation: Saturation = effects[Effect.SATURATION]
        rail = saturation.rail_v if saturation.rail_v is not None else readout.full_scale_v / 2
        v = np.clip(v, -rail, rail)

    floor_v = THRESHOLD_FLOOR_REL * theta
    taxel_theta = theta
    if Effect.THRESHOLD_MISMATCH in effects:
        mismatch: ThresholdMismatch = effects[Effect.THRESHOLD_MISMATCH]
        z = draw(Effect.THRESHOLD_MISMATCH, True).standard_normal()
        taxel_theta = max(theta * (1.0 + mismatch.sigma_rel * z), floor_v)

    comparator_offset = effects.get(Effect.COMPARATOR_OFFSET)
    comparator_noise = effects.get(Effect.COMPARATOR_NOISE)
    if comparator_offset is None and comparator_noise is None:
        return _run(_ideal_kernel, fs_hz, max_spikes, v, 1.0 / taxel_theta)

    up_v = down_v = taxel_theta
    if comparator_offset is not None:
        c_up, c_down = draw(Effect.COMPARATOR_OFFSET, True).standard_normal(2)
        up_v = max(taxel_theta + comparator_offset.sigma_v * c_up, floor_v)
        down_v = max(taxel_theta + comparator_offset.sigma_v * c_down, floor_v)
    if comparator_noise is not None:
        decision = draw(Effect.COMPARATOR_NOISE, False).standard_normal((2, len(v)))
        decision *= comparator_noise.sigma_v
        up_noise, down_noise = decision[0], decision[1]
    else:
        up_noise = down_noise = np.empty(0, np.float64)
    return _run(_general_kernel, fs_hz, max_spikes, v, up_v, down_v, up_noise, down_noise, floor_v)
