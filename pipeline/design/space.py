"""Design spaces: a base scene, ranges over scene fields and two or three objectives.

A *space* is what ``eskin optimize`` searches instead of gridding: each *dimension* is one scene
field and the values it may take, each *objective* a number of a point's result to maximise or
minimise. A *trial* is one point of the space, a scene like a grid's points: it is computed,
cached and keyed exactly as they are.

TOML layout::

    name = "design"
    base = "paper"                     # a built-in scene, a scene file, or a [base] table
    seed = 0                           # the search's seed (default 0)
    sampler = "auto"                   # "auto" (default), "gp", "tpe", "nsga2" or "random"

    [space]
    "readout.threshold_v" = { low = 0.02, high = 0.3, log = true }   # continuous, log-scaled
    "coding.window_s" = { choices = [0.05, 0.1, 0.2] }              # categorical
    "array.rows" = { low = 1, high = 4, step = 1 }                  # integer (an int field)

    [objectives]
    "accuracy.ffnn" = "max"            # accuracy_mean of a model the base scene trains
    "data_rate_bps" = "min"            # or readout_power_w, compute_s, array_area_m2

A range ``{low, high}`` of an integer field is an integer range (``step`` default 1), of a float
field a continuous one (``step`` optional, ``log = true`` samples ``log(value)`` uniformly and
needs ``low > 0``); ``choices`` lists the values of a categorical dimension (any values the field
takes, strings included). Everything is checked when the space loads, and every problem is
reported at once (:class:`pipeline.errors.SceneError`): unknown keys and fields, malformed
ranges, bounds and choices a scene refuses, unknown models, fewer than two or more than three
objectives. Bounds and choices are checked together, every combination of them (the corners of
the space, each a whole scene with the base's other fields), never one dimension alone at the
base: a chip deployment that needs the mismatch effect another dimension searches is valid.

Objectives (:class:`Metric`), read per trial from its result cube
(:func:`pipeline.results.objectives.objective_values`):

* ``accuracy.<model>``: ``accuracy_mean`` of that model (fraction);
* ``data_rate_bps``: the address-event data rate (bit/s);
* ``readout_power_w``: ``event_rate_hz * E_event + data_rate_bps * E_link`` with the default
  :class:`pipeline.results.readout_constants.EnergyModel` (W);
* ``compute_s``: the stage seconds of the point for the objective's models (all trained models,
  spike stages included), as measured when they were computed;
* ``decision_s.<model>``: the mean decision time (s of touch) of that model under early exit at
  confidence :data:`pipeline.results.early_exit.EXIT_CONFIDENCE` (0.9): each recording decided at
  the first time the softmax probability of its decided class reaches 0.9, else at the full
  touch (:func:`pipeline.results.early_exit.exit_objectives`). Chosen over the earliest decision
  time not significantly below the full touch, the report's, because a search compares trials
  by a number that is a property of the design: a significance test's verdict also depends on
  how many recordings the trial was tested on (more recordings make a small loss significant and
  the time later) and moves in steps. The early exit is what a decoder deployed with that rule
  would achieve, and its accuracy is the cost of deciding early;
* ``decoder_energy_j.<model>``: the decoder's mean energy per decision (J) under the same early
  exit, at the high end of its band (:class:`pipeline.results.decoder_energy.DecoderEnergyModel`;
  the high end so that a search never promises what only the most frugal chip delivers); both
  are NaN, and the trial failed, where the cube keeps no decisions. Both read decoders trained
  to decide along the touch: they need ``training.decisions = "along_touch"`` (the default) in
  the base scene or among the searched fields, since a decoder trained for the full touch alone
  and read early decides later than the design needs;
* ``array_area_m2``: the comparators' matched gate area of the array that the point's threshold
  mismatch demands by Pelgrom's law (:func:`pipeline.results.matched_area.array_area_m2` of
  ``array.rows * array.cols``, ``sigma_rel`` and ``threshold_v``, m^2; minimise it): needs
  ``readout.effects.threshold_mismatch`` in the base scene or a searched field of it;
* ``accuracy_p05.<model>``: the yield, the 5th percentile over chips of that model's accuracy
  (the cube's ``accuracy_p05``; maximise it): needs ``chips.count`` above 1 in the base scene
  or among the searched fields.

A point simulated as several chips (``chips.count`` > 1) states its accuracy and rates per chip:
``accuracy.<model>`` is then the mean over chips (``accuracy_chip_mean``) and the rates are
their means over chips.

Each metric declares the monotone transform its values go through before a sampler is told
them (:data:`TRANSFORMS`, :mod:`pipeline.design.transforms`): logarithmic for rates, power and
seconds, energy and area, linear for accuracy and yield. Stored and reported values are never
transformed.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import itertools
import json
import math
import tomllib
import types
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pipeline.design import fields
from pipeline.design.grid import (
    NAME_PATTERN,
    Grid,
    Sweep,
    SweepAxis,
    SweepMode,
    _read_base,
    _valid_name,
)
from pipeline.design.scene import DecisionTraining, Model, Scene
from pipeline.design.transforms import Transform
from pipeline.design.variants import SceneVariants
from pipeline.errors import SceneError

#: The name of the trial cube's sweep.
TRIALS = "trials"
#: The name of the trial cube's dimension.
TRIAL_DIM = "trial"


class Direction(enum.StrEnum):
    """Whether an objective is maximised or minimised."""

    MAX = "max"
    MIN = "min"

    @property
    def verb(self) -> str:
        """``"maximize"`` or ``"minimize"``, as search libraries (Optuna) name directions."""
        return f"{self.value}imize"


class Metric(enum.StrEnum):
    """What an objective measures (the part of its name before any ``.<model>``)."""

    ACCURACY = "accuracy"
    DATA_RATE = "data_rate_bps"
    POWER = "readout_power_w"
    COMPUTE = "compute_s"
    DECISION_TIME = "decision_s"
    DECODER_ENERGY = "decoder_energy_j"
    AREA = "array_area_m2"
    YIELD = "accuracy_p05"

    @property
    def per_model(self) -> bool:
        """Whether the objective is of one model (``<metric>.<model>``)."""
        return self in _PER_MODEL


#: The objectives of one model each.
_PER_MODEL = frozenset({Metric.ACCURACY, Metric.YIELD, Metric.DECISION_TIME, Metric.DECODER_ENERGY})


#: The dotted scene fields the area and yield objectives need (the mismatch that sizes the
#: comparators' devices, and the chips a yield is taken over).
MISMATCH_FIELD = "readout.effects.threshold_mismatch"
CHIPS_COUNT_FIELD = "chips.count"
#: The field that says what the decoders are trained for, and the objectives of early exit,
#: which need decoders trained along the touch.
DECISIONS_FIELD = "training.decisions"
_EARLY_EXIT = frozenset({Metric.DECISION_TIME, Metric.DECODER_ENERGY})


#: The transform each metric's values go through before a sampler is told them (the floor of a
#: logarithmic one in the metric's unit: 1 bit/s, 1 nW, 1 ms, 1 pJ, 1 um^2). Every metric declares
#: one.
TRANSFORMS: dict[Metric, Transform] = {
    Metric.ACCURACY: Transform.linear(),
    Metric.DATA_RATE: Transform.log(1.0),
    Metric.POWER: Transform.log(1e-9),
    Metric.COMPUTE: Transform.log(1e-3),
    Metric.DECISION_TIME: Transform.log(1e-3),
    Metric.DECODER_ENERGY: Transform.log(1e-12),
    Metric.AREA: Transform.log(1e-12),
    Metric.YIELD: Transform.linear(),
}


class Sampler(enum.StrEnum):
    """How trials are proposed: ``auto`` (the default) picks GP or TPE by the budget and the
    kinds of dimensions (:func:`flows.samplers.resolve_sampler`); a Gaussian process (log
    expected hypervolume improvement), multi-objective TPE (multivariate, a constant liar for
    running trials), NSGA-II, or uniformly at random (a baseline)."""

    TPE = "tpe"
    NSGA2 = "nsga2"
    RANDOM = "random"
    GP = "gp"
    AUTO = "auto"


class DimensionKind(enum.StrEnum):
    """How a dimension's values are drawn: from a float range (continuous, stepped or
    log-scaled), an integer range, or a list of choices."""

    FLOAT = "float"
    INT = "int"
    CATEGORICAL = "categorical"


@dataclass(frozen=True)
class Dimension:
    """One searched scene field: dotted ``field``, its ``kind`` and values.

    ``low``/``high`` bound a FLOAT or INT dimension (inclusive), ``step`` its grid (None:
    continuous), ``log`` samples it log-uniformly; ``choices`` are a CATEGORICAL one's values.
    """

    field: str
    kind: DimensionKind
    low: float | None = None
    high: float | None = None
    step: float | None = None
    log: bool = False
    choices: tuple[Any, ...] = ()

    def extremes(self) -> tuple[Any, ...]:
        """The values a scene must accept for every trial to be valid: bounds or choices."""
        return self.choices if self.kind is DimensionKind.CATEGORICAL else (self.low, self.high)

    def grid_values(self, n: int) -> tuple[Any, ...]:
        """``n`` values spread over the dimension (log-spaced when ``log``): every choice of a
        categorical one, every step of a stepped one with at most ``n`` steps."""
        if self.kind is DimensionKind.CATEGORICAL:
            return self.choices
        if self.step is not None and (self.high - self.low) / self.step + 1 <= n:
            count = round((self.high - self.low) / self.step) + 1
            values = self.low + self.step * np.arange(count)
        elif self.log:
            values = np.geomspace(self.low, self.high, n)
        else:
            values = np.linspace(self.low, self.high, n)
        if self.kind is DimensionKind.INT:
            return tuple(dict.fromkeys(round(float(v)) for v in values))
        return tuple(float(v) for v in values)


@dataclass(frozen=True)
class Objective:
    """One objective: ``metric`` (of ``model`` for those :attr:`Metric.per_model`) and its
    ``direction``."""

    metric: Metric
    direction: Direction
    model: str | None = None

    @property
    def name(self) -> str:
        """The metric's name, with ``.<model>`` for a model's accuracy (``"accuracy.ffnn"``)."""
        return self.metric.value + (f".{self.model}" if self.model else "")

    @property
    def transform(self) -> Transform:
        """What the sampler is told instead of a value (:data:`TRANSFORMS`)."""
        return TRANSFORMS[self.metric]

    @property
    def sign(self) -> float:
        """+1 for a minimised objective and -1 for a maximised one, so that ``sign * value`` is
        minimised."""
        return 1.0 if self.direction is Direction.MIN else -1.0


@dataclass(frozen=True)
class Space:
    """A base scene, the searched dimensions, the objectives and the search's seed."""

    name: str
    base: Scene
    dimensions: tuple[Dimension, ...]
    objectives: tuple[Objective, ...]
    seed: int = 0
    sampler: Sampler = Sampler.AUTO

    @classmethod
    def from_dict(
        cls, data: Mapping[str, Any], source: str = "<dict>", base_dir: Path | None = None
    ) -> Space:
        """Validate ``data`` (the TOML layout); raise :class:`~pipeline.errors.SceneError`
        listing every problem."""
        problems: list[str] = []
        space = _read_space(data, base_dir or Path.cwd(), problems)
        if problems:
            raise SceneError(problems, source, kind="space")
        return space

    def fingerprint(self, sampler: Sampler | None = None, *, every_field: bool = False) -> str:
        """A hash of everything that shapes the search: base, dimensions, objectives, seed and
        sampler (``sampler``, when given, in place of the space's: the fingerprint this space
        had with it).

        The base enters in its canonical form (:meth:`pipeline.design.scene.Scene.canonical`),
        so that a scene field added later at a neutral default changes no fingerprint, as it
        changes no cache key, and the journals of searches begun before it are still theirs.
        ``every_field``: the base as every one of its fields instead
        (:meth:`~pipeline.design.scene.Scene.to_dict`), the form of the journals written before
        the canonical one, which any field added since changes.
        """
        described = {
            "base": self.base.to_dict() if every_field else self.base.canonical(),
            "dimensions": [fields.plain(dataclasses.asdict(d)) for d in self.dimensions],
            "objectives": [[o.name, o.direction.value] for o in self.objectives],
            "seed": self.seed,
            "sampler": (sampler or self.sampler).value,
        }
        text = json.dumps(described, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    @property
    def fields(self) -> tuple[str, ...]:
        """The dotted scene fields searched, one per dimension, in order."""
        return tuple(d.field for d in self.dimensions)

    def scene(self, params: Mapping[str, Any]) -> Scene:
        """The trial scene: the base with each searched field at ``params[field]``."""
        return self.base.replace(**dict(params))

    def trial_grid(self, trials: Sequence[Mapping[str, Any]]) -> Grid:
        """The trials as a grid of one zipped sweep, :data:`TRIALS`, one point per trial in order
        (two trials at the same values are two points of one design, computed once)."""
        if not trials:
            raise ValueError("a trial grid needs at least one trial")
        axes = tuple(
            SweepAxis(field, field.split(".")[-1], tuple(t[field] for t in trials))
            for field in self.fields
        )
        return Grid(self.name, self.base, (Sweep(TRIALS, _named(axes), SweepMode.ZIP),))

    def exhaustive_grid(self, per_dimension: int) -> Grid:
        """The space gridded (Cartesian product, :meth:`Dimension.grid_values`): for the
        benchmark's exhaustive front and for what a grid of it would cost."""
        axes = tuple(
            SweepAxis(d.field, d.field.split(".")[-1], d.grid_values(per_dimension))
            for d in self.dimensions
        )
        return Grid(self.name, self.base, (Sweep("grid", _named(axes)),))


def _named(axes: tuple[SweepAxis, ...]) -> tuple[SweepAxis, ...]:
    """Axes whose last field parts clash take their last two parts as dimension names."""
    lasts = [a.field.split(".")[-1] for a in axes]
    return tuple(
        a
        if lasts.count(last) == 1
        else dataclasses.replace(a, dim="_".join(a.field.split(".")[-2:]))
        for a, last in zip(axes, lasts, strict=True)
    )


def load_space(path: str | Path) -> Space:
    """A space TOML file; raise :class:`~pipeline.errors.SceneError` naming the file and every
    problem."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SceneError([f"cannot read file: {exc.strerror}"], str(path), "space") from None
    except UnicodeDecodeError as exc:
        raise SceneError([f"not UTF-8 text (byte {exc.start})"], str(path), "space") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError([f"not valid TOML: {exc}"], str(path), "space") from None
    data.setdefault("name", path.stem)
    return Space.from_dict(data, source=str(path), base_dir=path.parent)


# ---------------------------------------------------------------------------------------------
# Reading and validation


def _read_space(data: Any, base_dir: Path, problems: list[str]) -> Space:
    if not isinstance(data, Mapping):
        problems.append(f"space: must be a table, got {type(data).__name__}")
        return Space("space", Scene(), (), ())
    known = ("name", "base", "seed", "sampler", "space", "objectives")
    for key in data:
        if key not in known:
            problems.append(f"{key}: unknown key (known: {', '.join(known)})")
    name = data.get("name", "space")
    if not _valid_name(name):
        problems.append(f"name: {name!r} is not a valid space name ({NAME_PATTERN})")
        name = "space"
    seed = data.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**32:
        problems.append(f"seed: expected an integer in [0, 2**32), got {seed!r}")
        seed = 0
    try:
        sampler = Sampler(data.get("sampler", Sampler.AUTO.value))
    except ValueError:
        known_samplers = ", ".join(repr(s.value) for s in Sampler)
        problems.append(f"sampler: {data.get('sampler')!r} is not one of {known_samplers}")
        sampler = Sampler.AUTO
    base = _read_base(data.get("base", "paper"), base_dir, problems)
    dims_data = data.get("space")
    if not isinstance(dims_data, Mapping) or not dims_data:
        problems.append(
            'space: needs at least one dimension ("field" = { low, high } or { choices })'
        )
        dims_data = {}
    dimensions = [d for f, v in dims_data.items() if (d := _read_dimension(f, v, problems))]
    _check_against_base(base, dimensions, problems)
    objectives = _read_objectives(data.get("objectives"), base, problems)
    _check_objective_needs(base, dimensions, objectives, problems)
    return Space(name, base, tuple(dimensions), tuple(objectives), seed, sampler)


def _read_dimension(field: str, value: Any, problems: list[str]) -> Dimension | None:
    where = f"space.{field}"
    try:
        slot = fields.resolve(Scene, field).slot
    except fields.UnknownField as exc:
        problems.append(f"space: {exc.text}")
        return None
    if not isinstance(value, Mapping):
        problems.append(
            f"{where}: expected {{ low, high }} or {{ choices = [...] }}, got {value!r}"
        )
        return None
    count = len(problems)
    if "choices" in value:
        extra = sorted(set(value) - {"choices"})
        if extra:
            problems.append(f"{where}: choices take no {', '.join(extra)}")
        choices = value["choices"]
        if not isinstance(choices, list) or len(choices) < 2:
            problems.append(f"{where}.choices: must list at least two values")
            return None
        if not all(isinstance(c, str | int | float) for c in choices):
            problems.append(f"{where}.choices: values must be strings, numbers or booleans")
            return None
        labels = [json.dumps(c, sort_keys=True) for c in choices]
        duplicates = sorted({c for c in labels if labels.count(c) > 1})
        if duplicates:
            problems.append(f"{where}.choices: duplicate values {', '.join(duplicates)}")
        if len(problems) > count:
            return None
        return Dimension(field, DimensionKind.CATEGORICAL, choices=tuple(choices))
    for key in value:
        if key not in ("low", "high", "step", "log"):
            problems.append(f"{where}.{key}: unknown key (known: low, high, step, log, choices)")
    integer = _is_integer(slot.kind)
    numbers = {}
    for key in ("low", "high", "step"):
        number = value.get(key)
        if number is None and key != "step":
            problems.append(f"{where}: needs {key} (or choices)")
        elif number is not None and (
            isinstance(number, bool)
            or not isinstance(number, int | float)
            or not math.isfinite(number)
            or (integer and not isinstance(number, int))
        ):
            kind = "an integer" if integer else "a finite number"
            problems.append(f"{where}.{key}: expected {kind}, got {number!r}")
        else:
            numbers[key] = number
    log = value.get("log", False)
    if not isinstance(log, bool):
        problems.append(f"{where}.log: expected true or false, got {log!r}")
    if not integer and not _is_float(slot.kind):
        problems.append(f"{where}: {field} is not a number; give its choices instead")
    if len(problems) > count:
        return None
    low, high, step = numbers["low"], numbers["high"], numbers.get("step")
    if low >= high:
        problems.append(f"{where}: low ({low}) must be below high ({high})")
    if step is not None and step <= 0:
        problems.append(f"{where}.step: must be > 0, got {step}")
    if log and low <= 0:
        problems.append(f"{where}: a log range needs low > 0, got {low}")
    if log and step is not None and not (integer and step == 1):
        problems.append(f"{where}: a log range takes no step")
    if step is not None and step > 0 and low < high and not _fits_steps(low, high, step):
        problems.append(f"{where}.step: {high} - {low} is not a whole number of steps of {step}")
    if len(problems) > count:
        return None
    if integer:
        kind, step = DimensionKind.INT, step or 1
    else:
        kind = DimensionKind.FLOAT
    return Dimension(field, kind, low, high, None if log and not integer else step, bool(log))


def _fits_steps(low: float, high: float, step: float) -> bool:
    n = (high - low) / step
    return abs(n - round(n)) <= 1e-9 * max(1.0, n)


def _is_integer(kind: Any) -> bool:
    return kind is int or (
        typing.get_origin(kind) in (typing.Union, types.UnionType)
        and int in typing.get_args(kind)
        and float not in typing.get_args(kind)
    )


def _is_float(kind: Any) -> bool:
    return kind is float or (
        typing.get_origin(kind) in (typing.Union, types.UnionType)
        and float in typing.get_args(kind)
    )


def _check_against_base(base: Scene, dimensions: list[Dimension], problems: list[str]) -> None:
    """Every combination of the dimensions' bounds and choices (the corners of the space) must
    make a valid scene, each checked whole with the base's other fields.

    A problem is said once for the values it needs: ``space.<field> = <value>: ...`` when every
    corner with that value has it and no other does (a bound the field refuses),
    ``space at <field> = <value>, ...: ...`` for a combination, ``space at every point: ...``
    when every corner has it; otherwise at each corner that has it.
    """
    if not dimensions:
        return
    extremes = [d.extremes() for d in dimensions]
    axes = [(d.field, e) for d, e in zip(dimensions, extremes, strict=True)]
    variants = SceneVariants(base, axes)
    corners = list(itertools.product(*(range(len(e)) for e in extremes)))
    found: dict[str, list[tuple[int, ...]]] = {}
    for corner in corners:
        for problem in variants.problems(corner):
            found.setdefault(problem, []).append(corner)

    def at(pairs: list[tuple[int, int]]) -> str:
        return ", ".join(f"{dimensions[d].field} = {extremes[d][i]!r}" for d, i in pairs)

    for problem, where in found.items():
        fixed = [
            (d, where[0][d]) for d in range(len(dimensions)) if len({c[d] for c in where}) == 1
        ]
        matching = sum(all(c[d] == i for d, i in fixed) for c in corners)
        if matching != len(where):
            problems += [f"space at {at(list(enumerate(c)))}: {problem}" for c in where]
        elif len(fixed) == 1:
            problems.append(f"space.{at(fixed)}: {problem}")
        else:
            problems.append(f"space at {at(fixed) or 'every point'}: {problem}")


def _read_objectives(data: Any, base: Scene, problems: list[str]) -> list[Objective]:
    if not isinstance(data, Mapping) or not 2 <= len(data) <= 3:
        problems.append('objectives: needs two or three, e.g. "accuracy.ffnn" = "max"')
        return []
    metrics = ", ".join(m.value + (".<model>" if m.per_model else "") for m in Metric)
    objectives = []
    for name, direction in data.items():
        where = f"objectives.{name}"
        metric_name, _, model = name.partition(".")
        try:
            metric = Metric(metric_name)
        except ValueError:
            problems.append(f"{where}: unknown objective (known: {metrics})")
            continue
        try:
            direction = Direction(direction)
        except ValueError:
            problems.append(f"{where}: expected 'max' or 'min', got {direction!r}")
            continue
        if metric.per_model != bool(model):
            problems.append(f"{where}: unknown objective (known: {metrics})")
            continue
        if model:
            trained = [m.value for m in base.training.models]
            if model not in [m.value for m in Model]:
                problems.append(f"{where}: unknown model {model!r} (known: {', '.join(Model)})")
                continue
            if model not in trained:
                problems.append(f"{where}: the base scene trains {', '.join(trained)}, not {model}")
                continue
        objectives.append(Objective(metric, direction, model or None))
    return objectives


def _check_objective_needs(
    base: Scene, dimensions: list[Dimension], objectives: list[Objective], problems: list[str]
) -> None:
    """The area objective needs a mismatch to size for; the yield objective needs chips; the
    early exit's need decoders trained along the touch."""
    searched = [d.field for d in dimensions]
    for objective in objectives:
        where = f"objectives.{objective.name}"
        if objective.metric is Metric.AREA:
            named = MISMATCH_FIELD.rsplit(".", 1)[1] in base.readout.effects
            if not named and not any(f.startswith(MISMATCH_FIELD + ".") for f in searched):
                problems.append(
                    f"{where}: needs {MISMATCH_FIELD} in the base scene or among the searched "
                    "fields (the area is sized for the mismatch a design names)"
                )
        if objective.metric is Metric.YIELD:
            try:
                count = fields.get(base, CHIPS_COUNT_FIELD)
            except (fields.UnknownField, AttributeError, KeyError):
                count = 1
            if not (isinstance(count, int) and count > 1) and CHIPS_COUNT_FIELD not in searched:
                problems.append(
                    f"{where}: needs {CHIPS_COUNT_FIELD} above 1 in the base scene or among the "
                    "searched fields (a yield is taken over chips)"
                )
        along = base.training.decisions is DecisionTraining.ALONG_TOUCH
        if objective.metric in _EARLY_EXIT and not along and DECISIONS_FIELD not in searched:
            problems.append(
                f'{where}: needs {DECISIONS_FIELD} = "along_touch" in the base scene or among the '
                "searched fields (decoders trained for the full touch decide late when read early)"
            )
