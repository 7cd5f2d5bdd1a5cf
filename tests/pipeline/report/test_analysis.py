"""The whole report from cubes: cubes that do not describe themselves, the paper grid's sweeps."""

import pytest

from pipeline.errors import EskinError
from pipeline.grid import load_grid
from pipeline.report import build_report
from pipeline.scene import cache_key
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes, paper_like_accuracy


def test_cubes_that_do_not_describe_themselves_are_refused():
    cubes = make_cubes({"threshold": PAPER_LIKE_SWEEPS["threshold"]})
    cubes["threshold"] = cubes["threshold"].drop_vars("result_key")
    with pytest.raises(EskinError, match="threshold .*older eskin-sweep.*eskin sweep"):
        build_report(cubes)


def test_paper_grid_observation_sweep_reuses_the_operating_points_spike_trains():
    grid = load_grid("paper")
    sweep = next(s for s in grid.sweeps if s.name == "observation")
    assert sweep.axes[0].field == "coding.n_windows" and sweep.axes[0].values[0] == 1
    spikes = {cache_key(p.scene, "spikes") for p in grid.points() if p.sweep == "observation"}
    assert spikes == {cache_key(grid.base, "spikes")}
    assert paper_like_accuracy(grid.base) > 0  # the helper accepts the paper scene too
