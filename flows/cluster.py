"""Dask clusters for sweeps: a local one by default, or an existing scheduler by address.

The local cluster runs ``workers`` processes with one thread each, every server on 127.0.0.1
(the scheduler's HTTP server on a free port). Its scheduler, workers and client speak TLS with
mutual authentication (``tls://`` addresses): the key and self-signed certificate are made for
the run (:meth:`distributed.security.Security.temporary`) and exist only in the memory of the
sweep process and of its workers (the nanny hands them over the pipe that starts a worker), so
another user of the machine who reaches the ports cannot connect a client and run code as the
sweep's owner. The dashboard is plain HTTP on 127.0.0.1, read only.

An existing scheduler is named by a ``tcp://`` or ``tls://`` address. For ``tls://`` the
client's CA file, certificate and key come from Dask's own configuration
(``distributed.comm.tls.ca-file``, ``distributed.comm.tls.client.cert`` and ``.key``), which the
command line's ``--tls-ca-file``, ``--tls-cert`` and ``--tls-key`` set (:func:`tls_config`).
The scheduler must answer within ``timeout_s`` and accept the credentials, or the sweep stops
with one line before any work is submitted.
"""

from __future__ import annotations

import logging
import numbers
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from pipeline.errors import EskinError

ADDRESS_PATTERN = re.compile(r"^(tcp|tls)://[^\s:/]+:\d{1,5}$")
CONNECT_TIMEOUT_S = 20.0
#: Dask's configuration of a client's TLS files, by the command-line option that sets each.
TLS_OPTIONS = {
    "--tls-ca-file": "distributed.comm.tls.ca-file",
    "--tls-cert": "distributed.comm.tls.client.cert",
    "--tls-key": "distributed.comm.tls.client.key",
}


class ClusterError(EskinError):
    """The Dask scheduler cannot be used."""


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity): the default number of local workers."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def check_workers(value: object, *, name: str | None = None) -> int:
    """``value`` as a number of workers: a whole number >= 1, or its decimal text.

    The one rule for worker counts: the command line's ``--workers`` type and every Python
    entry point (:func:`dask_client`, :func:`flows.run.run_sweep`) call it before
    anything starts.

    Raises
    ------
    ClusterError
        ``value`` is not a whole number >= 1 (the message starts with ``name`` when given;
        the command line names the option itself).
    """
    number = None
    if isinstance(value, str):
        try:
            number = int(value)
        except ValueError:
            pass
    elif isinstance(value, numbers.Integral) and not isinstance(value, bool):
        number = int(value)
    if number is None or number < 1:
        prefix = f"{name} " if name else ""
        raise ClusterError(f"{prefix}{value!r}: need a whole number >= 1")
    return number


def check_address(address: str) -> None:
    """Raise :class:`ClusterError` unless ``address`` looks like ``tcp://`` or
    ``tls://HOST:PORT``."""
    if not ADDRESS_PATTERN.match(address):
        raise ClusterError(f"--address {address!r}: expected tcp://HOST:PORT or tls://HOST:PORT")


def tls_config(address: str | None, files: dict[str, str | None]) -> dict[str, str]:
    """Dask's configuration for the TLS files given on the command line, checked.

    ``files`` maps each option of :data:`TLS_OPTIONS` to its value (None when not given).
    Files are only for a ``tls://`` address, and each must be a readable file; every problem
    is reported at once.

    Raises
    ------
    ClusterError
        Files without a ``tls://`` address, or files that cannot be read.
    """
    given = {option: value for option, value in files.items() if value is not None}
    if not given:
        return {}
    if address is None or not address.startswith("tls://"):
        raise ClusterError(f"{', '.join(given)}: only with --address tls://HOST:PORT")
    problems = [
        f"{option} {value}: not a readable file"
        for option, value in given.items()
        if not (Path(value).is_file() and os.access(value, os.R_OK))
    ]
    if problems:
        raise ClusterError("; ".join(problems))
    return {TLS_OPTIONS[option]: str(Path(value).absolute()) for option, value in given.items()}


def _client_security(address: str) -> object | None:
    """The client's TLS credentials for ``address`` from Dask's configuration (None for
    ``tcp://``); :class:`ClusterError` naming what is missing."""
    if not address.startswith("tls://"):
        return None
    import dask
    from distributed.security import Security

    missing = [option for option, name in TLS_OPTIONS.items() if not dask.config.get(name, None)]
    if missing:
        raise ClusterError(
            f"--address {address}: TLS needs {', '.join(missing)} (or Dask's "
            f"{', '.join(TLS_OPTIONS[m] for m in missing)} settings)"
        )
    return Security(require_encryption=True)


def _connect_failure(address: str, timeout_s: float, error: Exception) -> str:
    """One line saying why the scheduler at ``address`` could not be used."""
    from distributed.comm.core import FatalCommClosedError

    if isinstance(error, FatalCommClosedError) or "SSL" in type(error).__name__:
        reason = " ".join(str(error).split("More info")[0].split())
        return (
            f"the Dask scheduler at {address} and this client do not accept each other's TLS "
            f"credentials ({reason}): check {', '.join(TLS_OPTIONS)}"
        )
    return (
        f"cannot reach the Dask scheduler at {address} within {timeout_s:.0f} s: "
        f"{type(error).__name__}"
    )


def probe_scheduler(address: str, *, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """Connect to the scheduler at ``address`` and disconnect; raise :class:`ClusterError`."""
    with dask_client(address=address, timeout_s=timeout_s):
        pass


@contextmanager
def dask_client(
    workers: int | None = None, address: str | None = None, *, timeout_s: float = CONNECT_TIMEOUT_S
) -> Iterator[object]:
    """A ``distributed.Client`` on a fresh local cluster, or on the scheduler at ``address``.

    The local cluster has ``workers`` single-thread processes (default: one per available core)
    and speaks TLS with credentials made for it (see the module docstring).

    Raises
    ------
    ClusterError
        A bad ``workers`` or ``address``; a ``tls://`` address without the TLS files; a
        scheduler that does not answer within ``timeout_s`` or refuses the credentials.
    """
    import dask
    from distributed import Client, LocalCluster

    # Prefect's logging set-up shows every INFO line of the scheduler and nannies otherwise.
    logging.getLogger("distributed").setLevel(logging.WARNING)
    if address is not None:
        check_address(address)
        security = _client_security(address)
        try:
            client = Client(address, timeout=timeout_s, set_as_default=True, security=security)
        except Exception as exc:  # refused, timed out, or a handshake that failed
            raise ClusterError(_connect_failure(address, timeout_s, exc)) from None
        try:
            yield client
        finally:
            client.close()
        return
    workers = available_cores() if workers is None else check_workers(workers, name="workers")
    # Workers allocate from one glibc arena, whose heap can keep training's large tensors (see
    # flows.environment.tune_allocator); Dask's own MALLOC_TRIM_THRESHOLD_ would return them to
    # the kernel after every step. A variable the user set wins.
    allocator = {"MALLOC_ARENA_MAX": 1, "MALLOC_TRIM_THRESHOLD_": None}
    from distributed.security import Security

    security = Security.temporary()  # this run's key and certificate, in memory only
    with dask.config.set(
        {f"distributed.nanny.pre-spawn-environ.{k}": v for k, v in allocator.items()}
    ):
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            protocol="tls",
            security=security,
            dashboard_address="127.0.0.1:0",  # its HTTP server always runs: loopback, free port
            silence_logs=logging.ERROR,
        )
    try:
        client = Client(cluster, security=security, set_as_default=True)
        try:
            from flows.worker_logs import QuietHeartbeatAtClose

            client.register_plugin(QuietHeartbeatAtClose())
            yield client
        finally:
            client.close()
    finally:
        # A worker that trained takes seconds to finish exiting once closed (the interpreter's
        # teardown, after its last task); the nanny then kills it, which loses nothing, and
        # its warning would end every sweep.
        nanny = logging.getLogger("distributed.nanny")
        nanny.addFilter(_exiting_worker_killed)
        try:
            cluster.close()
        finally:
            nanny.removeFilter(_exiting_worker_killed)


def _exiting_worker_killed(record: logging.LogRecord) -> bool:
    """False for the nanny's warning that it killed a worker still exiting."""
    return not str(record.msg).startswith("Worker process still alive after")
