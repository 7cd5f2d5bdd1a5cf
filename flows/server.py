"""A local Prefect server that outlives a sweep, so the UI keeps the history of every run.

``eskin sweep`` (and ``eskin serve``) use the server named by ``PREFECT_API_URL`` when one is
set. Otherwise they use a local server whose state (its SQLite database, its log, ``server.json``
naming its PID and port) lives in one folder, ``runs/.prefect`` beside the run roots by default
(``ESKIN_SERVER_DIR`` names another). The first sweep that finds no server running starts one,
on 127.0.0.1 and a free port; later sweeps reuse it. It stops with ``eskin server stop``, or by
itself once no sweep has used it for ``ESKIN_SERVER_IDLE_S`` seconds (30 minutes by default).

Start-up waits as long as the machine needs: a first start sets up the database, which took
15-20 s on a busy 2-core machine, beyond Prefect's own 20 s limit for its temporary server. It
fails only when the server process exits, or after ``ESKIN_SERVER_START_TIMEOUT_S`` (15 minutes
by default), with a :class:`ServerError` naming the log to read.

The local server asks every client for an auth string (Prefect's basic authentication): on
its first start ``eskin`` draws one (``secrets.token_urlsafe``) and keeps it in
``<state>/auth-string``, readable by its owner alone (mode 0600, in a folder only its owner
enters), starts the server with it (``PREFECT_SERVER_API_AUTH_STRING``) and hands it to every
client of its own (``PREFECT_API_AUTH_STRING``). Another user of the machine who reaches the
port can neither read nor start nor cancel runs. The UI asks for the string once per browser;
``eskin server status`` says where it is. A server named by ``PREFECT_API_URL`` is the user's:
their own ``PREFECT_API_AUTH_STRING``, if any, is used as it is.

Who uses the server is told by leases: a process that uses it holds a shared ``flock`` on
``leases.lock`` for as long as it does. The server's idle monitor tries for an exclusive lock
now and then; it gets it only when no lease is held, and once that has been so for the idle
period it keeps the lock and shuts the server down. A sweep that wants a lease meanwhile waits
for that shutdown to end, finds no server, and starts a new one, so a sweep never gets a server
that is about to stop. The kernel drops a killed process's locks, so a killed sweep holds no
lease.

Which runs use the local server is told by a registry beside its state: a sweep or a search
(its flow, from the command line or a deployment) keeps ``runs/<id>.json`` there, naming its
process (PID and start time), what it is and its run root, for as long as it runs
(:func:`registered_run`). :func:`running_runs` lists the entries whose process still runs
(the same PID *and* start time, so a killed run's entry, or its PID reused, never counts) and
removes the others. ``eskin server stop`` refuses while it lists any, unless forced.

The server restarts on the port it last had (kept in ``<state>/port``) when that port is free,
so a run whose server was stopped or killed finds it again at the same address once anything
starts it again, and so do the UI's bookmarks.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import secrets
import signal
import subprocess
import sys
import threading
import time
import urllib.request
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from flows.environment import restored_environment
from pipeline.errors import EskinError

SERVER_DIR_ENV = "ESKIN_SERVER_DIR"
IDLE_ENV = "ESKIN_SERVER_IDLE_S"
START_TIMEOUT_ENV = "ESKIN_SERVER_START_TIMEOUT_S"
DEFAULT_SERVER_DIR = Path("runs") / ".prefect"
DEFAULT_IDLE_S = 1800.0
DEFAULT_START_TIMEOUT_S = 900.0
HOST = "127.0.0.1"
#: The file of the state folder that holds the local server's auth string.
AUTH_FILE = "auth-string"
#: The setting that carries the auth string to the server.
SERVER_AUTH_ENV = "PREFECT_SERVER_API_AUTH_STRING"
#: The setting that carries the auth string to every client.
CLIENT_AUTH_ENV = "PREFECT_API_AUTH_STRING"
#: In the server's command line; a PID whose command line lacks it is not our server.
MARKER = "flows.server"
STOP_GRACE_S = 30.0
#: The folder of the state folder that registers the runs using the server.
RUNS_DIR = "runs"
#: The file of the state folder that keeps the port the server last listened on.
PORT_FILE = "port"


class ServerError(EskinError):
    """The Prefect server cannot be started or reached: the run fails (exit status 1)."""

    exit_status = 1


@dataclass(frozen=True)
class ServerInfo:
    """A running local server: its process and where it listens."""

    pid: int
    port: int
    state_dir: Path

    @property
    def ui_url(self) -> str:
        """The server's UI, ``http://127.0.0.1:<port>``."""
        return f"http://{HOST}:{self.port}"

    @property
    def api_url(self) -> str:
        """The server's API, ``<ui_url>/api`` (what ``PREFECT_API_URL`` names)."""
        return f"{self.ui_url}/api"


def server_dir() -> Path:
    """The local server's state folder: ``$ESKIN_SERVER_DIR`` or ``runs/.prefect``."""
    return Path(os.environ.get(SERVER_DIR_ENV) or DEFAULT_SERVER_DIR).absolute()


def auth_file(state: Path | None = None) -> Path:
    """The file that holds the local server's auth string (which the UI asks for)."""
    return (state or server_dir()) / AUTH_FILE


def auth_string(state: Path) -> str:
    """The local server's auth string: read from :func:`auth_file`, or drawn and written
    there (mode 0600, created exclusively) on first use.

    Raises
    ------
    ServerError
        The file is readable by others than its owner, or empty.
    """
    path = auth_file(state)
    try:
        handle = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        handle = None
    if handle is not None:
        text = secrets.token_urlsafe(32)
        with os.fdopen(handle, "w", encoding="utf-8") as file:
            file.write(text + "\n")
        return text
    if path.stat().st_mode & 0o077:
        raise ServerError(
            f"{path}: others may read the Prefect server's auth string (chmod 600 it, or "
            "delete it to draw a new one)"
        )
    text = path.read_text(encoding="utf-8").strip()
    if not text:
        raise ServerError(f"{path}: empty (delete it to draw a new auth string)")
    return text


def _seconds_from_env(name: str, default: float) -> float:
    text = os.environ.get(name)
    if text is None:
        return default
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0:
        raise EskinError(f"{name}={text!r}: need a number of seconds > 0")
    return value


def healthy(api_url: str, timeout_s: float = 2.0) -> bool:
    """Whether the Prefect API at ``api_url`` answers its health check."""
    try:
        with urllib.request.urlopen(f"{api_url}/health", timeout=timeout_s) as response:
            return response.status == 200
    except (OSError, ValueError):
        return False


def status(state: Path | None = None) -> ServerInfo | None:
    """The local server of ``state`` if its process runs and answers, else None."""
    info = _recorded(state or server_dir())
    if info is None or not healthy(info.api_url):
        return None
    return info


@contextlib.contextmanager
def prefect_server(*, show_progress: bool = True) -> Iterator[str]:
    """Use a Prefect server for the duration of the block; yield its API URL.

    ``PREFECT_API_URL``, when set, names the server (it must answer). Otherwise the local server
    is started if none runs, and a lease keeps it from stopping while the block runs; Prefect
    (imported or not) uses it inside the block.

    Raises
    ------
    ServerError
        The named server does not answer, or the local one could not start.
    """
    named = os.environ.get("PREFECT_API_URL")
    if named:
        if not healthy(named, timeout_s=30.0):
            raise ServerError(f"PREFECT_API_URL={named}: the Prefect server does not answer")
        yield named
        return
    state = server_dir()
    state.mkdir(mode=0o700, parents=True, exist_ok=True)  # its database, log and auth string
    with open(state / "leases.lock", "a+") as lease:
        # Blocks only while an idle server shuts down (its monitor holds the lock exclusively).
        fcntl.flock(lease, fcntl.LOCK_SH)
        with _exclusive(state / "start.lock"):
            auth = auth_string(state)
            info = status(state) or _start(state, auth, show_progress=show_progress)
        with _using(info, auth):
            yield info.api_url


@contextlib.contextmanager
def _using(info: ServerInfo, auth: str) -> Iterator[None]:
    """Point Prefect at ``info``, with its auth string, for the block, and send it no flow-run
    heartbeats.

    Heartbeats only feed automations that mark silent runs as crashed, and the local server
    has none; Prefect's heartbeat thread, which wakes once a second, would still hold up the
    end of every flow run by up to a second. A server named by ``PREFECT_API_URL`` keeps
    Prefect's own setting.
    """
    settings = {
        "PREFECT_API_URL": info.api_url,
        "PREFECT_UI_URL": info.ui_url,
        CLIENT_AUTH_ENV: auth,
    }
    with restored_environment(settings):
        # Set before Prefect is imported too: it reads the environment when imported.
        os.environ.update(settings)
        import prefect.settings as names

        with names.temporary_settings(
            {getattr(names, k): v for k, v in settings.items()}
            | {names.PREFECT_FLOWS_HEARTBEAT_FREQUENCY: None}
        ):
            yield


@dataclass(frozen=True)
class RunningRun:
    """A run registered as using the local server, whose process still runs."""

    pid: int
    what: str
    root: str

    def __str__(self) -> str:
        return f"{self.what} of {self.root} (PID {self.pid})"


class ServerBusyError(EskinError):
    """``eskin server stop`` refused: runs use the server (exit status 1)."""

    exit_status = 1


def _process_started(pid: int) -> float | None:
    """The start time of process ``pid`` (psutil's), None if it does not run."""
    import psutil

    try:
        process = psutil.Process(pid)
        if process.status() == psutil.STATUS_ZOMBIE:
            return None
        return process.create_time()
    except psutil.Error:
        return None


@contextlib.contextmanager
def registered_run(api_url: str | None, *, what: str, root: str) -> Iterator[None]:
    """Register this process as a run of ``what`` in ``root`` using the local server, for the
    block, if ``api_url`` is that server's API (a server named by ``PREFECT_API_URL`` that is
    not the local one is not ours to stop)."""
    state = server_dir()
    info = _recorded(state)
    if info is None or api_url != info.api_url:
        yield
        return
    folder = state / RUNS_DIR
    folder.mkdir(mode=0o700, exist_ok=True)
    entry = folder / f"{uuid.uuid4().hex}.json"
    pid = os.getpid()
    entry.write_text(
        json.dumps({"pid": pid, "started": _process_started(pid), "what": what, "root": root})
    )
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            entry.unlink()


def running_runs(state: Path | None = None) -> list[RunningRun]:
    """The runs registered with the local server of ``state`` whose process still runs; the
    entries of runs that ended without removing theirs (killed) are removed."""
    folder = (state or server_dir()) / RUNS_DIR
    found = []
    for entry in sorted(folder.glob("*.json")) if folder.is_dir() else ():
        try:
            data = json.loads(entry.read_text())
            pid, started = int(data["pid"]), data["started"]
            run = RunningRun(pid, str(data["what"]), str(data["root"]))
        except FileNotFoundError:
            continue  # removed as it ended
        except (OSError, ValueError, KeyError, TypeError):
            started, run = None, None  # unreadable: not a live run's
        if run is not None and started is not None and _process_started(run.pid) == started:
            found.append(run)
        else:
            with contextlib.suppress(OSError):
                entry.unlink()
    return found


def check_stoppable(state: Path | None = None) -> None:
    """Raise :class:`ServerBusyError`, naming them, if runs use the local server."""
    runs = running_runs(state)
    if runs:
        raise ServerBusyError(
            f"the Prefect server is in use by {len(runs)} running run(s): "
            f"{'; '.join(map(str, runs))}; stopping it would leave their Prefect record "
            "incomplete (their results would still be complete): wait for them, or use --force"
        )


def stop(state: Path | None = None) -> ServerInfo | None:
    """Stop the local server of ``state`` (SIGTERM, SIGKILL after a grace); return what ran."""
    state = state or server_dir()
    info = _recorded(state)
    if info is None:
        return None
    os.kill(info.pid, signal.SIGTERM)
    deadline = time.monotonic() + STOP_GRACE_S
    while _alive(info.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    if _alive(info.pid):
        os.kill(info.pid, signal.SIGKILL)
    with contextlib.suppress(FileNotFoundError):
        (state / "server.json").unlink()
    return info


def _start(state: Path, auth: str, *, show_progress: bool) -> ServerInfo:
    """Start the local server, asking clients for ``auth``, and wait until it answers (as long
    as a busy machine needs)."""
    from tqdm import tqdm

    timeout_s = _seconds_from_env(START_TIMEOUT_ENV, DEFAULT_START_TIMEOUT_S)
    idle_s = _seconds_from_env(IDLE_ENV, DEFAULT_IDLE_S)
    port = _free_port(_last_port(state))
    log_path = state / "server.log"
    env = {
        **os.environ,
        "PREFECT_HOME": str(state),
        "PREFECT_SERVER_API_HOST": HOST,
        "PREFECT_SERVER_API_PORT": str(port),
        "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
        "DO_NOT_TRACK": "1",
        "MPLCONFIGDIR": str(state / "matplotlib"),
        SERVER_AUTH_ENV: auth,
    }
    for name in ("PREFECT_API_URL", "PREFECT_UI_URL", CLIENT_AUTH_ENV):
        env.pop(name, None)
    with open(log_path, "ab") as log:
        process = subprocess.Popen(
            [sys.executable, "-m", MARKER, str(state), str(port), repr(idle_s)],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # a Ctrl-C of the sweep must not stop the shared server
        )
    info = ServerInfo(process.pid, port, state)
    (state / "server.json").write_text(json.dumps({"pid": info.pid, "port": info.port}))
    (state / PORT_FILE).write_text(f"{port}\n")
    start = time.monotonic()
    with tqdm(
        desc=f"starting the Prefect server on {info.ui_url}",
        bar_format="{desc} ({elapsed})",
        file=sys.stderr,
        disable=None if show_progress else True,
        leave=False,
    ) as bar:
        while not healthy(info.api_url):
            if process.poll() is not None:
                raise ServerError(
                    f"the Prefect server exited with status {process.returncode} while "
                    f"starting; see {log_path}"
                )
            if time.monotonic() - start > timeout_s:
                stop(state)
                raise ServerError(
                    f"the Prefect server did not answer within {timeout_s:.0f} s "
                    f"({START_TIMEOUT_ENV}); see {log_path}"
                )
            time.sleep(0.25)
            bar.refresh()
    return info


def _recorded(state: Path) -> ServerInfo | None:
    try:
        data = json.loads((state / "server.json").read_text())
        info = ServerInfo(int(data["pid"]), int(data["port"]), state)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return info if _is_ours(info.pid) else None


def _is_ours(pid: int) -> bool:
    """Whether ``pid`` runs this module (a reused PID is left alone)."""
    try:
        cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return False
    return _alive(pid) and MARKER.encode() in cmdline


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists and has not exited (a zombie has)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[-1].split()[0] not in ("Z", "X")


@contextlib.contextmanager
def _exclusive(path: Path) -> Iterator[None]:
    with open(path, "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield


def _last_port(state: Path) -> int | None:
    """The port the server of ``state`` last listened on, if known."""
    try:
        return int((state / PORT_FILE).read_text())
    except (OSError, ValueError):
        return None


def _free_port(wanted: int | None = None) -> int:
    """``wanted`` if it is free on 127.0.0.1, else a free port."""
    import socket

    for port in (wanted, 0) if wanted else (0,):
        with socket.socket() as s:
            # As the server binds (uvicorn): connections of its last run in TIME_WAIT do not
            # keep it from its port.
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                s.bind((HOST, port))
            except OSError:
                continue
            return s.getsockname()[1]
    raise ServerError("no free port on 127.0.0.1")


# ---------------------------------------------------------------------------------------------
# The server process: ``python -m flows.server STATE PORT IDLE_S``


def _watch_idle(state: Path, idle_s: float, server: object) -> None:
    """Shut ``server`` down once no lease has been held for ``idle_s`` seconds."""
    poll_s = min(10.0, idle_s / 4)
    lease = open(state / "leases.lock", "a+")  # held until the process exits
    last_used = time.monotonic()
    while not server.should_exit:
        time.sleep(poll_s)
        try:
            fcntl.flock(lease, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            last_used = time.monotonic()
            continue
        if time.monotonic() - last_used >= idle_s:
            # Keep the lock until the process is gone: a new sweep waits, then starts afresh.
            print(f"eskin: no sweep for {idle_s:.0f} s; stopping", flush=True)
            server.should_exit = True
            return
        fcntl.flock(lease, fcntl.LOCK_UN)


def main(argv: list[str]) -> int:
    """Run the local server in this process (``python -m flows.server STATE PORT IDLE_S``).

    ``argv`` holds the state folder, the port and the idle period in seconds, as the process
    that starts the server passes them. The Prefect API and UI are served on 127.0.0.1 at that
    port until stopped (SIGTERM) or idle for ``IDLE_S`` seconds; ``server.json`` is then removed
    if it names this process. Returns the exit status, 0.
    """
    import uvicorn

    state, port, idle_s = Path(argv[0]), int(argv[1]), float(argv[2])
    config = uvicorn.Config(
        "prefect.server.api.server:create_app",
        factory=True,
        host=HOST,
        port=port,
        log_level="warning",
        lifespan="on",
    )
    server = uvicorn.Server(config)
    threading.Thread(target=_watch_idle, args=(state, idle_s, server), daemon=True).start()
    try:
        server.run()
    finally:
        recorded = state / "server.json"
        with contextlib.suppress(OSError, ValueError):
            if json.loads(recorded.read_text()).get("pid") == os.getpid():
                recorded.unlink()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
