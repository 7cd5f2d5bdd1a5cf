"""A real array end to end, in memory: a dataset whose class information sits in one taxel only
(:func:`tests.real_array_helpers.one_informative_taxel`). Tolerances: the
informative taxel alone and all four are each at least 90 % accurate and within 10 points of
each other; any other taxel alone is at most 33 % + 25 points (chance plus three binomial
standard deviations of 36 recordings, sqrt(1/3 * 2/3 / 36) = 7.9 points).
"""

import dataclasses

import numpy as np
import pytest

from pipeline.chain.metrics import SpikeMetrics
from pipeline.design.scene import Model, Scene
from pipeline.recordings.recording_set import Recordings
from pipeline.results.provenance import recordings_attrs
from pipeline.run.entries import (
    RecordingsInfo,
    ResultEntry,
    decode_result_entry,
    encode_result_entry,
)
from pipeline.run.fit import DatasetLimits, check_scene_fits
from pipeline.run.stages import LEVELS, RECORDINGS, RESULTS
from pipeline.run.stopwatch import Stopwatch
from tests.real_array_helpers import (
    CHANCE,
    INFORMATIVE,
    N_TAXELS,
    one_informative_taxel,
    only_taxel,
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


def test_a_result_states_the_recorded_taxels_and_their_positions_and_reads_them_back():
    grid = [[float(x), float(y)] for y in range(2) for x in range(2)]
    recordings = one_informative_taxel()
    placed = dataclasses.replace(recordings, taxel_positions_mm=np.array(grid))
    info = RecordingsInfo.of(placed)
    assert info.taxel_names == ("t0", "t1", "t2", "t3")
    assert info.taxel_positions_mm == ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0))
    entry = ResultEntry(
        {"ffnn": [0.5, 0.5]}, {"train_ffnn": 1.0}, SpikeMetrics(1, 0, 0, 2, 3, 4), recordings=info
    )
    values, attrs = encode_result_entry(entry)
    assert attrs["taxel_names"] == ["t0", "t1", "t2", "t3"] and attrs["taxel_positions_mm"] == grid
    assert decode_result_entry(values, attrs).recordings == info
    cube_attrs = recordings_attrs([info, info])
    assert cube_attrs["taxel_names"] == ["t0", "t1", "t2", "t3"]
    assert cube_attrs["taxel_positions_mm"] == grid
    # One channel states no taxels: its stored attributes are those it had before arrays.
    one = RecordingsInfo.of(only_taxel(recordings, 0))
    assert one.taxel_positions_mm is None
    single = RecordingsInfo("synthetic", ("a",), 2000.0)
    assert (
        "taxel_names"
        not in encode_result_entry(
            ResultEntry({"ffnn": [0.5, 0.5]}, {}, SpikeMetrics(1, 0, 0, 2, 3, 4), recordings=single)
        )[1]
    )
