"""What training for decisions along the touch costs: 10-fold cross-validation of the paper's
FFNN and CNN on the built-in data with ``training.decisions = "along_touch"`` against the same
with ``"full_touch"``, side by side (interleaved runs, one torch thread, as the workers train).

The target: along the touch costs at most twice the full touch. ``run(tiny=True)`` does the same
on the ``smoke`` scene, once each.
"""

from __future__ import annotations

import dataclasses

import torch

from benchmarks.timing import median_seconds
from benchmarks.training import scene_frames
from pipeline.chain.training import cross_validate
from pipeline.design.scene import DecisionTraining, Model, Scene


def run(repeat: int = 3, tiny: bool = False) -> list[dict]:
    """One row per model: seconds along the touch / seconds at the full touch."""
    scene = Scene.builtin("smoke" if tiny else "paper")
    repeat = 1 if tiny else repeat
    counts, labels = scene_frames(scene)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    rows = []
    try:
        for model in (Model.FFNN, Model.CNN):
            accuracy = {}

            def train(decisions: DecisionTraining, model=model, accuracy=accuracy) -> None:
                training = dataclasses.replace(scene.training, decisions=decisions)
                cv = cross_validate(counts, labels, model, training, frame_s=scene.coding.window_s)
                accuracy[decisions] = cv.mean

            along_s, full_s = median_seconds(
                lambda: train(DecisionTraining.ALONG_TOUCH),
                lambda: train(DecisionTraining.FULL_TOUCH),
                repeat=repeat,
                warm_up=not tiny,
            )
            along, full = (
                accuracy[DecisionTraining.ALONG_TOUCH],
                accuracy[DecisionTraining.FULL_TOUCH],
            )
            rows.append(
                {
                    "benchmark": f"{scene.training.folds}-fold CV {model.value.upper()} "
                    f"({scene.name}): along the touch / full touch",
                    "ratio": along_s / full_s,
                    "target": "<= 2",
                    "detail": f"1 torch thread; along {along_s:.2f} s (acc {along:.3f}), "
                    f"full {full_s:.2f} s (acc {full:.3f}); decisions read at every window",
                }
            )
    finally:
        torch.set_num_threads(threads)
    return rows
