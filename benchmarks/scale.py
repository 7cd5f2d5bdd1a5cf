"""High-density arrays and large datasets: a 32x32 scene against a 3x3 one, per taxel, and peak
memory of one point on the built-in data against a dataset 10x larger.

Every measurement runs ``python -m benchmarks.scale POINT`` in a fresh process with torch at one
thread and the allocator tuned (as on a Dask worker), so peak resident memory (``ru_maxrss``)
belongs to that point alone
and no run inherits another's heap. Runs of the two sides alternate; medians are quoted.

``run(tiny=True)`` compares the same way points of :data:`TINY_POINTS` (1x1 against 2x2 taxels,
4 against 8 short recordings per class, 1 epoch), once each.
"""

from __future__ import annotations

import json
import resource
import statistics
import subprocess
import sys
import time
from typing import Any

#: Each point: the fields it sets on the ``paper`` scene.
POINTS: dict[str, dict[str, Any]] = {
    "3x3": {"array.rows": 3, "array.cols": 3, "training.models": ["ffnn"]},
    "32x32": {"array.rows": 32, "array.cols": 32, "training.models": ["ffnn"]},
    "paper": {"array.rows": 3, "array.cols": 3},
    "paper-10x-data": {"array.rows": 3, "array.cols": 3, "dataset.recordings_per_class": 100},
}
#: The (small, large) pairs of points compared: taxels, then recordings.
PAIRS = (("3x3", "32x32"), ("paper", "paper-10x-data"))
_TINY = {"dataset.duration_s": 1.5, "training.epochs": 1, "training.folds": 4}
TINY_POINTS: dict[str, dict[str, Any]] = {
    "tiny-1x1": {
        **_TINY,
        "array.rows": 1,
        "array.cols": 1,
        "dataset.recordings_per_class": 4,
        "training.models": ["ffnn"],
    },
    "tiny-2x2": {
        **_TINY,
        "array.rows": 2,
        "array.cols": 2,
        "dataset.recordings_per_class": 4,
        "training.models": ["ffnn"],
    },
    "tiny-data": {**_TINY, "array.rows": 1, "array.cols": 1, "dataset.recordings_per_class": 4},
    "tiny-2x-data": {**_TINY, "array.rows": 1, "array.cols": 1, "dataset.recordings_per_class": 8},
}
TINY_PAIRS = (("tiny-1x1", "tiny-2x2"), ("tiny-data", "tiny-2x-data"))


def measure(name: str) -> dict:
    """Run one point in this process; return wall seconds, stage seconds and peak RSS (bytes)."""
    import torch

    from flows.environment import tune_allocator
    from pipeline.design.scene import Scene
    from pipeline.run.simulate import run_scene

    torch.set_num_threads(1)
    tune_allocator()
    scene = Scene.paper().replace(**{**POINTS, **TINY_POINTS}[name])
    start = time.perf_counter()
    result = run_scene(scene)
    return {
        "taxels": scene.array.rows * scene.array.cols,
        "recordings": scene.dataset.recordings_per_class,
        "models": [m.value.upper() for m in scene.training.models],
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


def run(repeat: int = 3, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: the points of :data:`TINY_PAIRS`, once each (module docstring)."""
    (few, many), (base_name, big_name) = TINY_PAIRS if tiny else PAIRS
    repeat = 1 if tiny else repeat
    small, large = alternate(few, many, repeat)
    small_s, large_s = median(small, "wall_s"), median(large, "wall_s")
    n_small, n_large = small[0]["taxels"], large[0]["taxels"]
    stages = max(large[0]["timings_s"], key=large[0]["timings_s"].get)
    base, big = alternate(base_name, big_name, repeat)
    return [
        {
            "benchmark": f"{many} scene point (built-in data, FFNN) / 60 s",
            "ratio": large_s / 60,
            "target": "<= 1",
            "detail": f"{large_s:.1f} s; slowest stage {stages} "
            f"{statistics.median(r['timings_s'][stages] for r in large):.1f} s; "
            f"peak {median(large, 'peak_rss') / 2**20:.0f} MiB",
        },
        {
            "benchmark": f"seconds per taxel: {many} / {few}",
            "ratio": (large_s / n_large) / (small_s / n_small),
            "target": "<= 1.3",
            "detail": f"{few} {small_s:.1f} s ({small_s / n_small * 1e3:.0f} ms/taxel), "
            f"{many} {large_s / n_large * 1e3:.0f} ms/taxel",
        },
        {
            "benchmark": f"peak memory of a {base_name} point: {big_name} / {base_name}",
            "ratio": median(big, "peak_rss") / median(base, "peak_rss"),
            "target": "~1 (chunked over recordings)",
            "detail": f"{median(base, 'peak_rss') / 2**20:.0f} MiB "
            f"({base[0]['recordings']} recordings per class) vs "
            f"{median(big, 'peak_rss') / 2**20:.0f} MiB ({big[0]['recordings']}), "
            + " + ".join(base[0]["models"]),
        },
    ]


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1])))
