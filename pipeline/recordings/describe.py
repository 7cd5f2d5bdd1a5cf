"""Is a dataset informative? Its facts, its touch statistics beside real touches, and warnings.

:func:`describe_dataset` gathers what a designer needs before sweeping a dataset:

- facts: classes and their recordings, sampling rate, units, durations, and how many whole
  windows of the paper's ``window_s`` (0.1 s) the shortest recording holds, at most the paper's
  :data:`pipeline.design.windows.MAX_AUTO_WINDOWS` (40, i.e. 4 s);
- the statistics of :mod:`pipeline.recordings.touch_statistics` over those windows, each beside its
  value on real touches (:data:`pipeline.recordings.touch_statistics.REAL_TOUCHES`) and judged
  inside or outside the real range (undefined when the dataset cannot give it); a per-class spectrum
  statistic is the range ``(min, max)`` over classes, inside when every class is;
- plain warnings, each with the condition that raises it:

  * segments of one recording: ``corr_within - corr_between < SEGMENT_MARGIN`` (0.15), where
    ``corr_*`` are the median envelope correlations within and between classes. Real touches
    give 0.59 vs 0.33 (0.26 apart); stationary scans and segments cut from one long recording
    give about 0 for both. The margin lies between the two gaps: real touches (0.26) clear it,
    the VibTac-12 copy's segments (-0.004) do not. The warning asks whether the touches are
    segments of one recording when the within-class correlation is below the real range (0.4),
    and says the time course is shared by every class when it is not. When the correlations
    are undefined (fewer than 3 windows, one class, no two non-silent touches of a class) the
    warning says so;
  * fewer recordings in a class than the folds of cross-validation (the paper scene's 10);
  * a silent class (every recording constant) and silent recordings (constant, no spike ever);
  * no contact transient: the first 0.25 s is less than the real range's lower bound (2) times
    the sliding level, as when recordings start mid-slide or are cut from one long scan;
  * recordings shorter than the paper's 40 windows (the scene codes fewer windows, and the slow
    decay over 3-4 s cannot be measured), or shorter than one window (nothing can be coded).

:func:`folder_layout` names the files of a folder dataset (the layout
:func:`pipeline.recordings.sources.load_folder` reads) that holds a dataset's recordings, so that
loading it gives back the same signals, labels, class names (made safe file names where needed)
and rate. It writes nothing.
"""

from __future__ import annotations

import enum
import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.design.scene import Scene
from pipeline.design.windows import MAX_AUTO_WINDOWS, whole_windows
from pipeline.recordings.describe_array import ArrayDescription, describe_array, taxel_mean
from pipeline.recordings.recording_set import listed
from pipeline.recordings.sources import Recordings
from pipeline.recordings.touch_statistics import (
    CONTACT_S,
    REAL_TOUCHES,
    Reference,
    TouchStatistics,
    touch_statistics,
)

__all__ = [
    "CLASS_MEDIANS",
    "SEGMENT_MARGIN",
    "Comparison",
    "DatasetContents",
    "DatasetDescription",
    "FolderLayout",
    "Verdict",
    "class_median_range",
    "describe_dataset",
    "folder_layout",
    "typical_text",
]

#: The within-class envelope correlation must exceed the between-class one by this much, or the
#: touches of a class are "no more alike over time than touches of different classes".
SEGMENT_MARGIN = 0.15
#: Longest file or folder name :func:`folder_layout` writes (characters, before ``.npy``).
MAX_NAME_CHARS = 100

#: The statistic a per-class spectrum reference judges: its name in ``REAL_TOUCHES`` -> the
#: per-class array of :class:`TouchStatistics`. Every other reference names a scalar field.
_PER_CLASS = {"centroid_hz": "class_centroid_hz", "bandwidth_hz": "class_bandwidth_hz"}
#: Scalar statistics that are medians over touches, judged as such, and their class medians
#: (shown beside them, as real touches' are in their reference's description).
CLASS_MEDIANS = {"modulation_share": "class_modulation_share", "floor_ratio": "class_floor_ratio"}
_FOLDER_TOML = "dataset.toml"
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


class Verdict(enum.Enum):
    """How a dataset's statistic compares with the real range."""

    INSIDE = "in"
    OUTSIDE = "out"
    UNDEFINED = "n/a"


@dataclass(frozen=True)
class Comparison:
    """One statistic of a dataset beside its real reference.

    ``value`` is a float (NaN or inf where the dataset cannot give it) or, for a per-class
    statistic, ``(min, max)`` over the classes that have a value.
    """

    name: str
    value: float | tuple[float, float]
    reference: Reference
    verdict: Verdict


@dataclass(frozen=True)
class DatasetContents:
    """What a dataset holds.

    ``recordings_per_class[c]`` counts the recordings of ``class_names[c]``; durations in s;
    ``n_windows`` whole windows of ``window_s`` fit the shortest recording, at most
    ``max_windows`` (the paper's 40); ``folds`` is the cross-validation the warnings assume.
    """

    name: str
    n_recordings: int
    class_names: tuple[str, ...]
    recordings_per_class: tuple[int, ...]
    fs_hz: float
    units: str
    duration_min_s: float
    duration_median_s: float
    duration_max_s: float
    window_s: float
    n_windows: int
    max_windows: int
    folds: int


@dataclass(frozen=True, eq=False)
class DatasetDescription:
    """A dataset's facts, its statistics beside real touches, and warnings (plain sentences).

    ``statistics`` is ``None`` when the shortest recording holds no whole window; every
    comparison is then undefined. For a real taxel array the statistics are those of the mean
    over its taxels, and ``array`` describes its taxels
    (:mod:`pipeline.recordings.describe_array`; its warnings are among ``warnings``).
    """

    facts: DatasetContents
    statistics: TouchStatistics | None
    comparisons: tuple[Comparison, ...]
    warnings: tuple[str, ...]
    array: ArrayDescription | None = None

    def to_json(self) -> dict[str, Any]:
        """Plain JSON values: NaN and infinities become ``None`` (JSON ``null``).

        Keys: ``dataset``, ``facts`` (scalars, ``durations_s`` min/median/max, ``windows``,
        ``classes``: name, recordings and, when measured, ``rms``, ``centroid_hz``,
        ``bandwidth_hz``, ``modulation_share``, ``floor_ratio`` per class), ``statistics``
        (name -> ``value``, ``inside`` (bool or ``None``), ``real``, ``low``, ``high``,
        ``description``; ``contact_transient`` also ``p10`` and ``p90``; the statistics of
        :data:`CLASS_MEDIANS` also ``classes``, the lowest and highest class median),
        ``warnings`` (list of strings); for a taxel array also ``array``
        (:meth:`pipeline.recordings.describe_array.ArrayDescription.to_json`).
        """
        f = self.facts
        stats = self.statistics
        classes = []
        for c, (name, count) in enumerate(zip(f.class_names, f.recordings_per_class, strict=True)):
            entry: dict[str, Any] = {"name": name, "recordings": count}
            if stats is not None:
                entry |= {
                    "rms": stats.class_rms[c],
                    "centroid_hz": stats.class_centroid_hz[c],
                    "bandwidth_hz": stats.class_bandwidth_hz[c],
                    "modulation_share": stats.class_modulation_share[c],
                    "floor_ratio": stats.class_floor_ratio[c],
                }
            classes.append(entry)
        statistics = {}
        for comparison in self.comparisons:
            ref = comparison.reference
            entry = {
                "value": comparison.value,
                "inside": {Verdict.INSIDE: True, Verdict.OUTSIDE: False}.get(comparison.verdict),
                "real": ref.typical,
                "low": ref.low,
                "high": ref.high,
                "description": ref.description,
            }
            if comparison.name == "contact_transient":
                entry |= {
                    "p10": stats.contact_transient_p10 if stats else math.nan,
                    "p90": stats.contact_transient_p90 if stats else math.nan,
                }
            if comparison.name in CLASS_MEDIANS:
                entry["classes"] = list(class_median_range(stats, comparison.name))
            statistics[comparison.name] = entry
        out = {
            "dataset": f.name,
            "facts": {
                "n_recordings": f.n_recordings,
                "n_classes": len(f.class_names),
                "sampling_rate_hz": f.fs_hz,
                "units": f.units,
                "durations_s": {
                    "min": f.duration_min_s,
                    "median": f.duration_median_s,
                    "max": f.duration_max_s,
                },
                "windows": {"window_s": f.window_s, "n": f.n_windows, "max": f.max_windows},
                "folds": f.folds,
                "classes": classes,
            },
            "statistics": statistics,
            "warnings": list(self.warnings),
        }
        if self.array is not None:
            out["array"] = self.array.to_json()
        return _json_values(out)


def describe_dataset(recordings: Recordings, *, folds: int | None = None) -> DatasetDescription:
    """Facts, statistics beside real touches, and warnings for ``recordings`` (module docstring).

    Parameters
    ----------
    recordings
        Any dataset.
    folds
        Cross-validation folds a sweep will use (>= 2); ``None``: the paper scene's (10).

    Raises
    ------
    ValueError
        ``folds`` is not an integer >= 2.
    """
    paper = Scene.paper()
    folds = paper.training.folds if folds is None else folds
    if isinstance(folds, bool) or not isinstance(folds, int) or folds < 2:
        raise ValueError(f"folds must be an integer >= 2, got {folds!r}")
    window_s = paper.coding.window_s
    durations = recordings.durations_s
    counts = np.bincount(recordings.labels, minlength=recordings.n_classes)
    n_windows = min(whole_windows(float(durations.min()), window_s), MAX_AUTO_WINDOWS)
    facts = DatasetContents(
        name=recordings.name,
        n_recordings=recordings.n_recordings,
        class_names=recordings.class_names,
        recordings_per_class=tuple(int(n) for n in counts),
        fs_hz=recordings.fs_hz,
        units=recordings.units,
        duration_min_s=float(durations.min()),
        duration_median_s=float(np.median(durations)),
        duration_max_s=float(durations.max()),
        window_s=window_s,
        n_windows=n_windows,
        max_windows=MAX_AUTO_WINDOWS,
        folds=folds,
    )
    stats = (
        touch_statistics(
            taxel_mean(recordings), window_s=window_s, span_s=MAX_AUTO_WINDOWS * window_s
        )
        if n_windows >= 1
        else None
    )
    comparisons = tuple(_compare(name, ref, stats) for name, ref in REAL_TOUCHES.items())
    array = (
        describe_array(
            recordings,
            span_s=max(n_windows, 1) * window_s,
            window_s=window_s,
            folds=folds,
        )
        if recordings.is_array
        else None
    )
    return DatasetDescription(
        facts=facts,
        statistics=stats,
        comparisons=comparisons,
        warnings=_warnings(recordings, facts, stats) + (array.warnings if array else ()),
        array=array,
    )


def _compare(name: str, reference: Reference, stats: TouchStatistics | None) -> Comparison:
    if stats is None:
        value: float | tuple[float, float] = math.nan
        if name in _PER_CLASS:
            value = (math.nan, math.nan)
        return Comparison(name, value, reference, Verdict.UNDEFINED)
    if name in _PER_CLASS:
        per_class = getattr(stats, _PER_CLASS[name])
        finite = per_class[np.isfinite(per_class)]
        if not finite.size:
            return Comparison(name, (math.nan, math.nan), reference, Verdict.UNDEFINED)
        value = (float(finite.min()), float(finite.max()))
        inside = reference.holds(value[0]) and reference.holds(value[1])
    else:
        value = float(getattr(stats, name))
        if math.isnan(value):
            return Comparison(name, value, reference, Verdict.UNDEFINED)
        inside = reference.holds(value)
    return Comparison(name, value, reference, Verdict.INSIDE if inside else Verdict.OUTSIDE)


def _warnings(
    recordings: Recordings, facts: DatasetContents, stats: TouchStatistics | None
) -> tuple[str, ...]:
    out = []
    silent = np.array([np.ptp(s) == 0 for s in recordings.signals])
    silent_classes = [
        name
        for c, name in enumerate(recordings.class_names)
        if silent[recordings.labels == c].all()
    ]
    if silent_classes:
        out.append(
            f"{_classes(silent_classes)} silent: every recording is constant, so the readout "
            "never spikes on it"
        )
    lone = [
        n
        for n, s, label in zip(recordings.names, silent, recordings.labels, strict=True)
        if s and recordings.class_names[label] not in silent_classes
    ]
    if lone:
        out.append(f"{_count(len(lone), 'recording')} silent (constant): {listed(lone)}")
    few = [
        f"{name} has {n}"
        for name, n in zip(facts.class_names, facts.recordings_per_class, strict=True)
        if n < facts.folds
    ]
    if few:
        out.append(
            f"fewer touches per class than folds ({facts.folds}, the paper scene's "
            f"cross-validation): {listed(few)}; set training.folds to at most "
            f"{min(facts.recordings_per_class)} or record more touches"
        )
    window = f"{facts.window_s:g} s"
    if stats is None:
        shortest = int(np.argmin(recordings.lengths))
        out.append(
            f"recordings shorter than one {window} window: the shortest "
            f"({recordings.names[shortest]}, {facts.duration_min_s:.3g} s) cannot be rate-coded, "
            "and no touch statistic can be measured"
        )
        return tuple(out)
    if facts.n_windows < facts.max_windows:
        span = facts.max_windows * facts.window_s
        out.append(
            f"recordings shorter than the paper's {facts.max_windows} windows of {window} "
            f"({span:g} s): the shortest ({facts.duration_min_s:.3g} s) holds {facts.n_windows}, "
            f"so a scene codes at most {facts.n_windows} windows"
            + ("" if math.isfinite(stats.slow_decay) else " and the slow decay is not measured")
        )
    within, between = stats.envelope_corr_within, stats.envelope_corr_between
    if math.isfinite(within) and math.isfinite(between):
        if within - between < SEGMENT_MARGIN:
            # Alike within classes as real touches are, but as alike across them: a time course
            # shared by every class (the robot's motion, say), not segments of a scan.
            low = REAL_TOUCHES["envelope_corr_within"].low
            shared = low is not None and within >= low
            out.append(
                "touches of a class are no more alike over time than touches of different "
                f"classes (envelope correlation {within:.2f} within, {between:.2f} between; real "
                f"touches {_typical('envelope_corr_within')} and "
                f"{_typical('envelope_corr_between')}): "
                + (
                    "their time course is the same for every class"
                    if shared
                    else "are these segments of one recording?"
                )
            )
    else:
        out.append(
            "the touches' time courses cannot be compared within and between classes (that "
            "needs at least 3 windows, two classes, and a class with two touches that are not "
            "silent)"
        )
    transient = stats.contact_transient
    low = REAL_TOUCHES["contact_transient"].low
    if math.isfinite(transient) and low is not None and transient < low:
        out.append(
            f"no contact transient: the first {CONTACT_S:g} s is {transient:.2g} times the "
            f"sliding level (real touches {_typical('contact_transient')}, at least {low:g}): "
            "do the recordings start mid-slide?"
        )
    return tuple(out)


def class_median_range(stats: TouchStatistics | None, name: str) -> tuple[float, float]:
    """Lowest and highest class median of a :data:`CLASS_MEDIANS` statistic (NaN: none)."""
    values = getattr(stats, CLASS_MEDIANS[name]) if stats is not None else np.array([])
    finite = values[np.isfinite(values)]
    return (float(finite.min()), float(finite.max())) if finite.size else (math.nan, math.nan)


def typical_text(reference: Reference) -> str:
    """A reference's typical value as text: ``"0.59"``, or ``"8-19"`` for a range."""
    typical = reference.typical
    return f"{typical[0]:g}-{typical[1]:g}" if isinstance(typical, tuple) else f"{typical:g}"


def _typical(name: str) -> str:
    return typical_text(REAL_TOUCHES[name])


def _classes(names: Sequence[str]) -> str:
    return (
        ("class " if len(names) == 1 else "classes ")
        + listed(names)
        + (" is" if len(names) == 1 else " are")
    )


def _count(n: int, noun: str) -> str:
    return f"{n} {noun} is" if n == 1 else f"{n} {noun}s are"


def _json_values(value: Any) -> Any:
    """``value`` as plain JSON: numpy scalars as Python numbers, non-finite floats as ``None``."""
    if isinstance(value, dict):
        return {k: _json_values(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_values(v) for v in value]
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    return value


# ---------------------------------------------------------------------------------------------
# Export layout


@dataclass(frozen=True)
class FolderLayout:
    """Where a dataset's recordings go in a folder dataset, and its ``dataset.toml``.

    ``class_folders[c]`` is the folder of class ``c``; ``files[n]`` is recording ``n``'s path
    ``"<class folder>/<name>.npy"`` (``.csv`` with a header line naming the taxels for an
    array); ``renamed`` lists ``"'old' -> 'new'"`` for every class name
    that had to change; ``toml`` is the text of ``dataset.toml``.
    """

    class_folders: tuple[str, ...]
    files: tuple[str, ...]
    renamed: tuple[str, ...]
    toml: str


def folder_layout(recordings: Recordings, *, source: str = "") -> FolderLayout:
    """File names of a folder dataset that loads back as ``recordings``.

    Names keep ``A-Z a-z 0-9 . _ -``; any run of other characters becomes ``_``, a leading ``.``
    (hidden, hence ignored by the loader) gets a ``_`` in front, and names are cut to
    ``MAX_NAME_CHARS`` characters. A recording's name is the part of its name after ``"<class>/"``
    (when it starts so) without a ``.csv``/``.npy`` suffix. When the names of a group (the
    classes, or the recordings of one class) then clash (also ignoring case) or would not sort
    into their order, every name of the group gets its zero-padded position in front
    (``"03_Texture3"``), so the loader's name order is the dataset's order. Deterministic:
    the same recordings always give the same layout.

    :func:`pipeline.recordings.sources.load_folder` on the written folder gives the same signals
    (bit for bit, as float64 ``.npy``, or an array's as the shortest decimals that read back as the
    same float64), rate, units and name (and an array's taxels and positions); recordings come back
    class by class, in their order within each class, so labels agree recording for recording when
    the dataset is stored class by class; class names are ``class_folders`` (equal to the original
    names unless ``renamed`` lists them). ``source`` (e.g. the path the dataset came from) goes into
    the description.
    """
    class_folders = _safe_names(recordings.class_names)
    renamed = tuple(
        f"{old!r} -> {new!r}"
        for old, new in zip(recordings.class_names, class_folders, strict=True)
        if old != new
    )
    files = [""] * recordings.n_recordings
    for c, (class_name, folder) in enumerate(
        zip(recordings.class_names, class_folders, strict=True)
    ):
        members = np.flatnonzero(recordings.labels == c)
        stems = []
        for n in members:
            stem = recordings.names[n].removeprefix(f"{class_name}/")
            for suffix in (".csv", ".npy"):
                if stem.lower().endswith(suffix):
                    stem = stem[: -len(suffix)]
            stems.append(stem)
        # An array's taxels are named by a CSV's header; a .npy has no column names.
        suffix = ".csv" if recordings.is_array else ".npy"
        for n, stem in zip(members, _safe_names(stems), strict=True):
            files[n] = f"{folder}/{stem}{suffix}"
    origin = f" from {source}" if source else ""
    description = (
        f"{recordings.name}{origin}, exported by eskin describe: {recordings.n_recordings} "
        f"recordings of {recordings.n_classes} classes, "
        + (
            f"{recordings.n_taxels} taxels, CSV with a header"
            if recordings.is_array
            else "float64 .npy"
        )
    )
    if renamed:
        description += "; class folders renamed to be safe file names in order: " + "; ".join(
            renamed
        )
    lines = [f"sampling_rate_hz = {recordings.fs_hz!r}", f"name = {_toml_string(recordings.name)}"]
    if recordings.units.strip():
        lines.append(f"units = {_toml_string(recordings.units)}")
    lines.append(f"description = {_toml_string(description)}")
    if recordings.is_array:
        lines.append(f"taxels = [{', '.join(map(_toml_string, recordings.taxel_names))}]")
    if recordings.taxel_positions_mm is not None:
        pairs = ", ".join(f"[{x!r}, {y!r}]" for x, y in recordings.taxel_positions_mm.tolist())
        lines.append(f"taxel_positions_mm = [{pairs}]")
    return FolderLayout(
        class_folders=class_folders,
        files=tuple(files),
        renamed=renamed,
        toml="\n".join(lines) + "\n",
    )


def _safe_names(names: Sequence[str]) -> tuple[str, ...]:
    """Safe, distinct file names that sort in the order of ``names`` (see folder_layout)."""
    safe = []
    for name in names:
        text = _UNSAFE.sub("_", name)
        # A leading dot hides an entry from the loader; a class named like the metadata file
        # would take its place.
        if not text or text.startswith(".") or text.casefold() == _FOLDER_TOML:
            text = "_" + text
        safe.append(text[:MAX_NAME_CHARS])
    folded = [s.casefold() for s in safe]
    if len(set(folded)) == len(folded) and safe == sorted(safe):
        return tuple(safe)
    width = len(str(len(names)))
    return tuple(f"{i + 1:0{width}d}_{s}"[:MAX_NAME_CHARS] for i, s in enumerate(safe))


def _toml_string(text: str) -> str:
    """A TOML basic string: JSON's escapes are TOML's, plus DEL, which TOML wants escaped."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")
