"""The spiking decoder: 10-fold cross-validation of the ``snn`` against the CNN at the paper
point, side by side (folds batched, one torch thread, as the Dask workers train), both trained
along the touch and both for the full touch (``training.decisions``), the four interleaved, so
that the ``snn``'s training along the touch is also timed against its own for the full touch;
and how the cost of its training step grows with the number of time steps (linear: doubling the
steps doubles it; a time loop that indexes a tensor inside autograd would quadruple it).

``run(tiny=True)`` does the same on the ``smoke`` scene with 5 epochs, once each.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import torch

from benchmarks.timing import median_seconds
from pipeline.chain.coding import resolve_n_windows
from pipeline.chain.decoders import build_model, decoder_of
from pipeline.chain.models import fold_generator
from pipeline.chain.training import CrossValidation, cross_validate
from pipeline.design.scene import DecisionTraining, Model, Scene
from pipeline.run.simulate import encode, prepare


def scene_inputs(scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The CNN's frames ``(n, 1, taxels, windows)``, the SNN's step counts ``(n, 2, taxels,
    steps)`` over the same span, and the labels, of a scene's REAL trains, coded as their
    decoders read them (:class:`pipeline.chain.decoders.Reads`)."""
    recordings, front_end = prepare(scene.dataset, scene.readout.full_scale_v)
    real = encode(recordings, front_end, scene).real
    n_windows = resolve_n_windows(scene.coding, real.duration_s)
    counts, steps = (
        decoder_of(model).reads.code(real, scene.coding, scene.training.snn, n_windows)[0]
        for model in (Model.CNN, Model.SNN)
    )
    return counts, steps, recordings.labels


def _accuracy(cv: CrossValidation) -> str:
    return f"acc {cv.mean:.3f} +- {cv.std:.3f}"


def run(repeat: int = 3, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: the ``smoke`` scene, 5 epochs, one timing of each."""
    scene = Scene.builtin("smoke" if tiny else "paper")
    scene = scene.replace(**{"training.models": ["cnn", "snn"]})
    if tiny:
        scene = scene.replace(**{"training.snn.epochs": 5})
        repeat = 1
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        counts, steps, labels = scene_inputs(scene)
        rows = _cost_rows(scene, counts, steps, labels, repeat, tiny)
        rows.append(_time_scaling_row(scene, steps.shape[2], 4 if tiny else 50, repeat))
    finally:
        torch.set_num_threads(threads)
    return rows


def _cost_rows(
    scene: Scene,
    counts: np.ndarray,
    steps: np.ndarray,
    labels: np.ndarray,
    repeat: int,
    tiny: bool,
) -> list[dict]:
    """The SNN's cross-validation time over the CNN's, both trained for each
    ``training.decisions``, and the SNN's along the touch over its own for the full touch: the
    four cross-validations interleaved in this process."""
    snn = scene.training.snn
    results: dict[tuple[Model, DecisionTraining], CrossValidation] = {}
    inputs = {Model.SNN: (steps, snn.step_s), Model.CNN: (counts, scene.coding.window_s)}
    runs = [(model, decisions) for decisions in DecisionTraining for model in inputs]

    def train(model: Model, decisions: DecisionTraining) -> None:
        training = dataclasses.replace(scene.training, decisions=decisions)
        frames, column_s = inputs[model]
        results[model, decisions] = cross_validate(
            frames, labels, model, training, frame_s=column_s
        )

    timings = median_seconds(
        *(functools.partial(train, *run) for run in runs), repeat=repeat, warm_up=not tiny
    )
    seconds = dict(zip(runs, timings, strict=True))
    rows = []
    for decisions in DecisionTraining:
        snn_s, cnn_s = seconds[Model.SNN, decisions], seconds[Model.CNN, decisions]
        rows.append(
            {
                "benchmark": f"{scene.training.folds}-fold CV SNN ({snn.epochs} epochs, "
                f"{steps.shape[-1]} steps of {snn.step_s} s, {snn.hidden_neurons} neurons, "
                f"{snn.time_constants.value} time constants) vs CNN "
                f"({scene.training.epochs} epochs), both trained {decisions.value}: "
                "seconds / CNN's",
                "ratio": snn_s / cnn_s,
                "target": "<= 3",
                "detail": f"1 torch thread, folds batched; SNN {snn_s:.2f} s "
                f"({_accuracy(results[Model.SNN, decisions])}), CNN {cnn_s:.2f} s "
                f"({_accuracy(results[Model.CNN, decisions])})",
            }
        )
    along_s = seconds[Model.SNN, DecisionTraining.ALONG_TOUCH]
    full_s = seconds[Model.SNN, DecisionTraining.FULL_TOUCH]
    rows.append(
        {
            "benchmark": f"{scene.training.folds}-fold CV SNN: trained along the touch / "
            "for the full touch",
            "ratio": along_s / full_s,
            "target": "<= 2",
            "detail": f"1 torch thread, folds batched; along {along_s:.2f} s, full {full_s:.2f} s, "
            "interleaved with the rows above",
        }
    )
    return rows


def _time_scaling_row(scene: Scene, taxels: int, n_steps: int, repeat: int) -> dict:
    """Seconds of one training step (forward and backward, 10 folds x 16 recordings) at
    ``n_steps``, twice and four times as many steps."""
    folds, batch = scene.training.folds, scene.training.batch_size
    generator = torch.Generator().manual_seed(0)
    calls = []
    for steps in (n_steps, 2 * n_steps, 4 * n_steps):
        net = build_model(
            Model.SNN,
            (2, taxels, steps),
            12,
            0,
            folds,
            [fold_generator(0, f, "init") for f in range(folds)],
            scene.training.snn,
        )
        x = torch.poisson(torch.full((folds, batch, 2, taxels, steps), 0.13), generator=generator)
        params = list(net.parameters())

        def step(net=net, x=x, params=params) -> None:
            torch.autograd.grad(net(x).logsumexp(-1).sum(), params)

        calls.append(step)
    seconds = median_seconds(*calls, repeat=max(repeat, 5))
    return {
        "benchmark": f"SNN training step at {4 * n_steps} vs {n_steps} time steps: seconds ratio",
        "ratio": seconds[2] / seconds[0],
        "target": "<= 4 (linear in the steps; quadratic would be 16)",
        "detail": f"{folds} folds x {batch} recordings, forward and backward: "
        + ", ".join(
            f"{k * n_steps} steps {s * 1e3:.1f} ms" for k, s in zip((1, 2, 4), seconds, strict=True)
        ),
    }
