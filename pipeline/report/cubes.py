"""Reading result cubes (:mod:`pipeline.results.cube`): swept fields, values, point keys.

A cube's *sweep dimensions* are those of ``accuracy_mean`` but ``model`` (one for a 1-D or zipped
sweep, two for a product of two axes, ...). Which panel a cube feeds is decided by the scene
fields its one dimension sweeps, read from the ``field`` attribute of its coordinates, never by
its name; a cube that also sweeps the chips' deployment feeds it too, one curve per deployment.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from pipeline.report.panels import (
    COLS,
    DATASET_KIND,
    DEPLOYMENT,
    MISMATCH_SIGMA_REL,
    N_WINDOWS,
    PANEL_FIELDS,
    ROWS,
    THRESHOLD_V,
    WINDOW_S,
    Panel,
)
from pipeline.results.cube import field_coordinate
from pipeline.results.variables import ACCURACY_MEAN, CORRELATION_R, MODEL_DIM, RESULT_KEY


def swept_fields(cube: xr.Dataset) -> frozenset[str]:
    """The scene fields a cube sweeps (the ``field`` attribute of its axes' coordinates)."""
    return frozenset(str(c.attrs["field"]) for c in cube.coords.values() if "field" in c.attrs)


def sweep_dims(cube: xr.Dataset) -> tuple[str, ...]:
    """The cube's sweep dimensions, in order (``accuracy_mean``'s dimensions but ``model``)."""
    return tuple(str(d) for d in cube[ACCURACY_MEAN].dims if d != MODEL_DIM)


def is_one_dimensional(cube: xr.Dataset) -> bool:
    """Whether ``cube`` holds accuracy along exactly one sweep dimension (a curve's cube)."""
    return ACCURACY_MEAN in cube and len(sweep_dims(cube)) == 1


def axis_coordinates(cube: xr.Dataset, dim: str) -> list[str]:
    """Names of the swept-axis coordinates along ``dim`` (the dimension's own first)."""
    names = [dim] if "field" in cube[dim].attrs else []
    return names + [
        str(name)
        for name, c in cube.coords.items()
        if name != dim and "field" in c.attrs and c.dims == (dim,)
    ]


def sweeps_for(panel: Panel, cubes: Mapping[str, xr.Dataset]) -> list[str]:
    """Names of the cubes that feed ``panel``, in the mapping's order."""
    if panel is Panel.SPIKE_METRICS:
        return [name for name, cube in cubes.items() if CORRELATION_R in cube]
    wanted = PANEL_FIELDS[panel]
    return [
        name
        for name, cube in cubes.items()
        if (is_one_dimensional(cube) and set(swept_fields(cube)) in wanted)
        or _by_deployment(cube, wanted)
    ]


def _by_deployment(cube: xr.Dataset, wanted: tuple[set[str], ...]) -> bool:
    """A two-dimensional cube of a panel's field and the chips' deployment (one curve per
    deployment, :mod:`pipeline.report.chip_population`)."""
    fields = set(swept_fields(cube))
    return (
        ACCURACY_MEAN in cube
        and len(sweep_dims(cube)) == 2
        and DEPLOYMENT in fields
        and fields - {DEPLOYMENT} in wanted
    )


def field_values(cube: xr.Dataset, field: str) -> np.ndarray | None:
    """The value of scene ``field`` at every point of a cube, shape (sweep shape); None if the
    cube has no coordinate of it (a field left unset).

    The cube's coordinate of ``field`` (:func:`pipeline.results.cube.field_coordinate`: a swept
    axis's, or the one named by the dotted field) holds it: along the dimensions where the field
    varies, a scalar where every point has the same value.
    """
    name = field_coordinate(cube, field)
    if name is None:
        return None
    keys = cube[RESULT_KEY]
    return cube[name].broadcast_like(keys).transpose(*keys.dims).values


def base_value(cube: xr.Dataset, field: str) -> Any:
    """Scene ``field`` where every point of the cube has the same value, as a Python scalar.

    Raises
    ------
    KeyError
        The cube has no coordinate ``field``.
    ValueError
        The field varies along the cube.
    """
    name = field_coordinate(cube, field)
    if name is None:
        raise KeyError(f"the cube has no coordinate of {field}")
    value = cube[name]
    if value.ndim:
        raise ValueError(f"{field} varies along the cube")
    return value.item()


def panel_x(panel: Panel, cube: xr.Dataset) -> np.ndarray:
    """The abscissa of ``panel`` at every point of a one-dimensional cube, float64 (n,)."""

    def number(field: str) -> np.ndarray:
        return np.asarray(field_values(cube, field), dtype=np.float64)

    if panel is Panel.THRESHOLD:
        return number(THRESHOLD_V)
    if panel is Panel.WINDOW:
        return number(WINDOW_S)
    if panel is Panel.TAXELS:
        return number(ROWS) * number(COLS)
    if panel is Panel.MISMATCH:
        return number(MISMATCH_SIGMA_REL)
    if panel is Panel.OBSERVATION:
        return number(N_WINDOWS) * number(WINDOW_S)
    raise ValueError(f"panel {panel} has no single abscissa")


def point_keys(cube: xr.Dataset) -> list[str]:
    """Result cache keys (the cube's ``result_key``) of its points in C order over its swept
    dimensions; points shared by two sweeps have one key."""
    return [str(k) for k in cube[RESULT_KEY].transpose(*sweep_dims(cube)).values.ravel()]


def dataset_kind(cubes: Mapping[str, xr.Dataset]) -> str:
    """The recordings' kinds (``dataset.kind``) of all cubes, sorted and comma-separated."""
    kinds: set[str] = set()
    for cube in cubes.values():
        values = field_values(cube, DATASET_KIND)
        if values is not None:
            kinds.update(str(kind) for kind in np.ravel(values))
    return ", ".join(sorted(kinds)) or "unknown"


def sampling_rate_hz(cubes: Mapping[str, xr.Dataset]) -> float | None:
    """The recordings' sampling rate (Hz) the cubes state (the first that does), or None."""
    for cube in cubes.values():
        if "sampling_rate_hz" in cube.attrs:
            return float(cube.attrs["sampling_rate_hz"])
    return None


def n_classes(cubes: Mapping[str, xr.Dataset]) -> int | None:
    """The number of classes the cubes state (the first that does), or None; chance is 1/n."""
    for cube in cubes.values():
        if "n_classes" in cube.attrs and int(cube.attrs["n_classes"]) > 0:
            return int(cube.attrs["n_classes"])
    return None


def describe_coordinate(cube: xr.Dataset, name: str) -> tuple[str, str]:
    """``(long_name, units)`` of a coordinate from its attributes; units "" when dimensionless."""
    attrs = cube[name].attrs
    units = str(attrs.get("units", ""))
    return str(attrs.get("long_name", attrs.get("field", name))), "" if units == "1" else units
