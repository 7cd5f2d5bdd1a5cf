"""Tests of pipeline.synthetic: determinism, layout and class-level structure."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import welch

import pipeline.synthetic as synthetic
from pipeline.errors import DatasetError
from pipeline.synthetic import TEXTURE_CLASSES, ridge_shape, synthetic_recordings

SHAPES = ("sine", "square", "bumps", "sawtooth", "triangle", "none")


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
    assert small.names[0] == "sine-1.00mm-smooth/rec01"
    assert small.names[-1] == "random-rough/rec06"
    assert (small.fs_hz, small.units, small.name) == (2000.0, "a.u.", "synthetic")
    assert set(small.lengths) == {4000}
    for signal in small.signals:
        assert signal.dtype == np.float64
        assert np.isfinite(signal).all()
        assert abs(signal.mean()) < 1e-12  # AC-coupled sensor
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


def _log_spectra(rec, max_hz=250.0):
    freqs, psd = welch(np.stack(rec.signals), fs=rec.fs_hz, nperseg=512, axis=-1)
    keep = freqs <= max_hz
    return freqs[keep], np.log10(psd[:, keep])


def test_every_pair_of_classes_differs_in_mean_spectrum(small):
    # For every pair of classes some frequency band's mean log-power differs by more than
    # 3 standard errors: class-level differences exist (this is not an accuracy target).
    _, spectra = _log_spectra(small)
    n = np.bincount(small.labels)
    mean = np.stack([spectra[small.labels == c].mean(0) for c in range(12)])
    var = np.stack([spectra[small.labels == c].var(0, ddof=1) for c in range(12)])
    for a in range(12):
        for b in range(a + 1, 12):
            se = np.sqrt(var[a] / n[a] + var[b] / n[b])
            assert np.max(np.abs(mean[a] - mean[b]) / se) > 3, (a, b)


@pytest.mark.parametrize("index", [0, 3, 4, 5])
def test_ridge_period_sets_the_dominant_frequency(small, index):
    # Scanning a period P at ~20 mm/s gives a fundamental near 20 / P Hz.
    texture = TEXTURE_CLASSES[index]
    signals = np.stack([s for s, c in zip(small.signals, small.labels, strict=True) if c == index])
    freqs, psd = welch(signals, fs=small.fs_hz, nperseg=2048, axis=-1)
    peak = freqs[np.argmax(psd.mean(0))]
    expected = synthetic.SCAN_SPEED_MM_S / texture.period_mm
    assert abs(peak - expected) < 0.1 * expected


def test_class_table_in_docstring_matches_the_code():
    rows = re.findall(
        r"^(\d+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)$", synthetic.__doc__, re.M
    )
    assert len(rows) == 12
    for (index, name, shape, period, ridge, rough, corr), texture in zip(
        rows, TEXTURE_CLASSES, strict=True
    ):
        assert (name, shape) == (texture.name, texture.shape)
        if shape != "none":
            assert float(period) == texture.period_mm
        assert float(ridge) == texture.ridge_um
        assert float(rough) == texture.roughness_um
        assert float(corr) == texture.correlation_mm
        assert int(index) == TEXTURE_CLASSES.index(texture)


@settings(max_examples=50, deadline=None)
@given(
    shape=st.sampled_from(SHAPES),
    phase=st.floats(-1e3, 1e3, allow_nan=False),
)
def test_ridge_shapes_have_period_one_and_unit_range(shape, phase):
    value = ridge_shape(shape, np.array([phase, phase + 1.0]))
    assert np.all(np.abs(value) <= 1.0 + 1e-12)
    np.testing.assert_allclose(value[0], value[1], atol=1e-9)


def test_unknown_ridge_shape():
    with pytest.raises(ValueError, match="unknown ridge shape"):
        ridge_shape("zigzag", np.zeros(3))
