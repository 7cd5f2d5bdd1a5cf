"""The public names the architecture lists as contracts import under those exact names."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import storage
from pipeline.chain import coding, readout
from pipeline.chain.spikes import SpikeTrains
from pipeline.coding import rate_code
from pipeline.design.scene import Polarity
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


# A ragged set of trains: (recordings, taxels) and each train's sorted times, some outside
# [0, 1) s and some on the 0.1 s edges, with random polarities.
one_train = st.lists(
    st.one_of(st.floats(-0.2, 1.2, allow_nan=False), st.integers(-1, 11).map(lambda k: k / 10)),
    max_size=25,
).map(sorted)


@settings(max_examples=60, deadline=None)
@given(
    shape=st.tuples(st.integers(1, 3), st.integers(1, 3)),
    data=st.data(),
)
def test_the_contract_codes_as_the_sweeps_frames_do(shape, data):
    n_trains = shape[0] * shape[1]
    times = data.draw(st.lists(one_train, min_size=n_trains, max_size=n_trains))
    signs = [
        data.draw(st.lists(st.sampled_from([-1, 1]), min_size=len(t), max_size=len(t)))
        for t in times
    ]
    trains = SpikeTrains.concatenate(
        [
            (np.array(t, dtype=np.float64), np.array(s, dtype=np.int8))
            for t, s in zip(times, signs, strict=True)
        ],
        shape[1],
        np.ones(shape[0]),
    )
    merged, dropped = coding.frames(trains, 0.1, 10)
    split, split_dropped = coding.frames(trains, 0.1, 10, Polarity.SPLIT)
    for index, train in enumerate(times):
        counts, lost = rate_code(np.array(train[::-1]), 0.1, 10)  # any order
        r, t = divmod(index, shape[1])
        np.testing.assert_array_equal(merged[r, 0, t], counts)
        assert dropped[r, t] == lost
        np.testing.assert_array_equal(split[r, :, t].sum(axis=0), counts)
        assert split_dropped[r, t] == lost
