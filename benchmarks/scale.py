"""High-density arrays and large datasets: a 32x32 scene against a 3x3 one, per taxel, and peak
memory of one point on the built-in data against a dataset 10x larger.

Every measurement runs ``python -m benchmarks.scale POINT`` in a fresh process with torch at one
thread and the allocator tuned (as on a Dask worker), so peak resident memory (``ru_maxrss``)
belongs to that point alone
and no run inherits another's heap. Runs of the two sides alternate; medians are quoted.
"""

from __future__ import annotations

import json
import resource
import statistics
import subprocess
import sys
import time

POINTS = {
    # name: (rows, cols, recordings per class, models)
    "3x3": (3, 3, 10, ("ffnn",)),
    "32x32": (32, 32, 10, ("ffnn",)),
    "paper": (3, 3, 10, ("ffnn", "cnn")),
    "paper-10x-data": (3, 3, 100, ("ffnn", "cnn")),
}


def measure(name: str) -> dict:
    """Run one point in this process; return wall seconds, stage seconds and peak RSS (bytes)."""
    import torch

    from flows.environment import tune_allocator
    from pipeline.design.scene import Scene
    from pipeline.run.simulate import run_scene

    torch.set_num_threads(1)
    tune_allocator()
    rows, cols, per_class, models = POINTS[name]
    scene = Scene.paper().replace(
        **{
            "array.rows": rows,
            "array.cols": cols,
            "dataset.recordings_per_class": per_class,
            "training.models": list(models),
        }
    )
    start = time.perf_counter()
    result = run_scene(scene)
    return {
        "wall_s": time.perf_counter() - start,
        "timings_s": result.timings_s,
        "peak_rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        "accuracy": {m.value: cv.mean for m, cv in result.accuracy.items()},
    }


def in_subprocess(name: str) -> dict:
    command = [sys.executable, "-m", "benchmarks.scale", name]
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def alternate(a: str, b: str, repeat: int) -> tuple[list[dict], list[dict]]:
    runs: tuple[list[dict], list[dict]] = ([], [])
    for _ in range(repeat):
        runs[0].append(in_subprocess(a))
        runs[1].append(in_subprocess(b))
    return runs


def median(runs: list[dict], key: str) -> float:
    return statistics.median(r[key] for r in runs)


def run(repeat: int = 3) -> list[dict]:
    small, large = alternate("3x3", "32x32", repeat)
    small_s, large_s = median(small, "wall_s"), median(large, "wall_s")
    stages = max(large[0]["timings_s"], key=large[0]["timings_s"].get)
    base, big = alternate("paper", "paper-10x-data", repeat)
    return [
        {
            "benchmark": "32x32 scene point (built-in data, FFNN) / 60 s",
            "ratio": large_s / 60,
            "target": "<= 1",
            "detail": f"{large_s:.1f} s; slowest stage {stages} "
            f"{statistics.median(r['timings_s'][stages] for r in large):.1f} s; "
            f"peak {median(large, 'peak_rss') / 2**20:.0f} MiB",
        },
        {
            "benchmark": "seconds per taxel: 32x32 / 3x3",
            "ratio": (large_s / 1024) / (small_s / 9),
            "target": "<= 1.3",
            "detail": f"3x3 {small_s:.1f} s ({small_s / 9 * 1e3:.0f} ms/taxel), "
            f"32x32 {large_s / 1024 * 1e3:.0f} ms/taxel",
        },
        {
            "benchmark": "peak memory of a paper point: 10x dataset / built-in",
            "ratio": median(big, "peak_rss") / median(base, "peak_rss"),
            "target": "~1 (chunked over recordings)",
            "detail": f"{median(base, 'peak_rss') / 2**20:.0f} MiB (120 recordings) vs "
            f"{median(big, 'peak_rss') / 2**20:.0f} MiB (1200), FFNN + CNN",
        },
    ]


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1])))
