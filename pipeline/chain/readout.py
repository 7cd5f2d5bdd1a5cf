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
    decision at sample i: v[i] - r >= up + e[i]  if v[i] >= r,  else  r - v[i] >= down + e[i]
                                                        (comparator_noise, per sample)

Every effective threshold is clipped below at ``floor_rel * theta`` (``threshold_mismatch``'s
``floor_rel`` when the scene names it, else :data:`THRESHOLD_FLOOR_REL`): mismatch or offsets
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
``effect_rng(seed, effect, taxel)``, the same for every recording. Noise is drawn from
``effect_rng(seed, effect, taxel, recording)``, one value per sample in time order, drawn inside
the compiled loops (the same numbers as ``standard_normal(n_samples)``, without the array). No
generator is created for an effect that is not named, so an ideal scene draws no random numbers
and its REAL train is its TRUE train.
"""

from __future__ import annotations

import math

import numpy as np

from pipeline.chain.jit import kernel
from pipeline.design.scene import (
    AmplifierNoise,
    AmplifierOffset,
    Effect,
    ReadoutSpec,
    Saturation,
    ThresholdMismatch,
)
from pipeline.errors import SimulationError

THRESHOLD_FLOOR_REL = 0.1
"""Smallest effective threshold, as a fraction of the nominal one, unless the scene's
``threshold_mismatch`` sets its own ``floor_rel``."""

MAX_SPIKES_PER_TRAIN = 20_000_000
"""Default cap on one train's length (180 MB of events); more is an error, not an explosion."""

_EFFECT_STREAM = {effect: index for index, effect in enumerate(Effect)}
_AMPLIFIER_EFFECTS = {Effect.AMPLIFIER_OFFSET, Effect.AMPLIFIER_NOISE, Effect.SATURATION}

# Samples the ideal kernel encodes per block: the block and its event list (1 MB together) stay
# in the cache between the kernel's two passes.
_BLOCK_SAMPLES = 1 << 16

# Spike counts saturate here (any train this long is over every cap), so int64 cannot overflow.
_COUNT_LIMIT = 2**61

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


@kernel(error_model="numpy", inline="always")
def _level(k, u):  # pragma: no cover - compiled
    """``clip(k, floor(u), ceil(u))``, branch-free; a NaN ``u`` gives NaN (so it is an event)."""
    at_least = k if k > np.floor(u) else np.floor(u)
    return at_least if at_least < np.ceil(u) else np.ceil(u)


@kernel(error_model="numpy", inline="always")
def _scan_lane(v, v0, inv_threshold, i, k, events, out):  # pragma: no cover - compiled
    """One sample of a lane: the new level, and where the next event index goes."""
    k_new = _level(k, (v[i] - v0) * inv_threshold)
    events[out] = i  # written every time, kept only when the level moved: no branch
    return k_new, out + (k_new != k)


@kernel(error_model="numpy", inline="always")
def _emit(v, v0, inv_threshold, i, k, times, polarity, out):  # pragma: no cover - compiled
    """Apply sample ``i`` to level ``k``: write its spikes while they fit; return the new level
    and count, or NaN and ``-(i + 1)`` for a non-finite sample."""
    u = (v[i] - v0) * inv_threshold
    if u - u != 0.0:
        return np.nan, -(i + 1)
    k_new = _level(k, u)
    if k_new == k:
        return k, out
    levels = abs(k_new - k)
    if out + levels > times.shape[0]:  # counted, not written; saturating, so never overflows
        return k_new, min(out + int(min(levels, _COUNT_LIMIT)), _COUNT_LIMIT)
    # One code path for both directions: m - u_prev over u - u_prev is, bit for bit, the
    # reference's u_prev - m over u_prev - u, and k + (-1.0) is k - 1.0.
    step = 1.0 if k_new > k else -1.0
    u_prev = (v[i - 1] - v0) * inv_threshold
    m = k
    while m != k_new:
        m += step
        times[out] = (i - 1) + (m - u_prev) / (u - u_prev)
        polarity[out] = np.int8(step)
        out += 1
    return k_new, out


@kernel(error_model="numpy")
def _encode_block(
    v, v0, inv_threshold, start, stop, k, events, times, polarity, out
):  # pragma: no cover - compiled
    """Samples ``start:stop`` from true level ``k``: return the new level and count (or NaN and
    ``-(i + 1)`` for a non-finite sample ``i``).

    Pass 1 runs the branch-free level chain on the four quarters of the block at once, to
    overlap their latencies, and records where each quarter's level moves. The first quarter
    starts from ``k``, the others from a guess; pass 2 walks each quarter's samples in order
    from the true level only until it meets the guessed trajectory (the play operator forgets
    its start once both agree, usually within a few spikes), then visits only the recorded
    samples, where it computes the spike times.
    """
    lane = (stop - start) // 4  # samples per quarter; the last one also takes the remainder
    first = (start, start + lane, start + 2 * lane, start + 3 * lane, stop)
    guess = np.empty(4)
    guess[0] = k
    for q in range(1, 4):
        guess[q] = np.floor((v[first[q] - 1] - v0) * inv_threshold)
    k0, k1, k2, k3 = guess[0], guess[1], guess[2], guess[3]
    e0, e1, e2, e3 = 0, lane, 2 * lane, 3 * lane  # quarter q records into events[q * lane:]
    for j in range(lane):
        k0, e0 = _scan_lane(v, v0, inv_threshold, first[0] + j, k0, events, e0)
        k1, e1 = _scan_lane(v, v0, inv_threshold, first[1] + j, k1, events, e1)
        k2, e2 = _scan_lane(v, v0, inv_threshold, first[2] + j, k2, events, e2)
        k3, e3 = _scan_lane(v, v0, inv_threshold, first[3] + j, k3, events, e3)
    for i in range(first[3] + lane, stop):
        k3, e3 = _scan_lane(v, v0, inv_threshold, i, k3, events, e3)
    ends = (e0, e1, e2, e3)

    for q in range(4):
        e = q * lane
        i = first[q]
        guessed = guess[q]
        while guessed != k and i < first[q + 1]:  # until the true level meets the guess
            guessed = _level(guessed, (v[i] - v0) * inv_threshold)
            if e < ends[q] and events[e] == i:
                e += 1
            k, out = _emit(v, v0, inv_threshold, i, k, times, polarity, out)
            if out < 0:
                return k, out
            i += 1
        for recorded in range(e, ends[q]):
            k, out = _emit(v, v0, inv_threshold, events[recorded], k, times, polarity, out)
            if out < 0:
                return k, out
    return k, out


@kernel(error_model="numpy")
def _ideal_kernel(v, inv_threshold, times, polarity):  # pragma: no cover - compiled
    """Emit the ideal train into ``times``/``polarity`` while it fits; return the full count.

    Spikes beyond the buffers' capacity are counted, not written, so an empty buffer makes a
    cheap counting pass. Times are in samples; ``u`` uses the same arithmetic in every pass.
    A non-finite sample ``i`` returns ``-(i + 1)`` instead of a count.

    Why blocks of two passes: the level ``k_i = clip(k_{i-1}, floor(u_i), ceil(u_i))`` is a
    chain that a branchy loop mispredicts at every spike (~15 ns each) and a branch-free loop
    waits on (max then min per sample); see :func:`_encode_block`. Blocks keep the samples in
    cache between the two passes.
    """
    n = v.shape[0]
    if n == 0:
        return 0
    v0 = v[0]
    if v0 - v0 != 0.0:  # NaN or +-inf
        return -1
    events = np.empty(min(n, _BLOCK_SAMPLES), dtype=np.int64)
    k = 0.0
    out = 0
    for start in range(1, n, _BLOCK_SAMPLES):
        stop = min(start + _BLOCK_SAMPLES, n)
        k, out = _encode_block(v, v0, inv_threshold, start, stop, k, events, times, polarity, out)
        if out < 0:
            break
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
        signal); the message gives a lower bound of the count.
    """
    v = _as_signal(v)
    _check_positive(fs_hz=fs_hz, threshold_v=threshold_v)
    inv_threshold = 1.0 / threshold_v
    return _run(lambda t, p: _ideal_kernel(v, inv_threshold, t, p), fs_hz, max_spikes, v)


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
    full count, as :func:`_ideal_kernel`, or stops at the first count above ``limit`` (a step
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


def _run(emit, fs_hz: float, max_spikes: int, v: np.ndarray) -> tuple:
    """Encode ``v`` with ``emit(times, polarity) -> count`` (a kernel call) into a buffer sized
    for typical trains; if the train is longer, check the cap and call ``emit`` again with buffers
    of the exact size (so ``emit`` must give the same train every call). Times become seconds."""
    capacity = min(max(len(v) // _TYPICAL_SAMPLES_PER_SPIKE, 1024), max_spikes)
    times = np.empty(capacity, dtype=np.float64)
    polarity = np.empty(capacity, dtype=np.int8)
    n = emit(times, polarity)
    if n < 0:
        _raise_non_finite(v, -n - 1)
    if n > max_spikes:
        raise SimulationError(
            f"the readout would emit at least {n:,} spikes in one taxel's train "
            f"(limit {max_spikes:,}): "
            "the threshold is too small for this signal"
        )
    if n > capacity:
        times = np.empty(n, dtype=np.float64)
        polarity = np.empty(n, dtype=np.int8)
        emit(times, polarity)
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
    floor_v = (THRESHOLD_FLOOR_REL if mismatch is None else mismatch.floor_rel) * theta
    taxel_theta = theta
    if mismatch is not None:
        z = draw(Effect.THRESHOLD_MISMATCH, True).standard_normal()
        taxel_theta = max(theta * (1.0 + mismatch.sigma_rel * z), floor_v)

    comparator_offset = effects.get(Effect.COMPARATOR_OFFSET)
    comparator_noise = effects.get(Effect.COMPARATOR_NOISE)
    if comparator_offset is None and comparator_noise is None:
        return level_crossings(v, fs_hz, taxel_theta, max_spikes=max_spikes)

    up_v = down_v = taxel_theta
    if comparator_offset is not None:
        c_up, c_down = draw(Effect.COMPARATOR_OFFSET, True).standard_normal(2)
        up_v = max(taxel_theta + comparator_offset.sigma_v * c_up, floor_v)
        down_v = max(taxel_theta + comparator_offset.sigma_v * c_down, floor_v)
    decision_sigma_v = 0.0 if comparator_noise is None else comparator_noise.sigma_v

    def emit(times: np.ndarray, polarity: np.ndarray) -> int:
        # A fresh generator per call: a second pass must see the same decision noise.
        decision_rng = None if comparator_noise is None else draw(Effect.COMPARATOR_NOISE, False)
        return _general_kernel(
            v, up_v, down_v, floor_v, decision_rng, decision_sigma_v, max_spikes, times, polarity
        )

    return _run(emit, fs_hz, max_spikes, v)
