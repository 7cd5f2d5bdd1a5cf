"""Objects: the small interface a run root on object storage is written through, with a POSIX
and an S3 implementation.

A run root is either a folder (``runs/paper``) or an S3-compatible URL
(``s3://bucket/prefix``). A folder root keeps the guarantees of its file system (rename,
``flock``; :mod:`storage.store`); an object root has none of them, only whole objects, each
written by one PUT, and conditional PUTs. :class:`Objects` is what the store needs of such a
root: list, get (one object or many at once), put, put-if-absent, put-if-match (on an ETag),
delete, and a Zarr store for a prefix. Keys are ``/``-separated and relative to the root.

:class:`S3Objects` talks to S3 through obstore (endpoint, region and credentials from the
standard AWS variables: ``AWS_ACCESS_KEY_ID``, ``AWS_SECRET_ACCESS_KEY``, ``AWS_REGION``,
``AWS_ENDPOINT_URL``, ``AWS_ALLOW_HTTP`` for a plain-http endpoint); it holds only the URL, so
it pickles cheaply to Dask workers. Every request waits a round trip, so whatever reads or
writes many objects does it concurrently (:meth:`Objects.get_many`, :meth:`Objects.publish`).
:meth:`S3Objects.check` asks the object store once, with few retries, before a root is used:
a root it cannot use (a plain-http endpoint without ``AWS_ALLOW_HTTP``, credentials missing or
refused, no such bucket, an endpoint that does not answer) is one line naming the cause and
what to set (:func:`s3_problem`), before anything is written. :class:`PosixObjects` gives the
same semantics on a local folder (an ETag there is the file's inode, size and modification
time; conditional writes hold the folder's ``flock``), so the object layout runs, and is
tested, without a server.
"""

from __future__ import annotations

import abc
import concurrent.futures
import contextlib
import datetime
import fcntl
import os
import re
import threading
import uuid
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import zarr

from storage.errors import StoreError, StoreWriteError

#: The URL schemes of object roots.
SCHEMES = ("s3://",)
# Objects written or read at once (each request waits tens of ms on S3).
PUT_THREADS = 16
#: Retries of the first request to an object root (:meth:`S3Objects.check`), within
#: :data:`CHECK_TIMEOUT_S`; later requests keep obstore's patient defaults (10 retries within
#: 3 minutes).
CHECK_RETRIES = 2
#: Seconds the retries of the first request to an object root may take.
CHECK_TIMEOUT_S = 10.0


class Conflict(Exception):
    """A conditional write found the object otherwise than required (present, or changed)."""


@dataclass(frozen=True)
class ObjectInfo:
    """One listed object: its key (relative to the root), last modification (s since the epoch)
    and ETag."""

    key: str
    modified_s: float
    etag: str


def is_object_url(root: str | Path) -> bool:
    """True if ``root`` names an object root (``s3://...``), not a folder."""
    return isinstance(root, str) and root.startswith(SCHEMES)


def run_root(root: str | Path) -> str | Path:
    """``root`` as the store keeps it: an object root's URL without a trailing ``/``, else a
    Path (``Path("s3://b/p")`` would make a folder named ``s3:``)."""
    if is_object_url(root):
        return str(root).rstrip("/")
    return Path(root)


class Objects(abc.ABC):
    """The object operations of a run root (see the module docstring); keys relative to it."""

    url: str

    @abc.abstractmethod
    def list(self, prefix: str) -> list[ObjectInfo]:
        """Every object whose key starts with ``prefix``, at any depth."""

    @abc.abstractmethod
    def get(self, key: str) -> tuple[bytes, str]:
        """The object's bytes and ETag; FileNotFoundError if there is none."""

    def get_many(self, keys: Iterable[str]) -> dict[str, bytes]:
        """The bytes of every object of ``keys``, read concurrently; FileNotFoundError if one is
        missing."""
        keys = list(dict.fromkeys(keys))
        return dict(zip(keys, _concurrently(lambda key: self.get(key)[0], keys), strict=True))

    @abc.abstractmethod
    def check(self) -> None:
        """Raise :class:`StoreError` (one line: the cause, and what to set) if the root cannot
        be used at all."""

    @abc.abstractmethod
    def put(self, key: str, data: bytes) -> str:
        """Write the object whole (replacing any); return its ETag."""

    @abc.abstractmethod
    def put_if_absent(self, key: str, data: bytes) -> str:
        """Write the object only if there is none; its ETag, or :class:`Conflict`."""

    @abc.abstractmethod
    def put_if_match(self, key: str, data: bytes, etag: str) -> str:
        """Replace the object only if its ETag is still ``etag``; the new ETag, or
        :class:`Conflict`."""

    @abc.abstractmethod
    def delete(self, keys: list[str]) -> None:
        """Remove the objects (missing ones are fine)."""

    @abc.abstractmethod
    def zarr_store(self, prefix: str, *, read_only: bool = False) -> zarr.abc.store.Store:
        """A Zarr store whose keys live under ``prefix``."""

    def where(self, key: str = "") -> str:
        """The URL or path of ``key``, for messages."""
        return f"{self.url}/{key}" if key else self.url

    def publish(self, prefix: str, files: Mapping[str, bytes], *, last: str) -> dict[str, str]:
        """Write ``files`` (relative key -> bytes) under ``prefix``, concurrently, and the file
        ``last`` after all the others have been written; return each file's ETag, by name."""
        rest = [name for name in files if name != last]
        written = _concurrently(lambda name: self.put(f"{prefix}{name}", files[name]), rest)
        etags = dict(zip(rest, written, strict=True))
        etags[last] = self.put(f"{prefix}{last}", files[last])
        return etags


def _concurrently(call: Callable[[str], Any], keys: list[str]) -> list[Any]:
    """``[call(key) for key in keys]``, :data:`PUT_THREADS` at a time (obstore releases the
    GIL while it waits)."""
    if len(keys) < 2:
        return [call(key) for key in keys]
    with concurrent.futures.ThreadPoolExecutor(min(PUT_THREADS, len(keys))) as pool:
        return list(pool.map(call, keys))


def objects_for(root: str | Path) -> Objects:
    """The objects of the run root ``root``: :class:`S3Objects` for an ``s3://`` URL, else
    :class:`PosixObjects` of the folder."""
    if is_object_url(root):
        return S3Objects(str(root))
    return PosixObjects(Path(root))


# ---------------------------------------------------------------------------------------------
# S3


class S3Objects(Objects):
    """An S3-compatible bucket and prefix, through obstore."""

    def __init__(self, url: str):
        self.url = str(url).rstrip("/")

    def __repr__(self) -> str:
        return f"S3Objects({self.url!r})"

    def __getstate__(self) -> dict[str, Any]:
        return {"url": self.url}  # the client is made again where it is unpickled

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.url = state["url"]

    @property
    def _store(self) -> Any:
        return _s3_store(self.url)

    def check(self) -> None:
        """One listing of the root's top level, with few retries (:data:`CHECK_RETRIES`), once
        per process and configuration: a root that cannot be used raises :class:`StoreError`
        with :func:`s3_problem`'s line."""
        import obstore

        checked = (self.url, _aws_config())
        if checked in _CHECKED:
            return
        with _s3_errors(self.url, self.url):
            obstore.list_with_delimiter(_s3_store(self.url, checking=True), None)
        _CHECKED.add(checked)

    def list(self, prefix: str) -> list[ObjectInfo]:
        import obstore

        # obstore lists whole path segments: list the folder, keep the keys with the prefix.
        folder = prefix.rpartition("/")[0]
        with _s3_errors(self.url, self.where(prefix)):
            found = obstore.list(self._store, folder or None).collect()
        return [
            ObjectInfo(o["path"], o["last_modified"].timestamp(), o["e_tag"] or "")
            for o in found
            if o["path"].startswith(prefix)
        ]

    def get(self, key: str) -> tuple[bytes, str]:
        import obstore

        with _s3_errors(self.url, self.where(key)):
            result = obstore.get(self._store, key)
            return bytes(result.bytes()), result.meta["e_tag"] or ""

    def put(self, key: str, data: bytes) -> str:
        return self._put(key, data, "overwrite")

    def put_if_absent(self, key: str, data: bytes) -> str:
        return self._put(key, data, "create")

    def put_if_match(self, key: str, data: bytes, etag: str) -> str:
        return self._put(key, data, {"e_tag": etag})

    def _put(self, key: str, data: bytes, mode: Any) -> str:
        import obstore
        from obstore.exceptions import AlreadyExistsError, PreconditionError

        try:
            with _s3_errors(self.url, self.where(key), writing=True):
                return obstore.put(self._store, key, data, mode=mode)["e_tag"] or ""
        except (AlreadyExistsError, PreconditionError) as error:
            raise Conflict(self.where(key)) from error

    def delete(self, keys: list[str]) -> None:
        import obstore

        if keys:
            with _s3_errors(self.url, self.where(), writing=True):
                obstore.delete(self._store, keys)

    def zarr_store(self, prefix: str, *, read_only: bool = False) -> zarr.abc.store.Store:
        with _s3_errors(self.url, self.where(prefix)):
            return zarr.storage.ObjectStore(_s3_store(self.where(prefix)), read_only=read_only)


_S3_STORES: dict[tuple[Any, ...], Any] = {}
_S3_GUARD = threading.Lock()
# (root URL, configuration) of the roots checked in this process.
_CHECKED: set[tuple[str, tuple[str, ...]]] = set()


def _aws_config() -> tuple[str, ...]:
    """The ``AWS_*`` variables, which configure obstore's S3 stores."""
    return tuple(sorted(f"{k}={v}" for k, v in os.environ.items() if k.startswith("AWS_")))


def _s3_store(url: str, *, checking: bool = False) -> Any:
    """obstore's S3 store of ``url``, configured from the environment (``AWS_*``): one per URL
    and configuration in a process; ``checking``: the one :meth:`S3Objects.check` asks with."""
    from obstore.store import S3Store

    key = (url, checking, _aws_config())
    with _S3_GUARD:
        if key not in _S3_STORES:
            options: dict[str, Any] = {}
            if checking:
                # Only the retries: client options given here would replace those of the
                # environment (AWS_ALLOW_HTTP among them), and obstore connects within 5 s.
                retries = datetime.timedelta(seconds=CHECK_TIMEOUT_S)
                options = {"retry_config": {"max_retries": CHECK_RETRIES, "retry_timeout": retries}}
            _S3_STORES[key] = S3Store.from_url(url, **options)
        return _S3_STORES[key]


#: S3 error codes that mean the credentials themselves were refused.
_REFUSED_CREDENTIALS = frozenset(
    {"InvalidAccessKeyId", "SignatureDoesNotMatch", "InvalidToken", "ExpiredToken"}
)
_S3_CODE = re.compile(r"<Code>\s*([A-Za-z]+)\s*</Code>")
# What an HTTP client says when nobody answers (refused, unresolvable, timed out).
_NO_ANSWER = ("error sending request", "timed out", "connection refused", "dns error")
_KEYS = ("AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY")
# Where a client without keys looks for an instance role's (the metadata service's paths).
_INSTANCE_CREDENTIALS = ("/latest/api/token", "/latest/meta-data", "169.254.169.254", "credential")


def s3_problem(error: BaseException, url: str) -> str | None:
    """Why the object root ``url`` cannot be used, as one line naming what to set, if
    ``error`` (of obstore) says so: a plain-http endpoint without ``AWS_ALLOW_HTTP``, missing or
    refused credentials, no such bucket, an endpoint that does not answer; else None."""
    text = str(error).split("Debug source:")[0]
    lowered = text.lower()
    found = _S3_CODE.search(text)
    code = found.group(1) if found else None
    bucket = url.removeprefix("s3://").split("/")[0]
    endpoint = next(
        (
            os.environ[k]
            for k in ("AWS_ENDPOINT_URL_S3", "AWS_ENDPOINT_URL", "AWS_ENDPOINT")
            if os.environ.get(k)
        ),
        "",
    )
    service = f"the object store at {endpoint}" if endpoint else "AWS S3"
    where = f"run root {url}"
    if "builder error" in lowered and endpoint.lower().startswith("http://"):
        allow = os.environ.get("AWS_ALLOW_HTTP")
        now = f" (it is {allow!r})" if allow is not None else ""
        return (
            f"{where}: the endpoint {endpoint} is plain http, which needs AWS_ALLOW_HTTP=true"
            f"{now}: set it, or give an https endpoint"
        )
    if code == "NoSuchBucket":
        return f"{where}: {service} has no bucket {bucket!r}: create it, or check the URL"
    if code in _REFUSED_CREDENTIALS:
        return (
            f"{where}: {service} refused the credentials ({code}): check AWS_ACCESS_KEY_ID "
            "and AWS_SECRET_ACCESS_KEY"
        )
    if code == "AccessDenied":
        return (
            f"{where}: {service} denied access to bucket {bucket!r} (AccessDenied): the "
            "credentials need permission to list, read and write it"
        )
    missing = [k for k in _KEYS if not os.environ.get(k)]
    if missing and any(words in lowered for words in _INSTANCE_CREDENTIALS):
        return (
            f"{where}: no credentials for {service}: {' and '.join(missing)} "
            f"{'is' if len(missing) == 1 else 'are'} not set (and no instance role answered)"
        )
    if any(words in lowered for words in _NO_ANSWER):
        return (
            f"{where}: {service} does not answer ({_first_cause(text)}): check "
            f"{'AWS_ENDPOINT_URL' if endpoint else 'the network'} and that the server is up"
        )
    return None


def _first_cause(text: str) -> str:
    """The HTTP client's few words on a request that found no answer."""
    lowered = text.lower()
    return next(words for words in _NO_ANSWER if words in lowered)


@contextlib.contextmanager
def _s3_errors(url: str, where: str, *, writing: bool = False) -> Iterator[None]:
    """obstore's errors on the root ``url`` (at ``where``) other than a missing object as
    one-line :class:`StoreError` (:func:`s3_problem`'s line where it knows the cause);
    ``writing``, a refused write as :class:`StoreWriteError` (every later one would be refused
    too)."""
    from obstore.exceptions import (
        AlreadyExistsError,
        BaseError,
        PermissionDeniedError,
        PreconditionError,
        UnauthenticatedError,
    )

    try:
        yield
    except (FileNotFoundError, AlreadyExistsError, PreconditionError):
        raise
    except (PermissionDeniedError, UnauthenticatedError) as error:
        if not writing:
            raise StoreError(_message(error, url, where)) from error
        raise StoreWriteError(url, "permission denied") from error
    except BaseError as error:
        raise StoreError(_message(error, url, where)) from error


def _message(error: BaseException, url: str, where: str) -> str:
    return s3_problem(error, url) or f"object store {where}: {_short(error)}"


def _short(error: BaseException) -> str:
    # obstore appends its Rust debug dump of the error: the sentence before it says it all.
    text = " ".join(str(error).split("Debug source:")[0].split())
    return f"{type(error).__name__}: {text}"


# ---------------------------------------------------------------------------------------------
# POSIX


class PosixObjects(Objects):
    """A local folder as objects: a key is a file path under it."""

    def __init__(self, root: Path):
        self.root = Path(root)
        self.url = str(self.root)

    def __repr__(self) -> str:
        return f"PosixObjects({self.url!r})"

    def check(self) -> None:
        """Nothing: a folder root is checked as it is opened (:mod:`storage.layout`)."""

    def list(self, prefix: str) -> list[ObjectInfo]:
        found = []
        for path in sorted(self.root.rglob("*")):
            key = path.relative_to(self.root).as_posix()
            if key.startswith(prefix) and path.is_file() and ".tmp-" not in path.name:
                stat = path.stat()
                found.append(ObjectInfo(key, stat.st_mtime, _posix_etag(stat)))
        return found

    def get(self, key: str) -> tuple[bytes, str]:
        with open(self.root / key, "rb") as file:
            return file.read(), _posix_etag(os.fstat(file.fileno()))

    def put(self, key: str, data: bytes) -> str:
        final = self.root / key
        os.replace(self._written(final, data), final)
        return _posix_etag(final.stat())

    def put_if_absent(self, key: str, data: bytes) -> str:
        final = self.root / key
        temporary = self._written(final, data)
        try:
            os.link(temporary, final)  # fails if final exists: create-if-absent, whole
        except FileExistsError as error:
            raise Conflict(self.where(key)) from error
        finally:
            os.unlink(temporary)
        return _posix_etag(final.stat())

    def put_if_match(self, key: str, data: bytes, etag: str) -> str:
        final = self.root / key
        with _folder_lock(final.parent):
            try:
                current = _posix_etag(final.stat())
            except FileNotFoundError as error:
                raise Conflict(self.where(key)) from error
            if current != etag:
                raise Conflict(self.where(key))
            return self.put(key, data)

    def delete(self, keys: list[str]) -> None:
        for key in keys:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self.root / key)

    def zarr_store(self, prefix: str, *, read_only: bool = False) -> zarr.abc.store.Store:
        return zarr.storage.LocalStore(self.root / prefix, read_only=read_only)

    def where(self, key: str = "") -> str:
        return str(self.root / key)

    @staticmethod
    def _written(final: Path, data: bytes) -> Path:
        final.parent.mkdir(parents=True, exist_ok=True)
        temporary = final.parent / f".tmp-{final.name}-{uuid.uuid4().hex}"
        temporary.write_bytes(data)
        return temporary


def _posix_etag(stat: os.stat_result) -> str:
    return f"{stat.st_ino}-{stat.st_size}-{stat.st_mtime_ns}"


@contextlib.contextmanager
def _folder_lock(folder: Path) -> Iterator[None]:
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)
