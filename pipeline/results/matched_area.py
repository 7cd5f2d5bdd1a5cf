r"""Area of the comparators' matched devices, by Pelgrom's law.

A design that names a threshold mismatch ``sigma_rel`` (``readout.effects.threshold_mismatch``: each
taxel's threshold is ``threshold_v * (1 + sigma_rel * z)``) asks for comparators whose input offset
has the standard deviation ``sigma_V = sigma_rel * threshold_v``. The offset of a differential pair
is the threshold-voltage difference of its two input transistors, which Pelgrom's law (M. J. M.
Pelgrom, A. C. J. Duinmaijer and A. P. G. Welbers, "Matching properties of MOS transistors", IEEE
JSSC 24(5), 1989) gives as ``sigma(dV_T) = A_VT / sqrt(W L)``, so each input transistor needs the
gate area

.. math::

    W L = \left(\frac{A_\mathrm{VT}}{\sigma_V}\right)^2
        = \left(\frac{A_\mathrm{VT}}{\mathrm{sigma\_rel} \cdot \mathrm{threshold\_v}}\right)^2
        \quad \text{[m}^2\text{]},

and a taxel, with two comparators (up and down) of two input transistors each
(:data:`MATCHED_DEVICES_PER_TAXEL`), ``A_taxel = 4 W L``; the array ``A_array = n A_taxel``
(:func:`taxel_area_m2`, :func:`array_area_m2`). :data:`A_VT_V_M` is declared once with its process
(:data:`A_VT_PROCESS`), unit, meaning and source (``A_VT``); a designer's own value (a
foundry's matching data) comes in as ``a_vt_v_m``. This is the matched gate area the
mismatch demands, not a layout: wiring, the front end and the comparators' other devices are
not counted, so it is a lower bound, and a meaningful one only where it exceeds the process's
minimum device (0.22 um x 0.18 um = 0.04 um^2 in 180 nm CMOS), which is not applied. A design
that names no mismatch, or ``sigma_rel = 0``, assumes perfect matching, which no finite device
gives: its area is not stated (NaN), rather than infinite or a guessed minimum.

Units: voltages in V, areas in m^2, A_VT in V m. The functions broadcast
(:mod:`pipeline.results.broadcast`): scalars, numpy arrays and ``xarray.DataArray`` inputs work
alike, and a DataArray keeps its dimensions and coordinates.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pipeline.results.broadcast import keep, non_negative, plain
from pipeline.results.readout_constants import Parameter

__all__ = [
    "A_VT",
    "A_VT_PROCESS",
    "A_VT_V_M",
    "MATCHED_DEVICES_PER_TAXEL",
    "array_area_m2",
    "matched_device_area_m2",
    "offset_sigma_v",
    "taxel_area_m2",
]

A_VT_V_M = 5e-9
"""Pelgrom's threshold-matching coefficient A_VT, in V m (5 mV um), of :data:`A_VT_PROCESS`
(declared as ``A_VT``)."""
A_VT_PROCESS = "180 nm bulk CMOS (gate oxide about 4 nm)"
"""The process :data:`A_VT_V_M` stands for."""
A_VT = Parameter(
    "mV um",
    1e-9,
    "Pelgrom's threshold-matching coefficient A_VT of the comparators' input pairs, "
    f"{A_VT_PROCESS}",
    "assumed from the trend of A_VT with gate-oxide thickness, about 1 mV um per nm of oxide, "
    "reviewed in P. R. Kinget, 'Device mismatch and tradeoffs in the design of analog "
    "circuits', IEEE JSSC 40(6), 2005, Sec. II; an order-of-magnitude figure: a foundry's "
    "matching data for the process at hand replaces it",
    positive=True,
)
"""The declaration of :data:`A_VT_V_M`, with its unit, what it is and where it comes from (a
constants file overrides it, :mod:`pipeline.results.hardware_constants`)."""
MATCHED_DEVICES_PER_TAXEL = 4
"""Matched input transistors per taxel (two comparators, up and down, a differential pair each)."""


def offset_sigma_v(sigma_rel: Any, threshold_v: Any) -> Any:
    """Standard deviation of a taxel's threshold, ``sigma_rel * threshold_v``, in V.

    ``sigma_rel`` (relative threshold mismatch, ``readout.effects.threshold_mismatch.sigma_rel``)
    and ``threshold_v`` (V) are finite and >= 0 and broadcast (float64 V).
    """
    sigma_rel = non_negative("sigma_rel", sigma_rel)
    threshold_v = non_negative("threshold_v", threshold_v)
    return plain(1.0 * sigma_rel * threshold_v)


def matched_device_area_m2(sigma_v: Any, a_vt_v_m: float = A_VT_V_M) -> Any:
    """Gate area ``W L = (A_VT / sigma_V)**2`` of one transistor of a pair whose offset has the
    standard deviation ``sigma_v`` (V), in m^2 (Pelgrom's law, see the module docstring).

    ``sigma_v`` is finite and >= 0 and broadcasts; where it is 0 (perfect matching) the area is
    NaN: no finite device gives it. ``a_vt_v_m`` is A_VT in V m (default :data:`A_VT_V_M`).

    Raises
    ------
    ValueError
        An input is not numeric, is NaN, infinite or negative, or ``a_vt_v_m`` is not > 0.
    """
    sigma_v = non_negative("sigma_v", sigma_v)
    if not (math.isfinite(a_vt_v_m) and a_vt_v_m > 0):
        raise ValueError(f"a_vt_v_m must be finite and > 0, got {a_vt_v_m!r}")
    sigma = np.asarray(sigma_v, dtype=np.float64)
    with np.errstate(divide="ignore"):
        area = np.where(sigma > 0, (a_vt_v_m / np.where(sigma > 0, sigma, 1.0)) ** 2, np.nan)
    return keep(sigma_v, area)


def taxel_area_m2(sigma_rel: Any, threshold_v: Any, a_vt_v_m: float = A_VT_V_M) -> Any:
    """Matched gate area of one taxel, ``MATCHED_DEVICES_PER_TAXEL * W L``, in m^2.

    ``W L`` is :func:`matched_device_area_m2` of :func:`offset_sigma_v`; the inputs broadcast;
    NaN where ``sigma_rel * threshold_v`` is 0 (no mismatch named: nothing to size for).
    """
    device = matched_device_area_m2(offset_sigma_v(sigma_rel, threshold_v), a_vt_v_m)
    return plain(MATCHED_DEVICES_PER_TAXEL * device)


def array_area_m2(
    n_taxels: Any, sigma_rel: Any, threshold_v: Any, a_vt_v_m: float = A_VT_V_M
) -> Any:
    """Matched gate area of an array of ``n_taxels`` taxels, ``n_taxels * taxel_area_m2``, in
    m^2; the inputs broadcast, NaN as in :func:`taxel_area_m2`."""
    n_taxels = non_negative("n_taxels", n_taxels)
    return plain(1.0 * n_taxels * taxel_area_m2(sigma_rel, threshold_v, a_vt_v_m))
