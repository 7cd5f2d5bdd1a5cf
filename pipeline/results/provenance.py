"""What a cube says of where it came from, as its attributes.

``grid``, ``sweep``, ``title``, ``mode``, ``seed``, ``training_seed`` (the base scene's),
``package_version`` and the versions of Python and of the libraries that shape the results as
``version_<name>`` strings (:data:`DEPENDENCY_VERSIONS`); and, where every point's result states
the same, what the recordings were: ``dataset_name``, ``sampling_rate_hz``, ``class_names`` and
``n_classes``, and for a real array its ``taxel_names`` and ``taxel_positions_mm`` (where the
dataset gives them) (:func:`recordings_attrs`).
"""

from __future__ import annotations

import platform
from collections.abc import Sequence
from importlib import metadata
from typing import Any

from pipeline.design.grid import Grid, Sweep
from pipeline.run.entries import RecordingsInfo

__all__ = ["DEPENDENCY_VERSIONS", "provenance", "recordings_attrs"]

# One string attribute per library, not a nested mapping: netCDF and Zarr attributes are flat, and
# plain strings keep cubes comparable with xarray.testing.assert_identical. Read once, at import:
# the process runs one set of libraries.
#: The versions of Python and of the libraries that shape the results, as the cube's string
#: attributes ``version_<name>`` (``version_python``, ``version_torch``, ``version_scikit_learn``,
#: ...), read at import.
#:
#: :meta hide-value:
DEPENDENCY_VERSIONS: dict[str, str] = {
    "version_python": platform.python_version(),
    **{
        f"version_{name.replace('-', '_')}": metadata.version(name)
        for name in ("torch", "numpy", "numba", "scikit-learn", "xarray", "zarr")
    },
}


def provenance(grid: Grid, sweep: Sweep) -> dict[str, Any]:
    """The cube's attributes that say what made it: grid, sweep, seeds and versions."""
    return {
        "grid": grid.name,
        "sweep": sweep.name,
        "title": sweep.title,
        "mode": sweep.mode.value,
        "seed": grid.base.seed,
        "training_seed": grid.base.training.seed,
        "package_version": metadata.version("eskin-sweep"),
        **DEPENDENCY_VERSIONS,
    }


def recordings_attrs(infos: Sequence[RecordingsInfo | None]) -> dict[str, Any]:
    """What every point says alike of its recordings; a fact any point lacks or contradicts is
    left out rather than guessed."""
    attrs: dict[str, Any] = {}
    for name in (
        "dataset_name",
        "sampling_rate_hz",
        "class_names",
        "taxel_names",
        "taxel_positions_mm",
    ):
        values = {None if info is None else getattr(info, name) for info in infos}
        if len(values) == 1 and None not in values:
            attrs[name] = values.pop()
    if "sampling_rate_hz" in attrs:
        attrs["sampling_rate_hz"] = float(attrs["sampling_rate_hz"])
    if "class_names" in attrs:
        # A list, not a tuple: attributes come back from Zarr as lists.
        attrs["class_names"] = [str(c) for c in attrs["class_names"]]
        attrs["n_classes"] = len(attrs["class_names"])
    if "taxel_names" in attrs:
        attrs["taxel_names"] = [str(t) for t in attrs["taxel_names"]]
    if "taxel_positions_mm" in attrs:
        attrs["taxel_positions_mm"] = [[float(x), float(y)] for x, y in attrs["taxel_positions_mm"]]
    return attrs
