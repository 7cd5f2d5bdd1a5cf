"""Result cubes from result entries: dimensions, coordinates, units, gaps, correlations."""

import json
import math
import platform
from importlib import metadata

import numpy as np
import pytest
import xarray as xr

from pipeline.grid import Grid, sweep_points
from pipeline.metrics import SpikeMetrics
from storage.cubes import build_cube
from storage.store import ResultEntry, SweepStore


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
    return {p.key: make(p) for p in sweep_points(grid.base, sweep)}


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

    cube = build_cube(grid, sweep, entries(grid, sweep, make))
    assert cube["accuracy"].dims == ("threshold_v", "window_s", "model", "fold")
    assert cube["accuracy"].shape == (2, 3, 2, 4)
    assert cube["accuracy"].sel(threshold_v=0.1, window_s=0.3, model="ffnn").values[0] == 0.1 + 0.02
    assert cube["accuracy"].sel(model="cnn").max() == pytest.approx(0.06)
    assert cube["window_s"].attrs == {"field": "coding.window_s", "units": "s"}
    assert cube["accuracy"].attrs["units"].startswith("1")
    assert cube["ssnr_db"].attrs["units"] == "dB"
    assert np.all(np.isinf(cube["ssnr_db"].values))
    assert cube["seconds"].sel(stage="train_ffnn").values.tolist() == [[1.0] * 3] * 2
    assert np.all(np.isnan(cube["seconds"].sel(stage="coding").values))  # not measured
    assert json.loads(cube.attrs["axes"]) == {
        "readout.threshold_v": "threshold_v",
        "coding.window_s": "window_s",
    }
    assert "correlation_r" not in cube


def test_models_and_folds_a_point_did_not_train_are_nan():
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"m": {"axes": {"training.models": [["ffnn"], ["cnn"]]}}}}
    )
    sweep = grid.sweeps[0]

    def make(point):
        model = point.scene.training.models[0].value
        return ResultEntry({model: np.full(4, 0.5)}, {}, metrics())

    cube = build_cube(grid, sweep, entries(grid, sweep, make))
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

    cube = build_cube(grid, sweep, entries(grid, sweep, make))
    r = cube["correlation_r"]
    assert r.dims == ("model", "metric", "coefficient")
    assert r.sel(model="ffnn", metric="ssnr_db", coefficient="pearson") > 0.9
    assert r.sel(model="ffnn", metric="ste_s2", coefficient="spearman") == pytest.approx(-1.0)
    assert cube["correlation_n"].sel(model="ffnn", metric="ssnr_db") == 3  # +inf left out
    assert cube["correlation_n"].sel(model="ffnn", metric="ste_s2") == 4
    assert np.all(np.isfinite(cube["correlation_p"].values))


def test_cube_records_dependency_versions_and_round_trips(tmp_path):
    grid = Grid.from_dict(
        {"base": "smoke", "sweeps": {"t": {"axes": {"readout.threshold_v": [0.05, 0.1]}}}}
    )
    sweep = grid.sweeps[0]
    cube = build_cube(grid, sweep, entries(grid, sweep, lambda p: ResultEntry({}, {}, metrics())))
    expected = {
        "version_python": platform.python_version(),
        "version_torch": metadata.version("torch"),
        "version_numpy": metadata.version("numpy"),
        "version_numba": metadata.version("numba"),
        "version_scikit_learn": metadata.version("scikit-learn"),
        "version_xarray": metadata.version("xarray"),
        "version_zarr": metadata.version("zarr"),
        "package_version": metadata.version("eskin-sweep"),
    }
    assert {name: cube.attrs.get(name) for name in expected} == expected
    store = SweepStore.open_or_create(tmp_path / "run")
    store.write_cube("t", cube)
    xr.testing.assert_identical(store.read_cube("t"), cube)  # plain strings survive Zarr
