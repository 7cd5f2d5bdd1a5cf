r"""Power of a readout: data rate, static and dynamic power, energy per decision.

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

The constants (:class:`~pipeline.results.readout_constants.EnergyModel`), their defaults, sources
and the calibration on a chip are in :mod:`pipeline.results.readout_constants`; the comparators'
matched area in :mod:`pipeline.results.matched_area`; the decoder's (the classifier's) energy in
:mod:`pipeline.results.decoder_energy`.

Not modelled: clock generation and distribution, protocol overhead on the link (framing,
handshakes, idle), the multiplexer's switching energy (small against a conversion), leakage of
digital logic, and the classifier (priced apart). The estimate is good to an order of magnitude
at best.

Units: rates in Hz (events or samples per second), data rates in bit/s, energies in J, power in
W, times in s.

The power functions broadcast (:mod:`pipeline.results.broadcast`): scalars, numpy arrays and
``xarray.DataArray`` inputs work alike, and a DataArray keeps its dimensions and coordinates.
Scalars give a Python float.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.results.broadcast import non_negative, plain
from pipeline.results.readout_constants import PARAMETERS, EnergyModel

__all__ = [
    "MAX_BITS",
    "PowerBudget",
    "ReadoutPower",
    "energy_per_decision_j",
    "event_data_rate_bps",
    "event_dynamic_power_w",
    "event_power_w",
    "event_static_power_w",
    "frame_data_rate_bps",
    "frame_dynamic_power_w",
    "frame_power_w",
    "frame_static_power_w",
    "power_budget",
]

MAX_BITS = 64
"""Largest ADC resolution accepted (bits). Beyond it ``2**bits`` is a unit mistake, not a design."""


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
        ("event_rate_hz", event_rate_hz, non_negative),
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

    event_rate_hz = non_negative("event_rate_hz", event_rate_hz)
    return plain(1.0 * event_rate_hz * bits_per_event(int(n_taxels)))


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
    n_taxels = non_negative("n_taxels", n_taxels)
    sampling_rate_hz = non_negative("sampling_rate_hz", sampling_rate_hz)
    bits = _bits(bits)
    # 1.0 first: integer inputs are multiplied as floats, never in a wrapping int64.
    return plain(1.0 * n_taxels * sampling_rate_hz * bits)


def event_static_power_w(n_taxels: Any, model: EnergyModel | None = None) -> Any:
    """Static power of the event readout: ``n_taxels * (P_fe + P_cmp)``, in W (broadcasts)."""
    model = _model(model)
    n_taxels = non_negative("n_taxels", n_taxels)
    return plain(1.0 * n_taxels * (model.front_end_w_per_taxel + model.comparator_w_per_taxel))


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
    event_rate_hz = non_negative("event_rate_hz", event_rate_hz)
    data_rate_bps = non_negative("data_rate_bps", data_rate_bps)
    return plain(event_rate_hz * model.event_energy_j + data_rate_bps * model.link_energy_j_per_bit)


def event_power_w(
    n_taxels: Any, event_rate_hz: Any, data_rate_bps: Any, model: EnergyModel | None = None
) -> Any:
    """Power of the event readout, static plus dynamic, in W (see the module docstring).

    ``n_taxels`` as in :func:`frame_data_rate_bps`, the rates as in
    :func:`event_dynamic_power_w`; the inputs broadcast together.
    """
    return plain(
        event_static_power_w(n_taxels, model)
        + event_dynamic_power_w(event_rate_hz, data_rate_bps, model)
    )


def frame_static_power_w(n_taxels: Any, model: EnergyModel | None = None) -> Any:
    """Static power of the frame readout: ``n_taxels * P_fe + ceil(n_taxels / m) * P_adc``, in W.

    ``m`` is :attr:`~pipeline.results.readout_constants.EnergyModel.taxels_per_adc`; broadcasts
    like :func:`frame_data_rate_bps`.
    """
    model = _model(model)
    n_taxels = non_negative("n_taxels", n_taxels)
    adcs = np.ceil(np.divide(n_taxels, model.taxels_per_adc))
    return plain(n_taxels * model.front_end_w_per_taxel + adcs * model.adc_static_w)


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
    n_taxels = non_negative("n_taxels", n_taxels)
    sampling_rate_hz = non_negative("sampling_rate_hz", sampling_rate_hz)
    bits = _bits(bits)
    samples_per_s = 1.0 * n_taxels * sampling_rate_hz
    per_sample_j = model.adc_fom_j_per_step * np.exp2(bits) + bits * model.link_energy_j_per_bit
    return plain(samples_per_s * per_sample_j)


def frame_power_w(
    n_taxels: Any, sampling_rate_hz: Any, bits: Any, model: EnergyModel | None = None
) -> Any:
    """Power of the frame readout, static plus dynamic, in W (see the module docstring); the
    arguments as in :func:`frame_dynamic_power_w`."""
    return plain(
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
    power_w = non_negative("power_w", power_w)
    observation_s = non_negative("observation_s", observation_s)
    return plain(1.0 * power_w * observation_s)


def _model(model: EnergyModel | None) -> EnergyModel:
    if model is None:
        return EnergyModel()
    if not isinstance(model, EnergyModel):
        raise TypeError(f"model must be an EnergyModel, got {type(model).__name__}")
    return model


def _bits(bits: Any) -> Any:
    bits = non_negative("bits", bits)
    largest = float(np.max(np.asarray(bits))) if np.size(bits) else 0.0
    if largest > MAX_BITS:
        raise ValueError(f"bits must be at most {MAX_BITS}, got {largest!r}")
    return bits
