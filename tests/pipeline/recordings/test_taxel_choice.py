"""Which taxels of a real array a reader takes, and their pitch."""

import math

import numpy as np
import pytest

from pipeline.recordings.taxel_choice import chosen_taxels, taxel_pitch_mm

#: A 4 x 4 grid at 1 mm, raster order (x along a row).
GRID_4X4 = np.array([[x, y] for y in range(4) for x in range(4)], dtype=np.float64)


def test_without_positions_the_taxels_read_are_the_middles_of_equal_stretches():
    assert chosen_taxels(16, None).tolist() == list(range(16))
    assert chosen_taxels(16, 16).tolist() == list(range(16))
    assert chosen_taxels(16, 1).tolist() == [8]
    assert chosen_taxels(16, 2).tolist() == [4, 12]
    assert chosen_taxels(16, 4).tolist() == [2, 6, 10, 14]
    assert chosen_taxels(5, 2).tolist() == [1, 3]
    for n in range(1, 20):
        for k in range(1, n + 1):
            chosen = chosen_taxels(n, k)
            assert len(np.unique(chosen)) == k and chosen.min() >= 0 and chosen.max() < n
            assert np.all(np.diff(chosen) > 0)


def test_with_positions_fewer_taxels_stand_farther_apart():
    assert chosen_taxels(16, 1, GRID_4X4).tolist() == [5]  # nearest the centre, first of four
    corners = chosen_taxels(16, 4, GRID_4X4)
    assert corners.tolist() == [0, 3, 12, 15]
    assert taxel_pitch_mm(GRID_4X4, corners) == 3.0
    assert taxel_pitch_mm(GRID_4X4, chosen_taxels(16, 16, GRID_4X4)) == 1.0
    assert taxel_pitch_mm(GRID_4X4, chosen_taxels(16, 2, GRID_4X4)) == pytest.approx(
        3 * math.sqrt(2), rel=1e-12
    )
    assert math.isnan(taxel_pitch_mm(GRID_4X4, chosen_taxels(16, 1, GRID_4X4)))
    pitches = [taxel_pitch_mm(GRID_4X4, chosen_taxels(16, k, GRID_4X4)) for k in range(2, 17)]
    assert np.all(np.diff(pitches) <= 0)


def test_reading_more_taxels_than_there_are_or_none_is_a_programming_error():
    with pytest.raises(ValueError, match="cannot read 5 of 4 taxels"):
        chosen_taxels(4, 5)
    with pytest.raises(ValueError, match="cannot read 0 of 4 taxels"):
        chosen_taxels(4, 0)
    with pytest.raises(ValueError, match=r"positions must be \(4, 2\)"):
        chosen_taxels(4, 2, GRID_4X4)
