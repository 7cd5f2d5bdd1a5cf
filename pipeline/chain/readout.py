r"""Continuous-time level-crossing readout: the TRUE (ideal) and REAL (non-ideal) spike trains.

Ideal encoder (the TRUE train)
------------------------------
Between samples the signal is the straight line through them. With ``u(t) = (v(t) - v_0) / theta``
the signal in units of the threshold (computed as ``(v - v_0) * (1 / theta)`` in float64, the
same way in every code path), the reference sits on the lattice of integers ``k`` and
starts at ``k = 0``. Whenever ``u`` reaches ``k + 1`` a +1 spike is emitted and ``k`` grows by
one; whenever it reaches ``k - 1`` a -1 spike is emitted and ``k`` shrinks by one. Reaching a level
counts (``>=``). Sample by sample this is the play (backlash) operator

.. math::

    k_n = \operatorname{clip}(k_{n-1}, \lfloor u_n \rfloor, \lceil u_n \rceil)

and a segment from ``u_{n-1}`` to ``u_n`` emits one spike per level it crosses, each at its own
interpolated time ``t = (n - 1 + (m - u_{n-1}) / (u_n - u_{n-1})) / fs``, in time order. Times are
computed from the integer sample index, so they keep sub-nanosecond precision for hours of
recording at kHz rates.

Decaying-threshold encoder
--------------------------
``readout.encoder = "decaying"`` (as in the decaying-threshold encoder of Alea et al., IEEE
TBioCAS 2024): the reference ``r`` starts at the first sample and the threshold is

.. math::

    \theta(t) = \theta_{\min} + (\theta_0 - \theta_{\min}) \, e^{-(t - t_\mathrm{last}) / \tau}

with ``t_last`` the time of the last spike (0 at the start). A +1 spike is emitted at the first
instant the interpolated signal reaches ``r + theta(t)``, a -1 spike at ``r - theta(t)``; the spike
moves ``r`` by that ``theta(t)`` and sets ``t_last``. Within a segment the condition is a line
minus a decaying exponential, which is concave, so its first root has a closed-form bracket and is
solved by safeguarded Newton steps in continuous time (see ``_first_reach``); a segment may
hold several spikes. ``theta_min = theta_0`` is the fixed encoder.

The scene's effects around these encoders (the REAL train), and the TRUE train of a scene's
encoder, are :mod:`pipeline.chain.readout_effects`.
"""

from __future__ import annotations

import math

import numpy as np

from pipeline.errors import SimulationError
from pipeline.jit import kernel

MAX_SPIKES_PER_TRAIN = 20_000_000
"""Default cap on one train's length (180 MB of events); more is an error, not an explosion."""


# Samples the ideal kernel encodes per block: the block and its event list (1 MB together) stay
# in the cache between the kernel's two passes.
_BLOCK_SAMPLES = 1 << 16

# Spike counts saturate here (any train this long is over every cap), so int64 cannot overflow.
_COUNT_LIMIT = 2**61

# First-pass buffer size: one spike per this many samples covers the trains of ordinary scenes
# (the paper's operating point emits about one per 16); longer trains cost a second pass.
_TYPICAL_SAMPLES_PER_SPIKE = 4


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


@kernel(error_model="numpy")
def _ideal_rows_kernel(rows, inv_threshold, times, polarity, counts):  # pragma: no cover - compiled
    """:func:`_ideal_kernel` on every row of ``rows``, row ``r`` into ``times[r]`` and
    ``polarity[r]``, its full count (or ``-(i + 1)``) into ``counts[r]``."""
    for r in range(rows.shape[0]):
        counts[r] = _ideal_kernel(rows[r], inv_threshold, times[r], polarity[r])


def level_crossings_rows(
    rows: np.ndarray,
    fs_hz: float,
    threshold_v: float,
    *,
    max_spikes: int = MAX_SPIKES_PER_TRAIN,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`level_crossings` of every row of ``rows`` (float64 ``(n_rows, n)``: the taxels of
    one recording), in one kernel call: the same trains, bit for bit, without a call per row.
    A row whose train outgrows the typical buffer, or that holds a non-finite sample, is
    encoded again on its own (its exact buffer, or its error)."""
    rows = np.ascontiguousarray(rows, dtype=np.float64)
    if rows.ndim != 2:
        raise ValueError(f"rows must be 2-D, got shape {rows.shape}")
    _check_positive(fs_hz=fs_hz, threshold_v=threshold_v)
    capacity = min(max(rows.shape[1] // _TYPICAL_SAMPLES_PER_SPIKE, 1024), max_spikes)
    times = np.empty((rows.shape[0], capacity), dtype=np.float64)
    polarity = np.empty((rows.shape[0], capacity), dtype=np.int8)
    counts = np.empty(rows.shape[0], dtype=np.int64)
    _ideal_rows_kernel(rows, 1.0 / threshold_v, times, polarity, counts)
    trains = []
    for row, count in enumerate(counts.tolist()):
        if not 0 <= count <= capacity:
            trains.append(level_crossings(rows[row], fs_hz, threshold_v, max_spikes=max_spikes))
            continue
        trains.append((times[row, :count] / fs_hz, polarity[row, :count].copy()))
    return trains


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
# Decaying-threshold encoder


@kernel(error_model="numpy", inline="always")
def _gap(x0, m, theta_min, swing, s_ref, tau, s):  # pragma: no cover - compiled
    """``f(s) = x0 + m * s - theta(s)``: how far the signal is past the level at local time
    ``s``, with ``theta(s) = theta_min + swing * exp((s_ref - s) / tau)``."""
    return x0 + m * s - (theta_min + swing * math.exp((s_ref - s) / tau))


@kernel(error_model="numpy")
def _first_reach(x0, m, theta_min, swing, s_ref, tau, lo):  # pragma: no cover - compiled
    """The first ``s`` in ``[lo, 1]`` where ``f(s) = x0 + m * s - theta(s) >= 0``
    (:func:`_gap`), or -1.0 if there is none.

    ``f`` is a line minus a decaying exponential, so ``f' = m + swing * w(s) / tau`` falls with
    ``s`` (``f`` is concave). Rising (``m >= 0``) it increases on the whole segment; falling,
    it increases up to ``s*`` where ``w(s*) = -m * tau / swing`` and falls after. Either way the
    first root, if any, lies in ``[lo, hi]`` with ``hi = min(s*, 1)`` and ``f`` increasing there:
    a guaranteed bracket, solved by Newton steps kept inside it (bisection when one leaves).
    """
    hi = 1.0
    if m < 0.0:
        hi = lo
        if swing > 0.0:
            hi = min(max(s_ref + tau * math.log(swing / (-m * tau)), lo), 1.0)
    f_hi = _gap(x0, m, theta_min, swing, s_ref, tau, hi)
    if f_hi < 0.0:
        return -1.0
    f_lo = _gap(x0, m, theta_min, swing, s_ref, tau, lo)
    if f_lo >= 0.0:
        return lo
    s = lo - f_lo * (hi - lo) / (f_hi - f_lo)  # the chord's root, inside the bracket
    for _ in range(200):
        f = _gap(x0, m, theta_min, swing, s_ref, tau, s)
        if f == 0.0:
            return s
        if f > 0.0:
            hi = s
        else:
            lo = s
        if hi - lo <= 4e-16:
            break
        step = f / (m + swing * math.exp((s_ref - s) / tau) / tau)
        if abs(step) <= 1e-15 and lo < s - step < hi:
            return s - step  # Newton from one side converges without shrinking the bracket
        s = s - step if lo < s - step < hi else 0.5 * (lo + hi)
    return hi


@kernel(error_model="numpy")
def _decaying_kernel(
    v,
    up0_v,
    up_min_v,
    down0_v,
    down_min_v,
    floor_v,
    tau,
    noise_rng,
    noise_sigma_v,
    limit,
    times,
    polarity,
):  # pragma: no cover - compiled
    """Decaying-threshold encoder with separate UP/DOWN threshold curves and decision noise.

    The UP threshold is ``up_min + (up0 - up_min) * exp(-(t - t_last) / tau)`` (``tau`` in
    samples), the DOWN one likewise; one decision-noise value per sample (drawn from
    ``noise_rng``, ``None``: none) shifts both ends of both curves in that sample's segment,
    each clipped below at ``floor_v``. A spike moves ``r`` by the threshold it crossed and
    restarts the decay. Segments whose ends stay closer to ``r`` than the lowest threshold are
    skipped without evaluating the exponential, and those closer than the thresholds at their
    end with one evaluation. Writes while the buffers have room and returns
    the full count, or stops at the first count above ``limit``, as :func:`_general_kernel`.
    """
    n = v.shape[0]
    capacity = times.shape[0]
    r = v[0]
    t_last = 0.0  # samples from the first sample
    out = 0
    for i in range(1, n):
        a = v[i - 1]
        b = v[i]
        e = 0.0 if noise_rng is None else noise_sigma_v * noise_rng.standard_normal()
        up_min = max(up_min_v + e, floor_v)
        down_min = max(down_min_v + e, floor_v)
        high = max(a, b) - r
        low = r - min(a, b)
        if high < up_min and low < down_min:
            continue
        up_swing = max(up0_v + e, floor_v) - up_min
        down_swing = max(down0_v + e, floor_v) - down_min
        decayed = math.exp((t_last - i) / tau)  # the thresholds only fall within the segment
        if high < up_min + up_swing * decayed and low < down_min + down_swing * decayed:
            continue
        lo = 0.0
        while True:
            s_ref = t_last - (i - 1)
            s_up = _first_reach(a - r, b - a, up_min, up_swing, s_ref, tau, lo)
            s_down = _first_reach(r - a, a - b, down_min, down_swing, s_ref, tau, lo)
            if s_up < 0.0 and s_down < 0.0:
                break
            rising = s_down < 0.0 or (0.0 <= s_up <= s_down)
            s = s_up if rising else s_down
            if rising:
                r += up_min + up_swing * math.exp((s_ref - s) / tau)
            else:
                r -= down_min + down_swing * math.exp((s_ref - s) / tau)
            t_last = (i - 1) + s
            if out < capacity:
                times[out] = t_last
                polarity[out] = np.int8(1 if rising else -1)
            out += 1
            if out > limit:
                return out
            lo = s
    return out


def decaying_crossings(
    v: np.ndarray, fs_hz: float, theta0_v: float, theta_min_v: float, tau_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """Ideal continuous-time level-crossing encoder with a decaying threshold.

    Between samples the signal is the straight line through them. The reference ``r`` starts
    at the first sample; the threshold is ``theta(t) = theta_min + (theta_0 - theta_min) *
    exp(-(t - t_last) / tau)`` with ``t_last`` the time of the last spike (0 at the start). A +1
    spike is emitted at the first instant the signal reaches ``r + theta(t)``, a -1 spike at
    ``r - theta(t)``; at a spike ``r`` moves by that ``theta(t)`` in its direction and ``t_last``
    becomes the spike time. Each crossing is solved in continuous time (a bracketed Newton
    solve of line = exponential, to about 1e-15 of a sample). ``theta_min_v == theta0_v`` is the
    fixed encoder :func:`level_crossings`.

    Parameters
    ----------
    v : float64 (n,)
        The signal's samples in volts, all finite.
    fs_hz : float
        Sampling rate in Hz, > 0.
    theta0_v, theta_min_v : float
        Threshold right after a spike and its floor, in volts, ``0 < theta_min_v <= theta0_v``.
    tau_s : float
        Time constant of the decay in seconds, > 0.

    Returns
    -------
    times_s : float64 (n_spikes,), polarity : int8 (n_spikes,)
        As :func:`level_crossings`.

    Raises
    ------
    ValueError
        Listing every bad parameter at once, or for a non-finite sample.
    SimulationError
        If the train would hold more than :data:`MAX_SPIKES_PER_TRAIN` spikes.
    """
    v = _as_signal(v)
    problems = _non_finite_problems(v) + _positive_problems(
        fs_hz=fs_hz, theta0_v=theta0_v, theta_min_v=theta_min_v, tau_s=tau_s
    )
    if math.isfinite(theta0_v) and theta_min_v > theta0_v:
        problems.append(f"theta_min_v ({theta_min_v!r}) must not be above theta0_v ({theta0_v!r})")
    if not problems and not tau_s * fs_hz > 0:  # tau below the smallest number in samples
        problems.append(f"tau_s * fs_hz must be > 0, got {tau_s!r} * {fs_hz!r}")
    if problems:
        raise ValueError("; ".join(problems))
    curve = (theta0_v, theta_min_v)
    return decaying_train(v, fs_hz, curve, curve, tau_s, MAX_SPIKES_PER_TRAIN)


def decaying_train(v, fs_hz, up, down, tau_s, max_spikes, floor_v=0.0, noise=None):
    """The decaying encoder's train with UP/DOWN ``(theta_0, theta_min)`` pairs, a threshold
    floor and decision noise (see ``_decaying_kernel`` and :func:`run_noisy`)."""

    def call(rng, sigma_v, times, polarity):
        tau = tau_s * fs_hz
        return _decaying_kernel(
            v, *up, *down, floor_v, tau, rng, sigma_v, max_spikes, times, polarity
        )

    return run_noisy(call, noise, fs_hz, max_spikes, v)


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
    raise ValueError(_non_finite_message(v, index))


def _non_finite_message(v: np.ndarray, index: int) -> str:
    return f"signal has a non-finite sample ({v[index]}) at index {index}"


def _non_finite_problems(v: np.ndarray) -> list[str]:
    """The first non-finite sample of 1-D ``v`` as a problem, or none."""
    if np.all(np.isfinite(v)):
        return []
    return [_non_finite_message(v, int(np.flatnonzero(~np.isfinite(v))[0]))]


def checked_signal(v: np.ndarray) -> np.ndarray:
    """A 1-D float64 signal whose samples are all finite (for paths without the kernel check)."""
    v = _as_signal(v)
    problems = _non_finite_problems(v)
    if problems:
        raise ValueError(problems[0])
    return v


def _positive_problems(**values: float) -> list[str]:
    return [
        f"{name} must be a finite number > 0, got {value!r}"
        for name, value in values.items()
        if not (math.isfinite(value) and value > 0)
    ]


def _check_positive(**values: float) -> None:
    problems = _positive_problems(**values)
    if problems:
        raise ValueError("; ".join(problems))


def run_noisy(call, noise, fs_hz: float, max_spikes: int, v: np.ndarray) -> tuple:
    """``_run`` of a kernel ``call(rng, sigma_v, times, polarity) -> count`` with decision
    ``noise`` (``(sigma_v, rng factory)``, or None for none)."""
    sigma_v, new_rng = (0.0, None) if noise is None else noise

    def emit(times: np.ndarray, polarity: np.ndarray) -> int:
        # A fresh generator per call: a second pass must see the same decision noise.
        return call(None if new_rng is None else new_rng(), sigma_v, times, polarity)

    return _run(emit, fs_hz, max_spikes, v)
