"""The readout of a real array against one channel of the same samples, per sample.

A 16-taxel array recording is made of 16 of the built-in touches (2 kHz, one per column, cut to
the shortest); the one-channel recording beside it holds the same 16 columns end to end, so both
hold the same samples and the same spikes but for the joins. Each is encoded as a scene encodes
it (:func:`pipeline.run.encoding.encode_trains`: the taxel signals, then the TRUE train of every
taxel and, for a non-ideal readout, its REAL train), interleaved, and the figure is the ratio of
the medians: the seconds per sample of the array over those of the one channel. Target: at most
1.5 (the readout is vectorised over taxels: the TRUE trains of a recording's taxels are one
kernel call, :func:`pipeline.chain.readout.level_crossings_rows`).

``run(tiny=True)``: one array recording of 4 taxels, one timing of each.
"""

from __future__ import annotations

import numpy as np

from benchmarks.timing import median_seconds
from pipeline.chain.frontend import fit_front_end
from pipeline.design.scene import Scene
from pipeline.recordings.recording_set import Recordings
from pipeline.recordings.synthetic import synthetic_recordings
from pipeline.run.encoding import encode_trains, warm_kernels
from pipeline.run.stopwatch import Stopwatch

TAXELS = 16
#: Every effect that draws per taxel or per sample but the comparator noise (which draws per
#: decision): the non-ideal readout of the second row.
NON_IDEAL = {"amplifier_offset": {}, "amplifier_noise": {}, "threshold_mismatch": {}}


def recordings_side_by_side(
    taxels: int, recordings_per_class: int
) -> tuple[Recordings, Recordings]:
    """An array of ``taxels`` columns per recording, and the same samples as one channel."""
    touches = synthetic_recordings(seed=0, recordings_per_class=recordings_per_class)
    n = touches.n_recordings // taxels
    length = touches.min_samples
    arrays = [
        np.stack(
            [np.asarray(s)[:length] for s in touches.signals[r * taxels : (r + 1) * taxels]], 1
        )
        for r in range(n)
    ]
    common = {
        "labels": np.arange(n) % 2,
        "class_names": ("a", "b"),
        "fs_hz": touches.fs_hz,
        "names": tuple(f"r{r}" for r in range(n)),
        "units": touches.units,
    }
    array = Recordings(
        signals=tuple(arrays),
        name="array",
        taxel_names=tuple(f"t{k}" for k in range(taxels)),
        **common,
    )
    one = Recordings(signals=tuple(a.T.ravel() for a in arrays), name="one", **common)
    return array, one


def run(repeat: int = 9, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: one recording of 4 taxels, one timing of each."""
    taxels, per_class, repeat = (4, 1, 1) if tiny else (TAXELS, 10, repeat)
    array, one = recordings_side_by_side(taxels, per_class)
    samples = sum(s.size for s in array.signals)
    rows = []
    for label, effects in (("ideal", {}), ("non-ideal", NON_IDEAL)):
        scene = Scene.paper().replace(
            **{"array.rows": 1, "array.cols": 1, "readout.effects": effects}
        )
        warm_kernels(scene.readout)
        watch = Stopwatch(None)

        def encode(recordings: Recordings, scene: Scene = scene, watch: Stopwatch = watch):
            front_end = fit_front_end(recordings, scene.readout.full_scale_v)
            return lambda: encode_trains(
                recordings, front_end, scene.array, scene.readout, scene.seed, watch
            )

        array_s, one_s = median_seconds(encode(array), encode(one), repeat=repeat)
        rows.append(
            {
                "benchmark": f"{taxels}-taxel array vs one channel of its samples, {label} readout",
                "ratio": array_s / one_s,
                "target": "<= 1.5",
                "detail": (
                    f"{array.n_recordings} recordings x {taxels} taxels x "
                    f"{array.min_samples} samples: {samples / array_s / 1e6:.1f} M samples/s "
                    f"({array_s * 1e3:.1f} ms) vs {samples / one_s / 1e6:.1f} M samples/s "
                    f"({one_s * 1e3:.1f} ms), medians of {repeat}"
                ),
            }
        )
    return rows
