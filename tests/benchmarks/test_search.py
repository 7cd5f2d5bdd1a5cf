"""The search benchmark's space and its scaling of objectives, without running it."""

import numpy as np

from benchmarks.search import SPACE, grid_params, scaled_costs
from pipeline.design.space import Space


def test_the_benchmark_space_grids_into_192_distinct_points():
    space = Space.from_dict(SPACE)
    params = grid_params(space)
    assert len(params) == 192 == len(space.exhaustive_grid(10).unique_points())
    assert params[0] == {
        "readout.threshold_v": 0.02,
        "coding.window_s": 0.05,
        "array.rows": 1,
        "array.cols": 1,
    }


def test_objectives_are_scaled_to_the_grid_range():
    values = np.array([[0.5, 0.0], [0.25, 99.0], [0.75, 9.0]])  # accuracy, data rate
    raw = np.column_stack([-values[:, 0], np.log10(1 + values[:, 1])])
    scaled = scaled_costs(values, raw.min(axis=0), raw.max(axis=0))
    np.testing.assert_allclose(scaled, [[0.5, 0.0], [1.0, 1.0], [0.0, 0.5]])
