"""The decoder's energy per decision: operations times per-operation energies, as a band."""

import math

import numpy as np
import pytest

from pipeline.results.decoder_energy import DecoderEnergyModel, OperationEnergy, decoder_energy_j


def test_the_declared_bands_are_the_cited_figures():
    model = DecoderEnergyModel()
    assert (model.ac.low_j, model.ac.high_j) == (12.7e-12, 23.6e-12)  # ODIN, Loihi
    assert math.isclose(model.mac.low_j, 3.7e-12 + 0.9e-12)  # Horowitz: fp32 multiply + add
    assert math.isclose(model.mac.high_j, 3.7e-12 + 0.9e-12 + 10e-12 / 2)  # + a 32-bit load
    assert (model.neuron_update.low_j, model.neuron_update.high_j) == (52e-12, 81e-12)
    sentences = model.assumptions()
    assert len(sentences) == 3
    assert "12.7 pJ (ODIN" in sentences[0] and "23.6 pJ (Loihi" in sentences[0]
    assert "Horowitz" in sentences[1] and "32-bit float" in sentences[1]


def test_energy_is_operations_times_energies_by_hand():
    # 1000 accumulates and 10 neuron updates: 1000 x 12.7 pJ + 10 x 52 pJ = 13.22 nJ at the
    # low end, 1000 x 23.6 pJ + 10 x 81 pJ = 24.41 nJ at the high end.
    band = decoder_energy_j(1000, 0, 10)
    assert math.isclose(band.low_j, 13.22e-9, rel_tol=1e-12)
    assert math.isclose(band.high_j, 24.41e-9, rel_tol=1e-12)
    assert isinstance(band.low_j, float)
    # 500 multiply-accumulates: 500 x 4.6 pJ = 2.3 nJ, 500 x 9.6 pJ = 4.8 nJ.
    band = decoder_energy_j(0.0, 500.0, 0.0)
    assert math.isclose(band.low_j, 2.3e-9) and math.isclose(band.high_j, 4.8e-9)


def test_counts_broadcast_and_an_unknown_count_is_an_unknown_energy():
    band = decoder_energy_j(np.array([[0.0, 100.0, np.nan]]), 0, np.array([[1.0], [2.0]]))
    assert band.low_j.shape == (2, 3)
    assert np.allclose(band.low_j[:, :2], [[52e-12, 1322e-12], [104e-12, 1374e-12]])
    assert np.isnan(band.low_j[:, 2]).all() and np.isnan(band.high_j[:, 2]).all()


def test_a_model_of_other_energies_prices_with_them():
    cheap = OperationEnergy(1e-12, 2e-12, "ac", "a", "b")
    band = decoder_energy_j(10, 0, 0, DecoderEnergyModel(ac=cheap))
    assert math.isclose(band.low_j, 10e-12) and math.isclose(band.high_j, 20e-12)


@pytest.mark.parametrize(
    ("counts", "match"),
    [
        ((-1, 0, 0), "ac counts must be finite and >= 0"),
        ((0, np.inf, 0), "mac counts must be finite"),
        ((0, 0, "many"), "neuron_update counts must be numbers"),
    ],
)
def test_bad_counts_are_refused_by_name(counts, match):
    with pytest.raises(ValueError, match=match):
        decoder_energy_j(*counts)


def test_a_band_upside_down_or_negative_is_refused():
    with pytest.raises(ValueError, match="low .* above high"):
        OperationEnergy(2e-12, 1e-12, "ac", "a", "b")
    with pytest.raises(ValueError, match="finite numbers >= 0"):
        OperationEnergy(-1e-12, 1e-12, "ac", "a", "b")
    with pytest.raises(TypeError, match="DecoderEnergyModel"):
        decoder_energy_j(1, 1, 1, model="loihi")
