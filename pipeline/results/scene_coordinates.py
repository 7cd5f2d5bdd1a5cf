"""The cube's coordinates from the points' scenes: each swept axis, and every other scene field.

* One per swept axis, named by its dimension (``threshold_v``), attribute ``field`` its dotted
  scene field, its values as the points' scenes read them (:func:`axis_coordinates`); the other
  axes of a zipped sweep lie along the first one's dimension.
* Every other scene field by its dotted name (:func:`scene_coordinates`): a scalar where every
  point has the same value, otherwise along the dimensions it varies with. Lists and tables are
  canonical JSON strings; a field that some point does not have (a swept table's) is left to
  the axis's coordinate.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from pipeline.design import fields
from pipeline.design.grid import Sweep
from pipeline.design.scene import canonical_parts, part_left_out
from pipeline.run.grid_keys import KeyedPoint

__all__ = ["axis_coordinates", "scene_coordinates"]


def _coordinate(values: Sequence[Any]) -> np.ndarray:
    """Numbers stay numbers; tables (e.g. a whole effects mapping) become canonical JSON."""
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        return np.asarray(values)
    if all(isinstance(v, str | bool) for v in values):
        return np.asarray(values)
    return np.asarray([json.dumps(v, sort_keys=True) for v in values])


def axis_coordinates(sweep: Sweep, points: list[KeyedPoint]) -> dict[str, Any]:
    """The coordinate of each swept axis, named by its dimension (attribute ``field``), along
    the first dimension of a zipped sweep: each value as the points' parsed scenes hold it (as
    :meth:`pipeline.design.scene.Scene.to_dict` writes it), read once per value."""
    dims = sweep.dims
    coords: dict[str, Any] = {}
    for position, axis in enumerate(sweep.axes):
        along = 0 if sweep.mode == "zip" else position
        # The first point (C order) at each index along the axis's dimension.
        first: dict[int, KeyedPoint] = {}
        for point in points:
            first.setdefault(point.index[along], point)
        values = [
            fields.plain(fields.get(first[i].scene, axis.field)) for i in range(len(axis.values))
        ]
        coords[axis.dim] = (dims[along], _coordinate(values), {"field": axis.field})
    return coords


def scene_coordinates(
    points: list[KeyedPoint], flat: np.ndarray, sweep: Sweep
) -> dict[str, xr.Variable]:
    """Every scene field that every point has, along the dims it varies with.

    ``flat`` gives each point's position in the flattened sweep dimensions. A field's values are
    read once per distinct object of the scene part holding it (the points of a sweep share
    their parts).
    """
    size = int(np.prod(sweep.shape))
    tops = [
        top
        for top in canonical_parts(type(points[0].scene))
        if not all(part_left_out(top, getattr(p.scene, top)) for p in points)
    ]
    # Per top-level field: each point's part as an index into that part's distinct objects,
    # and each distinct object's flattened fields.
    owner = {top: np.empty(size, dtype=np.int64) for top in tops}
    distinct: dict[str, dict[int, int]] = {top: {} for top in tops}
    flattened: dict[str, list[dict[str, Any]]] = {top: [] for top in tops}
    for i, point in zip(flat.tolist(), points, strict=True):
        scene = point.scene
        new = [top for top in tops if id(getattr(scene, top)) not in distinct[top]]
        if new:
            data = scene.to_dict()
            for top in new:
                distinct[top][id(getattr(scene, top))] = len(flattened[top])
                flattened[top].append(fields.flatten({top: data[top]} if top in data else {}))
        for top in tops:
            owner[top][i] = distinct[top][id(getattr(scene, top))]
    # A field with its owners, as above.
    columns: dict[str, tuple[np.ndarray, list[dict[str, Any]]]] = {}
    first = points[0].scene
    for top in tops:
        for field in flattened[top][distinct[top][id(getattr(first, top))]]:
            columns[field] = (owner[top], flattened[top])
    coords = {}
    for field, (owners, values) in columns.items():
        if not all(field in found for found in values):
            continue  # some points do not have it: a swept table's coordinate describes them
        coords[field] = _along_varied_owned(
            owners.reshape(sweep.shape), [found[field] for found in values], sweep.dims
        )
    return coords


def _along_varied_owned(
    owners: np.ndarray, values: list[Any], dims: tuple[str, ...]
) -> xr.Variable:
    """:func:`_along_varied` of ``values[owners]`` (owners: int, sweep shape), comparing the
    distinct ``values`` once rather than every point's."""
    codes: dict[Any, int] = {}
    try:
        equal = np.array([codes.setdefault(label, len(codes)) for label in map(_label, values)])
        comparable = all(label == label for label in codes)
    except TypeError:  # an unhashable value: compared point by point instead
        comparable = False
    if not comparable:  # a value unequal to itself (NaN) differs even from itself
        gathered = np.empty(owners.shape, dtype=object)
        for index, i in np.ndenumerate(owners):
            gathered[index] = values[i]
        return _along_varied(gathered, dims)
    labels = equal[owners]
    varied = [k for k in range(labels.ndim) if np.any(labels != np.take(labels, [0], axis=k))]
    if not varied:
        return xr.Variable((), _coordinate([values[owners.flat[0]]]).reshape(()))
    kept = owners[tuple(slice(None) if k in varied else 0 for k in range(owners.ndim))]
    data = _coordinate([values[i] for i in kept.ravel().tolist()]).reshape(kept.shape)
    return xr.Variable(tuple(dims[k] for k in varied), data)


def _along_varied(values: np.ndarray, dims: tuple[str, ...]) -> xr.Variable:
    """A coordinate over only the dims along which ``values`` (object, sweep shape) change."""
    labels = np.vectorize(_label, otypes=[object])(values)
    varied = [k for k in range(labels.ndim) if np.any(labels != np.take(labels, [0], axis=k))]
    if not varied:
        return xr.Variable((), _coordinate([values.flat[0]]).reshape(()))
    kept = values[tuple(slice(None) if k in varied else 0 for k in range(values.ndim))]
    data = _coordinate(kept.ravel().tolist()).reshape(kept.shape)
    return xr.Variable(tuple(dims[k] for k in varied), data)


def _label(value: Any) -> Any:
    """A value comparable with ``==``: tables and lists as canonical JSON."""
    return json.dumps(value, sort_keys=True) if isinstance(value, list | dict) else value
