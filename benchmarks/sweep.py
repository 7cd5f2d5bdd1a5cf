"""The paper grid on the built-in data: cold vs warm, 2 workers vs 1, overhead, worker memory.

Each sweep runs as the user runs it (``eskin sweep`` in a subprocess, its own temporary Prefect
server included). Overhead is the part of a cold run's wall time not spent in the stages
themselves: ``wall - (sum of stage seconds) / workers`` (idle workers count as overhead).
Peak memory is the largest resident set of any Dask worker process, sampled every 0.2 s.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil

from storage import EntryKind, SweepStore

GRID = "paper"


def run_sweep(root: Path, workers: int, grid: str = GRID) -> dict:
    """Run one sweep; return its summary, wall seconds and peak worker RSS (bytes)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PREFECT_")}
    command = [
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
    ]
    start = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env)
    peak = 0
    parent = psutil.Process(process.pid)
    while process.poll() is None:
        try:
            for child in parent.children(recursive=True):
                if "spawn_main" in " ".join(child.cmdline()):
                    peak = max(peak, child.memory_info().rss)
        except psutil.Error:
            pass
        time.sleep(0.2)
    wall = time.perf_counter() - start
    out = process.stdout.read()
    if process.returncode != 0:
        raise RuntimeError(f"eskin sweep failed ({process.returncode})")
    return {"summary": json.loads(out), "wall_s": wall, "peak_worker_rss": peak}


def stage_seconds(root: Path) -> float:
    """Sum of every computed stage's seconds: spike stages once per spike entry."""
    store = SweepStore.open(root)
    total = 0.0
    for kind in (EntryKind.SPIKES, EntryKind.RATES, EntryKind.RESULTS):
        folder = store.path / kind.value
        for key in (p.name for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".")):
            if kind is EntryKind.SPIKES:
                total += sum(store.read_spikes(key).seconds.values())
            elif kind is EntryKind.RATES:
                total += sum(store.read_rates(key).seconds.values())
            else:
                seconds = store.read_result(key).seconds
                total += sum(v for k, v in seconds.items() if k.startswith("train_"))
    return total


def run() -> list[dict]:
    with tempfile.TemporaryDirectory(prefix="eskin-bench-") as tmp:
        two = run_sweep(Path(tmp) / "two", workers=2)
        warm = run_sweep(Path(tmp) / "two", workers=2)
        one = run_sweep(Path(tmp) / "one", workers=1)
        busy = stage_seconds(Path(tmp) / "two")
    points = two["summary"]["points"]
    overhead = two["wall_s"] - busy / 2
    return [
        {
            "benchmark": f"paper grid cold, 2 workers ({points} points) / 600 s",
            "ratio": two["wall_s"] / 600,
            "target": "<= 1 (issue 3); <= 0.5 (issue 6)",
            "detail": f"{two['wall_s']:.0f} s",
        },
        {
            "benchmark": "paper grid warm / cold",
            "ratio": warm["wall_s"] / two["wall_s"],
            "target": "<= 0.05",
            "detail": f"warm {warm['wall_s']:.1f} s, {warm['summary']['cache_hits']} cache hits",
        },
        {
            "benchmark": "paper grid cold: 1 worker / 2 workers",
            "ratio": one["wall_s"] / two["wall_s"],
            "target": ">= 1.6 (issue 3), >= 1.7 (issue 6)",
            "detail": f"1 worker {one['wall_s']:.0f} s",
        },
        {
            "benchmark": "Prefect + Dask overhead / cold wall",
            "ratio": overhead / two["wall_s"],
            "target": "<= 0.15",
            "detail": f"{overhead:.0f} s of {two['wall_s']:.0f} s not in stages "
            f"({busy:.0f} stage-seconds over 2 workers)",
        },
        {
            "benchmark": "peak worker memory / 2 GB",
            "ratio": max(two["peak_worker_rss"], one["peak_worker_rss"]) / 2**31,
            "target": "<= 1 (issue 3), <= 0.75 (issue 6)",
            "detail": f"{max(two['peak_worker_rss'], one['peak_worker_rss']) / 2**20:.0f} MiB",
        },
    ]
