"""describe_dataset and folder_layout on hand-made datasets whose answers are known."""

import json
import math
import re
import tomllib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.recordings.describe import (
    MAX_NAME_CHARS,
    SEGMENT_MARGIN,
    Verdict,
    describe_dataset,
    folder_layout,
)
from pipeline.recordings.sources import Recordings, load_vibtac12
from pipeline.recordings.touch_statistics import REAL_TOUCHES

FS = 1000.0
SEGMENTS = "are these segments of one recording?"
NO_TRANSIENT = "no contact transient"


def _dataset(signals, labels, class_names=None, names=None, name="made", units="a.u."):
    n_classes = max(labels) + 1
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=tuple(class_names or (f"c{c}" for c in range(n_classes))),
        fs_hz=FS,
        names=tuple(names or (f"c{labels[i]}/r{i}" for i in range(len(signals)))),
        units=units,
        name=name,
    )


def _touches(per_class=10, seconds=5.0, seed=0):
    """Three classes whose touches share a class-specific time course: a contact transient
    (4x for 0.25 s) and then a sliding level that wanders the class's way."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    courses = [
        1 + 0.6 * np.sin(2 * np.pi * 0.5 * t),
        1 + 0.6 * np.sin(2 * np.pi * 0.7 * t + 1.0),
        1 + 0.6 * np.cos(2 * np.pi * 0.3 * t + 2.0),
    ]
    signals, labels = [], []
    for c, course in enumerate(courses):
        envelope = np.where(t < 0.25, 4.0, course)
        for _ in range(per_class):
            signals.append(envelope * rng.standard_normal(t.size))
            labels.append(c)
    return signals, labels


def _segments(per_class=10, seconds=2.0, seed=1):
    """Three classes, each one long stationary recording (its own level) cut into segments."""
    rng = np.random.default_rng(seed)
    n = int(seconds * FS)
    signals, labels = [], []
    for c, level in enumerate((1.0, 2.0, 3.0)):
        long = level * rng.standard_normal(n * per_class)
        signals += [long[i * n : (i + 1) * n] for i in range(per_class)]
        labels += [c] * per_class
    return signals, labels


def test_touches_with_a_class_time_course_give_facts_and_no_warning():
    signals, labels = _touches()
    signals[0] = np.concatenate([signals[0], np.zeros(500)])  # one recording 5.5 s long
    description = describe_dataset(_dataset(signals, labels))
    facts = description.facts
    assert facts.class_names == ("c0", "c1", "c2")
    assert facts.recordings_per_class == (10, 10, 10)
    assert facts.n_recordings == 30 and facts.fs_hz == FS and facts.units == "a.u."
    assert (facts.duration_min_s, facts.duration_median_s, facts.duration_max_s) == (5.0, 5.0, 5.5)
    assert (facts.window_s, facts.n_windows, facts.max_windows, facts.folds) == (0.1, 40, 40, 10)
    stats = description.statistics
    assert stats.envelope_corr_within - stats.envelope_corr_between > SEGMENT_MARGIN
    assert description.warnings == ()
    verdicts = {c.name: c.verdict for c in description.comparisons}
    assert set(verdicts) == set(REAL_TOUCHES)
    assert verdicts["envelope_corr_within"] is Verdict.INSIDE
    assert verdicts["contact_transient"] is Verdict.INSIDE


def test_segments_of_one_stationary_recording_are_called_so():
    description = describe_dataset(_dataset(*_segments()))
    assert any(w.endswith(SEGMENTS) for w in description.warnings), description.warnings
    assert any(w.startswith(NO_TRANSIENT) for w in description.warnings)
    verdicts = {c.name: c.verdict for c in description.comparisons}
    assert verdicts["envelope_corr_within"] is Verdict.OUTSIDE
    # 2 s recordings: 20 windows, no slow decay.
    assert description.facts.n_windows == 20
    assert verdicts["slow_decay"] is Verdict.UNDEFINED
    short = [w for w in description.warnings if "shorter than the paper's 40 windows" in w]
    assert short and "holds 20" in short[0] and "slow decay is not measured" in short[0]


def test_the_segment_warning_uses_the_margin():
    # A class-specific time course, diluted until within-class exceeds between by less than
    # the margin: same data, only the course's depth changes.
    rng = np.random.default_rng(4)
    t = np.arange(int(4 * FS)) / FS
    noise = [rng.standard_normal(t.size) for _ in range(30)]
    labels = [i // 10 for i in range(30)]

    def warned(depth):
        courses = [1 + depth * np.sin(2 * np.pi * f * t) for f in (0.5, 0.7, 0.3)]
        signals = [courses[c] * x for c, x in zip(labels, noise, strict=True)]
        d = describe_dataset(_dataset(signals, labels))
        gap = d.statistics.envelope_corr_within - d.statistics.envelope_corr_between
        return gap, any(w.endswith(SEGMENTS) for w in d.warnings)

    deep_gap, deep_warned = warned(0.6)
    flat_gap, flat_warned = warned(0.0)
    assert deep_gap > SEGMENT_MARGIN and not deep_warned
    assert flat_gap < SEGMENT_MARGIN and flat_warned


def test_the_vibtac12_copy_looks_like_segments_of_one_recording(vibtac12):
    description = describe_dataset(load_vibtac12(vibtac12))
    assert description.facts.class_names[0] == "Texture1"
    assert description.facts.recordings_per_class == (10,) * 12
    assert description.facts.n_windows == 19
    assert any(w.endswith(SEGMENTS) for w in description.warnings), description.warnings
    assert any(w.startswith(NO_TRANSIENT) for w in description.warnings)


def test_fewer_touches_than_folds_names_the_classes():
    signals, labels = _touches(per_class=3)
    signals, labels = signals[:-1], labels[:-1]  # c2 has 2
    description = describe_dataset(_dataset(signals, labels))
    (warning,) = [w for w in description.warnings if "fewer touches per class than folds" in w]
    assert "(10," in warning and "c0 has 3, c1 has 3, c2 has 2" in warning
    assert "at most 2" in warning
    assert not any(
        "folds" in w for w in describe_dataset(_dataset(signals, labels), folds=2).warnings
    )
    with pytest.raises(ValueError, match="folds"):
        describe_dataset(_dataset(signals, labels), folds=1)


def test_a_silent_class_and_a_silent_recording_are_named():
    signals, labels = _touches(per_class=10)
    class_names = ["rough", "smooth", "foam"]
    signals = [
        np.full(s.size, 0.25) if label == 2 else s for s, label in zip(signals, labels, strict=True)
    ]
    signals[3] = np.zeros(signals[3].size)
    names = [f"{class_names[label]}/t{i}" for i, label in enumerate(labels)]
    description = describe_dataset(_dataset(signals, labels, class_names, names))
    assert "class foam is silent: every recording is constant" in description.warnings[0]
    assert description.warnings[1] == "1 recording is silent (constant): rough/t3"
    assert not any("smooth" in w for w in description.warnings)
    # A silent class makes the loudest/quietest ratio infinite: outside, and null in JSON.
    ratio = next(c for c in description.comparisons if c.name == "loudest_quietest_ratio")
    assert math.isinf(ratio.value) and ratio.verdict is Verdict.OUTSIDE
    assert description.to_json()["statistics"]["loudest_quietest_ratio"]["value"] is None


def test_recordings_shorter_than_one_window_have_facts_but_no_statistics():
    rng = np.random.default_rng(5)
    signals = [rng.standard_normal(n) for n in (50, 300, 300, 300)]
    description = describe_dataset(_dataset(signals, [0, 0, 1, 1]))
    assert description.statistics is None and description.facts.n_windows == 0
    assert {c.verdict for c in description.comparisons} == {Verdict.UNDEFINED}
    (warning,) = [w for w in description.warnings if "one 0.1 s window" in w]
    assert "c0/r0" in warning and "0.05 s" in warning
    out = description.to_json()
    json.dumps(out, allow_nan=False)
    assert out["statistics"]["centroid_hz"]["value"] == [None, None]
    assert "rms" not in out["facts"]["classes"][0]


def test_json_is_plain_and_says_null_for_what_is_undefined():
    description = describe_dataset(_dataset(*_segments()))
    out = json.loads(json.dumps(description.to_json(), allow_nan=False))
    assert out["dataset"] == "made"
    facts = out["facts"]
    assert facts["n_classes"] == 3 and facts["sampling_rate_hz"] == FS
    assert facts["durations_s"] == {"min": 2.0, "median": 2.0, "max": 2.0}
    assert facts["windows"] == {"window_s": 0.1, "n": 20, "max": 40}
    assert [c["name"] for c in facts["classes"]] == ["c0", "c1", "c2"]
    assert [c["recordings"] for c in facts["classes"]] == [10, 10, 10]
    assert facts["classes"][2]["rms"] == pytest.approx(3.0, rel=0.05)
    stats = out["statistics"]
    assert set(stats) == set(REAL_TOUCHES)
    assert stats["slow_decay"]["value"] is None and stats["slow_decay"]["inside"] is None
    assert stats["envelope_corr_within"]["inside"] is False
    assert (
        stats["envelope_corr_within"]["real"] == 0.59
        and stats["envelope_corr_within"]["low"] == 0.4
    )
    assert stats["envelope_corr_within"]["high"] is None
    assert stats["centroid_hz"]["real"] == [8.0, 19.0] and len(stats["centroid_hz"]["value"]) == 2
    assert stats["contact_transient"]["p10"] <= stats["contact_transient"]["value"]
    assert out["warnings"] == list(description.warnings)


# -- folder layout ---------------------------------------------------------------------------


def test_layout_keeps_safe_sorted_names():
    signals, labels = _touches(per_class=2, seconds=0.5)
    names = [f"c{label}/take{i % 2}.csv" for i, label in enumerate(labels)]
    layout = folder_layout(_dataset(signals, labels, names=names, name="mine", units="N"))
    assert layout.class_folders == ("c0", "c1", "c2")
    assert layout.files == (
        "c0/take0.npy",
        "c0/take1.npy",
        "c1/take0.npy",
        "c1/take1.npy",
        "c2/take0.npy",
        "c2/take1.npy",
    )
    assert layout.renamed == ()
    toml = tomllib.loads(layout.toml)
    assert toml["sampling_rate_hz"] == FS and toml["name"] == "mine" and toml["units"] == "N"
    assert set(toml) == {"sampling_rate_hz", "name", "units", "description"}


def test_layout_sanitises_unsafe_names_deterministically_and_uniquely():
    class_names = ["a/b", "a_b", ".hidden", "dataset.toml", "Zeta", "zeta", "ü ñ", ""]
    labels = list(range(len(class_names)))
    signals = [np.arange(3.0)] * len(labels)
    names = ["../../etc/passwd", "x", "y", "z", "w", "v", "u", "t"]
    made = _dataset(signals, labels, class_names, names, name='odd "name"\n\x7f', units="µN")
    layout = folder_layout(made)
    assert layout == folder_layout(made)
    folders = layout.class_folders
    assert len({f.casefold() for f in folders}) == len(folders)
    assert list(folders) == sorted(folders)
    for folder in folders:
        assert folder and not folder.startswith(".") and folder.casefold() != "dataset.toml"
        assert set(folder) <= set(
            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-"
        )
    assert folders[0] == "1_a_b" and folders[2] == "3__.hidden"
    assert layout.files[0] == "1_a_b/_.._.._etc_passwd.npy"
    assert len(layout.renamed) == len(class_names)
    toml = tomllib.loads(layout.toml)
    assert toml["name"] == 'odd "name"\n\x7f' and toml["units"] == "µN"


def test_layout_numbers_recordings_whose_names_would_not_sort_in_order():
    signals = [np.arange(3.0)] * 3
    names = ["c0/b", "c0/a", "c0/b.npy"]  # out of order, and a clash once the suffix goes
    layout = folder_layout(_dataset(signals, [0, 0, 0], names=names))
    assert layout.files == ("c0/1_b.npy", "c0/2_a.npy", "c0/3_b.npy")
    long = folder_layout(_dataset(signals[:1], [0], names=["c0/" + "x" * 300]))
    assert long.files == ("c0/" + "x" * MAX_NAME_CHARS + ".npy",)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.text(min_size=0, max_size=120), min_size=1, max_size=12, unique=True))
def test_layout_names_are_always_safe_distinct_and_in_order(class_names):
    made = _dataset([np.arange(3.0)] * len(class_names), list(range(len(class_names))), class_names)
    folders = folder_layout(made).class_folders
    assert len({f.casefold() for f in folders}) == len(folders)
    assert list(folders) == sorted(folders)
    for folder in folders:
        assert 0 < len(folder) <= MAX_NAME_CHARS and not folder.startswith(".")
        assert re.fullmatch(r"[A-Za-z0-9._-]+", folder) and folder.casefold() != "dataset.toml"


def test_one_class_cannot_compare_time_courses_and_says_so():
    signals, labels = _touches(per_class=10)
    description = describe_dataset(_dataset(signals[:10], labels[:10]))
    assert any("cannot be compared within and between classes" in w for w in description.warnings)
    assert not any(w.endswith(SEGMENTS) for w in description.warnings)


def test_a_time_course_shared_by_every_class_is_called_so_not_segments():
    rng = np.random.default_rng(6)
    t = np.arange(int(4 * FS)) / FS
    course = 1 + 0.8 * np.sin(2 * np.pi * 0.5 * t)
    labels = [i // 10 for i in range(30)]
    signals = [course * rng.standard_normal(t.size) for _ in labels]
    description = describe_dataset(_dataset(signals, labels))
    assert description.statistics.envelope_corr_within > 0.4
    (warning,) = [w for w in description.warnings if "no more alike over time" in w]
    assert warning.endswith("their time course is the same for every class")


def test_statistics_over_touches_carry_their_class_medians():
    description = describe_dataset(_dataset(*_touches()))
    stats = description.statistics
    out = description.to_json()
    for name, field in (
        ("modulation_share", "class_modulation_share"),
        ("floor_ratio", "class_floor_ratio"),
    ):
        per_class = getattr(stats, field)
        assert out["statistics"][name]["classes"] == [per_class.min(), per_class.max()]
        assert [c[name] for c in out["facts"]["classes"]] == list(per_class)
        # The median over touches lies within the range of the class medians.
        assert per_class.min() <= out["statistics"][name]["value"] <= per_class.max()
    assert out["statistics"]["modulation_rate_f"]["low"] == 10.0
