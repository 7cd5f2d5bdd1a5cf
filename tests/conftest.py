"""Fixtures shared by the end-to-end suites (tests/flows, tests/reliability)."""

import json

import pytest

from tests.flows.helpers import eskin, hermetic_env


@pytest.fixture(scope="session")
def smoke_sweep(tmp_path_factory):
    """The smoke grid swept once on the default local cluster: (root, JSON summary, env)."""
    base = tmp_path_factory.mktemp("smoke-sweep")
    env = hermetic_env(base)
    root = base / "run"
    proc = eskin("sweep", "--grid", "smoke", "--root", str(root), "--json", env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return root, json.loads(proc.stdout), env
