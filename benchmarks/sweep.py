"""The fixed cost of a sweep: cold and warm runs of a grid, local server vs temporary server.

Each sweep runs as the user runs it, in a subprocess: ``eskin sweep --json`` on a long-lived
local Prefect server that this suite starts once (``eskin server start``, its state in a
temporary folder) and stops at the end. Side by side runs the path Prefect takes when no server
is configured: the flow called with no ``PREFECT_API_URL``, so Prefect starts a temporary server
inside the run (and fails the run when that server does not answer within 20 s).

Rows: a cold run of the grid on 2 workers and on 1 (both on the local server); the fixed
overhead of the cold 2-worker run, ``wall - (sum of stage seconds) / workers`` (idle workers
count as overhead); warm re-runs of the cold root (nothing to compute), the two paths
interleaved after one uncounted round, medians quoted; the peak resident set of any Dask worker
process, sampled every 0.2 s.

``python -m benchmarks.sweep [--grid smoke]`` runs this suite alone and prints its rows;
``ESKIN_BENCH_SWEEP_GRID=smoke`` picks the grid within ``python -m benchmarks`` too. The
``paper`` grid's two cold runs take several minutes on 2 cores; the ``smoke`` grid's, seconds.
``run(tiny=True)`` runs every step on :data:`TINY_GRID` (two points of ``smoke`` trained for one
epoch), with one warm round and no uncounted one, on the local server ``$ESKIN_SERVER_DIR``
names if set (the test suite's).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import psutil

from flows.server import IDLE_ENV, MARKER, SERVER_DIR_ENV
from flows.server import stop as stop_server
from pipeline.run.stages import RESULTS, SPIKES
from storage import SweepStore

GRID_ENV = "ESKIN_BENCH_SWEEP_GRID"
DEFAULT_GRID = "paper"
WORKERS = 2
REPEAT = 3
COLD_TARGET_S = 300.0
OVERHEAD_TARGET_S = 5.0
WARM_TARGET_S = 3.0
SPEEDUP_TARGET = 1.7
MEMORY_TARGET = 1.5 * 2**30
#: A safety net should this process die without its ``finally``; sweeps hold leases meanwhile.
SERVER_IDLE_S = 600
STOP_GRACE_S = 30.0
SAMPLE_S = 0.2
REPO = Path(__file__).resolve().parents[1]

#: The grid of ``run(tiny=True)`` here and in the suites that share this one's steps: two points
#: of ``smoke``, one epoch of training each.
TINY_GRID = """\
name = "tiny"
base = "smoke"
[sweeps.threshold]
set = { "training.epochs" = 1 }
axes = { "readout.threshold_v" = [0.05, 0.09] }
"""

#: The flow called directly, as before the local server: Prefect starts its temporary server.
TEMPORARY_SERVER_SWEEP = (
    "import json, sys\n"
    "from flows.sweep import sweep\n"
    "summary = sweep(grid=sys.argv[1], root=sys.argv[2], workers=int(sys.argv[3]))\n"
    "print(json.dumps(summary, default=str))\n"
)


@dataclass(frozen=True)
class Run:
    """One finished subprocess: wall seconds, exit status, output, peak Dask worker RSS (bytes)."""

    wall_s: float
    status: int
    stdout: str
    stderr: str
    peak_worker_rss: int

    def failure(self) -> str:
        lines = [line for line in self.stderr.splitlines() if line.strip()]
        return f"exit status {self.status}: {lines[-1] if lines else 'no output'}"

    def summary(self) -> dict:
        """The JSON object the sweep printed last on stdout (it opens a line with ``{``)."""
        start = self.stdout.rfind("\n{") + 1
        return json.loads(self.stdout[start:])


def run_command(command: list[str], env: dict[str, str], *, reap: bool = True) -> Run:
    """Run ``command`` from the repository; sample its Dask workers' memory while it runs.

    Every descendant seen is stopped by PID once the command ends (``reap``), or when this
    process is interrupted, except the local Prefect server, which :func:`run` stops.
    """
    seen: dict[int, psutil.Process] = {}
    peak = 0
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        process = subprocess.Popen(
            command, cwd=REPO, env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=err
        )
        try:
            parent = psutil.Process(process.pid)
            while True:
                try:
                    process.wait(timeout=SAMPLE_S)
                    break
                except subprocess.TimeoutExpired:
                    pass
                with contextlib.suppress(psutil.Error):
                    for child in parent.children(recursive=True):
                        seen.setdefault(child.pid, child)
                        if "spawn_main" in " ".join(child.cmdline()):
                            peak = max(peak, child.memory_info().rss)
            wall = time.perf_counter() - start
        finally:
            if process.poll() is None:
                process.terminate()  # a sweep unwinds on SIGTERM and stops its Dask cluster
                try:
                    process.wait(timeout=STOP_GRACE_S)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
                reap = True
            if reap:
                _stop_leftovers(list(seen.values()))
        out.seek(0)
        err.seek(0)
        return Run(wall, process.returncode, out.read().decode(), err.read().decode(), peak)


def _stop_leftovers(processes: list[psutil.Process]) -> None:
    """SIGTERM, then SIGKILL, the processes still running (psutil skips reused PIDs)."""
    alive = []
    for p in processes:
        with contextlib.suppress(psutil.Error):
            if p.is_running() and MARKER not in " ".join(p.cmdline()):
                p.terminate()
                alive.append(p)
    _, stubborn = psutil.wait_procs(alive, timeout=STOP_GRACE_S)
    for p in stubborn:
        with contextlib.suppress(psutil.Error):
            p.kill()


def eskin(*args: str, env: dict[str, str]) -> Run:
    return run_command([sys.executable, "-m", "flows.cli", *args], env, reap=False)


def local_sweep(grid: str, root: Path, workers: int, env: dict[str, str]) -> Run:
    """``eskin sweep --json``: uses the local server already up; a failure is an error."""
    run = run_command(
        [
            sys.executable,
            "-m",
            "flows.cli",
            "sweep",
            "--grid",
            grid,
            "--root",
            str(root),
            "--workers",
            str(workers),
            "--json",
        ],
        env,
    )
    if run.status != 0:
        raise RuntimeError(f"eskin sweep --grid {grid} failed, {run.failure()}")
    return run


def temporary_server_sweep(grid: str, root: Path, workers: int, env: dict[str, str]) -> Run:
    """The flow with no server configured; a failure (a slow temporary server) is recorded."""
    code = [sys.executable, "-c", TEMPORARY_SERVER_SWEEP, grid, str(root), str(workers)]
    return run_command(code, env)


def tiny_grid(folder: Path) -> str:
    """:data:`TINY_GRID` written into ``folder``: its path, as ``--grid`` takes it."""
    path = folder / "tiny.toml"
    path.write_text(TINY_GRID)
    return str(path)


def hermetic_env(tmp: Path) -> dict[str, str]:
    """This environment without Prefect settings or a server of the user's; offline."""
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith("PREFECT_") and k not in (SERVER_DIR_ENV, IDLE_ENV)
    }
    return env | {
        SERVER_DIR_ENV: str(tmp / "server"),
        IDLE_ENV: str(SERVER_IDLE_S),
        "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
        "DO_NOT_TRACK": "1",
    }


@contextlib.contextmanager
def local_server(tmp: Path, shared: bool = False) -> Iterator[dict[str, str]]:
    """:func:`hermetic_env` of ``tmp`` with the local Prefect server up for the ``with`` block:
    a server of its own (state in ``tmp/server``), stopped at the end; with ``shared``, the one
    ``$ESKIN_SERVER_DIR`` names when set (the test suite's), started if need be and left
    running, which spares a tiny run a server's start-up."""
    given = os.environ.get(SERVER_DIR_ENV) if shared else None
    server = Path(given) if given else tmp / "server"
    env = hermetic_env(tmp) | {SERVER_DIR_ENV: str(server)}
    try:
        started = eskin("server", "start", "--quiet", "--json", env=env)
        if started.status != 0:
            raise RuntimeError(f"eskin server start failed, {started.failure()}")
        yield env
    finally:
        if not given:
            stop_server(server)


def temporary_server_env(env: dict[str, str], state: Path) -> dict[str, str]:
    """``env`` with Prefect's, Dask's and matplotlib's state under ``state``, as the CLI sets."""
    folders = {
        "PREFECT_HOME": state / "prefect",
        "DASK_TEMPORARY_DIRECTORY": state / "dask",
        "MPLCONFIGDIR": state / "matplotlib",
    }
    for folder in folders.values():
        folder.mkdir(parents=True, exist_ok=True)
    # --json sets the same level in eskin sweep: both paths log alike.
    return env | {k: str(v) for k, v in folders.items()} | {"PREFECT_LOGGING_LEVEL": "WARNING"}


def stage_seconds(root: Path) -> float:
    """Sum of the seconds the workers paid for every computed point (each second charged to one
    point: a shared load or set-up once). For results stored before paid seconds were kept: spike
    stages once per spike entry, coding and training once per result (coding a rate matrix,
    which the store does not keep, is timed by each result that needed it)."""
    store = SweepStore.open(root)
    results = store.read_many(
        RESULTS.record, store.complete_keys(RESULTS.name), discard_corrupt=False
    )
    if results and all(entry.paid is not None for entry in results.values()):
        return sum(v for e in results.values() for steps in e.paid.values() for v in steps.values())
    spikes = store.read_many(SPIKES.record, store.complete_keys(SPIKES.name), discard_corrupt=False)
    total = sum(sum(entry.seconds.values()) for entry in spikes.values())
    for entry in results.values():
        total += sum(v for k, v in entry.seconds.items() if k == "coding" or k.startswith("train_"))
    return total


def warm_runs(
    grid: str,
    root: Path,
    env: dict[str, str],
    temporary_env: dict[str, str],
    repeat: int,
    warm_up: bool = True,
) -> tuple[list[Run], list[Run]]:
    """Re-runs of a computed root, interleaved (local, temporary, ...); the first round warms
    both paths up (the temporary server's database is created then) and is left out, unless
    not ``warm_up``."""
    local: list[Run] = []
    temporary: list[Run] = []
    for round_ in range(repeat + warm_up):
        a = local_sweep(grid, root, WORKERS, env)
        b = temporary_server_sweep(grid, root, WORKERS, temporary_env)
        if round_ or not warm_up:
            local.append(a)
            temporary.append(b)
    return local, temporary


def run(grid: str | None = None, repeat: int = REPEAT, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: :data:`TINY_GRID` for ``grid``, one warm round, not warmed up, on a
    shared local server (:func:`local_server`)."""
    with tempfile.TemporaryDirectory(prefix="eskin-bench-") as name:
        tmp = Path(name)
        if tiny:
            grid, repeat = tiny_grid(tmp), 1
        grid = grid or os.environ.get(GRID_ENV) or DEFAULT_GRID
        with local_server(tmp, shared=tiny) as env:
            two = local_sweep(grid, tmp / "two", WORKERS, env)
            busy = stage_seconds(tmp / "two")
            one = local_sweep(grid, tmp / "one", 1, env)
            warm, temporary = warm_runs(
                grid,
                tmp / "two",
                env,
                temporary_server_env(env, tmp / "temporary"),
                repeat,
                warm_up=not tiny,
            )
    label = Path(grid).stem  # a grid file by its name
    points = two.summary()["points"]
    overhead = two.wall_s - busy / WORKERS
    warm_s = statistics.median(r.wall_s for r in warm)
    hits = warm[-1].summary()["cache_hits"]
    done = [r for r in temporary if r.status == 0]
    if done:
        temporary_s = statistics.median(r.wall_s for r in done)
        versus = f"temporary server {temporary_s:.1f} s ({temporary_s / warm_s:.1f}x)"
    else:
        versus = "temporary server: no run finished"
    failed = [r for r in temporary if r.status != 0]
    if failed:
        versus += (
            f"; {len(failed)} of {len(temporary)} temporary-server runs failed, "
            f"{failed[0].failure()}"
        )
    peak = max(two.peak_worker_rss, one.peak_worker_rss)
    return [
        {
            "benchmark": f"{label} grid cold, {WORKERS} workers ({points} points) / "
            f"{COLD_TARGET_S:.0f} s",
            "ratio": two.wall_s / COLD_TARGET_S,
            "target": "<= 1",
            "detail": f"{two.wall_s:.0f} s, local server up",
        },
        {
            "benchmark": f"{label} grid cold: fixed overhead / {OVERHEAD_TARGET_S:.0f} s",
            "ratio": overhead / OVERHEAD_TARGET_S,
            "target": "<= 1",
            "detail": f"{overhead:.1f} s = {two.wall_s:.1f} s wall - {busy:.1f} stage-seconds / "
            f"{WORKERS} workers, local server up",
        },
        {
            "benchmark": f"{label} grid warm re-run, {WORKERS} workers / {WARM_TARGET_S:.0f} s",
            "ratio": warm_s / WARM_TARGET_S,
            "target": "<= 1",
            "detail": f"medians of {repeat}, interleaved: local server {warm_s:.1f} s vs "
            f"{versus}; {hits} cache hits",
        },
        {
            "benchmark": f"{label} grid cold: 1 worker / {WORKERS} workers",
            "ratio": one.wall_s / two.wall_s,
            "target": f">= {SPEEDUP_TARGET}",
            "detail": f"1 worker {one.wall_s:.0f} s",
        },
        {
            "benchmark": f"peak Dask worker memory / {MEMORY_TARGET / 2**30:.1f} GiB",
            "ratio": peak / MEMORY_TARGET,
            "target": "<= 1",
            "detail": f"{peak / 2**20:.0f} MiB",
        },
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.sweep",
        description="Benchmark a sweep's fixed cost: local Prefect server vs temporary server.",
    )
    parser.add_argument(
        "--grid",
        help=f"a built-in grid or a grid TOML file (default: ${GRID_ENV} or {DEFAULT_GRID}; "
        "smoke for a check in a few minutes)",
    )
    parser.add_argument("--repeat", type=int, default=REPEAT, help="counted warm runs of each path")
    args = parser.parse_args(argv)
    rows = run(args.grid, args.repeat)
    width = max(len(r["benchmark"]) for r in rows)
    print(f"{'benchmark':{width}s}  {'ratio':>8s}  target / detail")
    for r in rows:
        print(f"{r['benchmark']:{width}s}  {r['ratio']:8.2f}  {r['target']}; {r['detail']}")


if __name__ == "__main__":
    main()
