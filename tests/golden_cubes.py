"""Golden result cubes: hand-made result entries of a fixed grid, and today's cube variables.

``tests/data/golden_cubes.npz`` (values) and ``golden_cubes.json`` (dimensions, which names are
coordinates) hold, per sweep of :data:`GRID`, every data variable and coordinate a cube had
before cubes described themselves, without attributes: they were written by
``storage.cubes.build_cube`` of commit a3e6f52 from :func:`entries`, with :func:`write_golden`. A
cube built now must reproduce them exactly (:func:`existing_part`); coordinates and attributes
added since are not part of the comparison.
"""

import json
import math
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.grid import Grid
from pipeline.metrics import SpikeMetrics
from pipeline.scene import Scene
from storage.store import ResultEntry

DATA = Path(__file__).parent / "data"
GOLDEN = DATA / "golden_cubes"

# The smoke grid's sweeps as they were (inlined: a later change of smoke.toml must not move the
# golden file), plus a product sweep, a sweep of tables and one whose points name an effect the
# base does not.
GRID = {
    "name": "golden",
    "base": "smoke",
    "sweeps": {
        "threshold": {"axes": {"readout.threshold_v": [0.05, 0.09]}},
        "window": {"axes": {"coding.window_s": [0.1, 0.2]}},
        "noise": {
            "mode": "zip",
            "set": {"array.rows": 1, "array.cols": 1},
            "correlate": True,
            "axes": {
                "readout.effects.amplifier_noise.sigma_v": [0.005, 0.01, 0.02, 0.04],
                "readout.effects.comparator_noise.sigma_v": [0.005, 0.01, 0.02, 0.04],
            },
        },
        "product": {"axes": {"readout.threshold_v": [0.05, 0.2], "coding.n_windows": [1, 3, 5]}},
        "models": {"axes": {"training.models": [["ffnn"], ["cnn", "ffnn"]]}},
        "mismatch": {"axes": {"readout.effects.threshold_mismatch.sigma_rel": [0.0, 0.1, 0.3]}},
    },
}
FOLD_OFFSETS = np.array([-0.03, 0.01, 0.02, 0.0])


def grid() -> Grid:
    return Grid.from_dict(GRID)


def entry(scene: Scene) -> ResultEntry:
    """A result entry that is a fixed function of the scene: no training, exact numbers."""
    readout = scene.readout
    noise = sum(getattr(p, "sigma_v", 0.0) for p in readout.effects.values())
    mismatch = sum(getattr(p, "sigma_rel", 0.0) for p in readout.effects.values())
    windows = 0 if scene.coding.n_windows == "auto" else scene.coding.n_windows
    base = 0.4 + readout.threshold_v - 3.0 * noise - 0.2 * mismatch + 0.01 * windows
    base += 0.1 * scene.coding.window_s + 0.02 * scene.array.n_taxels
    fold_accuracy = {
        m.value: base + (0.05 if m.value == "cnn" else 0.0) + FOLD_OFFSETS
        for m in scene.training.models
    }
    seconds = {"load": 0.25, "front_end": 0.125, "taxels": 0.01 * scene.array.n_taxels}
    if readout.threshold_v < 0.08:  # some points lack stages: NaN in the cube
        seconds |= {"readout": 0.5 + noise, "metrics": 0.0625, "coding": 0.03125}
    seconds |= {f"train_{m.value}": 1.0 + windows for m in scene.training.models}
    return ResultEntry(
        fold_accuracy=fold_accuracy,
        seconds=seconds,
        metrics=SpikeMetrics(
            ssnr_db=-20 * math.log10(noise) if noise else math.inf,
            ste_s2=(noise - 0.015) * noise,  # negative for small noise, as the paper's STE can be
            ste_sign_safe_s2=abs(noise - 0.015) * noise,
            event_rate_hz=100.0 / readout.threshold_v,
            data_rate_bps=300.0 / readout.threshold_v,
            equivalent_bits=readout.equivalent_bits,
        ),
    )


def entries(g: Grid) -> dict[str, ResultEntry]:
    return {key: entry(scene) for key, scene in g.unique_points().items()}


def write_golden(cubes: dict[str, xr.Dataset], path: Path = GOLDEN) -> None:
    """Save every variable of ``cubes`` (values and dimensions; no attributes)."""
    arrays, layout = {}, {}
    for name, cube in cubes.items():
        layout[name] = {}
        for var, variable in cube.variables.items():
            arrays[f"{name}/{var}"] = np.asarray(variable.values)
            layout[name][str(var)] = {"dims": list(variable.dims), "coord": var in cube.coords}
    np.savez_compressed(path.with_suffix(".npz"), **arrays)
    path.with_suffix(".json").write_text(json.dumps(layout, indent=1, sort_keys=True) + "\n")


def read_golden(path: Path = GOLDEN) -> dict[str, xr.Dataset]:
    layout = json.loads(path.with_suffix(".json").read_text())
    with np.load(path.with_suffix(".npz"), allow_pickle=False) as arrays:
        cubes = {}
        for name, variables in layout.items():
            data, coords = {}, {}
            for var, spec in variables.items():
                (coords if spec["coord"] else data)[var] = (spec["dims"], arrays[f"{name}/{var}"])
            cubes[name] = xr.Dataset(data, coords=coords)
    return cubes


def existing_part(cube: xr.Dataset, golden: xr.Dataset) -> xr.Dataset:
    """``cube`` cut to the variables ``golden`` has, attributes dropped, for assert_identical.

    The golden cubes predate cross-validation repeats: their one repeat is compared without the
    ``repeat`` dimension."""
    extra = [name for name in cube.variables if name not in golden.variables]
    part = cube.drop_vars(extra).drop_attrs()
    if "repeat" in part.dims and "repeat" not in golden.dims and part.sizes["repeat"] == 1:
        part = part.isel(repeat=0, drop=True)
    return part
