"""Tests of the readout's energy constants: validation, option units, stated assumptions."""

from __future__ import annotations

import math
from dataclasses import fields

import pytest

from pipeline.results.readout_constants import PARAMETERS, EnergyModel


def test_model_from_option_units_and_its_problems():
    model = EnergyModel.from_options(
        {"front_end_w_per_taxel": 5.0, "event_energy_j": 20.0, "taxels_per_adc": 8.0}
    )
    assert model == EnergyModel(front_end_w_per_taxel=5e-9, event_energy_j=20e-12, taxels_per_adc=8)
    assert EnergyModel.from_options({name: None for name in PARAMETERS}) == EnergyModel()
    with pytest.raises(ValueError) as caught:
        EnergyModel.from_options({"adc_static_w": -1.0, "taxels_per_adc": 2.5})
    assert str(caught.value) == (
        "--adc-static-nw -1: need a finite number >= 0; --taxels-per-adc 2.5: need a whole "
        "number >= 1"
    )


FIELDS = [f.name for f in fields(EnergyModel)]
AMOUNTS = [n for n in FIELDS if not PARAMETERS[n].count]


@pytest.mark.parametrize("name", AMOUNTS)
@pytest.mark.parametrize("value", [-1e-12, math.nan, math.inf, "1e-12", True, None])
def test_model_constants_are_validated_naming_field_and_value(name, value):
    with pytest.raises(
        ValueError,
        match=rf"^EnergyModel\.{name} must be a finite number >= 0, got {value!r}$",
    ):
        EnergyModel(**{name: value})


@pytest.mark.parametrize("value", [0, 2.5, -1, math.inf, True])
def test_taxels_per_adc_is_a_whole_number_of_at_least_one(value):
    with pytest.raises(ValueError, match=r"^EnergyModel\.taxels_per_adc must be a whole number"):
        EnergyModel(taxels_per_adc=value)


def test_every_problem_is_named_at_once():
    with pytest.raises(ValueError, match=r"front_end_w_per_taxel .*; EnergyModel\.adc_static_w"):
        EnergyModel(front_end_w_per_taxel=-1.0, adc_static_w=math.nan)


def test_defaults_are_finite_and_positive_and_options_unique():
    model = EnergyModel()
    for name in FIELDS:
        value = getattr(model, name)
        assert isinstance(value, int if PARAMETERS[name].count else float)
        assert math.isfinite(value)
        assert value > 0
    options = [p.option for p in PARAMETERS.values()]
    assert len(set(options)) == len(options)
    assert [p.calibrated for p in PARAMETERS.values()].count(True) == 1


def test_default_assumptions_state_each_value_and_source():
    sentences = EnergyModel().assumptions()
    assert len(sentences) == len(FIELDS)
    assert sentences[0].startswith("front_end_w_per_taxel = 10 nW per taxel: static bias ")
    assert "calibrated on the chip of M. D. Alea et al." in sentences[0]
    assert "12.33 nW per taxel" in sentences[0]
    assert sentences[2].startswith("event_energy_j = 10 pJ per event: energy of ")
    assert sentences[4].startswith("adc_fom_j_per_step = 10 fJ per conversion step: Walden ")
    assert "neuromorphic" in sentences[2]
    assert "Murmann" in sentences[4]
    assert sentences[6].startswith("taxels_per_adc = 16 taxels: ")
    assert all(s.endswith(".") for s in sentences)


def test_user_values_are_named_with_the_default_beside_them():
    sentences = EnergyModel(
        event_energy_j=2.5e-11, adc_fom_j_per_step=0.0, link_energy_j_per_bit=3e-9
    ).assumptions()
    assert sentences[2].startswith("event_energy_j = 25 pJ per event: ")
    assert "; set by the user (the default, 10 pJ per event, is assumed from " in sentences[2]
    assert sentences[4].startswith("adc_fom_j_per_step = 0 fJ per conversion step: ")
    assert "the default, 10 fJ per conversion step, is" in sentences[4]
    assert sentences[3].startswith("link_energy_j_per_bit = 3000 pJ per bit: ")
