"""The built-in dataset's materials: twelve texture classes, their ridge shapes and the slow
variation of a material sample along the sliding path.

A class is one material sample (:class:`TextureClass`): a surface texture (ridges of a shape,
period and amplitude, roughness, asperities) and its mechanics (friction, stiffness, relaxation,
Stribeck speed, patchiness, macro texture). How a touch presses and slides on it and what the
sensor reports is :mod:`pipeline.recordings.touch`; the dataset of touches is
:mod:`pipeline.recordings.synthetic`.

The sample varies slowly along the path: ``g_m(x)`` (:func:`material_map`) is a stationary
Gaussian process of unit variance with a Gaussian spectrum of correlation length
``MAP_CORRELATION_MM``, periodic over ``MAP_PERIOD_MM``, drawn once per class from
``SeedSequence([seed, class_index], spawn_key=(1000,))``, which no recording uses.

Classes
-------
======  ====================  ========  ======  =====  =========  ======  =========  =====
index   name                  shape     P (mm)  A(um)  sigma(um)  l (mm)  lambda/mm  H(um)
======  ====================  ========  ======  =====  =========  ======  =========  =====
0       sine-0.35mm-smooth    sine      0.35    2      2.1        0.02    1          7
1       sine-0.35mm-rough     sine      0.35    2      4.2        0.04    1          7
2       sine-0.35mm-gritty    sine      0.35    2      2.1        0.02    2.5        7
3       sine-0.30mm-smooth    sine      0.30    2      2.1        0.02    1          7
4       sine-0.42mm-smooth    sine      0.42    2      2.1        0.02    1          7
5       sawtooth-0.50mm-deep  sawtooth  0.50    7.5    15         0.02    2          12
6       bumps-0.75mm          bumps     0.75    2.5    1.7        0.02    1.5        6.5
7       bumps-0.90mm          bumps     0.90    2.5    1.7        0.02    1.5        6.5
8       square-0.75mm         square    0.75    1.7    1.7        0.02    1.5        6.5
9       grit-fine             none      --      0      1.4        0.02    3          5.5
10      grit-coarse           none      --      0      2          0.06    1          11.5
11      random-rough          none      --      0      9.5        0.03    0          0
======  ====================  ========  ======  =====  =========  ======  =========  =====

Mechanics (friction coefficients, material stiffness ``k_m``, relaxing share ``r``, Stribeck
speed ``v_c``, patchiness ``s``) and macro texture (period ``Lambda``, depth ``beta``; the macro
rate ``v / Lambda`` at 20 mm/s; 0: none)::

    index   mu_s   mu_k   k_m (N/mm)  r     v_c (mm/s)  s     Lambda (mm)  beta  v/Lambda (Hz)
    0       0.55   0.40   2.0         0.20  25          0.35  1.40         0.8   14.3
    1       0.65   0.45   2.0         0.20  20          0.42  1.75         0.8   11.4
    2       0.70   0.50   2.0         0.20  18          0.42  1.05         0.8   19.0
    3       0.55   0.40   2.0         0.20  30          0.35  1.20         0.8   16.7
    4       0.55   0.40   2.0         0.20  22          0.35  2.10         0.8   9.5
    5       0.80   0.50   4.0         0.12  25          0.49  3.00         0.8   6.7
    6       0.45   0.35   1.0         0.28  30          0.28  2.25         0.8   8.9
    7       0.45   0.35   1.0         0.28  25          0.28  1.80         0.8   11.1
    8       0.55   0.35   1.5         0.24  20          0.35  3.00         0.8   6.7
    9       0.85   0.55   3.0         0.16  25          0.56  --           0     --
    10      0.80   0.60   3.0         0.16  15          0.49  --           0     --
    11      0.65   0.45   0.6         0.32  30          0.42  2.60         0.8   7.7

A ridged texture's macro period is a whole number of its ridges (4, 5, 3, 4, 5, 6, 3, 2, 4); the
grits have none (their sliding is modulated by stick-slip alone); the random-rough sample is a
fibrous one whose fibres bunch every 2.6 mm.

The classes are separable but not trivially: 0/1/2 share the ridges and differ in roughness, then
in asperity density, and in friction; 0/3/4 share the mechanics and differ in the period (14-20 %
apart) and Stribeck speed, as 6/7 do; 6/8 differ in ridge shape and friction; 5 is the one deep,
stiff texture; 9/10/11 have no ridges (dense fine grains and sparse large grains on grippy, stiff
samples; roughness alone on a soft one). Soft materials (6, 7, 11) press slowly and relax most.

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

__all__ = [
    "MAP_CORRELATION_MM",
    "MAP_PERIOD_MM",
    "MAP_SAMPLES",
    "TEXTURE_CLASSES",
    "TextureClass",
    "material_map",
    "periodic_process",
    "ridge_shape",
]

#: Period (mm) of a sample's slow variation along the path.
MAP_PERIOD_MM = 400.0
#: Correlation length (mm) of a sample's slow variation along the path.
MAP_CORRELATION_MM = 6.0
# Samples of the material map over one period.
MAP_SAMPLES = 2048
# Child stream of SeedSequence([seed, class]) that draws the material sample; a recording's own
# streams are the children 0..3 of SeedSequence([seed, class, recording]). (A key of its own is
# needed: SeedSequence([s, c]) and SeedSequence([s, c, 0]) hold the same entropy.)
_MATERIAL_STREAM = 1000


@dataclass(frozen=True)
class TextureClass:
    """One material: its surface texture and its mechanics.

    Attributes
    ----------
    name
        Class name, e.g. ``"sine-0.35mm-smooth"``.
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
    mu_static, mu_kinetic
        Static and kinetic friction coefficients ``mu_s > mu_k`` of the fingertip on it.
    stiffness_n_per_mm
        Normal contact stiffness ``k_m`` of the material (N/mm; its compliance is ``1 / k_m``).
    relaxation
        Share ``r`` of the normal force that relaxes (time constant
        :data:`pipeline.recordings.touch.RELAX_S`) while the height is held.
    stribeck_mm_s
        Stribeck speed ``v_c`` (mm/s): stick-slip dies out as the sliding speed exceeds it.
    patchiness
        Standard deviation ``s`` of the log of the sample's local friction and texture factor.
    macro_period_mm
        Macro period ``Lambda`` (mm) over which the texture's vibration is modulated (its ridges
        or grains come in groups); ignored when ``macro_depth`` is 0.
    macro_depth
        Depth ``beta`` in ``[0, 1)`` of that modulation (0: no macro texture).
    """

    name: str
    shape: str
    period_mm: float
    ridge_um: float
    roughness_um: float
    correlation_mm: float
    asperities_per_mm: float
    asperity_um: float
    mu_static: float
    mu_kinetic: float
    stiffness_n_per_mm: float
    relaxation: float
    stribeck_mm_s: float
    patchiness: float
    macro_period_mm: float
    macro_depth: float


# name, shape, P (mm), A (um), sigma (um), l (mm), lambda (/mm), H (um): the module docstring.
_TEXTURES = (
    ("sine-0.35mm-smooth", "sine", 0.35, 2.0, 2.1, 0.02, 1.0, 7.0),
    ("sine-0.35mm-rough", "sine", 0.35, 2.0, 4.2, 0.04, 1.0, 7.0),
    ("sine-0.35mm-gritty", "sine", 0.35, 2.0, 2.1, 0.02, 2.5, 7.0),
    ("sine-0.30mm-smooth", "sine", 0.30, 2.0, 2.1, 0.02, 1.0, 7.0),
    ("sine-0.42mm-smooth", "sine", 0.42, 2.0, 2.1, 0.02, 1.0, 7.0),
    ("sawtooth-0.50mm-deep", "sawtooth", 0.50, 7.5, 15.0, 0.02, 2.0, 12.0),
    ("bumps-0.75mm", "bumps", 0.75, 2.5, 1.7, 0.02, 1.5, 6.5),
    ("bumps-0.90mm", "bumps", 0.90, 2.5, 1.7, 0.02, 1.5, 6.5),
    ("square-0.75mm", "square", 0.75, 1.7, 1.7, 0.02, 1.5, 6.5),
    ("grit-fine", "none", 1.00, 0.0, 1.4, 0.02, 3.0, 5.5),
    ("grit-coarse", "none", 1.00, 0.0, 2.0, 0.06, 1.0, 11.5),
    ("random-rough", "none", 1.00, 0.0, 9.5, 0.03, 0.0, 0.0),
)
# mu_s, mu_k, k_m (N/mm), r, v_c (mm/s), s: the module docstring.
_MECHANICS = (
    (0.55, 0.40, 2.00, 0.20, 25.0, 0.35),
    (0.65, 0.45, 2.00, 0.20, 20.0, 0.42),
    (0.70, 0.50, 2.00, 0.20, 18.0, 0.42),
    (0.55, 0.40, 2.00, 0.20, 30.0, 0.35),
    (0.55, 0.40, 2.00, 0.20, 22.0, 0.35),
    (0.80, 0.50, 4.00, 0.12, 25.0, 0.49),
    (0.45, 0.35, 1.00, 0.28, 30.0, 0.28),
    (0.45, 0.35, 1.00, 0.28, 25.0, 0.28),
    (0.55, 0.35, 1.50, 0.24, 20.0, 0.35),
    (0.85, 0.55, 3.00, 0.16, 25.0, 0.56),
    (0.80, 0.60, 3.00, 0.16, 15.0, 0.49),
    (0.65, 0.45, 0.60, 0.32, 30.0, 0.42),
)
# Macro period Lambda (mm), its depth beta: the module docstring.
_MACRO = (
    (1.40, 0.8),
    (1.75, 0.8),
    (1.05, 0.8),
    (1.20, 0.8),
    (2.10, 0.8),
    (3.00, 0.8),
    (2.25, 0.8),
    (1.80, 0.8),
    (3.00, 0.8),
    (1.00, 0.0),
    (1.00, 0.0),
    (2.60, 0.8),
)
TEXTURE_CLASSES: tuple[TextureClass, ...] = tuple(
    TextureClass(*texture, *mechanics, *macro)
    for texture, mechanics, macro in zip(_TEXTURES, _MECHANICS, _MACRO, strict=True)
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


def material_map(seed: int, class_index: int) -> np.ndarray:
    """The material sample's slow variation along the path: float64 ``(MAP_SAMPLES,)``.

    A stationary Gaussian process of unit variance, periodic over :data:`MAP_PERIOD_MM`, with a
    Gaussian spectrum of correlation length :data:`MAP_CORRELATION_MM`, sampled at
    ``MAP_PERIOD_MM / MAP_SAMPLES`` mm; drawn from ``SeedSequence([seed, class_index])``'s
    child ``_MATERIAL_STREAM``, so every touch of the class meets the same sample.
    """
    stream = np.random.SeedSequence([int(seed), int(class_index)], spawn_key=(_MATERIAL_STREAM,))
    return periodic_process(np.random.default_rng(stream))


def periodic_process(rng: np.random.Generator) -> np.ndarray:
    """Unit-variance periodic Gaussian process on the map's grid (see :func:`material_map`)."""
    k = np.fft.rfftfreq(MAP_SAMPLES, d=MAP_PERIOD_MM / MAP_SAMPLES)  # cycles/mm
    weight = np.exp(-((math.pi * k * MAP_CORRELATION_MM) ** 2))
    weight[0] = 0.0
    coefficients = (rng.standard_normal(k.size) + 1j * rng.standard_normal(k.size)) * weight
    process = np.fft.irfft(coefficients, MAP_SAMPLES)
    return process / process.std()
