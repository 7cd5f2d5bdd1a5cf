"""Synthetic textures: the embedded default dataset (no download needed).

A probe with a small contact patch slides over a textured surface; the sensor reports the
contact-force fluctuation through a band-limited recording chain. Every recording is generated
from its own random stream, ``numpy.random.default_rng(SeedSequence([seed, class_index,
recording_index]))`` (split into independent child streams for the scan, the roughness, the
asperities and the sensor noise), so a recording does not depend on how many other recordings
are generated or in which order.

Model
-----
Surface profile of class ``c`` (height in um over the scan coordinate ``x`` in mm), as the
probe sees it::

    h(x)   = A_c s_c(x / P_c + phi_0) + rho(x)
    h_a(x) = (g_a * h)(x) + sum_j H_j exp(-(x - xi_j)^2 / (2 sigma_a^2))

``s_c`` is the ridge shape (period 1, range [-1, 1]; the shapes below), ``P_c`` the ridge
period (mm), ``A_c`` the ridge amplitude (um), ``phi_0 ~ U(0, 1)`` where the scan starts on the
ridge pattern. ``rho`` is Gaussian roughness with an exponential autocorrelation,
``E[rho(x) rho(x + u)] = sigma_c^2 exp(-|u| / l_c)`` (an Ornstein-Uhlenbeck process in space,
Lorentzian spectrum; exact AR(1) recursion on a grid of ``GRID_MM``), a fresh patch of surface
for every recording. The probe touches the surface over a patch: it sees the profile averaged by
the Gaussian ``g_a`` of standard deviation ``sigma_a = CONTACT_SIGMA_MM`` (a spatial low-pass
filter, transfer ``exp(-2 pi^2 sigma_a^2 k^2)`` at ``k`` cycles/mm). The asperities are grains
much narrower than the contact patch, at the points ``xi_j`` of a Poisson process of
``lambda_c`` per mm (fresh for every recording); through the patch each is a Gaussian bump of
width ``sigma_a`` and height ``H_j ~ Exponential(mean H_c)`` (um), added at its exact position.

The scan position follows a nominal speed ``v0 = SCAN_SPEED_MM_S`` with a per-recording speed
factor ``m ~ N(1, SPEED_SPREAD)`` and a slow wobble of three sinusoids (frequencies
``U(0.1, 1) Hz``, random phases, ``SPEED_WOBBLE_RMS`` rms in all)::

    v(t) = v0 * m * (1 + sum_k a_k sin(2 pi f_k t + psi_k))
    x(t) = v0 * m * (t + sum_k a_k (cos(psi_k) - cos(2 pi f_k t + psi_k)) / (2 pi f_k))

The sensor output (a.u.; 1 a.u. is ``UM_PER_AU`` um of filtered profile at nominal force) is::

    u(t) = kappa * h_a(x(t)) / UM_PER_AU + n(t)
    y    = B(u),                                  y <- y - mean(y)

with ``kappa ~ U(1 - FORCE_SPREAD, 1 + FORCE_SPREAD)`` the per-recording contact-force factor
(a harder press gives a larger force fluctuation) and ``n`` white Gaussian sensor noise of
``NOISE_RMS_AU`` rms per sample. ``B`` is the recording chain's anti-aliasing filter: a causal
Butterworth low-pass of order ``SENSOR_FILTER_ORDER`` with its corner at ``SENSOR_BAND_HZ``,
started in its steady state for the first sample (it is left out when ``SENSOR_BAND_HZ`` is not
below the Nyquist frequency ``fs_hz / 2``: the sampling then limits the band). The mean is
removed (an AC-coupled sensor: the static preload is not in the output). Samples are taken at
``t_k = k / fs_hz``, ``k = 0 .. round(duration_s * fs_hz) - 1``.

Classes
-------
======  ====================  ========  ======  =====  ========  ======  ========  =====
index   name                  shape     P (mm)  A(um)  sigma(um) l (mm)  lambda/mm H(um)
======  ====================  ========  ======  =====  ========  ======  ========  =====
0       sine-0.35mm-smooth    sine      0.35    2      2.1       0.02    1         7
1       sine-0.35mm-rough     sine      0.35    2      4.2       0.04    1         7
2       sine-0.35mm-gritty    sine      0.35    2      2.1       0.02    2.5       7
3       sine-0.30mm-smooth    sine      0.30    2      2.1       0.02    1         7
4       sine-0.42mm-smooth    sine      0.42    2      2.1       0.02    1         7
5       sawtooth-0.50mm-deep  sawtooth  0.50    7.5    15        0.02    2         12
6       bumps-0.75mm          bumps     0.75    2.5    1.7       0.02    1.5       6.5
7       bumps-0.90mm          bumps     0.90    2.5    1.7       0.02    1.5       6.5
8       square-0.75mm         square    0.75    1.7    1.7       0.02    1.5       6.5
9       grit-fine             none      --      0      1.4       0.02    3         5.5
10      grit-coarse           none      --      0      2         0.06    1         11.5
11      random-rough          none      --      0      9.5       0.03    0         0
======  ====================  ========  ======  =====  ========  ======  ========  =====

The table is built so that classes are separable but not trivially: 0/1/2 share the ridges and
differ in roughness (amount and correlation length), then in asperity density; 0/3/4 share
everything but the period (14-20 % apart), as do 6/7; 6/8 differ in ridge shape (harmonic
content) and depth; 5 is the one deep texture; 9/10/11 have no ridges: dense fine grains, sparse
large grains on a coarser roughness, and roughness alone. The values follow the physical picture
above; their levels, densities and the sensor band were set so that the classes' statistics fall
inside those measured on real recordings (last section), never to reach an accuracy or a figure.

Shapes of ``s(u)`` for the phase ``u = frac(x / P + phi_0)``:

- ``sine``: ``sin(2 pi u)``, one harmonic;
- ``square``: ``tanh(3 sin(2 pi u)) / tanh(3)``, a rounded square wave (odd harmonics);
- ``bumps``: ``2 exp(-(u - 1/2)^2 / (2 * 0.08^2)) - 1``, narrow ridges on a flat floor;
- ``sawtooth``: rises over 80 % of the period, falls over 20 % (all harmonics);
- ``triangle``: ``1 - 4 |u - 1/2|`` (odd harmonics, falling as 1/n^2);
- ``none``: 0.

Measured against real recordings
--------------------------------
Measured on 2026-11-23 with ``.venv/bin/python -m benchmarks.data_statistics``, which applies
:func:`class_statistics` (front end at 1 V full scale) to the VibTac-12 copy in
``shared/datasets/vibtac12`` (read with the project's loader: kind ``vibtac12``, z axis, 10
segments of 399 samples per texture, 200 Hz; segments of one recording stand in for the paper's
10 trials) and to this dataset at its defaults (seed 0, 10 recordings of 5 s per class, 2 kHz).
Per-class rows give the range over the 12 classes; dataset rows give one number per dataset, and
their VibTac-12 range is that of its x, y and z axes (the same recordings seen three ways: one
number has no spread of its own). "before" is this module before the calibration (force sensor
without a recording-chain filter, ridge-dominated classes, no asperities)::

    statistic               VibTac-12 min/max   before min/max      built-in min/max
    rms_v                   0.0370   0.1887     0.0517   0.1931     0.0428   0.1780
    rms_cv                  0.040    0.214      0.066    0.099      0.077    0.140
    mad_v                   0.0107   0.1514     0.0398   0.1880     0.0229   0.1152
    centroid_hz             33.4     47.6       13.3     61.6       35.2     44.1
    bandwidth_hz            20.0     27.1       37.9     132.6      21.9     24.6
    excess_kurtosis         -0.8     39.6       -1.5     0.1        -0.1     20.8
    across_class_cv         0.462    0.667      0.326    0.326      0.571    0.571
    across_class_ratio      2.94     9.48       3.74     3.74       4.16     4.16
    median_rms_v            0.0493   0.0675     0.1535   0.1535     0.0533   0.0533
    median_rms_cv           0.103    0.126      0.091    0.091      0.106    0.106
    centroid_nyquist        0.334    0.476      0.013    0.062      0.035    0.044
    bandwidth_nyquist       0.200    0.271      0.038    0.133      0.022    0.025

(``rms_v``, ``mad_v`` in V, the rest as in :class:`ClassStatistics`; VibTac-12's z axis alone
gives 0.667, 5.11, 0.0493 and 0.103 for the four dataset rows.) The tests check that every
built-in class and summary lies inside the VibTac-12 range, except the last two rows (not
matched, see below), and that both columns still read as printed here. Over seeds 0-7 every
per-class statistic stays inside the VibTac-12 range; of the summaries, ``median_rms_v`` spans
0.0494-0.0549 and ``median_rms_cv`` 0.098-0.126 (slightly below VibTac-12's range for some
seeds).

What the numbers say and what was changed. Levels are compared after the front end, in volts
of the 1 V full scale, because that is what the 0.02-0.2 V level-crossing thresholds see; the
front end maps the whole dataset's 99.9th percentile deviation to 0.5 V, so a level is set by
how a class compares with the loudest, most peaked parts of its dataset. VibTac-12 has two loud,
near-Gaussian textures and ten quieter ones, most of them peaky (median class 0.049 V, kurtosis
up to 40: mostly small vibration with sparse large events); before, most built-in classes sat at
0.13-0.19 V and were sub-Gaussian (ridge-dominated), with their power at the ridge fundamentals
(centroid 13-62 Hz) and a tail of harmonics and white sensor noise up to 1 kHz (bandwidth
38-133 Hz). Now one texture (5) is loud and one (11) in between, the others are quiet and carry
sparse asperities, ridges hold a smaller share of the power, and the recording chain has a band
like VibTac-12's.

Centroid and bandwidth are matched in Hz, not as fractions of the Nyquist frequency. VibTac-12
at 200 Hz is close to white up to its Nyquist frequency (last two rows; a white signal gives 0.5
and 0.289): its content lies below 100 Hz. The readout, the rate-coding windows and the taxel
delays all work in seconds, so the built-in recordings keep their content below about 100 Hz
too (``SENSOR_BAND_HZ``), which at 2 kHz is a few hundredths of their own Nyquist frequency.
Matching the fractions at 2 kHz would put the content near 400 Hz and multiply the level
crossings per second of signal about tenfold over VibTac-12's; matching both would need
sampling at 200 Hz.

Not matched: VibTac-12 is quantised to 6 bits (one count is 0.018 V at full scale) and its
segments last 2 s; the built-in recordings are not quantised and last ``duration_s`` (5 s by
default). The class levels, asperity densities, ``CONTACT_SIGMA_MM``, ``SENSOR_BAND_HZ`` and
``SENSOR_FILTER_ORDER`` were chosen to land inside the measured ranges; no accuracy or figure
was looked at.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.errors import DatasetError
from pipeline.frontend import fit_front_end
from pipeline.numbers import positive_number, whole_number
from pipeline.recording_set import Recordings

__all__ = [
    "CONTACT_SIGMA_MM",
    "DEFAULT_FS_HZ",
    "FORCE_SPREAD",
    "GRID_MM",
    "NOISE_RMS_AU",
    "SCAN_SPEED_MM_S",
    "SENSOR_BAND_HZ",
    "SENSOR_FILTER_ORDER",
    "SPEED_SPREAD",
    "SPEED_WOBBLE_RMS",
    "TEXTURE_CLASSES",
    "UM_PER_AU",
    "ClassStatistics",
    "TextureClass",
    "class_statistics",
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
CONTACT_SIGMA_MM = 0.03
#: Profile height (um) that gives 1 a.u. of force at nominal contact force.
UM_PER_AU = 10.0
#: RMS of the additive white sensor noise per sample, before the sensor filter (a.u.).
NOISE_RMS_AU = 0.05
#: Corner frequency of the recording chain's anti-aliasing low-pass (Hz).
SENSOR_BAND_HZ = 85.0
#: Order of that Butterworth low-pass.
SENSOR_FILTER_ORDER = 8
#: Spatial grid on which the surface is generated (mm); well below CONTACT_SIGMA_MM.
GRID_MM = 0.005

_WOBBLE_COMPONENTS = 3
_WOBBLE_BAND_HZ = (0.1, 1.0)
# An asperity's bump is added over +-this many contact widths (exp(-4.5^2 / 2) < 4e-5).
_ASPERITY_REACH = 4.5


@dataclass(frozen=True)
class TextureClass:
    """One synthetic texture: a ridge pattern, random roughness and scattered asperities.

    Attributes
    ----------
    name
        Class name, e.g. ``"sine-0.50mm-smooth"``.
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
    asperities_per_mm
        Mean number ``lambda`` of asperities per mm of scan (0: none).
    asperity_um
        Mean height ``H`` (um) of an asperity as the contact patch sees it.
    """

    name: str
    shape: str
    period_mm: float
    ridge_um: float
    roughness_um: float
    correlation_mm: float
    asperities_per_mm: float = 0.0
    asperity_um: float = 0.0


TEXTURE_CLASSES: tuple[TextureClass, ...] = (
    TextureClass("sine-0.35mm-smooth", "sine", 0.35, 2.0, 2.1, 0.02, 1.0, 7.0),
    TextureClass("sine-0.35mm-rough", "sine", 0.35, 2.0, 4.2, 0.04, 1.0, 7.0),
    TextureClass("sine-0.35mm-gritty", "sine", 0.35, 2.0, 2.1, 0.02, 2.5, 7.0),
    TextureClass("sine-0.30mm-smooth", "sine", 0.30, 2.0, 2.1, 0.02, 1.0, 7.0),
    TextureClass("sine-0.42mm-smooth", "sine", 0.42, 2.0, 2.1, 0.02, 1.0, 7.0),
    TextureClass("sawtooth-0.50mm-deep", "sawtooth", 0.50, 7.5, 15.0, 0.02, 2.0, 12.0),
    TextureClass("bumps-0.75mm", "bumps", 0.75, 2.5, 1.7, 0.02, 1.5, 6.5),
    TextureClass("bumps-0.90mm", "bumps", 0.90, 2.5, 1.7, 0.02, 1.5, 6.5),
    TextureClass("square-0.75mm", "square", 0.75, 1.7, 1.7, 0.02, 1.5, 6.5),
    TextureClass("grit-fine", "none", 1.00, 0.0, 1.4, 0.02, 3.0, 5.5),
    TextureClass("grit-coarse", "none", 1.00, 0.0, 2.0, 0.06, 1.0, 11.5),
    TextureClass("random-rough", "none", 1.00, 0.0, 9.5, 0.03, 0.0, 0.0),
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
            children = np.random.SeedSequence([int(seed), c, r]).spawn(4)
            streams = tuple(np.random.default_rng(s) for s in children)
            signals.append(_recording(texture, t, float(fs_hz), streams))
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
    fs_hz: float,
    streams: tuple[np.random.Generator, ...],
) -> np.ndarray:
    """One recording: float64, shape ``t.shape``, a.u. (the model of the module docstring).

    ``streams`` are the scan, roughness, asperity and sensor-noise generators, in that order.
    """
    # scipy.ndimage and scipy.signal take seconds to import; a sweep whose recordings are all
    # cached, or that checks a grid on other recordings, never needs them.
    from scipy.ndimage import gaussian_filter1d
    from scipy.signal import butter, sosfilt, sosfilt_zi

    scan, rough, grains, noise = streams
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
    if texture.asperities_per_mm > 0 and texture.asperity_um > 0:
        contact += _asperities(grains, grid, texture.asperities_per_mm, texture.asperity_um)

    u = kappa * np.interp(x, grid, contact) / UM_PER_AU
    u += NOISE_RMS_AU * noise.standard_normal(t.size)
    if SENSOR_BAND_HZ < fs_hz / 2:
        sos = butter(SENSOR_FILTER_ORDER, SENSOR_BAND_HZ, fs=fs_hz, output="sos")
        u, _ = sosfilt(sos, u, zi=sosfilt_zi(sos) * u[0])
    return u - u.mean()


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


# ---------------------------------------------------------------------------------------------
# Statistics of a dataset's classes (what the comparison with real recordings measures)


@dataclass(frozen=True, eq=False)
class ClassStatistics:
    """Per-class statistics of a dataset, as :func:`class_statistics` measures them.

    Every array is float64 of shape ``(n_classes,)``, in class-label order; a class value is the
    mean over the class's recordings of the per-recording value, except ``rms_cv``.

    Attributes
    ----------
    dataset
        Name of the dataset.
    class_names
        ``n_classes`` names.
    fs_hz
        Sampling rate (Hz).
    units
        Units of the recordings (``rms``).
    full_scale_v
        Full scale of the front end (V) that ``rms_v`` and ``mad_v`` refer to.
    gain_v_per_unit
        The front end's gain fitted on the whole dataset (V per recording unit).
    n_recordings
        int64: recordings per class.
    rms
        RMS of the mean-removed recording (recording units).
    rms_v
        ``rms`` after the front end (V): ``gain_v_per_unit * rms``.
    rms_cv
        Within-class coefficient of variation of the recordings' RMS, ``std(ddof=1) / mean``
        (NaN for a class of one recording).
    mad_v
        Median absolute deviation from the recording's mean after the front end (V).
    centroid_hz
        Power-weighted mean frequency of the recording's periodogram (Hz).
    bandwidth_hz
        Power-weighted standard deviation of frequency about the centroid (Hz).
    excess_kurtosis
        Fisher (excess) kurtosis of the samples (0 for a Gaussian, -1.5 for a sine).
    """

    dataset: str
    class_names: tuple[str, ...]
    fs_hz: float
    units: str
    full_scale_v: float
    gain_v_per_unit: float
    n_recordings: np.ndarray
    rms: np.ndarray
    rms_v: np.ndarray
    rms_cv: np.ndarray
    mad_v: np.ndarray
    centroid_hz: np.ndarray
    bandwidth_hz: np.ndarray
    excess_kurtosis: np.ndarray

    @property
    def nyquist_hz(self) -> float:
        """``fs_hz / 2`` (Hz)."""
        return self.fs_hz / 2.0

    @property
    def centroid_nyquist(self) -> np.ndarray:
        """float64 ``(n_classes,)``: ``centroid_hz`` as a fraction of the Nyquist frequency."""
        return self.centroid_hz / self.nyquist_hz

    @property
    def bandwidth_nyquist(self) -> np.ndarray:
        """float64 ``(n_classes,)``: ``bandwidth_hz`` as a fraction of the Nyquist frequency."""
        return self.bandwidth_hz / self.nyquist_hz

    @property
    def across_class_cv(self) -> float:
        """Spread of the class levels: ``std(rms_v, ddof=1) / mean(rms_v)`` over the classes."""
        return float(np.std(self.rms_v, ddof=1) / np.mean(self.rms_v))

    @property
    def across_class_ratio(self) -> float:
        """Loudest over quietest class: ``max(rms_v) / min(rms_v)``."""
        return float(np.max(self.rms_v) / np.min(self.rms_v))

    @property
    def median_rms_v(self) -> float:
        """Median over the classes of ``rms_v`` (V)."""
        return float(np.median(self.rms_v))

    @property
    def median_rms_cv(self) -> float:
        """Median over the classes of ``rms_cv``."""
        return float(np.median(self.rms_cv))


def class_statistics(recordings: Recordings, *, full_scale_v: float = 1.0) -> ClassStatistics:
    """Level, spread, spectrum and peakedness of each class of a dataset.

    Per recording ``x`` (mean removed, ``x0 = x - mean(x)``): ``rms = sqrt(mean(x0^2))``;
    ``mad = median(|x0|)``; the periodogram ``P(f)`` of ``x0`` (:func:`scipy.signal.periodogram`,
    rectangular window) gives ``centroid = sum(f P) / sum(P)`` and
    ``bandwidth = sqrt(sum((f - centroid)^2 P) / sum(P))``; the excess kurtosis is
    :func:`scipy.stats.kurtosis` (Fisher, biased). Volts are those of the project's front end
    (:func:`pipeline.frontend.fit_front_end`, fitted on the whole dataset at ``full_scale_v``),
    which is what the level-crossing threshold is compared with: this makes levels of datasets
    in different units comparable.

    Parameters
    ----------
    recordings
        Any dataset; every class needs at least one recording.
    full_scale_v
        Full scale of the front end (V, finite and > 0).

    Returns
    -------
    ClassStatistics
        A constant recording has ``rms = 0`` and NaN spectrum and kurtosis.

    Raises
    ------
    ValueError
        A class without recordings, or ``full_scale_v`` not a finite number > 0.
    """
    from scipy.signal import periodogram
    from scipy.stats import kurtosis

    counts = np.bincount(recordings.labels, minlength=recordings.n_classes)
    empty = [name for name, n in zip(recordings.class_names, counts, strict=True) if n == 0]
    if empty:
        raise ValueError(f"dataset {recordings.name}: classes without recordings: {empty}")
    gain = fit_front_end(recordings, full_scale_v).gain_v_per_unit
    per_recording = np.empty((recordings.n_recordings, 5))
    for n, signal in enumerate(recordings.signals):
        x0 = signal - signal.mean()
        freqs, power = periodogram(x0, fs=recordings.fs_hz, detrend=False)
        total = power.sum()
        with np.errstate(invalid="ignore", divide="ignore"):
            centroid = (freqs * power).sum() / total
            bandwidth = math.sqrt(((freqs - centroid) ** 2 * power).sum() / total)
            peakedness = kurtosis(x0) if total > 0 else math.nan
        rms = math.sqrt(np.mean(x0**2))
        per_recording[n] = rms, np.median(np.abs(x0)), centroid, bandwidth, peakedness

    def by_class(column: int, reduce=np.mean) -> np.ndarray:
        values = per_recording[:, column]
        return np.array([reduce(values[recordings.labels == c]) for c in range(len(counts))])

    rms = by_class(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms_cv = by_class(0, lambda v: np.std(v, ddof=1) / np.mean(v) if v.size > 1 else np.nan)
    return ClassStatistics(
        dataset=recordings.name,
        class_names=recordings.class_names,
        fs_hz=recordings.fs_hz,
        units=recordings.units,
        full_scale_v=float(full_scale_v),
        gain_v_per_unit=gain,
        n_recordings=counts.astype(np.int64),
        rms=rms,
        rms_v=gain * rms,
        rms_cv=rms_cv,
        mad_v=gain * by_class(1),
        centroid_hz=by_class(2),
        bandwidth_hz=by_class(3),
        excess_kurtosis=by_class(4),
    )
