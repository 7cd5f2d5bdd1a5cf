"""Golden result cubes: hand-made result entries of fixed grids, and the cubes built from them.

``tests/data/golden_cubes.npz`` (values) and ``golden_cubes.json`` (dimensions, which names are
coordinates) hold, per sweep of :data:`GRID`, every data variable and coordinate a cube had
before cubes described themselves, without attributes: they were written by
``storage.cubes.build_cube`` of commit a3e6f52 from :func:`entries`, with :func:`write_golden`. A
cube built now must reproduce them (:func:`existing_part`, :func:`assert_matches`); coordinates
and attributes added since are not part of the comparison.

``tests/data/golden_grids.npz`` and ``golden_grids.json`` hold, per sweep of the built-in
``paper`` and ``smoke`` grids as they were (:data:`GRIDS`, inlined), every data variable and
coordinate (values, dims, attrs) and the cube's attributes, but the versions of the software,
as ``pipeline.results.cube.build_cube`` built them before the stage registry declared what each
stage stores: from :func:`rich_entries` (which also state the recordings and keep out-of-fold
predictions), with :func:`write_golden` (``attrs=True``). A cube built now must reproduce them
(:func:`compare_golden`) apart from the names in :data:`RENAMED` and :data:`ADDED`.

What the cubes copy from the entries (integers, strings, the entries' floats) must be identical,
bit for bit. What the cube builder computes from them by reductions (:data:`COMPUTED`: means over
folds, their intervals, correlations over sweep points) is compared within :data:`ULPS` units in
the last place of 1, the scale of those values (all lie in [-1, 1]): numpy sums in an order of
its choosing, which depends on the CPU's SIMD instructions (an AVX-512 machine gives another last
bit), so bit-for-bit equality there would test the machine, not the code.
"""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.chain.metrics import SpikeMetrics
from pipeline.design.grid import Grid
from pipeline.design.scene import Scene
from pipeline.results.cube import CUBE_VARIABLES
from pipeline.results.variables import CHARGE_DIM, REPEAT_DIM, SECONDS, STAGE_DIM, WORK_SECONDS
from pipeline.run.entries import OutOfFold, RecordingsInfo, ResultEntry
from pipeline.run.grid_keys import unique_points
from pipeline.run.stages import SETUP_STEP

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

GRIDS_GOLDEN = DATA / "golden_grids"
# The built-in grids' sweeps as they were (inlined from pipeline/design/grids/*.toml: a later change
# of those files must not move the golden file).
_PAPER_NOISE_V = [0.0025, 0.005, 0.01, 0.02, 0.03, 0.05, 0.075, 0.1, 0.15]
GRIDS = {
    "smoke": {
        "name": "smoke",
        "base": "smoke",
        # The smoke grid's sweeps are the first three of GRID's.
        "sweeps": {name: GRID["sweeps"][name] for name in ("threshold", "window", "noise")},
    },
    "paper": {
        "name": "paper",
        "base": "paper",
        "sweeps": {
            "threshold": {
                "title": "Fig. 7a: accuracy against the readout threshold",
                "axes": {
                    "readout.threshold_v": [
                        0.01,
                        0.02,
                        0.03,
                        0.05,
                        0.07,
                        0.09,
                        0.12,
                        0.15,
                        0.2,
                        0.25,
                        0.3,
                    ]
                },
            },
            "window": {
                "title": "Fig. 7b: accuracy against the window length (about 4 s of touch each)",
                "mode": "zip",
                "axes": {
                    "coding.window_s": [0.025, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4],
                    "coding.n_windows": [160, 80, 53, 40, 26, 20, 13, 10],
                },
            },
            "taxels": {
                "title": "Fig. 8: accuracy against the taxel count (square arrays)",
                "mode": "zip",
                "axes": {"array.rows": [1, 2, 3, 4, 5], "array.cols": [1, 2, 3, 4, 5]},
            },
            "taxel_rows": {
                "title": "Fig. 8: accuracy against the taxel count "
                "(rows x 1 arrays along the scan)",
                "set": {"array.cols": 1},
                "axes": {"array.rows": [1, 2, 3, 4, 5]},
            },
            "noise": {
                **{k: GRID["sweeps"]["noise"][k] for k in ("mode", "set", "correlate")},
                "title": "Fig. 9: SSNR and STE against accuracy (one taxel, constant threshold, "
                "rising noise)",
                "axes": {
                    "readout.effects.amplifier_noise.sigma_v": _PAPER_NOISE_V,
                    "readout.effects.comparator_noise.sigma_v": _PAPER_NOISE_V,
                },
            },
            "mismatch": {
                "title": "Fig. 10: accuracy against threshold mismatch between taxels",
                "axes": {
                    "readout.effects.threshold_mismatch.sigma_rel": [0.0, 0.05, 0.1, 0.2, 0.3, 0.5]
                },
            },
            "observation": {
                "title": "Accuracy against observation time: the first n windows of 0.1 s",
                "set": {"coding.window_s": 0.1},
                "axes": {"coding.n_windows": [1, 2, 3, 5, 10, 20, 40]},
            },
        },
    },
}
# The recordings the rich entries claim: 3 classes of 2 recordings each.
CLASSES = ("fine", "medium", "coarse")
RECORDINGS = RecordingsInfo("synthetic", CLASSES, 2000.0)
RECORDING_NAMES = tuple(f"{c}/{i}" for c in CLASSES for i in range(2))
LABELS = np.repeat(np.arange(len(CLASSES)), 2)

#: Cube names (variables, coordinates) renamed since the golden grids' files were written: old
#: name -> the name now holding the same values (broadcast to its dims), in every cube that no
#: longer has the old name.
RENAMED: dict[str, str] = {
    # Equivalent bits are stored once: the spike metric's variable, not also a coordinate.
    "readout.equivalent_bits": "equivalent_bits",
    # A swept field is its axis's coordinate alone, no longer also a dotted one.
    "readout.threshold_v": "threshold_v",
    "coding.window_s": "window_s",
    "coding.n_windows": "n_windows",
    "array.rows": "rows",
    "array.cols": "cols",
    "readout.effects.amplifier_noise.sigma_v": "amplifier_noise_sigma_v",
    "readout.effects.comparator_noise.sigma_v": "comparator_noise_sigma_v",
    "readout.effects.threshold_mismatch.sigma_rel": "sigma_rel",
}
#: Names cubes have now that the golden grids' files do not.
ADDED: frozenset[str] = frozenset(
    {
        "n_windows_used",
        # The encoder architecture and the decaying encoder's parameters, new scene fields.
        "readout.encoder",
        "readout.decay.theta_min_v",
        "readout.decay.tau_s",
        # The spiking decoder's hyper-parameters, new scene fields.
        "training.snn.step_s",
        "training.snn.hidden_neurons",
        "training.snn.tau_mem_s",
        "training.snn.threshold",
        "training.snn.surrogate_slope",
        "training.snn.epochs",
        "training.snn.inputs",
        "training.snn.learning_rate",
        "training.snn.time_constants",
        "training.snn.readout",
        "training.snn.hidden_layers",
        "training.snn.along_touch_loss",
        # What decisions the decoders are trained for, a new scene field.
        "training.decisions",
    }
)
#: Variables the cube builder computes from the entries with floating-point reductions whose order
#: numpy chooses per CPU: compared within :data:`ULPS` (module docstring), the rest exactly.
COMPUTED: frozenset[str] = frozenset(
    {"accuracy_mean", "accuracy_low", "accuracy_high", "correlation_r", "correlation_p"}
)
#: Units in the last place of 1 (absolute) that a :data:`COMPUTED` value may differ by: a few
#: roundings of sums of terms of at most 1 (measured: at most 1.5 ulps on an AVX-512 machine).
ULPS = 4
# Attributes that name the software that built a cube: they change with every release.
_VERSION_ATTRS = ("package_version", "version_")


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
    return {key: entry(scene) for key, scene in unique_points(g).items()}


def rich_entry(scene: Scene) -> ResultEntry:
    """:func:`entry` that also states its recordings and keeps out-of-fold predictions: the
    first ``k`` recordings right (``k`` a fixed function of the scene), the others wrong."""
    plain = entry(scene)
    repeats, folds = scene.training.repeats, scene.training.folds
    predicted = {}
    for i, (model, accuracy) in enumerate(plain.fold_accuracy.items()):
        k = (round(float(np.mean(accuracy)) * 100) + i) % (len(LABELS) + 1)
        guess = np.where(np.arange(len(LABELS)) < k, LABELS, (LABELS + 1) % len(CLASSES))
        predicted[model] = np.tile(guess, (repeats, 1))
    test_fold = np.tile(np.arange(len(LABELS)) % folds, (repeats, 1))
    return dataclasses.replace(
        plain,
        recordings=RECORDINGS,
        out_of_fold=OutOfFold(RECORDING_NAMES, LABELS, predicted, test_fold),
    )


def rich_entries(g: Grid) -> dict[str, ResultEntry]:
    return {key: rich_entry(scene) for key, scene in unique_points(g).items()}


def grids() -> dict[str, Grid]:
    """The built-in grids as they were, by name: their points trained for the full touch, as
    every point then was (``training.decisions``; their keys are the keys they had)."""
    return {
        name: Grid.from_dict({**data, "base": _trained_for_the_full_touch(data["base"])})
        for name, data in GRIDS.items()
    }


def _trained_for_the_full_touch(base: str) -> dict:
    return Scene.builtin(base).replace(**{"training.decisions": "full_touch"}).to_dict()


def write_golden(cubes: dict[str, xr.Dataset], path: Path = GOLDEN, *, attrs: bool = False) -> None:
    """Save every variable of ``cubes`` (values and dimensions; with ``attrs``, also every
    variable's attributes and the cube's but those naming the software's versions)."""
    arrays, layout = {}, {}
    for name, cube in cubes.items():
        layout[name] = {}
        for var, variable in cube.variables.items():
            arrays[f"{name}/{var}"] = np.asarray(variable.values)
            layout[name][str(var)] = {"dims": list(variable.dims), "coord": var in cube.coords}
            if attrs:
                layout[name][str(var)]["attrs"] = _plain(variable.attrs)
        if attrs:
            layout[name]["@attrs"] = _plain(_without_versions(cube.attrs))
    np.savez_compressed(path.with_suffix(".npz"), **arrays)
    path.with_suffix(".json").write_text(json.dumps(layout, indent=1, sort_keys=True) + "\n")


def read_golden(path: Path = GOLDEN) -> dict[str, xr.Dataset]:
    layout = json.loads(path.with_suffix(".json").read_text())
    with np.load(path.with_suffix(".npz"), allow_pickle=False) as arrays:
        cubes = {}
        for name, variables in layout.items():
            data, coords = {}, {}
            cube_attrs = variables.pop("@attrs", {})
            for var, spec in variables.items():
                values = (spec["dims"], arrays[f"{name}/{var}"], spec.get("attrs", {}))
                (coords if spec["coord"] else data)[var] = values
            cubes[name] = xr.Dataset(data, coords=coords, attrs=cube_attrs)
    return cubes


def compare_golden(cube: xr.Dataset, golden: xr.Dataset) -> None:
    """Assert that ``cube`` holds exactly ``golden``'s variables, coordinates and attributes
    (values, dtypes, dims, attrs), apart from :data:`RENAMED` and :data:`ADDED`, seconds in
    their old layout (:func:`old_seconds_layout`)."""
    cube = old_seconds_layout(cube)
    renamed = {old: new for old, new in RENAMED.items() if old in golden and old not in cube}
    expected = set(golden.variables) - set(renamed) | set(renamed.values())
    assert set(cube.variables) == expected | (ADDED & set(cube.variables)), (
        f"{golden.attrs.get('sweep')}: variables differ: "
        f"{sorted(set(map(str, cube.variables)) ^ set(map(str, expected)))}"
    )
    kept = [name for name in golden.variables if name not in renamed]
    got = cube[kept].drop_vars([n for n in cube.coords if n not in kept])
    got.attrs = _plain(_without_versions(cube.attrs))
    assert_matches(got, golden.drop_vars(list(renamed)))
    for old, new in renamed.items():
        now = cube[new].variable
        was = golden[old].variable.set_dims(dict(now.sizes)).transpose(*now.dims)
        np.testing.assert_array_equal(was.values, now.values, err_msg=f"{old} -> {new}")


def assert_matches(got: xr.Dataset, golden: xr.Dataset) -> None:
    """Assert that ``got`` is ``golden``: identical (values, dtypes, dims, coordinates,
    attributes), but the values of :data:`COMPUTED` variables, which may differ by :data:`ULPS`
    units in the last place of 1 (NaN where ``golden`` has NaN)."""
    computed = sorted(COMPUTED & set(golden.data_vars))
    assert sorted(COMPUTED & set(got.data_vars)) == computed, "computed variables differ"
    xr.testing.assert_identical(got.drop_vars(computed), golden.drop_vars(computed))
    tolerance = ULPS * np.finfo(np.float64).eps
    for name in computed:
        now, was = got[name].variable, golden[name].variable
        assert (now.dims, now.dtype, now.attrs) == (was.dims, was.dtype, was.attrs), name
        np.testing.assert_allclose(now.values, was.values, rtol=0, atol=tolerance, err_msg=name)


def _without_versions(attrs: dict) -> dict:
    return {k: v for k, v in attrs.items() if not k.startswith(_VERSION_ATTRS)}


def _plain(attrs: dict) -> dict:
    """Attributes as JSON reads them back (tuples as lists, numpy scalars as numbers)."""
    return json.loads(json.dumps(attrs, default=lambda v: v.item()))


#: ``long_name`` of the golden files' ``seconds``: the stages' work seconds, as cubes held them
#: before they kept paid seconds apart.
_OLD_SECONDS_LONG_NAME = "wall time of the stage, as measured when computed"


def old_seconds_layout(cube: xr.Dataset) -> xr.Dataset:
    """``cube`` in the seconds layout of the golden files, the one change they do not hold.

    The golden files have ``seconds`` (axes..., stage): work seconds, the stages of that time.
    Cubes now hold those values as ``work_seconds``, with stage ``setup`` added (NaN for the
    golden entries, which predate it), and ``seconds`` (axes..., stage, charge) holds the paid
    seconds (NaN throughout: the golden entries state none). Both are checked here, then
    ``work_seconds`` without ``setup`` is compared as the old ``seconds``, under its old
    description (its new one is checked against the declaration).
    """
    if CHARGE_DIM not in cube.dims:
        return cube
    assert np.isnan(cube[SECONDS].values).all(), "golden entries state no paid seconds"
    assert np.isnan(cube[WORK_SECONDS].sel({STAGE_DIM: SETUP_STEP}).values).all()
    assert cube[WORK_SECONDS].attrs == CUBE_VARIABLES[WORK_SECONDS]
    old = cube.drop_vars([SECONDS, CHARGE_DIM]).drop_sel({STAGE_DIM: [SETUP_STEP]})
    old = old.rename({WORK_SECONDS: SECONDS})
    old[SECONDS].attrs = {"units": "s", "long_name": _OLD_SECONDS_LONG_NAME}
    return old


def existing_part(cube: xr.Dataset, golden: xr.Dataset) -> xr.Dataset:
    """``cube`` cut to the variables ``golden`` has, attributes dropped, for :func:`assert_matches`.

    The golden cubes predate cross-validation repeats: their one repeat is compared without the
    ``repeat`` dimension; seconds are compared in their old layout (:func:`old_seconds_layout`)."""
    cube = old_seconds_layout(cube)
    extra = [name for name in cube.variables if name not in golden.variables]
    part = cube.drop_vars(extra).drop_attrs()
    if REPEAT_DIM in part.dims and REPEAT_DIM not in golden.dims and part.sizes[REPEAT_DIM] == 1:
        part = part.isel({REPEAT_DIM: 0}, drop=True)
    return part
