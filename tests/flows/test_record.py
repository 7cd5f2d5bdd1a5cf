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
        self.lock = threading.Lock()

    def client(self, sync_client=True):
        return _Client(self)


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
            if what in self.server.refuse:
                raise httpx.HTTPStatusError("422", request=None, response=None)
            self.server.taken.append((what, payload))

    def create_logs(self, logs):
        from prefect.client.schemas.actions import LogCreate

        for log in logs:  # what the API takes, or a 422 as the real server gives
            try:
                LogCreate.model_validate(log)
            except ValueError as error:
                raise httpx.HTTPStatusError("422", request=None, response=None) from error
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

    record = records.Record("http://127.0.0.1:9/api")
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
    record = records.Record("http://127.0.0.1:9/api")
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
    record = records.Record("http://127.0.0.1:9/api")
    record.table("bad", [{"x": 1}], "refused")
    record.table("good", [{"x": 2}], "taken")
    assert not record.close(timeout_s=10)
    assert [what for what, _ in fake.taken] == ["create:good"]
    assert record.lost == 1 and record.down_since is None


def test_a_server_too_busy_to_take_it_all_before_the_end_is_named_so(fake):
    fake.slow_s = 0.5
    record = records.Record("http://127.0.0.1:9/api")
    for i in range(4):
        record.table(f"t{i}", [{"x": i}], "slow")
    assert not record.close(timeout_s=0.2)
    assert record.down_since is None and not record.lost
    note = record.incomplete_note()
    assert "had not taken all of it when the run ended" in note, note
    assert "refused" not in note


def test_run_logger_lines_as_prefect_prepares_them_are_taken(fake):
    entry = line("Dask dashboard: http://127.0.0.1:8787/status")
    assert "__payload_size__" in entry  # what made the API refuse every batch
    record = records.Record("http://127.0.0.1:9/api")
    record.log(entry)
    assert record.close(timeout_s=10)
    assert fake.taken == [("logs", ["Dask dashboard: http://127.0.0.1:8787/status"])]
    assert record.lost == 0
