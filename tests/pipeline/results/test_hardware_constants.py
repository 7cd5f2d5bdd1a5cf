"""Hardware constants a designer brings: every declared constant once, a file's overrides, every
problem in one line naming the file and the key."""

import dataclasses
from pathlib import Path

import pytest

from pipeline.errors import EskinError
from pipeline.results.decoder_energy import DECODER_OPERATIONS, DecoderEnergyModel
from pipeline.results.hardware_constants import (
    DECLARED,
    Constants,
    Override,
    load_constants,
)
from pipeline.results.matched_area import A_VT, A_VT_V_M
from pipeline.results.readout_constants import PARAMETERS, EnergyModel


def write(tmp_path, text: str):
    path = tmp_path / "mine.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_every_declared_constant_is_named_once_with_unit_meaning_and_source():
    decoder = [f"{op}_{end}_j" for op in DECODER_OPERATIONS for end in ("low", "high")]
    assert list(DECLARED) == [*PARAMETERS, "a_vt_v_m", *decoder]
    assert DECLARED["a_vt_v_m"].parameter is A_VT and DECLARED["a_vt_v_m"].default == A_VT_V_M
    assert DECLARED["ac_low_j"].default == DecoderEnergyModel().ac.low_j == 12.7e-12
    assert (
        DECLARED["neuron_update_high_j"].parameter.source
        == DecoderEnergyModel().neuron_update.high_source
    )
    for declared in DECLARED.values():
        p = declared.parameter
        assert p.unit and p.scale > 0 and p.what and p.source
    # As declared, the models are the defaults.
    assert Constants().energy_model() == EnergyModel()
    assert Constants().decoder_model() == DecoderEnergyModel()
    assert Constants().a_vt_v_m == A_VT_V_M


def test_a_file_overrides_constants_in_their_declared_units_each_with_its_source(tmp_path):
    path = write(
        tmp_path,
        """
[a_vt_v_m]
value = 3.5
unit = "mV um"
source = "foundry X, 180 nm matching report"

[event_energy_j]
value = 4
unit = "pJ per event"
source = "our comparator, post-layout"

[taxels_per_adc]
value = 8
unit = "taxels"
source = "one ADC per 8 columns"

[ac_high_j]
value = 30.0
unit = "pJ per operation"
source = "our accelerator"
""",
    )
    constants = load_constants(path)
    assert constants.origin == str(path)
    a_vt = constants.overrides["a_vt_v_m"]
    assert a_vt.source == "foundry X, 180 nm matching report"
    assert a_vt.value == pytest.approx(3.5e-9, rel=1e-15)
    assert constants.a_vt_v_m == pytest.approx(3.5e-9, rel=1e-15)
    energy = constants.energy_model()
    assert energy == EnergyModel(event_energy_j=energy.event_energy_j, taxels_per_adc=8)
    assert energy.event_energy_j == pytest.approx(4e-12, rel=1e-15)
    assert isinstance(energy.taxels_per_adc, int)
    decoder = constants.decoder_model()
    assert (
        decoder.ac.high_j == pytest.approx(30e-12) and decoder.ac.high_source == "our accelerator"
    )
    assert decoder.ac.low_j == DecoderEnergyModel().ac.low_j
    assert decoder.mac == DecoderEnergyModel().mac
    assert constants.source("comparator_w_per_taxel") == PARAMETERS["comparator_w_per_taxel"].source
    on_top = constants.overriding("event_energy_j", 7e-12, "the command line")
    assert on_top.value("event_energy_j") == 7e-12 and constants.value(
        "event_energy_j"
    ) == pytest.approx(4e-12)
    with pytest.raises(ValueError, match="not declared constants: wobble"):
        Constants({"wobble": Override(1.0, "x")})


def test_every_problem_of_a_file_is_one_line_naming_the_file_and_each_key(tmp_path):
    path = write(
        tmp_path,
        """
pelgrom = { value = 3.5, unit = "mV um", source = "x" }
a_vt_v_m = { value = 3.5, unit = "V m", source = "x" }
event_energy_j = { value = "ten", unit = "pJ per event", source = "x" }
front_end_w_per_taxel = { value = -1.0, unit = "nW per taxel", source = "x" }
taxels_per_adc = { value = 2.5, unit = "taxels", source = "x" }
link_energy_j_per_bit = { value = 1.0, unit = "pJ per bit" }
adc_static_w = 100
adc_fom_j_per_step = { value = 10, unit = "fJ per conversion step", source = "  ", note = 1 }
mac_low_j = { value = 20.0, unit = "pJ per operation", source = "x" }
""",
    )
    with pytest.raises(EskinError) as caught:
        load_constants(path)
    message = str(caught.value)
    assert "\n" not in message and caught.value.exit_status == 2
    assert message.startswith(f"invalid constants file {path} (10 problems): ")
    for expected in (
        "pelgrom: unknown constant (known: front_end_w_per_taxel, ",
        "a_vt_v_m.unit: 'V m' is not its unit (give it in mV um)",
        "event_energy_j.value 'ten': need a number",
        "front_end_w_per_taxel.value -1: need a finite number >= 0",
        "taxels_per_adc.value 2.5: need a whole number >= 1",
        "link_energy_j_per_bit: needs source",
        "adc_static_w: expected a table { value, unit, source }, got 100",
        "adc_fom_j_per_step.note: unknown key (known: value, unit, source)",
        "adc_fom_j_per_step.source: '  ' is not a source",
        "mac_low_j: 20 pJ per operation is above mac_high_j (9.6 pJ per operation)",
    ):
        assert expected in message, expected
    zero = write(tmp_path, 'a_vt_v_m = { value = 0, unit = "mV um", source = "x" }')
    with pytest.raises(EskinError, match=r"a_vt_v_m.value 0: need a finite number > 0"):
        load_constants(zero)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("a_vt_v_m = ", "not valid TOML"),
        (None, "cannot read file"),
        (b"\xff\xfe", "not UTF-8 text"),
    ],
)
def test_an_unreadable_file_is_one_line_naming_it(tmp_path, text, expected):
    path = tmp_path / "mine.toml"
    if isinstance(text, bytes):
        path.write_bytes(text)
    elif text is not None:
        path.write_text(text, encoding="utf-8")
    with pytest.raises(EskinError) as caught:
        load_constants(path)
    assert str(caught.value).startswith(f"invalid constants file {path}: {expected}")
    assert "\n" not in str(caught.value)


def test_constants_are_frozen_values():
    with pytest.raises(dataclasses.FrozenInstanceError):
        Constants().origin = "x"


def test_the_example_file_of_the_how_to_loads():
    example = Path(__file__).parents[3] / "examples" / "constants.toml"
    constants = load_constants(example)
    assert sorted(constants.overrides) == ["a_vt_v_m", "ac_high_j", "event_energy_j"]
    assert constants.a_vt_v_m == pytest.approx(3.5e-9)
    assert all(o.source.startswith("example: ") for o in constants.overrides.values())
