"""Result cubes from point results: layout, gaps, correlations, and what they say of themselves."""

import dataclasses
import json
import math
import subprocess
import sys
import types
import warnings

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from pipeline.chain.metrics import SpikeMetrics
from pipeline.design.effects import ThresholdMismatch
from pipeline.design.fields import flatten
from pipeline.design.grid import Grid, sweep_points
from pipeline.design.scene import ReadoutSpec
from pipeline.results.cube import (
    CUBE_VARIABLES,
    build_cube,
    field_attrs,
    field_coordinate,
    metric_attrs,
)
from pipeline.run.decisions import Decisions
from pipeline.run.entries import OutOfFold, RecordingsInfo, ResultEntry
from pipeline.run.grid_keys import keyed_points
from pipeline.run.records import Charge
from pipeline.run.stages import RESULTS, interval_generator
from tests import golden_cubes as golden


def metrics(ssnr_db: float = math.inf, ste_s2: float = 0.0) -> SpikeMetrics:
    return SpikeMetrics(
        ssnr_db=ssnr_db,
        ste_s2=ste_s2,
        ste_sign_safe_s2=abs(ste_s2),
        event_rate_hz=100.0,
        data_rate_bps=300.0,
        equivalent_bits=3.0,
    )


def entries(grid, sweep, make):
    return {p.key: make(p) for p in keyed_points(grid, sweep)}


def build(grid, sweep, records):
    return build_cube(grid, sweep, records)


def built() -> dict[str, xr.Dataset]:
    """The golden grid's cubes, built now."""
    grid = golden.grid()
    records = golden.entries(grid)
    return {s.name: build(grid, s, records) for s in grid.sweeps}


# ---------------------------------------------------------------------------------------------
# Nothing that cubes held before changed


def test_cubes_reproduce_the_golden_variables():
    """Values, dtypes, dimensions and the coordinates cubes had before they described
    themselves, as ``storage.cubes.build_cube`` of that time built them from the same entries:
    exactly, but what the builder computes by reductions (within a few ulps,
    :func:`tests.golden_cubes.assert_matches`)."""
    expected = golden.read_golden()
    cubes = built()
    assert set(cubes) == set(expected)
    for name, cube in cubes.items():
        golden.assert_matches(golden.existing_part(cube, expected[name]), expected[name])


def built_grids() -> dict[str, xr.Dataset]:
    """The built-in grids' cubes (as they were), built now from the rich golden entries."""
    cubes = {}
    for name, grid in golden.grids().items():
        records = golden.rich_entries(grid)
        for sweep in grid.sweeps:
            cubes[f"{name}/{sweep.name}"] = build(grid, sweep, records)
    return cubes


def test_building_cubes_imports_no_scipy_stats():
    """Intervals and correlations need only scipy.special: a warm re-run of a sweep rebuilds
    every cube, and importing scipy.stats would take it about a second. Nor does building a
    cube import torch (another second for the sweep's process, which never trains)."""
    code = (
        "import sys\n"
        "from pipeline.results.cube import build_cube\n"
        "from tests import golden_cubes as golden\n"
        "grid = golden.grid()\n"
        "records = golden.rich_entries(grid)\n"
        "cubes = [build_cube(grid, sweep, records) for sweep in grid.sweeps]\n"
        "assert any('correlation_r' in cube for cube in cubes)\n"
        "print(sorted(name for name in sys.modules if name.startswith(('scipy.stats', 'torch'))))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300
    )
    assert result.stdout.strip() == "[]", result.stdout


def test_builtin_grids_cubes_reproduce_the_golden_files():
    """Every variable, coordinate and attribute of the paper and smoke grids' cubes, as the
    code before the stage registry declared stored records built them (renames listed)."""
    expected = golden.read_golden(golden.GRIDS_GOLDEN)
    cubes = built_grids()
    assert set(cubes) == set(expected)
    for name, cube in cubes.items():
        golden.compare_golden(cube, expected[name])


@pytest.mark.parametrize("change", ["value", "attr", "extra"])
def test_the_grids_golden_comparison_sees_a_change(change):
    expected = golden.read_golden(golden.GRIDS_GOLDEN)["paper/threshold"]
    cube = built_grids()["paper/threshold"]
    if change == "value":
        cube["accuracy_low"].values[0, 0] = 0.5
    elif change == "attr":
        cube["work_seconds"].attrs["units"] = "ms"
    else:
        cube["extra"] = cube["ssnr_db"]
    with pytest.raises(AssertionError):
        golden.compare_golden(cube, expected)


def test_the_golden_comparison_sees_a_changed_value():
    expected = golden.read_golden()["threshold"]
    cube = built()["threshold"]
    cube["ssnr_db"].values[0] = 1.0
    with pytest.raises(AssertionError):
        golden.assert_matches(golden.existing_part(cube, expected), expected)


@pytest.mark.parametrize("ulps", [golden.ULPS, golden.ULPS + 2])
def test_the_golden_comparison_allows_computed_values_a_few_ulps_and_no_more(ulps):
    """A correlation a few ulps of 1 away (another CPU's summation order) still matches; one
    further away, or a value the cube copies from its entries one ulp away, does not."""
    expected = golden.read_golden()["noise"]
    cube = golden.existing_part(built()["noise"], expected)
    cube["correlation_r"] = expected["correlation_r"] + ulps * np.finfo(np.float64).eps
    if ulps <= golden.ULPS:
        golden.assert_matches(cube, expected)
    else:
        with pytest.raises(AssertionError, match="correlation_r"):
            golden.assert_matches(cube, expected)
    copied = cube.copy(deep=True)
    copied["correlation_r"] = expected["correlation_r"]
    copied["ssnr_db"].values[0] = np.nextafter(copied["ssnr_db"].values[0], np.inf)
    with pytest.raises(AssertionError):
        golden.assert_matches(copied, expected)


# ---------------------------------------------------------------------------------------------
# Layout


def test_product_cube_layout_and_units():
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "two": {
                    "axes": {"readout.threshold_v": [0.05, 0.1], "coding.window_s": [0.1, 0.2, 0.3]}
                }
            },
        }
    )
    sweep = grid.sweeps[0]

    def make(point):
        i, j = point.index
        folds = np.full(4, 0.1 * i + 0.01 * j)
        return ResultEntry({"ffnn": folds, "cnn": folds / 2}, {"train_ffnn": 1.0}, metrics())

    cube = build(grid, sweep, entries(grid, sweep, make))
    assert cube["accuracy"].dims == ("threshold_v", "window_s", "model", "repeat", "fold")
    assert cube["accuracy"].shape == (2, 3, 2, 1, 4)
    one = cube["accuracy"].sel(threshold_v=0.1, window_s=0.3, model="ffnn", repeat=0)
    assert one.values[0] == 0.1 + 0.02
    # Without predictions: the mean over folds, and no interval.
    assert cube["accuracy_mean"].dims == ("threshold_v", "window_s", "model")
    assert cube["accuracy_mean"].sel(threshold_v=0.1, window_s=0.3, model="ffnn") == 0.1 + 0.02
    assert np.isnan(cube["accuracy_low"]).all() and cube["accuracy_low"].attrs["interval"] == "none"
    assert "predicted" not in cube and "recording" not in cube.dims
    assert cube["accuracy"].sel(model="cnn").max() == pytest.approx(0.06)
    assert cube["window_s"].attrs == {
        "field": "coding.window_s",
        "units": "s",
        "long_name": "rate-coding window length",
    }
    assert cube["accuracy"].attrs["units"] == "1"
    assert cube["ssnr_db"].attrs["units"] == "dB"
    assert np.all(np.isinf(cube["ssnr_db"].values))
    assert cube["work_seconds"].dims == ("threshold_v", "window_s", "stage")
    assert cube["work_seconds"].sel(stage="train_ffnn").values.tolist() == [[1.0] * 3] * 2
    assert np.all(np.isnan(cube["work_seconds"].sel(stage="coding").values))  # not measured
    # Paid seconds by charge: NaN throughout, as these results state none.
    assert cube["seconds"].dims == ("threshold_v", "window_s", "stage", "charge")
    assert cube["charge"].values.tolist() == ["own", "shared"]
    assert np.all(np.isnan(cube["seconds"].values))
    assert cube["seconds"].attrs["units"] == cube["work_seconds"].attrs["units"] == "s"
    # A swept field is its axis's coordinate, not a second one under its dotted name.
    assert "readout.threshold_v" not in cube.coords and "coding.window_s" not in cube.coords
    assert field_coordinate(cube, "coding.window_s") == "window_s"
    assert cube["window_s"].values.tolist() == [0.1, 0.2, 0.3]
    assert field_coordinate(cube, "array.rows") == "array.rows"
    assert field_coordinate(cube, "dataset.path") is None  # unset: the built-in data
    assert "correlation_r" not in cube


def out_of_fold(n_correct: dict[str, int], names, labels, repeats=1) -> OutOfFold:
    """Predictions with the first ``n_correct[model]`` recordings right and the others wrong."""
    labels = np.asarray(labels)
    predicted = {}
    for model, k in n_correct.items():
        guess = np.where(np.arange(len(labels)) < k, labels, (labels + 1) % 3)
        predicted[model] = np.tile(guess, (repeats, 1))
    folds = np.tile(np.arange(len(labels)) % 2, (repeats, 1))
    return OutOfFold(tuple(names), labels, predicted, folds)


def test_out_of_fold_predictions_and_intervals():
    """``predicted``, ``correct`` and ``test_fold`` along the union of the points' recordings,
    and ``accuracy_mean`` with its Wilson interval from the predictions."""
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"per_class": {"axes": {"readout.threshold_v": [0.05, 0.1]}}}}
    )
    sweep = grid.sweeps[0]
    names = [f"r{i}" for i in range(6)]
    labels = [0, 1, 2, 0, 1, 2]

    def make(point):
        if point.index == (0,):  # four recordings only: the others are -1 in the cube
            oof = out_of_fold({"ffnn": 4, "cnn": 2}, names[:4], labels[:4])
        else:
            oof = out_of_fold({"ffnn": 6, "cnn": 0}, names, labels)
        return ResultEntry({"ffnn": [0.5, 0.5], "cnn": [0.5, 0.5]}, {}, metrics(), None, oof)

    cube = build(grid, sweep, entries(grid, sweep, make))
    assert cube["predicted"].dims == ("threshold_v", "model", "repeat", "recording")
    assert cube["recording"].values.tolist() == names
    assert cube["label"].values.tolist() == labels
    first = cube["correct"].sel(threshold_v=0.05, repeat=0)
    assert first.sel(model="ffnn").values.tolist() == [1, 1, 1, 1, -1, -1]
    assert first.sel(model="cnn").values.tolist() == [1, 1, 0, 0, -1, -1]
    assert cube["test_fold"].sel(threshold_v=0.05, repeat=0).values.tolist() == [0, 1, 0, 1, -1, -1]
    assert cube["predicted"].dtype == np.int16 and cube["correct"].dtype == np.int8
    mean = cube["accuracy_mean"]
    assert mean.sel(threshold_v=0.05).values.tolist() == [1.0, 0.5]
    assert mean.sel(threshold_v=0.1).values.tolist() == [1.0, 0.0]
    ci = stats.binomtest(2, 4).proportion_ci(0.95, method="wilson")
    low = float(cube["accuracy_low"].sel(threshold_v=0.05, model="cnn"))
    high = float(cube["accuracy_high"].sel(threshold_v=0.05, model="cnn"))
    assert (low, high) == pytest.approx((ci.low, ci.high), abs=1e-12)
    assert cube["accuracy_low"].attrs["interval"].startswith("Wilson")
    assert cube["accuracy_high"].sel(threshold_v=0.1, model="ffnn") == 1.0
    for name in ("predicted", "correct", "test_fold", "accuracy_mean", "recording", "label"):
        assert cube[name].attrs["long_name"]


def test_decisions_in_time_are_on_the_union_of_the_points_times():
    """``decision_correct``, ``decision_confidence`` and the decoder's operations on the union
    of the decision times: -1 / NaN where a model decides nothing, and through the store's
    codec unchanged."""
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"w": {"axes": {"coding.window_s": [0.1, 0.2]}}}}
    )
    sweep = grid.sweeps[0]
    names, labels = ["r0", "r1", "r2"], [0, 1, 2]

    def make(point):
        window = point.scene.coding.window_s
        times = np.round(window * np.arange(1, 3), 9)  # two windows
        guess = np.array([[[1, 1, 2], [0, 1, 2]]])  # (repeat, time, recording)
        sure = np.array([[[0.4, 0.5, 0.6], [0.7, 0.8, 0.9]]], dtype=np.float32)
        counted = np.array([[0.0, 10.0, 0.0], [0.0, 20.0, 0.0]]) * window
        decisions = Decisions.of({"ffnn": (times, guess, sure)}, {"ffnn": counted})
        oof = out_of_fold({"ffnn": 3, "cnn": 3}, names, labels)
        entry = ResultEntry(
            {"ffnn": [0.5, 0.5], "cnn": [0.5, 0.5]}, {}, metrics(), None, oof, decisions=decisions
        )
        values, attrs = RESULTS.record.encode(entry)
        return RESULTS.record.decode(values, attrs)

    cube = build(grid, sweep, entries(grid, sweep, make))
    assert cube["decision_s"].values.tolist() == [0.1, 0.2, 0.4]
    assert cube["decision_correct"].dims == (
        "window_s",
        "model",
        "decision_s",
        "repeat",
        "recording",
    )
    first = cube["decision_correct"].sel(window_s=0.1, model="ffnn", repeat=0)
    assert first.values.tolist() == [[0, 1, 1], [1, 1, 1], [-1, -1, -1]]
    second = cube["decision_correct"].sel(window_s=0.2, model="ffnn", repeat=0)
    assert second.values.tolist() == [[-1, -1, -1], [0, 1, 1], [1, 1, 1]]
    assert (cube["decision_correct"].sel(model="cnn") == -1).all()
    confidence = cube["decision_confidence"].sel(window_s=0.2, model="ffnn", repeat=0)
    assert np.isnan(confidence.values[0]).all()
    assert confidence.values[2].tolist() == pytest.approx([0.7, 0.8, 0.9])
    assert cube["decision_confidence"].dtype == np.float32
    macs = cube["decoder_macs"].sel(model="ffnn")
    assert macs.sel(window_s=0.1).values.tolist()[:2] == pytest.approx([1.0, 2.0])
    assert np.isnan(macs.sel(window_s=0.1, decision_s=0.4))
    assert (cube["decoder_acs"].sel(model="ffnn", window_s=0.2, decision_s=0.4) == 0).all()
    for name in ("decision_s", "decision_correct", "decision_confidence", "decoder_acs"):
        assert cube[name].attrs["long_name"] and cube[name].attrs["units"]
    assert cube["decision_s"].attrs["units"] == "s"


def test_repeats_are_a_dimension_and_the_interval_a_bootstrap():
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "one": {"set": {"training.repeats": 3}, "axes": {"readout.threshold_v": [0.05]}}
            },
        }
    )
    sweep = grid.sweeps[0]
    names, labels = [f"r{i}" for i in range(6)], [0, 1, 2, 0, 1, 2]

    def make(point):
        oof = out_of_fold({"ffnn": 3, "cnn": 3}, names, labels, repeats=3)
        return ResultEntry(
            {"ffnn": np.full((3, 2), 0.5), "cnn": np.full((3, 2), 0.5)}, {}, metrics(), None, oof
        )

    cube = build(grid, sweep, entries(grid, sweep, make))
    assert cube.sizes["repeat"] == 3
    assert cube["accuracy_mean"].sel(model="ffnn").item() == 0.5
    assert "bootstrap" in cube["accuracy_low"].attrs["interval"]
    low, high = (
        cube["accuracy_low"].sel(model="ffnn").item(),
        cube["accuracy_high"].sel(model="ffnn").item(),
    )
    assert 0 <= low < 0.5 < high <= 1
    again = build(grid, sweep, entries(grid, sweep, make))  # the bootstrap's seed is fixed
    xr.testing.assert_identical(again, cube)


def test_every_point_has_its_result_key():
    grid = golden.grid()
    cube = built()["product"]
    sweep = next(s for s in grid.sweeps if s.name == "product")
    assert cube["result_key"].dims == ("threshold_v", "n_windows")
    for point in keyed_points(grid, sweep):
        assert cube["result_key"].values[point.index] == point.key


def test_base_and_fixed_fields_are_scalar_coordinates():
    grid = golden.grid()
    cubes = built()
    noise = cubes["noise"]
    assert noise["array.rows"].ndim == 0 and noise["array.rows"].item() == 1  # the sweep's set
    assert noise["array.cols"].item() == 1
    assert noise["training.folds"].item() == grid.base.training.folds  # the base scene's
    assert noise["coding.n_windows"].item() == "auto"
    assert noise["dataset.kind"].item() == "synthetic"
    assert noise["comparator_noise_sigma_v"].dims == ("amplifier_noise_sigma_v",)
    assert "readout.effects.comparator_noise.sigma_v" not in noise.coords  # the axis holds it
    assert "dataset.path" not in noise.coords  # unset: the built-in data
    assert "name" not in noise.coords
    threshold = cubes["threshold"]
    assert threshold["array.rows"].item() == grid.base.array.rows
    assert threshold["readout.effects"].item() == "{}"  # ideal readout
    # A point's implied effect parameter is described although no one wrote it down.
    assert cubes["mismatch"]["readout.effects.threshold_mismatch.floor_rel"].item() == 0.1


def test_swept_axes_hold_the_values_the_scenes_read():
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "ints": {"axes": {"readout.effects.threshold_mismatch.sigma_rel": [0, 1]}},
                "tables": {"axes": {"readout.effects": [{}, {"amplifier_noise": {}}]}},
            },
        }
    )
    ints, tables = (
        build(grid, sweep, entries(grid, sweep, lambda p: ResultEntry({}, {}, metrics())))
        for sweep in grid.sweeps
    )
    # Whole numbers given for a float field are the floats the scenes hold.
    assert ints["sigma_rel"].dtype == np.float64
    assert ints["sigma_rel"].values.tolist() == [0.0, 1.0]
    # A table is written as the scene reads it, its defaults filled in.
    assert tables["effects"].values.tolist() == ["{}", '{"amplifier_noise": {"sigma_v": 0.005}}']
    assert tables["effects"].attrs["field"] == "readout.effects"
    assert "readout.effects" not in tables.coords


def test_equivalent_bits_are_stored_once_as_the_metric_variable():
    cube = built()["threshold"]
    assert "readout.equivalent_bits" not in cube.variables
    bits = cube["equivalent_bits"]
    assert bits.dims == ("threshold_v",) and bits.attrs == metric_attrs("equivalent_bits")
    np.testing.assert_array_equal(bits.values, np.log2(1.0 / cube["threshold_v"].values))


def test_models_and_folds_a_point_did_not_train_are_nan():
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"m": {"axes": {"training.models": [["ffnn"], ["cnn"]]}}}}
    )
    sweep = grid.sweeps[0]

    def make(point):
        model = point.scene.training.models[0].value
        return ResultEntry({model: np.full(4, 0.5)}, {}, metrics())

    cube = build(grid, sweep, entries(grid, sweep, make))
    assert list(cube["models"].values) == ['["ffnn"]', '["cnn"]']  # tables become JSON labels
    accuracy = cube["accuracy"]
    assert np.all(np.isnan(accuracy.isel(models=0).sel(model="cnn")))
    assert np.all(accuracy.isel(models=1).sel(model="cnn") == 0.5)


def test_correlations_along_a_noise_sweep():
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "noise": {
                    "correlate": True,
                    "axes": {"readout.effects.amplifier_noise.sigma_v": [0.0, 0.01, 0.02, 0.04]},
                }
            },
        }
    )
    sweep = grid.sweeps[0]
    ssnr = [math.inf, 30.0, 20.0, 10.0]
    accuracy = [0.9, 0.8, 0.6, 0.3]

    def make(point):
        i = point.index[0]
        return ResultEntry(
            {"ffnn": np.full(4, accuracy[i]), "cnn": np.full(4, accuracy[i])},
            {},
            metrics(ssnr_db=ssnr[i], ste_s2=1e-6 * i),
        )

    cube = build(grid, sweep, entries(grid, sweep, make))
    r = cube["correlation_r"]
    assert r.dims == ("model", "metric", "coefficient")
    assert r.sel(model="ffnn", metric="ssnr_db", coefficient="pearson") > 0.9
    assert r.sel(model="ffnn", metric="ste_s2", coefficient="spearman") == pytest.approx(-1.0)
    assert cube["correlation_n"].sel(model="ffnn", metric="ssnr_db") == 3  # +inf left out
    assert cube["correlation_n"].sel(model="ffnn", metric="ste_s2") == 4
    assert np.all(np.isfinite(cube["correlation_p"].values))
    assert "correlation_notes" not in cube.attrs


def test_a_correlation_that_cannot_be_computed_keeps_its_note():
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"n": {"correlate": True, "axes": {"seed": [1, 2, 3]}}}}
    )
    sweep = grid.sweeps[0]
    cube = build(
        grid,
        sweep,
        entries(grid, sweep, lambda p: ResultEntry({"ffnn": np.full(4, 0.5)}, {}, metrics())),
    )
    assert "ffnn/ssnr_db/pearson" in cube.attrs["correlation_notes"]


# ---------------------------------------------------------------------------------------------
# Units, names and attributes


def test_every_variable_and_coordinate_has_units_and_a_long_name():
    for name, cube in built().items():
        for var, variable in cube.variables.items():
            assert variable.attrs.get("units"), f"{name}: {var} has no units"
            assert variable.attrs.get("long_name"), f"{name}: {var} has no long_name"


def test_units_are_those_of_the_one_declaration():
    for cube in built().values():
        for var, variable in cube.variables.items():
            described = {k: variable.attrs[k] for k in ("units", "long_name")}
            if "field" in variable.attrs:
                assert described == field_attrs(variable.attrs["field"])
            elif var in CUBE_VARIABLES:
                assert described == CUBE_VARIABLES[var]
            elif var == "n_windows_used":
                assert described == RESULTS.record.variable(var).attrs()
            elif var in {f.name for f in dataclasses.fields(SpikeMetrics)}:
                assert described == metric_attrs(str(var))
            else:
                assert described == field_attrs(str(var))
    assert field_attrs("readout.threshold_v")["units"] == "V"
    assert metric_attrs("event_rate_hz")["units"] == "Hz"


def redeclare(monkeypatch, cls, name, **metadata):
    field = next(f for f in dataclasses.fields(cls) if f.name == name)
    if (
        "declared" in field.metadata
    ):  # a scene field: its declaration (pipeline.design.fields.param)
        metadata = {"declared": dataclasses.replace(field.metadata["declared"], **metadata)}
    monkeypatch.setattr(field, "metadata", types.MappingProxyType({**field.metadata, **metadata}))


def test_a_changed_declaration_changes_the_cube(monkeypatch):
    redeclare(monkeypatch, ReadoutSpec, "threshold_v", units="mV", long_name="the threshold")
    redeclare(monkeypatch, ReadoutSpec, "full_scale_v", units="kV")
    redeclare(monkeypatch, ThresholdMismatch, "floor_rel", long_name="floor")
    redeclare(monkeypatch, SpikeMetrics, "event_rate_hz", units="events/s")
    cubes = built()
    threshold = cubes["threshold"]
    assert threshold["threshold_v"].attrs["units"] == "mV"
    assert threshold["threshold_v"].attrs["long_name"] == "the threshold"
    assert threshold["readout.full_scale_v"].attrs["units"] == "kV"
    assert threshold["event_rate_hz"].attrs["units"] == "events/s"
    assert cubes["mismatch"]["readout.effects.threshold_mismatch.floor_rel"].attrs == {
        "units": "1",
        "long_name": "floor",
    }


def test_unknown_fields_are_refused():
    for field in ("readout.treshold_v", "readout.effects.wobble.sigma_v", "name"):
        with pytest.raises(KeyError):
            field_attrs(field)
    assert field_attrs("readout.effects.saturation")["units"] == "1"


def test_what_every_point_says_of_its_recordings_is_in_the_attributes():
    grid = golden.grid()
    sweep = next(s for s in grid.sweeps if s.name == "threshold")
    info = RecordingsInfo("synthetic", ("a", "b", "c"), 2000.0)
    records = {k: dataclasses.replace(e, recordings=info) for k, e in golden.entries(grid).items()}
    cube = build(grid, sweep, records)
    assert cube.attrs["n_classes"] == 3
    assert cube.attrs["class_names"] == ["a", "b", "c"]
    assert cube.attrs["sampling_rate_hz"] == 2000.0
    assert cube.attrs["dataset_name"] == "synthetic"
    # One point that does not say, or says otherwise: the fact is left out, not guessed.
    first, second = (p.key for p in keyed_points(grid, sweep))
    records[first] = dataclasses.replace(records[first], recordings=None)
    records[second] = dataclasses.replace(
        records[second], recordings=RecordingsInfo("synthetic", ("a", "b"), None)
    )
    cube = build(grid, sweep, records)
    assert not {"n_classes", "class_names", "sampling_rate_hz", "dataset_name"} & set(cube.attrs)
    records[first] = records[second]
    cube = build(grid, sweep, records)
    assert cube.attrs["n_classes"] == 2 and "sampling_rate_hz" not in cube.attrs


def test_provenance_attributes_are_plain_values():
    cube = built()["noise"]
    assert {"grid": "golden", "sweep": "noise", "mode": "zip", "seed": 0}.items() <= (
        cube.attrs.items()
    )
    assert not {"axes", "fixed", "base_scene", "grid_description"} & set(cube.attrs)
    assert all(isinstance(v, str | int | float | list) for v in cube.attrs.values())


# ---------------------------------------------------------------------------------------------
# The cube is assembled all at once; it is what a point-by-point assembly gives


MIXED = {
    "base": "smoke",
    "sweeps": {
        "mixed": {
            "axes": {
                "training.models": [["ffnn"], ["cnn", "ffnn"]],
                "training.repeats": [1, 2],
                "readout.threshold_v": [0.05, 0.1, 0.2],
            }
        }
    },
}
NAMES = [f"c{i % 3}/r{i}" for i in range(9)]
LABELS = [i % 3 for i in range(9)]


def mixed_entry(point) -> ResultEntry:
    """A point's result, drawn from a generator seeded by its index: some points without
    predictions, with fewer recordings, in another order, or missing a model's predictions."""
    i, r, t = point.index
    generator = np.random.default_rng([i, r, t])
    models = [m.value for m in point.scene.training.models]
    repeats = point.scene.training.repeats
    folds = {m: generator.random((repeats, 4)) for m in models}
    seconds = {"load": 0.5, "coding": 0.25} if t else {f"train_{m}": 1.0 + t for m in models}
    oof = None
    if (i, t) != (0, 2):
        order = list(range(9)) if t == 0 else list(range(6)) if t == 1 else list(range(8, -1, -1))
        names = [NAMES[j] for j in order]
        labels = np.array([LABELS[j] for j in order])
        right = generator.random((len(models), repeats, len(order))) < 0.7
        predicted = {
            m: np.where(right[k], labels, (labels + 1) % 3)
            for k, m in enumerate(models)
            if (i, r, t, m) != (1, 0, 1, "cnn")  # predictions of one model lost
        }
        test_fold = generator.integers(0, 4, (repeats, len(order)))
        oof = OutOfFold(tuple(names), labels, predicted, test_fold)
    # Paid seconds: stated by the points of one threshold only (the others' results are older).
    paid = None
    if i == 0:
        paid = {Charge.OWN: {"coding": 0.25 + t}, Charge.SHARED: {"load": 0.5 * r, "setup": 2.0}}
    return ResultEntry(
        folds, seconds, metrics(ssnr_db=10.0 * t, ste_s2=0.1 * i), None, oof, paid=paid
    )


def test_the_cube_is_what_a_point_by_point_assembly_gives():
    """Every variable of a sweep mixing one and two repeats, one and two models, points with and
    without predictions, on different recordings in different orders, against the cube written
    out point by point, model by model (intervals from ``accuracy_interval`` one at a time)."""
    from pipeline.results.stats import accuracy_interval

    grid = Grid.from_dict(MIXED)
    sweep = grid.sweeps[0]
    points = keyed_points(grid, sweep)
    cube = build(grid, sweep, {p.key: mixed_entry(p) for p in points})
    models = cube["model"].values.tolist()
    assert models == ["ffnn", "cnn"] and cube.sizes["repeat"] == 2
    order = [NAMES[j] for j in range(9)]  # the first point holds every recording, in order
    assert cube["recording"].values.tolist() == order
    assert cube["label"].values.tolist() == LABELS
    stages = cube["stage"].values.tolist()
    methods = set()
    for point in points:
        entry = mixed_entry(point)
        at = dict(zip(sweep.dims, point.index, strict=True))
        here = cube.isel(at)
        assert here["result_key"].item() == point.key
        assert here["ssnr_db"].item() == entry.metrics.ssnr_db
        expected_seconds = [entry.seconds.get(stage, np.nan) for stage in stages]
        np.testing.assert_array_equal(here["work_seconds"].values, expected_seconds)
        expected_paid = [
            [np.nan if entry.paid is None else entry.paid[c].get(stage, 0.0) for c in Charge]
            for stage in stages
        ]
        np.testing.assert_array_equal(
            here["seconds"].transpose("stage", "charge").values, expected_paid
        )
        oof = entry.out_of_fold
        test_fold = np.full((2, 9), -1)
        if oof is not None:
            columns = [order.index(name) for name in oof.recording_names]
            test_fold[: oof.test_fold.shape[0], columns] = oof.test_fold
        np.testing.assert_array_equal(here["test_fold"].values, test_fold)
        for m, model in enumerate(models):
            one = here.isel(model=m)
            accuracy = np.full((2, 4), np.nan)
            if model in entry.fold_accuracy:
                folds = entry.fold_accuracy[model]
                accuracy[: folds.shape[0]] = folds
            np.testing.assert_array_equal(one["accuracy"].values, accuracy)
            predicted = np.full((2, 9), -1)
            if oof is not None and model in oof.predicted:
                predicted[: oof.test_fold.shape[0], columns] = oof.predicted[model]
            np.testing.assert_array_equal(one["predicted"].values, predicted)
            correct = np.where(predicted >= 0, predicted == np.array(LABELS), -1)
            np.testing.assert_array_equal(one["correct"].values, correct)
            ran = (correct >= 0).any(axis=1)
            held = (correct[ran] >= 0).all(axis=0)
            if ran.any() and held.any():
                interval = accuracy_interval(
                    correct[ran][:, held] == 1,
                    np.array(LABELS)[held],
                    rng=interval_generator(point.key, model),
                )
                methods.add(interval.method)
                assert one["accuracy_mean"].item() == interval.estimate
                low, high = one["accuracy_low"].item(), one["accuracy_high"].item()
                assert (low, high) == pytest.approx((interval.low, interval.high), abs=1e-12)
            else:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", RuntimeWarning)
                    assert np.array_equal(
                        one["accuracy_mean"].item(), np.nanmean(accuracy), equal_nan=True
                    )
                assert np.isnan(one["accuracy_low"].item()) and np.isnan(one["accuracy_high"])
        # Every scene field, by its dotted name or its axis, has the point's value there.
        for field, value in flatten(point.scene.to_dict()).items():
            name = field_coordinate(cube, field)
            if name is not None and field != "name":
                table = isinstance(value, list | dict)
                expected = json.dumps(value, sort_keys=True) if table else value
                assert here[name].item() == expected, field
    assert len(methods) == 2  # a Wilson interval and a bootstrap both met
    assert cube["accuracy_low"].attrs["interval"] == "; ".join(sorted(methods))
    assert cube["correct"].dtype == np.int8 and cube["test_fold"].dtype == np.int16
    assert cube["repeats"].attrs["field"] == "training.repeats"
    assert "training.repeats" not in cube.coords
    assert cube["array.rows"].dims == ()


def test_a_sweep_of_the_grid_takes_the_points_the_grid_built():
    grid = Grid.from_dict({"base": "smoke", "sweeps": {**golden.GRID["sweeps"], **MIXED["sweeps"]}})
    start = 0
    for sweep in grid.sweeps:
        expected = sweep_points(grid.base, sweep)
        points = grid.points_of(sweep)
        assert points == expected
        # The very points the grid built once, not new ones.
        assert all(a is b for a, b in zip(points, grid.points()[start:], strict=False))
        start += len(points)
    # An equal sweep that is not one of the grid's own objects is expanded from its values.
    own = grid.sweeps[2]
    other = dataclasses.replace(own)
    points = grid.points_of(other)
    assert points == sweep_points(grid.base, other)
    assert not any(a is b for a, b in zip(points, grid.points()[4:], strict=False))


def test_a_cube_variable_declared_by_two_features_is_refused():
    from pipeline.results.cube import _gathered

    assert list(_gathered({"a": {}}, {"b": {}})) == ["a", "b"]
    with pytest.raises(ValueError, match=r"declared twice: \['a'\]"):
        _gathered({"a": {}}, {"a": {}, "b": {}})
