"""Recordings of a real taxel array: one named column per taxel, and perhaps a time column.

A folder dataset's recording holds several taxels when it is a ``.csv`` whose first line is a
header naming its columns, or a 2-D ``.npy`` of shape ``(samples, columns)`` (its columns are
named ``column1 .. columnN``). ``dataset.toml`` may then say (:class:`ColumnLayout`):

``taxels``
    The columns that are taxels, in the order the dataset declares them (column ``k`` of every
    signal is taxel ``taxels[k]``). Default: every numeric column but the time column, in file
    order; a column is numeric when its first value is a number (a later non-number in it is an
    error, not a reason to drop it). Every recording must hold the same taxels; with
    ``taxels`` given a recording may hold other columns too (proximity sensors, say), ignored.
``time_column`` and ``time_unit``
    The column of sample times and its unit (``"s"``, ``"ms"`` or ``"us"``; required with a
    time column). The times of each recording must increase strictly, except that a row
    repeated whole (the same time and the same taxel values as the row before, as a logger
    that writes its last row twice leaves) is one sample, read once. The rate is the dataset's
    mean sample interval ``T``, pooled over recordings,
    ``fs = sum_n (len_n - 1) / sum_n (t_n[-1] - t_n[0])``, and each recording is resampled onto
    its own uniform grid ``t_n[0] + k / fs``, ``k = 0 .. floor((t_n[-1] - t_n[0]) fs)``, by linear
    interpolation per taxel: the readout's own model of the signal between samples (a straight
    line through them), so a jittered or gapped clock gives no time warp. ``sampling_rate_hz``
    is then left out: the time column gives the rate.
``taxel_positions_mm``
    One ``[x, y]`` per taxel (mm), in the order of the taxels.
"""

from __future__ import annotations

import enum
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "ARRAY_KEYS",
    "ColumnLayout",
    "ColumnProblem",
    "TaxelRecording",
    "TaxelSet",
    "TaxelTable",
    "TimeUnit",
    "column_layout",
    "header_of",
    "mixed_problems",
    "npy_columns",
    "parse_with_header",
    "taxel_recording",
    "taxel_set",
    "uniform_rate_hz",
    "uniform_signal",
]


class TimeUnit(enum.Enum):
    """Unit of a time column."""

    S = "s"
    MS = "ms"
    US = "us"

    @property
    def seconds(self) -> float:
        """One unit in seconds."""
        return {TimeUnit.S: 1.0, TimeUnit.MS: 1e-3, TimeUnit.US: 1e-6}[self]


#: The ``dataset.toml`` keys of an array dataset.
ARRAY_KEYS = ("taxels", "time_column", "time_unit", "taxel_positions_mm")

_NUMBER = re.compile(
    r"\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf|infinity)\s*", re.IGNORECASE
)


class ColumnProblem(Exception):
    """One problem with one file; collected with the others by the folder reader."""


@dataclass(frozen=True)
class ColumnLayout:
    """What ``dataset.toml`` says of the columns (module docstring).

    ``taxels`` is empty for "every numeric column"; ``positions_mm`` is float64 ``(n, 2)`` or
    ``None``; ``time_unit`` is set exactly when ``time_column`` is.
    """

    taxels: tuple[str, ...] = ()
    time_column: str | None = None
    time_unit: TimeUnit | None = None
    positions_mm: np.ndarray | None = None

    @property
    def declared(self) -> bool:
        """Whether ``dataset.toml`` declares anything of an array."""
        return bool(self.taxels) or self.time_column is not None or self.positions_mm is not None


def column_layout(data: dict[str, Any], where: str, problems: list[str]) -> ColumnLayout:
    """The :data:`ARRAY_KEYS` of a parsed ``dataset.toml``; problems are appended, not raised."""
    taxels: tuple[str, ...] = ()
    if "taxels" in data:
        value = data["taxels"]
        if (
            not isinstance(value, list)
            or not value
            or not all(isinstance(t, str) and t.strip() for t in value)
        ):
            problems.append(f"{where}: taxels = {value!r} is not a list of column names")
        elif len({t.strip() for t in value}) != len(value):
            problems.append(f"{where}: taxels names a column twice: {value!r}")
        else:
            taxels = tuple(t.strip() for t in value)
    time_column, unit = None, None
    if "time_column" in data:
        value = data["time_column"]
        if isinstance(value, str) and value.strip():
            time_column = value.strip()
            if time_column in taxels:
                problems.append(f"{where}: time_column {time_column!r} is also in taxels")
        else:
            problems.append(f"{where}: time_column = {value!r} is not a column name")
    if "time_unit" in data:
        try:
            unit = TimeUnit(data["time_unit"])
        except (ValueError, TypeError):
            known = ", ".join(repr(u.value) for u in TimeUnit)
            problems.append(f"{where}: time_unit = {data['time_unit']!r} is not one of {known}")
    if ("time_column" in data) != ("time_unit" in data):
        problems.append(f"{where}: time_column and time_unit go together (give both or neither)")
    if "time_column" in data and "sampling_rate_hz" in data:
        problems.append(
            f"{where}: sampling_rate_hz and time_column both give the rate: leave "
            "sampling_rate_hz out (the time column's mean interval sets it)"
        )
    positions = None
    if "taxel_positions_mm" in data:
        positions = _positions(data["taxel_positions_mm"], where, problems)
    # A time column without a valid unit is reported above; reading goes on without it.
    return ColumnLayout(taxels, time_column if unit else None, unit, positions)


def _positions(value: Any, where: str, problems: list[str]) -> np.ndarray | None:
    def number(v: Any) -> bool:
        return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)

    if (
        isinstance(value, list)
        and value
        and all(isinstance(p, list) and len(p) == 2 and all(map(number, p)) for p in value)
    ):
        return np.array(value, dtype=np.float64)
    problems.append(
        f"{where}: taxel_positions_mm must be a list of [x, y] pairs of finite numbers (mm), "
        f"got {str(value)[:60]}"
    )
    return None


@dataclass(frozen=True)
class TaxelTable:
    """One recording's named columns: float64 ``values`` ``(n_samples, len(names))``;
    ``first_line`` is the file line of row 0 (1-based), 0 for a ``.npy``."""

    names: tuple[str, ...]
    values: np.ndarray
    first_line: int


def header_of(lines: Sequence[str]) -> tuple[str, ...] | None:
    """The column names of a CSV's first line, or ``None`` when it holds only numbers."""
    fields = lines[0].split(",")
    if all(_NUMBER.fullmatch(f) for f in fields):
        return None
    return tuple(f.strip() for f in fields)


def parse_with_header(lines: Sequence[str], where: str, wanted: set[str] | None) -> TaxelTable:
    """Parse a CSV whose first line names its columns.

    ``wanted`` are the columns that must be numeric (``None``: those whose first value is a
    number, the others are skipped). Raises :class:`ColumnProblem` naming ``where``, the line
    and the column.
    """
    names = tuple(f.strip() for f in lines[0].split(","))
    blank = [i + 1 for i, n in enumerate(names) if not n]
    if blank:
        raise ColumnProblem(f"{where}: line 1 (the header) leaves column {blank[0]} unnamed")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ColumnProblem(f"{where}: line 1 (the header) names column {twice[0]!r} twice")
    rows = list(lines[1:])
    if not rows:
        raise ColumnProblem(f"{where}: empty recording (a header and no samples)")
    for number, row in enumerate(rows, start=2):
        if row.count(",") + 1 != len(names):
            raise ColumnProblem(
                f"{where}: line {number} has {row.count(',') + 1} columns, the header names "
                f"{len(names)}"
            )
    if wanted is None:
        first = rows[0].split(",")
        numeric = tuple(bool(_NUMBER.fullmatch(f)) for f in first)
    else:
        missing = [n for n in sorted(wanted) if n not in names]
        if missing:
            raise ColumnProblem(
                f"{where}: no column {missing[0]!r} (the header names {_few(names)})"
            )
        numeric = tuple(n in wanted for n in names)
    used = [i for i, ok in enumerate(numeric) if ok]
    if not used:
        raise ColumnProblem(f"{where}: no numeric column")
    try:
        values = np.loadtxt(
            rows, delimiter=",", comments=None, usecols=used, ndmin=2, dtype=np.float64
        )
    except ValueError:
        raise ColumnProblem(_bad_number(rows, names, used, where)) from None
    return TaxelTable(tuple(names[i] for i in used), values, 2)


def _bad_number(rows: Sequence[str], names: Sequence[str], used: Sequence[int], where: str) -> str:
    bad = []
    for number, row in enumerate(rows, start=2):
        fields = row.split(",")
        for i in used:
            if not _NUMBER.fullmatch(fields[i]):
                shown = fields[i].strip()
                shown = shown if len(shown) <= 40 else shown[:37] + "..."
                bad.append(f"line {number}, column {names[i]}: {shown!r} is not a number")
                break
    more = f" (and {len(bad) - 1} more bad lines)" if len(bad) > 1 else ""
    first = bad[0] if bad else "not a table of numbers"
    return f"{where}: {first}{more}"


def npy_columns(array: np.ndarray) -> TaxelTable:
    """A 2-D ``.npy`` array's columns, named ``column1 .. columnN``."""
    names = tuple(f"column{k + 1}" for k in range(array.shape[1]))
    return TaxelTable(names, array.astype(np.float64), 0)


@dataclass(frozen=True)
class TaxelRecording:
    """One recording's taxels as read: names in file order, float64 ``(n_samples, n_taxels)``
    signal, sample times (s from the first) or ``None``."""

    where: str
    taxels: tuple[str, ...]
    signal: np.ndarray
    times_s: np.ndarray | None


def taxel_recording(table: TaxelTable, layout: ColumnLayout, where: str) -> TaxelRecording:
    """The taxels (and times) of one recording's columns.

    Raises :class:`ColumnProblem` for a missing column, a non-finite value (file, line and
    column named), or a time column that does not increase strictly.
    """
    index = {name: k for k, name in enumerate(table.names)}
    time = [layout.time_column] if layout.time_column else []
    missing = [n for n in [*layout.taxels, *time] if n not in index]
    if missing:
        raise ColumnProblem(f"{where}: no column {missing[0]!r} (it holds {_few(table.names)})")
    taxels = layout.taxels or tuple(n for n in table.names if n != layout.time_column)
    if not taxels:
        raise ColumnProblem(f"{where}: no taxel column besides the time column")
    for name in [*taxels, *time]:
        column = table.values[:, index[name]]
        bad = ~np.isfinite(column)
        if bad.any():
            row = int(np.argmax(bad))
            raise ColumnProblem(
                f"{where}: column {name}: non-finite value {column[row]} at sample {row}"
                + _line(table, row)
                + (f" ({int(bad.sum())} in all)" if bad.sum() > 1 else "")
            )
    signal = table.values[:, [index[n] for n in taxels]]
    times = None
    if layout.time_column is not None and layout.time_unit is not None:
        stamps = table.values[:, index[layout.time_column]]
        # A row written twice (same time, same taxel values) is one sample: keep the first.
        repeated = np.concatenate(
            [[False], (np.diff(stamps) == 0) & (np.diff(signal, axis=0) == 0).all(axis=1)]
        )
        steps = np.diff(stamps[~repeated])
        if (steps <= 0).any():
            row = np.flatnonzero(~repeated)[int(np.argmax(steps <= 0)) + 1]
            raise ColumnProblem(
                f"{where}: time column {layout.time_column} does not increase at sample {row}"
                f"{_line(table, row)}: {stamps[row]:.15g} after {stamps[row - 1]:.15g}"
            )
        signal = signal[~repeated]
        times = (stamps[~repeated] - stamps[0]) * layout.time_unit.seconds
    return TaxelRecording(where, taxels, signal, times)


@dataclass(frozen=True)
class TaxelSet:
    """The recordings of an array dataset, on one uniform grid and with one taxel order."""

    taxels: tuple[str, ...]
    signals: tuple[np.ndarray, ...]
    fs_hz: float | None
    positions_mm: np.ndarray | None


def taxel_set(
    recordings: Sequence[TaxelRecording],
    layout: ColumnLayout,
    fs_hz: float | None,
    problems: list[str],
    where: str,
) -> TaxelSet:
    """Check that every recording holds the same taxels and put them in one order (the first
    recording's, or ``layout.taxels``); resample onto a uniform grid when they carry times
    (module docstring). ``fs_hz`` is ``dataset.toml``'s rate (``None`` with a time column).
    Problems are appended; ``where`` names ``dataset.toml``."""
    if not recordings:
        return TaxelSet((), (), fs_hz, None)
    first = recordings[0]
    taxels = layout.taxels or first.taxels
    signals = []
    for recording in recordings:
        if set(recording.taxels) != set(taxels):
            lacks = [t for t in taxels if t not in recording.taxels]
            adds = [t for t in recording.taxels if t not in taxels]
            problems.append(
                f"{recording.where}: its taxels differ from {first.where}'s ("
                + "; ".join(
                    [f"lacks {_few(lacks)}"] * bool(lacks) + [f"adds {_few(adds)}"] * bool(adds)
                )
                + ")"
            )
            continue
        order = [recording.taxels.index(t) for t in taxels]
        signals.append(recording.signal[:, order])
    positions = layout.positions_mm
    if positions is not None and len(positions) != len(taxels):
        problems.append(
            f"{where}: taxel_positions_mm gives {len(positions)} positions for {len(taxels)} "
            f"taxels ({_few(taxels)})"
        )
    if layout.time_column is not None and len(signals) == len(recordings):
        times = [r.times_s for r in recordings if r.times_s is not None]
        fs_hz = uniform_rate_hz(times)
        signals = [uniform_signal(s, t, fs_hz) for s, t in zip(signals, times, strict=True)]
    return TaxelSet(taxels, tuple(signals), fs_hz, positions)


def mixed_problems(
    names: Sequence[str], signals: Sequence[np.ndarray | TaxelRecording], layout: ColumnLayout
) -> list[str]:
    """Problems of a dataset whose recordings are some one unnamed column, some named taxels.

    When ``dataset.toml`` declares an array, or most recordings hold taxels, each one-column
    recording is named; else each recording with taxels is (a stray header line in a dataset of
    one-column files, say)."""
    plain = [n for n, s in zip(names, signals, strict=True) if not isinstance(s, TaxelRecording)]
    arrays = [s for s in signals if isinstance(s, TaxelRecording)]
    if not plain or (not arrays and not layout.declared):
        return []
    if layout.declared or len(arrays) > len(plain):
        return [
            f"{name}: one unnamed column, where the dataset's recordings hold named taxels (a "
            "header line naming the columns, or a 2-D .npy)"
            for name in plain
        ]
    return [
        f"{a.where}: named columns ({_few(a.taxels)}), where {plain[0]} and the dataset's other "
        "recordings hold one unnamed column (a header line only if every recording has one)"
        for a in arrays
    ]


def uniform_rate_hz(times_s: Sequence[np.ndarray]) -> float:
    """The pooled mean sampling rate of recordings' sample times (module docstring), Hz."""
    intervals = sum(t.size - 1 for t in times_s)
    span = sum(float(t[-1] - t[0]) for t in times_s)
    return intervals / span


def uniform_signal(signal: np.ndarray, times_s: np.ndarray, fs_hz: float) -> np.ndarray:
    """``signal`` (``(n, taxels)`` at ``times_s``) linearly resampled at ``t0 + k / fs_hz``."""
    n = math.floor((times_s[-1] - times_s[0]) * fs_hz + 1e-9) + 1
    grid = times_s[0] + np.arange(n) / fs_hz
    out = np.empty((n, signal.shape[1]))
    for k in range(signal.shape[1]):
        out[:, k] = np.interp(grid, times_s, signal[:, k])
    return out


def _line(table: TaxelTable, row: int) -> str:
    return f" (line {table.first_line + row})" if table.first_line else ""


def _few(names: Sequence[str]) -> str:
    shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
    return shown or "none"
