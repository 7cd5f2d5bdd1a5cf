"""10-fold cross-validation of the paper's FFNN and CNN on the built-in data, and a whole run."""

from __future__ import annotations

from benchmarks.timing import median_seconds
from pipeline.coding import frames, resolve_n_windows
from pipeline.frontend import fit_front_end
from pipeline.recordings import load_recordings
from pipeline.scene import Model, Scene
from pipeline.simulate import encode, run_scene
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
    (run_s,) = median_seconds(lambda: run_scene(Scene.paper()), repeat=repeat)
    rows.append(
        {
            "benchmark": "eskin run, paper scene, end to end",
            "ratio": run_s / 60.0,
            "target": "<= 1 (60 s budget)",
            "detail": f"{run_s:.1f} s",
        }
    )
    return rows
