"""One synthetic touch: a fingertip pressed on a material sample and slid across it, as a
fingertip force sensor reports it.

:func:`touch` makes recording ``r`` of class ``c`` from its own random streams, the children
0..3 (motion, roughness, asperities, sensor noise) of
``numpy.random.SeedSequence([seed, c, r])``, on the material sample of its class
(:func:`pipeline.recordings.materials.material_map`); the classes and their parameters are
:mod:`pipeline.recordings.materials`.

Model
-----
Times ``t`` in s, forces in mN, lengths in mm (heights in um). Per touch ``i`` of material ``m``
the jitter is drawn first: contact time ``t_c ~ CONTACT_S + U(-1, 1) CONTACT_JITTER_S``, start of
the sliding motion ``t_s = t_c + HOLD_S + U(-1, 1) HOLD_JITTER_S``, press force ``F ~
PRESS_FORCE_N U(1 - FORCE_SPREAD, 1 + FORCE_SPREAD)``, speed ``v0 = SCAN_SPEED_MM_S (1 +
SPEED_SPREAD z)``, a slow wobble ``w(t)`` of three sinusoids (``U(0.1, 1) Hz``, random phases,
``SPEED_WOBBLE_RMS`` rms in all), the start on the sample ``x_0 ~ N(0, START_JITTER_MM)``, the
shear stiffness ``k_t = SHEAR_STIFFNESS_N_PER_MM exp(SHEAR_STIFFNESS_SPREAD z)`` (the fingertip's
compliant mounting and the pad's state differ from touch to touch), the macro phase ``phi_1 ~
U(0, 1)``.

Contact and press. The pad (stiffness ``k_f = FINGER_STIFFNESS_N_PER_MM``) and the material
(``k_m``) are springs in series, ``k = 1 / (1/k_f + 1/k_m)``. The robot approaches at ``v_a =
APPROACH_MM_S`` under force control, so the force rises with time constant ``tau_p = F / (k v_a)``
(a softer material takes longer), then holds the height while the contact relaxes (share ``r`` of
the force, time constant ``RELAX_S``); the impact rings at the contact resonance of the fingertip
mass ``M = FINGER_MASS_KG`` on ``k`` (damping ratio ``zeta = RING_DAMPING``)::

    s    = max(t - t_c, 0),       omega = sqrt(k / M)
    N(t) = F (1 - exp(-s / tau_p)) (1 - r (1 - exp(-s / RELAX_S)))         (t >= t_c, else 0)
    R(t) = v_a sqrt(k M) sin(omega sqrt(1 - zeta^2) s) exp(-zeta omega s)  (t >= t_c, else 0)

Sliding. The robot accelerates to its speed (time constant ``ACCEL_S``); ``X`` is how far it has
moved, ``x`` where the fingertip is on the sample::

    v(t) = v0 (1 - exp(-(t - t_s) / ACCEL_S)) (1 + w(t))    (t >= t_s, else 0)
    X(t) = integral of v from 0 to t,     x(t) = x_0 + X(t)

The sample varies slowly along the path: ``g_m(x)`` is a stationary Gaussian process of unit
variance with a Gaussian spectrum of correlation length ``MAP_CORRELATION_MM`` (periodic over
``MAP_PERIOD_MM``), one per material sample
(:func:`pipeline.recordings.materials.material_map`); a touch's path crosses the sample at a
slightly different place, so it meets ``rho g_m + sqrt(1 - rho^2) g_i`` with
``rho = MAP_SHARED`` and ``g_i`` its own draw of the same process. The local factor of friction
and texture is ``L(x) = exp(s_m (rho g_m(x) + sqrt(1 - rho^2) g_i(x)))``.

Friction. The shear spring of pad and mounting (``k_t``, mN/mm) is loaded by the motion until it
reaches static friction, at the first slip ``t_b``; from then on the tangential force is
stick-slip about kinetic friction, a relaxation oscillation: the contact sticks while the drive
reloads the spring by the drop ``D`` between static and kinetic friction, then slips. The drop
falls with speed as the Stribeck curve does (velocity weakening dies out above ``v_c``), so the
cycles come at ``f_ss = k_t v / D``: about 5-20 Hz at the scan speed, set by the material's
friction (``mu_s - mu_k``, ``v_c``), the stiffness and the speed, and varying along the path with
``L``. Each cycle's depth is scaled by ``exp(SLIP_DEPTH_SPREAD z_j)``::

    F_T(t) = k_t X(t)                                    t_s <= t < t_b: k_t X < mu_s L N
    D(t)   = (mu_s - mu_k) L(x) N(t) exp(-v(t) / v_c)
    phi(t) = integral from t_b to t of min(k_t v / D, fs / 4)          (0 where D < 1e-3 mN)
    F_T(t) = mu_k L(x) N(t) + D(t) exp(SLIP_DEPTH_SPREAD z_floor(phi)) (frac(phi) - 1/2)   t >= t_b

The pad. While the contact sticks the pad does not stop: its edge slips (partial slip), so it
creeps at ``1 - a`` of the drive's speed (``a = STICK_SPEED_LOSS``), and it catches up in the
slip, the last ``q = SLIP_SHARE`` of each cycle; before the first slip the creep grows with the
shear load. Its position ``x_p`` on the sample is what the texture sees::

    u(t)   = frac(phi(t)),         b(u) = 1/q for u >= 1 - q, else 0
    v_p(t) = v(t) (1 - a + a b(u))                                       t >= t_b
    v_p(t) = (1 - a) v(t) min(k_t X / (mu_s L N), 1)                     t_s <= t < t_b
    x_p(t) = x_0 + integral of v_p from 0 to t

The pad's mean speed over a cycle is the drive's; it never stops after the first slip, so
sliding never goes quiet.

Texture. The surface profile under the contact patch, ``h_a(x)`` (um; below), indents the pad in
proportion to the normal force (``TEXTURE_COUPLING`` of it: the pad partly conforms; ``k`` in N/mm
times um is mN; ``F_0`` is ``PRESS_FORCE_N`` in mN), where the pad is; a texture with a macro
period ``Lambda_m`` (its ridges or grains come in groups: a weave, a knurl) has its vibration
modulated by depth ``beta_m`` over that period, at ``v / Lambda_m`` Hz at the scan speed::

    M(x) = 1 + beta_m cos(2 pi (x / Lambda_m + phi_1))
    V(t) = TEXTURE_COUPLING k L(x) (N(t) / F_0) h_a(x_p(t)) M(x_p(t))

Before the sliding motion ``x_p`` is constant and ``V`` only follows the press: there is no sliding
vibration before contact nor before the motion starts.

Profile of texture ``m`` (height in um over ``x``)::

    h(x)   = A_m s_m(x / P_m + phi_0) + rho_r(x)
    h_a(x) = (g_a * h)(x) + sum_j H_j exp(-(x - xi_j)^2 / (2 sigma_a^2))

``s_m`` is the ridge shape (period 1, range [-1, 1]; the shapes below), ``P_m`` the ridge period,
``A_m`` the ridge amplitude, ``phi_0 ~ U(0, 1)``. ``rho_r`` is Gaussian roughness with an
exponential autocorrelation, ``E[rho_r(x) rho_r(x + u)] = sigma_m^2 exp(-|u| / l_m)`` (exact AR(1)
recursion on a grid of ``GRID_MM``), fresh for every touch. The pad sees the profile averaged by
the Gaussian ``g_a`` of standard deviation ``sigma_a = CONTACT_SIGMA_MM``; asperities are grains
at the points ``xi_j`` of a Poisson process of ``lambda_m`` per mm, heights ``H_j ~
Exponential(mean H_m)``, each a Gaussian bump of width ``sigma_a`` at its exact position.

Sensor. The pad's sensor sums normal and tangential force with the texture and the ring, plus
white noise ``n`` (``NOISE_RMS_MN`` rms per sample); it is AC-coupled (first-order high-pass at
``SENSOR_HIGHPASS_HZ``) and band-limited (Butterworth low-pass of order ``SENSOR_FILTER_ORDER`` at
``SENSOR_BAND_HZ``; a filter whose corner is not below ``fs_hz / 2`` is left out), starting from
rest (nothing touches it before ``t = 0``); the recording is its output with the mean removed::

    y = B(HP(N + F_T + V + R + n)),        y <- y - mean(y)

Samples are taken at ``t_k = k / fs_hz``, ``k = 0 .. round(duration_s * fs_hz) - 1`` (2 kHz by
default, as the real recordings; 5 s by default: the paper's 40 windows of 0.1 s plus room for
the taxel delays).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline import jit
from pipeline.recordings.materials import (
    MAP_PERIOD_MM,
    MAP_SAMPLES,
    TEXTURE_CLASSES,
    periodic_process,
    ridge_shape,
)

__all__ = [
    "ACCEL_S",
    "APPROACH_MM_S",
    "CONTACT_JITTER_S",
    "CONTACT_S",
    "CONTACT_SIGMA_MM",
    "FINGER_MASS_KG",
    "FINGER_STIFFNESS_N_PER_MM",
    "FORCE_SPREAD",
    "GRID_MM",
    "HOLD_JITTER_S",
    "HOLD_S",
    "MAP_SHARED",
    "NOISE_RMS_MN",
    "PRESS_FORCE_N",
    "RELAX_S",
    "RING_DAMPING",
    "SCAN_SPEED_MM_S",
    "SENSOR_BAND_HZ",
    "SENSOR_FILTER_ORDER",
    "SENSOR_HIGHPASS_HZ",
    "SHEAR_STIFFNESS_N_PER_MM",
    "SHEAR_STIFFNESS_SPREAD",
    "SLIP_DEPTH_SPREAD",
    "SLIP_SHARE",
    "SPEED_SPREAD",
    "SPEED_WOBBLE_RMS",
    "START_JITTER_MM",
    "STICK_SPEED_LOSS",
    "TEXTURE_COUPLING",
    "Touch",
    "touch",
]

# Contact and press
#: Mean time at which the fingertip meets the surface (s).
CONTACT_S = 0.03
#: Half-width of the jitter of the contact time (s).
CONTACT_JITTER_S = 0.01
#: Target normal force of the press (N).
PRESS_FORCE_N = 0.15
#: Half-width of the press force's per-touch jitter (relative).
FORCE_SPREAD = 0.15
#: Approach speed of the fingertip into the surface (mm/s).
APPROACH_MM_S = 2.0
#: Stiffness of the fingertip pad in the normal direction (N/mm), in series with the material's.
FINGER_STIFFNESS_N_PER_MM = 1.0
#: Moving mass of the fingertip (kg).
FINGER_MASS_KG = 0.01
#: Damping ratio of the fingertip's impact ring.
RING_DAMPING = 0.3
#: Time constant of the viscoelastic relaxation of the normal force while holding the height (s).
RELAX_S = 2.0

# Sliding
#: Time from contact to the start of the tangential motion (s).
HOLD_S = 0.08
#: Half-width of the jitter of that time (s).
HOLD_JITTER_S = 0.02
#: Nominal sliding speed (mm/s).
SCAN_SPEED_MM_S = 20.0
#: Per-touch spread of the sliding speed (relative s.d.).
SPEED_SPREAD = 0.03
#: Time constant of the robot's acceleration (s).
ACCEL_S = 0.15
#: RMS of the slow speed wobble within a touch (relative).
SPEED_WOBBLE_RMS = 0.08
#: Tangential stiffness of the pad and its compliant mounting on the robot (N/mm), which the
#: stick phase loads: with the materials' friction it sets stick-slip cycles of 5-20 Hz at the
#: scan speed.
SHEAR_STIFFNESS_N_PER_MM = 0.006
#: Standard deviation of the log of each stick-slip cycle's depth factor.
SLIP_DEPTH_SPREAD = 0.1
#: Standard deviation of the log of a touch's shear stiffness (the fingertip's mounting, the
#: pad's state): each touch's stick-slip runs at its own rate.
SHEAR_STIFFNESS_SPREAD = 0.1
#: Share of a stick-slip cycle that the slip takes (the rest the contact sticks).
SLIP_SHARE = 0.25
#: Share of the drive's speed that the pad loses while the contact sticks; it creeps at
#: ``1 - STICK_SPEED_LOSS`` of it (partial slip at the contact's edge) and catches up in the slip.
STICK_SPEED_LOSS = 0.2

# Where a touch meets the material sample
#: Share ``rho`` of the variation a touch meets that is the sample's own (the rest is the touch's:
#: its path crosses the sample at a slightly different place).
MAP_SHARED = 0.92
#: Standard deviation of where on the sample a touch starts sliding (mm).
START_JITTER_MM = 4.0
# Texture
#: Standard deviation of the Gaussian contact patch (mm).
CONTACT_SIGMA_MM = 0.03
#: Share of the filtered surface profile that indents the pad (the pad partly conforms).
TEXTURE_COUPLING = 1.5
#: Spatial grid on which the surface is generated (mm); well below CONTACT_SIGMA_MM.
GRID_MM = 0.005

# Sensor
#: Corner of the sensor's first-order AC coupling (Hz).
SENSOR_HIGHPASS_HZ = 4.0
#: Corner of the sensor's anti-aliasing low-pass (Hz).
SENSOR_BAND_HZ = 250.0
#: Order of that Butterworth low-pass.
SENSOR_FILTER_ORDER = 8
#: RMS of the additive white sensor noise per sample, before the sensor filter (mN).
NOISE_RMS_MN = 0.05

_WOBBLE_COMPONENTS = 3
_WOBBLE_BAND_HZ = (0.1, 1.0)
# An asperity's bump is added over +-this many contact widths (exp(-4.5^2 / 2) < 4e-5).
_ASPERITY_REACH = 4.5
# Stick-slip faster than this fraction of the sampling rate is steady sliding at this sampling.
_MAX_SLIP_RATE = 0.25
# Below this depth (mN) stick-slip has died out.
_MIN_SLIP_MN = 1e-3


@dataclass(frozen=True, eq=False)
class Touch:
    """One touch and the forces behind it; every array is float64 of the time axis' shape.

    Attributes
    ----------
    signal
        The recording: the sensor's output with its mean removed (mN).
    normal_mn
        Normal force ``N(t)`` (mN).
    friction_mn
        Tangential (friction) force ``F_T(t)`` (mN).
    texture_mn
        Texture force ``V(t)`` (mN).
    ring_mn
        Impact ring ``R(t)`` (mN).
    speed_mm_s
        Sliding speed ``v(t)`` of the drive (mm/s).
    pad_speed_mm_s
        Speed ``v_p(t)`` of the pad over the sample (mm/s): it creeps while the contact sticks
        and catches up in each slip.
    slip_rate_hz
        Rate ``f_ss(t) = k_t v / D`` of the stick-slip cycles (Hz; 0 before the motion and
        where stick-slip has died out), at most ``fs_hz / 4``.
    contact_s, slide_s, break_s
        Contact time ``t_c``, start of the sliding motion ``t_s`` and the first slip ``t_b`` (s;
        ``inf`` when the touch ends before it).
    """

    signal: np.ndarray
    normal_mn: np.ndarray
    friction_mn: np.ndarray
    texture_mn: np.ndarray
    ring_mn: np.ndarray
    speed_mm_s: np.ndarray
    pad_speed_mm_s: np.ndarray
    slip_rate_hz: np.ndarray
    contact_s: float
    slide_s: float
    break_s: float


def touch(
    seed: int, class_index: int, recording: int, t: np.ndarray, fs_hz: float, sample: np.ndarray
) -> Touch:
    """Recording ``recording`` of class ``class_index`` (the model of the module docstring).

    ``t`` is the time axis (s, float64 ``(n,)``, ``k / fs_hz``); ``sample`` the class's
    :func:`pipeline.recordings.materials.material_map`. The touch's own draws come from the
    children 0..3 (motion, surface, asperities, sensor noise) of
    ``SeedSequence([seed, class_index, recording])``.
    """
    gaussian_filter1d, sosfilt = _scipy_filters()

    m = TEXTURE_CLASSES[class_index]
    children = np.random.SeedSequence([int(seed), int(class_index), int(recording)]).spawn(4)
    motion, rough, grains, noise = (np.random.default_rng(s) for s in children)
    n = t.size

    # Per-touch jitter: timing, force, speed, where on the sample, the path's own variation.
    t_c = CONTACT_S + CONTACT_JITTER_S * motion.uniform(-1.0, 1.0)
    t_s = t_c + HOLD_S + HOLD_JITTER_S * motion.uniform(-1.0, 1.0)
    force_n = PRESS_FORCE_N * motion.uniform(1.0 - FORCE_SPREAD, 1.0 + FORCE_SPREAD)
    speed = SCAN_SPEED_MM_S * (1.0 + SPEED_SPREAD * motion.standard_normal())
    freqs = motion.uniform(*_WOBBLE_BAND_HZ, size=_WOBBLE_COMPONENTS)
    psi = motion.uniform(0.0, 2 * np.pi, size=_WOBBLE_COMPONENTS)
    direction = motion.standard_normal(_WOBBLE_COMPONENTS)
    amps = SPEED_WOBBLE_RMS * math.sqrt(2.0) * direction / np.linalg.norm(direction)
    x_start = START_JITTER_MM * motion.standard_normal()
    own = periodic_process(motion)
    phi0 = motion.uniform()
    macro_phase = motion.uniform()

    # Contact and press: force-controlled approach into the series of pad and material springs,
    # then the height is held and the force relaxes.
    k_eff = 1.0 / (1.0 / FINGER_STIFFNESS_N_PER_MM + 1.0 / m.stiffness_n_per_mm)  # N/mm
    s = np.maximum(t - t_c, 0.0)
    touching = t >= t_c
    tau_press = force_n / (k_eff * APPROACH_MM_S)
    relaxed = 1.0 - m.relaxation * (1.0 - np.exp(-s / RELAX_S))
    normal = 1e3 * force_n * (1.0 - np.exp(-s / tau_press)) * relaxed * touching  # mN
    omega = math.sqrt(1e3 * k_eff / FINGER_MASS_KG)  # rad/s
    ring_peak = 1e3 * APPROACH_MM_S * 1e-3 * math.sqrt(1e3 * k_eff * FINGER_MASS_KG)  # mN
    damped = omega * math.sqrt(1.0 - RING_DAMPING**2)
    ring = ring_peak * np.sin(damped * s) * np.exp(-RING_DAMPING * omega * s) * touching

    # Sliding: the robot accelerates to its speed; x is the position on the sample (mm).
    u = np.maximum(t - t_s, 0.0)
    wobble = amps @ np.sin(2 * np.pi * np.outer(freqs, t) + psi[:, None])
    v = speed * (1.0 - np.exp(-u / ACCEL_S)) * (1.0 + wobble) * (t >= t_s)
    travel = np.cumsum(v) / fs_hz
    x = x_start + travel
    grid_map = np.arange(MAP_SAMPLES) * (MAP_PERIOD_MM / MAP_SAMPLES)
    mixed = MAP_SHARED * sample + math.sqrt(1.0 - MAP_SHARED**2) * own
    local = np.exp(m.patchiness * np.interp(x, grid_map, mixed, period=MAP_PERIOD_MM))

    # Friction: the stick phase loads the shear spring up to mu_s N; then stick-slip about
    # mu_k N whose depth falls with speed (Stribeck) and whose cycles come at k_t v / D.
    stiffness_jitter = math.exp(SHEAR_STIFFNESS_SPREAD * motion.standard_normal())
    k_t = 1e3 * SHEAR_STIFFNESS_N_PER_MM * stiffness_jitter  # mN/mm
    load = k_t * travel
    broken = (t >= t_s) & (load >= m.mu_static * local * normal)
    first = int(np.argmax(broken)) if broken.any() else n
    depth = (m.mu_static - m.mu_kinetic) * local * normal * np.exp(-v / m.stribeck_mm_s)
    rate = np.where(depth > _MIN_SLIP_MN, k_t * v / np.maximum(depth, _MIN_SLIP_MN), 0.0)
    phase = np.cumsum(np.minimum(rate, _MAX_SLIP_RATE * fs_hz)) / fs_hz
    phase -= phase[min(first, n - 1)]
    cycle = np.floor(phase).astype(np.int64)
    cycle -= cycle.min()
    depth_factor = np.exp(SLIP_DEPTH_SPREAD * motion.standard_normal(int(cycle.max()) + 1))
    stick_slip = depth * depth_factor[cycle] * (phase - np.floor(phase) - 0.5)
    after = np.arange(n) >= first
    friction = np.where(after, m.mu_kinetic * local * normal + stick_slip, load * (t >= t_s))
    # The pad: it creeps at (1 - a) of the drive's speed while the contact sticks (partial
    # slip, growing with the shear load before the first slip) and catches up in each slip,
    # which takes the last SLIP_SHARE of a cycle.
    u_cycle = phase - np.floor(phase)
    burst = np.where(u_cycle >= 1.0 - SLIP_SHARE, 1.0 / SLIP_SHARE, 0.0)
    loaded = np.clip(load / np.maximum(m.mu_static * local * normal, 1e-9), 0.0, 1.0)
    pad_v = np.where(
        after,
        v * (1.0 - STICK_SPEED_LOSS + STICK_SPEED_LOSS * burst),
        (1.0 - STICK_SPEED_LOSS) * v * loaded,
    )
    x = x_start + np.cumsum(pad_v) / fs_hz

    # Texture: the surface profile under the contact patch, pressed in by the normal force.
    margin = 5.0 * CONTACT_SIGMA_MM
    x0 = float(x.min()) - margin
    n_grid = math.ceil((float(x.max()) + margin - x0) / GRID_MM) + 2
    grid = x0 + GRID_MM * np.arange(n_grid)
    height = m.ridge_um * ridge_shape(m.shape, grid / m.period_mm + phi0)
    if m.roughness_um > 0:
        height += _ou_roughness(rough, n_grid, m.roughness_um, m.correlation_mm)
    profile = gaussian_filter1d(height, CONTACT_SIGMA_MM / GRID_MM, mode="nearest", truncate=4.0)
    if m.asperities_per_mm > 0 and m.asperity_um > 0:
        profile += _asperities(grains, grid, m.asperities_per_mm, m.asperity_um)
    # k_eff (N/mm) times um is mN.
    texture = TEXTURE_COUPLING * k_eff * local * normal / (1e3 * PRESS_FORCE_N)
    texture = texture * np.interp(x, grid, profile)
    if m.macro_depth > 0:
        texture *= 1.0 + m.macro_depth * np.cos(2 * np.pi * (x / m.macro_period_mm + macro_phase))

    # Sensor: AC coupling, anti-aliasing low-pass, from rest (nothing touches it before t = 0).
    raw = normal + friction + texture + ring + NOISE_RMS_MN * noise.standard_normal(n)
    sections = _sensor_sections(float(fs_hz))
    out = sosfilt(sections, raw) if sections is not None else raw
    return Touch(
        signal=out - out.mean(),
        normal_mn=normal,
        friction_mn=friction,
        texture_mn=texture,
        ring_mn=ring,
        speed_mm_s=v,
        pad_speed_mm_s=pad_v,
        slip_rate_hz=np.minimum(rate, _MAX_SLIP_RATE * fs_hz),
        contact_s=float(t_c),
        slide_s=float(t_s),
        break_s=float(t[first]) if first < n else math.inf,
    )


@functools.cache
def _scipy_filters() -> tuple[Any, Any]:
    """scipy's ``gaussian_filter1d`` and ``sosfilt``, imported on the first call.

    scipy.ndimage and scipy.signal take seconds to import; a sweep whose recordings are all
    cached, or that checks a grid on other recordings, never needs them. The import is one-off
    time (:func:`pipeline.jit.one_off`: a step's timer books it as shared set-up), not
    the work of the first load of a process.
    """
    with jit.one_off():
        from scipy.ndimage import gaussian_filter1d
        from scipy.signal import sosfilt
    return gaussian_filter1d, sosfilt


@functools.lru_cache(maxsize=8)
def _sensor_sections(fs_hz: float) -> np.ndarray | None:
    """Second-order sections of the sensor's high-pass and low-pass at ``fs_hz`` (None: both left
    out). Designed once per rate: the design costs as much as filtering a touch."""
    from scipy.signal import butter

    sections = []
    if SENSOR_HIGHPASS_HZ < fs_hz / 2:
        sections.append(butter(1, SENSOR_HIGHPASS_HZ, "highpass", fs=fs_hz, output="sos"))
    if SENSOR_BAND_HZ < fs_hz / 2:
        sections.append(butter(SENSOR_FILTER_ORDER, SENSOR_BAND_HZ, fs=fs_hz, output="sos"))
    # sosfilt needs a writable array (it copies it); callers must not change it.
    return np.vstack(sections) if sections else None


def _ou_roughness(rng: np.random.Generator, n: int, sigma: float, corr_mm: float) -> np.ndarray:
    """Stationary exponentially correlated Gaussian noise on the grid: float64 ``(n,)``, um."""
    from scipy.signal import lfilter

    a = math.exp(-GRID_MM / corr_mm)
    start = sigma * rng.standard_normal()
    drive = rng.standard_normal(n)
    out, _ = lfilter([sigma * math.sqrt(1.0 - a * a)], [1.0, -a], drive, zi=[a * start])
    return out


def _asperities(
    rng: np.random.Generator, grid: np.ndarray, per_mm: float, mean_um: float
) -> np.ndarray:
    """Asperities as the contact patch sees them, on ``grid`` (mm): float64 ``grid.shape``, um.

    Poisson positions over the grid's stretch (uniform given their number), exponential heights,
    each a Gaussian bump of width ``CONTACT_SIGMA_MM`` at its exact position.
    """
    length = float(grid[-1] - grid[0])
    count = int(rng.poisson(per_mm * length))
    centres = grid[0] + length * rng.random(count)
    heights = rng.exponential(mean_um, count)
    reach = math.ceil(_ASPERITY_REACH * CONTACT_SIGMA_MM / GRID_MM)
    nearest = np.rint((centres - grid[0]) / GRID_MM).astype(np.int64)
    cells = nearest[:, None] + np.arange(-reach, reach + 1)
    inside = (cells >= 0) & (cells < grid.size)
    cells = np.clip(cells, 0, grid.size - 1)
    offsets = (grid[cells] - centres[:, None]) / CONTACT_SIGMA_MM
    bumps = np.where(inside, heights[:, None] * np.exp(-0.5 * offsets**2), 0.0)
    out = np.zeros(grid.size)
    np.add.at(out, cells.ravel(), bumps.ravel())
    return out
