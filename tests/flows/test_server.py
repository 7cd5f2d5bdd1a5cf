"""The local Prefect server: started on first need, reused, stopped on demand or when idle.

Each test uses its own state folder, so it starts (and stops) a server of its own and never
touches the suite's shared one. Only the first test's folder starts empty (the server makes it,
and sets up its database); the others hold a copy of a database already set up
(``migrated_server_state``), which spares each start several seconds.
"""

import fcntl
import json
import os
import stat
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request

import psutil
import pytest

from flows import server
from tests.flows.helpers import api_headers, eskin, hermetic_env

pytestmark = pytest.mark.slow


@pytest.fixture
def state(tmp_path, monkeypatch):
    folder = tmp_path / "server-state"
    monkeypatch.setenv(server.SERVER_DIR_ENV, str(folder))
    monkeypatch.delenv("PREFECT_API_URL", raising=False)
    yield folder
    server.stop(folder)


@pytest.fixture
def migrated(state, migrated_server_state):
    """Makes :func:`state`, with its database set up."""
    migrated_server_state(state)


def api_status(url: str, auth: str | None = None) -> int:
    """The HTTP status of a request that lists flow runs, with ``auth`` as basic auth."""
    request = urllib.request.Request(
        f"{url}/flow_runs/filter", data=b"{}", headers=api_headers(auth), method="POST"
    )
    try:
        with urllib.request.urlopen(request, timeout=60) as response:
            return response.status
    except urllib.error.HTTPError as error:
        return error.code


def test_started_once_reused_and_stopped(state):
    from prefect.settings import get_current_settings

    assert server.status(state) is None
    heartbeat_s = get_current_settings().flows.heartbeat_frequency
    assert heartbeat_s is not None
    with server.prefect_server(show_progress=False) as url:
        first = server.status(state)
        assert first is not None and url == first.api_url
        assert url.startswith("http://127.0.0.1:")
        assert os.environ["PREFECT_API_URL"] == url
        assert get_current_settings().api.url == url
        # Nothing on the local server reads heartbeats: flow runs send none.
        assert get_current_settings().flows.heartbeat_frequency is None
        auth = (state / server.AUTH_FILE).read_text().strip()
        assert os.environ[server.CLIENT_AUTH_ENV] == auth and len(auth) >= 40
        assert get_current_settings().api.auth_string.get_secret_value() == auth
        assert stat.S_IMODE((state / server.AUTH_FILE).stat().st_mode) == 0o600
        assert stat.S_IMODE(state.stat().st_mode) == 0o700
        # Only the string's holders get in; the health check stays open.
        assert api_status(url) == 401 and api_status(url, "guess") == 401
        assert api_status(url, auth) == 200
        assert server.healthy(url)
    assert "PREFECT_API_URL" not in os.environ, "the block's settings leaked"
    assert server.CLIENT_AUTH_ENV not in os.environ, "the block's settings leaked"
    assert get_current_settings().flows.heartbeat_frequency == heartbeat_s
    with server.prefect_server(show_progress=False) as again:
        assert again == url
    assert server.status(state).pid == first.pid, "a second use started another server"
    assert server.healthy(url)
    assert server.stop(state).pid == first.pid
    psutil.Process(first.pid).wait(timeout=10)  # stop() returns once it has exited
    assert server.status(state) is None and not (state / "server.json").exists()


@pytest.mark.usefixtures("migrated")
def test_idle_server_stops_by_itself_but_not_while_leased(state, monkeypatch):
    monkeypatch.setenv(server.IDLE_ENV, "1")
    with server.prefect_server(show_progress=False):
        info = server.status(state)
        time.sleep(2.5)  # more than twice the idle period, with a lease held
        assert server.status(state) is not None, "stopped while a sweep used it"
    psutil.Process(info.pid).wait(timeout=60)  # stops about 1 s after the lease ends
    assert not (state / "server.json").exists()
    assert "no sweep for 1 s; stopping" in (state / "server.log").read_text()


@pytest.mark.usefixtures("migrated")
def test_a_sweep_arriving_while_the_idle_server_stops_waits_and_gets_a_new_one(state):
    """The monitor holds the lease lock exclusively while it shuts down; a sweep waits for it."""
    with server.prefect_server(show_progress=False):
        old = server.status(state)
    got: list[str] = []
    with open(state / "leases.lock", "a+") as monitor:
        fcntl.flock(monitor, fcntl.LOCK_EX)  # what the idle monitor holds until it is gone

        def sweep():
            with server.prefect_server(show_progress=False) as url:
                got.append(url)

        arriving = threading.Thread(target=sweep)
        arriving.start()
        time.sleep(2)
        assert not got, "a sweep got a lease on a server that was stopping"
        server.stop(state)
    arriving.join(timeout=600)
    assert got and server.healthy(got[0])
    assert server.status(state).pid != old.pid


@pytest.mark.usefixtures("migrated")
def test_a_named_server_is_used_with_the_users_own_auth_string(state, monkeypatch):
    with server.prefect_server(show_progress=False) as url:
        auth = os.environ[server.CLIENT_AUTH_ENV]
    monkeypatch.setenv("PREFECT_API_URL", url)
    monkeypatch.setenv(server.CLIENT_AUTH_ENV, "the user's own")
    with server.prefect_server(show_progress=False) as named:
        assert named == url and os.environ[server.CLIENT_AUTH_ENV] == "the user's own"
    assert (state / server.AUTH_FILE).read_text().strip() == auth  # not drawn again


def test_an_auth_string_others_may_read_is_refused(tmp_path):
    (tmp_path / server.AUTH_FILE).write_text("secret\n")
    (tmp_path / server.AUTH_FILE).chmod(0o644)
    with pytest.raises(server.ServerError, match="others may read"):
        server.auth_string(tmp_path)
    (tmp_path / server.AUTH_FILE).chmod(0o600)
    assert server.auth_string(tmp_path) == "secret"


def test_a_named_server_is_used_and_must_answer(state, monkeypatch):
    monkeypatch.setenv("PREFECT_API_URL", "http://127.0.0.1:9/api")  # discard port: nothing
    with pytest.raises(server.ServerError, match="does not answer"), server.prefect_server():
        pass
    assert not state.exists(), "a local server was started although one was named"


def test_a_server_that_cannot_start_is_one_error_line_and_exit_1(tmp_path):
    """A state folder the server cannot use (its database path is a folder) fails fast."""
    state = tmp_path / "broken"
    (state / "prefect.db").mkdir(parents=True)
    env = hermetic_env(tmp_path, ESKIN_SERVER_DIR=str(state))
    proc = eskin("server", "start", env=env, timeout=300)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert lines[-1].startswith("eskin: error: the Prefect server exited with status")
    assert str(state / "server.log") in lines[-1]


def test_server_commands(tmp_path, migrated_server_state):
    state = migrated_server_state(tmp_path / "cli-state")
    env = hermetic_env(tmp_path, ESKIN_SERVER_DIR=str(state))
    try:
        status = eskin("server", "status", "--json", env=env)
        assert status.returncode == 0 and json.loads(status.stdout)["running"] is False
        started = eskin("server", "start", "--json", env=env, timeout=600)
        assert started.returncode == 0, started.stderr
        url = json.loads(started.stdout)["ui_url"]
        status = eskin("server", "status", env=env)
        assert status.returncode == 0 and url in status.stdout
        assert f"The UI asks for the auth string in {state / server.AUTH_FILE}" in status.stdout
        shown = json.loads(eskin("server", "status", "--json", env=env).stdout)
        assert shown["auth_string_file"] == str(state / server.AUTH_FILE)
        stopped = eskin("server", "stop", env=env)
        assert stopped.returncode == 0 and "stopped" in stopped.stdout
        assert json.loads(eskin("server", "status", "--json", env=env).stdout)["running"] is False
    finally:
        server.stop(state)


@pytest.mark.usefixtures("migrated")
def test_start_lock_serialises_concurrent_starts(state):
    """Two processes that both find no server start only one between them."""
    code = (
        "import sys; sys.path.insert(0, '.')\n"
        "from flows import server\n"
        "with server.prefect_server(show_progress=False) as url: print(url)\n"
    )
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", code],
            stdout=subprocess.PIPE,
            text=True,
            env={**os.environ, server.SERVER_DIR_ENV: str(state)},
        )
        for _ in range(2)
    ]
    urls = {p.communicate(timeout=600)[0].strip() for p in procs}
    assert len(urls) == 1 and all(p.returncode == 0 for p in procs)
    # The leases were released with the processes: the monitor could lock exclusively now.
    with open(state / "leases.lock", "a+") as lease:
        fcntl.flock(lease, fcntl.LOCK_EX | fcntl.LOCK_NB)


def register(state, pid: int, started: float | None, root: str = "/runs/x") -> None:
    """Write a registry entry as :func:`flows.server.registered_run` does."""
    folder = state / server.RUNS_DIR
    folder.mkdir(parents=True, exist_ok=True)
    entry = {"pid": pid, "started": started, "what": "sweep 'smoke'", "root": root}
    (folder / f"{pid}-{started}.json").write_text(json.dumps(entry))


def test_server_stop_is_refused_while_a_live_run_uses_it_unless_forced(tmp_path):
    """A live run's entry refuses ``server stop`` in one line naming it (exit 1); a killed
    run's entry, or one whose PID was reused, never blocks it and is removed."""
    state = tmp_path / "cli-state"
    env = hermetic_env(tmp_path, ESKIN_SERVER_DIR=str(state))
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    try:
        started = psutil.Process(live.pid).create_time()
        register(state, live.pid, started, "/runs/live")
        register(state, os.getpid(), started - 1000.0, "/runs/reused")  # alive, another start
        dead = subprocess.Popen([sys.executable, "-c", "pass"])
        dead.wait()
        register(state, dead.pid, started, "/runs/killed")
        assert server.running_runs(state) == [
            server.RunningRun(live.pid, "sweep 'smoke'", "/runs/live")
        ]
        assert len(list((state / server.RUNS_DIR).iterdir())) == 1, "stale entries kept"
        refused = eskin("server", "stop", env=env)
        assert refused.returncode == 1 and refused.stdout == ""
        lines = refused.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(
            "eskin: error: the Prefect server is in use by 1 running run(s): "
            f"sweep 'smoke' of /runs/live (PID {live.pid});"
        )
        assert lines[0].endswith("or use --force")
        forced = eskin("server", "stop", "--force", env=env)
        assert forced.returncode == 0 and "no Prefect server was running" in forced.stdout
    finally:
        live.kill()
        live.wait()
    assert server.running_runs(state) == []
    stopped = eskin("server", "stop", env=env)
    assert stopped.returncode == 0, stopped.stderr
