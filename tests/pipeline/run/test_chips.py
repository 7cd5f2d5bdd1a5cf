from dataclasses import astuple

import numpy as np

from pipeline.design.scene import Scene
from pipeline.run.entries import (
    decode_result_entry,
    decode_spike_entry,
    encode_result_entry,
    encode_spike_entry,
)
from pipeline.run.records import StepSeconds
from pipeline.run.stages import LEVELS, RESULTS, SPIKES
from pipeline.run.stopwatch import Stopwatch

SMOKE = Scene.builtin("smoke").replace(
    **{
        "readout.effects": {"threshold_mismatch": {"sigma_rel": 0.5}},
        "training.models": ["ffnn"],
        "training.epochs": 2,
        "dataset.duration_s": 1.0,
    }
)


def test_chip_trains_and_results_round_trip_through_their_entries():
    scene = SMOKE.replace(**{"chips.count": 3, "chips.deployment": "shared"})
    outputs = {}
    watch = Stopwatch(None)
    for level in LEVELS:
        outputs[level.name] = level.run(scene, outputs, watch)
    spikes = outputs[SPIKES.name]
    entry = SPIKES.record.make(spikes, _seconds(), outputs.get)
    back = decode_spike_entry(*encode_spike_entry(entry))
    for a, b in (
        (entry.chips.real, back.chips.real),
        (entry.chips.reference, back.chips.reference),
    ):
        for name in ("times_s", "polarity", "count", "duration_s"):
            assert np.array_equal(getattr(a, name), getattr(b, name))
    assert [astuple(m) for m in back.chips.metrics] == [astuple(m) for m in entry.chips.metrics]
    assert back.chips.n_chips == 3
    assert np.array_equal(back.chips.chip(0).times_s, spikes.encoded.real.times_s)
    result = RESULTS.record.make(outputs[RESULTS.name], _seconds(), outputs.get)
    again = decode_result_entry(*encode_result_entry(result))
    for model, values in result.chips.fold_accuracy.items():
        assert np.array_equal(again.chips.fold_accuracy[model], values)
        assert np.array_equal(again.chips.predicted[model], result.chips.predicted[model])
    assert [astuple(m) for m in again.chips.metrics] == [astuple(m) for m in result.chips.metrics]


def _seconds():
    return StepSeconds({"readout": 1.0}, {}, "key")
