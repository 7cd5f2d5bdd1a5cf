"""Recordings: the force (or acceleration) signals a scene starts from, one channel or one
column per taxel of a real array.

A dataset is a set of recordings ``x_n[k]``, ``n = 0..N-1``, each a finite float64 sequence
sampled at one rate ``fs_hz`` for the whole dataset (of one value per sample, or of one value per
taxel, the same taxels in every recording), with a class label ``c_n`` in ``0..C-1``. Recording
``n`` lasts ``len(x_n) / fs_hz`` seconds; lengths may differ.

Three sources (``pipeline.design.scene.DatasetKind``):

``synthetic``
    Generated from a seed, see :mod:`pipeline.recordings.synthetic`.
``vibtac12``
    The paper's dataset (Kursun and Patooghy, 2020) in its published layout: ``X.csv``,
    ``Y.csv``, ``Z.csv``, no header, 12 rows x 4000 columns, row ``i`` is texture ``i + 1``.
    Only the chosen axis is read. The first 3 samples of every row are start-up padding and
    dropped; the remaining ``L - 3`` samples are cut into ``segments`` equal, non-overlapping
    segments of ``(L - 3) // segments`` samples (the remainder at the end is dropped), so recording
    ``i * segments + s`` is ``row_i[3 + s * m : 3 + (s + 1) * m]``. Cutting one continuous
    recording per texture into segments only approximates the paper's 10 recordings per class.
``folder``
    ``DIR/dataset.toml`` (``sampling_rate_hz`` required, optional ``name``, ``units`` and
    ``description``, and for an array ``taxels``, ``time_column`` with ``time_unit`` (which
    replace ``sampling_rate_hz``) and ``taxel_positions_mm``, no other keys) plus one sub-folder
    per class, sorted by name, each holding one recording per file: ``.csv`` with one numeric
    column and no header, or ``.npy`` holding a 1-D numeric array; for an array, a ``.csv``
    whose first line names its columns, or a 2-D ``.npy`` ``(samples, columns)``
    (:mod:`pipeline.recordings.taxel_columns` says which columns are taxels and how a time
    column sets the rate). Hidden entries (names starting with ``.``) are ignored everywhere;
    other files at the top level (a README, say) are ignored; any other file or folder inside a
    class folder is an error.

Loading never executes code from data: ``.npy`` files are read with ``allow_pickle=False``,
TOML with ``tomllib``, CSV as text.

Every problem a user can cause raises :class:`pipeline.errors.DatasetError` with one line that
names the dataset and each offending file or recording (all problems found, at most
``MAX_LISTED`` listed, then ``"and N more"``).
"""

from __future__ import annotations

import os
import re
import tomllib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from pipeline.design.scene import Axis, DatasetKind, DatasetSpec
from pipeline.errors import DatasetError
from pipeline.numbers import positive_number, whole_number
from pipeline.recordings.recording_set import MAX_LISTED, Recordings, message, signal_problem
from pipeline.recordings.taxel_columns import (
    ARRAY_KEYS,
    ColumnLayout,
    ColumnProblem,
    TaxelRecording,
    column_layout,
    header_of,
    mixed_problems,
    npy_columns,
    parse_with_header,
    taxel_recording,
    taxel_set,
)

__all__ = [
    "MAX_ABS_SAMPLE",
    "MAX_LISTED",
    "VIBTAC12_PADDING",
    "VIBTAC12_ROWS",
    "Recordings",
    "load_folder",
    "load_recordings",
    "load_vibtac12",
    "resolve_dataset_argument",
]

#: Largest accepted sample magnitude. No sensor's reading is this large in any unit; such values
#: come from corrupt or misread files, and their squares (signal power, noise budgets) overflow
#: float64.
MAX_ABS_SAMPLE = 1e100
#: Leading start-up samples of every VibTac-12 row, dropped.
VIBTAC12_PADDING = 3
#: Rows (textures) of a VibTac-12 file.
VIBTAC12_ROWS = 12
#: Default sampling rate of VibTac-12 (undocumented by the authors; best estimate).
VIBTAC12_DEFAULT_RATE_HZ = 200.0

_FOLDER_TOML = "dataset.toml"
_FOLDER_KEYS = ("sampling_rate_hz", "name", "units", "description", *ARRAY_KEYS)
_VIBTAC_FILES = ("X.csv", "Y.csv", "Z.csv")
_RECORDING_SUFFIXES = (".csv", ".npy")
_NUMBER = re.compile(
    r"\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf|infinity)\s*", re.IGNORECASE
)


def _check_magnitudes(recordings: Recordings) -> Recordings:
    """``recordings`` unchanged, or a DatasetError naming every recording beyond MAX_ABS_SAMPLE.

    The readers themselves load any finite value exactly; this guards the simulation.
    """
    problems = []
    for name, signal in zip(recordings.names, recordings.signals, strict=True):
        huge = np.abs(signal) > MAX_ABS_SAMPLE
        if huge.any():
            first, column = divmod(int(np.argmax(huge)), recordings.n_taxels)
            taxel = f", taxel {recordings.taxel_names[column]}" if recordings.is_array else ""
            problems.append(
                f"{name}: absurd magnitude {float(signal.flat[int(np.argmax(huge))])!r} at sample "
                f"{first}{taxel} (more than {MAX_ABS_SAMPLE:g} in any unit: a corrupt or "
                "misread file)"
            )
    if problems:
        raise DatasetError(message(f"dataset {recordings.name}", problems))
    return recordings


# ---------------------------------------------------------------------------------------------
# Dispatch


def synthetic_arguments(spec: DatasetSpec) -> dict[str, Any]:
    """The keyword arguments of :func:`pipeline.recordings.synthetic.synthetic_recordings` for
    ``spec``."""
    from pipeline.recordings.synthetic import DEFAULT_FS_HZ

    return {
        "seed": spec.seed,
        "recordings_per_class": spec.recordings_per_class,
        "duration_s": spec.duration_s,
        "fs_hz": spec.sampling_rate_hz or DEFAULT_FS_HZ,
    }


def load_recordings(spec: DatasetSpec) -> Recordings:
    """Load the recordings a scene's ``dataset`` part describes.

    Parameters
    ----------
    spec
        ``kind="synthetic"`` calls :func:`pipeline.recordings.synthetic.synthetic_recordings` with
        ``seed``, ``recordings_per_class``, ``duration_s`` and ``sampling_rate_hz`` (2 kHz when
        ``None``); ``"vibtac12"`` calls :func:`load_vibtac12` with ``path``, ``axis``, ``segments``
        and ``sampling_rate_hz`` (200 Hz when ``None``); ``"folder"`` calls :func:`load_folder`. A
        folder's rate comes from its ``dataset.toml``; a different ``sampling_rate_hz`` in the
        spec is an error rather than a silent override. ``segments`` applies to VibTac-12 only.

    Returns
    -------
    Recordings

    Raises
    ------
    DatasetError
        The dataset is missing or unusable (one line naming what and where), or a sample's
        magnitude exceeds :data:`MAX_ABS_SAMPLE` (the readers load any finite value; the
        simulation refuses absurd ones).
    """
    kind = DatasetKind(spec.kind)
    if kind is DatasetKind.SYNTHETIC:
        from pipeline.recordings.synthetic import synthetic_recordings

        return synthetic_recordings(**synthetic_arguments(spec))
    if not spec.path:
        raise DatasetError(f"dataset of kind {kind.value!r} needs a path (dataset.path)")
    if kind is DatasetKind.VIBTAC12:
        return _check_magnitudes(
            load_vibtac12(
                spec.path,
                sampling_rate_hz=spec.sampling_rate_hz or VIBTAC12_DEFAULT_RATE_HZ,
                axis=spec.axis,
                segments=spec.segments,
            )
        )
    recordings = _check_magnitudes(load_folder(spec.path))
    if spec.sampling_rate_hz is not None and spec.sampling_rate_hz != recordings.fs_hz:
        raise DatasetError(
            f"folder dataset {spec.path}: dataset.sampling_rate_hz = {spec.sampling_rate_hz} Hz "
            f"in the scene contradicts sampling_rate_hz = {recordings.fs_hz} Hz in "
            f"{Path(spec.path) / _FOLDER_TOML} (leave it out of the scene)"
        )
    return recordings


def resolve_dataset_argument(text: str) -> dict[str, str]:
    """Turn the command line's ``--dataset NAME|PATH`` into a scene ``dataset`` table.

    Parameters
    ----------
    text
        ``"synthetic"`` (a name, even if a folder of that name exists), or a path (``~``
        expanded) to a folder holding ``dataset.toml`` (a folder dataset; this wins if the
        folder also holds CSVs) or any of ``X.csv``, ``Y.csv``, ``Z.csv`` (VibTac-12; the loader
        checks that the chosen axis is present).

    Returns
    -------
    dict
        ``{"kind": "synthetic"}``, ``{"kind": "folder", "path": <absolute path>}`` or
        ``{"kind": "vibtac12", "path": <absolute path>}``.

    Raises
    ------
    DatasetError
        The bare name ``vibtac12`` (the data is not shipped: it needs a path), a missing path, a
        path that is not a folder, or a folder of neither layout.
    """
    if text == DatasetKind.SYNTHETIC.value:
        return {"kind": DatasetKind.SYNTHETIC.value}
    if text == DatasetKind.VIBTAC12.value:
        hint = (
            " (a folder named vibtac12 is here: pass it as ./vibtac12)"
            if Path(text).is_dir()
            else ""
        )
        raise DatasetError(
            "--dataset vibtac12 needs a path: the data is not shipped, pass the folder that "
            f"holds X.csv, Y.csv and Z.csv, e.g. --dataset /path/to/vibtac12{hint}"
        )
    if not text.strip():
        raise DatasetError("--dataset is empty: give 'synthetic' or a path to a dataset folder")
    path = Path(text).expanduser().resolve()
    _require_folder(path, f"--dataset {text}: path {path}")
    if (path / _FOLDER_TOML).is_file():
        return {"kind": DatasetKind.FOLDER.value, "path": str(path)}
    if any((path / name).is_file() for name in _VIBTAC_FILES):
        return {"kind": DatasetKind.VIBTAC12.value, "path": str(path)}
    raise DatasetError(
        f"--dataset {text}: folder {path} is not a dataset: expected {_FOLDER_TOML} plus one "
        "sub-folder per class (a folder dataset) or X.csv, Y.csv, Z.csv (VibTac-12)"
    )


def _require_folder(path: Path, label: str) -> None:
    """Raise ``"<label> does not exist"`` or ``"<label> is not a directory"``."""
    if not path.exists():
        raise DatasetError(f"{label} does not exist")
    if not path.is_dir():
        raise DatasetError(f"{label} is not a directory")


# ---------------------------------------------------------------------------------------------
# VibTac-12


def load_vibtac12(
    path: str | os.PathLike[str],
    *,
    sampling_rate_hz: float = VIBTAC12_DEFAULT_RATE_HZ,
    axis: Axis | str = Axis.Z,
    segments: int = 10,
) -> Recordings:
    """Load one accelerometer axis of VibTac-12, cut into segments.

    Parameters
    ----------
    path
        Folder holding ``X.csv``, ``Y.csv``, ``Z.csv`` (only the chosen axis is read).
    sampling_rate_hz
        Sampling rate (Hz, > 0); undocumented by the authors, 200 Hz is the best estimate.
    axis
        ``Axis.X``, ``Axis.Y`` or ``Axis.Z`` (or ``"x"``, ``"y"``, ``"z"``, any case).
    segments
        Equal, non-overlapping segments per row (>= 1); each is one recording.

    Returns
    -------
    Recordings
        ``12 * segments`` recordings of ``(L - 3) // segments`` samples each (399 for the real
        4000-column files and 10 segments), ordered texture-major; labels ``0..11``, class names
        ``"Texture1".."Texture12"``, recording names ``"Texture3/segment07"`` (1-based), units
        ``"counts"``, name ``"vibtac12-<axis>"``.

    Raises
    ------
    DatasetError
        Missing folder or file, binary or non-numeric content (file and line named), a row count
        other than 12, rows too short for ``segments`` segments of 2 samples, or a non-finite
        value (recording, sample and file position named).
    """
    try:
        axis = Axis(str(axis.value if isinstance(axis, Axis) else axis).lower())
    except ValueError:
        raise DatasetError(f"vibtac12 axis {axis!r} is not one of 'x', 'y', 'z'") from None
    rate = positive_number(sampling_rate_hz)
    if rate is None:
        raise DatasetError(f"vibtac12 sampling_rate_hz must be > 0, got {sampling_rate_hz!r}")
    if whole_number(segments, 1) is None:
        raise DatasetError(f"vibtac12 segments must be an integer >= 1, got {segments!r}")
    segments = int(segments)
    root = Path(path)
    head = f"vibtac12 dataset {root}"
    _require_folder(root, head)
    file = root / f"{axis.value.upper()}.csv"
    if not file.is_file():
        raise DatasetError(f"{head}: file {file.name} for axis {axis.value} does not exist")
    try:
        table = _parse_table(_read_text(file, file.name), file.name, columns=None)
    except ColumnProblem as exc:
        raise DatasetError(message(head, [str(exc)])) from None
    n_rows, n_cols = table.shape
    if n_rows != VIBTAC12_ROWS:
        raise DatasetError(
            f"{head}: {file.name} has {n_rows} rows, expected {VIBTAC12_ROWS} (one per texture)"
        )
    seg_len = (n_cols - VIBTAC12_PADDING) // segments
    if seg_len < 2:
        raise DatasetError(
            f"{head}: {file.name} rows have {n_cols} samples, too few for {segments} segments of "
            f"at least 2 samples after dropping {VIBTAC12_PADDING} padding samples"
        )
    width = max(2, len(str(segments)))
    signals, labels, names, problems = [], [], [], []
    for row in range(n_rows):
        for seg in range(segments):
            start = VIBTAC12_PADDING + seg * seg_len
            signal = table[row, start : start + seg_len]
            name = f"Texture{row + 1}/segment{seg + 1:0{width}d}"
            problem = signal_problem(
                name,
                signal,
                lambda i, r=row, c=start: f"{file.name} row {r + 1}, column {c + i + 1}",
            )
            if problem:
                problems.append(problem)
            signals.append(signal)
            labels.append(row)
            names.append(name)
    if problems:
        raise DatasetError(message(head, problems))
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels, dtype=np.int64),
        class_names=tuple(f"Texture{i + 1}" for i in range(n_rows)),
        fs_hz=rate,
        names=tuple(names),
        units="counts",
        name=f"vibtac12-{axis.value}",
    )


# ---------------------------------------------------------------------------------------------
# Folder datasets


def load_folder(path: str | os.PathLike[str]) -> Recordings:
    """Load a folder dataset: ``dataset.toml`` plus one sub-folder of recordings per class.

    Parameters
    ----------
    path
        The dataset folder. ``dataset.toml`` holds ``sampling_rate_hz`` (number > 0, required),
        ``name`` (string, default: the folder's name), ``units`` (string, default ``"a.u."``)
        and ``description`` (free text for people reading the folder; not loaded).
        Each non-hidden sub-folder is a class (sorted by name; the folder name is the class
        name) holding one recording per file, sorted by file name: ``.csv`` with one numeric
        column, no header (blank lines only at the end), UTF-8; or ``.npy`` with a 1-D integer
        or floating-point array (read without unpickling). An array dataset's files are CSVs
        with a header line or 2-D ``.npy`` arrays, and ``dataset.toml`` may hold ``taxels``,
        ``time_column`` and ``time_unit``, ``taxel_positions_mm``
        (:mod:`pipeline.recordings.taxel_columns`).

    Returns
    -------
    Recordings
        Labels in class-folder order; recording names ``"<class>/<file name>"``; for an array,
        ``taxel_names`` in the declared (or the first recording's) order and the positions.

    Raises
    ------
    DatasetError
        One line listing every problem found: missing or non-folder path; ``dataset.toml``
        missing, not TOML, without a valid ``sampling_rate_hz``, with a ``description`` that is
        not a string or with unknown keys; no class folders; a class folder without recordings;
        a file of another type or a folder inside a class folder; a binary or non-numeric CSV
        (file and line), a CSV with more than one column, an empty recording, a recording
        shorter than 2 samples, a non-finite value (recording and first bad sample); a ``.npy``
        that is not a valid ``.npy`` file, not 1-D or 2-D or not numeric. For an array:
        recordings with different taxel sets (or a one-column recording among them), a missing
        taxel or time column, a non-numeric or non-finite value in one (file, line and column
        named), a time column that does not increase, positions whose count differs from the
        taxels', a time column with ``sampling_rate_hz`` or without ``time_unit``.
    """
    root = Path(path)
    head = f"folder dataset {root}"
    _require_folder(root, head)
    problems: list[str] = []
    meta, data = _read_dataset_toml(root / _FOLDER_TOML, problems)
    try:
        class_dirs = sorted(
            (p for p in root.iterdir() if not p.name.startswith(".") and p.is_dir()),
            key=lambda p: p.name,
        )
    except OSError as exc:
        raise DatasetError(f"{head}: cannot list the folder: {exc.strerror}") from None
    if not class_dirs:
        problems.append("no class folders (expected one sub-folder of recordings per class)")
    layout = column_layout(data, _FOLDER_TOML, problems)
    signals, labels, names = [], [], []
    for label, class_dir in enumerate(class_dirs):
        try:
            entries = sorted(
                (p for p in class_dir.iterdir() if not p.name.startswith(".")),
                key=lambda p: p.name,
            )
        except OSError as exc:
            problems.append(f"{class_dir.name}/: cannot list the folder: {exc.strerror}")
            continue
        n_found = 0
        for entry in entries:
            rel = f"{class_dir.name}/{entry.name}"
            if entry.is_dir():
                problems.append(f"{rel}/: a folder inside a class folder (expected files)")
                continue
            suffix = entry.suffix.lower()
            if suffix not in _RECORDING_SUFFIXES:
                problems.append(f"{rel}: not a recording (expected a .csv or .npy file)")
                continue
            n_found += 1
            try:
                signal = _read_recording(entry, rel, suffix, layout)
            except ColumnProblem as exc:
                problems.append(str(exc))
                continue
            if isinstance(signal, TaxelRecording):
                problem = signal_problem(rel, signal.signal)
            elif suffix == ".csv":
                problem = signal_problem(rel, signal, lambda i: f"line {i + 1}")
            else:
                problem = signal_problem(rel, signal)
            if problem:
                problems.append(problem)
                continue
            signals.append(signal)
            labels.append(label)
            names.append(rel)
        if n_found == 0:
            problems.append(f"{class_dir.name}/: class folder holds no recordings (.csv, .npy)")
    arrays = [s for s in signals if isinstance(s, TaxelRecording)]
    problems += mixed_problems(names, signals, layout)
    taxels = taxel_set(arrays, layout, meta.get("sampling_rate_hz"), problems, _FOLDER_TOML)
    if not problems:
        problems = [p for p in map(signal_problem, names, taxels.signals) if p]
    if problems:
        raise DatasetError(message(head, problems))
    return Recordings(
        signals=taxels.signals or tuple(signals),
        labels=np.array(labels, dtype=np.int64),
        class_names=tuple(p.name for p in class_dirs),
        fs_hz=taxels.fs_hz or meta["sampling_rate_hz"],
        names=tuple(names),
        units=meta.get("units", "a.u."),
        name=meta.get("name", root.resolve().name),
        taxel_names=taxels.taxels,
        taxel_positions_mm=taxels.positions_mm,
    )


def _read_recording(
    file: Path, where: str, suffix: str, layout: ColumnLayout
) -> np.ndarray | TaxelRecording:
    """One recording: a 1-D signal (a headerless one-column CSV, a 1-D ``.npy``) or its taxels
    (a CSV with a header line, a 2-D ``.npy``). Raises :class:`ColumnProblem`."""
    if suffix == ".npy":
        array = _read_npy(file, where)
        return array if array.ndim == 1 else taxel_recording(npy_columns(array), layout, where)
    text = _read_text(file, where)
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if lines and header_of(lines) is not None:
        wanted = {*layout.taxels, *([layout.time_column] if layout.time_column else [])}
        table = parse_with_header(lines, where, wanted if layout.taxels else None)
        return taxel_recording(table, layout, where)
    return _parse_table(text, where, columns=1)[:, 0]


def _read_dataset_toml(file: Path, problems: list[str]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Validated ``dataset.toml`` scalars and the parsed table (for the array keys); problems are
    appended, not raised."""
    where = file.name
    if not file.is_file():
        problems.append(f"{where}: missing (it must give sampling_rate_hz)")
        return {}, {}
    try:
        data = tomllib.loads(file.read_text(encoding="utf-8"))
    except OSError as exc:
        problems.append(f"{where}: cannot read: {exc.strerror}")
        return {}, {}
    except UnicodeDecodeError:
        problems.append(f"{where}: not UTF-8 text")
        return {}, {}
    except tomllib.TOMLDecodeError as exc:
        problems.append(f"{where}: not valid TOML: {exc}")
        return {}, {}
    meta: dict[str, Any] = {}
    for key in data:
        if key not in _FOLDER_KEYS:
            problems.append(f"{where}: unknown key {key!r} (known: {', '.join(_FOLDER_KEYS)})")
    if "sampling_rate_hz" not in data and "time_column" not in data:
        problems.append(
            f"{where}: sampling_rate_hz is missing (required, in Hz, unless a time_column gives it)"
        )
    elif "sampling_rate_hz" in data:
        rate = positive_number(data["sampling_rate_hz"])
        if rate is None:
            problems.append(
                f"{where}: sampling_rate_hz = {data['sampling_rate_hz']!r} is not a number > 0"
            )
        else:
            meta["sampling_rate_hz"] = rate
    for key in ("name", "units"):
        if key in data:
            if isinstance(data[key], str) and data[key].strip():
                meta[key] = data[key]
            else:
                problems.append(f"{where}: {key} = {data[key]!r} is not a non-empty string")
    if "description" in data and not isinstance(data["description"], str):
        problems.append(f"{where}: description = {data['description']!r} is not a string")
    return meta, data


def _read_text(file: Path, where: str) -> str:
    """A text file's contents; binary data (NUL bytes, invalid UTF-8) is a problem."""
    try:
        data = file.read_bytes()
    except OSError as exc:
        raise ColumnProblem(f"{where}: cannot read: {exc.strerror}") from None
    nul = data.find(b"\x00")
    if nul >= 0:
        raise ColumnProblem(f"{where}: binary data, not text (NUL byte at offset {nul})")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ColumnProblem(f"{where}: binary data, not UTF-8 text (byte {exc.start})") from None


def _parse_table(text: str, where: str, *, columns: int | None) -> np.ndarray:
    """Parse comma-separated numbers, one row per line; trailing blank lines are allowed.

    Returns float64, shape ``(n_lines, n_columns)``. ``columns`` is the required column count
    (``None``: any, but the same on every line). Raises :class:`ColumnProblem` naming ``where`` and
    the first bad line (1-based), with a count of further bad lines.
    """
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise ColumnProblem(f"{where}: empty recording (no samples)")
    table = None
    if all(line.strip() for line in lines):
        try:
            table = np.loadtxt(lines, delimiter=",", comments=None, ndmin=2, dtype=np.float64)
        except ValueError:
            table = None
    if table is not None and (columns is None or table.shape[1] == columns):
        return table
    raise ColumnProblem(_diagnose_table(lines, where, columns))


def _diagnose_table(lines: Iterable[str], where: str, columns: int | None) -> str:
    """The first problem in a table that failed to parse, and how many lines are bad."""
    bad: list[str] = []
    expected = columns
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            bad.append(f"line {number} is empty")
            continue
        fields = line.split(",")
        if expected is None:
            expected = len(fields)
        if len(fields) != expected:
            want = "one column" if expected == 1 else f"{expected} columns"
            hint = " (several taxels need a header line naming the columns)" * (expected == 1)
            bad.append(f"line {number} has {len(fields)} columns, expected {want}{hint}")
            continue
        for column, field in enumerate(fields, start=1):
            if not _NUMBER.fullmatch(field):
                shown = field.strip()
                shown = shown if len(shown) <= 40 else shown[:37] + "..."
                col = f", column {column}" if expected != 1 else ""
                hint = " (a header line is not allowed)" if number == 1 else ""
                bad.append(f"line {number}{col}: {shown!r} is not a number{hint}")
                break
    if not bad:  # pragma: no cover - the diagnosis mirrors the parser
        return f"{where}: not a table of numbers"
    more = f" (and {len(bad) - 1} more bad lines)" if len(bad) > 1 else ""
    return f"{where}: {bad[0]}{more}"


def _read_npy(file: Path, where: str) -> np.ndarray:
    """A 1-D or 2-D numeric ``.npy`` array as float64, read without unpickling."""
    try:
        with file.open("rb") as handle:
            if handle.read(6) != b"\x93NUMPY":
                raise ColumnProblem(f"{where}: not a .npy file (bad magic bytes)")
            handle.seek(0)
            array = np.lib.format.read_array(handle, allow_pickle=False)
    except ColumnProblem:
        raise
    except OSError as exc:
        raise ColumnProblem(f"{where}: cannot read: {exc.strerror or exc}") from None
    except (ValueError, EOFError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ColumnProblem(f"{where}: unreadable .npy ({reason})") from None
    if array.dtype.kind not in "iuf":
        raise ColumnProblem(
            f"{where}: .npy holds {array.dtype} values, expected integers or floats"
        )
    if array.ndim not in (1, 2):
        raise ColumnProblem(
            f"{where}: .npy array has shape {array.shape}, expected 1-D or (samples, taxels)"
        )
    return array.astype(np.float64)
