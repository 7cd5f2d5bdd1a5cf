"""Rate coding of the paper scene's spike trains against a per-taxel ``np.histogram`` loop."""

from __future__ import annotations

import numpy as np

from benchmarks.timing import median_seconds
from pipeline.chain.coding import frames, resolve_n_windows, window_edges_s
from pipeline.chain.frontend import fit_front_end
from pipeline.chain.spikes import SpikeTrains
from pipeline.design.scene import Scene
from pipeline.recordings.sources import load_recordings
from pipeline.run.simulate import encode


def paper_trains(recordings_per_class: int = 10) -> tuple[SpikeTrains, float, int]:
    """The REAL trains of the paper scene on the built-in data (``recordings_per_class`` of
    each class), its window length and count."""
    scene = Scene.paper().replace(**{"dataset.recordings_per_class": recordings_per_class})
    recordings = load_recordings(scene.dataset)
    trains = encode(recordings, fit_front_end(recordings, scene.readout.full_scale_v), scene).real
    return trains, scene.coding.window_s, resolve_n_windows(scene.coding, trains.duration_s)


def histogram_frames(trains: SpikeTrains, window_s: float, n_windows: int) -> np.ndarray:
    """The baseline: one ``np.histogram`` per train on the same explicit edges.

    (Its last window is closed, so a spike exactly at ``n_windows * window_s`` would be counted;
    the speed comparison does not depend on that.)
    """
    edges = window_edges_s(window_s, n_windows)
    counts = np.empty((trains.n_recordings, trains.n_taxels, n_windows), dtype=np.int64)
    for recording in range(trains.n_recordings):
        for taxel in range(trains.n_taxels):
            times, _ = trains.train(recording, taxel)
            counts[recording, taxel] = np.histogram(times, edges)[0]
    return counts


def run(repeat: int = 7, tiny: bool = False) -> list[dict]:
    """The row; ``tiny``: one recording per class, one timing of each."""
    trains, window_s, n_windows = paper_trains(1 if tiny else 10)
    repeat = 1 if tiny else repeat
    ours = frames(trains, window_s, n_windows)[0][:, 0]
    if not np.array_equal(ours, histogram_frames(trains, window_s, n_windows)):
        raise RuntimeError("rate coding and the np.histogram baseline count differently")
    ours_s, baseline_s = median_seconds(
        lambda: frames(trains, window_s, n_windows),
        lambda: histogram_frames(trains, window_s, n_windows),
        repeat=repeat,
    )
    n = len(trains.times_s)
    return [
        {
            "benchmark": "rate coding vs per-taxel np.histogram",
            "ratio": baseline_s / ours_s,
            "target": ">= 50 M events/s",
            "detail": (
                f"{n / ours_s / 1e6:.0f} M events/s vs {n / baseline_s / 1e6:.1f} M events/s "
                f"({trains.count.size} trains, {n:,} events)"
            ),
        }
    ]
