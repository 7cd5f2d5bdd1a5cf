"""Batches: many cache entries of one kind packed into one Zarr group, written once.

A sweep of 100,000 points cannot afford a group of small arrays per entry (each array is a
metadata file and a chunk file: about 60 files per point, which no shared file system of a
cluster enjoys). A batch holds the entries one task made, stacked variable by variable:

``<kind>/batch-<32 hex>/``, a Zarr v3 group, attrs::

    eskin_batch   the kind of its entries ("spikes", "results")
    entries       [{"key": str, "attrs": {...}, "shapes": {variable: [n, ...]}}, ...]
    sha256        {variable: hex digest of the stored array, "@entries": digest of ``entries``}

and one 1-D array per variable name, ``<variable>`` on dimension ``flat_<variable>``: the
C-order values of every entry that has the variable, one after the other, in the order of
``entries``. Entry ``i``'s values are the next ``prod(shapes[variable])`` of them (a 0-d value is
one), reshaped; an entry without the variable has no ``shapes`` item for it. The array's attrs
hold the entry-level ``dims`` (e.g. ``["recording", "taxel"]``) and whatever else the entry
declared (``units``, ``long_name``).

The number of files of a batch grows with its variables (about two per variable plus one),
not with its entries. A batch is written under a partial name and renamed into place, like
an entry before it, and read whole: its digests cover whole arrays.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from zarr.abc.store import Store
from zarr.codecs import BloscCodec

#: One entry's variables: name -> (entry-level dims, values, attrs).
Variables = dict[str, tuple[tuple[str, ...], np.ndarray, dict[str, str]]]

BATCH_PREFIX = "batch-"
FLAT_PREFIX = "flat_"
# Chunks of at most this many bytes: big spike batches are read in parts, small ones in one.
CHUNK_BYTES = 64 * 2**20
_TO_ZARR = {"consolidated": False, "zarr_format": 3, "write_empty_chunks": True}
_OPEN_ZARR = {"consolidated": False, "zarr_format": 3, "chunks": None, "decode_cf": False}


@dataclass(frozen=True)
class BatchEntry:
    """One entry as a batch stores it: its key, its variables and its JSON attributes."""

    key: str
    variables: Variables
    attrs: dict[str, Any]


class BatchError(ValueError):
    """A batch's data or metadata is inconsistent (corrupt): its message says what."""


def write_batch(path: Path | Store, kind: str, records: Sequence[BatchEntry]) -> None:
    """Write ``records`` as one batch group at ``path`` (a folder or a Zarr store; empty).

    Raises
    ------
    ValueError
        No record, or a variable with different dims or dtypes in two records.
    """
    if not records:
        raise ValueError("a batch needs at least one entry")
    pieces: dict[str, list[np.ndarray]] = {}
    about: dict[str, tuple[tuple[str, ...], np.dtype, dict[str, str]]] = {}
    entries = []
    for record in records:
        shapes = {}
        for name, (dims, values, attrs) in record.variables.items():
            values = np.asarray(values)
            if len(dims) != values.ndim:
                raise ValueError(f"{name}: dims {dims} do not match shape {values.shape}")
            known = about.setdefault(name, (tuple(dims), values.dtype, dict(attrs)))
            if known[0] != tuple(dims) or known[1] != values.dtype:
                raise ValueError(
                    f"{name}: {values.dtype} {tuple(dims)} in entry {record.key}, "
                    f"{known[1]} {known[0]} in another"
                )
            pieces.setdefault(name, []).append(values.ravel())
            shapes[name] = list(values.shape)
        entries.append({"key": record.key, "attrs": record.attrs, "shapes": shapes})
    data = {}
    encoding = {}
    digests = {}
    for name, parts in pieces.items():
        dims, dtype, attrs = about[name]
        values = np.concatenate(parts) if len(parts) > 1 else parts[0]
        values = np.asarray(values, dtype=dtype)
        digests[name] = digest(values)
        # An empty string array has no strings for xarray to infer the type from (it stores
        # float64): the attribute keeps what it was.
        strings = {"strings": True} if dtype.kind in "OTU" else {}
        data[name] = xr.Variable(
            (f"{FLAT_PREFIX}{name}",), values, {**attrs, **strings, "dims": list(dims)}
        )
        encoding[name] = {"chunks": (_chunk_length(values),), **_compressors(values)}
    digests["@entries"] = json_digest(entries)
    attrs = {"eskin_batch": kind, "entries": entries, "sha256": digests}
    xr.Dataset(data, attrs=attrs).to_zarr(_target(path), mode="w-", encoding=encoding, **_TO_ZARR)


def read_batch_keys(path: Path) -> tuple[str, ...]:
    """The keys of the batch at ``path``, from its group metadata alone (one small file)."""
    return metadata_keys((path / "zarr.json").read_bytes())


def metadata_keys(metadata: bytes) -> tuple[str, ...]:
    """The keys of a batch, from the bytes of its group metadata (``zarr.json``)."""
    entries = json.loads(metadata)["attributes"]["entries"]
    return tuple(str(entry["key"]) for entry in entries)


def read_batch(path: Path | Store, kind: str) -> list[BatchEntry]:
    """Every entry of the batch at ``path`` (a folder or a Zarr store), checked against the
    batch's digests.

    Raises
    ------
    BatchError
        The batch is not of ``kind``, fails a digest or is inconsistent.
    Exception
        Whatever Zarr and its codecs raise for a chunk they cannot read or decode (``OSError``,
        ``ValueError``, ``RuntimeError``, ...): corruption too, to the caller.
    """
    with xr.open_zarr(_target(path), **_OPEN_ZARR) as lazy:
        ds = lazy.load()
    attrs = dict(ds.attrs)
    if attrs.get("eskin_batch") != kind:
        raise BatchError(f"it is not a batch of {kind} entries")
    entries, digests = attrs.get("entries"), attrs.get("sha256")
    names = {str(n) for n in ds.variables}
    if not isinstance(entries, list) or not isinstance(digests, dict):
        raise BatchError("its metadata lacks entries or digests")
    if set(digests) != {*names, "@entries"}:
        raise BatchError("its variables do not match its checksums")
    if json_digest(entries) != digests["@entries"]:
        raise BatchError("its entry list fails its sha256")
    arrays = {}
    for name in names:
        variable = ds.variables[name]
        values = np.asarray(variable.values)
        if variable.attrs.get("strings") and values.size == 0:
            values = np.empty(0, dtype=object)
        if digest(values) != digests[name]:
            raise BatchError(f"variable {name!r} fails its sha256")
        arrays[name] = (tuple(variable.attrs.get("dims", ())), values)
    offsets = dict.fromkeys(arrays, 0)
    records = []
    for entry in entries:
        variables: Variables = {}
        for name, shape in entry["shapes"].items():
            dims, flat = arrays[name]
            size = math.prod(shape)
            start = offsets[name]
            if start + size > flat.size or len(shape) != len(dims):
                raise BatchError(f"variable {name!r} does not match its entries' shapes")
            variables[name] = (dims, flat[start : start + size].reshape(shape), {})
            offsets[name] = start + size
        records.append(BatchEntry(str(entry["key"]), variables, entry["attrs"]))
    if any(offsets[name] != arrays[name][1].size for name in arrays):
        raise BatchError("a variable holds values of no entry")
    return records


def _target(path: Path | Store) -> str | Store:
    return str(path) if isinstance(path, Path) else path


def digest(values: np.ndarray, *, canonical_nan: bool = False) -> str:
    """sha256 hex of dtype, shape and little-endian bytes; strings by value, not by width."""
    values = np.asarray(values)
    hasher = hashlib.sha256()
    if values.dtype.kind in "OTUS":
        # <U, object and StringDType hold the same strings in different widths/layouts.
        hasher.update(f"str{values.shape}".encode())
        hasher.update(json.dumps([str(v) for v in values.ravel().tolist()]).encode())
        return hasher.hexdigest()
    values = np.asarray(values, dtype=values.dtype.newbyteorder("<"), order="C")
    if canonical_nan and values.dtype.kind in "fc":
        values = values.copy()
        values[np.isnan(values)] = np.nan
    hasher.update(f"{values.dtype.str}{values.shape}".encode())
    hasher.update(values.tobytes())
    return hasher.hexdigest()


def json_digest(value: Any) -> str:
    """sha256 hex of the canonical JSON of ``value`` (sorted keys, no NaN)."""
    text = json.dumps(value, sort_keys=True, allow_nan=False, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _compressors(values: np.ndarray) -> dict[str, Any]:
    """Numbers: Blosc (a core Zarr v3 codec) with zstd over byte-shuffled values, which packs
    small integers (the tick deltas of spike trains, :mod:`storage.codec`) to about their
    entropy; strings: Zarr's default."""
    if values.dtype.kind in "OTU":
        return {}
    shuffled = BloscCodec(cname="zstd", clevel=5, shuffle="shuffle", typesize=values.itemsize)
    return {"compressors": (shuffled,)}


def _chunk_length(values: np.ndarray) -> int:
    if values.dtype.kind in "OTU":
        return max(1, values.size)
    return max(1, min(values.size, CHUNK_BYTES // max(1, values.dtype.itemsize)))


def nbytes(variables: Mapping[str, tuple[Any, np.ndarray, Any]]) -> int:
    """Bytes of an entry's values (what a batch of it will roughly hold)."""
    return sum(np.asarray(values).nbytes for _, values, _ in variables.values())
