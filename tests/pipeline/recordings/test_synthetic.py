"""Tests of pipeline.recordings.synthetic: determinism, layout, the phases of a touch, and the
statistics the module docstring quotes (built-in touches inside the real touches' ranges)."""

from __future__ import annotations

import math
import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import welch

import pipeline.recordings.synthetic as synthetic
from pipeline.errors import DatasetError
from pipeline.recordings.synthetic import (
    TEXTURE_CLASSES,
    material_map,
    ridge_shape,
    synthetic_recordings,
    touch,
)
from pipeline.recordings.touch_statistics import REAL_TOUCHES, touch_statistics

SHAPES = ("sine", "square", "bumps", "sawtooth", "triangle", "none")
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
from pipeline.run.stages import SETUP_STEP, Charge, Stopwatch, load

assert "scipy.signal" not in sys.modules and "scipy.ndimage" not in sys.modules
dataset = DatasetSpec(recordings_per_class=1, duration_s=0.5)
first, later = Stopwatch(None), Stopwatch(None)
load(dataset=dataset, watch=first)
assert "scipy.signal" in sys.modules and "scipy.ndimage" in sys.modules
assert first.paid[Charge.SHARED].get(SETUP_STEP, 0.0) > 0.0, first.paid
assert first.paid[Charge.SHARED]["load"] == first.seconds["load"], first.paid
booked = jit.one_off_seconds()
load(dataset=dataset, watch=later)
assert jit.one_off_seconds() == booked, "a later load booked one-off time"
assert SETUP_STEP not in later.paid[Charge.SHARED], later.paid
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


def test_the_material_sample_is_shared_by_a_class_and_differs_between_classes():
    sample = material_map(0, 2)
    np.testing.assert_array_equal(sample, material_map(0, 2))
    assert sample.std() == pytest.approx(1.0)
    # Independent draws (about 70 correlation lengths per period: |r| well below 0.6).
    assert abs(np.corrcoef(sample, material_map(0, 3))[0, 1]) < 0.6
    assert abs(np.corrcoef(sample, material_map(1, 2))[0, 1]) < 0.6


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


def _docstring_rows(heading: str, columns: int) -> list[list[str]]:
    section = synthetic.__doc__.split(heading)[1]
    return re.findall(r"^ *(\d+)" + r"\s+(\S+)" * columns + " *$", section, re.M)


def test_class_tables_in_docstring_match_the_code():
    rows = _docstring_rows("Classes\n", 8)[:12]
    mechanics = _docstring_rows("Mechanics (", 9)[:12]
    assert len(rows) == len(mechanics) == 12
    for (index, name, shape, *texture), (index2, *mech, period_mm, depth, rate_hz), m in zip(
        rows, mechanics, TEXTURE_CLASSES, strict=True
    ):
        assert int(index) == int(index2) == TEXTURE_CLASSES.index(m)
        assert (name, shape) == (m.name, m.shape)
        period, ridge, rough, corr, density, height = texture
        if shape != "none":
            assert float(period) == m.period_mm
        values = (m.ridge_um, m.roughness_um, m.correlation_mm, m.asperities_per_mm, m.asperity_um)
        assert [float(v) for v in (ridge, rough, corr, density, height)] == list(values)
        expected = (
            m.mu_static,
            m.mu_kinetic,
            m.stiffness_n_per_mm,
            m.relaxation,
            m.stribeck_mm_s,
            m.patchiness,
        )
        assert [float(v) for v in mech] == list(expected)
        assert float(depth) == m.macro_depth
        if m.macro_depth > 0:
            assert float(period_mm) == m.macro_period_mm
            expected_hz = synthetic.SCAN_SPEED_MM_S / m.macro_period_mm
            assert float(rate_hz) == pytest.approx(expected_hz, abs=0.05)
            assert 5.0 <= expected_hz <= 20.0
        else:
            assert period_mm == rate_hz == "--"


def test_materials_are_physical():
    for m in TEXTURE_CLASSES:
        assert 0 < m.mu_kinetic < m.mu_static < 1.5
        assert m.stiffness_n_per_mm > 0 and 0 <= m.relaxation < 1
        assert m.stribeck_mm_s > 0 and m.patchiness >= 0


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
# The phases of a touch


@pytest.fixture(scope="module")
def touches():
    t = np.arange(10_000) / FS
    return [touch(0, c, 1, t, FS, material_map(0, c)) for c in range(12)]


def test_nothing_before_contact_and_no_sliding_before_the_motion(touches):
    t = np.arange(10_000) / FS
    for tc in touches:
        before = t < tc.contact_s
        # The first slip comes after mu_s / (mu_s - mu_k) cycles' worth of loading: 3-4.5
        # cycles of 5-20 Hz, later on a sample's grippy patches.
        assert 0.0 < tc.contact_s < tc.slide_s < tc.break_s < 2.5
        for force in (tc.normal_mn, tc.friction_mn, tc.texture_mn, tc.ring_mn):
            assert np.all(force[before] == 0.0)
        assert np.all(tc.speed_mm_s[t < tc.slide_s] == 0.0)
        assert np.all(tc.friction_mn[t < tc.slide_s] == 0.0)
        # No texture vibration while the fingertip is not moving: the texture force only
        # follows the press, whose shape it keeps.
        pressing = (t >= tc.contact_s + 0.005) & (t < tc.slide_s)
        ratio = tc.texture_mn[pressing] / tc.normal_mn[pressing]
        np.testing.assert_allclose(ratio, ratio[0], rtol=1e-9)


def test_the_press_rises_to_the_target_force_and_relaxes(touches):
    t = np.arange(10_000) / FS
    for tc, m in zip(touches, TEXTURE_CLASSES, strict=True):
        n = tc.normal_mn
        peak = n.max()
        target = 1e3 * synthetic.PRESS_FORCE_N
        assert (1 - synthetic.FORCE_SPREAD) * target * (1 - m.relaxation) < peak
        assert peak <= (1 + synthetic.FORCE_SPREAD) * target
        assert np.all(np.diff(n[(t >= tc.contact_s) & (t < tc.contact_s + 0.05)]) > 0)
        # Relaxation: the force falls towards (1 - r) of its peak once pressed.
        late = n[t >= 3.0]
        assert np.all(np.diff(late) < 0)
        assert late[-1] > (1 - m.relaxation) * peak * 0.99


def test_the_softer_material_presses_more_slowly(touches):
    t = np.arange(10_000) / FS

    def rise_s(tc):
        n = tc.normal_mn
        return t[np.argmax(n >= 0.5 * n.max())] - tc.contact_s

    soft, stiff = touches[11], touches[5]  # k_m 0.6 and 4 N/mm
    assert rise_s(soft) > 1.5 * rise_s(stiff)


def test_static_friction_breaks_away_into_kinetic_friction(touches):
    t = np.arange(10_000) / FS
    for tc, m in zip(touches, TEXTURE_CLASSES, strict=True):
        f, n = tc.friction_mn, tc.normal_mn
        broke = int(np.searchsorted(t, tc.break_s))
        # Before the first slip the shear load grows with the motion up to static friction.
        loading = f[(t >= tc.slide_s) & (t < tc.break_s)]
        assert np.all(np.diff(loading) >= 0)
        # The breakaway is a drop from static friction to below kinetic friction.
        assert f[broke] < f[broke - 1]
        assert f[broke - 1] / n[broke - 1] > f[broke] / n[broke]
        # Sliding: the force stays about mu_k N (times the sample's local factor).
        mu = f[t > 2.0] / n[t > 2.0]
        assert 0.2 * m.mu_kinetic < np.median(mu) < 5.0 * m.mu_kinetic


def test_stick_slip_cycles_at_5_to_20_hz_faster_where_the_friction_drop_is_small(touches):
    t = np.arange(10_000) / FS
    rates = np.array([np.median(tc.slip_rate_hz[(t >= 1.0) & (t < 4.0)]) for tc in touches])
    assert np.all((rates > 3.0) & (rates < 30.0)), rates
    assert 5.0 <= np.median(rates) <= 20.0
    # f_ss = k_t v / D: the bumps (mu_s - mu_k = 0.10) cycle faster than the grits (0.30, 0.20)
    # and the deep sawtooth (0.30).
    assert min(rates[6], rates[7]) > max(rates[5], rates[9], rates[10])


def test_the_pad_creeps_while_it_sticks_and_keeps_pace_with_the_drive(touches):
    t = np.arange(10_000) / FS
    loss = synthetic.STICK_SPEED_LOSS
    for tc in touches:
        sliding = t >= tc.break_s
        pad, drive = tc.pad_speed_mm_s[sliding], tc.speed_mm_s[sliding]
        # Never stops: at least (1 - a) of the drive's speed, more in each slip.
        assert np.all(pad >= (1 - loss) * drive - 1e-12)
        assert pad.max() > (1 + loss) * drive.max() * 0.9
        # Over the sliding part the pad covers what the drive covers (whole cycles but one).
        assert pad.sum() == pytest.approx(drive.sum(), rel=0.02)
        assert np.all(tc.pad_speed_mm_s[t < tc.slide_s] == 0.0)


@pytest.mark.parametrize("index", [0, 4, 5])
def test_macro_texture_modulates_the_texture_at_the_scan_speed_over_its_period(index):
    # The texture force's level (5 ms RMS) carries the macro rate v / Lambda.
    t = np.arange(10_000) / FS
    m = TEXTURE_CLASSES[index]
    spectra = []
    for r in range(4):
        force = touch(1, index, r, t, FS, material_map(1, index)).texture_mn[2000:8000]
        level = np.log(np.sqrt(((force - force.mean()) ** 2).reshape(-1, 10).mean(axis=1)))
        spectra.append(np.abs(np.fft.rfft(level - level.mean())) ** 2)
    freqs = np.fft.rfftfreq(600, d=10 / FS)
    band = (freqs >= 4.0) & (freqs <= 25.0)
    peak = freqs[band][np.argmax(np.mean(spectra, axis=0)[band])]
    expected = synthetic.SCAN_SPEED_MM_S / m.macro_period_mm
    assert abs(peak - expected) < 0.15 * expected, (peak, expected)


def test_the_sliding_speed_reaches_the_nominal_speed(touches):
    t = np.arange(10_000) / FS
    for tc in touches:
        late = tc.speed_mm_s[t > tc.slide_s + 6 * synthetic.ACCEL_S]
        assert abs(np.median(late) / synthetic.SCAN_SPEED_MM_S - 1) < 0.15
        assert np.all(tc.speed_mm_s >= 0)


def test_the_contact_transient_stands_out_of_the_sliding_level(touches):
    ratios = [
        np.sqrt(np.mean(tc.signal[:500] ** 2) / np.mean(tc.signal[2000:8000] ** 2))
        for tc in touches
    ]
    assert np.median(ratios) > 2.0


@pytest.mark.parametrize("index", [0, 5, 6])
def test_ridge_period_shows_in_the_sliding_spectrum(index):
    # The pad passes a period P at its own speed: creeping at (1 - a) of the drive's ~20 mm/s
    # for most of each stick-slip cycle, faster in the slips, which puts the peak between
    # (1 - a) 20 / P and 20 / P Hz.
    t = np.arange(10_000) / FS
    texture = TEXTURE_CLASSES[index]
    forces = [touch(2, index, r, t, FS, material_map(2, index)).texture_mn for r in range(4)]
    freqs, psd = welch(np.stack(forces)[:, 2000:], fs=FS, nperseg=2048, axis=-1)
    drive_hz = synthetic.SCAN_SPEED_MM_S / texture.period_mm
    creep_hz = (1 - synthetic.STICK_SPEED_LOSS) * drive_hz
    # Above the slow modulation of the texture's level (stick-slip, macro texture: <= 20 Hz).
    band = (freqs > 0.6 * creep_hz) & (freqs < 200)
    peak = freqs[band][np.argmax(psd.mean(0)[band])]
    assert 0.85 * creep_hz < peak < 1.15 * drive_hz, (peak, creep_hz, drive_hz)


# ---------------------------------------------------------------------------------------------
# The recording chain


def test_recordings_are_band_limited_by_the_sensor_filter(small):
    # Above twice the corner the 8th-order low-pass leaves about 1e-7 of the power.
    freqs, psd = welch(np.stack(small.signals), fs=small.fs_hz, nperseg=1024, axis=-1)
    above = psd[:, freqs > 2 * synthetic.SENSOR_BAND_HZ].sum(-1) / psd.sum(-1)
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
