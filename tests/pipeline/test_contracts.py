"""The public names the architecture lists as contracts import under those exact names."""

import numpy as np

import storage
from pipeline.chain import coding, readout
from pipeline.coding import rate_code
from pipeline.readout import decaying_crossings, level_crossings
from storage import open_results


def test_contract_names_are_the_chain_functions():
    assert level_crossings is readout.level_crossings
    assert decaying_crossings is readout.decaying_crossings
    assert rate_code is coding.rate_code
    assert open_results is storage.open_results


def test_contract_names_work_as_documented():
    times_s, polarity = level_crossings(np.array([0.0, 0.25, 0.0]), 10.0, 0.1)
    assert times_s.dtype == np.float64 and polarity.dtype == np.int8
    assert polarity.tolist() == [1, 1, -1, -1]
    counts, dropped = rate_code(times_s, 0.15, 1)
    assert counts.tolist() == [2] and dropped == 2


def test_the_decaying_encoder_works_as_documented():
    # theta_min = theta_0: the fixed encoder; then a threshold that decays from 0.1 V to 0.05 V
    # with a 1 ms time constant fires on the flat 0.06 V at t = 1 ms * ln(5) = 1.609 ms.
    times_s, polarity = decaying_crossings(np.array([0.0, 0.25, 0.0]), 10.0, 0.1, 0.1, 1.0)
    assert times_s.dtype == np.float64 and polarity.dtype == np.int8
    assert polarity.tolist() == [1, 1, -1, -1]
    times_s, polarity = decaying_crossings(
        np.array([0.0, 0.06, 0.06, 0.06]), 1000.0, 0.1, 0.05, 1e-3
    )
    assert polarity.tolist() == [1]
    assert abs(times_s[0] - 1e-3 * np.log(5.0)) < 1e-12
