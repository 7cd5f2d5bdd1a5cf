"""Beyond one machine: an existing ``dask scheduler`` with two ``dask worker`` processes, and the
Prefect deployment started with ``prefect deployment run``. Both stop every process by PID."""

import json
import subprocess
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from flows import server
from tests.flows.helpers import (
    BIN,
    api_headers,
    assert_same_cubes,
    eskin,
    hermetic_env,
    stop,
    wait_for,
)

pytestmark = pytest.mark.slow


def test_existing_scheduler_and_workers_give_identical_cubes(smoke_sweep, tmp_path):
    env = hermetic_env(tmp_path)
    scheduler_file = tmp_path / "scheduler.json"
    scheduler = subprocess.Popen(
        [
            BIN / "dask",
            "scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            "0",
            "--no-dashboard",
            "--scheduler-file",
            str(scheduler_file),
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    workers = []
    try:
        wait_for(scheduler_file.exists, 60, "the scheduler file")
        wait_for(
            lambda: json.loads(scheduler_file.read_text() or "{}").get("address"),
            30,
            "the scheduler address",
        )
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        workers = [
            subprocess.Popen(
                [
                    BIN / "dask",
                    "worker",
                    address,
                    "--nthreads",
                    "1",
                    "--host",
                    "127.0.0.1",
                    "--no-dashboard",
                ],
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            for _ in range(2)
        ]
        root = tmp_path / "run"
        proc = eskin(
            "sweep", "--grid", "smoke", "--root", str(root), "--address", address, "--json", env=env
        )
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert json.loads(proc.stdout)["computed"] == 7
        assert_same_cubes(smoke_sweep[0], root)
    finally:
        stop(*workers, scheduler)


def api_post(api: str, path: str, body: dict, auth: str | None) -> list[dict]:
    """POST ``body`` to the Prefect API, with ``auth`` as its basic-auth string."""
    request = urllib.request.Request(
        f"{api}/{path}", data=json.dumps(body).encode(), headers=api_headers(auth), method="POST"
    )
    with urllib.request.urlopen(request, timeout=60) as response:
        return json.loads(response.read())


def test_prefect_deployment_run(smoke_sweep, tmp_path, migrated_server_state):
    """``prefect deployment run sweep/default --watch`` on the local server ``eskin`` starts,
    with its auth string set as a user sets it; afterwards the API lists the run's task runs
    (one per named sweep) and its artifacts. Without the string the API answers 401."""
    state = migrated_server_state(tmp_path / "server-state")  # set up: no flow run in it yet
    # The runner of `eskin serve` asks for scheduled runs every second, not Prefect's 10.
    env = hermetic_env(tmp_path, ESKIN_SERVER_DIR=str(state), PREFECT_RUNNER_POLL_FREQUENCY="1")
    serving = None
    try:
        started = eskin("server", "start", "--json", env=env, timeout=900)
        assert started.returncode == 0, started.stderr[-2000:]
        info = json.loads(started.stdout)
        api = info["api_url"]
        auth = Path(info["auth_string_file"]).read_text().strip()
        with pytest.raises(urllib.error.HTTPError) as refused:
            api_post(api, "flow_runs/filter", {}, None)
        assert refused.value.code == 401
        env["PREFECT_API_URL"] = api
        env["PREFECT_API_AUTH_STRING"] = auth
        serving = subprocess.Popen(
            [BIN / "eskin", "serve", "--grid", "smoke"],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            cwd=tmp_path,
        )

        def deployed() -> bool:
            # The API itself (what `prefect deployment inspect` asks, without a CLI start each).
            request = urllib.request.Request(
                f"{api}/deployments/name/sweep/default", headers=api_headers(auth)
            )
            try:
                with urllib.request.urlopen(request, timeout=60) as response:
                    return response.status == 200
            except urllib.error.HTTPError as error:
                if error.code == 404:
                    return False
                raise

        wait_for(deployed, 180, "the deployment sweep/default", interval=0.5)
        root = tmp_path / "deployed"
        run = subprocess.run(
            [
                BIN / "prefect",
                "deployment",
                "run",
                "sweep/default",
                "--param",
                "grid=smoke",
                "--param",
                f"root={root}",
                "--param",
                "workers=1",
                "--watch",
                "--watch-timeout",
                "600",
            ],
            env=env,
            capture_output=True,
            text=True,
            timeout=700,
        )
        assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
        assert "Completed" in run.stdout + run.stderr
        assert_same_cubes(smoke_sweep[0], root)

        (flow_run,) = api_post(api, "flow_runs/filter", {}, auth)
        assert flow_run["state_type"] == "COMPLETED"
        task_runs = api_post(
            api, "task_runs/filter", {"flow_runs": {"id": {"any_": [flow_run["id"]]}}}, auth
        )
        names = sorted(t["name"] for t in task_runs)
        assert names[0].startswith("plan-")  # Prefect numbers unnamed task runs
        assert names[1:] == ["sweep-noise", "sweep-threshold", "sweep-window"]
        assert all(t["state_type"] == "COMPLETED" for t in task_runs)
        artifacts = api_post(
            api, "artifacts/filter", {"flow_runs": {"id": {"any_": [flow_run["id"]]}}}, auth
        )
        keys = {a["key"]: a for a in artifacts}
        assert {"smoke-threshold-best", "smoke-window-best", "smoke-noise-best"} <= set(keys)
        assert keys["smoke-progress"]["type"] == "progress"
        assert keys["smoke-progress"]["data"] == 100.0
        table = json.loads(keys["smoke-threshold-best"]["data"])
        assert {row["model"] for row in table} == {"ffnn", "cnn"}
    finally:
        stop(*(p for p in (serving,) if p is not None))
        server.stop(state)
