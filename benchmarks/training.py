"""10-fold cross-validation of the paper's FFNN and CNN on the built-in data, the largest point of
the paper grid (time and peak memory), and a whole run.

Training is timed at one torch thread, as the Dask workers run it (``torch.set_num_threads(1)``;
the previous setting is restored afterwards). ``run(tiny=True)`` does the same with the ``smoke``
scene and grid (4 folds, 5 epochs, 4 short recordings per class) in place of ``paper``.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import time

import numpy as np
import torch

from benchmarks.timing import median_seconds
from pipeline.chain.training import CrossValidation, cross_validate
from pipeline.design.grid import load_grid
from pipeline.design.scene import Model, Scene
from pipeline.run.decoding import rate_frames
from pipeline.run.grid_keys import unique_points
from pipeline.run.simulate import encode, prepare

WORKER_MEMORY_BYTES = 1.5 * 2**30
"""Memory budget of one Dask worker, the peak resident memory target of docs/performance.md."""


def scene_frames(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Rate-coded frames ``(n_rec, C, taxels, windows)`` of a scene's REAL trains, and labels."""
    recordings, front_end = prepare(scene.dataset, scene.readout.full_scale_v)
    encoded = encode(recordings, front_end, scene)
    counts, _ = rate_frames(encoded.real, scene.coding)
    return counts, recordings.labels


def largest_point(grid: str = "paper") -> Scene:
    """The built-in grid's point with the most frame cells (taxels x windows; ``auto`` as 40)."""

    def cells(scene: Scene) -> int:
        n_windows = scene.coding.n_windows
        return scene.array.rows * scene.array.cols * (40 if n_windows == "auto" else n_windows)

    return max(unique_points(load_grid(grid)).values(), key=cells)


def _accuracy(cv: CrossValidation) -> str:
    return f"acc {cv.mean:.3f} +- {cv.std:.3f}"


def train_largest_point(grid: str = "paper") -> None:
    """Entry point of the memory subprocess: train the largest point of the built-in ``grid``,
    print a JSON summary."""
    torch.set_num_threads(1)
    scene = largest_point(grid)
    counts, labels = scene_frames(scene)
    seconds = {}
    for model in scene.training.models:
        start = time.perf_counter()
        cross_validate(counts, labels, model, scene.training)
        seconds[model.value] = time.perf_counter() - start
    summary = {
        "shape": list(counts.shape[1:]),
        "seconds": seconds,
        "peak_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
    }
    print(json.dumps(summary))


def run(repeat: int = 3, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: the ``smoke`` scene and grid for ``paper``, one timing of each (the
    whole run not warmed up)."""
    name, repeat = ("smoke", 1) if tiny else ("paper", repeat)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        rows = _fold_batching_rows(Scene.builtin(name), repeat)
    finally:
        torch.set_num_threads(threads)
    code = f"from benchmarks.training import train_largest_point; train_largest_point({name!r})"
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    largest = json.loads(out.stdout)
    _, taxels, windows = largest["shape"]
    rows.append(
        {
            "benchmark": f"largest {name} point ({taxels} taxels x {windows} windows): "
            "peak RSS of training / 1.5 GiB",
            "ratio": largest["peak_rss_bytes"] / WORKER_MEMORY_BYTES,
            "target": "<= 1",
            "detail": f"{largest['peak_rss_bytes'] / 2**20:.0f} MiB (whole process); 1 torch "
            "thread, training "
            + ", ".join(f"{k.upper()} {v:.1f} s" for k, v in largest["seconds"].items()),
        }
    )
    eskin = [sys.executable, "-m", "flows.cli", "run", "--scene", name, "--json"]
    timings = {}

    def end_to_end():
        out = subprocess.run(eskin, check=True, capture_output=True, text=True).stdout
        timings.update(json.loads(out)["timings_s"])

    (run_s,) = median_seconds(end_to_end, repeat=repeat, warm_up=not tiny)
    rows.append(
        {
            "benchmark": f"eskin run --scene {name}, wall time incl. start-up / 60 s",
            "ratio": run_s / 60.0,
            "target": "<= 1",
            "detail": f"{run_s:.1f} s; stages: "
            + ", ".join(f"{k} {v:.2f}" for k, v in timings.items()),
        }
    )
    return rows


def _fold_batching_rows(scene: Scene, repeat: int) -> list[dict]:
    counts, labels = scene_frames(scene)
    rows = []
    for model in (Model.FFNN, Model.CNN):
        results = {}

        def fold_batch(batched: bool, model=model, results=results):
            results[batched] = cross_validate(
                counts, labels, model, scene.training, batched=batched
            )

        batched_s, sequential_s = median_seconds(
            lambda: fold_batch(True), lambda: fold_batch(False), repeat=repeat
        )
        rows.append(
            {
                "benchmark": f"{scene.training.folds}-fold CV {model.value.upper()}, "
                f"{scene.training.epochs} epochs: batched vs sequential",
                "ratio": sequential_s / batched_s,
                "target": ">= 4" + ("; batched <= 2 s" if model == "ffnn" else ""),
                "detail": f"1 torch thread; batched {batched_s:.2f} s "
                f"({_accuracy(results[True])}), sequential {sequential_s:.2f} s "
                f"({_accuracy(results[False])})",
            }
        )
    return rows
