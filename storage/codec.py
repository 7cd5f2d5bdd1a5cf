"""Entries as batch records, by their declaration alone.

A kind of entry is declared by whoever computes it (a stored level of the stage registry hands
its record declaration to the store); this module knows no kind by name. A declaration has:

``name``
    the kind (the group its batches live in);
``entry_type``
    the type of its entries;
``variables``
    each with ``name``, ``dims`` (entry-level), ``dtype`` (a numpy dtype name, or ``"str"``),
    ``units``, ``long_name`` and ``optional``;
``encode(entry) -> (values, attrs)`` and ``decode(values, attrs) -> entry``
    between an entry and its named arrays plus JSON attributes.

A variable may also declare ``ticks`` (``resolution_s``, ``runs``, ``sign``): event times, kept
compactly as an address-event chip sends them. Their values must be whole ticks,
``t = k * resolution_s`` (float64 product) with ``k`` non-decreasing within each train (the
consecutive runs whose lengths are the variable ``runs``, C order); the store keeps one
``uint32`` per event, ``2 * (k - k_before) + (sign > 0)`` (``k_before``: the previous event's
tick in its train, 0 for its first), under the times variable's name, and not the ``+-1``
variable ``sign`` apart. Its attributes say so (``ticks_s``, ``ticks_runs``, ``ticks_sign``),
so any Zarr reader rebuilds the times with a cumulative sum per train. Reading gives back the
very float64 times and int8 signs written (checked on write: a time that is not a whole tick,
a sign that is not +-1 or a gap of more than ``2**31 - 1`` ticks is refused).

Writing casts every array to its declared dtype (little-endian; never across kinds, never an
integer that changes value), checks its number of dims, refuses undeclared and missing
variables and attributes that JSON cannot hold (NaN, infinities), and writes the declared
``units`` and ``long_name`` beside the values. Reading checks each array's dims and dtype
against the declaration before decoding; strings come back as numpy ``<U`` arrays.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from storage.batches import BatchEntry, Variables


class DeclaredVariable(Protocol):
    """What the store needs of one declared variable of a kind (see the module docstring).

    ``name`` is its name in the entry and in the batch, ``dims`` its entry-level dimension names
    (``()`` for a scalar), ``dtype`` a numpy dtype name or ``"str"``, ``units`` and
    ``long_name`` the attributes written beside its values, and ``optional`` whether an entry
    may lack it.
    """

    name: str
    dims: tuple[str, ...]
    dtype: str
    units: str
    long_name: str
    optional: bool
    ticks: DeclaredTicks | None


class DeclaredTicks(Protocol):
    """How event times are kept (see the module docstring): the resolution (s), the name of the
    variable holding each train's length and of the +-1 variable folded into the low bit."""

    resolution_s: float
    runs: str
    sign: str


class Declaration(Protocol):
    """What the store needs of a kind of entry (see the module docstring)."""

    name: str
    entry_type: type
    variables: Sequence[DeclaredVariable]
    encode: Callable[[Any], tuple[Mapping[str, Any], Mapping[str, Any]]]
    decode: Callable[[Mapping[str, np.ndarray], Mapping[str, Any]], Any]


def to_record(kind: Declaration, key: str, entry: Any) -> BatchEntry:
    """``entry`` of ``kind`` as a batch record, checked against its declaration.

    Raises
    ------
    TypeError
        ``entry`` is not of the kind's entry type.
    ValueError
        As ``kind.encode`` raises; a value that does not fit its declared dtype or dims; an
        undeclared or missing variable; attributes JSON cannot hold.
    """
    if not isinstance(entry, kind.entry_type):
        raise TypeError(
            f"a {kind.name} entry must be a {kind.entry_type.__name__}, got {type(entry)}"
        )
    values, attrs = kind.encode(entry)
    declared = {variable.name: variable for variable in kind.variables}
    undeclared = sorted(set(values) - set(declared))
    if undeclared:
        raise ValueError(f"{kind.name} entry: undeclared variables {undeclared}")
    missing = sorted(n for n, v in declared.items() if not v.optional and n not in values)
    if missing:
        raise ValueError(f"{kind.name} entry: missing variables {missing}")
    variables: Variables = {}
    for name, value in values.items():
        variable = declared[name]
        array = _cast(value, variable.dtype, name)
        if array.ndim != len(variable.dims):
            raise ValueError(f"{name}: {array.ndim} dimensions, declared {variable.dims}")
        variables[name] = (
            tuple(variable.dims),
            array,
            {"units": variable.units, "long_name": variable.long_name},
        )
    for variable in kind.variables:
        if variable.ticks is not None and variable.name in variables:
            _fold_ticks(variables, variable.name, variable.ticks)
    try:
        json.dumps(attrs, allow_nan=False)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{kind.name} entry: attributes JSON cannot hold: {error}") from error
    return BatchEntry(key, variables, dict(attrs))


def from_record(kind: Declaration, record: BatchEntry) -> Any:
    """The entry a batch record holds, its arrays checked against ``kind``'s declaration.

    Raises
    ------
    TypeError, ValueError, KeyError
        The record does not match the declaration, or ``kind.decode`` refuses it.
    """
    declared = {variable.name: variable for variable in kind.variables}
    stored = dict(record.variables)
    for variable in kind.variables:
        if variable.ticks is not None and variable.name in stored:
            _unfold_ticks(stored, variable, declared[variable.ticks.sign])
    values = {}
    for name, (dims, array, _) in stored.items():
        if name not in declared:
            raise ValueError(f"undeclared variable {name!r}")
        variable = declared[name]
        if variable.dtype == "str":
            if array.dtype.kind not in "OTU" or tuple(dims) != tuple(variable.dims):
                raise TypeError(f"variable {name!r} is {array.dtype} {dims}, not strings")
            array = as_strings(array)
        elif tuple(dims) != tuple(variable.dims) or array.dtype != np.dtype(variable.dtype):
            raise TypeError(f"variable {name!r} is {array.dtype} {dims}, not {variable.dims}")
        values[name] = np.asarray(array)
    missing = sorted(n for n, v in declared.items() if not v.optional and n not in values)
    if missing:
        raise ValueError(f"missing variables {missing}")
    return kind.decode(values, record.attrs)


def as_strings(values: np.ndarray) -> np.ndarray:
    """Object or StringDType strings as a numpy ``<U`` array."""
    return np.array([str(v) for v in np.asarray(values).ravel().tolist()], dtype=str).reshape(
        np.shape(values)
    )


def _cast(value: Any, dtype: str, what: str) -> np.ndarray:
    """``value`` as a contiguous little-endian ``dtype`` array (strings as objects).

    Refuses casts across kinds (float to int) and integer casts that change values.
    """
    array = np.asarray(value)
    if dtype == "str":
        if array.dtype.kind not in "OTU" or not all(
            isinstance(v, str) for v in array.ravel().tolist()
        ):
            raise ValueError(f"{what}: cannot store {array.dtype} values as strings")
        return array.astype(object)  # Zarr v3 stores these as its ``string`` type
    target = np.dtype(dtype).newbyteorder("<")
    if not np.can_cast(array.dtype, target, "same_kind"):
        raise ValueError(f"{what}: cannot store {array.dtype} values as {target}")
    cast = np.asarray(array, dtype=target, order="C")  # keeps 0-d arrays 0-d
    if target.kind in "iu" and not np.array_equal(cast, array):
        raise ValueError(f"{what}: values do not fit {target}")
    return cast


#: How folded tick deltas are stored, one bit of sign and 31 of delta.
TICKS_DTYPE = np.dtype("<u4")


def _fold_ticks(variables: Variables, name: str, ticks: DeclaredTicks) -> None:
    """Replace the times ``name`` and their sign by one array of folded tick deltas."""
    dims, times, attrs = variables[name]
    if ticks.runs not in variables or ticks.sign not in variables:
        raise ValueError(f"{name}: stored as ticks, it needs {ticks.runs} and {ticks.sign}")
    _, sign, _ = variables.pop(ticks.sign)
    runs = variables[ticks.runs][1].ravel()
    if sign.shape != times.shape or (runs < 0).any() or int(runs.sum()) != times.size:
        raise ValueError(f"{name}: {ticks.sign} and {ticks.runs} do not match its events")
    if not np.isin(sign, (-1, 1)).all():
        raise ValueError(f"{name}: {ticks.sign} holds values other than -1 and +1")
    tick = np.rint(times / ticks.resolution_s)
    if not np.array_equal(tick * ticks.resolution_s, times) or (tick < 0).any():
        raise ValueError(f"{name}: times are not whole ticks of {ticks.resolution_s} s")
    delta = np.diff(tick.astype(np.int64), prepend=0)
    first = (np.cumsum(runs) - runs)[runs > 0]
    delta[first] = tick[first]
    if (delta < 0).any():
        raise ValueError(f"{name}: times decrease within a train")
    if delta.size and int(delta.max()) > (int(np.iinfo(TICKS_DTYPE).max) >> 1):
        raise ValueError(f"{name}: a gap of more than 2**31 - 1 ticks does not fit {TICKS_DTYPE}")
    folded = (delta.astype(TICKS_DTYPE) << 1) | (sign > 0)
    about = {
        "units": "1",
        "long_name": f"{attrs['long_name']}: 2 * ticks since the train's last + ({ticks.sign} > 0)",
        "ticks_s": ticks.resolution_s,
        "ticks_runs": ticks.runs,
        "ticks_sign": ticks.sign,
    }
    variables[name] = (dims, folded, about)


def _unfold_ticks(variables: Variables, variable: DeclaredVariable, sign: DeclaredVariable) -> None:
    """The inverse of :func:`_fold_ticks`: the float64 times and int8 signs, from the stored
    folded deltas and the runs."""
    ticks = variable.ticks
    dims, folded, _ = variables[variable.name]
    if folded.dtype != TICKS_DTYPE or ticks.runs not in variables:
        raise TypeError(f"variable {variable.name!r} is not folded {TICKS_DTYPE} tick deltas")
    runs = variables[ticks.runs][1].ravel()
    if (runs < 0).any() or int(runs.sum()) != folded.size:
        raise ValueError(f"{ticks.runs} does not match {variable.name}")
    # One running sum over all trains, each train's first delta less the previous train's last
    # tick, in place: a chip study reads tens of millions of events per entry.
    tick = (folded >> 1).astype(np.int64)
    first = (np.cumsum(runs) - runs)[runs > 0]
    if first.size > 1:
        tick[first[1:]] -= np.add.reduceat(tick, first)[:-1]
    np.cumsum(tick, out=tick)
    times = tick * ticks.resolution_s
    signs = (folded & 1).astype(np.dtype(sign.dtype))
    signs *= 2
    signs -= 1
    variables[variable.name] = (dims, times, {})
    variables[sign.name] = (dims, signs, {})
