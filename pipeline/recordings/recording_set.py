"""The value object of a dataset: a labelled set of recordings at one sampling rate, each one
channel or one column per taxel of a real array (:mod:`pipeline.recordings.sources` reads them
from files, :mod:`pipeline.recordings.synthetic` makes them)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.errors import DatasetError

__all__ = ["MAX_LISTED", "Recordings", "listed", "message", "signal_problem"]

#: At most this many problems are spelled out in one error message.
MAX_LISTED = 10


# ---------------------------------------------------------------------------------------------
# The value object


@dataclass(frozen=True, eq=False)
class Recordings:
    """A labelled set of recordings, all at one sampling rate and with the same taxels.

    Attributes
    ----------
    signals
        One float64 array per recording, in ``units``; lengths may differ; every value finite, at
        least 2 samples. Shape ``(n_samples_n,)`` for one channel (``taxel_names`` empty), else
        ``(n_samples_n, n_taxels)``, column ``k`` being taxel ``taxel_names[k]``. Stored as
        read-only copies.
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
    taxel_names
        Empty for one-channel recordings; else the name of each recorded taxel (column), in the
        declared order, distinct.
    taxel_positions_mm
        ``None``, or float64 ``(n_taxels, 2)``: each taxel's ``[x, y]`` position (mm), finite.
        Only with ``taxel_names``. Stored as a read-only copy.

    Raises
    ------
    ValueError
        Inconsistent structure (a programming error): lengths of ``signals``, ``labels`` and
        ``names`` differ, a label is out of range, ``fs_hz`` is not a positive number, a signal is
        not 1-D (one channel) or not ``(n_samples, n_taxels)`` (an array), positions given without
        taxels or not of shape ``(n_taxels, 2)``.
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
    taxel_names: tuple[str, ...] = ()
    taxel_positions_mm: np.ndarray | None = None

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
        taxel_names = tuple(str(t) for t in self.taxel_names)
        if len(set(taxel_names)) != len(taxel_names):
            raise ValueError(f"taxel names are not distinct: {taxel_names!r}")
        expected = "1-D" if not taxel_names else f"(n_samples, {len(taxel_names)})"
        for name, signal in zip(names, signals, strict=True):
            if signal.shape[1:] != ((len(taxel_names),) if taxel_names else ()):
                raise ValueError(f"recording {name}: signal must be {expected}, got {signal.shape}")
        positions = self.taxel_positions_mm
        if positions is not None:
            positions = _frozen_copy(positions, np.float64)
            if positions.shape != (len(taxel_names), 2) or not taxel_names:
                raise ValueError(
                    f"taxel_positions_mm must be ({len(taxel_names)}, 2) for "
                    f"{len(taxel_names)} taxels, got {positions.shape}"
                )
            if not np.isfinite(positions).all():
                raise ValueError("taxel_positions_mm must be finite")
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
        object.__setattr__(self, "taxel_names", taxel_names)
        object.__setattr__(self, "taxel_positions_mm", positions)

    @property
    def n_recordings(self) -> int:
        """Number of recordings."""
        return len(self.signals)

    @property
    def n_classes(self) -> int:
        """Number of classes (``len(class_names)``)."""
        return len(self.class_names)

    @property
    def n_taxels(self) -> int:
        """How many taxels each recording holds (1 for one channel, else ``len(taxel_names)``)."""
        return len(self.taxel_names) or 1

    @property
    def is_array(self) -> bool:
        """Whether each recording holds one column per taxel of a real array."""
        return bool(self.taxel_names)

    @property
    def lengths(self) -> np.ndarray:
        """int64, shape ``(n_recordings,)``: samples per recording."""
        return np.array([s.shape[0] for s in self.signals], dtype=np.int64)

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
    """A one-phrase problem with one recording (1-D, or one column per taxel), or ``None``.

    ``locate(i)`` says where sample ``i`` is in the file (e.g. ``"line 13"``), if known.
    """
    n_samples = signal.shape[0] if signal.ndim else 0
    if signal.size == 0:
        return f"{name}: empty recording (no samples)"
    if n_samples < 2:
        return f"{name}: recording has {n_samples} sample, needs at least 2"
    bad = ~np.isfinite(signal)
    if bad.any():
        first, column = divmod(int(np.argmax(bad)), signal.size // n_samples)
        where = f"sample {first}" + (f", column {column}" if signal.ndim > 1 else "")
        if locate is not None:
            where += f" ({locate(first)})"
        n_bad = int(bad.sum())
        more = f" ({n_bad} non-finite samples in all)" if n_bad > 1 else ""
        return f"{name}: non-finite value {signal.flat[int(np.argmax(bad))]} at {where}{more}"
    return None


def listed(items: Sequence[str]) -> str:
    """``"a, b, c"``, at most ``MAX_LISTED`` items, then ``"and N more"``."""
    shown = list(items[:MAX_LISTED])
    if len(items) > MAX_LISTED:
        shown.append(f"and {len(items) - MAX_LISTED} more")
    return ", ".join(shown)


def message(head: str, problems: Sequence[str]) -> str:
    """One line: ``head: p1; p2; ...; and N more`` (newlines in names escaped)."""
    n = len(problems)
    listed = list(problems[:MAX_LISTED])
    if n > MAX_LISTED:
        listed.append(f"and {n - MAX_LISTED} more")
    head = head + (f" ({n} problems)" if n > 1 else "")
    text = f"{head}: " + "; ".join(listed)
    return text.replace("\r", "\\r").replace("\n", "\\n")
