"""Result cubes in the store: every coordinate and attribute survives Zarr, versions recorded."""

import dataclasses
import platform
from importlib import metadata

import numpy as np
import pytest
import xarray as xr

from pipeline.results.cube import build_cube
from pipeline.run.entries import RecordingsInfo
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


def test_a_cube_written_with_a_source_tells_whether_it_is_intact_and_from_that_source(tmp_path):
    store = SweepStore.open_or_create(tmp_path / "run")
    cube = xr.Dataset({"a": ("x", np.arange(3.0))}, coords={"x": [1, 2, 3]}, attrs={"t": "x"})
    note = {"best": [{"model": "ffnn", "accuracy": 0.5}]}
    store.write_cube("c", cube)
    assert store.current_note("c", "s1") is None  # written without a source
    store.write_cube("c", cube, source="s1", note=note)
    assert store.current_note("c", "s1") == note
    assert store.current_note("c", "s2") is None
    assert store.current_note("missing", "s1") is None
    # What the writer keeps for itself is not part of the cube.
    xr.testing.assert_identical(store.read_cube("c"), cube)
    xr.testing.assert_identical(store.read_cube("c", lazy=True).compute(), cube)
    folder = store.path / "cubes" / "c"
    chunk = next(p for p in (folder / "a").rglob("*") if p.is_file() and p.name != "zarr.json")
    original = chunk.read_bytes()
    chunk.write_bytes(original[:-1] + bytes([original[-1] ^ 1]))
    assert store.current_note("c", "s1") is None
    chunk.write_bytes(original)
    assert store.current_note("c", "s1") == note
    (folder / "a" / "stray").write_bytes(b"")
    assert store.current_note("c", "s1") is None
    (folder / "a" / "stray").unlink()
    (folder / "x" / "zarr.json").unlink()
    assert store.current_note("c", "s1") is None


@pytest.mark.parametrize("name", ["eskin_sha256", "eskin_source", "eskin_note", "eskin_files"])
def test_a_cube_may_not_use_the_stores_own_attributes(tmp_path, name):
    store = SweepStore.open_or_create(tmp_path / "run")
    with pytest.raises(ValueError, match=f"attribute '{name}' is reserved"):
        store.write_cube("c", xr.Dataset(attrs={name: "mine"}))
