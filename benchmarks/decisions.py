"""What training for decisions along the touch costs: 10-fold cross-validation of the paper's
FFNN and CNN on the built-in data with ``training.decisions = "along_touch"`` against the same
with ``"full_touch"``, side by side (interleaved runs, one torch thread, as the workers train).

The target: along the touch costs at most twice the full touch. ``run(tiny=True)`` does the same
on the ``smoke`` scene, once each.

``python -m benchmarks.decisions MODEL [--repeats R] [--set FIELD=VALUE ...]`` prints, for the
paper scene on the built-in data, the accuracy of ``MODEL``'s decisions read at 0.5, 1, 2 and 4 s
trained along the touch, trained for the full touch, and trained on each duration alone
(``coding.n_windows`` 5, 10, 20: the reference a decoder trained along the touch is held to),
and at the end of the touch (``accuracy_at_end``; a touch of other recordings may be shorter),
the figures of docs/model.md's "Spiking decoder and decisions in time". ``--dataset`` reads
other recordings, as ``eskin --dataset`` does (a path to a folder).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np
import torch

from benchmarks.timing import median_seconds
from benchmarks.training import scene_frames
from pipeline.chain.decoders import decoder_of
from pipeline.chain.training import cross_validate
from pipeline.design.scene import DecisionTraining, Model, Scene
from pipeline.recordings.sources import resolve_dataset_argument
from pipeline.run.simulate import encode, prepare

#: Decision times (s of touch) the accuracy table reads.
TIMES_S = (0.5, 1.0, 2.0, 4.0)


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


def accuracy_along(scene: Scene, model: Model) -> list[dict]:
    """Rows of the accuracy table for ``model`` of ``scene``: trained along the touch and for
    the full touch (decisions read at :data:`TIMES_S`), and for each earlier duration of
    :data:`TIMES_S` alone (``coding.n_windows``; the ``snn`` on the steps of those windows)."""
    recordings, front_end = prepare(scene.dataset, scene.readout.full_scale_v)
    real = encode(recordings, front_end, scene).real
    reads = decoder_of(model).reads
    coding, snn = scene.coding, scene.training.snn
    column_s = reads.column_s(coding, snn)
    rows = []
    plan = [(d, TIMES_S[-1]) for d in DecisionTraining]
    plan += [(DecisionTraining.FULL_TOUCH, t) for t in TIMES_S[:-1]]
    for decisions, duration_s in plan:
        frames, _ = reads.code(real, coding, snn, round(duration_s / coding.window_s))
        training = dataclasses.replace(scene.training, decisions=decisions)
        start = time.perf_counter()
        cv = cross_validate(frames, recordings.labels, model, training, frame_s=column_s)
        seconds = time.perf_counter() - start
        at = {}
        for t in TIMES_S:
            k = int(np.searchsorted(cv.decision_s, t - 1e-9))
            if k < len(cv.decision_s):
                at[t] = float((cv.decision_predicted[:, k] == recordings.labels).mean())
        last = cv.decision_predicted[:, -1]
        rows.append(
            {
                "model": model.value,
                "decisions": decisions.value,
                "trained_s": duration_s,
                "accuracy_at_s": at,
                "accuracy_at_end": round(float((last == recordings.labels).mean()), 4),
                "seconds": round(seconds, 1),
            }
        )
    return rows


def main(argv: list[str] | None = None) -> None:
    """Print the accuracy table's rows as JSON lines (see the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.decisions")
    parser.add_argument("model", choices=[m.value for m in Model])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE")
    parser.add_argument("--dataset", default="synthetic", help="as eskin's --dataset")
    args = parser.parse_args(argv)
    changes = {"training.models": [args.model], "training.repeats": args.repeats}
    changes |= {f"dataset.{k}": v for k, v in resolve_dataset_argument(args.dataset).items()}
    for item in args.set:
        field, value = item.split("=", 1)
        changes[field] = json.loads(value) if value[:1] in "0123456789-[" else value
    torch.set_num_threads(1)
    for row in accuracy_along(Scene.paper().replace(**changes), Model(args.model)):
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
