"""Ideal encoder against a plain memory copy (the memory-bound limit) and a pure-Python loop."""

from __future__ import annotations

import numpy as np

from benchmarks.timing import median_seconds
from pipeline.frontend import fit_front_end
from pipeline.readout import level_crossings, reference_level_crossings
from pipeline.scene import Scene
from pipeline.synthetic import synthetic_recordings


def built_in_signal() -> np.ndarray:
    """All built-in recordings, front-end scaled and concatenated: float64 (1.2 M samples)."""
    scene = Scene.paper()
    recordings = synthetic_recordings(seed=scene.dataset.seed)
    front_end = fit_front_end(recordings, scene.readout.full_scale_v)
    return np.concatenate([front_end.apply(s) for s in recordings.signals])


def run(repeat: int = 7) -> list[dict]:
    signal = built_in_signal()
    threshold = Scene.paper().readout.threshold_v
    destination = np.empty_like(signal)
    destination[:] = 1.0  # touch the pages so the copy measures bandwidth, not page faults
    encoder_s, copy_s = median_seconds(
        lambda: level_crossings(signal, 2000.0, threshold),
        lambda: np.copyto(destination, signal),
        repeat=repeat,
    )
    again_encoder_s, loop_s = median_seconds(
        lambda: level_crossings(signal, 2000.0, threshold),
        lambda: reference_level_crossings(signal, 2000.0, threshold),
        repeat=3,
    )
    n = len(signal)
    return [
        {
            "benchmark": "ideal encoder vs memory copy",
            "ratio": encoder_s / copy_s,
            "target": "<= 20 (issue 2), <= 10 (issue 6)",
            "detail": f"{n / encoder_s / 1e6:.0f} M samples/s vs copy {n / copy_s / 1e6:.0f} M/s",
        },
        {
            "benchmark": "ideal encoder vs pure-Python loop",
            "ratio": loop_s / again_encoder_s,
            "target": ">= 100",
            "detail": f"{n / loop_s / 1e6:.2f} M samples/s in the loop",
        },
    ]
