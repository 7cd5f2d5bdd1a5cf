"""The cube of a sweep whose points simulate chips: the chip dimension and the yield variables."""

import numpy as np
import pytest

from pipeline.chain.metrics import SpikeMetrics
from pipeline.design.grid import Grid
from pipeline.results.cube import CUBE_VARIABLES, build_cube
from pipeline.results.yields import yield_statistics
from pipeline.run.chips import ChipResults
from pipeline.run.entries import OutOfFold, RecordingsInfo, ResultEntry
from pipeline.run.grid_keys import keyed_points

NAMES = tuple(f"c{c}/{i}" for c in range(2) for i in range(4))
LABELS = np.array([0, 0, 0, 0, 1, 1, 1, 1])
FOLDS = np.array([[0, 1, 0, 1, 0, 1, 0, 1]])

GRID = {
    "name": "chips",
    "base": "smoke",
    "sweeps": {
        "mixed": {
            "set": {"readout.effects": {"threshold_mismatch": {}}, "training.models": ["ffnn"]},
            "axes": {"chips.count": [1, 3]},
        }
    },
}


def metrics(rate: float) -> SpikeMetrics:
    return SpikeMetrics(10.0, 0.0, 0.0, rate, 3 * rate, 3.47)


def entry(n_chips: int) -> ResultEntry:
    # Chip k gets recordings 0..k wrong: accuracy (8 - k - 1) / 8 for k < n.
    predicted = np.tile(LABELS, (n_chips, 1, 1))
    for k in range(n_chips):
        predicted[k, 0, : k + 1] = 1 - LABELS[: k + 1]
    right = predicted == LABELS
    fold = np.stack([[right[k, 0, FOLDS[0] == f].mean() for f in (0, 1)] for k in range(n_chips)])
    chips = None
    if n_chips > 1:
        chips = ChipResults(
            {"ffnn": fold[:, np.newaxis]},
            {"ffnn": predicted},
            tuple(metrics(100.0 + k) for k in range(n_chips)),
        )
    return ResultEntry(
        fold_accuracy={"ffnn": fold[0][np.newaxis]},
        seconds={"readout": 1.0},
        metrics=metrics(100.0),
        recordings=RecordingsInfo("synthetic", ("a", "b"), 2000.0),
        out_of_fold=OutOfFold(NAMES, LABELS, {"ffnn": predicted[0]}, FOLDS),
        n_windows_used=14,
        chips=chips,
    )


@pytest.fixture(scope="module")
def cube():
    grid = Grid.from_dict(GRID)
    (sweep,) = grid.sweeps
    records = {p.key: entry(p.scene.chips.count) for p in keyed_points(grid, sweep)}
    return build_cube(grid, sweep, records)


def test_variables_lie_along_the_chip_dimension_padded_where_a_point_has_fewer(cube):
    assert list(cube["chip"].values) == [0, 1, 2]
    assert cube["accuracy"].dims == ("count", "model", "chip", "repeat", "fold")
    assert cube["accuracy_mean"].dims == ("count", "model", "chip")
    assert cube["predicted"].dims == ("count", "model", "chip", "repeat", "recording")
    assert cube["event_rate_hz"].dims == ("count", "chip")
    assert cube["equivalent_bits"].dims == ("count",)
    one, three = cube["accuracy_mean"].sel(model="ffnn").values
    assert one[0] == pytest.approx(7 / 8) and np.isnan(one[1:]).all()
    assert three == pytest.approx([7 / 8, 6 / 8, 5 / 8])
    assert (cube["predicted"].isel(count=0, chip=slice(1, None)) == -1).all()
    assert cube["event_rate_hz"].values[1] == pytest.approx([100.0, 101.0, 102.0])
    correct = cube["correct"].isel(count=1, chip=2, repeat=0, model=0).values
    assert correct.tolist() == [0] * 3 + [1] * 5


def test_yield_variables_are_those_of_the_yields_module_with_declared_units(cube):
    expected = yield_statistics(cube["accuracy_mean"].values, 0.5)
    for name, values in expected.items():
        assert cube[name].dims == ("count", "model")
        np.testing.assert_array_equal(cube[name].values, values)
        assert cube[name].attrs == CUBE_VARIABLES[name]
    assert cube["accuracy_chip_mean"].values[1, 0] == pytest.approx(6 / 8)
    assert cube["yield_share"].values[:, 0] == pytest.approx([1.0, 1.0])
    assert int(cube["chips.deployment"].size) == 1 and cube["chips.yield_target"] == 0.5
