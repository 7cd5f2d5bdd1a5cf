"""Pictures for any grid: a curve along any one-dimensional sweep, a heat map of a 2-D sweep.

A one-dimensional cube (one axis, or several zipped axes) whose field the paper's figures do not
plot gets a :class:`SweepPlot`: accuracy (``accuracy_mean`` with its 95 % interval) against the
values of its first axis, titled and labelled from the coordinate's ``long_name``, dotted field and
``units``. Values that are not numbers (an effects table, a polarity) are placed at 0, 1, ... and
labelled. A cube with two sweep dimensions gets a :class:`Heatmap`: ``accuracy_mean`` per model
over the two axes' values. Cubes of three or more dimensions get no picture (the report says so).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.report.cubes import axis_coordinates, describe_coordinate, sweep_dims
from pipeline.report.curves import Curve, sweep_curves
from pipeline.report.text import label
from pipeline.results.variables import ACCURACY_MEAN, MODEL_DIM


@dataclass(frozen=True)
class SweepPlot:
    """Accuracy along one one-dimensional sweep, one curve per model.

    ``ticks`` names the positions 0, 1, ... of a field whose values are not numbers (None for
    numbers); ``log`` draws the abscissa logarithmically (positive values spanning a decade).
    """

    sweep: str
    title: str
    xlabel: str
    ticks: tuple[str, ...] | None
    log: bool
    curves: tuple[Curve, ...]

    @property
    def stem(self) -> str:
        """File stem of the figure, ``"sweep_<sweep name>"`` (:func:`safe_stem`)."""
        return "sweep_" + safe_stem(self.sweep)


@dataclass(frozen=True)
class Heatmap:
    """``accuracy`` float64 (models, rows, cols) of a two-dimensional sweep (NaN: not trained).

    ``rows``/``cols`` hold the values of the first and second sweep dimension as text.
    """

    sweep: str
    title: str
    row_label: str
    col_label: str
    rows: tuple[str, ...]
    cols: tuple[str, ...]
    models: tuple[str, ...]
    accuracy: np.ndarray

    @property
    def stem(self) -> str:
        """File stem of the figure, ``"heatmap_<sweep name>"`` (:func:`safe_stem`)."""
        return "heatmap_" + safe_stem(self.sweep)


def safe_stem(name: str) -> str:
    """A cube's name as a file stem: anything but letters, digits, ``_``, ``-`` and ``.`` becomes
    ``_``; the ``.`` of a search's cube (``design.front``) stays, so that it never shares a stem
    with a sweep (``design_front``)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def axis_label(cube: xr.Dataset, name: str) -> str:
    """``long_name (dotted field, units)`` of a swept axis's coordinate."""
    long_name, units = describe_coordinate(cube, name)
    field = str(cube[name].attrs.get("field", name))
    return f"{long_name} ({field}{', ' + units if units else ''})"


def sweep_plot(name: str, cube: xr.Dataset) -> SweepPlot | None:
    """The curve of a one-dimensional cube along its first axis; None if no model has data."""
    (dim,) = sweep_dims(cube)
    values = cube[dim].values
    numeric = values.dtype.kind in "iuf"
    x = values.astype(np.float64) if numeric else np.arange(values.size, dtype=np.float64)
    curves = sweep_curves(name, cube, x)
    if not curves:
        return None
    others = [str(cube[c].attrs["field"]) for c in axis_coordinates(cube, dim)[1:]]
    long_name, _ = describe_coordinate(cube, dim)
    title = str(cube.attrs.get("title") or "") or f"Accuracy against {long_name}"
    xlabel = axis_label(cube, dim) + (f"; with {', '.join(others)}" if others else "")
    positive = numeric and bool(np.all(x > 0))
    return SweepPlot(
        sweep=name,
        title=f"{title} (sweep {name})",
        xlabel=xlabel,
        ticks=None if numeric else tuple(label(v) for v in values),
        log=positive and float(x.max() / x.min()) >= 10.0,
        curves=curves,
    )


def heatmap(name: str, cube: xr.Dataset) -> Heatmap | None:
    """The heat map of a two-dimensional cube; None if no model has data."""
    first, second = sweep_dims(cube)
    accuracy = cube[ACCURACY_MEAN].transpose(MODEL_DIM, first, second).values.astype(np.float64)
    keep = [m for m in range(accuracy.shape[0]) if np.isfinite(accuracy[m]).any()]
    if not keep:
        return None
    title = str(cube.attrs.get("title") or "")
    if not title:
        title = (
            f"Accuracy against {describe_coordinate(cube, first)[0]} and "
            f"{describe_coordinate(cube, second)[0]}"
        )
    return Heatmap(
        sweep=name,
        title=f"{title} (sweep {name})",
        row_label=axis_label(cube, first),
        col_label=axis_label(cube, second),
        rows=tuple(label(v) for v in cube[first].values),
        cols=tuple(label(v) for v in cube[second].values),
        models=tuple(str(cube[MODEL_DIM].values[m]) for m in keep),
        accuracy=accuracy[keep],
    )
