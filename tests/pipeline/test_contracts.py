"""The public names the architecture lists as contracts import under those exact names."""

import numpy as np

import storage
from pipeline.chain import coding, readout
from pipeline.coding import rate_code
from pipeline.readout import level_crossings
from storage import open_results


def test_contract_names_are_the_chain_functions():
    assert level_crossings is readout.level_crossings
    assert rate_code is coding.rate_code
    assert open_results is storage.open_results


def test_contract_names_work_as_documented():
    times_s, polarity = level_crossings(np.array([0.0, 0.25, 0.0]), 10.0, 0.1)
    assert times_s.dtype == np.float64 and polarity.dtype == np.int8
    assert polarity.tolist() == [1, 1, -1, -1]
    counts, dropped = rate_code(times_s, 0.15, 1)
    assert counts.tolist() == [2] and dropped == 2
