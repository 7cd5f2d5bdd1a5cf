"""Result cubes in the store: every coordinate and attribute survives Zarr, versions recorded."""

import dataclasses
import platform
from importlib import metadata

import xarray as xr

from pipeline.results.cube import build_cube
from pipeline.run.records import RecordingsInfo
from storage.store import SweepStore
from tests import golden_cubes as golden


def test_cube_records_dependency_versions_and_round_trips(tmp_path):
    grid = golden.grid()
    info = RecordingsInfo("synthetic", ("fine", "coarse"), 2000.0)
    records = {
        key: dataclasses.replace(entry, recordings=info)
        for key, entry in golden.entries(grid).items()
    }
    store = SweepStore.open_or_create(tmp_path / "run")
    for sweep in grid.sweeps:
        cube = build_cube(grid, sweep, records)
        store.write_cube(sweep.name, cube)
        # Scalar and dotted coordinates, units, lists in attributes: all as they were built.
        xr.testing.assert_identical(store.read_cube(sweep.name), cube)
    expected = {
        "version_python": platform.python_version(),
        "version_torch": metadata.version("torch"),
        "version_numpy": metadata.version("numpy"),
        "version_numba": metadata.version("numba"),
        "version_scikit_learn": metadata.version("scikit-learn"),
        "version_xarray": metadata.version("xarray"),
        "version_zarr": metadata.version("zarr"),
        "package_version": metadata.version("eskin-sweep"),
        "n_classes": 2,
        "class_names": ["fine", "coarse"],
    }
    assert {name: cube.attrs.get(name) for name in expected} == expected
