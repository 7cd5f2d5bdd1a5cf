"""Synthetic textures: the embedded default dataset (no download needed).

A probe with a small contact patch slides over a textured surface; the sensor reports the
contact-force fluctuation. Every recording is generated from its own random stream,
``numpy.random.default_rng(SeedSequence([seed, class_index, recording_index]))`` (split into
independent child streams for the scan, the roughness and the sensor noise), so a recording does
not depend on how many other recordings are generated or in which order.

Model
-----
Surface profile of class ``c`` (height in um over the scan coordinate ``x`` in mm)::

    h(x) = A_c * s_c(x / P_c + phi_0) + rho(x)

``s_c`` is the ridge shape (period 1, range [-1, 1]; the shapes below), ``P_c`` the ridge
period (mm), ``A_c`` the ridge amplitude (um), ``phi_0 ~ U(0, 1)`` where the scan starts on the
ridge pattern. ``rho`` is Gaussian roughness with an exponential autocorrelation,
``E[rho(x) rho(x + u)] = sigma_c^2 exp(-|u| / l_c)`` (an Ornstein-Uhlenbeck process in space,
Lorentzian spectrum; exact AR(1) recursion on a grid of ``GRID_MM``), a fresh patch of surface
for every recording.

The probe touches the surface over a patch: it sees the profile averaged by a Gaussian of
standard deviation ``CONTACT_SIGMA_MM`` (a spatial low-pass filter, transfer
``exp(-2 pi^2 sigma_a^2 k^2)`` at ``k`` cycles/mm), ``h_a = h * g_a``.

The scan position follows a nominal speed ``v0 = SCAN_SPEED_MM_S`` with a per-recording speed
factor ``m ~ N(1, SPEED_SPREAD)`` and a slow wobble of three sinusoids (frequencies
``U(0.1, 1) Hz``, random phases, ``SPEED_WOBBLE_RMS`` rms in all)::

    v(t) = v0 * m * (1 + sum_k a_k sin(2 pi f_k t + psi_k))
    x(t) = v0 * m * (t + sum_k a_k (cos(psi_k) - cos(2 pi f_k t + psi_k)) / (2 pi f_k))

The sensor output (a.u.; 1 a.u. is ``UM_PER_AU`` um of filtered profile at nominal force) is::

    y(t) = kappa * h_a(x(t)) / UM_PER_AU + n(t),     y <- y - mean(y)

with ``kappa ~ U(1 - FORCE_SPREAD, 1 + FORCE_SPREAD)`` the per-recording contact-force factor
(a harder press gives a larger force fluctuation), ``n`` white Gaussian sensor noise of
``NOISE_RMS_AU`` rms, and the mean removed (an AC-coupled sensor: the static preload is not in
the output). Samples are taken at ``t_k = k / fs_hz``, ``k = 0 .. round(duration_s * fs_hz) - 1``.

Classes
-------
======  ======================  ========  ======  =====  ========  ======
index   name                    shape     P (mm)  A(um)  sigma(um) l (mm)
======  ======================  ========  ======  =====  ========  ======
0       sine-1.00mm-smooth      sine      1.00    10     1.0       0.10
1       sine-1.00mm-rough       sine      1.00    10     4.0       0.10
2       sine-1.00mm-wavy        sine      1.00    10     4.0       1.00
3       sine-0.80mm-smooth      sine      0.80    10     1.0       0.10
4       sine-1.25mm-smooth      sine      1.25    10     1.0       0.10
5       square-1.00mm-smooth    square    1.00    10     1.0       0.10
6       bumps-2.00mm            bumps     2.00    12     2.0       0.20
7       bumps-2.50mm            bumps     2.50    12     2.0       0.20
8       sawtooth-2.00mm         sawtooth  2.00    12     2.0       0.20
9       triangle-0.50mm         triangle  0.50    6      2.0       0.05
10      triangle-0.60mm         triangle  0.60    6      2.0       0.05
11      random-rough            none      --      0      6.0       0.30
======  ======================  ========  ======  =====  ========  ======

The table is built so that classes are separable but not trivially: 0/1/2 share the period and
ridges and differ only in roughness (amount, then correlation length); 0/3/4, 6/7 and 9/10
share everything but the period (20-25 % apart); 0/5 and 6/8 differ only in ridge shape
(harmonic content); 11 has no ridges at all. The values come from the physical picture above
and were not tuned to reach any accuracy.

Shapes of ``s(u)`` for the phase ``u = frac(x / P + phi_0)``:

- ``sine``: ``sin(2 pi u)``, one harmonic;
- ``square``: ``tanh(3 sin(2 pi u)) / tanh(3)``, a rounded square wave (odd harmonics);
- ``bumps``: ``2 exp(-(u - 1/2)^2 / (2 * 0.08^2)) - 1``, narrow ridges on a flat floor;
- ``sawtooth``: rises over 80 % of the period, falls over 20 % (all harmonics);
- ``triangle``: ``1 - 4 |u - 1/2|`` (odd harmonics, falling as 1/n^2);
- ``none``: 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.errors import DatasetError
from pipeline.numbers import positive_number, whole_number
from pipeline.recordings import Recordings

__all__ = [
    "CONTACT_SIGMA_MM",
    "DEFAULT_FS_HZ",
    "FORCE_SPREAD",
    "GRID_MM",
    "NOISE_RMS_AU",
    "SCAN_SPEED_MM_S",
    "SPEED_SPREAD",
    "SPEED_WOBBLE_RMS",
    "TEXTURE_CLASSES",
    "UM_PER_AU",
    "TextureClass",
    "ridge_shape",
    "synthetic_recordings",
]

#: Default sampling rate (Hz).
DEFAULT_FS_HZ = 2000.0
#: Nominal scan speed (mm/s).
SCAN_SPEED_MM_S = 20.0
#: Standard deviation of the per-recording speed factor ``m`` (relative).
SPEED_SPREAD = 0.02
#: RMS of the slow speed wobble within one recording (relative).
SPEED_WOBBLE_RMS = 0.03
#: Half-width of the uniform per-recording contact-force factor ``kappa`` (relative).
FORCE_SPREAD = 0.15
#: Standard deviation of the Gaussian contact patch (mm).
CONTACT_SIGMA_MM = 0.1
#: Profile height (um) that gives 1 a.u. of force at nominal contact force.
UM_PER_AU = 10.0
#: RMS of the additive white sensor noise (a.u.).
NOISE_RMS_AU = 0.05
#: Spatial grid on which the surface is generated (mm); well below CONTACT_SIGMA_MM.
GRID_MM = 0.01

_WOBBLE_COMPONENTS = 3
_WOBBLE_BAND_HZ = (0.1, 1.0)


@dataclass(frozen=True)
class TextureClass:
    """One synthetic texture: a ridge pattern plus random roughness.

    Attributes
    ----------
    name
        Class name, e.g. ``"sine-1.00mm-smooth"``.
    shape
        Ridge shape, one of ``"sine"``, ``"square"``, ``"bumps"``, ``"sawtooth"``,
        ``"triangle"``, ``"none"`` (see :func:`ridge_shape`).
    period_mm
        Ridge period ``P`` (mm); ignored for ``"none"``.
    ridge_um
        Ridge amplitude ``A`` (um): the ridge term spans ``[-A, A]``.
    roughness_um
        RMS ``sigma`` of the roughness (um).
    correlation_mm
        Correlation length ``l`` of the roughness (mm).
    """

    name: str
    shape: str
    period_mm: float
    ridge_um: float
    roughness_um: float
    correlation_mm: float


TEXTURE_CLASSES: tuple[TextureClass, ...] = (
    TextureClass("sine-1.00mm-smooth", "sine", 1.00, 10.0, 1.0, 0.10),
    TextureClass("sine-1.00mm-rough", "sine", 1.00, 10.0, 4.0, 0.10),
    TextureClass("sine-1.00mm-wavy", "sine", 1.00, 10.0, 4.0, 1.00),
    TextureClass("sine-0.80mm-smooth", "sine", 0.80, 10.0, 1.0, 0.10),
    TextureClass("sine-1.25mm-smooth", "sine", 1.25, 10.0, 1.0, 0.10),
    TextureClass("square-1.00mm-smooth", "square", 1.00, 10.0, 1.0, 0.10),
    TextureClass("bumps-2.00mm", "bumps", 2.00, 12.0, 2.0, 0.20),
    TextureClass("bumps-2.50mm", "bumps", 2.50, 12.0, 2.0, 0.20),
    TextureClass("sawtooth-2.00mm", "sawtooth", 2.00, 12.0, 2.0, 0.20),
    TextureClass("triangle-0.50mm", "triangle", 0.50, 6.0, 2.0, 0.05),
    TextureClass("triangle-0.60mm", "triangle", 0.60, 6.0, 2.0, 0.05),
    TextureClass("random-rough", "none", 1.00, 0.0, 6.0, 0.30),
)


def ridge_shape(shape: str, phase: np.ndarray) -> np.ndarray:
    """Ridge profile ``s(u)`` of period 1 and range ``[-1, 1]``.

    Parameters
    ----------
    shape
        ``"sine"``, ``"square"``, ``"bumps"``, ``"sawtooth"``, ``"triangle"`` or ``"none"``.
    phase
        float64, any shape: the phase ``u`` in periods (any real; only ``frac(u)`` matters).

    Returns
    -------
    numpy.ndarray
        float64, same shape as ``phase``.
    """
    u = np.mod(np.asarray(phase, dtype=np.float64), 1.0)
    if shape == "sine":
        return np.sin(2 * np.pi * u)
    if shape == "square":
        return np.tanh(3.0 * np.sin(2 * np.pi * u)) / np.tanh(3.0)
    if shape == "bumps":
        return 2.0 * np.exp(-0.5 * ((u - 0.5) / 0.08) ** 2) - 1.0
    if shape == "sawtooth":
        rise = 0.8
        return np.where(u < rise, -1.0 + 2.0 * u / rise, 1.0 - 2.0 * (u - rise) / (1.0 - rise))
    if shape == "triangle":
        return 1.0 - 4.0 * np.abs(u - 0.5)
    if shape == "none":
        return np.zeros_like(u)
    raise ValueError(f"unknown ridge shape {shape!r}")


@dataclass(frozen=True)
class SyntheticLayout:
    """What :func:`synthetic_recordings` will make, known without generating a sample.

    Attributes
    ----------
    n_samples : int
        Samples of every recording.
    fs_hz : float
        Sampling rate (Hz).
    labels : tuple of int
        Class index of each recording, class-major.
    names : tuple of str
        ``"<class name>/rec01"`` (1-based) per recording.
    class_names : tuple of str
        The class names, in label order.
    """

    n_samples: int
    fs_hz: float
    labels: tuple[int, ...]
    names: tuple[str, ...]
    class_names: tuple[str, ...] = tuple(tc.name for tc in TEXTURE_CLASSES)


def synthetic_layout(
    *,
    seed: int = 0,
    recordings_per_class: int = 10,
    duration_s: float = 5.0,
    fs_hz: float = DEFAULT_FS_HZ,
) -> SyntheticLayout:
    """Check :func:`synthetic_recordings`' arguments and give the shape of its dataset.

    Checking a grid against its recordings needs only their lengths, names and classes; this
    gives them in microseconds, where generating the recordings takes about a second.

    Raises
    ------
    DatasetError
        An argument out of range (named in the message).
    """
    problems = []
    if whole_number(seed, 0) is None:
        problems.append(f"seed must be an integer >= 0, got {seed!r}")
    if whole_number(recordings_per_class, 1) is None:
        problems.append(
            f"recordings_per_class must be an integer >= 1, got {recordings_per_class!r}"
        )
    if positive_number(fs_hz) is None:
        problems.append(f"fs_hz must be a finite number > 0, got {fs_hz!r}")
    if positive_number(duration_s) is None:
        problems.append(f"duration_s must be a finite number > 0, got {duration_s!r}")
    elif not problems and round(duration_s * fs_hz) < 2:
        problems.append(
            f"duration_s = {duration_s} s at fs_hz = {fs_hz} Hz gives fewer than 2 samples"
        )
    if problems:
        raise DatasetError("synthetic dataset: " + "; ".join(problems))

    n_samples = round(duration_s * fs_hz)
    per_class = range(int(recordings_per_class))
    return SyntheticLayout(
        n_samples=n_samples,
        fs_hz=float(fs_hz),
        labels=tuple(c for c in range(len(TEXTURE_CLASSES)) for _ in per_class),
        names=tuple(f"{tc.name}/rec{r + 1:02d}" for tc in TEXTURE_CLASSES for r in per_class),
    )


def synthetic_recordings(
    *,
    seed: int = 0,
    recordings_per_class: int = 10,
    duration_s: float = 5.0,
    fs_hz: float = DEFAULT_FS_HZ,
) -> Recordings:
    """Generate the synthetic texture dataset (12 classes; see the module docstring).

    Parameters
    ----------
    seed
        Non-negative integer; the dataset is a deterministic function of it (and of the other
        arguments). Recording ``r`` of class ``c`` depends only on ``(seed, c, r)``,
        ``duration_s`` and ``fs_hz``.
    recordings_per_class
        Recordings per class (>= 1).
    duration_s
        Duration of every recording (s, > 0); ``round(duration_s * fs_hz)`` samples, at least 2.
    fs_hz
        Sampling rate (Hz, > 0).

    Returns
    -------
    Recordings
        ``12 * recordings_per_class`` recordings, class-major (class 0's recordings first),
        float64 force signals in a.u., names ``"<class name>/rec01"`` (1-based), dataset name
        ``"synthetic"``.

    Raises
    ------
    DatasetError
        An argument out of range (named in the message).
    """
    layout = synthetic_layout(
        seed=seed, recordings_per_class=recordings_per_class, duration_s=duration_s, fs_hz=fs_hz
    )
    t = np.arange(layout.n_samples, dtype=np.float64) / fs_hz
    signals = []
    for c, texture in enumerate(TEXTURE_CLASSES):
        for r in range(int(recordings_per_class)):
            streams = np.random.SeedSequence([int(seed), c, r]).spawn(3)
            scan, rough, noise = (np.random.default_rng(s) for s in streams)
            signals.append(_recording(texture, t, scan, rough, noise))
    return Recordings(
        signals=tuple(signals),
        labels=np.array(layout.labels, dtype=np.int64),
        class_names=layout.class_names,
        fs_hz=layout.fs_hz,
        names=layout.names,
        units="a.u.",
        name="synthetic",
    )


def _recording(
    texture: TextureClass,
    t: np.ndarray,
    scan: np.random.Generator,
    rough: np.random.Generator,
    noise: np.random.Generator,
) -> np.ndarray:
    """One recording: float64, shape ``t.shape``, a.u. (the model of the module docstring)."""
    # scipy.ndimage and scipy.signal take seconds to import; a sweep whose recordings are all
    # cached, or that checks a grid on other recordings, never needs them.
    from scipy.ndimage import gaussian_filter1d

    # Scan: position x(t) in mm, integrated analytically from the speed.
    speed = SCAN_SPEED_MM_S * (1.0 + SPEED_SPREAD * scan.standard_normal())
    freqs = scan.uniform(*_WOBBLE_BAND_HZ, size=_WOBBLE_COMPONENTS)
    psi = scan.uniform(0.0, 2 * np.pi, size=_WOBBLE_COMPONENTS)
    direction = scan.standard_normal(_WOBBLE_COMPONENTS)
    amps = SPEED_WOBBLE_RMS * math.sqrt(2.0) * direction / np.linalg.norm(direction)
    omega = 2 * np.pi * freqs
    wobble = (amps / omega) @ (np.cos(psi)[:, None] - np.cos(np.outer(omega, t) + psi[:, None]))
    x = speed * (t + wobble)
    kappa = scan.uniform(1.0 - FORCE_SPREAD, 1.0 + FORCE_SPREAD)
    phi0 = scan.uniform()

    # Surface on a grid covering the scanned stretch plus the contact filter's reach.
    margin = 5.0 * CONTACT_SIGMA_MM
    x0 = float(x.min()) - margin
    n_grid = math.ceil((float(x.max()) + margin - x0) / GRID_MM) + 2
    grid = x0 + GRID_MM * np.arange(n_grid)
    height = texture.ridge_um * ridge_shape(texture.shape, grid / texture.period_mm + phi0)
    if texture.roughness_um > 0:
        height += _ou_roughness(rough, n_grid, texture.roughness_um, texture.correlation_mm)
    contact = gaussian_filter1d(height, CONTACT_SIGMA_MM / GRID_MM, mode="nearest", truncate=4.0)

    y = kappa * np.interp(x, grid, contact) / UM_PER_AU
    y += NOISE_RMS_AU * noise.standard_normal(t.size)
    y -= y.mean()
    return y


def _ou_roughness(rng: np.random.Generator, n: int, sigma: float, corr_mm: float) -> np.ndarray:
    """Stationary exponentially correlated Gaussian noise on the grid: float64 ``(n,)``, um."""
    from scipy.signal import lfilter

    a = math.exp(-GRID_MM / corr_mm)
    start = sigma * rng.standard_normal()
    drive = rng.standard_normal(n)
    out, _ = lfilter([sigma * math.sqrt(1.0 - a * a)], [1.0, -a], drive, zi=[a * start])
    return out
