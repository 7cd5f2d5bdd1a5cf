"""One synthetic touch: its phases (contact, press, breakaway, stick-slip, sliding), its texture
and its asperities."""

import math

import numpy as np
import pytest
from scipy.signal import welch

import pipeline.recordings.touch as touch_module
from pipeline.recordings.materials import TEXTURE_CLASSES, material_map
from pipeline.recordings.touch import touch

FS = 2000.0


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
        target = 1e3 * touch_module.PRESS_FORCE_N
        assert (1 - touch_module.FORCE_SPREAD) * target * (1 - m.relaxation) < peak
        assert peak <= (1 + touch_module.FORCE_SPREAD) * target
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
    loss = touch_module.STICK_SPEED_LOSS
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
    expected = touch_module.SCAN_SPEED_MM_S / m.macro_period_mm
    assert abs(peak - expected) < 0.15 * expected, (peak, expected)


def test_the_sliding_speed_reaches_the_nominal_speed(touches):
    t = np.arange(10_000) / FS
    for tc in touches:
        late = tc.speed_mm_s[t > tc.slide_s + 6 * touch_module.ACCEL_S]
        assert abs(np.median(late) / touch_module.SCAN_SPEED_MM_S - 1) < 0.15
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
    drive_hz = touch_module.SCAN_SPEED_MM_S / texture.period_mm
    creep_hz = (1 - touch_module.STICK_SPEED_LOSS) * drive_hz
    # Above the slow modulation of the texture's level (stick-slip, macro texture: <= 20 Hz).
    band = (freqs > 0.6 * creep_hz) & (freqs < 200)
    peak = freqs[band][np.argmax(psd.mean(0)[band])]
    assert 0.85 * creep_hz < peak < 1.15 * drive_hz, (peak, creep_hz, drive_hz)


def test_asperities_are_gaussian_bumps_of_the_drawn_heights():
    grid = 10.0 + touch_module.GRID_MM * np.arange(20_001)  # 100 mm
    profile = touch_module._asperities(np.random.default_rng(7), grid, 0.2, 5.0)
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
    area = profile.sum() * touch_module.GRID_MM
    expected = heights.sum() * math.sqrt(2 * math.pi) * touch_module.CONTACT_SIGMA_MM
    assert area == pytest.approx(expected, rel=1e-5)
    assert area < expected
    # The tallest bump peaks at its drawn height (its centre is within half a cell of a node).
    tallest = int(np.argmax(heights))
    node = int(np.argmin(np.abs(grid - centres[tallest])))
    offset = (grid[node] - centres[tallest]) / touch_module.CONTACT_SIGMA_MM
    assert profile[node] >= heights[tallest] * math.exp(-0.5 * offset**2) - 1e-12
