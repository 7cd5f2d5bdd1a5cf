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
