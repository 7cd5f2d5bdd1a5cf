"""The value object of a dataset: a labelled set of one-channel recordings at one sampling rate
(:mod:`pipeline.recordings.sources` reads them from files, :mod:`pipeline.recordings.synthetic`
makes them)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.errors import DatasetError

__all__ = ["MAX_LISTED", "Recordings", "message", "signal_problem"]

#: At most this many problems are spelled out in one error message.
MAX_LISTED = 10


# ---------------------------------------------------------------------------------------------
# The value object


@dataclass(frozen=True, eq=False)
class Recordings:
    """A labelled set of one-channel recordings, all at one sampling rate.

    Attributes
    ----------
    signals
        One float64 1-D array per recording, shape ``(n_samples_n,)``, in ``units``; lengths may
        differ; every value finite, at least 2 samples. Stored as read-only copies.
    labels
        int64, shape ``(n_recordings,)``: class index ``0..n_classes - 1`` of each recording.
        Stored as a read-only copy.
    class_names
        ``n_classes`` distinct names; ``class_names[c]`` names class ``c``.
    fs_hz
        Sampling rate (Hz), finite and > 0.
    names
        One human-readable name per recording, used in messages, e.g. ``"Texture3/segment07"``.
    units
        Units of the samples, e.g. ``"counts"``, ``"N"``, ``"a.u."``.
    name
        Name of the dataset.

    Raises
    ------
    ValueError
        Inconsistent structure (a programming error): lengths of ``signals``, ``labels`` and
        ``names`` differ, a label is out of range, ``fs_hz`` is not a positive number, a signal is
        not 1-D.
    DatasetError
        No recordings, a recording shorter than 2 samples, or a non-finite sample (the message
        names the recording and the first bad sample index).
    """

    signals: tuple[np.ndarray, ...]
    labels: np.ndarray
    class_names: tuple[str, ...]
    fs_hz: float
    names: tuple[str, ...]
    units: str
    name: str

    def __post_init__(self) -> None:
        fs = float(self.fs_hz)
        if not (math.isfinite(fs) and fs > 0):
            raise ValueError(f"fs_hz must be a finite number > 0, got {self.fs_hz!r}")
        signals = tuple(_frozen_copy(s, np.float64) for s in self.signals)
        labels = _frozen_copy(self.labels, np.int64)
        class_names = tuple(str(c) for c in self.class_names)
        names = tuple(str(n) for n in self.names)
        if labels.ndim != 1 or not len(signals) == labels.size == len(names):
            raise ValueError(
                f"{len(signals)} signals, labels of shape {labels.shape} and {len(names)} names "
                "do not match"
            )
        if len(set(class_names)) != len(class_names):
            raise ValueError(f"class names are not distinct: {class_names!r}")
        if labels.size and (labels.min() < 0 or labels.max() >= len(class_names)):
            raise ValueError(f"labels must be in 0..{len(class_names) - 1}")
        for name, signal in zip(names, signals, strict=True):
            if signal.ndim != 1:
                raise ValueError(f"recording {name}: signal must be 1-D, got {signal.shape}")
        problems = [p for p in map(signal_problem, names, signals) if p]
        if not signals:
            problems.append("no recordings")
        if problems:
            raise DatasetError(message(f"dataset {self.name}", problems))
        object.__setattr__(self, "signals", signals)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "class_names", class_names)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "fs_hz", fs)
        object.__setattr__(self, "units", str(self.units))
        object.__setattr__(self, "name", str(self.name))

    @property
    def n_recordings(self) -> int:
        """Number of recordings."""
        return len(self.signals)

    @property
    def n_classes(self) -> int:
        """Number of classes (``len(class_names)``)."""
        return len(self.class_names)

    @property
    def lengths(self) -> np.ndarray:
        """int64, shape ``(n_recordings,)``: samples per recording."""
        return np.array([s.size for s in self.signals], dtype=np.int64)

    @property
    def durations_s(self) -> np.ndarray:
        """float64, shape ``(n_recordings,)``: duration of each recording, ``len / fs_hz`` (s)."""
        return self.lengths / self.fs_hz

    @property
    def min_samples(self) -> int:
        """Length (samples) of the shortest recording."""
        return int(self.lengths.min())


def _frozen_copy(values: Any, dtype: type) -> np.ndarray:
    array = np.array(values, dtype=dtype, copy=True)
    array.flags.writeable = False
    return array


def signal_problem(
    name: str, signal: np.ndarray, locate: Callable[[int], str] | None = None
) -> str | None:
    """A one-phrase problem with one recording, or ``None``.

    ``locate(i)`` says where sample ``i`` is in the file (e.g. ``"line 13"``), if known.
    """
    if signal.size == 0:
        return f"{name}: empty recording (no samples)"
    if signal.size < 2:
        return f"{name}: recording has {signal.size} sample, needs at least 2"
    bad = ~np.isfinite(signal)
    if bad.any():
        first = int(np.argmax(bad))
        where = f"sample {first}"
        if locate is not None:
            where += f" ({locate(first)})"
        n_bad = int(bad.sum())
        more = f" ({n_bad} non-finite samples in all)" if n_bad > 1 else ""
        return f"{name}: non-finite value {signal[first]} at {where}{more}"
    return None


def message(head: str, problems: Sequence[str]) -> str:
    """One line: ``head: p1; p2; ...; and N more`` (newlines in names escaped)."""
    n = len(problems)
    listed = list(problems[:MAX_LISTED])
    if n > MAX_LISTED:
        listed.append(f"and {n - MAX_LISTED} more")
    head = head + (f" ({n} problems)" if n > 1 else "")
    text = f"{head}: " + "; ".join(listed)
    return text.replace("\r", "\\r").replace("\n", "\\n")
