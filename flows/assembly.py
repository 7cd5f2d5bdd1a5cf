"""Assembling a sweep's cubes from the store once its points are done, and their best points.

A cube is rebuilt from the plan's cached results and the results computed since; one equal to
the cube already stored (a re-run with nothing new) is left as it is, not written again.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from flows.planning import SweepPlan
from pipeline.run.stages import RESULTS
from storage import StoreError, SweepStore


def assemble_cube(plan: SweepPlan, name: str) -> xr.Dataset:
    """Build the cube of the sweep ``name`` from the store, write it and return it.

    The points cached at planning come from the plan; the others are read from the store, each
    batch once. A stored cube identical to the new one (values, coordinates and attributes) is
    kept instead of being written again.

    Raises
    ------
    StoreError
        A point of the sweep has no result in the store (it failed, or was never computed).
    CorruptEntryError
        A result's batch fails its checksum.
    """
    from pipeline.results.cube import build_cube

    store = SweepStore.open(plan.root)
    spec = next(s for s in plan.grid.sweeps if s.name == name)
    keys = plan.sweep_keys[name]
    computed = [key for key in keys if key not in plan.records]
    read = store.read_many(RESULTS.record, computed, discard_corrupt=False)
    missing = [key for key in computed if key not in read]
    if missing:
        raise StoreError(
            f"sweep {name!r}: {len(missing)} point(s) have no result in {plan.root} "
            f"(first: {missing[0]})"
        )
    records = {key: plan.records[key] if key in plan.records else read[key] for key in keys}
    cube = build_cube(plan.grid, spec, records)
    if not _stored_as(store, name, cube):
        store.write_cube(name, cube)
    return cube


def _stored_as(store: SweepStore, name: str, cube: xr.Dataset) -> bool:
    """Whether the store's cube ``name`` is identical to ``cube`` (a missing or corrupt one is
    not)."""
    try:
        return store.read_cube(name).identical(cube)
    except StoreError:
        return False


def assemble_cubes(plan: SweepPlan) -> dict[str, str]:
    """Build every sweep's cube from the store and write it; return where each cube is."""
    for spec in plan.grid.sweeps:
        assemble_cube(plan, spec.name)
    return {spec.name: cube_location(plan, spec.name) for spec in plan.grid.sweeps}


def cube_location(plan: SweepPlan, name: str) -> str:
    return str(Path(plan.root) / "store.zarr" / "cubes" / name)


def best_points(cube: xr.Dataset) -> list[dict[str, Any]]:
    """Per model, the best accuracy (``accuracy_mean``) of a cube and the swept values it is at.

    Returns
    -------
    list of dict
        ``{"model", "accuracy", "at"}`` per model, ``at`` mapping each swept dimension to its
        value at the best point (the first of equals, in the cube's order).
    """
    mean = cube["accuracy_mean"]
    rows = []
    for model in cube["model"].values:
        per_model = mean.sel(model=model)
        flat = int(np.nanargmax(per_model.values)) if per_model.size else 0
        index = np.unravel_index(flat, per_model.shape)
        at = {
            dim: per_model[dim].values[i].item()
            for dim, i in zip(per_model.dims, index, strict=True)
        }
        rows.append({"model": str(model), "accuracy": float(per_model.values[index]), "at": at})
    return rows
