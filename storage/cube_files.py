"""Result cubes on disk: ``<store>/cubes/<name>/``, any xarray Dataset, written whole and
swapped in atomically, every chunk with a CRC-32C and every variable with a sha256.

Cubes carry ``eskin_sha256`` (digests of their variables; NaN payloads are canonicalized because
xarray's CF decoding of cubes rewrites them), removed again on reading.

A writer may also give a cube its ``source`` (an opaque digest of what it was built from) and a
small JSON ``note``. Both are kept in the cube's group metadata with a manifest (the sha256 of
every other file of the cube), so that :func:`current_note` can tell, from the files' bytes and
without decoding the cube, that the cube stored under a name is intact and was built from a
given source. Strings are stored as
Zarr's variable-length ``string`` type and read back as numpy ``<U`` arrays.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import hashlib
import json
import os
import re
import shutil
import uuid
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import xarray as xr
import zarr
from zarr.abc.store import Store
from zarr.codecs import Crc32cCodec, ZstdCodec

from storage.batches import digest
from storage.codec import as_strings
from storage.errors import CorruptEntryError, StoreError, one_line
from storage.layout import PARTIAL_PREFIX

CUBE_DIGESTS = "eskin_sha256"
CUBE_SOURCE = "eskin_source"
CUBE_NOTE = "eskin_note"
CUBE_FILES = "eskin_files"
_RESERVED = (CUBE_DIGESTS, CUBE_SOURCE, CUBE_NOTE, CUBE_FILES)
METADATA = "zarr.json"
# A sweep's name, or a search's and what its cube holds (``design.trials``): no name is "." or
# "..", none starts with the "." of a partial cube.
_CUBE_NAME = re.compile(r"[A-Za-z0-9_-]{1,64}(\.[A-Za-z0-9_-]{1,64})?")
_TO_ZARR = {"consolidated": False, "zarr_format": 3, "write_empty_chunks": True}
_OPEN_ZARR = {"consolidated": False, "zarr_format": 3}


def write_cube(
    folder: Path,
    name: str,
    cube: xr.Dataset,
    *,
    source: str | None = None,
    note: Mapping[str, Any] | None = None,
) -> None:
    """Store ``cube`` as ``<folder>/<name>``, replacing an older cube of that name atomically.

    ``source`` and ``note`` (JSON-serialisable), when given, are kept with the cube for
    :func:`current_note`.

    The new cube is written in full under a partial name, then swapped in with one
    ``renameat2(RENAME_EXCHANGE)`` (Linux), so the name always refers to a complete cube,
    old or new, never a mix; where the exchange is unavailable the old cube is moved aside
    first and the name is briefly missing. A reader in the middle of reading the old cube at
    the swap may fail (its files are then deleted) and should retry. The cube is computed
    first if it is Dask-backed, and its variables' encodings are dropped (a cube read from
    another store would otherwise carry that store's chunking and codecs); ``cube`` itself is
    not modified.

    Raises
    ------
    ValueError
        ``name`` cannot name a cube (:func:`valid_name`), or ``cube`` uses a reserved attribute
        (``eskin_sha256``, ``eskin_source``, ``eskin_note``, ``eskin_files``).
    """
    path = cube_path(folder, name)
    cube, encoding = prepared(name, cube)
    partial = path.parent / f"{PARTIAL_PREFIX}{name}-{uuid.uuid4().hex}"
    try:
        write_group(str(partial), cube, encoding, source, note, lambda: _manifest(partial))
        replace_folder(partial, path)
    finally:
        shutil.rmtree(partial, ignore_errors=True)


def prepared(name: str, cube: xr.Dataset) -> tuple[xr.Dataset, dict[str, Any]]:
    """``cube`` as it is stored (computed, its digests in its attributes, strings as objects)
    and its encoding (every chunk with a CRC-32C); ``cube`` itself is not modified.

    Raises
    ------
    TypeError, ValueError
        Not a Dataset; a reserved attribute.
    """
    if not isinstance(cube, xr.Dataset):
        raise TypeError(f"cube {name!r}: expected an xarray.Dataset, got {type(cube)}")
    for reserved in _RESERVED:
        if reserved in cube.attrs:
            raise ValueError(f"cube {name!r}: attribute {reserved!r} is reserved")
    cube = cube.compute().drop_encoding()
    digests = {str(n): digest(v.values, canonical_nan=True) for n, v in cube.variables.items()}
    cube = _strings_to_objects(cube)
    cube.attrs = {**cube.attrs, CUBE_DIGESTS: digests}
    # Every chunk carries a CRC-32C, which Zarr checks on each read: a lazy reader, which
    # never reads a whole variable to check its sha256, still never reads a torn chunk.
    encoding = {str(n): {"compressors": (ZstdCodec(), Crc32cCodec())} for n in cube.variables}
    return cube, encoding


def write_group(
    target: str | Store,
    cube: xr.Dataset,
    encoding: dict[str, Any],
    source: str | None,
    note: Mapping[str, Any] | None,
    manifest: Callable[[], dict[str, str]],
) -> None:
    """Write the :func:`prepared` ``cube`` as a new group at ``target``; with ``source``, add
    ``source``, ``note`` and ``manifest()`` (of the files written) to its group metadata."""
    cube.to_zarr(target, mode="w-", encoding=encoding, **_TO_ZARR)
    if source is not None:
        # The group's metadata is written last, with the manifest of everything else.
        zarr.open_group(target, mode="r+", zarr_format=3).attrs.update(
            {CUBE_SOURCE: source, CUBE_NOTE: dict(note or {}), CUBE_FILES: manifest()}
        )


def cube_names(folder: Path) -> list[str]:
    """Names of the stored cubes, sorted."""
    if not folder.is_dir():
        return []
    return sorted(
        p.name for p in folder.iterdir() if valid_name(p.name) and (p / "zarr.json").is_file()
    )


def read_cube(folder: Path, name: str, *, lazy: bool = False) -> xr.Dataset:
    """The cube ``name``, string variables as ``<U``.

    Parameters
    ----------
    lazy
        False (default): loaded into memory and checked against its sha256 digests. True:
        its data variables are Dask arrays, read chunk by chunk when computed (for cubes
        larger than memory); each chunk is checked against its CRC-32C as it is read (a
        mismatch raises then), the whole-variable digests are not. Coordinates are loaded.

    Raises
    ------
    StoreError
        No cube ``name``.
    CorruptEntryError
        The cube fails its checksum or cannot be read (when loaded).
    """
    path = cube_path(folder, name)
    if not (path / "zarr.json").is_file():
        raise StoreError(f"no cube {name!r} in {folder.parent.parent}")
    return read_group(str(path), f"cube {name} in {folder.parent.parent}", lazy=lazy)


def read_group(target: str | Store, where: str, *, lazy: bool) -> xr.Dataset:
    """The cube stored at ``target`` (:func:`read_cube`); ``where`` names it in errors."""
    try:
        if lazy:
            cube = _objects_to_strings(xr.open_zarr(target, **_OPEN_ZARR, chunks={}))
            for reserved in _RESERVED:
                cube.attrs.pop(reserved, None)
            return cube
        with xr.open_zarr(target, **_OPEN_ZARR, chunks=None) as opened:
            cube = _objects_to_strings(opened.load())
        digests = cube.attrs.pop(CUBE_DIGESTS)
        for reserved in _RESERVED:
            cube.attrs.pop(reserved, None)
        if not isinstance(digests, dict) or set(digests) != {str(n) for n in cube.variables}:
            raise CorruptEntryError(f"corrupt {where}: variables do not match its checksums")
        for var, variable in cube.variables.items():
            if digest(variable.values, canonical_nan=True) != digests[str(var)]:
                raise CorruptEntryError(f"corrupt {where}: variable {var!r} fails its sha256")
    except StoreError:
        raise
    except Exception as error:
        raise CorruptEntryError(f"corrupt {where}: {one_line(error)}") from error
    return cube


def current_note(folder: Path, name: str, source: str) -> dict[str, Any] | None:
    """The note of cube ``name`` if it was written with ``source`` and every file of it is as
    written (its manifest); else None (no such cube, another source, no manifest, or a file
    missing, added or changed). Reads the files' bytes, never decodes the cube."""
    path = cube_path(folder, name)
    return note_of(
        lambda: (path / METADATA).read_bytes(), source, lambda files: files == _manifest(path)
    )


def note_of(
    metadata: Callable[[], bytes], source: str, intact: Callable[[dict[str, str]], bool]
) -> dict[str, Any] | None:
    """:func:`current_note` of a cube given its group metadata's bytes and ``intact(manifest)``,
    which tells whether the cube's other files are as its recorded manifest (the sha256 of each
    by name) says, each called only when needed (any OSError or bad JSON: None)."""
    try:
        attributes = json.loads(metadata())["attributes"]
        if attributes[CUBE_SOURCE] != source:
            return None
        files, note = attributes[CUBE_FILES], attributes[CUBE_NOTE]
        ok = isinstance(note, dict) and isinstance(files, dict) and intact(files)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return note if ok else None


def _manifest(path: Path) -> dict[str, str]:
    """sha256 of every file under the cube folder ``path`` but its group metadata, by path."""
    found = {}
    for folder, _, files in os.walk(path):
        relative = os.path.relpath(folder, path)
        for name in files:
            if relative == "." and name == METADATA:
                continue
            with open(os.path.join(folder, name), "rb") as file:
                digest_ = hashlib.sha256(file.read()).hexdigest()
            found[name if relative == "." else f"{relative}/{name}"] = digest_
    return dict(sorted(found.items()))


def manifest_of(files: Mapping[str, bytes]) -> dict[str, str]:
    """sha256 of every file of a cube (relative name -> bytes) but its group metadata, as
    ``_manifest`` gives it for a folder."""
    return {
        name: hashlib.sha256(data).hexdigest()
        for name, data in sorted(files.items())
        if name != METADATA
    }


def cube_path(folder: Path, name: str) -> Path:
    """The folder of cube ``name`` under the cubes folder ``folder``; ValueError if ``name``
    cannot name a cube (:func:`checked_name`)."""
    return folder / checked_name(name)


def valid_name(name: Any) -> bool:
    """True if ``name`` can name a cube: ``[A-Za-z0-9_-]{1,64}``, optionally followed by ``.``
    and another such part (a search's cubes, :func:`storage.search_log.search_cube_name`)."""
    return isinstance(name, str) and _CUBE_NAME.fullmatch(name) is not None


def checked_name(name: Any) -> str:
    """``name`` if it can name a cube; else ValueError."""
    if not valid_name(name):
        raise ValueError(
            f"invalid cube name {name!r}: expected [A-Za-z0-9_-]{{1,64}}, optionally "
            "followed by . and another such part"
        )
    return name


def _strings_to_objects(ds: xr.Dataset) -> xr.Dataset:
    """``<U`` variables as object arrays, which Zarr v3 stores as its specified ``string`` type."""
    names = [name for name, v in ds.variables.items() if v.dtype.kind == "U"]
    return _convert(ds, names, lambda v: v.astype(object))


def _objects_to_strings(ds: xr.Dataset) -> xr.Dataset:
    """Read-back strings (StringDType or object) as ``<U``, the dtype cubes are built with."""
    names = [name for name, v in ds.variables.items() if v.dtype.kind in "OT"]
    return _convert(
        ds, names, lambda v: xr.Variable(v.dims, as_strings(v.values), v.attrs, v.encoding)
    )


def _convert(
    ds: xr.Dataset, names: list[Any], convert: Callable[[xr.Variable], xr.Variable]
) -> xr.Dataset:
    coords = {n: convert(ds.variables[n]) for n in names if n in ds.coords}
    data = {n: convert(ds.variables[n]) for n in names if n not in ds.coords}
    return ds.assign_coords(coords).assign(data)


_AT_FDCWD = -100
_RENAME_EXCHANGE = 2


def _renameat2() -> Callable[..., int] | None:
    """glibc's ``renameat2``, or None where it does not exist (not Linux, old glibc)."""
    try:
        return ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return None


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swap two directories; False where the platform cannot."""
    renameat2 = _renameat2()
    if renameat2 is None:
        return False
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):  # file system cannot exchange
        return False
    raise OSError(code, os.strerror(code), str(b))


def replace_folder(new: Path, final: Path) -> None:
    """Put directory ``new`` at ``final``, replacing what is there; ``new`` is gone afterwards.

    Readers of ``final`` see the old folder or the new one whole, never a mix: where Linux offers
    ``renameat2(RENAME_EXCHANGE)`` the two are swapped in one step, elsewhere the old folder is
    renamed aside first (a reader may then briefly find no folder). ``new`` and ``final`` must be
    on one file system.

    Raises
    ------
    OSError
        A rename failed (``final`` keeps its old folder where it had one).
    StoreError
        Concurrent writers of ``final`` kept replacing it (100 tries).
    """
    for _ in range(100):  # only concurrent writers of the same name make this loop
        if not final.exists():
            try:
                os.rename(new, final)
                return
            except OSError as error:
                if error.errno not in (errno.EEXIST, errno.ENOTEMPTY):
                    raise
                continue
        try:
            swapped = _exchange(new, final)
        except FileNotFoundError:  # final vanished between the check and the swap
            continue
        if swapped:
            shutil.rmtree(new, ignore_errors=True)  # now the old directory
            return
        # No atomic exchange: move the old one aside, then the new one in.
        old = final.parent / f"{PARTIAL_PREFIX}{final.name}-{uuid.uuid4().hex}"
        try:
            os.rename(final, old)
        except FileNotFoundError:
            continue
        try:
            os.rename(new, final)
        except OSError as error:
            if error.errno in (errno.EEXIST, errno.ENOTEMPTY):  # another writer's cube came in
                shutil.rmtree(old, ignore_errors=True)
                continue
            with contextlib.suppress(OSError):  # keep the old cube rather than none
                os.rename(old, final)
            raise
        shutil.rmtree(old, ignore_errors=True)
        return
    raise StoreError(f"could not replace {final}: too many concurrent writers")
