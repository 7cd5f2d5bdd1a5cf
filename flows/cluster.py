"""Dask clusters for sweeps: a local one by default, or an existing scheduler by address.

The local cluster runs ``workers`` processes with one thread each, every server on 127.0.0.1
(the scheduler's HTTP server on a free port). An existing scheduler must answer within
``timeout_s`` or the sweep stops with a clear error before any work is submitted.
"""

from __future__ import annotations

import logging
import numbers
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager

from pipeline.errors import EskinError

ADDRESS_PATTERN = re.compile(r"^tcp://[^\s:/]+:\d{1,5}$")
CONNECT_TIMEOUT_S = 20.0


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
    """Raise :class:`ClusterError` unless ``address`` looks like ``tcp://HOST:PORT``."""
    if not ADDRESS_PATTERN.match(address):
        raise ClusterError(f"--address {address!r}: expected tcp://HOST:PORT")


def probe_scheduler(address: str, *, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """Connect to the scheduler at ``address`` and disconnect; raise :class:`ClusterError`."""
    with dask_client(address=address, timeout_s=timeout_s):
        pass


@contextmanager
def dask_client(
    workers: int | None = None, address: str | None = None, *, timeout_s: float = CONNECT_TIMEOUT_S
) -> Iterator[object]:
    """A ``distributed.Client`` on a fresh local cluster, or on the scheduler at ``address``.

    The local cluster has ``workers`` single-thread processes (default: one per available core).
    """
    import dask
    from distributed import Client, LocalCluster

    # Prefect's logging set-up shows every INFO line of the scheduler and nannies otherwise.
    logging.getLogger("distributed").setLevel(logging.WARNING)
    if address is not None:
        check_address(address)
        try:
            client = Client(address, timeout=timeout_s, set_as_default=True)
        except (OSError, TimeoutError) as exc:
            raise ClusterError(
                f"cannot reach the Dask scheduler at {address} within {timeout_s:.0f} s: "
                f"{type(exc).__name__}"
            ) from None
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
    with dask.config.set(
        {f"distributed.nanny.pre-spawn-environ.{k}": v for k, v in allocator.items()}
    ):
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",  # its HTTP server always runs: loopback, free port
            silence_logs=logging.ERROR,
        )
    try:
        client = Client(cluster, set_as_default=True)
        try:
            yield client
        finally:
            client.close()
    finally:
        cluster.close()
