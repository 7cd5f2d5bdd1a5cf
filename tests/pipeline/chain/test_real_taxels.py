"""The taxels a design reads of a real array: their signals (the chosen columns, undelayed), the
chain counting the taxels read, and the refusals of a design that does not fit the array."""

import dataclasses

import numpy as np
import pytest

from pipeline.chain.frontend import FrontEnd
from pipeline.chain.real_taxels import (
    array_misfits,
    taxel_rows,
    taxels_read,
)
from pipeline.chain.taxels import recording_taxels
from pipeline.design.scene import Scene
from pipeline.errors import SceneError
from pipeline.recordings.recording_set import Recordings
from pipeline.run.encoding import encode_spikes, encode_trains, spike_metrics
from pipeline.run.fit import DatasetLimits, check_scene_fits
from pipeline.run.stopwatch import Stopwatch
from tests.real_array_helpers import only_taxel


def array_recordings(n_taxels: int = 4, n_samples: int = 400) -> Recordings:
    """Four recordings of ``n_taxels`` taxels at 1 kHz, taxel ``k`` a sine of ``k + 1`` Hz
    times ``k + 1``, so every column differs."""
    t = np.arange(n_samples) / 1000.0
    columns = [(k + 1) * np.sin(2 * np.pi * 5 * (k + 1) * t) for k in range(n_taxels)]
    signal = np.stack(columns, axis=1)
    return Recordings(
        signals=tuple(signal * (1 + r) for r in range(4)),
        labels=np.array([0, 0, 1, 1]),
        class_names=("a", "b"),
        fs_hz=1000.0,
        names=tuple(f"c/r{r}.npy" for r in range(4)),
        units="a.u.",
        name="array",
        taxel_names=tuple(f"t{k}" for k in range(n_taxels)),
    )


def real_array(**changes) -> Scene:
    """The paper's scene on a real array (no time-shift grid), two folds."""
    grid = {"array.rows": 1, "array.cols": 1, "training.folds": 2}
    return Scene.paper().replace(**{**grid, **changes})


# -- their signals ---------------------------------------------------------------------------


def test_a_real_array_reads_its_chosen_columns_undelayed_one_row_each():
    recordings = array_recordings(n_taxels=4)
    scene = real_array(**{"array.taxels": 2})
    assert taxels_read(recordings, scene.array).tolist() == [1, 3]
    front_end = FrontEnd(offset=0.0, gain_v_per_unit=0.5)
    made = list(recording_taxels(recordings, front_end, scene.array, Stopwatch(None).stage))
    assert [index for index, _ in made] == [0, 1, 2, 3]
    for index, taxels in made:
        expected = 0.5 * np.asarray(recordings.signals[index])[:, [1, 3]].T
        assert taxels.n_taxels == 2 and taxels.n_samples == 400
        np.testing.assert_array_equal(taxels.signals, expected)
        assert taxels.signals.flags.c_contiguous
        np.testing.assert_array_equal(taxels.taxel(1), expected[1])


def test_one_channel_recordings_keep_their_time_shift_grid():
    recordings = array_recordings(n_taxels=1)
    one_channel = dataclasses.replace(
        recordings,
        signals=tuple(np.asarray(s)[:, 0] for s in recordings.signals),
        name="one",
        taxel_names=(),
    )
    scene = Scene.paper()
    assert taxels_read(one_channel, scene.array) is None
    front_end = FrontEnd(offset=0.0, gain_v_per_unit=1.0)
    _, taxels = next(recording_taxels(one_channel, front_end, scene.array, Stopwatch(None).stage))
    assert taxels.n_taxels == 9  # 3 x 3, three distinct delays
    assert len(taxels.signals) == 3


def test_taxel_rows_copies_columns_in_the_order_chosen():
    signal = np.arange(12, dtype=np.float64).reshape(4, 3)
    np.testing.assert_array_equal(
        taxel_rows(signal, np.array([0, 2])), [[0, 3, 6, 9], [2, 5, 8, 11]]
    )


def test_the_chain_counts_the_taxels_read_not_the_grid():
    """Trains, event and data rates follow the taxels read; each taxel's REAL train is measured
    against its own TRUE train; random effects are drawn per taxel read."""
    recordings = array_recordings(n_taxels=4)
    noisy = {"readout.effects": {"comparator_offset": {}, "threshold_mismatch": {}}}
    watch = Stopwatch(None)
    front_end = FrontEnd(offset=0.0, gain_v_per_unit=0.1)
    encoded = {}
    for k in (1, 2, 4):
        scene = real_array(**{"array.taxels": k, **noisy})
        encoded[k] = encode_trains(
            recordings, front_end, scene.array, scene.readout, scene.seed, watch
        )
        assert encoded[k].true.n_taxels == k and encoded[k].real.n_taxels == k
        assert encoded[k].true.count.shape == (4, k)
    # Reading all four taxels: the TRUE train of taxel k is that of column k alone.
    one = real_array(**{"array.taxels": 1})
    for k in range(4):
        column = only_taxel(recordings, k)
        alone = encode_trains(column, front_end, one.array, one.readout, one.seed, watch)
        np.testing.assert_array_equal(alone.true.count[:, 0], encoded[4].true.count[:, k])
    # Four taxels read: the address-event word is two address bits and a polarity bit, and the
    # event rate sums the four taxels' spikes (per recording, averaged).
    scene = real_array(**{"array.taxels": 4, **noisy})
    metrics = spike_metrics(encoded[4], scene.readout)
    real = encoded[4].real
    assert metrics.event_rate_hz == pytest.approx(
        float(np.mean(real.count.sum(axis=1) / real.duration_s)), rel=1e-12
    )
    assert metrics.data_rate_bps == pytest.approx(metrics.event_rate_hz * 3, rel=1e-12)
    # Different taxels read draw different mismatch: the REAL trains are not all equal to the TRUE.
    assert not np.array_equal(encoded[4].real.count, encoded[4].true.count)


# -- refusals --------------------------------------------------------------------------------


def test_more_taxels_than_recorded_or_a_grid_on_a_real_array_is_refused_in_one_line_each():
    limits = DatasetLimits.of(array_recordings(n_taxels=4))
    assert limits.n_taxels == 4 and limits.is_array
    check_scene_fits(real_array(**{"array.taxels": 4}), limits)
    check_scene_fits(real_array(), limits)
    with pytest.raises(SceneError) as info:
        check_scene_fits(real_array(**{"array.taxels": 5}), limits)
    assert (
        "array.taxels: 5 taxels asked by array.taxels of dataset 'array', "
        "whose recordings hold 4 taxels" in str(info.value)
    )
    with pytest.raises(SceneError) as info:
        check_scene_fits(real_array(**{"array.rows": 3, "array.cols": 3}), limits)
    assert "array: a 3x3 grid of time-shifted copies asked of dataset 'array'" in str(info.value)
    assert array_misfits(Scene.paper().array, 1, False, "one") == []
    (problem,) = array_misfits(real_array(**{"array.taxels": 2}).array, 1, False, "one")
    assert problem == (
        "array.taxels",
        "2 taxels asked by array.taxels of dataset 'one', whose recordings hold one channel",
    )


def test_fewer_than_one_taxel_is_refused_by_the_field():
    with pytest.raises(SceneError, match=r"array.taxels: 0 is out of range: must be between 1"):
        real_array(**{"array.taxels": 0})


def test_the_field_at_its_default_changes_no_key():
    assert "taxels" not in Scene.paper().canonical()
    assert '"taxels":4' in real_array(**{"array.taxels": 4}).canonical()


def test_chips_of_a_real_array_draw_per_taxel_read():
    """Every chip holds one train per taxel read; chip 0 is the scene's own REAL trains, and
    another chip draws its own mismatch (its trains differ)."""
    recordings = array_recordings(n_taxels=4)
    scene = real_array(
        **{
            "array.taxels": 2,
            "readout.effects": {"threshold_mismatch": {"sigma_rel": 0.3}},
            "chips.count": 3,
        }
    )
    front_end = FrontEnd(offset=0.0, gain_v_per_unit=0.1)
    spikes = encode_spikes(
        recordings=recordings,
        front_end=front_end,
        array=scene.array,
        readout=scene.readout,
        seed=scene.seed,
        count=scene.chips.count,
        deployment=scene.chips.deployment,
        watch=Stopwatch(None),
    )
    chips = spikes.chips
    assert spikes.encoded.real.count.shape == (4, 2)
    assert chips.real.count.shape == (3 * 4, 2)
    np.testing.assert_array_equal(chips.real.count[:4], spikes.encoded.real.count)
    assert not np.array_equal(chips.real.count[4:8], chips.real.count[:4])
    assert len(chips.metrics) == 3
