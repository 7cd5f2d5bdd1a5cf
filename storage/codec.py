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
    values = {}
    for name, (dims, array, _) in record.variables.items():
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
