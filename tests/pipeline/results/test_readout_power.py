"""Tests of the readout power: data rates, event and frame readout powers, the power budget."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import xarray as xr

from pipeline.results.readout_constants import PARAMETERS, EnergyModel
from pipeline.results.readout_power import (
    MAX_BITS,
    energy_per_decision_j,
    event_data_rate_bps,
    event_dynamic_power_w,
    event_power_w,
    event_static_power_w,
    frame_data_rate_bps,
    frame_dynamic_power_w,
    frame_power_w,
    frame_static_power_w,
    power_budget,
)

# Round constants so that every expected value below is plain arithmetic.
MODEL = EnergyModel(
    front_end_w_per_taxel=3e-9,
    comparator_w_per_taxel=1e-9,
    event_energy_j=2e-11,
    link_energy_j_per_bit=1e-12,
    adc_fom_j_per_step=5e-15,
    adc_static_w=1e-7,
    taxels_per_adc=4,
)
ZERO = EnergyModel(**{name: 1 if p.count else 0.0 for name, p in PARAMETERS.items()})


def test_frame_data_rate_is_taxels_times_rate_times_bits():
    # Table I's ref. [16]: 10-bit frames at 9.6 kHz; 9 taxels.
    got = frame_data_rate_bps(9, 9600.0, 10)
    assert got == 864_000.0
    assert type(got) is float


def test_frame_data_rate_of_integers_is_float_and_does_not_wrap():
    assert type(frame_data_rate_bps(np.int64(9), np.int64(100), np.int64(10))) is float
    got = frame_data_rate_bps(np.array([2**40]), np.array([2**30]), np.array([60]))
    assert got.dtype == np.float64
    assert got[0] == pytest.approx(2.0**70 * 60, rel=1e-12)


def test_event_power_by_hand():
    # 50 events/s of a 9-taxel array: 5 bits per event, 250 bit/s.
    # dynamic: 50 * 20 pJ + 250 * 1 pJ = 1000 pJ/s + 250 pJ/s = 1.25 nW;
    # static: 9 * (3 nW + 1 nW) = 36 nW.
    assert event_data_rate_bps(9, 50.0) == 250.0
    got = event_dynamic_power_w(50.0, 250.0, MODEL)
    assert got == pytest.approx(1.25e-9, rel=1e-12)
    assert type(got) is float
    assert event_static_power_w(9, MODEL) == pytest.approx(36e-9, rel=1e-12)
    assert event_power_w(9, 50.0, 250.0, MODEL) == pytest.approx(37.25e-9, rel=1e-12)


def test_frame_power_by_hand():
    # dynamic: 4 taxels x 1 kHz x (5 fJ * 2**8 + 8 bit * 1 pJ) = 4000 * 9.28 pJ = 37.12 nW;
    # static: 4 * 3 nW front end + one ADC (4 taxels per ADC) of 100 nW = 112 nW.
    assert frame_dynamic_power_w(4, 1000.0, 8, MODEL) == pytest.approx(37.12e-9, rel=1e-12)
    assert frame_static_power_w(4, MODEL) == pytest.approx(112e-9, rel=1e-12)
    assert frame_power_w(4, 1000.0, 8, MODEL) == pytest.approx(149.12e-9, rel=1e-12)


def test_the_frame_readout_pays_one_adc_per_taxels_per_adc_rounded_up():
    # 4 taxels per ADC: 1 -> 1 ADC, 4 -> 1, 5 -> 2, 9 -> 3.
    taxels = np.array([1, 4, 5, 9])
    np.testing.assert_allclose(
        frame_static_power_w(taxels, MODEL), taxels * 3e-9 + np.array([1, 1, 2, 3]) * 1e-7
    )


def test_frame_power_accepts_fractional_bits():
    # 1 taxel x 1 Hz x (5 fJ * 2**3.5 + 3.5 pJ)
    got = frame_dynamic_power_w(1, 1.0, 3.5, MODEL)
    assert got == pytest.approx(5e-15 * 2**3.5 + 3.5e-12, rel=1e-12)


def test_default_model_is_used_when_none_is_given():
    assert event_dynamic_power_w(1.0, 0.0) == EnergyModel().event_energy_j
    assert frame_dynamic_power_w(1, 1.0, 0) == EnergyModel().adc_fom_j_per_step


# The chip the defaults are calibrated on (Alea et al., IEEE TBioCAS 2024): 192 taxels,
# 2.2 kevent/s for the whole array, 12.33 nW per taxel. The model must stay within 30 %.
CHIP_TAXELS, CHIP_EVENTS_HZ, CHIP_W_PER_TAXEL, CALIBRATION_TOLERANCE = 192, 2200.0, 12.33e-9, 0.3


def test_the_default_event_readout_is_calibrated_on_the_chip():
    budget = power_budget(CHIP_TAXELS, CHIP_EVENTS_HZ, bits=4)
    per_taxel = budget.to_json()["event_readout_per_taxel_w"]
    assert per_taxel == pytest.approx(CHIP_W_PER_TAXEL, rel=CALIBRATION_TOLERANCE)
    # As the module docstring states it: 10 + 2 nW static and 0.22 nW dynamic per taxel.
    assert per_taxel == pytest.approx(12.218e-9, rel=1e-4)
    assert budget.event.static_share == pytest.approx(12 / 12.218, rel=1e-4)
    # The event rate alone cannot reach the chip's figure: without bias it is 60x below.
    assert budget.event.dynamic_w / CHIP_TAXELS < CHIP_W_PER_TAXEL / 50


def test_power_budget_adds_both_readouts_parts():
    budget = power_budget(4, 50.0, 8, 1000.0, MODEL)
    out = budget.to_json()
    # 4 taxels: 3 bits per event, 150 bit/s; dynamic 50 * 20 pJ + 150 pJ/s = 1.15 nW.
    assert out["event_data_rate_bps"] == 150.0
    assert out["event_readout_static_w"] == pytest.approx(16e-9, rel=1e-12)
    assert out["event_readout_dynamic_w"] == pytest.approx(1.15e-9, rel=1e-12)
    assert out["event_readout_w"] == pytest.approx(17.15e-9, rel=1e-12)
    assert out["event_readout_per_taxel_w"] == pytest.approx(17.15e-9 / 4, rel=1e-12)
    assert out["frame_readout_w"] == pytest.approx(149.12e-9, rel=1e-12)
    assert out["frame_readout_static_w"] == pytest.approx(112e-9, rel=1e-12)
    assert out["frame_data_rate_bps"] == 32_000.0
    assert out["frame_over_event_power"] == pytest.approx(149.12 / 17.15, rel=1e-12)
    unknown = power_budget(4, 50.0, 8, None, MODEL).to_json()
    assert unknown["frame_readout_w"] is None and unknown["frame_data_rate_bps"] is None


def test_power_budget_names_every_bad_argument():
    with pytest.raises(ValueError) as caught:
        power_budget(0, -1.0, MAX_BITS + 1, 0.0)
    message = str(caught.value)
    for name in ("n_taxels", "event_rate_hz", "bits", "sampling_rate_hz"):
        assert name in message


def test_energy_per_decision_is_power_times_observation():
    assert energy_per_decision_j(2e-9, 4.0) == pytest.approx(8e-9, rel=1e-12)


def test_functions_broadcast_over_numpy_arrays():
    rates = np.array([0.0, 10.0, 100.0])
    np.testing.assert_allclose(
        event_dynamic_power_w(rates, 5 * rates, MODEL),
        rates * 2e-11 + 5 * rates * 1e-12,
        rtol=1e-12,
    )
    taxels = np.array([[1], [4]])
    bits = np.array([4, 8])
    power = frame_dynamic_power_w(taxels, 100.0, bits, MODEL)
    expected = taxels * 100.0 * (5e-15 * 2.0**bits + bits * 1e-12)
    assert power.shape == (2, 2)
    np.testing.assert_allclose(power, expected, rtol=1e-12)
    np.testing.assert_array_equal(frame_data_rate_bps(taxels, 100.0, bits), taxels * 100.0 * bits)


def test_lists_are_taken_as_arrays():
    np.testing.assert_array_equal(frame_data_rate_bps([1, 2], 10, 3), [30.0, 60.0])


def test_data_arrays_keep_their_coordinates():
    threshold_v = [0.05, 0.09, 0.2]
    events = xr.DataArray(
        [100.0, 50.0, 10.0], dims="threshold_v", coords={"threshold_v": threshold_v}
    )
    power = event_dynamic_power_w(events, events * 5, MODEL)
    assert isinstance(power, xr.DataArray)
    assert power.dims == ("threshold_v",)
    np.testing.assert_array_equal(power["threshold_v"], threshold_v)
    np.testing.assert_allclose(power, events.values * 2.5e-11, rtol=1e-12)

    bits = xr.DataArray([4.0, 8.0], dims="bits", coords={"bits": [4.0, 8.0]})
    frame = frame_dynamic_power_w(9, 9600.0, bits, MODEL)
    assert frame.dims == ("bits",)
    np.testing.assert_allclose(
        frame, 9 * 9600.0 * (5e-15 * 2.0**bits.values + bits.values * 1e-12), rtol=1e-12
    )
    ratio = frame / power
    assert ratio.dims == ("bits", "threshold_v")

    energy = energy_per_decision_j(power, xr.DataArray(4.0))
    np.testing.assert_array_equal(energy["threshold_v"], threshold_v)


def test_zero_rates_give_zero_dynamic_power_not_nan():
    assert event_dynamic_power_w(0.0, 0.0, MODEL) == 0.0
    assert event_power_w(9, 0.0, 0.0, MODEL) == event_static_power_w(9, MODEL)
    assert frame_power_w(0, 1000.0, MAX_BITS, MODEL) == 0.0
    assert frame_dynamic_power_w(9, 0.0, MAX_BITS, MODEL) == 0.0
    assert frame_data_rate_bps(9, 1000.0, 0) == 0.0
    assert energy_per_decision_j(0.0, 4.0) == 0.0
    zeros = frame_dynamic_power_w(np.zeros(3), np.zeros(3), np.full(3, MAX_BITS), MODEL)
    np.testing.assert_array_equal(zeros, np.zeros(3))


def test_a_zero_model_costs_nothing():
    assert event_power_w(9, 10.0, 50.0, ZERO) == 0.0
    assert frame_power_w(9, 1000.0, 10, ZERO) == 0.0


CALLS = {
    "n_taxels": lambda v: frame_power_w(v, 1.0, 8),
    "sampling_rate_hz": lambda v: frame_data_rate_bps(1, v, 8),
    "bits": lambda v: frame_power_w(1, 1.0, v),
    "event_rate_hz": lambda v: event_power_w(1, v, 1.0),
    "data_rate_bps": lambda v: event_power_w(1, 1.0, v),
    "power_w": lambda v: energy_per_decision_j(v, 1.0),
    "observation_s": lambda v: energy_per_decision_j(1.0, v),
}


@pytest.mark.parametrize("name", list(CALLS))
@pytest.mark.parametrize("value", [-0.5, -1e-300, math.nan, math.inf])
def test_bad_numbers_are_refused_naming_the_argument(name, value):
    with pytest.raises(ValueError, match=rf"^{name} must be finite and >= 0, got {value!r}"):
        CALLS[name](value)


@pytest.mark.parametrize("name", list(CALLS))
def test_one_bad_element_of_an_array_is_refused(name):
    with pytest.raises(ValueError, match=rf"^{name} .* got -2\.0 \(1 of 3 values\)"):
        CALLS[name](np.array([1.0, -2.0, 3.0]))
    with pytest.raises(ValueError, match=rf"^{name} .* got nan"):
        CALLS[name](xr.DataArray([1.0, math.nan], dims="x"))


@pytest.mark.parametrize("value", [True, "8", None, np.array([1 + 1j])])
def test_non_numbers_are_refused(value):
    with pytest.raises(ValueError, match=r"^bits must be a number or an array of numbers"):
        frame_data_rate_bps(1, 1.0, value)


def test_bits_above_the_maximum_are_refused():
    one_joule_per_step = dataclasses.replace(ZERO, adc_fom_j_per_step=1.0)
    assert frame_dynamic_power_w(1, 1.0, MAX_BITS, one_joule_per_step) == 2.0**MAX_BITS
    integer_bits = np.array([MAX_BITS - 1, MAX_BITS])  # 2**bits would wrap in int64
    np.testing.assert_array_equal(
        frame_dynamic_power_w(1, 1.0, integer_bits, one_joule_per_step), [2.0**63, 2.0**64]
    )
    with pytest.raises(ValueError, match=rf"^bits must be at most {MAX_BITS}, got 65\.0"):
        frame_power_w(1, 1.0, [8, MAX_BITS + 1])


def test_model_must_be_an_energy_model():
    with pytest.raises(TypeError, match="model must be an EnergyModel, got dict"):
        event_power_w(1, 1.0, 1.0, {"event_energy_j": 1e-12})
