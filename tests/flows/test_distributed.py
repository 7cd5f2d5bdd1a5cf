"""Beyond one machine: an existing ``dask scheduler`` with two ``dask worker`` processes, and the
Prefect deployment started with ``prefect deployment run``. Both stop every process by PID."""

import json
import subprocess
import urllib.request

from tests.flows.helpers import (
    BIN,
    assert_same_cubes,
    eskin,
    free_port,
    hermetic_env,
    stop,
    wait_for,
)


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


def test_prefect_deployment_run(smoke_sweep, tmp_path):
    port = free_port()
    api = f"http://127.0.0.1:{port}/api"
    env = hermetic_env(tmp_path, PREFECT_API_URL=api)
    server = subprocess.Popen(
        [BIN / "prefect", "server", "start", "--host", "127.0.0.1", "--port", str(port)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    serving = None
    try:

        def healthy():
            try:
                with urllib.request.urlopen(f"{api}/health", timeout=2) as response:
                    return response.status == 200
            except OSError:
                return False

        wait_for(healthy, 180, "the Prefect server")
        serving = subprocess.Popen(
            [BIN / "eskin", "serve", "--grid", "smoke"],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            cwd=tmp_path,
        )

        def deployed():
            inspect = subprocess.run(
                [BIN / "prefect", "deployment", "inspect", "sweep/default"],
                env=env,
                capture_output=True,
                timeout=60,
            )
            return inspect.returncode == 0

        wait_for(deployed, 180, "the deployment sweep/default", interval=2)
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
    finally:
        stop(*(p for p in (serving, server) if p is not None))
