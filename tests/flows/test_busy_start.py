"""A Prefect server that answers busy (503: its database held by other requests) as a run
starts: the run starts again and ends as it would have; busy at every start, the run fails in
one line and leaves the root as it was.

The busy answers are made in the sweep's own process (a subprocess of the test), in front of the
flow engine's real request that creates the flow run, as Prefect's client raises them; the rest
is the real command on the suite's server, a warm re-run of the smoke sweep's root (a copy).
"""

import json
import shutil
import subprocess
import sys

import pytest

from flows import record
from storage.locking import LOCK_NAME
from tests.flows.helpers import live_tree

#: The sweep's process: the first ``busy`` (argv[1]) creations of a flow run are answered 503,
#: then the command runs with ``argv[2:]``; the record's waits are shortened.
SCRIPT = """
import sys

import httpx
import prefect.client.orchestration as orchestration
from prefect.exceptions import PrefectHTTPStatusError

from flows import cli, record

busy = int(sys.argv[1])
create = orchestration.SyncPrefectClient.create_flow_run
calls = []


def busy_then_create(self, *args, **kwargs):
    calls.append(1)
    if len(calls) <= busy:
        request = httpx.Request("POST", f"{self.api_url}flow_runs/")
        response = httpx.Response(503, request=request, json={"detail": "database is locked"})
        answer = httpx.HTTPStatusError("503", request=request, response=response)
        raise PrefectHTTPStatusError.from_httpx_error(answer)
    return create(self, *args, **kwargs)


orchestration.SyncPrefectClient.create_flow_run = busy_then_create
record.START_WAITS_S = (0.1, 0.2)
status = cli.main(sys.argv[2:])
print(f"creations: {len(calls)}", file=sys.stderr)
sys.exit(status)
"""


def run_busy(busy: int, root, env) -> subprocess.CompletedProcess:
    command = ["sweep", "--grid", "smoke", "--root", str(root), "--json"]
    return subprocess.run(
        [sys.executable, "-c", SCRIPT, str(busy), *command],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
        stdin=subprocess.DEVNULL,
    )


def written(root) -> dict:
    """Each entry of ``root`` and when it was last written, but the lock file, which any run
    touches as it takes the lock."""
    return {
        path: (root / path).stat().st_mtime_ns for path in live_tree(root) if path.name != LOCK_NAME
    }


@pytest.fixture
def warm_root(smoke_sweep, tmp_path):
    root, _, env = smoke_sweep
    copy = tmp_path / "run"
    shutil.copytree(root, copy)
    return copy, env


@pytest.mark.slow
def test_a_run_whose_server_is_busy_as_it_starts_starts_again(warm_root):
    root, env = warm_root
    proc = run_busy(2, root, env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert summary["prefect_record"] == "complete"
    assert summary["cache_hits"] == summary["points"] > 0 and summary["computed"] == 0
    again = [line for line in proc.stderr.splitlines() if "(busy)" in line]
    assert len(again) == 2, proc.stderr
    assert again[0].startswith("eskin: the Prefect server at http://127.0.0.1:")
    assert again[0].endswith("answered 503 (busy) as the run started; starting it again in 0.1 s")
    assert again[1].endswith("starting it again in 0.2 s")
    assert "creations: 3" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.slow
def test_a_run_whose_server_stays_busy_fails_in_one_line_and_leaves_the_root(warm_root):
    root, env = warm_root
    before = written(root)
    proc = run_busy(3, root, env)
    assert proc.returncode == 1, proc.stderr[-3000:]
    assert proc.stdout == ""
    errors = [line for line in proc.stderr.splitlines() if line.startswith("eskin: error:")]
    assert len(errors) == 1, proc.stderr
    assert errors[0].endswith(
        "answered 503 (busy) to each of 3 starts of the run; nothing was computed; run it again"
    )
    assert "creations: 3" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert written(root) == before


def test_only_answers_that_ask_to_try_again_are_busy():
    import httpx

    request = httpx.Request("POST", "http://127.0.0.1:1/api/flow_runs/")
    for status, busy in ((503, 503), (429, 429), (500, None), (422, None)):
        answer = httpx.HTTPStatusError(
            str(status), request=request, response=httpx.Response(status, request=request)
        )
        assert record.busy_status(answer) == busy
    assert record.busy_status(httpx.ConnectError("refused")) is None
    assert record.busy_status(ValueError("503")) is None
