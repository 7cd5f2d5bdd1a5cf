"""Scenes: frozen, validated descriptions of one simulated situation.

A scene has five parts (``dataset``, ``array``, ``readout``, ``coding``, ``training``) and a
``seed``. It loads from a dict or a TOML file, rejects unknown keys and out-of-range values with a
message naming every offending field at once, and has a canonical form (sorted keys, units in the
field names) from which cache keys are hashed.

Readout *effects* are a mapping from effect name to parameters. An effect that is not named is not
simulated and is not part of any cache key; an ideal scene names none. The scene seed enters the
spike-train key only when a named effect draws random numbers.

Cache keys (:func:`cache_key`) hash exactly the fields a stage depends on; which fields those are
is declared with the stages themselves, in :mod:`pipeline.stages`::

    recordings : dataset
    spikes     : dataset, array, readout (+ seed if a random effect is named)
    rates      : spikes fields + coding
    results    : rates fields + training

Many scenes that differ in a few fields (a grid's points) are built by :class:`SceneVariants`,
which reads each part once per distinct combination of the values in it and shares the part
between the scenes. The canonical form is written part by part (the JSON of a dict with sorted
keys is its items' JSON in key order), so a memo writes a shared part once for all its scenes.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import json
import math
import operator
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Literal

from pipeline.errors import SceneError

MAX_TAXELS_PER_SIDE = 256


def _about(units: str, long_name: str) -> dict[str, str]:
    """Field metadata: CF ``units`` ("1" when dimensionless or a label) and a prose name.

    Declared here once; result cubes write them on every coordinate a scene field becomes.
    """
    return {"units": units, "long_name": long_name}


class DatasetKind(enum.StrEnum):
    """Where recordings come from."""

    SYNTHETIC = "synthetic"
    VIBTAC12 = "vibtac12"
    FOLDER = "folder"


class Axis(enum.StrEnum):
    """Accelerometer axis of the VibTac-12 recordings."""

    X = "x"
    Y = "y"
    Z = "z"


class ScanDirection(enum.StrEnum):
    """Scan direction ``(d_x, d_y)`` across the taxel grid."""

    Y = "y"  # along rows: taxel (i, j) is delayed by i * pitch / speed (the paper's Fig. 4)
    X = "x"  # along columns
    XY = "xy"  # diagonal, unit vector (1, 1) / sqrt(2)

    @property
    def vector(self) -> tuple[float, float]:
        """``(d_x, d_y)``."""
        return {"y": (0.0, 1.0), "x": (1.0, 0.0), "xy": (math.sqrt(0.5), math.sqrt(0.5))}[
            self.value
        ]


class Polarity(enum.StrEnum):
    """How ON and OFF spikes enter the rate code."""

    MERGED = "merged"  # one count per window, both polarities (the paper)
    SPLIT = "split"  # two channels: +1 spikes, then -1 spikes


class Model(enum.StrEnum):
    """Classifiers."""

    FFNN = "ffnn"
    CNN = "cnn"


class Effect(enum.StrEnum):
    """Non-ideal readout effects, in the order they act on the signal."""

    AMPLIFIER_OFFSET = "amplifier_offset"
    AMPLIFIER_NOISE = "amplifier_noise"
    SATURATION = "saturation"
    COMPARATOR_OFFSET = "comparator_offset"
    COMPARATOR_NOISE = "comparator_noise"
    THRESHOLD_MISMATCH = "threshold_mismatch"


# ---------------------------------------------------------------------------------------------
# Effect parameters


@dataclass(frozen=True)
class AmplifierOffset:
    """Static input offset per taxel, ``N(0, sigma_v)`` V; matters through saturation."""

    sigma_v: float = field(
        default=0.01, metadata=_about("V", "standard deviation of the amplifier offset per taxel")
    )


@dataclass(frozen=True)
class AmplifierNoise:
    """White Gaussian noise on every sample, ``sigma_v`` V rms."""

    sigma_v: float = field(default=0.005, metadata=_about("V", "rms amplifier noise per sample"))


@dataclass(frozen=True)
class Saturation:
    """Clip the amplified signal at the rails ``+-rail_v``; ``None`` means half the full scale."""

    rail_v: float | None = field(
        default=None, metadata=_about("V", "saturation rail of the amplified signal")
    )


@dataclass(frozen=True)
class ComparatorOffset:
    """Static offsets of the UP and DOWN comparators per taxel, each ``N(0, sigma_v)`` V."""

    sigma_v: float = field(
        default=0.005,
        metadata=_about("V", "standard deviation of the comparator offsets per taxel"),
    )


@dataclass(frozen=True)
class ComparatorNoise:
    """Gaussian noise on each comparator decision (per sample), ``sigma_v`` V rms."""

    sigma_v: float = field(default=0.005, metadata=_about("V", "rms comparator noise per decision"))


@dataclass(frozen=True)
class ThresholdMismatch:
    """Fixed-pattern threshold per taxel, ``threshold_v * (1 + sigma_rel * z)``, ``z ~ N(0, 1)``.

    A draw that would push a threshold below ``floor_rel * threshold_v`` (zero or negative
    included) is clipped to that floor: a comparator cannot resolve a smaller step.
    """

    sigma_rel: float = field(
        default=0.05, metadata=_about("1", "relative standard deviation of the threshold per taxel")
    )
    floor_rel: float = field(
        default=0.1, metadata=_about("1", "lowest threshold per taxel, relative to threshold_v")
    )


EFFECT_TYPES: dict[Effect, type] = {
    Effect.AMPLIFIER_OFFSET: AmplifierOffset,
    Effect.AMPLIFIER_NOISE: AmplifierNoise,
    Effect.SATURATION: Saturation,
    Effect.COMPARATOR_OFFSET: ComparatorOffset,
    Effect.COMPARATOR_NOISE: ComparatorNoise,
    Effect.THRESHOLD_MISMATCH: ThresholdMismatch,
}
RANDOM_EFFECTS = frozenset(EFFECT_TYPES) - {Effect.SATURATION}


# ---------------------------------------------------------------------------------------------
# Scene parts


@dataclass(frozen=True)
class DatasetSpec:
    """Which recordings, and how they are cut.

    ``kind="synthetic"`` is the embedded default (``seed``, ``recordings_per_class``,
    ``duration_s``); ``vibtac12`` reads the X/Y/Z CSVs in ``path`` (``axis``, ``segments``,
    ``sampling_rate_hz``, default 200 Hz); ``folder`` reads ``path/dataset.toml``.
    """

    kind: DatasetKind = field(
        default=DatasetKind.SYNTHETIC, metadata=_about("1", "source of the recordings")
    )
    path: str | None = field(default=None, metadata=_about("1", "folder of the recordings"))
    sampling_rate_hz: float | None = field(
        default=None, metadata=_about("Hz", "sampling rate of the VibTac-12 recordings")
    )
    axis: Axis = field(
        default=Axis.Z, metadata=_about("1", "accelerometer axis of the VibTac-12 recordings")
    )
    segments: int = field(
        default=10, metadata=_about("1", "segments cut from each VibTac-12 recording")
    )
    seed: int = field(default=0, metadata=_about("1", "seed of the built-in recordings"))
    recordings_per_class: int = field(
        default=10, metadata=_about("1", "built-in recordings per class")
    )
    duration_s: float = field(
        default=5.0, metadata=_about("s", "duration of each built-in recording")
    )


@dataclass(frozen=True)
class ArraySpec:
    """Taxel grid ``rows x cols`` at ``pitch_mm``, scanned at ``speed_mm_s`` along ``direction``."""

    rows: int = field(default=3, metadata=_about("1", "taxel rows of the array"))
    cols: int = field(default=3, metadata=_about("1", "taxel columns of the array"))
    pitch_mm: float = field(
        default=1.0, metadata=_about("mm", "distance between neighbouring taxels")
    )
    speed_mm_s: float = field(default=20.0, metadata=_about("mm/s", "scan speed across the array"))
    direction: ScanDirection = field(
        default=ScanDirection.Y, metadata=_about("1", "scan direction across the taxel grid")
    )

    @property
    def n_taxels(self) -> int:
        return self.rows * self.cols


@dataclass(frozen=True)
class ReadoutSpec:
    """Level-crossing readout: ``threshold_v`` of a ``full_scale_v`` range, and effects."""

    threshold_v: float = field(
        default=0.09, metadata=_about("V", "comparator threshold (level-crossing step)")
    )
    full_scale_v: float = field(
        default=1.0, metadata=_about("V", "full-scale input range of the readout")
    )
    effects: Mapping[Effect, Any] = field(
        default_factory=dict, metadata=_about("1", "non-ideal readout effects and their parameters")
    )

    @property
    def is_ideal(self) -> bool:
        return not self.effects

    @property
    def is_random(self) -> bool:
        return any(e in RANDOM_EFFECTS for e in self.effects)

    @property
    def equivalent_bits(self) -> float:
        return math.log2(self.full_scale_v / self.threshold_v)


@dataclass(frozen=True)
class CodingSpec:
    """Rate coding: ``n_windows`` windows of ``window_s``; ``"auto"`` fits the recordings."""

    window_s: float = field(default=0.1, metadata=_about("s", "rate-coding window length"))
    n_windows: int | Literal["auto"] = field(
        default="auto", metadata=_about("1", "rate-coding windows per recording")
    )
    polarity: Polarity = field(
        default=Polarity.MERGED, metadata=_about("1", "how ON and OFF spikes enter the rate code")
    )


@dataclass(frozen=True)
class TrainingSpec:
    """Classifiers and stratified k-fold cross-validation."""

    models: tuple[Model, ...] = field(
        default=(Model.FFNN, Model.CNN), metadata=_about("1", "classifiers trained")
    )
    epochs: int = field(default=100, metadata=_about("1", "training epochs"))
    learning_rate: float = field(default=1e-3, metadata=_about("1", "Adam learning rate"))
    hidden_units: int = field(default=100, metadata=_about("1", "hidden units of the FFNN"))
    batch_size: int = field(default=16, metadata=_about("1", "training batch size"))
    folds: int = field(default=10, metadata=_about("1", "cross-validation folds"))
    repeats: int = field(
        default=1, metadata=_about("1", "cross-validation repeats, each a fresh stratified split")
    )
    seed: int = field(default=0, metadata=_about("1", "training seed"))


@dataclass(frozen=True)
class Scene:
    """One simulated situation. Build with :meth:`from_dict`, :meth:`from_toml` or :meth:`paper`."""

    name: str = "scene"
    seed: int = field(default=0, metadata=_about("1", "scene seed (random readout effects)"))
    dataset: DatasetSpec = field(default_factory=DatasetSpec)
    array: ArraySpec = field(default_factory=ArraySpec)
    readout: ReadoutSpec = field(default_factory=ReadoutSpec)
    coding: CodingSpec = field(default_factory=CodingSpec)
    training: TrainingSpec = field(default_factory=TrainingSpec)

    # -- construction ---------------------------------------------------------------------------

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> Scene:
        """Validate ``data`` (the TOML layout) and build a scene; raise :class:`SceneError`."""
        reader = _Reader(source)
        scene = reader.scene(data)
        reader.raise_if_problems()
        return scene

    @classmethod
    def from_toml(cls, path: str | Path) -> Scene:
        """Load a scene from a TOML file."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise SceneError([f"cannot read file: {exc.strerror}"], str(path)) from None
        except UnicodeDecodeError as exc:
            raise SceneError([f"not UTF-8 text (byte {exc.start})"], str(path)) from None
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise SceneError([f"not valid TOML: {exc}"], str(path)) from None
        data.setdefault("name", path.stem)
        return cls.from_dict(with_dataset_path_from(data, path.parent), source=str(path))

    @classmethod
    def builtin(cls, name: str) -> Scene:
        """A scene shipped with the package (``paper``, ``smoke``)."""
        names = builtin_scene_names()
        if name not in names:
            raise SceneError([f"no built-in scene {name!r} (built-in: {', '.join(names)})"], name)
        text = resources.files("pipeline.scenes").joinpath(f"{name}.toml").read_text("utf-8")
        data = tomllib.loads(text)
        data.setdefault("name", name)
        return cls.from_dict(data, source=f"built-in scene {name!r}")

    @classmethod
    def paper(cls) -> Scene:
        """The paper's operating point: 3x3 taxels, 0.09 V of 1 V, 0.1 s x 40 windows, FFNN+CNN."""
        return cls.builtin("paper")

    @classmethod
    def load(cls, name_or_path: str) -> Scene:
        """A built-in scene by name, or a TOML file by path."""
        if name_or_path in builtin_scene_names():
            return cls.builtin(name_or_path)
        return cls.from_toml(name_or_path)

    def replace(self, **changes: Any) -> Scene:
        """A copy with dotted fields replaced (``{"readout.threshold_v": 0.05}``), re-validated."""
        data = self.to_dict()
        for dotted, value in changes.items():
            node = data
            *parents, leaf = dotted.split(".")
            for part in parents:
                node = node.setdefault(part, {})
            node[leaf] = value
        return Scene.from_dict(data, source=f"scene {self.name!r} with {sorted(changes)}")

    # -- canonical form -------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict in the TOML layout (enums as strings, tuples as lists)."""
        return _plain(self)

    def canonical(
        self, parts: tuple[str, ...] | None = None, memo: CanonicalMemo | None = None
    ) -> str:
        """Stable JSON of the scene (or of ``parts``: top-level parts such as ``"readout"``, or
        dotted fields of one such as ``"readout.full_scale_v"``), sorted, units in names.

        ``memo`` holds the canonical form of part objects already written: give the same dict
        for many scenes that share part objects (the scenes of a :class:`SceneVariants`) and
        each part is written once. The text does not depend on it.
        """
        # The JSON of a dict with sorted keys is its items' JSON in key order, so each part can
        # be written (and remembered) on its own: the text is that of the whole selection.
        items = []
        for top, fields in _canonical_plan(_CANONICAL_PARTS if parts is None else tuple(parts)):
            value = getattr(self, top)
            if fields is None:
                text = _canonical_part(value, memo)
            else:
                text = _canonical_json(_selected({top: _plain(value)}, fields)[top])
            items.append(f'"{top}":{text}')
        return "{" + ",".join(items) + "}"


#: Canonical memo: the canonical JSON of a part object by its ``id``, with the object itself,
#: which keeps it alive so that its ``id`` is not reused while the memo holds it.
CanonicalMemo = dict[int, tuple[Any, str]]

#: The top-level fields a canonical form holds (every field but the name).
_CANONICAL_PARTS = ("array", "coding", "dataset", "readout", "seed", "training")


def _canonical_json(data: Any) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _canonical_part(value: Any, memo: CanonicalMemo | None) -> str:
    """The canonical JSON of one top-level part, from ``memo`` if it was written before."""
    if memo is None:
        return _canonical_json(_plain(value))
    found = memo.get(id(value))
    if found is None:
        found = memo[id(value)] = (value, _canonical_json(_plain(value)))
    return found[1]


@functools.lru_cache(maxsize=64)
def _canonical_plan(parts: tuple[str, ...]) -> tuple[tuple[str, tuple[str, ...] | None], ...]:
    """The top-level parts ``parts`` selects, sorted, each whole (None) or with its dotted
    fields; raises ``KeyError`` for a part that is not in the canonical form."""
    whole: set[str] = set()
    dotted: dict[str, list[str]] = {}
    for part in parts:
        top = part.split(".", 1)[0]
        if top not in _CANONICAL_PARTS:
            raise KeyError(top)
        if top == part:
            whole.add(top)
        else:
            dotted.setdefault(top, []).append(part)
    return tuple(
        (top, None if top in whole else tuple(dotted[top])) for top in sorted(whole | dotted.keys())
    )


def _selected(data: dict[str, Any], parts: tuple[str, ...]) -> dict[str, Any]:
    """The ``parts`` of ``data``, nested as in ``data``; a dotted field left unset is left out."""
    selected: dict[str, Any] = {}
    for part in parts:
        *parents, leaf = part.split(".")
        source, target = data, selected
        for name in parents:
            source = source[name]
            target = target.setdefault(name, {})
        if parents and leaf not in source:  # None: the field keeps its default
            continue
        target[leaf] = source[leaf]
    return selected


def stage_fields(scene: Scene, stage: str) -> tuple[str, ...]:
    """The scene parts the output of ``stage`` depends on (see :mod:`pipeline.stages`)."""
    # Imported here: the stage registry imports this module.
    from pipeline.stages import level_named

    return level_named(stage).key_parts(scene)


#: Revision of what the stages compute for a given scene. Bump it with any change that alters a
#: stage's output for the same fields (a different random stream, a fixed bug, a new training
#: step), so that stores made before the change are recomputed instead of mixed with new points.
#: 2: comparator noise takes one draw per decision; ``threshold_mismatch.floor_rel`` is used.
#: 3: results keep every recording's out-of-fold prediction; the built-in recordings' classes
#: follow the statistics measured on real texture recordings.
MODEL_REVISION = 4


def cache_key(scene: Scene, stage: str, memo: CanonicalMemo | None = None) -> str:
    """SHA-256 (hex, 32 chars) of :data:`MODEL_REVISION` and the canonical form of exactly the
    fields ``stage`` uses (:meth:`pipeline.stages.Level.key`); ``memo`` as for
    :meth:`Scene.canonical`."""
    from pipeline.stages import level_named

    return level_named(stage).key(scene, memo)


def with_dataset_path_from(data: Mapping[str, Any], folder: Path) -> Mapping[str, Any]:
    """``data`` with a relative ``dataset.path`` made absolute against ``folder``.

    A scene file's dataset path means the same folder whatever directory the command runs in:
    a relative path is taken from the folder of the file that names it (``~`` is expanded).
    Anything but a string path is left for validation to report.
    """
    dataset = data.get("dataset")
    if not isinstance(dataset, Mapping) or not isinstance(dataset.get("path"), str):
        return data
    if not dataset["path"]:
        return data
    path = Path(dataset["path"]).expanduser()
    if not path.is_absolute():
        path = Path(folder).absolute() / path
    return {**data, "dataset": {**dataset, "path": str(path)}}


def builtin_scene_names() -> tuple[str, ...]:
    files = resources.files("pipeline.scenes").iterdir()
    return tuple(sorted(f.name[:-5] for f in files if f.name.endswith(".toml")))


# ---------------------------------------------------------------------------------------------
# Many variants of one scene

#: The scene's top-level fields in the order the reader reads (and reports) them.
_READ_ORDER = ("dataset", "array", "readout", "coding", "training", "name", "seed")


class SceneVariants:
    """Copies of one scene with the same dotted fields replaced, each field from its own list.

    ``variants.scene(indices)`` is ``scene.replace(**{field: values[i] ...})`` over ``axes``
    and ``indices``: the same scene, or a :class:`SceneError` with the same problems, but each
    scene part (``dataset``, ``array``, ...) is read and validated once per distinct
    combination of the value indices of the fields in it (a part no field is in, once), and
    the scenes share their parts. A grid whose fields take a few values each thus validates a
    few parts, not every point, and its scenes' canonical forms can be written once per part
    (:meth:`Scene.canonical` with a memo).

    Parameters
    ----------
    scene : Scene
        The scene the variants start from.
    axes : sequence of (str, sequence)
        Dotted scene fields (``"readout.threshold_v"``), each with its values. A field must
        start with a top-level scene field (``dataset``, ..., ``name``, ``seed``).

    Raises
    ------
    ValueError
        A field does not start with a top-level scene field.
    """

    def __init__(self, scene: Scene, axes: Sequence[tuple[str, Sequence[Any]]]):
        self._data = scene.to_dict()
        self._fields = [name for name, _ in axes]
        self._values = [values for _, values in axes]
        self.source = f"scene {scene.name!r} with {sorted(self._fields)}"
        tops = [name.split(".")[0] for name in self._fields]
        unknown = sorted(set(tops) - set(_READ_ORDER))
        if unknown:
            raise ValueError(f"not top-level scene fields: {', '.join(unknown)}")
        self._positions = {
            top: tuple(i for i, t in enumerate(tops) if t == top) for top in _READ_ORDER
        }
        # The memo key of a part: the indices of the values in it (none for an untouched part).
        self._part_indices = [
            (top, operator.itemgetter(*positions) if positions else lambda _: ())
            for top, positions in self._positions.items()
        ]
        self._parts: dict[tuple[str, Any], tuple[Any, list[str]]] = {}

    def problems(self, indices: Sequence[int]) -> list[str]:
        """What :meth:`scene` would raise at ``indices`` (one index per axis), or ``[]``."""
        problems: list[str] = []
        for top, part_indices in self._part_indices:
            problems += self._part(top, part_indices(indices), indices)[1]
        return problems

    def scene(self, indices: Sequence[int]) -> Scene:
        """The scene with each field set to ``values[indices[axis]]``.

        Raises
        ------
        SceneError
            The values the scene refuses, exactly as :meth:`Scene.replace` says.
        """
        parts: dict[str, Any] = {}
        problems: list[str] = []
        for top, part_indices in self._part_indices:
            value, found = self._part(top, part_indices(indices), indices)
            parts[top] = value
            problems += found
        if problems:
            raise SceneError(problems, self.source)
        return Scene(**parts)

    def _part(self, top: str, part_indices: Any, indices: Sequence[int]) -> tuple[Any, list[str]]:
        found = self._parts.get((top, part_indices))
        if found is None:
            positions = self._positions[top]
            changes = [(self._fields[i], self._values[i][indices[i]]) for i in positions]
            found = self._parts[top, part_indices] = self._read(top, changes)
        return found

    def _read(self, top: str, changes: list[tuple[str, Any]]) -> tuple[Any, list[str]]:
        """Part ``top`` with ``changes`` made as :meth:`Scene.replace` makes them, and what the
        reader found wrong with it."""
        data = {top: _copy_plain(self._data[top])}
        for dotted, value in changes:
            node = data
            *parents, leaf = dotted.split(".")
            for part in parents:
                node = node.setdefault(part, {})
            node[leaf] = value
        reader = _Reader(self.source)
        if top == "name":
            part = reader.convert(data[top], "name", _string)
        elif top == "seed":
            part = reader.convert(data[top], "seed", _seed)
        else:
            part = getattr(reader, top)(data[top], top)
        return part, reader.problems


def _copy_plain(value: Any) -> Any:
    """A copy of a plain nested dict/list, so that changing it leaves the original alone."""
    if isinstance(value, dict):
        return {k: _copy_plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy_plain(v) for v in value]
    return value


# ---------------------------------------------------------------------------------------------
# Validation


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value):  # None means "default": TOML has no null
        fields = ((f.name, getattr(value, f.name)) for f in dataclasses.fields(value))
        return {name: _plain(v) for name, v in fields if v is not None}
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, Mapping):
        return {str(_plain(k)): _plain(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return value


class _Reader:
    """Reads a nested dict into scene parts, collecting every problem before raising."""

    def __init__(self, source: str):
        self.source = source
        self.problems: list[str] = []

    def raise_if_problems(self) -> None:
        if self.problems:
            raise SceneError(self.problems, self.source)

    def problem(self, where: str, what: str) -> None:
        self.problems.append(f"{where}: {what}")

    def table(self, data: Any, where: str) -> Mapping[str, Any]:
        if data is None:
            return {}
        if not isinstance(data, Mapping):
            self.problem(where, f"must be a table, got {type(data).__name__}")
            return {}
        return data

    def build(self, cls: type, data: Any, where: str, **checks: Any) -> Any:
        """Build dataclass ``cls`` from table ``data``: unknown keys, types and ranges checked.

        ``checks`` maps a field name to ``(converter, predicate, requirement)``; the converter
        turns the raw value into the field's type (raising ``TypeError``/``ValueError``), the
        predicate says whether the converted value is in range.
        """
        data = self.table(data, where)
        known = {f.name: f for f in dataclasses.fields(cls)}
        for key in data:
            if key not in known:
                self.problem(_join(where, key), f"unknown key (known: {', '.join(known)})")
        values = {}
        for name, (convert, ok, requirement) in checks.items():
            if name not in data:
                continue
            here = _join(where, name)
            try:
                value = convert(data[name])
            except (TypeError, ValueError) as exc:
                self.problem(here, str(exc) or f"invalid value {data[name]!r}")
                continue
            if ok is not None and not ok(value):
                self.problem(here, f"{data[name]!r} is out of range: must be {requirement}")
                continue
            values[name] = value
        try:
            return cls(**values)
        except (TypeError, ValueError) as exc:  # pragma: no cover - checks cover every field
            self.problem(where, str(exc))
            return cls()

    def scene(self, data: Any) -> Scene:
        data = self.table(data, "scene")
        parts = {
            "dataset": self.dataset,
            "array": self.array,
            "readout": self.readout,
            "coding": self.coding,
            "training": self.training,
        }
        for key in data:
            if key not in (*parts, "name", "seed"):
                self.problem(key, f"unknown key (known: name, seed, {', '.join(parts)})")
        values: dict[str, Any] = {k: read(data.get(k), k) for k, read in parts.items()}
        if "name" in data:
            values["name"] = self.convert(data["name"], "name", _string)
        if "seed" in data:
            values["seed"] = self.convert(data["seed"], "seed", _seed)
        return Scene(**{k: v for k, v in values.items() if v is not None})

    def convert(self, value: Any, where: str, convert: Any) -> Any:
        try:
            return convert(value)
        except (TypeError, ValueError) as exc:
            self.problem(where, str(exc))
            return None

    def dataset(self, data: Any, where: str) -> DatasetSpec:
        spec = self.build(
            DatasetSpec,
            data,
            where,
            kind=(_enum(DatasetKind), None, ""),
            path=(_string, None, ""),
            sampling_rate_hz=(_optional(_float), _none_or(_positive), "> 0 Hz"),
            axis=(_enum(Axis), None, ""),
            segments=(_int, lambda v: 1 <= v <= 1000, "between 1 and 1000"),
            seed=(_seed, None, ""),
            recordings_per_class=(_int, lambda v: 1 <= v <= 10_000, "between 1 and 10000"),
            duration_s=(_float, lambda v: 0.1 <= v <= 36_000, "between 0.1 and 36000 s"),
        )
        if spec.kind in (DatasetKind.VIBTAC12, DatasetKind.FOLDER) and not spec.path:
            self.problem(_join(where, "path"), f"required for kind {spec.kind.value!r}")
        return spec

    def array(self, data: Any, where: str) -> ArraySpec:
        side = (
            _int,
            lambda v: 1 <= v <= MAX_TAXELS_PER_SIDE,
            f"between 1 and {MAX_TAXELS_PER_SIDE}",
        )
        return self.build(
            ArraySpec,
            data,
            where,
            rows=side,
            cols=side,
            pitch_mm=(_float, _positive, "> 0 mm"),
            speed_mm_s=(_float, _positive, "> 0 mm/s"),
            direction=(_enum(ScanDirection), None, ""),
        )

    def readout(self, data: Any, where: str) -> ReadoutSpec:
        data = self.table(data, where)
        spec = self.build(
            ReadoutSpec,
            {k: v for k, v in data.items() if k != "effects"},
            where,
            threshold_v=(_float, _positive, "> 0 V"),
            full_scale_v=(_float, _positive, "> 0 V"),
        )
        effects = {}
        raw = self.table(data.get("effects"), _join(where, "effects"))
        for name, params in raw.items():
            here = _join(where, "effects", name)
            try:
                effect = Effect(name)
            except ValueError:
                self.problem(here, f"unknown effect (known: {', '.join(e.value for e in Effect)})")
                continue
            effects[effect] = self.effect(effect, params, here)
        if spec.threshold_v >= spec.full_scale_v:
            self.problem(
                _join(where, "threshold_v"),
                f"{spec.threshold_v!r} V is not below full_scale_v = {spec.full_scale_v!r} V",
            )
        return dataclasses.replace(spec, effects=dict(sorted(effects.items())))

    def effect(self, effect: Effect, params: Any, where: str) -> Any:
        nonneg = (_float, _nonnegative, ">= 0")
        checks = {
            Effect.AMPLIFIER_OFFSET: {"sigma_v": nonneg},
            Effect.AMPLIFIER_NOISE: {"sigma_v": nonneg},
            Effect.COMPARATOR_OFFSET: {"sigma_v": nonneg},
            Effect.COMPARATOR_NOISE: {"sigma_v": nonneg},
            Effect.SATURATION: {"rail_v": (_optional(_float), _none_or(_positive), "> 0 V")},
            Effect.THRESHOLD_MISMATCH: {
                "sigma_rel": nonneg,
                "floor_rel": (_float, lambda v: 0 < v <= 1, "in (0, 1]"),
            },
        }[effect]
        return self.build(EFFECT_TYPES[effect], params, where, **checks)

    def coding(self, data: Any, where: str) -> CodingSpec:
        return self.build(
            CodingSpec,
            data,
            where,
            window_s=(_float, lambda v: 1e-6 <= v <= 3600, "between 1e-6 and 3600 s"),
            n_windows=(_auto_or_int, lambda v: v == "auto" or 1 <= v <= 100_000, "'auto' or >= 1"),
            polarity=(_enum(Polarity), None, ""),
        )

    def training(self, data: Any, where: str) -> TrainingSpec:
        return self.build(
            TrainingSpec,
            data,
            where,
            models=(_models, lambda v: len(v) > 0, "a non-empty list of 'ffnn', 'cnn'"),
            epochs=(_int, lambda v: 1 <= v <= 100_000, "between 1 and 100000"),
            learning_rate=(_float, lambda v: 0 < v <= 10, "in (0, 10]"),
            hidden_units=(_int, lambda v: 1 <= v <= 100_000, "between 1 and 100000"),
            batch_size=(_int, lambda v: 1 <= v <= 1_000_000, ">= 1"),
            folds=(_int, lambda v: 2 <= v <= 1000, "between 2 and 1000"),
            repeats=(_int, lambda v: 1 <= v <= 100, "between 1 and 100"),
            seed=(_seed, None, ""),
        )


def _join(*parts: str) -> str:
    return ".".join(p for p in parts if p)


def _float(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"expected a finite number, got {value!r}")
    return value


def _int(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"expected an integer, got {value!r}")
    return value


def _seed(value: Any) -> int:
    value = _int(value)
    if not 0 <= value < 2**63:
        raise ValueError(f"seed must be in [0, 2**63), got {value!r}")
    return value


def _string(value: Any) -> str:
    if not isinstance(value, str):
        raise TypeError(f"expected a string, got {value!r}")
    return value


def _optional(convert: Any) -> Any:
    return lambda v: None if v is None else convert(v)


def _none_or(ok: Any) -> Any:
    return lambda v: v is None or ok(v)


def _positive(v: float) -> bool:
    return v > 0


def _nonnegative(v: float) -> bool:
    return v >= 0


def _enum(kind: type[enum.StrEnum]) -> Any:
    def convert(value: Any) -> Any:
        try:
            return kind(value)
        except ValueError:
            options = ", ".join(repr(m.value) for m in kind)
            raise ValueError(f"{value!r} is not one of {options}") from None

    return convert


def _auto_or_int(value: Any) -> int | str:
    if value == "auto":
        return "auto"
    return _int(value)


def _models(value: Any) -> tuple[Model, ...]:
    if isinstance(value, str) or not isinstance(value, list | tuple):
        raise TypeError(f"expected a list of model names, got {value!r}")
    models = tuple(_enum(Model)(v) for v in value)
    if len(set(models)) != len(models):
        raise ValueError(f"duplicate model in {list(value)!r}")
    return models
