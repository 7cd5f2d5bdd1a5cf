"""Fixtures shared by the end-to-end suites (tests/flows, tests/reliability)."""

import contextlib
import functools
import json
import os
import shutil
import sqlite3
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from flows import server
from tests.flows.helpers import (
    BIN,
    eskin,
    hermetic_env,
    in_process_client,
    server_state_with_db,
)

#: A backstop: the session's server stops by itself if the suite dies before its teardown.
SUITE_SERVER_IDLE_S = "600"


@pytest.fixture(scope="session", autouse=True)
def suite_prefect_server(tmp_path_factory):
    """One local Prefect server state for the whole suite, stopped at its end.

    Every sweep the tests start (in a subprocess or in this process) finds the folder through
    ``ESKIN_SERVER_DIR``: the first starts the server, the others reuse it, as a user's do.
    """
    state = tmp_path_factory.mktemp("prefect-server")
    saved = {k: os.environ.get(k) for k in (server.SERVER_DIR_ENV, server.IDLE_ENV)}
    os.environ[server.SERVER_DIR_ENV] = str(state)
    os.environ[server.IDLE_ENV] = SUITE_SERVER_IDLE_S
    yield state
    server.stop(state)
    for name, value in saved.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


@pytest.fixture(scope="session")
def migrated_prefect_db(tmp_path_factory) -> Path:
    """A Prefect database (SQLite, one file) with every migration applied and nothing stored.

    Made once a session, by ``prefect server database upgrade`` (the migrations a server runs
    on its first start), and copied whole through SQLite's backup, so no write-ahead log is
    left beside it.
    """
    base = tmp_path_factory.mktemp("prefect-db")
    env = hermetic_env(base)
    proc = subprocess.run(
        [BIN / "prefect", "server", "database", "upgrade", "-y"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        stdin=subprocess.DEVNULL,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    template = base / "prefect.db"
    with (
        contextlib.closing(sqlite3.connect(Path(env["PREFECT_HOME"]) / "prefect.db")) as source,
        contextlib.closing(sqlite3.connect(template)) as copy,
    ):
        source.backup(copy)
    return template


@pytest.fixture
def migrated_server_state(migrated_prefect_db) -> Callable[[Path], Path]:
    """``make(state)``: :func:`tests.flows.helpers.server_state_with_db` of
    :func:`migrated_prefect_db`, so that the server started there skips the database set-up of
    a first start (several seconds). Tests about a first start itself (the folder's creation,
    the set-up's time on a busy machine) start from no folder instead."""
    return functools.partial(server_state_with_db, database=migrated_prefect_db)


@pytest.fixture(scope="session")
def suite_server_db(suite_prefect_server, migrated_prefect_db) -> None:
    """The suite's server state holds a copy of :func:`migrated_prefect_db` before the server
    first starts there, so that start skips the set-up. A state that has a database already
    (its server started) is left alone; the first users of the server ask for this."""
    database = suite_prefect_server / "prefect.db"
    if not database.exists():
        shutil.copyfile(migrated_prefect_db, database)


@pytest.fixture(scope="session")
def smoke_sweep(tmp_path_factory, suite_server_db):
    """The smoke grid swept once on the default local cluster: (root, JSON summary, env)."""
    base = tmp_path_factory.mktemp("smoke-sweep")
    env = hermetic_env(base)
    root = base / "run"
    proc = eskin("sweep", "--grid", "smoke", "--root", str(root), "--json", env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return root, json.loads(proc.stdout), env


@pytest.fixture(scope="module")
def client():
    """A Dask client on an in-process cluster of one single-thread worker."""
    with in_process_client() as client:
        yield client
