"""What `eskin describe` says of a real taxel array: its taxels, what they say beyond each other,
and dead or saturated taxels."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from pipeline.recordings.describe import describe_dataset
from pipeline.recordings.describe_array import (
    describe_array,
    taxel_mean,
)
from pipeline.recordings.recording_set import Recordings
from pipeline.recordings.sources import load_folder
from pipeline.recordings.touch_statistics import touch_statistics
from tests.pipeline.recordings.test_taxel_columns import fabricslide_subset

FS_HZ = 200.0
TAXELS = ("t0", "t1", "t2", "t3", "t4")


def informed_array(
    *, informative: int = 2, n_classes: int = 4, per_class: int = 15, seed: int = 0
) -> Recordings:
    """Noise on every taxel, 4 s at 200 Hz; only taxel ``informative``'s amplitude depends on the
    class (1, 2, 3, 4 times), the others' is drawn alike for every class (0.5 to 4.5)."""
    rng = np.random.default_rng(seed)
    signals, labels = [], []
    for c in range(n_classes):
        for _ in range(per_class):
            scale = rng.uniform(0.5, 4.5, len(TAXELS))
            scale[informative] = 1.0 + c
            signals.append(10.0 + scale * rng.standard_normal((int(4 * FS_HZ), len(TAXELS))))
            labels.append(c)
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=tuple(f"c{c}" for c in range(n_classes)),
        fs_hz=FS_HZ,
        names=tuple(f"c{label}/r{i}" for i, label in enumerate(labels)),
        units="a.u.",
        name="informed",
        taxel_names=TAXELS,
        taxel_positions_mm=np.array([[2.0 * k, 0.0] for k in range(len(TAXELS))]),
    )


def test_the_taxel_that_holds_the_class_is_as_accurate_as_all_and_the_others_at_chance():
    array = describe_array(informed_array(per_class=30), span_s=4.0, window_s=0.1, folds=10)
    single = {s.taxels[0]: s.accuracy for s in array.single}
    assert array.chance == 0.25 and array.folds == 10
    # 120 recordings: a taxel at chance scores 0.25 +- 0.04 (one standard deviation); 0.4 is
    # more than three above it, and the informative taxel's amplitudes 1-4 separate fully. (With
    # 15 recordings a class, all five taxels' 20 statistics overfit: 0.8, not 1.)
    assert single["t2"] >= 0.95
    assert all(acc <= 0.4 for name, acc in single.items() if name != "t2")
    every = array.subsets[-1]
    assert every.taxels == TAXELS and every.accuracy >= single["t2"] - 0.05
    # The subsets are the taxels a design reads (pipeline.recordings.taxel_choice): on this line
    # of five, one taxel is the middle one, t2; two are the ends, without t2: at chance again.
    assert [s.taxels for s in array.subsets] == [
        ("t2",),
        ("t0", "t4"),
        ("t0", "t1", "t2", "t4"),
        TAXELS,
    ]
    assert array.subsets[0].accuracy >= 0.95 and array.subsets[1].accuracy <= 0.4
    assert array.taxels[3].position_mm == (6.0, 0.0)
    assert not array.warnings


def test_level_activity_and_a_dead_and_a_saturated_taxel_are_warned_of():
    rec = informed_array(per_class=5)
    signals = []
    for signal in rec.signals:
        signal = signal.copy()
        signal[:, 0] = 7.0  # dead: constant
        signal[:, 4] = np.clip(signal[:, 4], None, 11.0)  # clipped at a rail of 11
        signals.append(signal)
    rec = dataclasses.replace(rec, signals=tuple(signals), taxel_positions_mm=None)
    array = describe_array(rec, span_s=4.0, window_s=0.1, folds=10)
    facts = {t.name: t for t in array.taxels}
    assert facts["t0"].dead and facts["t0"].activity == 0 and facts["t0"].level == 7.0
    assert facts["t0"].rail_share == 0.0
    assert facts["t4"].high == 11.0 and facts["t4"].rail_share > 0.2
    assert not facts["t2"].dead and facts["t2"].rail_share < 0.01
    # t2's amplitude is 1 in class c0 and the median over recordings of its std lies at 2-3.
    assert 1.5 < facts["t2"].activity < 3.5 and facts["t2"].level == pytest.approx(10.0, abs=0.2)
    assert array.folds == 5
    dead, saturated = array.warnings
    assert dead.startswith("1 taxel is dead") and dead.endswith(": t0")
    assert saturated.startswith("1 taxel is saturated") and "t4 (" in saturated


def test_the_describe_of_an_array_judges_the_mean_over_taxels_and_adds_the_array():
    rec = informed_array(per_class=3)
    description = describe_dataset(rec, folds=3)
    assert description.array is not None and description.array.folds == 3
    mean = touch_statistics(taxel_mean(rec), window_s=0.1, span_s=4.0)
    assert description.statistics.envelope_corr_within == mean.envelope_corr_within
    np.testing.assert_array_equal(description.statistics.class_rms, mean.class_rms)
    out = json.loads(json.dumps(description.to_json(), allow_nan=False))
    assert [t["name"] for t in out["array"]["taxels"]] == list(TAXELS)
    assert out["array"]["taxels"][1]["position_mm"] == [2.0, 0.0]
    assert out["array"]["accuracy"]["subsets"][-1]["n_taxels"] == 5
    assert set(out["array"]["accuracy"]["single"]) == set(TAXELS)
    assert math.isfinite(out["array"]["envelope_corr_taxels"])


def test_taxels_that_move_together_are_said_to_and_one_channel_is_not_an_array():
    rng = np.random.default_rng(4)
    course = np.exp(np.linspace(0, 2, 800))[:, None]
    signals = tuple(course * rng.standard_normal((800, 3)) for _ in range(4))
    rec = Recordings(
        signals=signals,
        labels=np.array([0, 0, 1, 1]),
        class_names=("a", "b"),
        fs_hz=FS_HZ,
        names=("a/1", "a/2", "b/1", "b/2"),
        units="N",
        name="together",
        taxel_names=("x", "y", "z"),
    )
    array = describe_array(rec, span_s=4.0, window_s=0.1, folds=10)
    assert array.envelope_corr_taxels > 0.9
    assert any("they move together" in w for w in array.warnings)
    assert taxel_mean(rec).signals[0].shape == (800,)
    one = taxel_mean(rec)
    assert taxel_mean(one) is one
    with pytest.raises(ValueError, match="holds one channel, not a taxel array"):
        describe_array(one, span_s=4.0, window_s=0.1, folds=10)


def test_a_few_real_fabricslide_recordings_have_no_dead_or_saturated_taxel(tmp_path):
    rec = load_folder(fabricslide_subset(tmp_path, per_class=4))
    array = describe_array(rec, span_s=3.9, window_s=0.1, folds=4)
    assert [t.name for t in array.taxels] == [f"channel{k}" for k in range(1, 17)]
    assert not any(t.dead for t in array.taxels) and not array.warnings
    assert max(t.rail_share for t in array.taxels) < 0.01
    # Each taxel has a time course of its own (0.25 on all 210 recordings).
    assert 0.0 < array.envelope_corr_taxels < 0.6
    assert array.folds == 4 and array.chance == pytest.approx(1 / 7)


def test_touch_statistics_refuse_an_array_in_one_line():
    with pytest.raises(ValueError, match="touch statistics are of one channel, not of 5 taxels"):
        touch_statistics(informed_array(per_class=2), window_s=0.1, span_s=4.0)
