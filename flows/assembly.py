"""Assembling a sweep's cubes from the store once its points are done, and their best points.

A cube is rebuilt from the plan's cached results and the results computed since; one equal to
the cube already stored (a re-run with nothing new) is left as it is, not written again.

A cube is stored with its summary (:func:`summarize`: its swept dimensions and best points)
and the digest of what it was built from (:func:`flows.planning.cube_source`). A cube that
planning finds current is kept and its summary taken as stored (:func:`assemble`); a damaged
or outdated cube is built again.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from flows.planning import SweepPlan, cube_source
from pipeline.results.variables import ACCURACY_MEAN, MODEL_DIM
from pipeline.results.yields import ACCURACY_CHIP_MEAN
from pipeline.run.stages import RESULTS
from storage import StoreError, SweepStore


def assemble(plan: SweepPlan, name: str) -> dict[str, Any]:
    """Make the stored cube of sweep ``name`` current; return its summary (:func:`summarize`).

    A cube that planning found current (:attr:`flows.planning.SweepPlan.current`) is kept and
    its stored summary returned without reading it; any other is built (:func:`assemble_cube`).

    Raises
    ------
    As :func:`assemble_cube`.
    """
    if name in plan.current:
        return plan.current[name]
    return summarize(assemble_cube(plan, name))


def assemble_cube(plan: SweepPlan, name: str) -> xr.Dataset:
    """Build the cube of the sweep ``name`` from the store, write it and return it.

    The points cached at planning come from the plan; the others are read from the store, each
    batch once. A stored cube identical to the new one (values, coordinates and attributes),
    stored with its source and summary, is kept instead of being written again.

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
    source = cube_source(plan.grid, name, keys, store.entry_batches(RESULTS.record))
    note = summarize(cube)
    current = source is not None and store.current_note(name, source) == note
    if not (current and _stored_as(store, name, cube)):
        store.write_cube(name, cube, source=source, note=note)
    return cube


def _stored_as(store: SweepStore, name: str, cube: xr.Dataset) -> bool:
    """Whether the store's cube ``name`` is identical to ``cube`` (a missing or corrupt one is
    not)."""
    try:
        return store.read_cube(name).identical(cube)
    except StoreError:
        return False


def assemble_cubes(plan: SweepPlan) -> dict[str, str]:
    """Make every sweep's stored cube current (:func:`assemble`); return where each cube is."""
    for spec in plan.grid.sweeps:
        assemble(plan, spec.name)
    return {spec.name: cube_location(plan, spec.name) for spec in plan.grid.sweeps}


def cube_location(plan: SweepPlan, name: str) -> str:
    """Where the plan's store keeps the cube of sweep ``name``: a folder, or the URL of its
    prefix on an object root (:meth:`storage.store.SweepStore.cube_location`)."""
    return SweepStore(plan.root).cube_location(name)


def summarize(cube: xr.Dataset) -> dict[str, Any]:
    """What a sweep's summary states of its cube, in plain JSON values.

    Returns
    -------
    dict
        ``{"dims": {dim: size}, "best": best_points(cube)}``, ``dims`` the swept dimensions
        of ``accuracy_mean`` in order.
    """
    mean = cube[ACCURACY_MEAN]
    dims = {str(dim): int(cube.sizes[dim]) for dim in mean.dims if dim != MODEL_DIM}
    return {"dims": dims, "best": best_points(cube)}


def best_points(cube: xr.Dataset) -> list[dict[str, Any]]:
    """Per model, the best accuracy (``accuracy_mean``) of a cube and the swept values it is at
    (a cube of chips: the best design by its mean over the chips, ``accuracy_chip_mean``).

    Returns
    -------
    list of dict
        ``{"model", "accuracy", "at"}`` per model, ``at`` mapping each swept dimension to its
        value at the best point (the first of equals, in the cube's order); a model with no
        finite accuracy has no row.
    """
    mean = cube[ACCURACY_CHIP_MEAN if ACCURACY_CHIP_MEAN in cube else ACCURACY_MEAN]
    rows = []
    for model in cube[MODEL_DIM].values:
        per_model = mean.sel({MODEL_DIM: model})
        if not np.isfinite(per_model.values).any():
            continue
        flat = int(np.nanargmax(per_model.values))
        index = np.unravel_index(flat, per_model.shape)
        at = {
            dim: per_model[dim].values[i].item()
            for dim, i in zip(per_model.dims, index, strict=True)
        }
        rows.append({"model": str(model), "accuracy": float(per_model.values[index]), "at": at})
    return rows
