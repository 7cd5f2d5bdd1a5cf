"""A real array end to end, in memory: a dataset whose class information sits in one taxel only.

Three classes, 12 recordings each, of 4 taxels at 500 Hz: taxel 2 (the one a design reading one
taxel of four reads, :func:`pipeline.chain.real_taxels.chosen_taxels`) vibrates at a frequency
of its class; the other three carry noise drawn alike for every class. Tolerances: the
informative taxel alone and all four are each at least 90 % accurate and within 10 points of
each other; any other taxel alone is at most 33 % + 25 points (chance plus three binomial
standard deviations of 36 recordings, sqrt(1/3 * 2/3 / 36) = 7.9 points).
"""

import numpy as np
import pytest

from pipeline.design.scene import Model, Scene
from pipeline.recordings.recording_set import Recordings
from pipeline.run.fit import DatasetLimits, check_scene_fits
from pipeline.run.stages import LEVELS, RECORDINGS, RESULTS
from pipeline.run.stopwatch import Stopwatch

FS_HZ = 500.0
N_TAXELS = 4
INFORMATIVE = 2
PER_CLASS = 12
CLASS_HZ = (4.0, 12.0, 30.0)
CHANCE = 1 / len(CLASS_HZ)


def one_informative_taxel(seed: int = 0) -> Recordings:
    """The dataset of the module docstring: 1 s recordings, float64 (500, 4)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(FS_HZ)) / FS_HZ
    signals, labels = [], []
    for label, hz in enumerate(CLASS_HZ):
        for _ in range(PER_CLASS):
            columns = []
            for taxel in range(N_TAXELS):
                if taxel == INFORMATIVE:
                    phase = rng.uniform(0, 2 * np.pi)
                    column = np.sin(2 * np.pi * hz * t + phase)
                else:  # every class alike: a random frequency from one range
                    f = rng.uniform(CLASS_HZ[0], CLASS_HZ[-1])
                    column = np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
                columns.append(column + 0.05 * rng.standard_normal(t.size))
            signals.append(np.stack(columns, axis=1))
            labels.append(label)
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=tuple(f"c{hz:g}Hz" for hz in CLASS_HZ),
        fs_hz=FS_HZ,
        names=tuple(f"c{label}/r{i:02d}.npy" for i, label in enumerate(labels)),
        units="a.u.",
        name="one informative taxel",
        taxel_names=tuple(f"t{k}" for k in range(N_TAXELS)),
    )


def only_taxel(recordings: Recordings, taxel: int) -> Recordings:
    """The dataset of one taxel's column alone."""
    return Recordings(
        signals=tuple(np.asarray(s)[:, [taxel]] for s in recordings.signals),
        labels=recordings.labels,
        class_names=recordings.class_names,
        fs_hz=recordings.fs_hz,
        names=recordings.names,
        units=recordings.units,
        name=f"taxel {taxel}",
        taxel_names=(recordings.taxel_names[taxel],),
    )


SCENE = Scene.from_dict(
    {
        "array": {"rows": 1, "cols": 1},
        "readout": {"threshold_v": 0.05},
        "coding": {"window_s": 0.1},
        "training": {
            "models": ["ffnn"],
            "epochs": 60,
            "learning_rate": 0.01,
            "hidden_units": 32,
            "folds": 4,
        },
    }
)


def accuracy(scene: Scene, recordings: Recordings) -> float:
    """Out-of-fold accuracy of the FFNN, the levels run in memory on ``recordings``."""
    check_scene_fits(scene, DatasetLimits.of(recordings))
    watch = Stopwatch(None)
    outputs = {RECORDINGS.name: recordings}
    for level in LEVELS[1:]:
        outputs[level.name] = level.run(scene, outputs, watch)
    result = outputs[RESULTS.name][Model.FFNN]
    return float(np.mean(result.predicted == recordings.labels))


@pytest.fixture(scope="module")
def dataset() -> Recordings:
    return one_informative_taxel()


def test_the_informative_taxel_alone_is_as_accurate_as_all_of_them(dataset):
    alone = accuracy(SCENE.replace(**{"array.taxels": 1}), dataset)
    every = accuracy(SCENE, dataset)
    assert alone >= 0.9 and every >= 0.9
    assert abs(alone - every) <= 0.1
    assert accuracy(SCENE, only_taxel(dataset, INFORMATIVE)) == alone


@pytest.mark.parametrize("taxel", [t for t in range(N_TAXELS) if t != INFORMATIVE])
def test_any_other_taxel_alone_is_at_chance(dataset, taxel):
    assert accuracy(SCENE, only_taxel(dataset, taxel)) <= CHANCE + 0.25
