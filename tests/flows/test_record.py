"""The Prefect record of a run: what the server cannot take is kept and sent when it answers
again, in order, the newest of each artifact; what it refuses is counted lost."""

import threading
import time

import httpx
import pytest

from flows import record as records


class _Server:
    """A stand-in for the Prefect API: answers or not, records what it took."""

    def __init__(self):
        self.answers = True
        self.taken: list[tuple[str, object]] = []
        self.refuse: set[str] = set()
        #: Seconds each request takes (a busy server).
        self.slow_s = 0.0
        #: Requests still to answer "busy, try again" (503), or with a time-out.
        self.busy = 0
        self.timeouts = 0
        self.lock = threading.Lock()

    def client(self, sync_client=True):
        return _Client(self)


def status_error(status: int) -> httpx.HTTPStatusError:
    """The error Prefect's client raises for an answer of ``status``."""
    request = httpx.Request("POST", "http://127.0.0.1:9/api/")
    response = httpx.Response(status, request=request)
    return httpx.HTTPStatusError(str(status), request=request, response=response)


class _Client:
    def __init__(self, server):
        self.server = server

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def _take(self, what, payload):
        time.sleep(self.server.slow_s)
        with self.server.lock:
            if not self.server.answers:
                raise httpx.ConnectError("[Errno 111] Connection refused")
            if self.server.busy:
                self.server.busy -= 1
                raise status_error(503)
            if self.server.timeouts:
                self.server.timeouts -= 1
                raise httpx.ReadTimeout("timed out")
            if what in self.server.refuse:
                raise status_error(422)
            self.server.taken.append((what, payload))

    def create_logs(self, logs):
        from prefect.client.schemas.actions import LogCreate

        for log in logs:  # what the API takes, or a 422 as the real server gives
            try:
                LogCreate.model_validate(log)
            except ValueError as error:
                raise status_error(422) from error
        self._take("logs", [log["message"] for log in logs])

    def create_artifact(self, artifact):
        self._take(f"create:{artifact.key}", artifact.data)

        class _Made:
            id = f"id-{artifact.key}"

        return _Made()

    def update_artifact(self, artifact_id, update):
        self._take(f"update:{artifact_id}", update.data)

    def set_flow_run_state(self, run_id, state, force=False):
        self._take("state", state.type.value)


@pytest.fixture
def fake(monkeypatch):
    import prefect.client.orchestration as orchestration

    server = _Server()
    monkeypatch.setattr(orchestration, "get_client", server.client)
    monkeypatch.setattr(records, "healthy", lambda url, timeout_s=2.0: server.answers)
    monkeypatch.setattr(records, "PROBE_S", 0.05)
    monkeypatch.setattr(records, "BUSY_RETRY_S", 0.05)
    monkeypatch.setattr(records, "SEND_EVERY_S", 0.05)
    return server


def line(message):
    """A run-logger line as Prefect's API log handler gives the log sink."""
    import logging

    from prefect.logging.handlers import APILogHandler

    entry = logging.LogRecord("prefect.flow_runs", logging.INFO, __file__, 1, message, None, None)
    entry.flow_run_id = "8a6f6a2e-5c1e-4a43-9d2f-2f1f5b9e0c11"
    return APILogHandler().prepare(entry)


def settle(condition, timeout_s=10.0):
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.02)


def test_what_a_gone_server_could_not_take_is_sent_when_it_answers_again(fake):
    from prefect.states import Completed

    record = records.PrefectRecord("http://127.0.0.1:9/api")
    record.flow_run_id = "run"
    record.progress("p", 10.0, "points done")
    settle(lambda: ("create:p", 10.0) in fake.taken)

    fake.answers = False
    record.log(line("1 of 4 points done"))
    settle(lambda: record.down_since is not None)
    record.progress("p", 50.0, "points done")
    record.progress("p", 75.0, "points done")  # only the newest goes
    record.table("best", [{"model": "ffnn", "accuracy": 0.5}], "best point")
    record.log(line("3 of 4 points done"))
    record.final_state(Completed())
    time.sleep(0.3)
    assert fake.taken == [("create:p", 10.0)], "sent while the server did not answer"
    assert not record.complete

    fake.answers = True
    assert record.close(timeout_s=10)
    assert fake.taken[1:] == [
        ("logs", ["1 of 4 points done", "3 of 4 points done"]),
        ("update:id-p", 75.0),
        ("create:best", '[{"model": "ffnn", "accuracy": 0.5}]'),
        ("state", "COMPLETED"),
    ]
    assert record.complete and record.was_down


def test_a_server_that_never_answers_again_is_not_waited_for(fake):
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    fake.answers = False
    record.log(line("held"))
    settle(lambda: record.down_since is not None)
    start = time.monotonic()
    assert not record.close(timeout_s=30)
    assert time.monotonic() - start < 5
    note = record.incomplete_note()
    assert note.startswith("eskin: note: the Prefect record of this run is incomplete (its")
    assert "stopped answering at" in note and "results in the run root are complete" in note


def test_what_an_answering_server_refuses_is_counted_lost(fake):
    fake.refuse.add("create:bad")
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    record.table("bad", [{"x": 1}], "refused")
    record.table("good", [{"x": 2}], "taken")
    assert not record.close(timeout_s=10)
    assert [what for what, _ in fake.taken] == ["create:good"]
    assert record.lost == 1 and record.down_since is None


def test_a_server_too_busy_to_take_it_all_before_the_end_is_named_so(fake):
    fake.slow_s = 0.5
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    for i in range(4):
        record.table(f"t{i}", [{"x": i}], "slow")
    assert not record.close(timeout_s=0.2)
    assert record.down_since is None and not record.lost
    note = record.incomplete_note()
    assert "had not taken all of it when the run ended" in note, note
    assert "refused" not in note


def test_a_busy_server_taking_it_all_slowly_is_waited_for_while_it_takes(fake):
    """The end of a run waits while the server takes something within each ``timeout_s``, not
    a fixed time from the end: 12 requests of 0.1 s outlast a 0.5 s time-out."""
    fake.slow_s = 0.1
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    for i in range(12):
        record.table(f"t{i}", [{"x": i}], "slow")
    start = time.monotonic()
    assert record.close(timeout_s=0.5), record.incomplete_note()
    assert time.monotonic() - start > 0.5
    assert [what for what, _ in fake.taken] == [f"create:t{i}" for i in range(12)]


def test_a_busy_server_does_not_stop_the_end_of_the_run_for_longer_than_the_limit(fake):
    fake.slow_s = 0.1
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    for i in range(40):
        record.table(f"t{i}", [{"x": i}], "slow")
    start = time.monotonic()
    assert not record.close(timeout_s=0.5, limit_s=0.6)
    assert time.monotonic() - start < 1.5
    assert "had not taken all of it" in record.incomplete_note()


def test_busy_answers_and_time_outs_are_sent_again_not_lost(fake):
    """503 ("busy, try again") and a request that timed out: a busy server, neither gone nor
    refusing; what they did not take goes in order once it takes it."""
    fake.busy, fake.timeouts = 2, 1
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    record.log(line("first"))
    record.table("best", [{"x": 1}], "after the lines")
    assert record.close(timeout_s=10), record.incomplete_note()
    assert [what for what, _ in fake.taken] == ["logs", "create:best"]
    assert record.lost == 0 and not record.was_down


def test_a_slow_health_check_is_a_busy_server_not_a_gone_one(fake, monkeypatch):
    """A server that answers its health check in 3 s (a cold server on a busy machine) is
    answering: given :data:`flows.record.HEALTH_TIMEOUT_S`, not 2 s."""
    asked = []

    def healthy(url, timeout_s=2.0):
        asked.append(timeout_s)
        return timeout_s >= 3.0

    monkeypatch.setattr(records, "healthy", healthy)
    fake.refuse.add("create:bad")
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    record.table("bad", [{"x": 1}], "refused")
    assert not record.close(timeout_s=10)
    assert asked and min(asked) >= 3.0
    assert record.lost == 1 and record.down_since is None


def test_run_logger_lines_as_prefect_prepares_them_are_taken(fake):
    entry = line("Dask dashboard: http://127.0.0.1:8787/status")
    assert "__payload_size__" in entry  # what made the API refuse every batch
    record = records.PrefectRecord("http://127.0.0.1:9/api")
    record.log(entry)
    assert record.close(timeout_s=10)
    assert fake.taken == [("logs", ["Dask dashboard: http://127.0.0.1:8787/status"])]
    assert record.lost == 0
