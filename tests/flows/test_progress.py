"""Tests of flows.progress: which points of a finished task failed, and why."""

import pickle

from flows.progress import point_failures
from flows.work import PointsFailed


class _Finished:
    """A finished Dask future, as far as :func:`point_failures` looks at it."""

    def __init__(self, error=None):
        self.status = "error" if error else "finished"
        self.key = "points-abc"
        self._error = error

    def exception(self):
        return self._error


def test_point_failures_name_only_the_failed_points_of_a_partly_failed_task():
    assert point_failures(_Finished(), ["a", "b"]) == {}
    partly = PointsFailed({"b": "ValueError: bad"})
    assert point_failures(_Finished(partly), ["a", "b"]) == {"b": "point b: ValueError: bad"}
    whole = point_failures(_Finished(MemoryError("killed")), ["a", "b"])
    assert whole == {"a": "points-abc: killed", "b": "points-abc: killed"}
    again = pickle.loads(pickle.dumps(partly))  # Dask ships it back to the coordinator
    assert isinstance(again, PointsFailed) and again.failures == partly.failures
    assert "1 point(s) failed: b: ValueError: bad" in str(again)


def test_a_worker_leaves_a_write_failure_to_the_coordinator_and_logs_other_failures():
    import logging

    from flows.work import _WriteFailureFilter

    def record(exception_text):
        args = ("points-abc", "executing", "<Task ...>", exception_text, "  File ...")
        message = "Compute Failed\nKey: %s\nState: %s\nTask: %s\nException: %r\nTraceback: %r\n"
        return logging.LogRecord("distributed.worker", logging.ERROR, "", 0, message, args, None)

    quiet = _WriteFailureFilter()
    assert not quiet.filter(record("StoreWriteError('cannot write to run root r: x')"))
    assert quiet.filter(record("OSError(5, 'Input/output error')"))


def test_every_stop_names_its_real_cause():
    import threading

    from flows.progress import StopCause, describe_stop
    from storage import StoreWriteError

    written = StoreWriteError("/runs/x", "no space left on the device")
    assert describe_stop(written).startswith("a write to the run root failed (")
    assert describe_stop(KeyboardInterrupt()) == "it was interrupted (Ctrl-C or SIGTERM)"
    assert describe_stop(RuntimeError("boom")) == "RuntimeError: boom"
    for error in (KeyboardInterrupt(), RuntimeError("boom")):
        assert "write" not in describe_stop(error)

    cause = StopCause()
    assert cause.wait(timeout_s=0.01) == StopCause.CLUSTER_LOST  # cancelled with no cause noted
    threading.Timer(0.05, cause.note, args=(KeyboardInterrupt(),)).start()
    assert cause.wait(timeout_s=5) == "it was interrupted (Ctrl-C or SIGTERM)"
    cause.note(written)  # the first cause stays
    assert cause.wait(timeout_s=0) == "it was interrupted (Ctrl-C or SIGTERM)"
