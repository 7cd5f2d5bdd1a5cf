r"""Hardware cost of a readout: data rate and an order-of-magnitude energy estimate.

Two readouts of the same array of ``n`` taxels are compared.

*Event readout* (this project's design): each taxel's level-crossing encoder emits a signed spike
when its signal moves by one threshold; the array sends every spike as an address event. Its
rates are the ones :mod:`pipeline.chain.metrics` measures: ``event_rate_hz`` (spikes per second of
the whole array, averaged over recordings) and ``data_rate_bps = event_rate_hz * (ceil(log2 n) +
1)``
(taxel address plus polarity bit per event; time is implicit in the asynchronous bus). Power::

    P_event = event_rate_hz * E_event + data_rate_bps * E_link

*Frame readout* (the conventional alternative): every taxel is sampled by an ADC of ``bits``
resolution at ``sampling_rate_hz`` and every sample is sent::

    R_frame = n * sampling_rate_hz * bits                                  [bit/s]
    P_frame = n * sampling_rate_hz * FOM * 2**bits + R_frame * E_link      [W]

with the Walden figure of merit ``FOM = P / (2**ENOB * f_s)``, so that one conversion costs
``FOM * 2**bits`` (here ``bits`` stands for the effective number of bits).

Energy per decision: a classifier that observes ``observation_s`` seconds of touch per decision
(``n_windows * window_s`` in the report) spends ``E = P * observation_s`` joules of readout energy
on it, see :func:`energy_per_decision_j`.

Units: rates in Hz (events or samples per second), data rates in bit/s, energies in J, power in
W, times in s. ``E_event`` (:attr:`EnergyModel.event_energy_j`), ``FOM``
(:attr:`EnergyModel.adc_fom_j_per_step`) and ``E_link``
(:attr:`EnergyModel.link_energy_j_per_bit`) are set by the user; their defaults are
order-of-magnitude ASSUMPTIONS from the literature, not measurements of a circuit
(:meth:`EnergyModel.assumptions` states them in words for a report).

Modelled: the dynamic energy that scales with activity. The frame readout pays one ADC conversion
per taxel per sample whatever the signal does; the event readout pays per event, so a still
surface costs nothing and a rough one costs more.

Not modelled: static and bias power (the comparators of a continuous-time level-crossing encoder
are biased all the time, as are an ADC's references; at low event rates this floor can dominate
the event readout), clock generation and distribution, the sensor front end (charge amplifiers,
shared by both readouts), any ADC multiplexing overhead, protocol overhead on the link (framing,
handshakes, idle), and the classifier. The estimate is therefore a comparison of the
activity-dependent parts of the two readouts, good to an order of magnitude at best.

The functions broadcast: scalars, numpy arrays and ``xarray.DataArray`` inputs work alike, and a
DataArray keeps its dimensions and coordinates, since after validation only numpy arithmetic is
applied to the inputs. Scalars give a Python float.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

__all__ = [
    "MAX_BITS",
    "EnergyModel",
    "energy_per_decision_j",
    "event_power_w",
    "frame_data_rate_bps",
    "frame_power_w",
]

MAX_BITS = 64
"""Largest ADC resolution accepted: beyond it ``2**bits`` is a unit mistake, not a design."""

# What each constant is, its unit, and where its default comes from; kept next to the class so
# that a changed default and its stated source are edited together.
_ABOUT = {
    "event_energy_j": (
        "energy of the level-crossing comparators and the address-event encoder, per event",
        "J per event",
        "event-driven (level-crossing) readouts and address-event interfaces in the "
        "neuromorphic-sensor literature",
        "tens of pJ per event is typical, and reported figures range from pJ to nJ with the "
        "process and with what is counted",
    ),
    "adc_fom_j_per_step": (
        "Walden figure of merit of the frame readout's ADC, one conversion costing FOM * 2**bits",
        "J per conversion step",
        "low-power SAR ADCs at kHz sampling rates in B. Murmann's ADC Performance Survey",
        "good designs lie between about 1 and 10 fJ per step and the best below, and a lower "
        "value makes the frame readout cheaper",
    ),
    "link_energy_j_per_bit": (
        "energy per bit sent on the link, charged to both readouts",
        "J per bit",
        "low-power wired serial links",
        "these spend of the order of 1 pJ per bit",
    ),
}


@dataclass(frozen=True)
class EnergyModel:
    """Constants of the energy estimate; defaults are order-of-magnitude ASSUMPTIONS.

    The defaults are round values from bodies of literature, named in :meth:`assumptions`; they
    are meant for comparing the two readouts to an order of magnitude, not for predicting the
    power of a circuit. Set them to a design's own figures where they are known.

    Parameters
    ----------
    event_energy_j : float
        Energy per spike event, in J: the level-crossing comparators and the address-event
        encoder, once per event. Default 10 pJ (event-driven readouts and AER interfaces report
        tens of pJ per event; the order of magnitude is taken).
    adc_fom_j_per_step : float
        Walden figure of merit of the frame readout's ADC, in J per conversion step; one
        conversion of ``bits`` bits costs ``adc_fom_j_per_step * 2**bits``. Default 10 fJ
        (good low-power SAR ADCs at low sampling rates in B. Murmann's ADC Performance Survey
        lie between about 1 and 10 fJ per step; the upper end is taken).
    link_energy_j_per_bit : float
        Energy per bit sent on the link, in J, charged to both readouts. Default 1 pJ (low-power
        wired serial links, order of pJ per bit).

    Raises
    ------
    ValueError
        If a constant is not a finite number >= 0; the message names the field and its value.
    """

    event_energy_j: float = 10e-12
    adc_fom_j_per_step: float = 10e-15
    link_energy_j_per_bit: float = 1e-12

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            number = isinstance(value, int | float | np.integer | np.floating)
            if isinstance(value, bool) or not number or not math.isfinite(value) or value < 0:
                raise ValueError(
                    f"EnergyModel.{f.name} must be a finite number >= 0, got {value!r}"
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
            what, unit, source, note = _ABOUT[f.name]
            value = getattr(self, f.name)
            if value == f.default:
                origin = f"an order-of-magnitude assumption from {source}; {note}"
            else:
                origin = (
                    f"set by the user; the default, {_si(f.default, unit)}, is an "
                    f"order-of-magnitude assumption from {source}"
                )
            sentences.append(f"{f.name} = {_si(value, unit)} ({what}): {origin}.")
        return tuple(sentences)


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


def event_power_w(event_rate_hz: Any, data_rate_bps: Any, model: EnergyModel | None = None) -> Any:
    """Power of the event readout: ``event_rate_hz * E_event + data_rate_bps * E_link``.

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


def frame_power_w(
    n_taxels: Any, sampling_rate_hz: Any, bits: Any, model: EnergyModel | None = None
) -> Any:
    """Power of the frame readout: ADC conversions plus link, see the module docstring.

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


_PREFIXES = ((1e0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n"), (1e-12, "p"), (1e-15, "f"))


def _si(value: float, unit: str) -> str:
    """``value`` with an SI prefix and 3 significant digits, e.g. ``10 pJ per event``."""
    value = float(f"{value:.3g}")
    for factor, prefix in _PREFIXES:
        if value >= factor:
            return f"{value / factor:.3g} {prefix}{unit}"
    if value == 0:
        return f"0 {unit}"
    return f"{value:.3g} {unit}"
