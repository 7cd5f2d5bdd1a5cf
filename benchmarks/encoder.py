"""Encoders on the built-in data: the ideal one against a plain memory copy (the memory-bound
limit) and a pure-Python loop, the non-ideal one with every effect on against the ideal one, and
the ideal decaying-threshold encoder against the ideal fixed one."""

from __future__ import annotations

import numpy as np

from benchmarks.timing import median_seconds
from pipeline.chain.frontend import fit_front_end
from pipeline.chain.readout import decaying_crossings, level_crossings, reference_level_crossings
from pipeline.chain.readout_effects import real_train
from pipeline.design.effects import Effect
from pipeline.design.scene import Scene
from pipeline.recordings.synthetic import synthetic_recordings

FS_HZ = 2000.0


def built_in_signal(recordings_per_class: int = 10) -> np.ndarray:
    """The built-in recordings, front-end scaled and concatenated: float64 (1.2 M samples with
    the default 10 recordings per class)."""
    scene = Scene.paper()
    recordings = synthetic_recordings(
        seed=scene.dataset.seed, recordings_per_class=recordings_per_class
    )
    front_end = fit_front_end(recordings, scene.readout.full_scale_v)
    return np.concatenate([front_end.apply(s) for s in recordings.signals])


def run(repeat: int = 7, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: one recording per class (120,000 samples), one timing of each."""
    signal = built_in_signal(1 if tiny else 10)
    repeat = 1 if tiny else repeat
    n = len(signal)
    paper = Scene.paper()
    threshold = paper.readout.threshold_v
    every_effect = Scene.from_dict(
        {"readout": {"threshold_v": threshold, "effects": {e.value: {} for e in Effect}}}
    ).readout

    def ideal():
        return level_crossings(signal, FS_HZ, threshold)

    def ideal_10x():  # long enough per timing that a preemption rarely lands in the median
        for _ in range(10):
            ideal()

    destination = np.empty_like(signal)
    destination[:] = 1.0  # touch the pages so the copy measures bandwidth, not page faults
    encoder_s, copy_s = median_seconds(ideal, lambda: np.copyto(destination, signal), repeat=repeat)
    ten_s, loop_s = median_seconds(
        ideal_10x,
        lambda: reference_level_crossings(signal, FS_HZ, threshold),
        repeat=min(repeat, 3),
    )
    ideal_s, real_s = median_seconds(
        ideal,
        lambda: real_train(signal, FS_HZ, every_effect, seed=paper.seed, taxel=0, recording=0),
        repeat=repeat,
    )
    decay = paper.replace(**{"readout.encoder": "decaying"}).readout.decay
    fixed_s, decaying_s = median_seconds(
        ideal,
        lambda: decaying_crossings(signal, FS_HZ, threshold, decay.theta_min_v, decay.tau_s),
        repeat=repeat,
    )
    spikes = len(decaying_crossings(signal, FS_HZ, threshold, decay.theta_min_v, decay.tau_s)[0])
    return [
        {
            "benchmark": "ideal encoder vs memory copy",
            "ratio": encoder_s / copy_s,
            "target": "<= 10",
            "detail": f"{n / encoder_s / 1e6:.0f} M samples/s vs copy {n / copy_s / 1e6:.0f} M/s",
        },
        {
            "benchmark": "ideal encoder vs pure-Python loop",
            "ratio": loop_s / (ten_s / 10),
            "target": ">= 100",
            "detail": (
                f"{10 * n / ten_s / 1e6:.0f} M samples/s vs {n / loop_s / 1e6:.2f} M samples/s "
                "in the loop"
            ),
        },
        {
            "benchmark": "non-ideal encoder (every effect) vs ideal",
            "ratio": real_s / ideal_s,
            "target": "<= 3",
            "detail": (
                f"{n / real_s / 1e6:.0f} M samples/s vs {n / ideal_s / 1e6:.0f} M samples/s "
                "(two Gaussian draws per sample)"
            ),
        },
        {
            "benchmark": "decaying-threshold encoder vs fixed (ideal)",
            "ratio": decaying_s / fixed_s,
            "target": "-",
            "detail": (
                f"{n / decaying_s / 1e6:.0f} M samples/s vs {n / fixed_s / 1e6:.0f} M samples/s "
                f"(theta {threshold} -> {decay.theta_min_v} V, tau {decay.tau_s} s: "
                f"{spikes / n:.3f} spikes per sample, each a bracketed Newton solve)"
            ),
        },
    ]
