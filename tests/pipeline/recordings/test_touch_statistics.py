"""Touch statistics on hand-made recordings whose answers are known."""

import math

import numpy as np
import pytest

from pipeline.recordings.sources import Recordings
from pipeline.recordings.touch_statistics import REAL_TOUCHES, touch_statistics

FS = 1000.0


def _dataset(signals, labels, name="made"):
    n_classes = max(labels) + 1
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=tuple(f"c{c}" for c in range(n_classes)),
        fs_hz=FS,
        names=tuple(f"r{i}" for i in range(len(signals))),
        units="a.u.",
        name=name,
    )


def _touch(rng, envelope, seconds=5.0):
    t = np.arange(int(seconds * FS)) / FS
    return envelope(t) * rng.standard_normal(t.size)


def test_a_time_course_repeated_within_classes_correlates_within_not_between():
    rng = np.random.default_rng(0)
    courses = [
        lambda t: 1 + 0.8 * np.sin(2 * np.pi * 0.5 * t),
        lambda t: 1 + 0.8 * np.sin(2 * np.pi * 0.7 * t + 1.0),
        lambda t: 1 + 0.8 * np.cos(2 * np.pi * 0.3 * t + 2.0),
    ]
    signals, labels = [], []
    for c, course in enumerate(courses):
        for _ in range(6):
            signals.append(_touch(rng, course))
            labels.append(c)
    stats = touch_statistics(_dataset(signals, labels))
    assert stats.n_windows == 40
    assert stats.envelope_corr_within > 0.8
    assert stats.envelope_corr_between < stats.envelope_corr_within - 0.3


def test_stationary_noise_has_no_envelope_structure_and_no_transient():
    rng = np.random.default_rng(1)
    signals = [rng.standard_normal(int(5 * FS)) for _ in range(12)]
    stats = touch_statistics(_dataset(signals, [i % 3 for i in range(12)]))
    assert abs(stats.envelope_corr_within) < 0.15
    assert abs(stats.envelope_corr_between) < 0.15
    assert stats.contact_transient == pytest.approx(1.0, abs=0.15)
    assert stats.slow_decay == pytest.approx(1.0, abs=0.1)


def test_contact_transient_and_slow_decay_of_a_piecewise_square_wave():
    # +-a square waves: window RMS equals the amplitude exactly.
    t = np.arange(int(5 * FS)) / FS
    sign = np.where(np.arange(t.size) % 2 == 0, 1.0, -1.0)
    amplitude = np.select([t < 0.25, t < 3.0], [4.0, 1.0], 0.5)
    stats = touch_statistics(_dataset([amplitude * sign, 2 * amplitude * sign], [0, 0]))
    assert stats.contact_transient == pytest.approx(4.0, rel=1e-9)
    # Windows from 1 s: 20 at 1.0 and 20 at 0.5 in the first 4 s; median 0.75.
    assert stats.slow_decay == pytest.approx(0.5, rel=1e-9)
    assert stats.level_spread_within == pytest.approx(math.sqrt(2) / 3, rel=1e-6)


def test_short_recordings_window_what_they_hold_and_have_no_slow_decay():
    rng = np.random.default_rng(2)
    signals = [rng.standard_normal(int(1.95 * FS)) for _ in range(4)]
    stats = touch_statistics(_dataset(signals, [0, 0, 1, 1]))
    assert stats.n_windows == 19
    assert math.isnan(stats.slow_decay)
    assert math.isfinite(stats.contact_transient)


def test_class_levels_and_ratio():
    rng = np.random.default_rng(3)
    signals = [s * rng.standard_normal(int(2 * FS)) for s in (1, 1, 3, 3)]
    stats = touch_statistics(_dataset(signals, [0, 0, 1, 1]))
    assert stats.loudest_quietest_ratio == pytest.approx(3.0, rel=0.05)
    assert stats.class_rms.shape == (2,)
    assert stats.to_dict()["class_rms"] == [float(v) for v in stats.class_rms]


def test_a_recording_shorter_than_a_window_is_refused():
    with pytest.raises(ValueError, match="shorter than one"):
        touch_statistics(_dataset([np.ones(50), np.arange(50.0)], [0, 0]))


def test_reference_ranges_judge_values():
    transient = REAL_TOUCHES["contact_transient"]
    assert transient.holds(4.1) and not transient.holds(1.1) and not transient.holds(math.nan)


def test_stationary_noise_is_not_modulated_at_5_to_20_hz_and_never_goes_quiet():
    rng = np.random.default_rng(5)
    signals = [rng.standard_normal(int(5 * FS)) for _ in range(12)]
    stats = touch_statistics(_dataset(signals, [i % 3 for i in range(12)]))
    # 1 kHz: 5 ms blocks of 5 samples, envelope at 200 Hz; a flat spectrum puts 15 of the
    # 99.5 Hz above 0.5 Hz in the band.
    assert stats.modulation_share == pytest.approx(15 / 99.5, abs=0.04)
    assert not REAL_TOUCHES["modulation_share"].holds(stats.modulation_share)
    assert stats.floor_ratio > 0.85
    assert not REAL_TOUCHES["floor_ratio"].holds(stats.floor_ratio)


def _modulated(rng, rate_hz, seconds=5.0, depth=0.8):
    """Noise whose level follows 1 + depth sin(2 pi rate t): a 5-20 Hz modulated touch."""
    t = np.arange(int(seconds * FS)) / FS
    phase = rng.uniform(0, 2 * np.pi)
    return (1 + depth * np.sin(2 * np.pi * rate_hz * t + phase)) * rng.standard_normal(t.size)


def test_a_level_modulated_at_a_class_rate_gives_a_large_share_and_a_large_f():
    rng = np.random.default_rng(6)
    rates = (7.0, 11.0, 16.0)
    signals = [_modulated(rng, rates[i % 3] * rng.uniform(0.97, 1.03)) for i in range(18)]
    labels = [i % 3 for i in range(18)]
    stats = touch_statistics(_dataset(signals, labels))
    assert stats.modulation_share > 0.6
    assert stats.class_modulation_share.shape == (3,)
    assert stats.modulation_rate_f > 100
    # The same modulation in every class: the rate tells the classes apart no more than chance.
    same = [_modulated(rng, 11.0 * rng.uniform(0.97, 1.03)) for _ in range(18)]
    assert touch_statistics(_dataset(same, labels)).modulation_rate_f < 5


def test_floor_ratio_of_a_touch_with_quiet_windows():
    # +-a square waves: window RMS equals the amplitude exactly. 40 windows in the first 4 s,
    # 8 of them at 0.25: the 10th percentile is 0.25, the median 1.
    t = np.arange(int(5 * FS)) / FS
    sign = np.where(np.arange(t.size) % 2 == 0, 1.0, -1.0)
    quiet = (t >= 2.0) & (t < 2.8)
    stats = touch_statistics(_dataset([np.where(quiet, 0.25, 1.0) * sign], [0]))
    assert stats.floor_ratio == pytest.approx(0.25, rel=1e-9)
    assert stats.class_floor_ratio == pytest.approx([0.25], rel=1e-9)


def test_modulation_needs_a_second_of_sliding_and_5_ms_blocks_of_several_samples():
    rng = np.random.default_rng(7)
    short = [rng.standard_normal(int(1.95 * FS)) for _ in range(4)]
    stats = touch_statistics(_dataset(short, [0, 0, 1, 1]))
    assert math.isnan(stats.modulation_share) and math.isnan(stats.modulation_rate_f)
    assert math.isfinite(stats.floor_ratio)
    slow = Recordings(
        signals=tuple(rng.standard_normal(1000) for _ in range(4)),
        labels=np.array([0, 0, 1, 1]),
        class_names=("c0", "c1"),
        fs_hz=200.0,
        names=tuple(f"r{i}" for i in range(4)),
        units="a.u.",
        name="slow",
    )
    assert math.isnan(touch_statistics(slow).modulation_share)
