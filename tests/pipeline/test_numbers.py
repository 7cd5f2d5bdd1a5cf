"""Tests of pipeline.numbers: the shared checks of user-given numbers."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.numbers import positive_number, whole_number


@pytest.mark.parametrize(
    ("value", "expected"),
    [(1, 1.0), (2.5, 2.5), (np.int16(3), 3.0), (np.float32(0.5), 0.5), (1e-300, 1e-300)],
)
def test_positive_number_accepts_finite_positive_numbers_as_float(value, expected):
    got = positive_number(value)
    assert got == expected
    assert type(got) is float


@pytest.mark.parametrize(
    "value", [0, 0.0, -1, -0.0, float("nan"), float("inf"), True, "100", None, [1.0]]
)
def test_positive_number_refuses_everything_else(value):
    assert positive_number(value) is None


@pytest.mark.parametrize(("value", "minimum"), [(0, 0), (1, 1), (np.int64(7), 1), (2**70, 1)])
def test_whole_number_accepts_integers_from_the_minimum_as_int(value, minimum):
    got = whole_number(value, minimum)
    assert got == value
    assert type(got) is int


@pytest.mark.parametrize("value", [0, -3, 1.0, 2.0, True, "2", None, np.float64(2)])
def test_whole_number_refuses_everything_else(value):
    assert whole_number(value, 1) is None
