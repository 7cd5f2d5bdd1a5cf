r"""Hardware cost of a readout: data rate, static and dynamic power, energy per decision.

Two readouts of the same array of ``n`` taxels are compared. Both have a *front end* per taxel
(the sensor's charge or capacitance amplifier), biased all the time; they differ in how its
signal leaves the taxel.

*Event readout* (this project's design): each taxel's level-crossing encoder (two continuous-time
comparators, up and down) emits a signed spike when its signal moves by one threshold; the array
sends every spike as an address event. Its rates are the ones :mod:`pipeline.chain.metrics`
measures: ``event_rate_hz`` (spikes per second of the whole array) and ``data_rate_bps =
event_rate_hz * (ceil(log2 n) + 1)`` (taxel address plus polarity bit per event; time is implicit
in the asynchronous bus). Power:

.. math::

    \begin{aligned}
    P_\mathrm{event} &= n \, (P_\mathrm{fe} + P_\mathrm{cmp})
        && \text{static [W]} \\
    &\quad + \mathrm{event\_rate\_hz} \cdot E_\mathrm{event}
        + \mathrm{data\_rate\_bps} \cdot E_\mathrm{link}
        && \text{dynamic [W]}
    \end{aligned}

*Frame readout* (the conventional alternative): every taxel is sampled by an ADC of ``bits``
resolution at ``sampling_rate_hz`` and every sample is sent. One ADC serves ``m`` taxels through
a multiplexer (``ceil(n / m)`` ADCs, each converting at ``m * sampling_rate_hz``):

.. math::

    \begin{aligned}
    R_\mathrm{frame} &= n \cdot \mathrm{sampling\_rate\_hz} \cdot \mathrm{bits}
        && \text{[bit/s]} \\
    P_\mathrm{frame} &= n \, P_\mathrm{fe} + \lceil n / m \rceil \, P_\mathrm{adc}
        && \text{static [W]} \\
    &\quad + n \cdot \mathrm{sampling\_rate\_hz}
        \cdot (\mathrm{FOM} \cdot 2^\mathrm{bits} + \mathrm{bits} \cdot E_\mathrm{link})
        && \text{dynamic [W]}
    \end{aligned}

with the Walden figure of merit ``FOM = P / (2**ENOB * f_s)``, so that one conversion costs
``FOM * 2**bits`` whatever the rate (``bits`` stands for the effective number of bits).
``P_adc`` is the ADC's static power that published figures of merit leave out (reference buffer,
bias of the multiplexer's sampling driver).

Energy per decision: a classifier that observes ``observation_s`` seconds of touch per decision
(the windows a point really used times the window length) spends ``E = P * observation_s`` joules
of readout energy on it, see :func:`energy_per_decision_j`.

Constants (:class:`EnergyModel`; units in their names, SI), their defaults and sources:

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

Area of the comparators' matched devices (Pelgrom's law). A design that names a threshold
mismatch ``sigma_rel`` (``readout.effects.threshold_mismatch``: each taxel's threshold is
``threshold_v * (1 + sigma_rel * z)``) asks for comparators whose input offset has the standard
deviation ``sigma_V = sigma_rel * threshold_v``. The offset of a differential pair is the
threshold-voltage difference of its two input transistors, which Pelgrom's law (M. J. M. Pelgrom,
A. C. J. Duinmaijer and A. P. G. Welbers, "Matching properties of MOS transistors", IEEE JSSC
24(5), 1989) gives as ``sigma(dV_T) = A_VT / sqrt(W L)``, so each input transistor needs the gate
area

.. math::

    W L = \left(\frac{A_\mathrm{VT}}{\sigma_V}\right)^2
        = \left(\frac{A_\mathrm{VT}}{\mathrm{sigma\_rel} \cdot \mathrm{threshold\_v}}\right)^2
        \quad \text{[m}^2\text{]},

and a taxel, with two comparators (up and down) of two input transistors each
(:data:`MATCHED_DEVICES_PER_TAXEL`), ``A_taxel = 4 W L``; the array ``A_array = n A_taxel``
(:func:`taxel_area_m2`, :func:`array_area_m2`). :data:`A_VT_V_M` is declared once with its process
(:data:`A_VT_PROCESS`) and source (:data:`A_VT_SOURCE`). This is the matched gate area the
mismatch demands, not a layout: wiring, the front end and the comparators' other devices are
not counted, so it is a lower bound, and a meaningful one only where it exceeds the process's
minimum device (0.22 um x 0.18 um = 0.04 um^2 in 180 nm CMOS), which is not applied. A design
that names no mismatch, or ``sigma_rel = 0``, assumes perfect matching, which no finite device
gives: its area is not stated (NaN), rather than infinite or a guessed minimum.

Not modelled: clock generation and distribution, protocol overhead on the link (framing,
handshakes, idle), the multiplexer's switching energy (small against a conversion), leakage of
digital logic, and the classifier. The estimate is good to an order of magnitude at best.

*Decoder energy per decision* (the classifier, priced apart from the readout), in the style of
NeuroBench: a decision read at ``t`` seconds of touch has cost its decoder, on average,
``AC(t)`` accumulates (effective synaptic operations whose input is a spike: nonzero inputs times
fan-out), ``MAC(t)`` multiply-accumulates (the same where the input is a real number, as the
rate-coded networks' counts and activations are) and ``NU(t)`` neuron updates, cumulative from
the touch's start (the cubes' ``decoder_acs``, ``decoder_macs``, ``decoder_neuron_updates``).
Its energy is a band, each operation priced at the low and at the high end of its declared
range (:class:`DecoderEnergyModel`, :func:`decoder_energy_j`):

.. math::

    E_\mathrm{low|high}(t) = \mathrm{AC}(t) \, e^\mathrm{AC}_\mathrm{low|high}
        + \mathrm{MAC}(t) \, e^\mathrm{MAC}_\mathrm{low|high}
        + \mathrm{NU}(t) \, e^\mathrm{NU}_\mathrm{low|high}

===================  ===============  =====================================================
operation            low - high       sources
===================  ===============  =====================================================
accumulate (AC)      12.7 - 23.6 pJ   ODIN (measured, 28 nm) - Loihi (pre-silicon, 14 nm)
multiply-acc. (MAC)  4.6 - 9.6 pJ     32-bit float arithmetic, alone - with a weight load
neuron update (NU)   52 - 81 pJ       Loihi, inactive - active neuron
===================  ===============  =====================================================

The per-synaptic-operation figures of the spiking chips include reading the synapse's weight;
the MAC's low end is the arithmetic alone (M. Horowitz, ISSCC 2014, 45 nm, 0.9 V: 3.7 pJ
multiply plus 0.9 pJ add, 32-bit float, the precision the rate-coded networks run in here), its
high end adds one 32-bit weight load, half a 64-bit read of an 8 kB SRAM (10 pJ) in the same
table. Neuron updates are priced at Loihi's for every model (a ReLU's update on a conventional
processor costs less: for the rate-coded networks the high end overstates). Not modelled: the
output's softmax, moving activations between layers, static power of the decoder's chip.

Units: rates in Hz (events or samples per second), data rates in bit/s, energies in J, power in
W, times in s. The command line takes each constant in the unit of its :class:`Parameter`
(``--front-end-nw``, ``--event-energy-pj``, ...), declared once on the field.

The power functions broadcast: scalars, numpy arrays and ``xarray.DataArray`` inputs work alike,
and a DataArray keeps its dimensions and coordinates, since after validation only numpy
arithmetic is applied to the inputs. Scalars give a Python float.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

__all__ = [
    "A_VT_PROCESS",
    "A_VT_SOURCE",
    "A_VT_V_M",
    "CHIP",
    "CHIP_EVENT_RATE_HZ",
    "CHIP_TAXELS",
    "DECODER_OPERATIONS",
    "HOROWITZ",
    "LOIHI",
    "MATCHED_DEVICES_PER_TAXEL",
    "MAX_BITS",
    "ODIN",
    "PARAMETERS",
    "DecoderEnergyModel",
    "EnergyBand",
    "EnergyModel",
    "OperationEnergy",
    "Parameter",
    "PowerBudget",
    "ReadoutPower",
    "array_area_m2",
    "decoder_energy_j",
    "energy_per_decision_j",
    "event_data_rate_bps",
    "event_dynamic_power_w",
    "event_power_w",
    "event_static_power_w",
    "frame_data_rate_bps",
    "frame_dynamic_power_w",
    "frame_power_w",
    "frame_static_power_w",
    "matched_device_area_m2",
    "offset_sigma_v",
    "power_budget",
    "taxel_area_m2",
]

MAX_BITS = 64
"""Largest ADC resolution accepted (bits). Beyond it ``2**bits`` is a unit mistake, not a design."""

CHIP = (
    "M. D. Alea et al., IEEE TBioCAS, Dec. 2024 (doi 10.1109/TBCAS.2024.3387545): 192 taxels, "
    "2.2 kevent/s, 12.33 nW per taxel"
)
"""The chip the event readout's defaults are calibrated on (see the module docstring)."""
CHIP_TAXELS, CHIP_EVENT_RATE_HZ = 192, 2200.0
"""Its array and its events per second in all, which the calibration feeds the model."""

A_VT_V_M = 5e-9
"""Pelgrom's threshold-matching coefficient A_VT, in V m (5 mV um), of :data:`A_VT_PROCESS`."""
A_VT_PROCESS = "180 nm bulk CMOS (gate oxide about 4 nm)"
"""The process :data:`A_VT_V_M` stands for."""
A_VT_SOURCE = (
    "assumed from the trend of A_VT with gate-oxide thickness, about 1 mV um per nm of oxide, "
    "reviewed in P. R. Kinget, 'Device mismatch and tradeoffs in the design of analog "
    "circuits', IEEE JSSC 40(6), 2005, Sec. II; an order-of-magnitude figure: a foundry's "
    "matching data for the process at hand replaces it"
)
"""Where :data:`A_VT_V_M` comes from."""
MATCHED_DEVICES_PER_TAXEL = 4
"""Matched input transistors per taxel (two comparators, up and down, a differential pair each)."""


@dataclass(frozen=True)
class Parameter:
    """How one :class:`EnergyModel` constant is stated: declared once, on its field.

    ``option`` is the command-line option, which takes the value in ``unit`` (``scale`` SI units
    each, e.g. pJ = 1e-12 J); ``what`` says what it is, ``source`` where its default comes from;
    ``calibrated`` marks the constant fitted to :data:`CHIP` (the others are literature values
    or assumptions); ``count`` marks an integer count >= 1 (no unit).
    """

    option: str
    unit: str
    scale: float
    what: str
    source: str
    calibrated: bool = False
    count: bool = False

    def problem(self, value: Any) -> str | None:
        """Why ``value`` (in :attr:`unit`) is not valid, or None."""
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            return f"{self.option} {value!r}: need a number"
        if self.count:
            if not (math.isfinite(value) and value >= 1 and value == int(value)):
                return f"{self.option} {value:g}: need a whole number >= 1"
        elif not math.isfinite(value) or value < 0:
            return f"{self.option} {value:g}: need a finite number >= 0"
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
            "--front-end-nw",
            "nW per taxel",
            1e-9,
            "static bias of one taxel's front end (both readouts)",
            f"calibrated on the chip of {CHIP}, as the remainder once the other constants "
            "are taken",
            calibrated=True,
        ),
    )
    comparator_w_per_taxel: float = _constant(
        2e-9,
        Parameter(
            "--comparator-nw",
            "nW per taxel",
            1e-9,
            "static bias of one taxel's two level-crossing comparators (event readout)",
            "assumed: continuous-time comparators biased in weak inversion, of the order of 1 "
            "nA each at about 1 V, as in low-power level-crossing ADCs",
        ),
    )
    event_energy_j: float = _constant(
        10e-12,
        Parameter(
            "--event-energy-pj",
            "pJ per event",
            1e-12,
            "energy of the comparators' switching and the address-event encoder, per event",
            "assumed from event-driven readouts and address-event interfaces in the "
            "neuromorphic-sensor literature (tens of pJ per event is typical)",
        ),
    )
    link_energy_j_per_bit: float = _constant(
        1e-12,
        Parameter(
            "--link-energy-pj-per-bit",
            "pJ per bit",
            1e-12,
            "energy per bit sent on the link (both readouts)",
            "assumed from low-power wired serial links (of the order of 1 pJ per bit)",
        ),
    )
    adc_fom_j_per_step: float = _constant(
        10e-15,
        Parameter(
            "--adc-fom-fj",
            "fJ per conversion step",
            1e-15,
            "Walden figure of merit of the frame readout's ADC, one conversion costing "
            "FOM * 2**bits",
            "assumed from low-power SAR ADCs at kHz sampling rates in B. Murmann's ADC "
            "Performance Survey (good designs lie between about 1 and 10 fJ per step)",
        ),
    )
    adc_static_w: float = _constant(
        100e-9,
        Parameter(
            "--adc-static-nw",
            "nW per ADC",
            1e-9,
            "static power of one ADC that its figure of merit leaves out (reference buffer, "
            "sampling driver of the multiplexer)",
            "an order-of-magnitude assumption for a kS/s low-power SAR ADC, whose published "
            "figure of merit usually counts the core alone",
        ),
    )
    taxels_per_adc: int = _constant(
        16,
        Parameter(
            "--taxels-per-adc",
            "taxels",
            1.0,
            "taxels multiplexed onto one ADC of the frame readout",
            "assumed: one ADC per column of 16 taxels, as in column-parallel sensor readouts",
            count=True,
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


@dataclass(frozen=True)
class ReadoutPower:
    """Power of one readout of one array: ``static_w`` (bias, paid whatever the signal does) and
    ``dynamic_w`` (per event, conversion and bit sent), in W."""

    static_w: float
    dynamic_w: float

    @property
    def total_w(self) -> float:
        """Static plus dynamic power (W)."""
        return self.static_w + self.dynamic_w

    @property
    def static_share(self) -> float:
        """Fraction of the power that is static (NaN when there is no power)."""
        return self.static_w / self.total_w if self.total_w > 0 else math.nan


@dataclass(frozen=True)
class PowerBudget:
    """Both readouts of one array (:func:`power_budget`); ``frame`` None: its rate not given."""

    n_taxels: int
    event_rate_hz: float
    bits: float
    sampling_rate_hz: float | None
    event: ReadoutPower
    event_data_rate_bps: float
    frame: ReadoutPower | None
    frame_data_rate_bps: float | None
    model: EnergyModel

    def to_json(self) -> dict[str, Any]:
        """Plain JSON values by name, units in the names; ``None`` (JSON ``null``) for what is
        unknown (the frame readout without a sampling rate, a ratio to no power)."""
        frame, event_w = self.frame, self.event.total_w
        return {
            "n_taxels": self.n_taxels,
            "event_rate_hz": self.event_rate_hz,
            "bits": self.bits,
            "sampling_rate_hz": self.sampling_rate_hz,
            "event_readout_w": event_w,
            "event_readout_static_w": self.event.static_w,
            "event_readout_dynamic_w": self.event.dynamic_w,
            "event_readout_per_taxel_w": event_w / self.n_taxels,
            "event_data_rate_bps": self.event_data_rate_bps,
            "frame_readout_w": frame.total_w if frame else None,
            "frame_readout_static_w": frame.static_w if frame else None,
            "frame_readout_dynamic_w": frame.dynamic_w if frame else None,
            "frame_readout_per_taxel_w": frame.total_w / self.n_taxels if frame else None,
            "frame_data_rate_bps": self.frame_data_rate_bps,
            "frame_over_event_power": frame.total_w / event_w if frame and event_w > 0 else None,
            "energy_model": {name: getattr(self.model, name) for name in PARAMETERS},
        }


def power_budget(
    n_taxels: int,
    event_rate_hz: float,
    bits: float,
    sampling_rate_hz: float | None = None,
    model: EnergyModel | None = None,
) -> PowerBudget:
    """Power (static and dynamic) and data rate of both readouts of an array of ``n_taxels``.

    Parameters
    ----------
    n_taxels : int
        Taxels in the array, >= 1.
    event_rate_hz : float
        Events per second of the whole array, >= 0.
    bits : float
        The frame readout's ADC resolution, 0 to :data:`MAX_BITS`.
    sampling_rate_hz : float, optional
        The frame readout's samples per second per taxel, > 0; None leaves the frame readout
        unknown.
    model : EnergyModel, optional
        The constants (default ``EnergyModel()``).

    Raises
    ------
    ValueError
        Every bad argument, named in one message.
    """
    model = _model(model)
    problems = []
    if isinstance(n_taxels, bool) or not isinstance(n_taxels, int | np.integer) or n_taxels < 1:
        problems.append(f"n_taxels must be a whole number >= 1, got {n_taxels!r}")
    if sampling_rate_hz is not None and not (
        math.isfinite(sampling_rate_hz) and sampling_rate_hz > 0
    ):
        problems.append(f"sampling_rate_hz must be finite and > 0, got {sampling_rate_hz!r}")
    for name, value, check in (
        ("event_rate_hz", event_rate_hz, _non_negative),
        ("bits", bits, lambda _, v: _bits(v)),
    ):
        try:
            check(name, value)
        except ValueError as exc:
            problems.append(str(exc))
    if problems:
        raise ValueError("; ".join(problems))
    data_rate = event_data_rate_bps(n_taxels, event_rate_hz)
    event = ReadoutPower(
        event_static_power_w(n_taxels, model),
        event_dynamic_power_w(event_rate_hz, data_rate, model),
    )
    frame = frame_rate = None
    if sampling_rate_hz is not None:
        frame = ReadoutPower(
            frame_static_power_w(n_taxels, model),
            frame_dynamic_power_w(n_taxels, sampling_rate_hz, bits, model),
        )
        frame_rate = frame_data_rate_bps(n_taxels, sampling_rate_hz, bits)
    return PowerBudget(
        int(n_taxels),
        float(event_rate_hz),
        float(bits),
        None if sampling_rate_hz is None else float(sampling_rate_hz),
        event,
        data_rate,
        frame,
        frame_rate,
        model,
    )


def event_data_rate_bps(n_taxels: int, event_rate_hz: Any) -> Any:
    """Address-event bits per second: ``event_rate_hz * (ceil(log2 n_taxels) + 1)``.

    ``n_taxels`` is one whole number >= 1; ``event_rate_hz`` broadcasts (float64 bit/s).
    """
    # Imported here: the command line reads this module for its options, and the metrics module
    # compiles kernels on import.
    from pipeline.chain.metrics import bits_per_event

    event_rate_hz = _non_negative("event_rate_hz", event_rate_hz)
    return _plain(1.0 * event_rate_hz * bits_per_event(int(n_taxels)))


def frame_data_rate_bps(n_taxels: Any, sampling_rate_hz: Any, bits: Any) -> Any:
    """Bits per second of a frame readout: ``n_taxels * sampling_rate_hz * bits``.

    Parameters
    ----------
    n_taxels : float or array-like
        Taxels in the array, >= 0 (a count, but any non-negative number is accepted so that a
        rate per taxel can be had with 1).
    sampling_rate_hz : float or array-like
        Samples per second of each taxel, in Hz, >= 0.
    bits : float or array-like
        ADC resolution in bits, 0 to :data:`MAX_BITS`.

    Returns
    -------
    float, numpy.ndarray or xarray.DataArray
        float64 bit/s, the inputs broadcast together (a DataArray keeps its coordinates).

    Raises
    ------
    ValueError
        If an input is not numeric, is NaN, infinite or negative, or ``bits > MAX_BITS``; the
        message names the argument.
    """
    n_taxels = _non_negative("n_taxels", n_taxels)
    sampling_rate_hz = _non_negative("sampling_rate_hz", sampling_rate_hz)
    bits = _bits(bits)
    # 1.0 first: integer inputs are multiplied as floats, never in a wrapping int64.
    return _plain(1.0 * n_taxels * sampling_rate_hz * bits)


def event_static_power_w(n_taxels: Any, model: EnergyModel | None = None) -> Any:
    """Static power of the event readout: ``n_taxels * (P_fe + P_cmp)``, in W (broadcasts)."""
    model = _model(model)
    n_taxels = _non_negative("n_taxels", n_taxels)
    return _plain(1.0 * n_taxels * (model.front_end_w_per_taxel + model.comparator_w_per_taxel))


def event_dynamic_power_w(
    event_rate_hz: Any, data_rate_bps: Any, model: EnergyModel | None = None
) -> Any:
    """Dynamic power of the event readout: ``event_rate_hz * E_event + data_rate_bps * E_link``.

    Parameters
    ----------
    event_rate_hz : float or array-like
        Events per second of the whole array, in Hz, >= 0 (``SpikeMetrics.event_rate_hz``).
    data_rate_bps : float or array-like
        Address-event bits per second, >= 0 (``SpikeMetrics.data_rate_bps``, i.e.
        ``event_rate_hz * (ceil(log2 n_taxels) + 1)``).
    model : EnergyModel, optional
        The constants; ``EnergyModel()`` (the defaults) if not given.

    Returns
    -------
    float, numpy.ndarray or xarray.DataArray
        float64 W, the inputs broadcast together (a DataArray keeps its coordinates).

    Raises
    ------
    ValueError
        If an input is not numeric, is NaN, infinite or negative; the message names it.
    """
    model = _model(model)
    event_rate_hz = _non_negative("event_rate_hz", event_rate_hz)
    data_rate_bps = _non_negative("data_rate_bps", data_rate_bps)
    return _plain(
        event_rate_hz * model.event_energy_j + data_rate_bps * model.link_energy_j_per_bit
    )


def event_power_w(
    n_taxels: Any, event_rate_hz: Any, data_rate_bps: Any, model: EnergyModel | None = None
) -> Any:
    """Power of the event readout, static plus dynamic, in W (see the module docstring).

    ``n_taxels`` as in :func:`frame_data_rate_bps`, the rates as in
    :func:`event_dynamic_power_w`; the inputs broadcast together.
    """
    return _plain(
        event_static_power_w(n_taxels, model)
        + event_dynamic_power_w(event_rate_hz, data_rate_bps, model)
    )


def frame_static_power_w(n_taxels: Any, model: EnergyModel | None = None) -> Any:
    """Static power of the frame readout: ``n_taxels * P_fe + ceil(n_taxels / m) * P_adc``, in W.

    ``m`` is :attr:`EnergyModel.taxels_per_adc`; broadcasts like :func:`frame_data_rate_bps`.
    """
    model = _model(model)
    n_taxels = _non_negative("n_taxels", n_taxels)
    adcs = np.ceil(np.divide(n_taxels, model.taxels_per_adc))
    return _plain(n_taxels * model.front_end_w_per_taxel + adcs * model.adc_static_w)


def frame_dynamic_power_w(
    n_taxels: Any, sampling_rate_hz: Any, bits: Any, model: EnergyModel | None = None
) -> Any:
    """Dynamic power of the frame readout: ADC conversions plus link, in W.

    ``n_taxels * sampling_rate_hz * (FOM * 2**bits + bits * E_link)``.

    Parameters
    ----------
    n_taxels, sampling_rate_hz, bits
        As in :func:`frame_data_rate_bps`.
    model : EnergyModel, optional
        The constants; ``EnergyModel()`` (the defaults) if not given.

    Returns
    -------
    float, numpy.ndarray or xarray.DataArray
        float64 W, the inputs broadcast together (a DataArray keeps its coordinates).

    Raises
    ------
    ValueError
        As :func:`frame_data_rate_bps`.
    """
    model = _model(model)
    n_taxels = _non_negative("n_taxels", n_taxels)
    sampling_rate_hz = _non_negative("sampling_rate_hz", sampling_rate_hz)
    bits = _bits(bits)
    samples_per_s = 1.0 * n_taxels * sampling_rate_hz
    per_sample_j = model.adc_fom_j_per_step * np.exp2(bits) + bits * model.link_energy_j_per_bit
    return _plain(samples_per_s * per_sample_j)


def frame_power_w(
    n_taxels: Any, sampling_rate_hz: Any, bits: Any, model: EnergyModel | None = None
) -> Any:
    """Power of the frame readout, static plus dynamic, in W (see the module docstring); the
    arguments as in :func:`frame_dynamic_power_w`."""
    return _plain(
        frame_static_power_w(n_taxels, model)
        + frame_dynamic_power_w(n_taxels, sampling_rate_hz, bits, model)
    )


def energy_per_decision_j(power_w: Any, observation_s: Any) -> Any:
    """Readout energy spent on one classification: ``power_w * observation_s``.

    Parameters
    ----------
    power_w : float or array-like
        Readout power in W, >= 0 (from :func:`event_power_w` or :func:`frame_power_w`).
    observation_s : float or array-like
        Seconds of touch observed per decision, >= 0 (``n_windows * window_s``).

    Returns
    -------
    float, numpy.ndarray or xarray.DataArray
        float64 J, the inputs broadcast together (a DataArray keeps its coordinates).

    Raises
    ------
    ValueError
        If an input is not numeric, is NaN, infinite or negative; the message names it.
    """
    power_w = _non_negative("power_w", power_w)
    observation_s = _non_negative("observation_s", observation_s)
    return _plain(1.0 * power_w * observation_s)


def offset_sigma_v(sigma_rel: Any, threshold_v: Any) -> Any:
    """Standard deviation of a taxel's threshold, ``sigma_rel * threshold_v``, in V.

    ``sigma_rel`` (relative threshold mismatch, ``readout.effects.threshold_mismatch.sigma_rel``)
    and ``threshold_v`` (V) are finite and >= 0 and broadcast (float64 V).
    """
    sigma_rel = _non_negative("sigma_rel", sigma_rel)
    threshold_v = _non_negative("threshold_v", threshold_v)
    return _plain(1.0 * sigma_rel * threshold_v)


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
    sigma_v = _non_negative("sigma_v", sigma_v)
    if not (math.isfinite(a_vt_v_m) and a_vt_v_m > 0):
        raise ValueError(f"a_vt_v_m must be finite and > 0, got {a_vt_v_m!r}")
    sigma = np.asarray(sigma_v, dtype=np.float64)
    with np.errstate(divide="ignore"):
        area = np.where(sigma > 0, (a_vt_v_m / np.where(sigma > 0, sigma, 1.0)) ** 2, np.nan)
    return _keep(sigma_v, area)


def taxel_area_m2(sigma_rel: Any, threshold_v: Any, a_vt_v_m: float = A_VT_V_M) -> Any:
    """Matched gate area of one taxel, ``MATCHED_DEVICES_PER_TAXEL * W L``, in m^2.

    ``W L`` is :func:`matched_device_area_m2` of :func:`offset_sigma_v`; the inputs broadcast;
    NaN where ``sigma_rel * threshold_v`` is 0 (no mismatch named: nothing to size for).
    """
    device = matched_device_area_m2(offset_sigma_v(sigma_rel, threshold_v), a_vt_v_m)
    return _plain(MATCHED_DEVICES_PER_TAXEL * device)


def array_area_m2(
    n_taxels: Any, sigma_rel: Any, threshold_v: Any, a_vt_v_m: float = A_VT_V_M
) -> Any:
    """Matched gate area of an array of ``n_taxels`` taxels, ``n_taxels * taxel_area_m2``, in
    m^2; the inputs broadcast, NaN as in :func:`taxel_area_m2`."""
    n_taxels = _non_negative("n_taxels", n_taxels)
    return _plain(1.0 * n_taxels * taxel_area_m2(sigma_rel, threshold_v, a_vt_v_m))


def _keep(like: Any, values: np.ndarray) -> Any:
    """``values`` shaped as ``like``: a DataArray keeps its coordinates, a 0-d one is a float."""
    if hasattr(like, "copy") and hasattr(like, "dims"):
        return like.copy(data=values)
    return _plain(values)


ODIN = "ODIN, C. Frenkel et al., IEEE TBioCAS 13(1), 2019, 28 nm, measured"
"""The low end of a synaptic operation's energy, 12.7 pJ (:class:`DecoderEnergyModel`)."""
LOIHI = "Loihi, M. Davies et al., IEEE Micro 38(1), 2018, 14 nm, pre-silicon figures"
"""The high end of a synaptic operation's energy, 23.6 pJ, and a neuron update's, 52 pJ for an
inactive and 81 pJ for an active neuron."""
HOROWITZ = "M. Horowitz, ISSCC 2014, 45 nm, 0.9 V"
"""The source of a multiply-accumulate's energy, with 3.7 pJ per 32-bit float multiply, 0.9 pJ
per add and 10 pJ per 64-bit read of an 8 kB SRAM."""


@dataclass(frozen=True)
class OperationEnergy:
    """The energy of one decoder operation as a band, ``low_j <= high_j`` (J), with what the
    operation is and where each end comes from.

    Raises
    ------
    ValueError
        An end is not a finite number >= 0, or ``low_j > high_j``.
    """

    low_j: float
    high_j: float
    what: str
    low_source: str
    high_source: str

    def __post_init__(self) -> None:
        ends = (self.low_j, self.high_j)
        if not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and v >= 0
            for v in ends
        ):
            raise ValueError(f"{self.what}: energies must be finite numbers >= 0, got {ends}")
        if self.low_j > self.high_j:
            raise ValueError(f"{self.what}: low {self.low_j!r} J above high {self.high_j!r} J")

    def sentence(self) -> str:
        """The band, what it prices and its sources, in one sentence."""
        return (
            f"{self.what}: {self.low_j * 1e12:.3g} pJ ({self.low_source}) to "
            f"{self.high_j * 1e12:.3g} pJ ({self.high_source})."
        )


@dataclass(frozen=True)
class DecoderEnergyModel:
    """Per-operation energies of a decoder (the classifier), each a band; defaults and sources
    in the module docstring.

    Attributes
    ----------
    ac : OperationEnergy
        An accumulate: a synaptic operation whose input is a spike. 12.7 pJ (:data:`ODIN`) to
        23.6 pJ (:data:`LOIHI`).
    mac : OperationEnergy
        A multiply-accumulate: a synaptic operation whose input is a real number, 32-bit float.
        4.6 pJ (arithmetic alone) to 9.6 pJ (with a 32-bit weight load), :data:`HOROWITZ`.
    neuron_update : OperationEnergy
        One neuron's state update. 52 pJ (inactive) to 81 pJ (active), :data:`LOIHI`.
    """

    ac: OperationEnergy = OperationEnergy(
        12.7e-12,
        23.6e-12,
        "accumulate (synaptic operation on a spike)",
        ODIN,
        LOIHI,
    )
    mac: OperationEnergy = OperationEnergy(
        4.6e-12,
        9.6e-12,
        "multiply-accumulate (synaptic operation on a real input, 32-bit float)",
        f"the arithmetic alone, a 3.7 pJ multiply and a 0.9 pJ add, {HOROWITZ}",
        f"with a 32-bit weight load, half a 10 pJ 64-bit read of an 8 kB SRAM, {HOROWITZ}",
    )
    neuron_update: OperationEnergy = OperationEnergy(
        52e-12,
        81e-12,
        "neuron update (priced alike for every model)",
        f"an inactive neuron, {LOIHI}",
        f"an active neuron, {LOIHI}",
    )

    def assumptions(self) -> tuple[str, ...]:
        """One sentence per operation (:data:`DECODER_OPERATIONS` order), with its band and
        sources."""
        return tuple(getattr(self, name).sentence() for name in DECODER_OPERATIONS)


#: The decoder's operations, as :class:`DecoderEnergyModel` names them, in the order
#: :func:`decoder_energy_j` takes their counts.
DECODER_OPERATIONS = ("ac", "mac", "neuron_update")


@dataclass(frozen=True)
class EnergyBand:
    """Energy of one decision at both ends of the per-operation bands, in J (floats, or arrays
    of one shape)."""

    low_j: Any
    high_j: Any


def decoder_energy_j(
    acs: Any, macs: Any, neuron_updates: Any, model: DecoderEnergyModel | None = None
) -> EnergyBand:
    """The decoder's energy per decision, low and high: operations times their energies.

    ``E = acs * e_ac + macs * e_mac + neuron_updates * e_nu`` at the low and at the high end of
    every band (see the module docstring).

    Parameters
    ----------
    acs, macs, neuron_updates : float or array-like
        Mean accumulates, multiply-accumulates and neuron updates per decision, >= 0; NaN where
        a count is unknown (a time the model decides nothing at) gives a NaN energy there. The
        three broadcast together.
    model : DecoderEnergyModel, optional
        The per-operation energies (default ``DecoderEnergyModel()``).

    Returns
    -------
    EnergyBand
        float64 J at each end, the inputs broadcast (Python floats for scalar inputs).

    Raises
    ------
    ValueError
        A count is not numeric, negative or infinite; the message names it.
    """
    model = DecoderEnergyModel() if model is None else model
    if not isinstance(model, DecoderEnergyModel):
        raise TypeError(f"model must be a DecoderEnergyModel, got {type(model).__name__}")
    counts = []
    for name, value in zip(DECODER_OPERATIONS, (acs, macs, neuron_updates), strict=True):
        values = np.asarray(value)
        if values.dtype.kind not in "iuf":
            raise ValueError(f"{name} counts must be numbers, got dtype {values.dtype}")
        values = values.astype(np.float64)
        bad = np.isinf(values) | (values < 0)
        if bad.any():
            raise ValueError(f"{name} counts must be finite and >= 0 (or NaN: unknown)")
        counts.append(values)
    ends = []
    for end in ("low_j", "high_j"):
        energy = sum(
            count * getattr(getattr(model, name), end)
            for name, count in zip(DECODER_OPERATIONS, counts, strict=True)
        )
        ends.append(_plain(np.asarray(energy, dtype=np.float64)))
    return EnergyBand(*ends)


def _model(model: EnergyModel | None) -> EnergyModel:
    if model is None:
        return EnergyModel()
    if not isinstance(model, EnergyModel):
        raise TypeError(f"model must be an EnergyModel, got {type(model).__name__}")
    return model


def _non_negative(name: str, value: Any) -> Any:
    """``value`` checked to be numeric, finite and >= 0 everywhere; returned for arithmetic.

    Scalars, arrays and DataArrays are returned as they are, so that the caller's arithmetic keeps
    their coordinates; lists and tuples become float64 arrays.
    """
    values = np.asarray(value)
    if values.dtype.kind not in "iuf":
        raise ValueError(
            f"{name} must be a number or an array of numbers, got {type(value).__name__} "
            f"of dtype {values.dtype}"
        )
    bad = ~(np.isfinite(values) & (values >= 0))
    if bad.any():
        first = values[np.unravel_index(np.argmax(bad), values.shape)] if values.ndim else values
        where = f" ({np.count_nonzero(bad)} of {values.size} values)" if values.ndim else ""
        raise ValueError(f"{name} must be finite and >= 0, got {first.item()!r}{where}")
    if isinstance(value, list | tuple):
        return values.astype(np.float64)
    return value


def _bits(bits: Any) -> Any:
    bits = _non_negative("bits", bits)
    largest = float(np.max(np.asarray(bits))) if np.size(bits) else 0.0
    if largest > MAX_BITS:
        raise ValueError(f"bits must be at most {MAX_BITS}, got {largest!r}")
    return bits


def _plain(result: Any) -> Any:
    """A 0-d numpy result as a Python float; arrays and DataArrays unchanged."""
    if isinstance(result, np.generic | np.ndarray) and np.ndim(result) == 0:
        return float(result)
    return result


def _in_unit(value: float, parameter: Parameter) -> str:
    """A constant in its option's unit, e.g. ``10 pJ per event``."""
    return f"{value / parameter.scale:.4g} {parameter.unit}"
