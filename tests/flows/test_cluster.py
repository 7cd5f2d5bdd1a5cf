"""``flows.cluster.check_workers``: the one rule for worker counts, CLI and Python alike."""

import numpy as np
import pytest

from flows.cluster import ClusterError, check_workers, dask_client


@pytest.mark.parametrize("value", [1, "3", np.int64(2)])
def test_whole_numbers_from_one_up_are_worker_counts(value):
    assert check_workers(value) == int(value)


@pytest.mark.parametrize("value", [0, -1, "0", "two", "1.5", 2.0, True, None])
def test_anything_else_is_refused_naming_the_value(value):
    with pytest.raises(ClusterError, match=r"need a whole number >= 1") as caught:
        check_workers(value)
    assert str(caught.value).startswith(repr(value))


def test_the_python_name_prefixes_the_message():
    with pytest.raises(ClusterError, match=r"^workers 0: need a whole number >= 1$"):
        check_workers(0, name="workers")


def test_a_local_cluster_is_refused_before_it_starts():
    with pytest.raises(ClusterError, match=r"^workers -2: "), dask_client(workers=-2):
        pytest.fail("a cluster started")


def test_tls_files_are_dasks_settings_and_only_for_a_tls_address(tmp_path):
    from flows.cluster import TLS_OPTIONS, tls_config

    none = dict.fromkeys(TLS_OPTIONS)
    assert tls_config(None, none) == {} == tls_config("tcp://127.0.0.1:1", none)
    files = {option: tmp_path / option.strip("-") for option in TLS_OPTIONS}
    for path in files.values():
        path.write_text("PEM")
    settings = tls_config("tls://10.0.0.1:8786", {o: str(p) for o, p in files.items()})
    assert settings == {TLS_OPTIONS[o]: str(p) for o, p in files.items()}
    with pytest.raises(ClusterError, match=r"^--tls-ca-file: only with --address tls://"):
        tls_config("tcp://10.0.0.1:8786", {**none, "--tls-ca-file": str(files["--tls-ca-file"])})
    missing = {**none, "--tls-cert": str(tmp_path / "no-cert"), "--tls-key": str(tmp_path)}
    with pytest.raises(ClusterError) as caught:
        tls_config("tls://10.0.0.1:8786", missing)
    assert str(caught.value) == (
        f"--tls-cert {tmp_path / 'no-cert'}: not a readable file; "
        f"--tls-key {tmp_path}: not a readable file"
    )


def test_a_tls_address_without_credentials_is_one_line_before_connecting():
    import dask

    blank = {name: None for name in ("ca-file", "client.cert", "client.key")}
    with (
        dask.config.set({f"distributed.comm.tls.{k}": v for k, v in blank.items()}),
        pytest.raises(ClusterError, match=r"TLS needs --tls-ca-file, --tls-cert, --tls-key \("),
        dask_client(address="tls://127.0.0.1:9", timeout_s=60),
    ):
        pytest.fail("connected")


def test_only_the_kill_of_a_worker_still_exiting_is_left_unsaid():
    import logging

    from flows.cluster import _exiting_worker_killed

    def record(message):
        return logging.LogRecord("distributed.nanny", logging.WARNING, "", 0, message, (), None)

    killed = record("Worker process still alive after 4.0 seconds, killing")
    assert not _exiting_worker_killed(killed)
    assert _exiting_worker_killed(record("Restarting worker"))


def _worker_logs(messages):
    """Which of ``messages`` this process's Dask worker logger lets through, at ERROR."""
    import logging

    logger = logging.getLogger("distributed.worker")
    records = [logging.LogRecord(logger.name, logging.ERROR, "", 0, m, (), None) for m in messages]
    return [bool(logger.filter(r)) for r in records]


@pytest.mark.slow
def test_a_local_worker_does_not_report_a_heartbeat_to_its_closed_scheduler():
    messages = ["Failed to communicate with scheduler during heartbeat.", "Compute Failed"]
    with dask_client(workers=1) as client:
        (said,) = client.run(_worker_logs, messages).values()
    assert said == [False, True]
