"""Readouts and signals for the readout's tests: a scene's readout with named effects, a random
walk."""

import numpy as np

from pipeline.design.scene import Scene


def readout_with(encoder="lcs", **effects):
    readout = {"threshold_v": 0.1, "encoder": encoder, "effects": effects}
    return Scene.from_dict({"readout": readout}).readout


def walk(n=4000, seed=0, step=0.02):
    return np.cumsum(np.random.default_rng(seed).standard_normal(n)) * step
