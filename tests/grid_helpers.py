"""Reference expansions and keys of grids, as first written: every point made by
``Scene.replace`` one at a time, every key hashed from the whole canonical form. The grid's
tests (:mod:`pipeline.design.grid`) and its keys' (:mod:`pipeline.run.grid_keys`) compare with
them."""

import hashlib
import json

from pipeline.design import fields
from pipeline.design.grid import Grid
from pipeline.design.scene import MODEL_REVISION, Scene


def keyed_dict(scene: Scene) -> dict:
    """The scene's plain form without what no key holds: its name, the fixed-threshold
    encoder (the neutral default) with the decay of a threshold it does not decay, the chips
    part while all its fields hold their (neutral) defaults, and the spiking decoder's fields of
    a scene that does not train it."""
    data = scene.to_dict()
    data.pop("name")
    if data["readout"]["encoder"] == "lcs":
        del data["readout"]["encoder"], data["readout"]["decay"]
    if not fields.plain(scene.chips, canonical=True):
        del data["chips"]
    if data["training"]["decisions"] == "full_touch":  # what every key before the choice meant
        del data["training"]["decisions"]
    if "snn" not in data["training"]["models"]:
        del data["training"]["snn"]
    return data


def reference_key(scene: Scene, level) -> str:
    """A level's key as it was first written: its parts found level by level, the canonical
    form of the whole scene as one dict."""
    paths = {}
    for each in (*level.upstream(), level):
        for read in each.reads:
            if read.applies(scene):
                paths.setdefault(read.path, None)
    parts = tuple(p for p in paths if not any(p.startswith(f"{q}.") for q in paths))
    assert level.key_parts(scene) == parts
    data = keyed_dict(scene)
    canonical = json.dumps(
        fields.select(data, parts),
        sort_keys=True,
        separators=(",", ":"),
        allow_nan=False,
    )
    text = f"r{MODEL_REVISION}:{level.name}:{canonical}"
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def reference_points(grid: Grid) -> list[tuple[str, tuple[int, ...], Scene]]:
    """Every point as ``Scene.replace`` makes it, one point at a time, its ``set`` and axis
    values together."""
    return [
        (s.name, index, grid.base.replace(**{**s.fixed, **values}))
        for s in grid.sweeps
        for index, values in s.index_values()
    ]


MANY_AXES = {
    "base": "paper",
    "sweeps": {
        "product": {
            "set": {"array.cols": 2, "readout.effects.amplifier_noise.sigma_v": 0.01},
            "axes": {
                "readout.threshold_v": [0.05, 0.09],
                "readout.effects.threshold_mismatch.sigma_rel": [0.0, 0.1, 0.2],
                "coding.window_s": [0.1, 0.2],
                "training.seed": [0, 1],
                "seed": [0, 5],
            },
        },
        "zipped": {
            "mode": "zip",
            "axes": {
                "readout.effects.comparator_noise.sigma_v": [0.0, 0.01, 0.02],
                "array.rows": [1, 2, 3],
                "coding.n_windows": [10, "auto", 5],
            },
        },
        "tables": {
            "axes": {
                "readout.effects": [{}, {"saturation": {"rail_v": 0.4}}],
                "training.models": [["ffnn"], ["cnn", "ffnn"]],
                "dataset.seed": [0, 1],
            }
        },
    },
}
