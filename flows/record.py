"""The Prefect record of a run: every call a sweep or a search makes to the Prefect API, guarded.

The run root's store is the truth and Prefect a window on it: a sweep (or a search) computes,
stores and writes its cubes whether its Prefect server answers or not. What the run tells
Prefect goes through one :class:`PrefectRecord`, which sends it from a thread of its own, so that
no step of the run waits for the server or fails with it:

- artifacts (progress, tables, links) are kept by key, the newest of each, and sent in order;
- run-logger lines are kept (at most :data:`MAX_HELD_LOGS`, the oldest dropped beyond) and sent
  in batches;
- what fails to go because the server does not answer is kept, not dropped: the record then
  asks the server's health check every :data:`PROBE_S` seconds and sends it all once the server
  answers again (the local server restarts on the port it had, :mod:`flows.server`); what an
  answering server refuses (a bad request) is dropped and counted as lost;
- a busy server is not a gone one: an answer "busy, try again" (:data:`BUSY_STATUSES`) or a
  request that timed out is kept and sent again after :data:`BUSY_RETRY_S`, and the health check
  that tells a gone server from a slow one waits up to :data:`HEALTH_TIMEOUT_S`. A local server
  on its first start, on a machine whose cores a sweep keeps busy, took 3 s to answer its health
  check, and about 2 s every few seconds while its services set up their state: a 2 s check
  took it for gone, and at the end of the run the record then gave up on it at once, as it gave
  up after 15 s on a server that was still taking what it held;
- task-run states travel as Prefect events over a websocket: Prefect's events client keeps the
  events the server has not confirmed and sends them again when it next connects, which an
  event of the record's own starts once the server answers again. Events the client reports
  lost are counted.

Prefect's HTTP client retries a failed request 5 times over about a minute in the thread that
made it. While a record is active the flow engine's own requests (the flow run's states) retry
:data:`ENGINE_RETRIES` times, a few seconds, and the record's own not at all (it retries in its
own time). When the engine cannot set the flow run's final state, the command line takes the
run's outcome from the record (its ``outcome``, an :class:`Outcome`) and the record sets that
state once the server answers.

The server may answer a request "busy, try again" (503, when other requests hold its SQLite
database; 429): the flow engine, which does not retry, then fails. Before the flow's body began
nothing ran, so the run starts again after each of :data:`START_WAITS_S` (:func:`started`, one
line on stderr each time); the server still busy after the last, the run fails in one line
(exit status 1) with nothing computed. A flow run the engine had made before the busy answer is
left pending on the server.

A run that ends with its record incomplete says so in one line
(:meth:`PrefectRecord.incomplete_note`); its results are complete and its exit status is that of
the run (0 for a sweep that finished).
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import sys
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, TypeVar

from flows.server import ServerError, healthy, registered_run

#: Seconds between health checks of a server that stopped answering.
PROBE_S = 2.0
#: Seconds between sends of what the record holds (run-logger lines come in batches).
SEND_EVERY_S = 1.0
#: Run-logger lines held while the server does not answer; older ones are dropped beyond.
MAX_HELD_LOGS = 20_000
#: Lines per request.
LOG_BATCH = 500
#: How long the health check that tells a gone server from a slow one waits for its answer (a
#: gone server's port refuses at once).
HEALTH_TIMEOUT_S = 30.0
#: Seconds before what a busy server did not take (a busy answer, a time-out) is sent again.
BUSY_RETRY_S = 1.0
#: At the end of a run, how long an answering server is given to take the next of what the record
#: holds: the wait goes on while it takes something within each such period (a busy server takes
#: a batch of lines in seconds), up to :data:`FLUSH_LIMIT_S` in all.
FLUSH_TIMEOUT_S = 15.0
#: At the end of a run, the longest wait for an answering server to take all the record holds.
FLUSH_LIMIT_S = 120.0
#: The same for a run that was interrupted (Ctrl-C, SIGTERM), which must end within seconds.
INTERRUPTED_FLUSH_S = 2.0
#: Retries of the flow engine's own requests while a record is active (Prefect's default, 5,
#: takes a minute per request when the server is gone; its transport still tries to connect
#: 4 times over about 3.5 s).
ENGINE_RETRIES = 0
#: Seconds waited before each new start of a flow whose server answered busy before its body
#: began (:func:`started`): doubling, as Prefect's own client backs off, 7 s in all.
START_WAITS_S = (1.0, 2.0, 4.0)
#: The HTTP statuses of an answer that asks the client to try again later.
BUSY_STATUSES = (429, 503)
#: Prefect's log lines that say an event was not sent (the record counts them instead).
_EVENT_LOSS = ("Unable to connect to", "Service 'EventsWorker' failed")
#: Prefect's loggers whose lines about a server that does not answer the record stands in for.
_QUIETED_LOGGERS = (
    "prefect.events.clients",
    "prefect._internal.concurrency",
    "prefect.flow_runs",
    "prefect.task_runs",
)

T = TypeVar("T")
_active: PrefectRecord | None = None


@dataclass
class Outcome:
    """How a flow's body ended: ``done`` once it returned (``value``) or raised (``error``)."""

    done: bool = False
    value: Any = None
    error: BaseException | None = None


class PrefectRecord:
    """What a run tells its Prefect server, sent from a thread of its own (module docstring).

    Use :func:`recording` to make one active; the flows find it there.
    """

    def __init__(self, api_url: str | None):
        self.api_url = api_url
        self.flow_run_id: Any = None
        self.outcome = Outcome()
        #: Wall time the server stopped answering, None while it answers.
        self.down_since: float | None = None
        #: Whether the server stopped answering at any time.
        self.was_down = False
        self.lost = 0
        self.events_lost_at: float | None = None
        self.reconnected_at: float | None = None
        self._cond = threading.Condition()
        self._items: OrderedDict[str, Callable[[Any], None]] = OrderedDict()
        self._logs: deque[dict[str, Any]] = deque()
        self._artifacts: dict[str, Any] = {}
        self._sending = False
        self._closed = False
        #: Monotonic time the server last took something (or the wait for it began).
        self._taken_at = time.monotonic()
        context = contextvars.copy_context()  # the settings of the run: API URL, auth string
        self._thread = threading.Thread(
            target=context.run, args=(self._run,), name="eskin-prefect-record", daemon=True
        )
        self._thread.start()

    # What a run tells Prefect ---------------------------------------------------------------

    def progress(self, key: str, percent: float, description: str) -> None:
        """Create, then update, the progress artifact ``key`` (``percent`` of 100)."""
        ids = _run_ids()

        def send(client: Any) -> None:
            from prefect.artifacts import ProgressArtifact
            from prefect.client.schemas.actions import ArtifactUpdate

            if key in self._artifacts:
                client.update_artifact(self._artifacts[key], ArtifactUpdate(data=percent))
                return
            artifact = ProgressArtifact(key=key, description=description, progress=percent)
            self._artifacts[key] = _create(client, artifact, ids).id

        self._put(f"progress:{key}", send)

    def table(self, key: str, table: list[dict[str, Any]], description: str) -> None:
        """Create the table artifact ``key``."""
        from prefect.artifacts import TableArtifact

        artifact = TableArtifact(key=key, description=description, table=table)
        ids = _run_ids()
        self._put(f"table:{key}", lambda client: _create(client, artifact, ids))

    def link(self, key: str, link: str, link_text: str, description: str) -> None:
        """Create the link artifact ``key``."""
        from prefect.artifacts import LinkArtifact

        artifact = LinkArtifact(key=key, link=link, link_text=link_text, description=description)
        ids = _run_ids()
        self._put(f"link:{key}", lambda client: _create(client, artifact, ids))

    def log(self, entry: dict[str, Any]) -> None:
        """Keep a run-logger line (Prefect's API log sink)."""
        # Prefect's handler sizes each line for its own batching in a "__payload_size__" key,
        # which its log worker drops before sending and the API refuses (422).
        entry = {key: value for key, value in entry.items() if key != "__payload_size__"}
        with self._cond:
            self._logs.append(entry)
            if len(self._logs) > MAX_HELD_LOGS:
                self._logs.popleft()
                self.lost += 1
            self._cond.notify()

    def final_state(self, state: Any) -> None:
        """Set the flow run's final ``state`` (the engine could not)."""
        run_id = self.flow_run_id
        if run_id is None:
            return
        self._put("state", lambda client: client.set_flow_run_state(run_id, state, force=True))

    # Its end --------------------------------------------------------------------------------

    def close(self, timeout_s: float = FLUSH_TIMEOUT_S, limit_s: float = FLUSH_LIMIT_S) -> bool:
        """Send what is held if the server answers, for as long as it takes something within
        each ``timeout_s``, ``limit_s`` at most; return whether the record is complete. A server
        that does not answer now is not waited for."""
        start = time.monotonic()
        if self.down_since is not None and self._answers(min(timeout_s, HEALTH_TIMEOUT_S)):
            self.down_since = None  # back: send at once rather than at the next probe
            self._reconnected()
        with self._cond:
            self._taken_at = time.monotonic()
            while self._held() or self._sending:
                now = time.monotonic()
                if self.down_since is not None or now - self._taken_at > timeout_s:
                    break
                if now - start > limit_s:
                    break
                self._cond.wait(0.1)
            self._closed = True  # what is still held stays so: nothing waits for it now
            self._cond.notify_all()
        self._drain_events(max(0.5, min(5.0, timeout_s - (time.monotonic() - self._taken_at))))
        return self.complete

    @property
    def complete(self) -> bool:
        """Nothing held, nothing lost, no event reported unsent. (Prefect's events client
        sends the events it kept again once the server answers, but does not say whether it
        did: an event once unsent counts, so that an incomplete record is never called
        complete.)"""
        return not self._held() and not self.lost and self.events_lost_at is None

    def incomplete_note(self) -> str:
        """One line: the Prefect record of this run is incomplete, why, and that the results
        are complete."""
        if self.down_since is not None:
            when = time.strftime("%H:%M:%S", time.localtime(self.down_since))
            why = f"its Prefect server ({self.api_url}) stopped answering at {when}"
        elif self.was_down:
            why = f"its Prefect server ({self.api_url}) stopped answering for a while"
        elif self._held():
            why = f"its Prefect server ({self.api_url}) had not taken all of it when the run ended"
        else:
            why = "its Prefect server refused part of it"
        return (
            f"eskin: note: the Prefect record of this run is incomplete ({why}); the results "
            "in the run root are complete"
        )

    # The sending thread ---------------------------------------------------------------------

    def _put(self, key: str, send: Callable[[Any], None]) -> None:
        with self._cond:
            self._items.pop(key, None)  # the newest of a key only, in the order of the last
            self._items[key] = send
            self._cond.notify()

    def _held(self) -> int:
        return len(self._items) + len(self._logs)

    def _run(self) -> None:
        import prefect.settings as names

        with names.temporary_settings({names.PREFECT_CLIENT_MAX_RETRIES: 0}):
            while not self._closed:
                with self._cond:
                    if not self._held() and not self._closed:
                        self._cond.wait(SEND_EVERY_S)
                if self._closed:
                    return
                if self.down_since is not None:
                    if not self._answers():
                        with self._cond:
                            self._cond.wait(PROBE_S)
                        continue
                    self.down_since = None
                    self._reconnected()
                self._send_held()

    def _send_held(self) -> None:
        from prefect.client.orchestration import get_client

        with self._cond:
            self._sending = True
        try:
            with get_client(sync_client=True) as client:
                while self.down_since is None:
                    with self._cond:
                        n_logs = min(LOG_BATCH, len(self._logs))
                        logs = [self._logs.popleft() for _ in range(n_logs)]
                        item = None if logs or not self._items else self._items.popitem(last=False)
                    if not logs and item is None:
                        return
                    try:
                        if logs:
                            client.create_logs(logs)
                        else:
                            item[1](client)
                    except Exception as error:  # whatever it was: kept, or counted lost
                        if self._failed(error, logs, item):
                            return  # busy: the next round sends it again
                    else:
                        with self._cond:
                            self._taken_at = time.monotonic()
                            self._cond.notify_all()
        except Exception as error:  # the client itself could not be made
            self._failed(error, [], None)
        finally:
            with self._cond:
                self._sending = False
                self._cond.notify_all()

    def _failed(self, error: Exception, logs: list[dict[str, Any]], item: Any) -> bool:
        """Keep what did not go if the server is busy or does not answer, count it lost if it
        refused it; return whether it was busy (then wait :data:`BUSY_RETRY_S`)."""
        busy = busy_status(error) is not None or _timed_out(error)
        if not busy and self._answers():
            self.lost += len(logs) + (item is not None)
            logging.getLogger(__name__).debug("Prefect refused part of the record: %s", error)
            return False
        with self._cond:
            self._logs.extendleft(reversed(logs))
            if item is not None and item[0] not in self._items:
                self._items[item[0]] = item[1]
                self._items.move_to_end(item[0], last=False)
            if busy:
                self._cond.wait(BUSY_RETRY_S)
                return True
        if self.down_since is None:
            self.down_since = time.time()
            self.was_down = True
        return False

    def _answers(self, timeout_s: float = HEALTH_TIMEOUT_S) -> bool:
        """Whether the server answers its health check within ``timeout_s``."""
        return bool(self.api_url) and healthy(self.api_url, timeout_s=timeout_s)

    def _reconnected(self) -> None:
        """The server answers again: have Prefect's events client send what it kept."""
        from prefect.settings import PREFECT_API_URL

        self.reconnected_at = time.time()
        # Without an API URL Prefect would start a temporary server to take the event.
        if self.flow_run_id is None or not PREFECT_API_URL.value():
            return
        with contextlib.suppress(Exception):
            from prefect.events import emit_event

            emit_event(
                event="eskin.record.reconnected",
                resource={"prefect.resource.id": f"prefect.flow-run.{self.flow_run_id}"},
            )

    def _drain_events(self, timeout_s: float) -> None:
        with contextlib.suppress(Exception):
            from prefect.events.worker import EventsWorker

            EventsWorker.drain_all(timeout=timeout_s)

    def _event_lost(self) -> None:
        self.events_lost_at = time.time()
        self._server_gone()

    def _server_gone(self) -> None:
        if self.down_since is None:
            self.down_since = time.time()
            self.was_down = True
        with self._cond:
            self._cond.notify_all()


def _timed_out(error: BaseException) -> bool:
    """Whether ``error`` is a request that got no answer in time: a busy server, not a gone one
    (whose port refuses at once)."""
    import httpx

    return isinstance(error, httpx.TimeoutException)


def _run_ids() -> tuple[Any, Any]:
    """The task run and flow run this call is made in (Prefect's run context)."""
    from prefect.utilities.context import get_task_and_flow_run_ids

    return get_task_and_flow_run_ids()


def _create(client: Any, artifact: Any, ids: tuple[Any, Any]) -> Any:
    """Create ``artifact`` for the task run and flow run ``ids`` with ``client``."""
    from prefect.client.schemas.actions import ArtifactCreate

    task_run_id, flow_run_id = ids
    return client.create_artifact(
        ArtifactCreate(
            type=artifact.type,
            key=artifact.key,
            description=artifact.description,
            task_run_id=task_run_id,
            flow_run_id=flow_run_id,
            data=artifact.format(_sync=True),
        )
    )


class _ServerGoneFilter(logging.Filter):
    """Drops Prefect's lines (and tracebacks) about a server that does not answer, which the
    record's one line replaces, and tells the record."""

    def __init__(self, record: PrefectRecord):
        super().__init__()
        self.record = record

    def filter(self, entry: logging.LogRecord) -> bool:
        import httpx

        if entry.name in _QUIETED_LOGGERS[:2] and entry.getMessage().startswith(_EVENT_LOSS):
            self.record._event_lost()
            return False
        error = entry.exc_info[1] if entry.exc_info else None
        gone = isinstance(error, httpx.TransportError) and not _timed_out(error)
        if gone or "ConnectError(" in entry.getMessage():
            self.record._server_gone()
            return False
        return True


@contextlib.contextmanager
def recording(api_url: str | None = None) -> Iterator[PrefectRecord]:
    """Make a :class:`PrefectRecord` of the Prefect server at ``api_url`` (default: Prefect's
    ``PREFECT_API_URL``) active for the block; yield it, or the one already active.

    The record is closed (:meth:`PrefectRecord.close`) at the end of the block that made it.
    """
    global _active
    if _active is not None:
        yield _active
        return
    import prefect.settings as names
    from prefect.events.clients import PrefectEventsClient
    from prefect.events.worker import EventsWorker
    from prefect.logging.handlers import set_api_log_sink

    api_url = api_url or names.PREFECT_API_URL.value()
    filters = []
    with names.temporary_settings({names.PREFECT_CLIENT_MAX_RETRIES: ENGINE_RETRIES}):
        record = PrefectRecord(api_url)
        _active = record
        set_api_log_sink(record.log)
        if api_url:
            # The same client type (Prefect emits only through the types it knows), trying
            # twice instead of 11 times per event, a second apart, while the server is gone.
            EventsWorker.set_client_override(
                PrefectEventsClient, api_url=api_url, reconnection_attempts=1
            )
        for name in _QUIETED_LOGGERS:
            filters.append((logging.getLogger(name), _ServerGoneFilter(record)))
            filters[-1][0].addFilter(filters[-1][1])
        flush_s = (FLUSH_TIMEOUT_S, FLUSH_LIMIT_S)
        try:
            yield record
        except BaseException as error:
            if not isinstance(error, Exception):  # interrupted: end within seconds
                flush_s = (INTERRUPTED_FLUSH_S, INTERRUPTED_FLUSH_S)
            raise
        finally:
            try:
                record.close(*flush_s)
            finally:
                set_api_log_sink(None)
                EventsWorker.set_client_override(None)
                for logger, each in filters:
                    logger.removeFilter(each)
                _active = None


def active_record() -> PrefectRecord | None:
    """The active record, if any."""
    return _active


def run_recorded(body: Callable[[PrefectRecord], T], *, what: str, root: str) -> T:
    """Run a flow's ``body`` with the active record (or one of its own), noting its outcome,
    while registered as a run of the local server (:func:`flows.server.registered_run`) of
    ``what`` (``sweep``, ``optimize``) in ``root``."""
    from prefect.runtime import flow_run

    with recording() as record:
        record.flow_run_id = flow_run.get_id()
        with registered_run(record.api_url, what=what, root=root):
            try:
                value = body(record)
            except BaseException as error:
                record.outcome = Outcome(done=True, error=error)
                raise
            record.outcome = Outcome(done=True, value=value)
            return value


def busy_status(error: BaseException) -> int | None:
    """The status of a Prefect API answer that asks the client to try again later
    (:data:`BUSY_STATUSES`), None for any other error."""
    import httpx

    if isinstance(error, httpx.HTTPStatusError):
        if error.response.status_code in BUSY_STATUSES:
            return error.response.status_code
    return None


def started(record: PrefectRecord, call: Callable[[], T]) -> T:
    """``call()``, a flow's run with ``record`` active; called again after each of
    :data:`START_WAITS_S` while it fails with a busy answer (:func:`busy_status`) before the
    flow's body began (the record has no flow run id yet), as the module docstring says.

    Raises
    ------
    ServerError
        Still busy after the last wait (exit status 1); the busy answer is its cause.
    """
    waits = iter(START_WAITS_S)
    while True:
        try:
            return call()
        except Exception as error:
            status = busy_status(error)
            if status is None or record.flow_run_id is not None or record.outcome.done:
                raise
            where = record.api_url or "the Prefect API"
            wait_s = next(waits, None)
            if wait_s is None:
                tries = len(START_WAITS_S) + 1
                raise ServerError(
                    f"the Prefect server at {where} answered {status} (busy) to each of {tries} "
                    "starts of the run; nothing was computed; run it again"
                ) from error
            print(
                f"eskin: the Prefect server at {where} answered {status} (busy) as the run "
                f"started; starting it again in {wait_s:g} s",
                file=sys.stderr,
                flush=True,
            )
            time.sleep(wait_s)
