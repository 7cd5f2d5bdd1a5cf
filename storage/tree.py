"""A run root's result cubes as one ``xarray.DataTree``: one child node per sweep, and one per
cube of each search (``design.trials``, ``design.front``).

The tree holds the same cubes as :func:`storage.store.open_results` (loaded into memory), so a
notebook can browse a whole run at once (``tree["threshold"]``, ``tree.children``) and apply
one operation to every cube (``tree.map_over_datasets``).
"""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from storage.store import SweepStore, open_results


def open_tree(root: str | Path) -> xr.DataTree:
    """Every result cube of the run root ``root`` as a child of one tree, named as
    :func:`storage.store.open_results` names it.

    The root node holds no data; its attribute ``root`` is the run root's path. Each child is
    the cube of one named sweep or one cube of a search, in the store's order, with its
    dimensions, coordinates and attributes unchanged.

    Raises
    ------
    StoreError
        ``root`` is not a sweep store.
    CorruptEntryError
        A cube fails its checksum or cannot be read.
    """
    store = SweepStore.open(root)
    cubes = open_results(store.root)
    tree = xr.DataTree.from_dict({f"/{name}": cube for name, cube in cubes.items()})
    tree.attrs["root"] = str(store.root)
    return tree
