"""Fixtures shared by the end-to-end suites (tests/flows, tests/reliability), and the rules the
whole suite runs by.

End-to-end tests (a sweep, a search, a Prefect server or a Dask cluster started) are marked
``slow``: an unmarked test that starts one fails (:func:`pytest_configure`), so
``make test-quick`` (``-m "not slow"``) runs everything else alone. Under pytest-xdist
(``make test`` runs ``-n 3 --dist loadfile --no-loadscope-reorder``) a module runs on one
worker, in order, so that a module-scoped fixture (a sweep, the documentation site) is made once
and two sweeps of one module never compete for the cores; the modules are handed out in the
order :func:`run_order` gives, the longest first, so that no long module starts last. The
workers share one Prefect server, one migrated database and one smoke sweep (:func:`once`).
Every test has a time limit (pytest-timeout, ``timeout`` in pyproject.toml); slow tests get
:data:`SLOW_TIMEOUT_S`.
"""

import contextlib
import fcntl
import functools
import json
import os
import shutil
import sqlite3
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from flows import server
from flows.environment import restored_environment
from tests.flows.helpers import (
    BIN,
    eskin,
    hermetic_env,
    in_process_client,
    server_state_with_db,
    start_cluster,
    stop_pids,
)
from tests.shared_data import vibtac12_copy

#: A backstop: the session's server stops by itself if the suite dies before its teardown.
SUITE_SERVER_IDLE_S = "600"
#: The time limit of a test marked slow (pytest-timeout), whose sweeps take minutes on a busy
#: machine; other tests have pyproject.toml's ``timeout``.
SLOW_TIMEOUT_S = 900
#: Commands of ``eskin`` that start a sweep, a search or a server (end-to-end runs; ``eskin run``
#: runs one scene in its own process).
END_TO_END_COMMANDS = frozenset({"sweep", "optimize", "serve", "server"})
#: Arguments with which those commands start nothing.
STARTS_NOTHING = frozenset({"--help", "-h", "--dry-run", "status", "stop"})


def run_order(items: list[pytest.Item]) -> list[pytest.Item]:
    """``items`` module by module, in the order pytest-xdist hands the modules out: the modules
    with end-to-end tests first, most of them first (each starts a sweep, a search or a server:
    tens of seconds), then the others, most tests first, so that the shortest fill the end of
    the run on whichever worker is free. Ties keep the collection order; a module's own tests
    keep theirs (its fixtures rely on it)."""
    modules: dict[str, list[pytest.Item]] = {}
    for item in items:
        modules.setdefault(item.nodeid.split("::", 1)[0], []).append(item)

    def weight(tests: list[pytest.Item]) -> tuple[int, int]:
        slow = sum(item.get_closest_marker("slow") is not None for item in tests)
        return (-slow, 0) if slow else (1, -len(tests))

    return [item for tests in sorted(modules.values(), key=weight) for item in tests]


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Slow tests get :data:`SLOW_TIMEOUT_S`; the modules run in :func:`run_order`."""
    for item in items:
        if item.get_closest_marker("slow") and item.get_closest_marker("timeout") is None:
            item.add_marker(pytest.mark.timeout(SLOW_TIMEOUT_S))
    items[:] = run_order(items)


#: The test running now (its set-up, call and tear-down), for :func:`_refuse_unmarked`.
_running: list[pytest.Item] = []


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    _running.append(item)
    try:
        return (yield)
    finally:
        _running.pop()


def _refuse_unmarked(what: str) -> None:
    """Fail the running test, if it is not marked slow, for starting ``what``."""
    if _running and _running[-1].get_closest_marker("slow") is None:
        pytest.fail(f"{_running[-1].nodeid} {what}: mark it @pytest.mark.slow", pytrace=False)


def _eskin_command(args: object) -> str | None:
    """The ``eskin`` command a subprocess runs (``eskin CMD`` or ``python -m flows.cli CMD``),
    if it starts something (a run, a server), else None."""
    words = [str(arg) for arg in args] if isinstance(args, list | tuple) else [str(args)]
    if words[1:3] == ["-m", server.MARKER]:
        return "a Prefect server"
    if words[1:3] == ["-m", "flows.cli"]:
        command = words[3:4]
    else:
        command = words[1:2] if words and Path(words[0]).name == "eskin" else []
    if set(command) & END_TO_END_COMMANDS and not STARTS_NOTHING & set(words):
        return f"`eskin {command[0]}`"
    return None


def pytest_configure(config: pytest.Config) -> None:
    """End-to-end runs are marked ``slow``: a test not so marked fails (:func:`_refuse_unmarked`)
    when it, or a fixture made for it, starts a subprocess of :func:`_eskin_command`, or in this
    process uses the local Prefect server or starts a Dask cluster of worker processes."""
    from distributed import LocalCluster

    popen_init = subprocess.Popen.__init__

    def checked_popen(self, args, *more, **kwargs):
        what = _eskin_command(args)
        if what is not None:
            _refuse_unmarked(f"runs {what}")
        popen_init(self, args, *more, **kwargs)

    def checked(function: Callable[..., object], what: str) -> Callable[..., object]:
        @functools.wraps(function)
        def check(*args, **kwargs):
            _refuse_unmarked(what)
            return function(*args, **kwargs)

        return check

    def checked_cluster(self, *args, **kwargs):
        if kwargs.get("processes", True):
            _refuse_unmarked("starts a Dask cluster of worker processes")
        cluster_init(self, *args, **kwargs)

    subprocess.Popen.__init__ = checked_popen
    server.prefect_server = checked(server.prefect_server, "uses the local Prefect server")
    cluster_init = LocalCluster.__init__
    LocalCluster.__init__ = checked_cluster


def shared_folder(tmp_path_factory) -> Path:
    """A folder every pytest-xdist worker of this run shares (their base folders' parent), or
    this session's base folder when the tests run in one process."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    with open(path, "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield


def once(tmp_path_factory, name: str, make: Callable[[Path], None]) -> Path:
    """``shared_folder()/name``, made by ``make(folder)`` by the first worker that asks (the
    others wait for it, then use what it made)."""
    folder = shared_folder(tmp_path_factory) / name
    with _locked(folder.with_name(f"{name}.lock")):
        if not (folder / ".made").exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            (folder / ".made").touch()
    return folder


@contextlib.contextmanager
def _shared_service(
    tmp_path_factory, name: str, start: Callable[[Path], None], stop: Callable[[Path], None]
) -> Iterator[Path]:
    """``shared_folder()/name`` for the ``with`` block, made by ``start(folder)`` when no
    pytest-xdist worker of the run uses it, and ended by ``stop(folder)`` when the last one that
    does leaves (a count of users beside it, under a lock)."""
    folder = shared_folder(tmp_path_factory) / name
    users, lock = folder.with_name(f"{name}.users"), folder.with_name(f"{name}.lock")
    with _locked(lock):
        count = int(users.read_text()) if users.exists() else 0
        if count == 0:
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            start(folder)
        users.write_text(f"{count + 1}\n")
    try:
        yield folder
    finally:
        with _locked(lock):
            count = int(users.read_text()) - 1
            users.write_text(f"{count}\n")
            if count == 0:
                stop(folder)


@pytest.fixture(scope="session", autouse=True)
def suite_prefect_server(tmp_path_factory):
    """One local Prefect server state for the whole suite (:func:`_shared_service`), its server
    stopped at the end of the last pytest-xdist worker that uses it.

    Every sweep the tests start (in a subprocess or in this process) finds the folder through
    ``ESKIN_SERVER_DIR``: the first starts the server, the others reuse it, as a user's do.
    """
    with (
        _shared_service(
            tmp_path_factory, "prefect-server", lambda state: state.chmod(0o700), server.stop
        ) as state,
        restored_environment((server.SERVER_DIR_ENV, server.IDLE_ENV)),
    ):
        os.environ[server.SERVER_DIR_ENV] = str(state)
        os.environ[server.IDLE_ENV] = SUITE_SERVER_IDLE_S
        yield state


def _start_suite_cluster(folder: Path) -> None:
    arguments, pids = start_cluster(folder, hermetic_env(folder))
    (folder / "cluster.json").write_text(json.dumps({"arguments": arguments, "pids": pids}))


def _stop_suite_cluster(folder: Path) -> None:
    stop_pids(json.loads((folder / "cluster.json").read_text())["pids"])


@pytest.fixture(scope="session")
def suite_cluster(tmp_path_factory) -> Iterator[list[str]]:
    """The ``eskin sweep`` arguments (``--address`` and the ``--tls-*`` files) of one Dask
    cluster for the run (:func:`tests.flows.helpers.start_cluster`: a scheduler and two
    single-thread workers), started by the first pytest-xdist worker that asks, stopped by the
    last to leave.

    For end-to-end tests whose subject is not the cluster: a sweep on it skips a local cluster's
    start, whose workers each import the numerical stack again (seconds of CPU). Tests of the
    local cluster, of a killed sweep's or worker's processes, or of what a worker logs on the
    sweep's stderr keep a cluster of their own."""
    with _shared_service(
        tmp_path_factory, "dask-cluster", _start_suite_cluster, _stop_suite_cluster
    ) as folder:
        yield json.loads((folder / "cluster.json").read_text())["arguments"]


@pytest.fixture(scope="session")
def migrated_prefect_db(tmp_path_factory) -> Path:
    """A Prefect database (SQLite, one file) with every migration applied and nothing stored.

    Made once a run (:func:`once`), by ``prefect server database upgrade`` (the migrations a
    server runs on its first start), and copied whole through SQLite's backup, so no write-ahead
    log is left beside it.
    """
    return once(tmp_path_factory, "prefect-db", _migrated_db) / "prefect.db"


def _migrated_db(base: Path) -> None:
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
    with (
        contextlib.closing(sqlite3.connect(Path(env["PREFECT_HOME"]) / "prefect.db")) as source,
        contextlib.closing(sqlite3.connect(base / "prefect.db")) as copy,
    ):
        source.backup(copy)


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
    with _locked(suite_prefect_server.with_name("prefect-server.lock")):
        if not database.exists():
            shutil.copyfile(migrated_prefect_db, database)


@pytest.fixture(scope="session")
def smoke_sweep(tmp_path_factory, suite_server_db):
    """The smoke grid swept once a run on the default local cluster (:func:`once`): (root, JSON
    summary, env: this worker's own Prefect home and scratch folders). The root is read, never
    written: a test that sweeps it again copies it."""
    base = once(tmp_path_factory, "smoke-sweep", _sweep_smoke)
    env = hermetic_env(tmp_path_factory.mktemp("smoke-env"))
    return base / "run", json.loads((base / "summary.json").read_text()), env


def _sweep_smoke(base: Path) -> None:
    proc = eskin(
        "sweep", "--grid", "smoke", "--root", str(base / "run"), "--json", env=hermetic_env(base)
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    (base / "summary.json").write_text(proc.stdout)


@pytest.fixture
def vibtac12() -> Path:
    """The VibTac-12 copy of ``../shared`` (:func:`tests.shared_data.vibtac12_copy`): the test
    skips without it, or fails under CI."""
    return vibtac12_copy()


@pytest.fixture(scope="module")
def client():
    """A Dask client on an in-process cluster of one single-thread worker."""
    with in_process_client() as client:
        yield client
