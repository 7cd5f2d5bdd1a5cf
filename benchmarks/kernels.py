"""Does a fresh worker pay to compile? The first point's ``readout`` seconds over a later point's.

Each measurement is a fresh Python process, as a fresh Dask worker is: it loads the built-in
recordings and fits their front end (the paper scene's), then runs the spike level
(:data:`pipeline.run.stages.SPIKES`) of the paper's operating point three times, three points of
equal work, each on a stopwatch of its own. The numba kernels are found in the disk cache (as by
every sweep after the first: the cache is filled by an uncounted process first), so the first
point pays their load in its ``setup`` step (charged as shared) and its ``readout`` step
should cost what a later point's does.

Rows: the median over :data:`REPEAT` processes of the first point's ``readout`` work seconds
over the median of the later points' (target <= 1.2); and the first point's ``setup`` step
with a warm cache over that with an empty one (``NUMBA_CACHE_DIR`` a new folder: every kernel
compiled), medians of the same processes, the compile seconds a sweep after the first saves.

``run(tiny=True)`` measures one process of each kind at the ``smoke`` point, the compiling one
filling the cache the other loads (no uncounted process). ``python -m benchmarks.kernels
[--repeat N]`` runs this suite alone and prints its rows.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPEAT = 5
TARGET = 1.2
POINTS = 3

#: One fresh process: the seconds of every step of each of POINTS points of the built-in scene
#: named by its argument, as JSON.
_FRESH_WORKER = f"""
import json, sys
from pipeline.design.scene import Scene
from pipeline.run.stages import FRONT_END, RECORDINGS, SPIKES
from pipeline.run.stopwatch import Stopwatch

scene = Scene.builtin(sys.argv[1])
outputs = {{}}
for level in (RECORDINGS, FRONT_END):
    outputs[level.name] = level.run(scene, outputs, Stopwatch(None))
points = []
for _ in range({POINTS}):
    watch = Stopwatch(None)
    SPIKES.run(scene, outputs, watch)
    points.append({{"work": watch.seconds, "paid": watch.paid_total()}})
print(json.dumps(points))
"""


def fresh_worker(cache_dir: Path | None, scene: str = "paper") -> list[dict]:
    """The steps' seconds of each point of the built-in ``scene`` in one fresh process;
    ``cache_dir``: the kernels' disk cache (None: the default one)."""
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = str(cache_dir)
    done = subprocess.run(
        [sys.executable, "-c", _FRESH_WORKER, scene],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    if done.returncode != 0:
        raise RuntimeError(f"fresh worker failed: {done.stderr[-2000:]}")
    return json.loads(done.stdout.splitlines()[-1])


def measure(repeat: int = REPEAT, scene: str = "paper", warm_up: bool = True) -> dict:
    """Medians over ``repeat`` pairs of fresh processes at the built-in ``scene``: one compiling
    into an empty cache, one loading from a filled cache (filled by an uncounted process when
    ``warm_up``, else by the first compiling one)."""
    ratios, first_s, later_s, warm_compile_s, cold_compile_s, old_first_s = [], [], [], [], [], []
    with tempfile.TemporaryDirectory(prefix="eskin-bench-compile-") as tmp:
        warm = Path(tmp) / "warm" if warm_up else Path(tmp) / "cold-0"
        if warm_up:
            fresh_worker(warm, scene)  # fills the cache: not counted
        for i in range(repeat):
            cold = fresh_worker(Path(tmp) / f"cold-{i}", scene)
            points = fresh_worker(warm, scene)
            readout = [p["work"]["readout"] for p in points]
            first_s.append(readout[0])
            later_s.append(statistics.median(readout[1:]))
            ratios.append(readout[0] / statistics.median(readout[1:]))
            warm_compile_s.append(points[0]["paid"]["setup"])
            cold_compile_s.append(cold[0]["paid"]["setup"])
            # The first point's readout as it was measured before the kernels' load or compile
            # was kept apart: all of it, in the first step that called a kernel.
            old_first_s.append(cold[0]["paid"]["setup"] + cold[0]["work"]["readout"])
    return {
        "ratio": statistics.median(ratios),
        "first_s": statistics.median(first_s),
        "later_s": statistics.median(later_s),
        "warm_compile_s": statistics.median(warm_compile_s),
        "cold_compile_s": statistics.median(cold_compile_s),
        "old_first_s": statistics.median(old_first_s),
        "repeat": repeat,
        "scene": scene,
    }


def rows(result: dict) -> list[dict]:
    return [
        {
            "benchmark": "first point's readout / a later point's, fresh worker, cached kernels",
            "ratio": result["ratio"],
            "target": f"<= {TARGET}",
            "detail": f"medians of {result['repeat']} processes: first {result['first_s']:.4f} s, "
            f"later {result['later_s']:.4f} s ({result['scene']} point)",
        },
        {
            "benchmark": "kernels: load from the disk cache / compile (first point's compile step)",
            "ratio": result["warm_compile_s"] / result["cold_compile_s"],
            "target": "< 1",
            "detail": f"{result['warm_compile_s']:.2f} s loaded vs "
            f"{result['cold_compile_s']:.2f} s compiled (before: first readout "
            f"{result['old_first_s']:.2f} s with an empty cache)",
        },
    ]


def run(repeat: int = REPEAT, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: one process of each kind at the ``smoke`` point (the same steps)."""
    return rows(measure(1, "smoke", warm_up=False) if tiny else measure(repeat))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=REPEAT)
    args = parser.parse_args()
    for r in run(args.repeat):
        print(f"{r['benchmark']}  {r['ratio']:.3f}  {r['target']}; {r['detail']}")


if __name__ == "__main__":
    main()
