"""The TRUE trains of a recording's taxels in one kernel call: the trains of a call per taxel,
bit for bit, a long train or a bad sample included."""

import numpy as np
import pytest

from pipeline.chain.readout import level_crossings, level_crossings_rows
from pipeline.chain.readout_effects import true_train, true_trains
from pipeline.design.scene import Scene

FS = 1000.0


def rows_of_walks(n_rows: int = 5, n: int = 3000, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.normal(scale=0.05, size=(n_rows, n)), axis=1)


def assert_same_trains(got, expected):
    assert len(got) == len(expected)
    for (t, p), (t0, p0) in zip(got, expected, strict=True):
        np.testing.assert_array_equal(t, t0)
        np.testing.assert_array_equal(p, p0)
        assert t.dtype == np.float64 and p.dtype == np.int8


def test_rows_give_the_trains_of_one_call_each_bit_for_bit():
    rows = rows_of_walks()
    for threshold in (0.01, 0.09, 0.5):
        expected = [level_crossings(row, FS, threshold) for row in rows]
        assert_same_trains(level_crossings_rows(rows, FS, threshold), expected)


def test_a_train_longer_than_the_typical_buffer_is_encoded_again_whole():
    rows = rows_of_walks(n_rows=3, n=5000)
    rows[1] = np.where(np.arange(5000) % 2, 1.0, -1.0)  # a spike pair per sample: past n / 4
    expected = [level_crossings(row, FS, 0.3) for row in rows]
    assert len(expected[1][0]) > 5000 // 4
    assert_same_trains(level_crossings_rows(rows, FS, 0.3), expected)


def test_a_non_finite_sample_is_the_row_s_own_error():
    rows = rows_of_walks(n_rows=2, n=100)
    rows[1, 40] = np.nan
    with pytest.raises(ValueError, match="non-finite sample"):
        level_crossings_rows(rows, FS, 0.09)
    with pytest.raises(ValueError, match="rows must be 2-D"):
        level_crossings_rows(rows[0], FS, 0.09)


@pytest.mark.parametrize("encoder", ["lcs", "decaying"])
def test_true_trains_are_the_true_train_of_each_row(encoder):
    readout = Scene.paper().replace(**{"readout.encoder": encoder}).readout
    rows = rows_of_walks(n_rows=3, n=800)
    assert_same_trains(true_trains(rows, FS, readout), [true_train(r, FS, readout) for r in rows])
