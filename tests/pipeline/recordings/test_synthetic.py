"""Tests of pipeline.recordings.synthetic: determinism, layout, the recordings the sensor gives,
and the statistics the module docstring quotes (built-in touches inside the real touches'
ranges)."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
from scipy.signal import welch

import pipeline.recordings.synthetic as synthetic
from pipeline.errors import DatasetError
from pipeline.recordings import touch as touch_module
from pipeline.recordings.materials import TEXTURE_CLASSES, material_map
from pipeline.recordings.synthetic import synthetic_recordings
from pipeline.recordings.touch import touch
from pipeline.recordings.touch_statistics import REAL_TOUCHES, touch_statistics

FS = 2000.0


@pytest.fixture(scope="module")
def small():
    return synthetic_recordings(seed=3, recordings_per_class=6, duration_s=2.0)


def test_same_seed_gives_identical_recordings():
    a = synthetic_recordings(seed=11, recordings_per_class=2, duration_s=0.5)
    b = synthetic_recordings(seed=11, recordings_per_class=2, duration_s=0.5)
    assert a.names == b.names
    np.testing.assert_array_equal(a.labels, b.labels)
    for x, y in zip(a.signals, b.signals, strict=True):
        np.testing.assert_array_equal(x, y)


# A fresh process, as a worker: its first load imports scipy's filters, which the load step's
# timer must book as shared set-up, not as the load's work; a later load imports nothing, so it
# books no one-off time at all.
_FIRST_LOAD = """
import sys
from pipeline import jit
from pipeline.design.scene import DatasetSpec
from pipeline.run.stages import SETUP_STEP, load, step_charge
from pipeline.run.records import Charge
from pipeline.run.stopwatch import Stopwatch

assert "scipy.signal" not in sys.modules and "scipy.ndimage" not in sys.modules
dataset = DatasetSpec(recordings_per_class=1, duration_s=0.5)
first, later = Stopwatch(None), Stopwatch(None)
load(dataset=dataset, watch=first)
assert "scipy.signal" in sys.modules and "scipy.ndimage" in sys.modules
paid = first.paid(step_charge)
assert paid[Charge.SHARED].get(SETUP_STEP, 0.0) > 0.0, paid
assert paid[Charge.SHARED]["load"] == first.seconds["load"], paid
booked = jit.one_off_seconds()
load(dataset=dataset, watch=later)
assert jit.one_off_seconds() == booked, "a later load booked one-off time"
assert SETUP_STEP not in later.paid(step_charge)[Charge.SHARED], later.seconds
"""


def test_a_process_s_first_load_books_importing_scipy_as_one_off_set_up_not_load_work():
    done = subprocess.run([sys.executable, "-c", _FIRST_LOAD], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_different_seed_gives_different_recordings():
    a = synthetic_recordings(seed=0, recordings_per_class=2, duration_s=0.5)
    b = synthetic_recordings(seed=1, recordings_per_class=2, duration_s=0.5)
    for x, y in zip(a.signals, b.signals, strict=True):
        assert not np.array_equal(x, y)


def test_a_recording_does_not_depend_on_how_many_are_made():
    two = synthetic_recordings(seed=5, recordings_per_class=2, duration_s=0.5)
    three = synthetic_recordings(seed=5, recordings_per_class=3, duration_s=0.5)
    for c in range(12):
        for r in range(2):
            np.testing.assert_array_equal(two.signals[2 * c + r], three.signals[3 * c + r])


def test_layout_labels_names_and_units(small):
    assert small.n_recordings == 72
    assert small.n_classes == 12
    assert small.class_names == tuple(tc.name for tc in TEXTURE_CLASSES)
    assert len(set(small.class_names)) == 12
    np.testing.assert_array_equal(small.labels, np.repeat(np.arange(12), 6))
    np.testing.assert_array_equal(np.bincount(small.labels), np.full(12, 6))
    assert small.names[0] == "sine-0.35mm-smooth/rec01"
    assert small.names[-1] == "random-rough/rec06"
    assert (small.fs_hz, small.units, small.name) == (2000.0, "mN", "synthetic")
    assert set(small.lengths) == {4000}
    for signal in small.signals:
        assert signal.dtype == np.float64
        assert np.isfinite(signal).all()
        assert abs(signal.mean()) < 1e-9  # AC-coupled sensor, mean removed
        assert signal.std() > 0


def test_default_size_and_custom_rate():
    rec = synthetic_recordings()
    assert rec.n_recordings == 120
    np.testing.assert_array_equal(rec.durations_s, np.full(120, 5.0))
    slow = synthetic_recordings(recordings_per_class=1, duration_s=1.25, fs_hz=400.0)
    assert set(slow.lengths) == {500}


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
        ({"recordings_per_class": 0}, "recordings_per_class"),
        ({"recordings_per_class": True}, "recordings_per_class"),
        ({"duration_s": 0.0}, "duration_s"),
        ({"duration_s": float("nan")}, "duration_s"),
        ({"fs_hz": -1.0}, "fs_hz"),
        ({"duration_s": 0.0005}, "fewer than 2 samples"),
    ],
)
def test_invalid_arguments_name_the_field(kwargs, field):
    with pytest.raises(DatasetError, match=f"synthetic dataset: .*{field}"):
        synthetic_recordings(**kwargs)


def test_a_recording_does_not_depend_on_the_order_of_generation():
    t = np.arange(2000) / FS
    alone = touch(4, 7, 3, t, FS, material_map(4, 7)).signal
    rec = synthetic_recordings(seed=4, recordings_per_class=4, duration_s=1.0)
    np.testing.assert_array_equal(rec.signals[7 * 4 + 3], alone)


@pytest.fixture(scope="module")
def built_in():
    return synthetic_recordings()


def test_every_pair_of_classes_differs_in_mean_log_envelope_or_spectrum(built_in):
    # For every pair of classes some window's mean log envelope, or some band's mean log power,
    # differs by more than 3 standard errors: class-level differences exist (no accuracy target).
    windows = np.stack([s[:8000].reshape(40, 200) for s in built_in.signals])
    envelope = np.log(np.sqrt((windows**2).mean(-1)))
    freqs, psd = welch(np.stack(built_in.signals), fs=built_in.fs_hz, nperseg=1024, axis=-1)
    features = np.hstack([envelope, np.log10(psd[:, freqs <= 250.0])])
    n = np.bincount(built_in.labels)
    mean = np.stack([features[built_in.labels == c].mean(0) for c in range(12)])
    var = np.stack([features[built_in.labels == c].var(0, ddof=1) for c in range(12)])
    for a in range(12):
        for b in range(a + 1, 12):
            se = np.sqrt(var[a] / n[a] + var[b] / n[b])
            assert np.max(np.abs(mean[a] - mean[b]) / se) > 3, (a, b)


# ---------------------------------------------------------------------------------------------
# The recording chain


def test_recordings_are_band_limited_by_the_sensor_filter(small):
    # Above twice the corner the 8th-order low-pass leaves about 1e-7 of the power.
    freqs, psd = welch(np.stack(small.signals), fs=small.fs_hz, nperseg=1024, axis=-1)
    above = psd[:, freqs > 2 * touch_module.SENSOR_BAND_HZ].sum(-1) / psd.sum(-1)
    assert above.max() < 1e-5


def test_the_sensor_filter_is_left_out_below_its_band():
    # At 150 Hz the sampling limits the band (Nyquist 75 Hz < 85 Hz): no filter, still finite.
    rec = synthetic_recordings(recordings_per_class=1, duration_s=2.0, fs_hz=150.0)
    assert set(rec.lengths) == {300}
    assert all(np.isfinite(s).all() and s.std() > 0 for s in rec.signals)


def test_short_recordings_end_before_sliding():
    rec = synthetic_recordings(recordings_per_class=1, duration_s=0.05)
    assert set(rec.lengths) == {100}
    assert all(np.isfinite(s).all() for s in rec.signals)


# ---------------------------------------------------------------------------------------------
# The measurement quoted in the module docstring


@pytest.fixture(scope="module")
def built_in_statistics(built_in):
    return touch_statistics(built_in)


def _docstring_seed0() -> dict[str, str]:
    """``statistic -> value as printed`` in the "seed 0" column of the docstring's table."""
    section = synthetic.__doc__.split("Measured against real touches")[1]
    rows = re.findall(r"^    ([a-z_]+)\s+(.*)$", section, re.M)
    columns = {name: re.split(r"\s{2,}", rest.strip()) for name, rest in rows}
    return {name: cells[-2] for name, cells in columns.items() if name in REAL_TOUCHES}


def _matches_as_printed(value: float, text: str) -> bool:
    decimals = len(text.split(".")[1])
    return abs(value - float(text)) <= 0.5 * 10.0**-decimals + 1e-12


def _inside_every_real_range(s) -> None:
    assert s.envelope_corr_within >= 0.4
    assert s.envelope_corr_within >= s.envelope_corr_between + 0.15
    assert 2.0 <= s.contact_transient <= 8.0
    # Sliding modulated at 5-20 Hz at a rate that depends on the material, never quiet.
    assert s.modulation_share >= 0.3 and s.modulation_rate_f >= 10.0
    assert s.floor_ratio >= 0.55
    for name, reference in REAL_TOUCHES.items():
        values = getattr(s, f"class_{name}") if name.endswith("_hz") else [getattr(s, name)]
        assert all(reference.holds(float(v)) for v in values), (name, values)


def test_built_in_touches_are_like_real_ones(built_in_statistics):
    _inside_every_real_range(built_in_statistics)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(1, 8))
def test_built_in_touches_are_like_real_ones_at_every_seed_the_docstring_quotes(seed):
    _inside_every_real_range(touch_statistics(synthetic_recordings(seed=seed)))


def test_docstring_seed0_column_matches_the_code(built_in_statistics):
    printed = _docstring_seed0()
    assert set(printed) == set(REAL_TOUCHES)
    for name, text in printed.items():
        if name.endswith("_hz"):
            values = getattr(built_in_statistics, f"class_{name}")
            low, high = text.split("-")
            assert _matches_as_printed(values.min(), low), (name, values.min(), low)
            assert _matches_as_printed(values.max(), high), (name, values.max(), high)
        else:
            value = getattr(built_in_statistics, name)
            assert _matches_as_printed(value, text), (name, value, text)
