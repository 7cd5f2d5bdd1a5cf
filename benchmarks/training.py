"""10-fold cross-validation of the paper's FFNN and CNN on the built-in data, and a whole run."""

from __future__ import annotations

import json
import subprocess
import sys

from benchmarks.timing import median_seconds
from pipeline.coding import frames, resolve_n_windows
from pipeline.frontend import fit_front_end
from pipeline.recordings import load_recordings
from pipeline.scene import Model, Scene
from pipeline.simulate import encode
from pipeline.training import cross_validate


def paper_frames():
    scene = Scene.paper()
    recordings = load_recordings(scene.dataset)
    encoded = encode(recordings, fit_front_end(recordings, scene.readout.full_scale_v), scene)
    n_windows = resolve_n_windows(scene.coding, encoded.real.duration_s)
    counts, _ = frames(encoded.real, scene.coding.window_s, n_windows)
    return scene, counts, recordings.labels


def run(repeat: int = 3) -> list[dict]:
    scene, counts, labels = paper_frames()
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
                "benchmark": f"10-fold CV {model.value.upper()}, 100 epochs: batched vs sequential",
                "ratio": sequential_s / batched_s,
                "target": ">= 4 (issue 6)"
                + ("; batched <= 2 s (issue 2)" if model == "ffnn" else ""),
                "detail": f"batched {batched_s:.2f} s (acc {results[True].mean:.3f}), "
                f"sequential {sequential_s:.2f} s (acc {results[False].mean:.3f})",
            }
        )
    eskin = [sys.executable, "-m", "flows.cli", "run", "--scene", "paper", "--json"]
    timings = {}

    def end_to_end():
        out = subprocess.run(eskin, check=True, capture_output=True, text=True).stdout
        timings.update(json.loads(out)["timings_s"])

    (run_s,) = median_seconds(end_to_end, repeat=repeat)
    rows.append(
        {
            "benchmark": "eskin run --scene paper, wall time incl. start-up / 60 s",
            "ratio": run_s / 60.0,
            "target": "<= 1",
            "detail": f"{run_s:.1f} s; stages: "
            + ", ".join(f"{k} {v:.2f}" for k, v in timings.items()),
        }
    )
    return rows
