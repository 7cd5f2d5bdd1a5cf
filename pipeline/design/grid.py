"""Grids: a base scene plus named sweeps over scene fields.

A *sweep* varies one or more scene fields (its *axes*) around the base scene. Axes combine as a
Cartesian product (``mode = "product"``, the default) or element by element (``mode = "zip"``,
all axes the same length, one cube dimension named after the first axis). A sweep may also fix
other fields for all its points (``set``) and ask for the correlation of spike metrics with
accuracy along it (``correlate``), and carry a free-text ``title`` saying what it is for, which
its result cube keeps as its ``title`` attribute. A grid's points are the union of its sweeps'
points; points that are the same scene (equal result cache keys) are computed once.

TOML layout::

    name = "mine"
    base = "paper"                       # a built-in scene name, a scene file, or a [base] table

    [sweeps.threshold]
    title = "Fig. 7a"                    # free text, kept as the cube's ``title`` attribute
    axes = { "readout.threshold_v" = [0.03, 0.09, 0.2] }

    [sweeps.noise]
    mode = "zip"
    set = { "array.rows" = 1, "array.cols" = 1 }
    correlate = true

    [sweeps.noise.axes]
    "readout.effects.amplifier_noise.sigma_v" = [0.0, 0.01]
    "readout.effects.comparator_noise.sigma_v" = [0.0, 0.01]

A relative ``dataset.path`` in the base scene (a file or a ``[base]`` table) is taken from the
folder of the file that names it. Grid and sweep names are letters, digits, ``_`` and ``-``
only: they become folder names (``runs/<grid>``, ``cubes/<sweep>``) and so cannot leave the
run root.

A cube dimension is named after the last part of its field (``threshold_v``); where two axes of a
sweep would clash it takes the last two parts (``amplifier_noise_sigma_v``).

Everything that can be checked without the recordings is checked when the grid loads, and every
problem is reported at once: unknown fields, empty axes, duplicate values, zipped axes of unequal
length, and values a scene refuses. A sweep is checked point by point, each point's whole scene
(base, ``set`` and the point's axis values together, :func:`point_problems`), never its ``set``
alone: a ``set`` that needs a swept field (``chips.deployment = "shared"`` needs the mismatch effect
its axis names) is valid wherever every point has that field. :func:`pipeline.run.fit.check_fits`
then checks the points against the recordings (windows longer than a recording, arrays whose delays
eat it, classes smaller than the folds) before any work starts, naming the shortest recording. A
point's result cache key, which tells which points are the same scene, is the run layer's
(:mod:`pipeline.run.grid_keys`); what a point and a plan cost is :mod:`pipeline.design.grid_cost`.

Expanding and checking a grid costs a few tens of microseconds per point, linear in the points:
a sweep's scenes are built by :class:`pipeline.design.variants.SceneVariants` (each scene part
validated once per distinct combination of the swept values in it, and shared by the points that
have it), and a grid builds its points once.
"""

from __future__ import annotations

import collections
import dataclasses
import enum
import functools
import itertools
import json
import math
import tomllib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from pipeline.design import fields
from pipeline.design.grid_cost import PLAN_BYTES_PER_POINT, PLAN_SECONDS_PER_POINT, TYPICAL_POINT_S
from pipeline.design.scene import Scene, with_dataset_path_from
from pipeline.design.variants import SceneVariants
from pipeline.errors import SceneError

NAME_PATTERN = "letters, digits, '_' or '-', at most 64 characters"


class SweepMode(enum.StrEnum):
    """How a sweep combines its axes."""

    PRODUCT = "product"
    ZIP = "zip"


@dataclass(frozen=True)
class SweepAxis:
    """One swept scene field: dotted ``field`` path, cube dimension name ``dim``, ``values``."""

    field: str
    dim: str
    values: tuple[Any, ...]


@dataclass(frozen=True)
class Sweep:
    """A named sweep: its axes, how they combine, fixed fields, whether to correlate, a title."""

    name: str
    axes: tuple[SweepAxis, ...]
    mode: SweepMode = SweepMode.PRODUCT
    fixed: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    correlate: bool = False
    title: str = ""

    @property
    def dims(self) -> tuple[str, ...]:
        """Cube dimensions (without ``model`` and ``fold``)."""
        if self.mode == SweepMode.ZIP:
            return (self.axes[0].dim,)
        return tuple(axis.dim for axis in self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        """Cube sizes along :attr:`dims` (one size, the axes' common length, for a zipped
        sweep)."""
        if self.mode == SweepMode.ZIP:
            return (len(self.axes[0].values),)
        return tuple(len(axis.values) for axis in self.axes)

    def index_values(self) -> list[tuple[tuple[int, ...], dict[str, Any]]]:
        """Every point as ``(index in the cube, {field: value})``, in C order."""
        if self.mode == SweepMode.ZIP:
            return [
                ((i,), {axis.field: axis.values[i] for axis in self.axes})
                for i in range(len(self.axes[0].values))
            ]
        ranges = [range(len(axis.values)) for axis in self.axes]
        return [
            (index, {axis.field: axis.values[i] for axis, i in zip(self.axes, index, strict=True)})
            for index in itertools.product(*ranges)
        ]


@dataclass(frozen=True)
class GridPoint:
    """One point of a sweep: where it sits in the cube and the scene it simulates (with its
    result cache key: :class:`pipeline.run.grid_keys.KeyedPoint`)."""

    sweep: str
    index: tuple[int, ...]
    scene: Scene


@dataclass(frozen=True)
class Grid:
    """A base scene and its sweeps; build with :func:`load_grid` or :meth:`from_dict`."""

    name: str
    base: Scene
    sweeps: tuple[Sweep, ...]

    @classmethod
    def from_dict(
        cls,
        data: Mapping[str, Any],
        source: str = "<dict>",
        base_dir: Path | None = None,
        max_points: int | None = None,
    ) -> Grid:
        """Validate ``data`` (the TOML layout); raise :class:`~pipeline.errors.SceneError`
        listing every problem.

        A grid of more than ``max_points`` points (counted from its axis sizes, none built:
        :func:`too_large`) is refused with its count, its cost and the advice to search it.
        """
        problems: list[str] = []
        grid = _read_grid(data, source, base_dir or Path.cwd(), problems, max_points)
        if problems:
            raise SceneError(problems, source, kind="grid")
        return grid

    def points(self) -> list[GridPoint]:
        """Every point of every sweep (a point shared by two sweeps appears in both)."""
        return list(self._points)

    def points_of(self, sweep: Sweep) -> list[GridPoint]:
        """The points of ``sweep``, as :func:`sweep_points` makes them.

        For one of this grid's own sweep objects they are those of :meth:`points`, built once
        per grid; for any other sweep they are made now.
        """
        start = 0
        for own in self.sweeps:
            count = math.prod(own.shape)
            if own is sweep:
                return list(self._points[start : start + count])
            start += count
        return sweep_points(self.base, sweep)

    @functools.cached_property
    def _points(self) -> tuple[GridPoint, ...]:
        # Built once per grid: checking, planning and counting a sweep all walk its points.
        return tuple(point for sweep in self.sweeps for point in sweep_points(self.base, sweep))

    def with_dataset(self, fields: Mapping[str, Any]) -> Grid:
        """This grid with the base scene's ``dataset`` table replaced, so every point uses it.

        Parameters
        ----------
        fields
            A scene ``dataset`` table, e.g. ``{"kind": "folder", "path": "/data/mine"}`` as
            :func:`pipeline.recordings.sources.resolve_dataset_argument` returns it. A relative
            ``path`` is taken from the current directory. If ``kind`` is the base's own (or
            missing), the base's other dataset settings stay (a synthetic dataset's size, a
            VibTac-12 axis and segments) and ``fields`` override them; a different ``kind``
            replaces the whole table, as one kind's settings mean nothing to another (a
            folder dataset refuses a ``sampling_rate_hz`` it does not have).

        Returns
        -------
        Grid
            Same name and sweeps; its base (and so the provenance of its cubes, which records
            the base scene) names the new dataset.

        Raises
        ------
        SceneError
            A sweep sets or sweeps a ``dataset.*`` field itself (the override would silently
            lose to it at some points and not at others), naming each such sweep and field;
            or ``fields`` is not a valid dataset table.
        """
        problems = [
            f"sweeps.{sweep.name}.{part}: {field!r} sets the dataset itself, so the dataset "
            "cannot be replaced for the whole grid (drop the field from the sweep, or the "
            "dataset override)"
            for sweep in self.sweeps
            for part, fields_of_sweep in (
                ("set", list(sweep.fixed)),
                ("axes", [axis.field for axis in sweep.axes]),
            )
            for field in fields_of_sweep
            if field.split(".")[0] == "dataset"
        ]
        if problems:
            raise SceneError(problems, repr(self.name), "grid")
        data = self.base.to_dict()
        new = dict(fields)
        same_kind = new.get("kind", data["dataset"]["kind"]) == data["dataset"]["kind"]
        data["dataset"] = {**data["dataset"], **new} if same_kind else new
        data = with_dataset_path_from(data, Path.cwd())
        base = Scene.from_dict(data, source=f"scene {self.base.name!r} with dataset {new}")
        return dataclasses.replace(self, base=base)

    def describe(self) -> dict[str, Any]:
        """A JSON-able description (for provenance in cube attrs)."""
        return {
            "name": self.name,
            "base": self.base.to_dict(),
            "sweeps": {
                s.name: {
                    "mode": s.mode.value,
                    "set": dict(s.fixed),
                    "axes": {a.field: list(a.values) for a in s.axes},
                    "correlate": s.correlate,
                    "title": s.title,
                }
                for s in self.sweeps
            },
        }


def sweep_points(base: Scene, sweep: Sweep) -> list[GridPoint]:
    """The scenes of one sweep (already validated when the grid loaded).

    Each point's scene is ``base.replace(**sweep.fixed, **values)`` with the point's
    ``values`` (the whole scene at once: ``set`` is never a scene of its own), built as
    :class:`pipeline.design.variants.SceneVariants` builds it: each scene part is validated once
    per distinct combination of the swept values in it, and the points share equal parts (so
    that their keys write each part's canonical form once).
    """
    variants = _variants(base, sweep)
    return [
        GridPoint(sweep.name, index, variants.scene(indices))
        for index, indices in _positions(sweep)
    ]


def _variants(base: Scene, sweep: Sweep) -> SceneVariants:
    return SceneVariants(base, [(axis.field, axis.values) for axis in sweep.axes], sweep.fixed)


def _positions(sweep: Sweep) -> Iterator[tuple[tuple[int, ...], tuple[int, ...]]]:
    """Every point as ``(index in the cube, index into each axis's values)``, in C order (as
    :meth:`Sweep.index_values`)."""
    if sweep.mode == SweepMode.ZIP:
        n_axes = len(sweep.axes)
        for i in range(len(sweep.axes[0].values)):
            yield (i,), (i,) * n_axes
        return
    for index in itertools.product(*(range(len(axis.values)) for axis in sweep.axes)):
        yield index, index


def sweep_sizes(sweeps: Any) -> dict[str, int]:
    """Points of each sweep of a grid's ``sweeps`` table, from its axis sizes alone (a product
    of their lengths, or the longest of zipped axes); axes that are not lists count 1."""
    sizes = {}
    for name, data in sweeps.items() if isinstance(sweeps, Mapping) else ():
        axes = data.get("axes") if isinstance(data, Mapping) else None
        lengths = [
            len(v)
            for v in (axes.values() if isinstance(axes, Mapping) else ())
            if isinstance(v, list)
        ]
        zipped = isinstance(data, Mapping) and data.get("mode") == SweepMode.ZIP.value
        sizes[str(name)] = max(lengths, default=0) if zipped else math.prod(lengths)
    return sizes


def too_large(sweeps: Any, max_points: int | None) -> str:
    """Why a grid's ``sweeps`` table is too large to plan (more than ``max_points`` points,
    :func:`sweep_sizes`), with its count, its planning and computing cost and the advice to
    search it instead; empty when it is not (or ``max_points`` is None)."""
    sizes = sweep_sizes(sweeps)
    n = sum(sizes.values())
    if max_points is None or n <= max_points:
        return ""
    largest = max(sizes, key=sizes.__getitem__)
    memory_gb = n * PLAN_BYTES_PER_POINT / 1e9
    return (
        f"sweeps: {n:,} points (sweeps.{largest} has {sizes[largest]:,}) are more than this "
        f"machine can plan ({max_points:,} at most); planning them would take about "
        f"{memory_gb:,.1f} GB and {_duration(n * PLAN_SECONDS_PER_POINT)}, computing them about "
        f"{_duration(n * TYPICAL_POINT_S)} of stage time at {TYPICAL_POINT_S:g} s per point: "
        "search the space with `eskin optimize` instead"
    )


def _duration(seconds: float) -> str:
    for unit, size in (("years", 365 * 86400), ("days", 86400), ("hours", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:,.1f} {unit}"
    return f"{seconds:.0f} s"


def builtin_grid_names() -> tuple[str, ...]:
    """Names of the built-in grids (the TOML files of :mod:`pipeline.design.grids`), sorted."""
    files = resources.files("pipeline.design.grids").iterdir()
    return tuple(sorted(f.name[:-5] for f in files if f.name.endswith(".toml")))


def load_grid(name_or_path: str | Path, max_points: int | None = None) -> Grid:
    """A built-in grid by name (``paper``, ``smoke``) or a grid TOML file by path; more than
    ``max_points`` points are refused (:meth:`Grid.from_dict`)."""
    text = str(name_or_path)
    if text in builtin_grid_names():
        content = (
            resources.files("pipeline.design.grids").joinpath(f"{text}.toml").read_text("utf-8")
        )
        data = tomllib.loads(content)
        data.setdefault("name", text)
        return Grid.from_dict(data, source=f"built-in {text!r}", max_points=max_points)
    path = Path(text)
    try:
        content = path.read_text(encoding="utf-8")
    except OSError as exc:
        known = ", ".join(builtin_grid_names())
        raise SceneError(
            [f"cannot read file: {exc.strerror} (built-in grids: {known})"], str(path), "grid"
        ) from None
    except UnicodeDecodeError as exc:
        raise SceneError([f"not UTF-8 text (byte {exc.start})"], str(path), "grid") from None
    try:
        data = tomllib.loads(content)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError([f"not valid TOML: {exc}"], str(path), "grid") from None
    data.setdefault("name", path.stem)
    return Grid.from_dict(data, source=str(path), base_dir=path.parent, max_points=max_points)


# ---------------------------------------------------------------------------------------------
# Reading and validation


def _read_grid(
    data: Any, source: str, base_dir: Path, problems: list[str], max_points: int | None = None
) -> Grid:
    if not isinstance(data, Mapping):
        problems.append(f"grid: must be a table, got {type(data).__name__}")
        return Grid("grid", Scene(), ())
    for key in data:
        if key not in ("name", "base", "sweeps"):
            problems.append(f"{key}: unknown key (known: name, base, sweeps)")
    name = data.get("name", "grid")
    if not _valid_name(name):
        problems.append(f"name: {name!r} is not a valid grid name ({NAME_PATTERN})")
        name = "grid"
    base = _read_base(data.get("base", "paper"), base_dir, problems)
    sweeps_data = data.get("sweeps", {})
    if not isinstance(sweeps_data, Mapping) or not sweeps_data:
        problems.append("sweeps: a grid needs at least one [sweeps.<name>] table")
        sweeps_data = {}
    # Counted before any point is checked: a grid too large to plan is refused at once.
    refusal = too_large(sweeps_data, max_points)
    if refusal:
        problems.append(refusal)
    sweeps = []
    for sweep_name, sweep_data in sweeps_data.items():
        sweep = _read_sweep(sweep_name, sweep_data, base, problems, check_points=not refusal)
        if sweep is not None:
            sweeps.append(sweep)
    return Grid(name, base, tuple(sweeps))


def _read_base(value: Any, base_dir: Path, problems: list[str]) -> Scene:
    try:
        if isinstance(value, Mapping):
            return Scene.from_dict(with_dataset_path_from(value, base_dir), source="base")
        if isinstance(value, str):
            path = base_dir / value
            return Scene.from_toml(path) if path.suffix == ".toml" else Scene.load(value)
        problems.append(f"base: expected a scene name, a file or a table, got {value!r}")
    except SceneError as exc:
        problems.append(f"base: {exc}")
    return Scene()


def _read_sweep(
    name: str, data: Any, base: Scene, problems: list[str], check_points: bool = True
) -> Sweep | None:
    where = f"sweeps.{name}"
    if not _valid_name(name):
        problems.append(f"{where}: not a valid sweep name ({NAME_PATTERN})")
        return None
    if not isinstance(data, Mapping):
        problems.append(f"{where}: must be a table")
        return None
    known = ("axes", "mode", "set", "correlate", "title")
    for key in data:
        if key not in known:
            problems.append(f"{where}.{key}: unknown key (known: {', '.join(known)})")
    count = len(problems)
    try:
        mode = SweepMode(data.get("mode", "product"))
    except ValueError:
        problems.append(f"{where}.mode: {data.get('mode')!r} is not 'product' or 'zip'")
        mode = SweepMode.PRODUCT
    fixed = data.get("set", {})
    if not isinstance(fixed, Mapping):
        problems.append(f"{where}.set: must be a table of field = value")
        fixed = {}
    for field in fixed:
        _check_field(field, f"{where}.set", problems)
    correlate = data.get("correlate", False)
    if not isinstance(correlate, bool):
        problems.append(f"{where}.correlate: expected true or false, got {correlate!r}")
    title = data.get("title", "")
    if not isinstance(title, str):
        problems.append(f"{where}.title: expected a string, got {title!r}")
    axes_data = data.get("axes")
    if not isinstance(axes_data, Mapping) or not axes_data:
        problems.append(f"{where}.axes: a sweep needs at least one axis (field = [values])")
        return None
    axes = []
    for field, values in axes_data.items():
        here = f"{where}.axes.{field}"
        _check_field(field, f"{where}.axes", problems)
        if field in fixed:
            problems.append(f"{here}: also fixed in {where}.set")
        if not isinstance(values, list) or not values:
            problems.append(f"{here}: must be a non-empty list of values")
            continue
        counts = collections.Counter(json.dumps(v, sort_keys=True) for v in values)
        duplicates = sorted(v for v, n in counts.items() if n > 1)
        if duplicates:
            problems.append(f"{here}: duplicate values {', '.join(duplicates)}")
        axes.append((field, tuple(values)))
    if mode == SweepMode.ZIP and len({len(v) for _, v in axes}) > 1:
        lengths = ", ".join(f"{f} has {len(v)}" for f, v in axes)
        problems.append(f"{where}.axes: zipped axes need equal lengths ({lengths})")
    if len(problems) > count:
        return None
    sweep = Sweep(name, _name_dims(axes), mode, dict(fixed), bool(correlate), title)
    if check_points:
        problems += point_problems(base, sweep)
    return sweep


def point_problems(base: Scene, sweep: Sweep) -> list[str]:
    """What the scenes of ``sweep``'s points refuse, each point's whole scene checked (base,
    ``set`` and the point's axis values together), or ``[]``.

    A problem is named with its sweep and the point's axis values (``sweeps.s at
    readout.threshold_v = 1.5: readout.threshold_v: ...``); one found at every point of a sweep
    of several (a ``set`` the scene refuses whatever the axes say) is said once, ``at every
    point``. Each scene part is validated once per combination of the swept values in it, not
    per point.
    """
    where = f"sweeps.{sweep.name}"
    variants = _variants(base, sweep)
    refused = []
    for _, indices in _positions(sweep):
        found = variants.problems(indices)
        if found:
            refused.append((indices, found))
    if not refused:
        return []
    everywhere: list[str] = []
    if len(refused) == math.prod(sweep.shape) > 1:
        everywhere = [p for p in refused[0][1] if all(p in found for _, found in refused)]
    problems = [f"{where} at every point: {'; '.join(everywhere)}"] if everywhere else []
    for indices, found in refused:
        rest = [p for p in found if p not in everywhere]
        if rest:
            at = ", ".join(
                f"{axis.field} = {axis.values[i]!r}"
                for axis, i in zip(sweep.axes, indices, strict=True)
            )
            problems.append(f"{where} at {at}: {'; '.join(rest)}")
    return problems


def _name_dims(axes: Sequence[tuple[str, tuple[Any, ...]]]) -> tuple[SweepAxis, ...]:
    lasts = [field.split(".")[-1] for field, _ in axes]
    named = []
    for (field, values), last in zip(axes, lasts, strict=True):
        dim = last if lasts.count(last) == 1 else "_".join(field.split(".")[-2:])
        named.append(SweepAxis(field, dim, values))
    return tuple(named)


def _check_field(field: str, where: str, problems: list[str]) -> None:
    """A dotted path must name a scene field (or an effect, or an effect's parameter)."""
    try:
        fields.resolve(Scene, field)
    except fields.UnknownField as exc:
        problems.append(f"{where}: {exc.text}")


def _valid_name(name: Any) -> bool:
    return (
        isinstance(name, str)
        and 0 < len(name) <= 64
        and all(c.isascii() and (c.isalnum() or c in "_-") for c in name)
    )
