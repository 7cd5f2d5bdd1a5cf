"""Tests of pipeline.synthetic: determinism, layout, class-level structure, and the statistics
the module docstring quotes (built-in classes inside VibTac-12's ranges)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import welch

import pipeline.synthetic as synthetic
from pipeline.errors import DatasetError
from pipeline.frontend import fit_front_end
from pipeline.recordings import Recordings, load_recordings
from pipeline.scene import DatasetSpec
from pipeline.synthetic import (
    TEXTURE_CLASSES,
    class_statistics,
    ridge_shape,
    synthetic_recordings,
)

SHAPES = ("sine", "square", "bumps", "sawtooth", "triangle", "none")
REAL_VIBTAC12 = Path(__file__).resolve().parents[3] / "shared/datasets/vibtac12"


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
    assert small.names[0] == "sine-0.35mm-smooth/rec01"
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


@pytest.mark.parametrize("index", [0, 3, 4, 5, 6])
def test_ridge_period_sets_the_dominant_frequency(small, index):
    # Scanning a period P at ~20 mm/s gives a fundamental near 20 / P Hz.
    texture = TEXTURE_CLASSES[index]
    signals = np.stack([s for s, c in zip(small.signals, small.labels, strict=True) if c == index])
    freqs, psd = welch(signals, fs=small.fs_hz, nperseg=2048, axis=-1)
    peak = freqs[np.argmax(psd.mean(0))]
    expected = synthetic.SCAN_SPEED_MM_S / texture.period_mm
    assert abs(peak - expected) < 0.1 * expected


def test_class_table_in_docstring_matches_the_code():
    rows = re.findall(r"^(\d+)" + r"\s+(\S+)" * 8 + "$", synthetic.__doc__, re.M)
    assert len(rows) == 12
    for (index, name, shape, period, ridge, rough, corr, density, height), texture in zip(
        rows, TEXTURE_CLASSES, strict=True
    ):
        assert (name, shape) == (texture.name, texture.shape)
        if shape != "none":
            assert float(period) == texture.period_mm
        assert float(ridge) == texture.ridge_um
        assert float(rough) == texture.roughness_um
        assert float(corr) == texture.correlation_mm
        assert float(density) == texture.asperities_per_mm
        assert float(height) == texture.asperity_um
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


# ---------------------------------------------------------------------------------------------
# The recording chain


def test_recordings_are_band_limited_by_the_sensor_filter(small):
    # Above twice the corner the 8th-order low-pass leaves about 1e-7 of the power; without it
    # (sensor noise, asperity edges) every recording here would keep 1 % to 7 %.
    freqs, psd = welch(np.stack(small.signals), fs=small.fs_hz, nperseg=1024, axis=-1)
    above = psd[:, freqs > 2 * synthetic.SENSOR_BAND_HZ].sum(-1) / psd.sum(-1)
    assert above.max() < 1e-5


def test_the_sensor_filter_is_left_out_below_its_band():
    # At 150 Hz the sampling limits the band (Nyquist 75 Hz < 85 Hz): no filter, still finite.
    rec = synthetic_recordings(recordings_per_class=1, duration_s=2.0, fs_hz=150.0)
    assert set(rec.lengths) == {300}
    assert all(np.isfinite(s).all() and s.std() > 0 for s in rec.signals)


def test_asperities_are_gaussian_bumps_of_the_drawn_heights():
    grid = 10.0 + synthetic.GRID_MM * np.arange(20_001)  # 100 mm
    profile = synthetic._asperities(np.random.default_rng(7), grid, 0.2, 5.0)
    # Replay the draws: count, centres, heights.
    replay = np.random.default_rng(7)
    count = int(replay.poisson(0.2 * (grid[-1] - grid[0])))
    centres = grid[0] + (grid[-1] - grid[0]) * replay.random(count)
    heights = replay.exponential(5.0, count)
    assert count > 10
    assert profile.min() >= 0.0
    # Every bump's area is H sqrt(2 pi) sigma (all centres lie well inside this grid), less the
    # tails beyond the +-4.5 sigma the bumps are cut at (7e-6 of it).
    assert (np.diff(np.sort(centres)).min() > 0) and (centres.min() - grid[0] > 0.2)
    assert grid[-1] - centres.max() > 0.2
    area = profile.sum() * synthetic.GRID_MM
    expected = heights.sum() * math.sqrt(2 * math.pi) * synthetic.CONTACT_SIGMA_MM
    assert area == pytest.approx(expected, rel=1e-5)
    assert area < expected
    # The tallest bump peaks at its drawn height (its centre is within half a cell of a node).
    tallest = int(np.argmax(heights))
    node = int(np.argmin(np.abs(grid - centres[tallest])))
    offset = (grid[node] - centres[tallest]) / synthetic.CONTACT_SIGMA_MM
    assert profile[node] >= heights[tallest] * math.exp(-0.5 * offset**2) - 1e-12


# ---------------------------------------------------------------------------------------------
# class_statistics


def _recordings(signals, labels, fs_hz=1000.0, n_classes=None):
    n_classes = max(labels) + 1 if n_classes is None else n_classes
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=tuple(f"c{i}" for i in range(n_classes)),
        fs_hz=fs_hz,
        names=tuple(f"r{i}" for i in range(len(signals))),
        units="N",
        name="handmade",
    )


def test_class_statistics_of_known_signals():
    t = np.arange(1000) / 1000.0  # whole periods of 50 Hz and 150 Hz
    tone = np.sin(2 * np.pi * 50 * t)
    two_tones = 2 * np.sin(2 * np.pi * 50 * t) + np.sin(2 * np.pi * 150 * t)
    square = np.where(np.arange(1000) % 20 < 10, 3.0, -3.0)
    rec = _recordings([tone + 7.0, 2 * tone, two_tones, square], [0, 0, 1, 2])
    stats = class_statistics(rec)
    gain = fit_front_end(rec, 1.0).gain_v_per_unit

    assert stats.class_names == ("c0", "c1", "c2")
    assert (stats.fs_hz, stats.units, stats.dataset) == (1000.0, "N", "handmade")
    np.testing.assert_array_equal(stats.n_recordings, [2, 1, 1])
    assert stats.gain_v_per_unit == gain
    # RMS of the mean-removed signal: a sine's is A / sqrt(2), whatever its offset.
    np.testing.assert_allclose(stats.rms, [1.5 / math.sqrt(2), math.sqrt(2.5), 3.0], rtol=1e-12)
    np.testing.assert_allclose(stats.rms_v, gain * stats.rms, rtol=1e-15)
    # Amplitudes 1 and 2: std(ddof=1) / mean = sqrt(2) |a - b| / (a + b) = sqrt(2) / 3.
    assert stats.rms_cv[0] == pytest.approx(math.sqrt(2) / 3, rel=1e-12)
    assert np.isnan(stats.rms_cv[1:]).all()  # one recording
    assert stats.mad_v[2] == pytest.approx(3.0 * gain, rel=1e-12)
    # Power-weighted: (4 * 50 + 1 * 150) / 5 = 70 Hz; sqrt((4 * 20^2 + 80^2) / 5) = 40 Hz.
    assert stats.centroid_hz[0] == pytest.approx(50.0, rel=1e-9)
    assert stats.bandwidth_hz[0] == pytest.approx(0.0, abs=1e-4)
    assert stats.centroid_hz[1] == pytest.approx(70.0, rel=1e-9)
    assert stats.bandwidth_hz[1] == pytest.approx(40.0, rel=1e-9)
    np.testing.assert_allclose(stats.centroid_nyquist[:2], [0.1, 0.14], rtol=1e-9)
    assert stats.bandwidth_nyquist[1] == pytest.approx(0.08, rel=1e-9)
    # Excess kurtosis: -1.5 for a sine, -2 for a symmetric square wave.
    assert stats.excess_kurtosis[0] == pytest.approx(-1.5, abs=1e-9)
    assert stats.excess_kurtosis[2] == pytest.approx(-2.0, abs=1e-12)


def test_class_statistics_dataset_summaries():
    t = np.arange(400) / 400.0
    tone = np.sin(2 * np.pi * 20 * t)
    rec = _recordings([1 * tone, 3 * tone, 2 * tone, 4 * tone], [0, 0, 1, 1], fs_hz=400.0)
    stats = class_statistics(rec, full_scale_v=2.0)
    gain = fit_front_end(rec, 2.0).gain_v_per_unit
    assert stats.full_scale_v == 2.0
    level = np.array([2.0, 3.0]) / math.sqrt(2) * gain  # mean RMS per class
    np.testing.assert_allclose(stats.rms_v, level, rtol=1e-12)
    assert stats.across_class_ratio == pytest.approx(1.5, rel=1e-12)
    assert stats.across_class_cv == pytest.approx((1 / math.sqrt(2)) / 2.5, rel=1e-12)
    assert stats.median_rms_v == pytest.approx(level.mean(), rel=1e-12)
    cvs = [math.sqrt(2) * 2 / 4, math.sqrt(2) * 2 / 6]
    assert stats.median_rms_cv == pytest.approx(np.mean(cvs), rel=1e-12)


def test_class_statistics_constant_recording_and_errors():
    t = np.arange(200) / 200.0
    rec = _recordings([np.full(200, 4.0), np.sin(2 * np.pi * 10 * t)], [0, 1])
    stats = class_statistics(rec)
    assert stats.rms[0] == 0.0
    assert np.isnan([stats.centroid_hz[0], stats.bandwidth_hz[0], stats.excess_kurtosis[0]]).all()
    assert np.isfinite([stats.centroid_hz[1], stats.excess_kurtosis[1]]).all()
    with pytest.raises(ValueError, match=r"classes without recordings: \['c2'\]"):
        class_statistics(_recordings([t, t], [0, 1], n_classes=3))
    with pytest.raises(ValueError, match="full_scale_v"):
        class_statistics(rec, full_scale_v=0.0)


# ---------------------------------------------------------------------------------------------
# The measurement quoted in the module docstring

PER_DATASET = ("across_class_cv", "across_class_ratio", "median_rms_v", "median_rms_cv")
NOT_MATCHED = ("centroid_nyquist", "bandwidth_nyquist")


def _docstring_table() -> dict[str, list[str]]:
    """``statistic -> [real min, real max, before min, before max, min, max]`` as printed."""
    section = synthetic.__doc__.split("Measured against real recordings")[1]
    rows = re.findall(r"^    ([a-z_]+)" + r"\s+(-?\d+\.\d+)" * 6 + r"$", section, re.M)
    return {name: list(values) for name, *values in rows}


def _matches_as_printed(value: float, text: str) -> bool:
    decimals = len(text.split(".")[1])
    return abs(value - float(text)) <= 0.5 * 10.0**-decimals + 1e-12


def _extremes(stats, name: str) -> tuple[float, float]:
    value = getattr(stats, name)
    return (float(value), float(value)) if name in PER_DATASET else (value.min(), value.max())


@pytest.fixture(scope="module")
def built_in_statistics():
    return class_statistics(synthetic_recordings())


def test_docstring_table_lists_every_statistic():
    table = _docstring_table()
    per_class = {"rms_v", "rms_cv", "mad_v", "centroid_hz", "bandwidth_hz", "excess_kurtosis"}
    assert set(table) == per_class | set(PER_DATASET) | set(NOT_MATCHED)


def test_built_in_statistics_fall_inside_the_measured_ranges(built_in_statistics):
    for name, (real_min, real_max, *_) in _docstring_table().items():
        if name in NOT_MATCHED:
            continue
        low, high = _extremes(built_in_statistics, name)
        assert float(real_min) <= low and high <= float(real_max), (name, low, high)


def test_docstring_built_in_column_matches_the_code(built_in_statistics):
    for name, (*_, printed_min, printed_max) in _docstring_table().items():
        low, high = _extremes(built_in_statistics, name)
        assert _matches_as_printed(low, printed_min), (name, low, printed_min)
        assert _matches_as_printed(high, printed_max), (name, high, printed_max)


@pytest.mark.skipif(
    not REAL_VIBTAC12.is_dir(), reason=f"the VibTac-12 copy is absent ({REAL_VIBTAC12})"
)
def test_docstring_vibtac12_column_matches_the_data():
    def axis(name):
        spec = DatasetSpec(
            kind="vibtac12", path=str(REAL_VIBTAC12), axis=name, segments=10, sampling_rate_hz=200.0
        )
        return class_statistics(load_recordings(spec))

    axes = {name: axis(name) for name in ("z", "x", "y")}
    for name, (printed_min, printed_max, *_) in _docstring_table().items():
        if name in PER_DATASET:
            values = [getattr(stats, name) for stats in axes.values()]
            low, high = min(values), max(values)
        else:
            low, high = _extremes(axes["z"], name)
        assert _matches_as_printed(low, printed_min), (name, low, printed_min)
        assert _matches_as_printed(high, printed_max), (name, high, printed_max)
    quoted = re.search(
        r"z axis alone\s+gives ([\d.]+), ([\d.]+), ([\d.]+) and ([\d.]+)", synthetic.__doc__
    )
    for name, printed in zip(PER_DATASET, quoted.groups(), strict=True):
        assert _matches_as_printed(getattr(axes["z"], name), printed), name
