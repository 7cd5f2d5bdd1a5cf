"""Declared fields: each field of a frozen value object states once what it is, and the rest
follows.

A field is declared with :func:`param` (a leaf value) or :func:`part` (a nested value object,
read as a table of its own). A leaf declares, next to its dataclass annotation (its type) and
default: its CF ``units`` ("1" when dimensionless or a label), a prose ``long_name``, the range it
must lie ``within``, whether its default is *neutral*, whether it is a *label*, what it does to a
point's *cost*, and for a table of named entries (the readout's effects) the type of each entry.
From that one declaration:

* :func:`read` builds a value object from a nested dict (the TOML layout), checking unknown
  keys, types and ranges and collecting every problem as ``"<dotted field>: <what>"``; a class
  may add checks that involve several of its fields with a method ``refusals(self)`` yielding
  ``(field name, text)`` pairs;
* :func:`plain` writes it back as a plain nested dict, or as its *canonical form*, which leaves
  out every field at a neutral default: a field added with a default that reproduces what was
  done before it existed is not in the canonical form of any existing scene, and so changes no
  cache key; a part declared ``only_when`` (the parameters of one option of an enum) is left
  out while its option is not chosen;
* :func:`resolve`, :func:`get`, :func:`put`, :func:`select` and :func:`flatten` walk dotted
  paths (``"readout.effects.amplifier_noise.sigma_v"``) through the declaration, a value object
  or a plain dict;
* :func:`cost_parts` tells what the cost of computing a value depends on;
* :func:`listing` lists every field (entries' parameters included) with its type, default,
  units, range and description, for ``--help`` and the documentation.

``None`` stands for "the default applies" (TOML has no null): a field holding ``None`` is left
out of both plain forms.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import json
import math
import types
import typing
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Literal, NewType

#: An integer seed, ``0 <= seed < 2**63``.
Seed = NewType("Seed", int)


# ---------------------------------------------------------------------------------------------
# Declarations


@dataclass(frozen=True)
class Range:
    """Accepted values of a number: ``low`` and/or ``high`` bounds, each open or closed, plus
    the literal values ``also`` (e.g. ``("auto",)``)."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    also: tuple[str, ...] = ()

    def holds(self, value: Any) -> bool:
        """Whether the number ``value`` (or literal) is accepted: one of ``also`` or within the
        bounds."""
        if value in self.also:
            return True
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            return False
        return self.high is None or (value < self.high if self.high_open else value <= self.high)

    def text(self, units: str) -> str:
        """The requirement in words, e.g. ``"> 0 V"``, ``"between 1 and 1000"``."""
        unit = "" if units == "1" else f" {units}"
        low, high = _number(self.low), _number(self.high)
        if self.high is None:
            words = f"{'>' if self.low_open else '>='} {low}{unit}"
        elif self.low is None:
            words = f"{'<' if self.high_open else '<='} {high}{unit}"
        elif not (self.low_open or self.high_open):
            words = f"between {low} and {high}{unit}"
        else:
            left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
            words = f"in {left}{low}, {high}{right}{unit}"
        return " or ".join([*(repr(v) for v in self.also), words])


#: The range of numbers above 0.
POSITIVE = Range(0, low_open=True)
#: The range of numbers from 0 up.
NONNEGATIVE = Range(0)


@dataclass(frozen=True)
class NonEmpty:
    """Accepted values of a list: any but the empty one."""

    def holds(self, value: Any) -> bool:
        """Whether the list ``value`` has at least one item."""
        return len(value) > 0

    def text(self, units: str) -> str:
        """The requirement in words: ``"a non-empty list"`` (``units`` is not used)."""
        return "a non-empty list"


class Cost(enum.Enum):
    """What a field's value does to the cost of computing a point."""

    KIND = "kind"  # points that differ in it cost differently (a dataset, a model's epochs)
    FREE = "free"  # its value does not change the cost (a threshold, a seed, an effect strength)
    SIZE = "size"  # the cost grows in proportion to it (taxel rows, windows, models trained)


@dataclass(frozen=True)
class Declared:
    """What :func:`param` declares of a leaf field (see the module docstring)."""

    units: str
    long_name: str
    within: Range | NonEmpty | None = None
    neutral: bool = False
    label: bool = False
    cost: Cost = Cost.KIND
    entries: Mapping[Any, type] | None = None
    formerly: tuple[Any, ...] = ()


_DECLARED = "declared"


def param(
    default: Any = dataclasses.MISSING,
    units: str = "1",
    long_name: str = "",
    *,
    default_factory: Callable[[], Any] | Any = dataclasses.MISSING,
    within: Range | NonEmpty | None = None,
    neutral: bool | None = None,
    label: bool = False,
    cost: Cost = Cost.KIND,
    entries: Mapping[Any, type] | None = None,
    formerly: Any = dataclasses.MISSING,
) -> Any:
    """A dataclass field with its declaration.

    Parameters
    ----------
    default, default_factory
        As for ``dataclasses.field``.
    units, long_name
        CF units ("1" when dimensionless or a label) and a prose name; result cubes write them
        on every coordinate the field becomes.
    within
        The values it accepts (checked when read), or None for any value of its type.
    neutral
        Whether the default is *neutral*: a value equal to it is left out of the canonical form
        (and so of every cache key). Give a new field a neutral default that reproduces what was
        done without it, and no existing key changes. Default: only a ``None`` default.
    label
        A name, not part of what is simulated: left out of the canonical form, of result cubes'
        coordinates, and not a field a sweep can vary.
    cost
        What its value does to the cost of a point (:class:`Cost`).
    entries
        For a table of named entries (a mapping field): the type of each entry by its key, an
        enum member (e.g. ``Effect``); each entry is read as a table of that type.
    formerly
        For a field whose default is not what was done before it existed: the value that
        reproduces that, left out of the canonical form as a neutral default is, so a scene
        that sets it keeps its key (a scene at the new default gets a new one).
    """
    declared = Declared(
        units=units,
        long_name=long_name,
        within=within,
        neutral=default is None if neutral is None else neutral,
        label=label,
        cost=cost,
        entries=entries,
        formerly=() if formerly is dataclasses.MISSING else (formerly,),
    )
    metadata = {_DECLARED: declared}
    if default_factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=default_factory, metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


_ONLY_WHEN = "only_when"


def part(cls: type, *, only_when: tuple[str, Any] | None = None) -> Any:
    """A dataclass field holding a nested value object of type ``cls``, read as its own table.

    ``only_when=(name, value)``: the part matters only while the sibling field ``name`` holds
    ``value`` (the parameters of one option of an enum), or holds it among others when ``name``
    is a list of options (the parameters of one of the models trained), so the canonical form
    leaves it out otherwise, and a value that does not use it keeps the key it had before the
    part existed.
    """
    metadata = {} if only_when is None else {_ONLY_WHEN: only_when}
    return dataclasses.field(default_factory=cls, metadata=metadata)


@dataclass(frozen=True)
class Slot:
    """One field of a declared class: its ``name``, its resolved annotation ``kind``
    (``float``, ``int | Literal["auto"]``, an enum, ...), its ``default`` (made by the default
    factory, if it has one), the dataclass ``field`` whose metadata holds its declaration, and
    for a :func:`part` the nested class ``part``."""

    name: str
    kind: Any
    default: Any
    field: dataclasses.Field
    part: type | None

    @property
    def declared(self) -> Declared | None:
        """The field's declaration; None for a :func:`part`."""
        return self.field.metadata.get(_DECLARED)

    @property
    def convert(self) -> Callable[[Any], Any]:
        """The reader of the field's values, from a value as given in a TOML table or dict to
        the value of ``kind``; it raises TypeError or ValueError, with a message, for one it
        refuses."""
        return _converter(self.kind)

    @property
    def only_when(self) -> tuple[str, Any] | None:
        """The sibling field and the value under which a :func:`part` declared ``only_when``
        matters; None for any other field."""
        return self.field.metadata.get(_ONLY_WHEN)


@functools.cache
def slots(cls: type) -> tuple[Slot, ...]:
    """The fields of declared class ``cls``, in declaration order."""
    hints = typing.get_type_hints(cls)
    found = []
    for f in dataclasses.fields(cls):
        if f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = f.default
        declared = f.metadata.get(_DECLARED)
        nested = hints[f.name] if declared is None else None
        if nested is not None and not dataclasses.is_dataclass(nested):
            raise TypeError(f"{cls.__name__}.{f.name} is neither a param() nor a part()")
        found.append(Slot(f.name, hints[f.name], default, f, nested))
    return tuple(found)


@functools.cache
def slot_named(cls: type) -> dict[str, Slot]:
    """The fields of declared class ``cls`` by name."""
    return {slot.name: slot for slot in slots(cls)}


# ---------------------------------------------------------------------------------------------
# Dotted paths


class UnknownField(KeyError):
    """A dotted path names no declared field; ``text`` says which part is wrong."""

    def __init__(self, text: str):
        super().__init__(text)
        self.text = text

    def __str__(self) -> str:
        return self.text


@dataclass(frozen=True)
class Resolved:
    """What a dotted path names: a leaf field (``slot``; a table of entries is one), or one
    whole entry of a table (``entry``, its key, with ``slot`` the table's field)."""

    path: str
    slot: Slot
    entry: Any = None

    @property
    def units(self) -> str:
        """CF units of the field; ``"1"`` for a whole entry."""
        return "1" if self.declared is None else self.declared.units

    @property
    def long_name(self) -> str:
        """Prose name of the field, or of a whole entry (``"parameters of the ... effect"``)."""
        if self.entry is not None:
            return f"parameters of the {self.entry.value} {_noun(type(self.entry))}"
        return "" if self.declared is None else self.declared.long_name

    @property
    def declared(self) -> Declared | None:
        """The leaf field's declaration; None for a whole entry."""
        return None if self.entry is not None else self.slot.declared


def resolve(root: type, path: str) -> Resolved:
    """The field of ``root`` (a declared class) that dotted ``path`` names.

    Raises
    ------
    UnknownField
        No leaf field of ``root`` has that path (a whole part is not one); the text names the
        path and what is known there. Label fields (:func:`param` ``label=True``) are not
        fields here.
    """
    names = path.split(".")
    unknown = f"{path!r} is not a {_noun(root)} field"
    cls, i = root, 0
    while True:
        known = slot_named(cls)
        slot = known.get(names[i])
        if slot is None or (slot.declared is not None and slot.declared.label):
            if i != 1:
                raise UnknownField(unknown)
            raise UnknownField(f"{unknown} (known in {names[0]}: {', '.join(sorted(known))})")
        if slot.part is not None and i == len(names) - 1:
            listed = ", ".join(sorted(slot_named(slot.part)))
            raise UnknownField(f"{unknown} (known in {path}: {listed})")
        if i == len(names) - 1:
            return Resolved(path, slot)
        if slot.part is not None:
            cls, i = slot.part, i + 1
            continue
        entries = slot.declared.entries if slot.declared is not None else None
        if entries is None:
            raise UnknownField(unknown)
        key_type = type(next(iter(entries)))
        try:
            key = key_type(names[i + 1])
        except ValueError:
            raise UnknownField(f"{path!r} names an unknown {_noun(key_type)}") from None
        if i + 1 == len(names) - 1:
            return Resolved(path, slot, key)
        params = slot_named(entries[key])
        if i + 2 != len(names) - 1 or names[i + 2] not in params:
            raise UnknownField(
                f"{path!r} is not a parameter of {key.value} (known: {', '.join(sorted(params))})"
            )
        return Resolved(path, params[names[i + 2]])


def get(value: Any, path: str) -> Any:
    """The value at dotted ``path`` in a value object or a plain nested dict.

    Raises
    ------
    KeyError, AttributeError
        Nothing is there (an entry the table does not hold, a field left out of a dict).
    """
    for name in path.split("."):
        value = value[name] if isinstance(value, Mapping) else getattr(value, name)
    return value


def put(data: dict[str, Any], path: str, value: Any) -> None:
    """Set dotted ``path`` of plain nested dict ``data`` to ``value``, making missing tables."""
    *parents, leaf = path.split(".")
    for name in parents:
        data = data.setdefault(name, {})
    data[leaf] = value


def select(data: Mapping[str, Any], paths: Iterable[str]) -> dict[str, Any]:
    """The dotted ``paths`` of plain nested dict ``data``, nested as in ``data``; a path that is
    not there (a field left out of a plain form) is left out."""
    selected: dict[str, Any] = {}
    for path in paths:
        try:
            put(selected, path, get(data, path))
        except KeyError:
            continue
    return selected


def flatten(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """A plain nested dict by dotted path: ``{"array": {"rows": 3}}`` as ``{"array.rows": 3}``;
    an empty table is a leaf."""
    flat: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, Mapping) and value:
            flat |= flatten(value, f"{prefix}{key}.")
        else:
            flat[f"{prefix}{key}"] = value
    return flat


@dataclass(frozen=True)
class FieldInfo:
    """One line of :func:`listing`: a field by dotted ``path`` and what it declares."""

    path: str
    type: str
    default: Any
    units: str
    range: str
    description: str
    neutral: bool
    cost: Cost

    def text(self) -> str:
        """One line for ``--help`` and the docs, e.g. ``readout.threshold_v: float = 0.09 V
        (> 0 V), comparator threshold (level-crossing step)``."""
        default = "" if self.default is None else f" = {json.dumps(self.default)}"
        unit = "" if self.units == "1" or self.default is None else f" {self.units}"
        within = f" ({self.range})" if self.range else ""
        return f"{self.path}: {self.type}{default}{unit}{within}, {self.description}"


def listing(root: type) -> list[FieldInfo]:
    """Every leaf field of declared class ``root``, entries' parameters included (as
    ``<table>.<entry>.<parameter>``), in declaration order; label fields left out.

    ``default`` is the plain value (enums as strings, tuples as lists); ``range`` is "" where
    any value of the type is accepted.
    """
    found: list[FieldInfo] = []
    for path, slot, d in _leaves(root, ""):
        found.append(
            FieldInfo(
                path=path,
                type=_type_text(slot.kind),
                default=plain(slot.default),
                units=d.units,
                range="" if d.within is None else d.within.text(d.units),
                description=d.long_name,
                neutral=d.neutral,
                cost=d.cost,
            )
        )
    return found


def _leaves(cls: type, prefix: str) -> Iterator[tuple[str, Slot, Declared]]:
    for slot in slots(cls):
        path, declared = f"{prefix}{slot.name}", slot.declared
        if slot.part is not None:
            yield from _leaves(slot.part, f"{path}.")
        elif declared is not None and not declared.label:
            if declared.entries is None:
                yield path, slot, declared
            for key, entry in (declared.entries or {}).items():
                yield from _leaves(entry, f"{path}.{key.value}.")


# ---------------------------------------------------------------------------------------------
# Plain and canonical forms


def part_applies(owner: Any, name: str) -> bool:
    """Whether part ``name`` of value object ``owner`` matters: always, unless it is declared
    ``only_when`` its sibling field holds a value (or, for a list of options, lists it) that the
    sibling does not hold now. Checks of a part's own values ask this, so that they follow the
    declaration instead of naming the option."""
    only_when = slot_named(type(owner))[name].only_when
    if only_when is None:
        return True
    chosen = getattr(owner, only_when[0])
    if isinstance(chosen, tuple):  # a list of options (the models): is the value among them
        return only_when[1] in chosen
    return chosen == only_when[1]


def left_out(slot: Slot, value: Any, canonical: bool, owner: Any = None) -> bool:
    """Whether field ``slot`` of value object ``owner`` holding ``value`` is left out of a plain
    form: when ``None``, and in the canonical form when at a neutral default or its
    ``formerly`` value or, for a part declared ``only_when``, when its sibling field does not
    hold that value."""
    if value is None:
        return True
    if not canonical:
        return False
    declared, only_when = slot.declared, slot.only_when
    if only_when is not None and owner is not None:
        return not part_applies(owner, slot.name)
    if declared is None:
        return False
    return (declared.neutral and value == slot.default) or value in declared.formerly


def plain(value: Any, canonical: bool = False) -> Any:
    """``value`` as plain JSON-able data: value objects as dicts of their fields (``None``
    left out), enums as their values, tuples as lists, mapping keys as strings.

    With ``canonical``, a field at a neutral default is left out too (:func:`param`).
    """
    if dataclasses.is_dataclass(value):
        data = {}
        for slot in slots(type(value)):
            v = getattr(value, slot.name)
            if not left_out(slot, v, canonical, value):
                data[slot.name] = plain(v, canonical)
        return data
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, Mapping):
        return {str(plain(k)): plain(v, canonical) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [plain(v, canonical) for v in value]
    return value


def cost_parts(value: Any) -> tuple[Any, list[Any]]:
    """What the cost of computing value object ``value`` depends on, from the declarations
    (:class:`Cost`): its plain form without the fields declared free (nor labels), and the
    values of the fields its cost grows with, in declaration order (parts walked in)."""
    sizes: list[Any] = []

    def walk(value: Any) -> Any:
        if dataclasses.is_dataclass(value):
            data = {}
            for slot in slots(type(value)):
                declared, v = slot.declared, getattr(value, slot.name)
                if declared is not None and (declared.label or declared.cost is Cost.FREE):
                    continue
                if slot.only_when is not None and left_out(slot, v, True, value):
                    continue  # the parameters of an option not chosen cost nothing
                if declared is not None and declared.cost is Cost.SIZE:
                    sizes.append(v)
                if v is not None:
                    data[slot.name] = walk(v)
            return data
        if isinstance(value, Mapping):
            return {str(plain(k)): walk(v) for k, v in value.items()}
        return plain(value)

    return walk(value), sizes


# ---------------------------------------------------------------------------------------------
# Reading


def read(cls: type, data: Any, where: str, problems: list[str]) -> Any:
    """Build declared class ``cls`` from table ``data`` (the TOML layout) at ``where``.

    Unknown keys, types and ranges are checked and every problem is appended to ``problems``
    as ``"<dotted field>: <what>"``; a field with a problem keeps its default, so that the
    object is always built and later checks still run. Nested parts are read (and reported)
    before the leaves of ``cls``, then the class's own ``refusals``.
    """
    table = _table(data, where or "scene", problems)
    for key in table:
        if key not in slot_named(cls):
            names = ", ".join(s.name for s in slots(cls))
            problems.append(f"{_join(where, key)}: unknown key (known: {names})")
    values: dict[str, Any] = {}
    for slot in read_order(cls):
        if slot.part is None and slot.name not in table:
            continue
        values[slot.name] = read_slot(slot, table.get(slot.name), _join(where, slot.name), problems)
    built = cls(**values)
    refusals = getattr(built, "refusals", None)
    if refusals is not None:
        problems.extend(f"{_join(where, name)}: {text}" for name, text in refusals())
    return built


@functools.cache
def read_order(cls: type) -> tuple[Slot, ...]:
    """The fields of ``cls`` in the order :func:`read` reads (and reports) them: its parts,
    then its leaves, each in declaration order."""
    return tuple(sorted(slots(cls), key=lambda s: s.part is None))


def read_slot(slot: Slot, raw: Any, where: str, problems: list[str]) -> Any:
    """Field ``slot`` read from ``raw`` at ``where``: its value, or its default with the
    problems appended to ``problems``."""
    declared = slot.declared
    if declared is None:  # a part
        return read(slot.part, raw, where, problems)
    if declared.entries is not None:
        return _read_entries(declared.entries, raw, where, problems)
    try:
        value = slot.convert(raw)
    except (TypeError, ValueError) as exc:
        problems.append(f"{where}: {exc or f'invalid value {raw!r}'}")
        return slot.default
    within = declared.within
    if within is not None and value is not None and not within.holds(value):
        problems.append(f"{where}: {raw!r} is out of range: must be {within.text(declared.units)}")
        return slot.default
    return value


def _read_entries(
    entries: Mapping[Any, type], data: Any, where: str, problems: list[str]
) -> dict[Any, Any]:
    key_type = type(next(iter(entries)))
    found = {}
    for name, params in _table(data, where, problems).items():
        here = _join(where, name)
        try:
            key = key_type(name)
        except ValueError:
            known = ", ".join(k.value for k in entries)
            problems.append(f"{here}: unknown {_noun(key_type)} (known: {known})")
            continue
        found[key] = read(entries[key], params, here, problems)
    return dict(sorted(found.items()))


def _table(data: Any, where: str, problems: list[str]) -> Mapping[str, Any]:
    if data is None:
        return {}
    if not isinstance(data, Mapping):
        problems.append(f"{where}: must be a table, got {type(data).__name__}")
        return {}
    return data


def _join(*parts: str) -> str:
    return ".".join(p for p in parts if p)


def _noun(kind: type) -> str:
    """``Effect`` -> ``"effect"``."""
    return kind.__name__.lower()


def _number(value: float | None) -> str:
    if value is not None and float(value).is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


# -- converters: the raw value as the annotation's type ----------------------------------------


@functools.cache
def _converter(kind: Any) -> Callable[[Any], Any]:
    if kind is float:
        return _float
    if kind is int:
        return _int
    if kind is str:
        return _string
    if kind is Seed:
        return _seed
    if isinstance(kind, type) and issubclass(kind, enum.StrEnum):
        return _enum(kind)
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if origin in (typing.Union, types.UnionType):
        literals = tuple(v for a in args if typing.get_origin(a) is Literal for v in a.__args__)
        rest = [a for a in args if typing.get_origin(a) is not Literal and a is not type(None)]
        (inner,) = rest
        convert = _converter(inner)
        if type(None) in args:
            return lambda v: None if v is None else convert(v)
        return lambda v: v if isinstance(v, str) and v in literals else convert(v)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        return _list_of_distinct(args[0])
    raise TypeError(f"no reader for fields of type {kind!r}")


def _type_text(kind: Any) -> str:
    """The type of a field in words, for :func:`listing`."""
    if kind is Seed:
        return "int in [0, 2**63)"
    if isinstance(kind, type) and issubclass(kind, enum.StrEnum):
        return " | ".join(repr(m.value) for m in kind)
    if isinstance(kind, type):
        return kind.__name__
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if origin is Literal:
        return " | ".join(repr(a) for a in args)
    if origin in (typing.Union, types.UnionType):
        texts = [_type_text(a) for a in args if a is not type(None)]
        return " | ".join(texts) + (" (optional)" if type(None) in args else "")
    if origin is tuple:
        return f"list of {_type_text(args[0])}"
    if isinstance(origin, type) and issubclass(origin, Mapping):
        return "table"
    return str(kind)


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


def _enum(kind: type[enum.StrEnum]) -> Callable[[Any], Any]:
    def convert(value: Any) -> Any:
        try:
            return kind(value)
        except ValueError:
            options = ", ".join(repr(m.value) for m in kind)
            raise ValueError(f"{value!r} is not one of {options}") from None

    return convert


def _list_of_distinct(item: Any) -> Callable[[Any], tuple[Any, ...]]:
    convert = _converter(item)
    noun = _noun(item) if isinstance(item, type) else "item"

    def convert_list(value: Any) -> tuple[Any, ...]:
        if isinstance(value, str) or not isinstance(value, list | tuple):
            raise TypeError(f"expected a list of {noun} names, got {value!r}")
        items = tuple(convert(v) for v in value)
        if len(set(items)) != len(items):
            raise ValueError(f"duplicate {noun} in {list(value)!r}")
        return items

    return convert_list
