"""Result cubes with chosen accuracies, for the report tests (no training: exact numbers).

Every point gets hand-made out-of-fold predictions of :data:`N_RECORDINGS` recordings (classes
``i % n_classes``, fold ``i % 4``): for a chosen accuracy ``a`` the first ``round(a * n)``
recordings are right and the others wrong. Points are therefore *nested*: of two points with
``k_a >= k_b`` right recordings, the first ``k_b`` recordings are right in both, the next
``k_a - k_b`` right only in the first, so a paired comparison has exactly ``k_a - k_b`` discordant
recordings, all one way, and the exact McNemar p-value is ``binomtest(k_a - k_b, k_a - k_b)``.
Fold accuracies are those of the same predictions, fold by fold.
"""

import math
from collections.abc import Callable

import numpy as np

from pipeline.chain.metrics import SpikeMetrics
from pipeline.design.grid import Grid
from pipeline.design.scene import Scene
from pipeline.results.cube import build_cube
from pipeline.run.entries import OutOfFold, RecordingsInfo, ResultEntry
from pipeline.run.grid_keys import unique_points
from pipeline.run.records import Charge

N_RECORDINGS = 120
N_FOLDS = 4
RECORDINGS = RecordingsInfo("synthetic", tuple(f"texture{i}" for i in range(12)), 2000.0)
CNN_BONUS = 0.05  # the CNN is this much more accurate than the FFNN at every point

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


def n_right(accuracy: float, n: int = N_RECORDINGS) -> int:
    """Recordings a point with ``accuracy`` gets right (the first ones, see the module)."""
    return int(np.clip(round(accuracy * n), 0, n))


def out_of_fold(accuracies: dict[str, float], n_classes: int, repeats: int = 1) -> OutOfFold:
    """Predictions with ``n_right(a)`` right recordings per model, the same in every repeat."""
    labels = np.arange(N_RECORDINGS) % n_classes
    wrong = (labels + 1) % n_classes if n_classes > 1 else np.full_like(labels, 1)
    predicted = {}
    for model, a in accuracies.items():
        row = np.where(np.arange(N_RECORDINGS) < n_right(a), labels, wrong)
        predicted[model] = np.tile(row, (repeats, 1))
    return OutOfFold(
        recording_names=tuple(f"rec{i:03d}" for i in range(N_RECORDINGS)),
        labels=labels,
        predicted=predicted,
        test_fold=np.tile(np.arange(N_RECORDINGS) % N_FOLDS, (repeats, 1)),
    )


def fold_accuracy(oof: OutOfFold) -> dict[str, np.ndarray]:
    """Accuracy of every fold of every repeat, (repeats, folds), from the predictions."""
    result = {}
    for model, predicted in oof.predicted.items():
        right = np.asarray(predicted) == oof.labels
        result[model] = np.array(
            [
                [right[r][oof.test_fold[r] == k].mean() for k in range(N_FOLDS)]
                for r in range(len(right))
            ]
        )
    return result


def make_cubes(
    sweeps: dict | None = None,
    accuracy: Callable[[Scene], float] = paper_like_accuracy,
    recordings: RecordingsInfo | None = RECORDINGS,
    *,
    predictions: bool = True,
    models: tuple[str, ...] = ("ffnn", "cnn"),
    repeats: int = 1,
    rates: Callable[[Scene], tuple[float, float]] | None = None,
    paid: bool = True,
) -> dict:
    """``{name: cube}`` of a grid on the smoke scene: the FFNN gets ``accuracy(scene)`` and the
    CNN :data:`CNN_BONUS` more, as exact out-of-fold predictions (see the module docstring).

    Seconds grow with the taxel count and window count; SSNR falls with noise (inf when ideal);
    event and data rates fall with the threshold (``rates(scene)`` gives ``(event_rate_hz,
    data_rate_bps)`` instead, when given). Every point states ``recordings`` (12 classes at
    2 kHz by default) and the windows it used (8 for ``auto``, else ``coding.n_windows``).
    ``predictions=False`` makes cubes of a run that predates per-recording
    results (fold accuracies only, no intervals); ``paid=False`` of one that predates paid
    seconds (else the first point paid the one load of the recordings, shared by the others)."""
    base = Scene.load("smoke").to_dict()
    # trained for the full touch, as the points of the golden report were (their result keys)
    base["training"] |= {"models": list(models), "repeats": repeats, "decisions": "full_touch"}
    grid = Grid.from_dict({"name": "t", "base": base, "sweeps": sweeps or PAPER_LIKE_SWEEPS})
    n_classes = len(recordings.class_names) if recordings and recordings.class_names else 12
    records = {}
    for key, scene in unique_points(grid).items():
        noise = sum(getattr(p, "sigma_v", 0.0) for p in scene.readout.effects.values())
        a = accuracy(scene)
        event_rate, data_rate = (
            rates(scene)
            if rates
            else (100.0 / scene.readout.threshold_v, 700.0 / scene.readout.threshold_v)
        )
        bonus = {"ffnn": 0.0, "cnn": CNN_BONUS}
        oof = out_of_fold({m: a + bonus[m] for m in models}, n_classes, repeats)
        seconds = {
            "load": 0.1,
            "readout": 0.01 * scene.array.n_taxels,
            "coding": 0.02,
            **{"train_ffnn": 0.5, "train_cnn": 2.0 + 0.1 * scene.array.n_taxels},
        }
        own = {step: value for step, value in seconds.items() if step != "load"}
        # One worker: the first point paid the load, the others found the recordings loaded.
        shared = {"load": 0.1} if not records else {}
        records[key] = ResultEntry(
            fold_accuracy=fold_accuracy(oof),
            seconds=seconds,
            paid={Charge.OWN: own, Charge.SHARED: shared} if paid else None,
            metrics=SpikeMetrics(
                ssnr_db=-20 * np.log10(noise) if noise else np.inf,
                ste_s2=noise**2,
                ste_sign_safe_s2=noise**2,
                event_rate_hz=event_rate,
                data_rate_bps=data_rate,
                equivalent_bits=scene.readout.equivalent_bits,
            ),
            recordings=recordings,
            out_of_fold=oof if predictions else None,
            n_windows_used=8 if scene.coding.n_windows == "auto" else scene.coding.n_windows,
        )
    return {s.name: build_cube(grid, s, records) for s in grid.sweeps}


#: How a chip's accuracy falls with the mismatch sigma_rel, by deployment (points per unit of
#: sigma_rel), and how far its chips spread (the chips' offsets scale with sigma_rel too).
CHIP_LOSS = {"per_chip": 0.1, "robust": 0.3, "shared": 0.6}
CHIP_SPREAD = {"per_chip": 0.1, "robust": 0.2, "shared": 0.4}


def with_chips(cube, deployment: str, n_chips: int = 20, target: float = 0.4):
    """``cube`` (one sweep of ``readout.effects.threshold_mismatch.sigma_rel``, one repeat, from
    :func:`make_cubes`) as the contract lays out a cube of ``n_chips`` chips per point.

    Chip ``c`` of a point of accuracy ``a`` at mismatch ``s`` gets the first
    ``n_right(a - CHIP_LOSS[d] * s + CHIP_SPREAD[d] * s * z_c)`` recordings right, ``z_c``
    spread evenly over [-1, 1]: nested, so that paired tests are exact. The yield variables are
    computed here by plain numpy (the 5th percentile the order statistic of rank ceil(0.05 N),
    its interval, for the test's sake, the order statistics 1 and 3). Result keys get
    ``|deployment`` appended.
    """
    dim = "sigma_rel"
    sigma = cube[dim].values
    z = np.linspace(-1.0, 1.0, n_chips)
    labels = cube["label"].values
    n = labels.size
    base = cube["accuracy_mean"].transpose(dim, "model").values
    per = np.array(
        [
            [
                [
                    n_right(a - CHIP_LOSS[deployment] * s + CHIP_SPREAD[deployment] * s * zc)
                    for zc in z
                ]
                for a in row
            ]
            for s, row in zip(sigma, base, strict=True)
        ]
    )  # (sigma, model, chip) right recordings
    right = np.arange(n)[None, None, None, :] < per[..., None]  # (sigma, model, chip, rec)
    wrong = (labels + 1) % 12
    predicted = np.where(right, labels, wrong).astype(np.int16)[:, :, :, None, :]
    correct = right.astype(np.int8)[:, :, :, None, :]
    folds = cube["test_fold"].values[0, 0]  # (recording,)
    accuracy = np.stack([right[..., folds == k].mean(axis=-1) for k in range(N_FOLDS)], -1)
    accuracy = accuracy[:, :, :, None, :]
    chip_acc = per / n
    ordered = np.sort(chip_acc, axis=-1)
    p05 = ordered[..., max(1, math.ceil(0.05 * n_chips - 1e-9)) - 1]  # rank ceil(0.05 N)
    keys = [f"{k}|{deployment}" for k in cube["result_key"].values]
    dims = (dim, "model", "chip")
    out = cube.drop_vars(
        [
            *("accuracy", "accuracy_mean", "accuracy_low", "accuracy_high"),
            *("predicted", "correct", "ssnr_db", "event_rate_hz", "data_rate_bps"),
        ]
    )
    return (
        out.assign(
            accuracy=((*dims, "repeat", "fold"), accuracy),
            accuracy_mean=(dims, chip_acc),
            accuracy_low=(dims, chip_acc - 0.08),
            accuracy_high=(dims, chip_acc + 0.08),
            predicted=((*dims, "repeat", "recording"), predicted),
            correct=((*dims, "repeat", "recording"), correct),
            ssnr_db=(
                (dim, "chip"),
                np.broadcast_to(cube["ssnr_db"].values[:, None], (sigma.size, n_chips)),
            ),
            event_rate_hz=((dim, "chip"), np.tile(cube["event_rate_hz"].values[:, None], n_chips)),
            data_rate_bps=((dim, "chip"), np.tile(cube["data_rate_bps"].values[:, None], n_chips)),
            accuracy_chip_mean=((dim, "model"), chip_acc.mean(axis=-1)),
            accuracy_p05=((dim, "model"), p05),
            accuracy_p05_low=((dim, "model"), ordered[..., 0]),
            accuracy_p05_high=((dim, "model"), ordered[..., 2]),
            yield_share=((dim, "model"), (chip_acc >= target).mean(axis=-1)),
        )
        .assign_coords(
            chip=("chip", np.arange(n_chips)),
            result_key=(dim, keys),
            **{
                "chips.deployment": deployment,
                "chips.count": n_chips,
                "chips.yield_target": target,
            },
        )
        .assign_attrs(sweep=f"{cube.attrs['sweep']}_{deployment}")
    )


def deployment_sweep(cube, deployments=("per_chip", "shared", "robust"), **chips):
    """One cube of the mismatch and the deployment swept together: :func:`with_chips` of each
    deployment, concatenated along a ``deployment`` dimension (attribute ``field``
    ``chips.deployment``)."""
    import xarray as xr

    parts = [with_chips(cube, d, **chips).drop_vars("chips.deployment") for d in deployments]
    joined = xr.concat(
        parts, "deployment", data_vars="all", coords="different", compat="equals", join="exact"
    )
    attrs = {"field": "chips.deployment", "units": "1", "long_name": "deployment"}
    joined = joined.assign_coords(deployment=("deployment", list(deployments), attrs))
    return joined.transpose("sigma_rel", "deployment", ...).assign_attrs(
        sweep="mismatch_deployment"
    )
