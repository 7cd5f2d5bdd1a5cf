"""``storage.open_tree``: a run root's cubes as one DataTree, a node per sweep."""

import numpy as np
import pytest
import xarray as xr

from storage import StoreError, SweepStore, open_results, open_tree


def small_cube(scale: float) -> xr.Dataset:
    rng = np.random.default_rng(0)
    accuracy = scale * rng.random((2, 3))
    return xr.Dataset(
        {"accuracy": (("threshold_v", "fold"), accuracy, {"units": "1"})},
        coords={"threshold_v": ("threshold_v", [0.05, 0.09], {"units": "V"})},
        attrs={"sweep": "x"},
    )


def test_every_cube_is_a_child_node_identical_to_open_results(tmp_path):
    store = SweepStore.open_or_create(tmp_path / "run")
    store.write_cube("threshold", small_cube(1.0))
    store.write_cube("window", small_cube(0.5))
    tree = open_tree(store.root)
    cubes = open_results(store.root)
    assert sorted(tree.children) == ["threshold", "window"]
    assert not tree.dataset.data_vars and tree.attrs["root"] == str(store.root)
    for name, cube in cubes.items():
        xr.testing.assert_identical(tree[name].to_dataset(), cube)


def test_a_store_without_cubes_is_an_empty_tree(tmp_path):
    store = SweepStore.open_or_create(tmp_path / "run")
    assert dict(open_tree(store.root).children) == {}


def test_a_folder_that_is_no_store_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(StoreError):
        open_tree(tmp_path)
