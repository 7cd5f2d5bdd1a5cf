"""Fixtures shared by the end-to-end suites (tests/flows, tests/reliability)."""

import json
import os

import pytest

from flows import server
from tests.flows.helpers import eskin, hermetic_env, in_process_client

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
def smoke_sweep(tmp_path_factory):
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
