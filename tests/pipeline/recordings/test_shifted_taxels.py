"""What makes a shifted taxel informative on the built-in touches (docs: the model page,
"Shifted taxels").

Taxels are time-shifted copies of one recording. Shifted by exactly one window, taxel ``k + 1``'s
window ``j + 1`` sees the same stretch of the touch as taxel ``k``'s window ``j``: whatever its
counts add must come from how it quantises that stretch. Each taxel's level-crossing reference
starts at its own first sample, so each quantises on its own grid ``r_0 + n theta``; these tests
hold that this is where a shifted taxel's information comes from, measured as the conditional
entropy of its counts given its neighbour's over the same stretches, and that it vanishes when
the grids are made the same.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipeline.chain.coding import rate_code
from pipeline.chain.frontend import fit_front_end
from pipeline.chain.readout import level_crossings
from pipeline.chain.taxels import taxel_signals
from pipeline.recordings.synthetic import synthetic_recordings

THRESHOLD_V = 0.09  # the paper's operating point, 1 V full scale
WINDOW_S = 0.1
ROWS = 4
SLIDING_FROM_S = 1.0


def _aligned_counts(common_grid: bool) -> np.ndarray:
    """int64 ``(ROWS, n)``: each taxel's counts over the same sliding stretches of the touches.

    ``common_grid``: start every taxel's reference on the grid ``n theta`` (its first sample
    moved to the nearest level) instead of at its own first sample.
    """
    recordings = synthetic_recordings(seed=0, recordings_per_class=2, duration_s=3.0)
    front_end = fit_front_end(recordings, 1.0)
    fs = recordings.fs_hz
    delays_s = np.arange(ROWS) * WINDOW_S
    per_stretch = []
    for signal in recordings.signals:
        taxels = taxel_signals(front_end.apply(signal), fs, delays_s)
        n_windows = math.floor(taxels.n_samples / fs / WINDOW_S)
        counts = []
        for k in range(ROWS):
            v = taxels.taxel(k).copy()
            if common_grid:
                v[0] = THRESHOLD_V * np.round(v[0] / THRESHOLD_V)
            times_s, _ = level_crossings(v, fs, THRESHOLD_V)
            counts.append(rate_code(times_s, WINDOW_S, n_windows)[0])
        # Taxel k lags taxel 0 by k windows: its window j + k covers taxel 0's window j.
        shared = n_windows - (ROWS - 1)
        aligned = np.stack([c[k : k + shared] for k, c in enumerate(counts)])
        sliding = np.arange(shared) * WINDOW_S >= SLIDING_FROM_S
        per_stretch.append(aligned[:, sliding])
    return np.concatenate(per_stretch, axis=1)


def _conditional_entropy_bits(x: np.ndarray, given: np.ndarray) -> float:
    """Empirical ``H(x | given)`` in bits of two int arrays of the same shape."""
    _, joint = np.unique(np.stack([given, x]), axis=1, return_counts=True)
    _, marginal = np.unique(given, return_counts=True)
    p_joint = joint / joint.sum()
    p_given = marginal / marginal.sum()
    return float(-(p_joint * np.log2(p_joint)).sum() + (p_given * np.log2(p_given)).sum())


@pytest.fixture(scope="module")
def own_grids():
    return _aligned_counts(common_grid=False)


@pytest.fixture(scope="module")
def common_grid():
    return _aligned_counts(common_grid=True)


def test_sliding_crosses_levels_at_the_operating_point(own_grids):
    # A sliding stretch that crosses no level is quantised alike on every grid.
    assert np.mean(own_grids > 0) > 0.3


def test_each_shifted_taxel_adds_information_through_its_own_grid(own_grids):
    for k in range(ROWS - 1):
        added = _conditional_entropy_bits(own_grids[k + 1], given=own_grids[k])
        assert added > 0.3, (k, added)
        assert np.mean(own_grids[k + 1] != own_grids[k]) > 0.2


def test_on_a_common_grid_a_shifted_taxel_adds_nothing(own_grids, common_grid):
    # The same stretches, the same signal, the same encoder: only the grids are made equal.
    assert common_grid.shape == own_grids.shape
    for k in range(ROWS - 1):
        assert _conditional_entropy_bits(common_grid[k + 1], given=common_grid[k]) < 0.02
        assert np.mean(common_grid[k + 1] != common_grid[k]) < 0.01
