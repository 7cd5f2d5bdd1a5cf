"""Result cubes with chosen accuracies, for the report tests (no training: exact numbers)."""

from collections.abc import Callable

import numpy as np

from pipeline.cube import RecordingsInfo, build_cube
from pipeline.grid import Grid
from pipeline.metrics import SpikeMetrics
from pipeline.scene import Scene
from storage import ResultEntry
from storage.cubes import SPIKE_STAGES

FOLD_OFFSETS = np.array([-0.02, 0.02, -0.02, 0.02])  # std over folds (ddof 0) is 0.02
RECORDINGS = RecordingsInfo("synthetic", tuple(f"texture{i}" for i in range(12)), 2000.0)

PAPER_LIKE_SWEEPS = {
    "threshold": {"axes": {"readout.threshold_v": [0.03, 0.09, 0.2]}},
    "window": {"axes": {"coding.window_s": [0.05, 0.1, 0.2]}},
    "taxels": {"mode": "zip", "axes": {"array.rows": [1, 4, 5], "array.cols": [1, 4, 5]}},
    "noise": {
        "mode": "zip",
        "set": {"array.rows": 1, "array.cols": 1},
        "correlate": True,
        "axes": {
            "readout.effects.amplifier_noise.sigma_v": [0.005, 0.01, 0.02, 0.04],
            "readout.effects.comparator_noise.sigma_v": [0.005, 0.01, 0.02, 0.04],
        },
    },
    "mismatch": {"axes": {"readout.effects.threshold_mismatch.sigma_rel": [0.0, 0.1, 0.2, 0.3]}},
    "observation": {"axes": {"coding.n_windows": [1, 2, 5]}},
}


def paper_like_accuracy(scene: Scene) -> float:
    """Peaks at 0.09 V and 0.1 s, +63 % from 1 to 16 taxels then flat, falls with noise and
    mismatch, rises with observation time."""
    r = scene.readout
    acc = 0.6 - 2.0 * abs(r.threshold_v - 0.09) - 1.0 * abs(scene.coding.window_s - 0.1)
    acc *= {1: 1 / 1.63, 16: 1.0, 25: 1.0}.get(scene.array.n_taxels, 1.0)
    for effect, params in r.effects.items():
        acc -= 5.0 * getattr(params, "sigma_v", 0.0) + 0.5 * getattr(params, "sigma_rel", 0.0)
        del effect
    if scene.coding.n_windows != "auto":
        acc -= 0.2 / scene.coding.n_windows
    return acc


def make_cubes(
    sweeps: dict | None = None,
    accuracy: Callable[[Scene], float] = paper_like_accuracy,
    recordings: RecordingsInfo | None = RECORDINGS,
) -> dict:
    """``{name: cube}`` of a grid on the smoke scene with ``accuracy(scene)`` +- 0.02 per fold.

    Seconds grow with the taxel count and window count; SSNR falls with noise (inf when ideal).
    Every point states ``recordings`` (12 classes at 2 kHz by default)."""
    grid = Grid.from_dict({"name": "t", "base": "smoke", "sweeps": sweeps or PAPER_LIKE_SWEEPS})
    records = {}
    for key, scene in grid.unique_points().items():
        noise = sum(getattr(p, "sigma_v", 0.0) for p in scene.readout.effects.values())
        a = accuracy(scene)
        records[key] = ResultEntry(
            fold_accuracy={"ffnn": a + FOLD_OFFSETS, "cnn": a + 0.05 + FOLD_OFFSETS},
            seconds={
                "load": 0.1,
                "readout": 0.01 * scene.array.n_taxels,
                "coding": 0.02,
                "train_ffnn": 0.5,
                "train_cnn": 2.0 + 0.1 * scene.array.n_taxels,
            },
            metrics=SpikeMetrics(
                ssnr_db=-20 * np.log10(noise) if noise else np.inf,
                ste_s2=noise**2,
                ste_sign_safe_s2=noise**2,
                event_rate_hz=100.0 / scene.readout.threshold_v,
                data_rate_bps=700.0 / scene.readout.threshold_v,
                equivalent_bits=scene.readout.equivalent_bits,
            ),
            recordings=recordings,
        )
    return {s.name: build_cube(grid, s, records, spike_stages=SPIKE_STAGES) for s in grid.sweeps}
