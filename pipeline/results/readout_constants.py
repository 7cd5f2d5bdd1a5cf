r"""The readout's energy constants, declared once as data with their defaults and sources.

The equations that use them are in :mod:`pipeline.results.readout_power`. Each constant is a field
of :class:`EnergyModel` whose :class:`Parameter` says its command-line option and unit, what it
is and where its default comes from; the command line takes each in that unit
(``--front-end-nw``, ``--event-energy-pj``, ...), and the report states every one with its
source (:meth:`EnergyModel.assumptions`). Units in the field names, SI. A designer's constants
file overrides any of them by field name, each with its source
(:mod:`pipeline.results.hardware_constants`).

The constants, their defaults and sources:

===========================  ========  =====================================================
``front_end_w_per_taxel``    10 nW     CALIBRATED on the chip below (the remainder)
``comparator_w_per_taxel``   2 nW      two comparators in weak inversion, ~1 nA each at ~1 V
``event_energy_j``           10 pJ     per event: comparator switching, address-event encoder
``link_energy_j_per_bit``    1 pJ      low-power wired serial links
``adc_fom_j_per_step``       10 fJ     low-power SAR ADCs at kHz rates (Murmann's survey)
``adc_static_w``             100 nW    per ADC, reference buffer and sampling driver
``taxels_per_adc``           16        taxels multiplexed onto one ADC (one per column)
===========================  ========  =====================================================

Calibration. The closest silicon is M. D. Alea et al., "A Fingertip-Mimicking 12x16 200-um
Resolution e-Skin Taxel Readout Chip with Per-Taxel Spiking Readout and Embedded Receptive Field
Processing", IEEE TBioCAS, Dec. 2024, doi 10.1109/TBCAS.2024.3387545: 192 taxels, 3-5 equivalent
bits, 2.2 kevent/s for the whole array and 12.33 nW per taxel. The chip reports only the total
per taxel, so one constant is calibrated and the rest are taken from the literature: the
comparators (2 nW), the event energy (10 pJ) and the link (1 pJ per bit) are literature values;
at the chip's activity their dynamic part is ``(2200 * 10 pJ + 2200 * 9 bit * 1 pJ) / 192 =
0.22 nW`` per taxel, and the front end's bias is the remainder, ``12.33 - 2 - 0.22 = 10.1 nW``,
rounded to 10 nW. Fed the chip's array, the model gives 12.22 nW per taxel (0.9 % below the
chip; a test holds it within 30 %). Static power is then 98 % of the event readout's power: at
such rates the bias floor, not the events, sets the cost. The frame readout's ADC constants are
order-of-magnitude ASSUMPTIONS (no frame-readout chip of this array is calibrated here).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

__all__ = [
    "CHIP",
    "CHIP_EVENT_RATE_HZ",
    "CHIP_TAXELS",
    "PARAMETERS",
    "EnergyModel",
    "Parameter",
]

CHIP = (
    "M. D. Alea et al., IEEE TBioCAS, Dec. 2024 (doi 10.1109/TBCAS.2024.3387545): 192 taxels, "
    "2.2 kevent/s, 12.33 nW per taxel"
)
"""The chip the event readout's defaults are calibrated on (see the module docstring)."""
CHIP_TAXELS, CHIP_EVENT_RATE_HZ = 192, 2200.0
"""Its array and its events per second in all, which the calibration feeds the model."""


@dataclass(frozen=True)
class Parameter:
    """How one hardware constant is stated: declared once, where the constant is kept (the
    :class:`EnergyModel` fields here, ``A_VT`` beside
    :data:`pipeline.results.matched_area.A_VT_V_M`).

    ``unit`` is the unit the constant is given in (``scale`` SI units each, e.g. pJ = 1e-12 J) on
    the command line and in a constants file (:mod:`pipeline.results.hardware_constants`);
    ``what`` says what it is, ``source`` where its default comes from; ``option`` is its
    command-line option (empty: none); ``calibrated`` marks the constant fitted to :data:`CHIP`
    (the others are literature values or assumptions); ``count`` marks an integer count >= 1 (no
    unit); ``positive`` a constant that must be above 0.
    """

    unit: str
    scale: float
    what: str
    source: str
    option: str = ""
    calibrated: bool = False
    count: bool = False
    positive: bool = False

    def problem(self, value: Any, name: str = "") -> str | None:
        """Why ``value`` (in :attr:`unit`) is not valid, or None; the reason starts with
        ``name`` (default :attr:`option`)."""
        name = name or self.option
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            return f"{name} {value!r}: need a number"
        if self.count:
            if not (math.isfinite(value) and value >= 1 and value == int(value)):
                return f"{name} {value:g}: need a whole number >= 1"
        elif self.positive and not (math.isfinite(value) and value > 0):
            return f"{name} {value:g}: need a finite number > 0"
        elif not math.isfinite(value) or value < 0:
            return f"{name} {value:g}: need a finite number >= 0"
        return None


def _constant(default: float, parameter: Parameter) -> Any:
    return field(default=default, metadata={"parameter": parameter})


@dataclass(frozen=True)
class EnergyModel:
    """Constants of the power estimate, in SI units; defaults and sources in the module docstring.

    Parameters
    ----------
    front_end_w_per_taxel : float
        Static (bias) power of one taxel's front end, in W; both readouts pay it. Default 10 nW,
        calibrated on :data:`CHIP`.
    comparator_w_per_taxel : float
        Static power of one taxel's level-crossing comparators, in W (event readout). Default
        2 nW.
    event_energy_j : float
        Energy per spike event, in J: comparator switching and the address-event encoder.
        Default 10 pJ.
    link_energy_j_per_bit : float
        Energy per bit sent on the link, in J, charged to both readouts. Default 1 pJ.
    adc_fom_j_per_step : float
        Walden figure of merit of the frame readout's ADC, in J per conversion step; one
        conversion of ``bits`` bits costs ``adc_fom_j_per_step * 2**bits``. Default 10 fJ.
    adc_static_w : float
        Static power of one ADC not counted in its figure of merit, in W. Default 100 nW.
    taxels_per_adc : int
        Taxels multiplexed onto one ADC of the frame readout, >= 1. Default 16.

    Raises
    ------
    ValueError
        If a constant is not a finite number >= 0 (a whole number >= 1 for ``taxels_per_adc``);
        the message names every such field and its value.
    """

    front_end_w_per_taxel: float = _constant(
        10e-9,
        Parameter(
            "nW per taxel",
            1e-9,
            "static bias of one taxel's front end (both readouts)",
            f"calibrated on the chip of {CHIP}, as the remainder once the other constants "
            "are taken",
            calibrated=True,
            option="--front-end-nw",
        ),
    )
    comparator_w_per_taxel: float = _constant(
        2e-9,
        Parameter(
            "nW per taxel",
            1e-9,
            "static bias of one taxel's two level-crossing comparators (event readout)",
            "assumed: continuous-time comparators biased in weak inversion, of the order of 1 "
            "nA each at about 1 V, as in low-power level-crossing ADCs",
            option="--comparator-nw",
        ),
    )
    event_energy_j: float = _constant(
        10e-12,
        Parameter(
            "pJ per event",
            1e-12,
            "energy of the comparators' switching and the address-event encoder, per event",
            "assumed from event-driven readouts and address-event interfaces in the "
            "neuromorphic-sensor literature (tens of pJ per event is typical)",
            option="--event-energy-pj",
        ),
    )
    link_energy_j_per_bit: float = _constant(
        1e-12,
        Parameter(
            "pJ per bit",
            1e-12,
            "energy per bit sent on the link (both readouts)",
            "assumed from low-power wired serial links (of the order of 1 pJ per bit)",
            option="--link-energy-pj-per-bit",
        ),
    )
    adc_fom_j_per_step: float = _constant(
        10e-15,
        Parameter(
            "fJ per conversion step",
            1e-15,
            "Walden figure of merit of the frame readout's ADC, one conversion costing "
            "FOM * 2**bits",
            "assumed from low-power SAR ADCs at kHz sampling rates in B. Murmann's ADC "
            "Performance Survey (good designs lie between about 1 and 10 fJ per step)",
            option="--adc-fom-fj",
        ),
    )
    adc_static_w: float = _constant(
        100e-9,
        Parameter(
            "nW per ADC",
            1e-9,
            "static power of one ADC that its figure of merit leaves out (reference buffer, "
            "sampling driver of the multiplexer)",
            "an order-of-magnitude assumption for a kS/s low-power SAR ADC, whose published "
            "figure of merit usually counts the core alone",
            option="--adc-static-nw",
        ),
    )
    taxels_per_adc: int = _constant(
        16,
        Parameter(
            "taxels",
            1.0,
            "taxels multiplexed onto one ADC of the frame readout",
            "assumed: one ADC per column of 16 taxels, as in column-parallel sensor readouts",
            count=True,
            option="--taxels-per-adc",
        ),
    )

    def __post_init__(self) -> None:
        problems = [
            f"EnergyModel.{f.name} must be "
            + ("a whole number >= 1" if p.count else "a finite number >= 0")
            + f", got {getattr(self, f.name)!r}"
            for f in fields(self)
            if (p := f.metadata["parameter"]).problem(getattr(self, f.name)) is not None
        ]
        if problems:
            raise ValueError("; ".join(problems))

    @classmethod
    def from_options(cls, values: Mapping[str, Any]) -> EnergyModel:
        """The model of values given in their options' units, by field name (None: default).

        Raises
        ------
        ValueError
            A value is not valid; the message names every such option (``--front-end-nw -1:
            need a finite number >= 0``).
        """
        unknown = sorted(set(values) - set(PARAMETERS))
        if unknown:
            raise ValueError(f"unknown energy constant(s): {', '.join(unknown)}")
        given = {name: v for name, v in values.items() if v is not None}
        problems = [p for n, v in given.items() if (p := PARAMETERS[n].problem(v)) is not None]
        if problems:
            raise ValueError("; ".join(problems))
        return cls(
            **{
                name: int(v) if PARAMETERS[name].count else v * PARAMETERS[name].scale
                for name, v in given.items()
            }
        )

    def assumptions(self) -> tuple[str, ...]:
        """One sentence per constant, with its value and where the value comes from.

        Returns
        -------
        tuple of str
            In field order. A value other than the default is said to be set by the user, and
            the sentence still names the default and its source.
        """
        sentences = []
        for f in fields(self):
            p: Parameter = f.metadata["parameter"]
            value = getattr(self, f.name)
            origin = (
                p.source
                if value == f.default
                else f"set by the user (the default, {_in_unit(f.default, p)}, is {p.source})"
            )
            sentences.append(f"{f.name} = {_in_unit(value, p)}: {p.what}; {origin}.")
        return tuple(sentences)


PARAMETERS: dict[str, Parameter] = {f.name: f.metadata["parameter"] for f in fields(EnergyModel)}
"""Every constant's :class:`Parameter` by field name, in field order."""


def _in_unit(value: float, parameter: Parameter) -> str:
    """A constant in its option's unit, e.g. ``10 pJ per event``."""
    return f"{value / parameter.scale:.4g} {parameter.unit}"
