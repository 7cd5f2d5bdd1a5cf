"""Early exit on hand-made decisions: decision times, accuracy and energy per threshold."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pipeline.results.decoder_energy import DecoderEnergyModel
from pipeline.results.early_exit import decides, early_exit, exit_energy_j, full_touch

TIMES = np.array([1.0, 2.0, 3.0])
TIMES4 = np.array([0.1, 0.2, 0.3, 0.4])
NAN = np.nan
# (times, repeats=1, recordings=4). Recording 3 is never decided; recording 2 not at 1 s.
CONFIDENCE = np.array(
    [
        [[0.6, 0.2, NAN, NAN]],
        [[0.95, 0.4, 0.91, NAN]],
        [[0.99, 0.5, 0.7, NAN]],
    ]
)
CORRECT = np.array(
    [
        [[0, 0, -1, -1]],
        [[1, 0, 1, -1]],
        [[1, 1, 0, -1]],
    ],
    dtype=np.int8,
)


@pytest.mark.parametrize(
    ("threshold", "times", "right"),
    [
        # 0.9: recording 0 passes at 2 s (right), 1 never (last, 3 s, right), 2 at 2 s (right).
        (0.9, [2.0, 3.0, 2.0], [1, 1, 1]),
        # 0.5: 0 at 1 s (wrong), 1 reaches 0.5 at 3 s (right), 2 at 2 s (right).
        (0.5, [1.0, 3.0, 2.0], [0, 1, 1]),
        # 0: every recording at its first decision; 2's is at 2 s.
        (0.0, [1.0, 1.0, 2.0], [0, 0, 1]),
        # 1: none passes; all at the last time they decide.
        (1.0, [3.0, 3.0, 3.0], [1, 1, 0]),
    ],
)
def test_each_recording_exits_at_the_first_confident_decision_else_the_last(
    threshold, times, right
):
    found = early_exit(CONFIDENCE, CORRECT, TIMES, threshold)
    assert found.decision_s[0, :3].tolist() == times and np.isnan(found.decision_s[0, 3])
    assert found.correct[0].tolist() == [*right, -1]
    assert found.index[0, 3] == -1 and found.n == 3
    assert math.isclose(found.mean_decision_s, sum(times) / 3)
    assert math.isclose(found.accuracy, sum(right) / 3)


def test_leading_dimensions_are_points_each_exited_alone():
    confidence = np.stack([CONFIDENCE, np.where(np.isnan(CONFIDENCE), NAN, 1.0)])
    found = early_exit(confidence, np.stack([CORRECT, CORRECT]), TIMES, 0.9)
    assert found.mean_decision_s.shape == (2,)
    assert np.allclose(found.mean_decision_s, [7 / 3, 4 / 3])
    assert np.allclose(found.accuracy, [1.0, 1 / 3])


def test_exit_energy_is_the_mean_of_the_operations_counted_up_to_each_exit():
    # Exits at 0.9: 2 s, 3 s, 2 s -> 20, 30, 20 accumulates and 1, 1, 1 neuron update.
    found = early_exit(CONFIDENCE, CORRECT, TIMES, 0.9)
    band = exit_energy_j(found, np.array([10.0, 20.0, 30.0]), np.zeros(3), np.ones(3))
    assert math.isclose(band.low_j, 70 / 3 * 12.7e-12 + 52e-12)
    assert math.isclose(band.high_j, 70 / 3 * 23.6e-12 + 81e-12)
    model = DecoderEnergyModel()
    assert band.low_j < band.high_j and model.ac.low_j < model.ac.high_j


def test_no_decision_at_all_is_nan_not_an_error():
    found = early_exit(CONFIDENCE[..., 3:], CORRECT[..., 3:], TIMES, 0.9)
    assert found.n == 0 and math.isnan(found.mean_decision_s) and math.isnan(found.accuracy)
    band = exit_energy_j(found, np.ones(3), np.ones(3), np.ones(3))
    assert math.isnan(band.low_j) and math.isnan(band.high_j)


def test_decision_times_of_a_model_and_its_full_touch():
    assert decides(CORRECT).tolist() == [True, True, True]
    assert full_touch(CORRECT) == 2
    assert full_touch(np.full((3, 1, 2), -1)) is None


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ((CONFIDENCE, CORRECT[:2], TIMES, 0.9), "one shape"),
        ((CONFIDENCE, CORRECT, TIMES[:2], 0.9), "decision_s must have shape"),
        ((CONFIDENCE, CORRECT, TIMES[::-1], 0.9), "strictly ascending"),
        ((CONFIDENCE, CORRECT, TIMES, 1.5), r"threshold must be a number in \[0, 1\]"),
        ((CONFIDENCE, CORRECT, TIMES, NAN), r"threshold must be a number in \[0, 1\]"),
        ((CONFIDENCE, CORRECT * 2, TIMES, 0.9), "only 1, 0 and -1"),
    ],
)
def test_bad_input_is_refused(args, match):
    with pytest.raises(ValueError, match=match):
        early_exit(*args)


@settings(max_examples=60, deadline=None)
@given(
    decided=arrays(np.bool_, (4, 2, 5)),
    right=arrays(np.bool_, (4, 2, 5)),
    confidence=arrays(np.float64, (4, 2, 5), elements=st.floats(0.0, 1.0)),
    thresholds=st.lists(st.floats(0.0, 1.0), min_size=2, max_size=2),
)
def test_a_higher_threshold_never_decides_sooner_and_exits_only_where_decided(
    decided, right, confidence, thresholds
):
    correct = np.where(decided, right.astype(np.int8), np.int8(-1))
    confidence = np.where(decided, confidence, np.nan)
    low, high = sorted(thresholds)
    early, late = (early_exit(confidence, correct, TIMES4, t) for t in (low, high))
    has = decided.any(axis=0)
    assert np.array_equal(early.index >= 0, has) and np.array_equal(late.index >= 0, has)
    assert np.all(early.index[has] <= late.index[has])
    at = np.take_along_axis(decided, np.maximum(late.index, 0)[np.newaxis], axis=0)[0]
    assert np.all(at[has])  # every exit is a time the pair was decided at
    assert early.n == late.n == int(has.sum())
