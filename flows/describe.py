"""``eskin describe``: print a dataset's description, and export its recordings as a folder.

The description is :func:`pipeline.recordings.describe.describe_dataset`'s; this module only lays it
out as text and writes the folder dataset that :func:`pipeline.recordings.describe.folder_layout`
names.

The export is never half-written: the folder is built under a hidden temporary name beside the
target and renamed into place in one step (a rename onto an existing empty folder replaces it;
onto a non-empty one it fails, so a user's folder is never replaced). On any failure the
temporary folder is removed.
"""

from __future__ import annotations

import errno
import math
import os
import shutil
import tempfile
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.design.scene import DatasetKind, DatasetSpec
from pipeline.errors import EskinError
from pipeline.recordings.describe import (
    CLASS_MEDIANS,
    Comparison,
    DatasetDescription,
    class_median_range,
    folder_layout,
    typical_text,
)
from pipeline.recordings.describe_array import ArrayDescription
from pipeline.recordings.sources import Recordings

__all__ = ["Export", "ExportError", "check_export_folder", "export_folder", "format_description"]


#: Warnings are wrapped to lines of this many characters.
WIDTH = 100


class ExportError(EskinError):
    """The export folder is refused or cannot be written; the message names it."""


@dataclass(frozen=True)
class Export:
    """A written folder dataset: where, how many recordings, which class names changed."""

    path: Path
    n_recordings: int
    renamed: tuple[str, ...]

    def to_json(self) -> dict[str, object]:
        """The export as plain JSON values, as ``eskin describe --export DIR --json`` prints it:
        ``{"path", "n_recordings", "renamed"}`` (the path as text, the renamed classes as a
        list)."""
        return {
            "path": str(self.path),
            "n_recordings": self.n_recordings,
            "renamed": list(self.renamed),
        }


def dataset_spec(argument: str | None) -> DatasetSpec:
    """The recordings ``eskin describe --dataset`` names: the paper scene's when ``None``."""
    from pipeline.design.scene import Scene
    from pipeline.recordings.sources import resolve_dataset_argument

    scene = Scene.paper()
    if argument is not None:
        override = resolve_dataset_argument(argument)
        scene = scene.replace(**{f"dataset.{k}": v for k, v in override.items()})
    return scene.dataset


def check_export_folder(target: str | os.PathLike[str], dataset: DatasetSpec | None = None) -> Path:
    """The absolute export folder, if it may be written: missing or an empty folder.

    Raises
    ------
    ExportError
        ``target`` is a file or a symlink, a non-empty folder, its parent is not a folder, or
        it lies inside the folder of ``dataset`` (it would become one of its classes).
    """
    path = Path(target).expanduser().absolute()
    head = f"--export {target}: folder {path}"
    if (
        dataset is not None
        and dataset.path
        and path.resolve().is_relative_to(Path(dataset.path).resolve())
    ):
        raise ExportError(f"{head} is inside the dataset folder {dataset.path}")
    if path.is_symlink() or (path.exists() and not path.is_dir()):
        raise ExportError(f"{head} is not a directory")
    if path.is_dir():
        try:
            contents = sorted(p.name for p in path.iterdir())
        except OSError as error:
            raise ExportError(f"{head} cannot be listed: {error.strerror}") from None
        if contents:
            shown = ", ".join(contents[:3]) + (", ..." if len(contents) > 3 else "")
            raise ExportError(f"{head} is not empty ({shown}): give a new or empty folder")
    if not path.parent.is_dir():
        raise ExportError(f"{head}: parent folder {path.parent} does not exist")
    return path


def export_folder(
    recordings: Recordings, target: str | os.PathLike[str], *, source: str = ""
) -> Export:
    """Write ``recordings`` as a folder dataset at ``target`` (see the module docstring).

    Layout and names: :func:`pipeline.recordings.describe.folder_layout`; each recording a float64
    1-D ``.npy`` written without pickling, or for an array a CSV whose header names the taxels.

    Raises
    ------
    ExportError
        ``target`` is refused (:func:`check_export_folder`) or cannot be written; nothing is
        left behind.
    """
    path = check_export_folder(target)
    layout = folder_layout(recordings, source=source)
    try:
        partial = Path(tempfile.mkdtemp(prefix=f".{path.name}-partial-", dir=path.parent))
    except OSError as error:
        raise ExportError(_cannot_write(target, path, error)) from None
    try:
        (partial / "dataset.toml").write_text(layout.toml, encoding="utf-8")
        for folder in layout.class_folders:
            (partial / folder).mkdir()
        for file, signal in zip(layout.files, recordings.signals, strict=True):
            with (partial / file).open("xb") as handle:
                if recordings.is_array:
                    handle.write(_header_csv(recordings.taxel_names, signal).encode())
                    continue
                np.lib.format.write_array(
                    handle, np.ascontiguousarray(signal, dtype=np.float64), allow_pickle=False
                )
        partial.chmod(0o777 & ~_umask())
        try:
            os.rename(partial, path)
        except OSError as error:
            if error.errno in (errno.ENOTEMPTY, errno.EEXIST):
                raise ExportError(
                    f"--export {target}: folder {path} is not empty (it filled up during the "
                    "export): give a new or empty folder"
                ) from None
            raise
    except OSError as error:
        raise ExportError(_cannot_write(target, path, error)) from None
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    return Export(path=path, n_recordings=recordings.n_recordings, renamed=layout.renamed)


def _header_csv(names: tuple[str, ...], signal: np.ndarray) -> str:
    """A CSV with a header line; ``repr`` gives the shortest decimals that read back exactly."""
    rows = (",".join(map(repr, row)) for row in signal.tolist())
    return ",".join(names) + "\n" + "\n".join(rows) + "\n"


def _cannot_write(target: object, path: Path, error: OSError) -> str:
    return f"--export {target}: cannot write folder {path}: {error.strerror or error}"


def _umask() -> int:
    # mkdtemp makes a private folder; the export gets the permissions of any new folder.
    mask = os.umask(0)
    os.umask(mask)
    return mask


def describe_source(spec: DatasetSpec) -> str:
    """Where recordings come from, for the exported ``dataset.toml``."""
    if DatasetKind(spec.kind) is DatasetKind.SYNTHETIC:
        return f"the built-in data (seed {spec.seed})"
    return str(spec.path)


# ---------------------------------------------------------------------------------------------
# Text


def format_description(description: DatasetDescription, export: Export | None = None) -> str:
    """The description as lines of text: facts, classes, statistics beside real, warnings."""
    f = description.facts
    stats = description.statistics
    counts = set(f.recordings_per_class)
    per_class = (
        f"{f.recordings_per_class[0]} per class"
        if len(counts) == 1
        else f"{min(counts)} to {max(counts)} per class"
    )
    lines = [
        f"dataset     {f.name}: {f.n_recordings} recordings, {len(f.class_names)} classes",
        f"touches     {per_class}",
        f"sampling    {f.fs_hz:g} Hz, units {f.units}",
        f"durations   {f.duration_min_s:.4g} / {f.duration_median_s:.4g} / "
        f"{f.duration_max_s:.4g} s (min / median / max)",
        f"windows     {f.n_windows} of {f.window_s:g} s in the shortest recording "
        f"(the paper codes {f.max_windows})",
        "",
    ]
    class_rows = [
        (
            "class",
            "touches",
            f"RMS ({f.units})",
            "centroid Hz",
            "bandwidth Hz",
            "5-20 Hz share",
            "floor ratio",
        )
    ]
    for c, (name, n) in enumerate(zip(f.class_names, f.recordings_per_class, strict=True)):
        measured = (
            (
                stats.class_rms[c],
                stats.class_centroid_hz[c],
                stats.class_bandwidth_hz[c],
                stats.class_modulation_share[c],
                stats.class_floor_ratio[c],
            )
            if stats is not None
            else (math.nan,) * 5
        )
        class_rows.append((name, str(n), *(_number(v, 3) for v in measured)))
    lines += _table(class_rows)
    lines.append("")
    stat_rows = [("statistic", "this dataset", "real 12x10", "real range", "judged")]
    for comparison in description.comparisons:
        stat_rows.append(
            (
                comparison.name,
                _value(comparison, description),
                typical_text(comparison.reference),
                _range(comparison),
                comparison.verdict.value,
            )
        )
    lines += _table(stat_rows)
    lines.append("")
    if description.array is not None:
        lines += _array_lines(description.array, f.units)
        lines.append("")
    if description.warnings:
        lines.append("warnings")
        for warning in description.warnings:
            lines += textwrap.wrap(warning, WIDTH, initial_indent="  - ", subsequent_indent="    ")
    else:
        lines.append("no warnings")
    if export is not None:
        lines.append("")
        lines.append(f"exported {export.n_recordings} recordings to {export.path}")
        lines += [f"  class renamed: {r}" for r in export.renamed]
    return "\n".join(lines)


def _array_lines(array: ArrayDescription, units: str) -> list[str]:
    """The taxels of a real array, and what they say beyond each other."""
    names = [t.name for t in array.taxels]
    where = "positions given" if array.taxels[0].position_mm else "no positions given"
    lines = [f"taxels      {len(names)}: {names[0]} .. {names[-1]} ({where})"]
    rows = [("taxel", "x, y mm", f"level ({units})", "activity (std)", "range", "at rails")]
    for t in array.taxels:
        position = "-" if t.position_mm is None else f"{t.position_mm[0]:g}, {t.position_mm[1]:g}"
        rows.append(
            (
                t.name + (" (dead)" if t.dead else ""),
                position,
                _number(t.level, 4),
                _number(t.activity, 3),
                f"{_number(t.low, 4)} to {_number(t.high, 4)}",
                f"{t.rail_share:.1%}",
            )
        )
    lines += _table(rows)
    lines.append("")
    lines += textwrap.wrap(
        f"taxels say  envelopes correlate {_number(array.envelope_corr_taxels)} between taxels "
        "(median); a plain classifier (logistic regression on 4 statistics per taxel over the "
        f"first {array.span_s:.3g} s, {array.folds}-fold) reads:",
        WIDTH,
        subsequent_indent=" " * 12,
    )
    rows = [("taxels read", "accuracy")]
    rows += [
        (
            f"{len(s.taxels)} ({', '.join(s.taxels) if len(s.taxels) <= 4 else 'evenly spread'})",
            _percent(s.accuracy),
        )
        for s in array.subsets
    ]
    single = sorted(array.single, key=lambda s: (s.accuracy, s.taxels))
    if single:
        rows.append(
            (
                "each alone",
                f"{_percent(single[0].accuracy)} ({single[0].taxels[0]}) to "
                f"{_percent(single[-1].accuracy)} ({single[-1].taxels[0]}), median "
                f"{_percent(float(np.median([s.accuracy for s in single])))}",
            )
        )
    rows.append(("chance", _percent(array.chance)))
    return lines + ["  " + line for line in _table(rows)]


def _percent(value: float) -> str:
    return "n/a" if math.isnan(value) else f"{100 * value:.1f} %"


def _table(rows: list[tuple[str, ...]]) -> list[str]:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return [
        "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
        for row in rows
    ]


def _number(value: float | tuple[float, float], significant: int | None = None) -> str:
    """``significant`` digits, zeros kept; by default 3 decimals below 10 (a correlation of
    0.0047 is "0.005", a decay of 1.003 not "1") and 4 digits above; "n/a" for NaN; a range as
    "low-high"."""
    if isinstance(value, tuple):
        return f"{_number(value[0], significant)}-{_number(value[1], significant)}"
    if math.isnan(value):
        return "n/a"
    if not math.isfinite(value):
        return "inf" if value > 0 else "-inf"
    if significant is None:
        return f"{value:.3f}" if abs(value) < 10 else f"{value:#.4g}"
    return f"{value:#.{significant}g}"


def _value(comparison: Comparison, description: DatasetDescription) -> str:
    text = _number(comparison.value)
    stats = description.statistics
    if comparison.name == "contact_transient" and stats is not None and text != "n/a":
        p10, p90 = stats.contact_transient_p10, stats.contact_transient_p90
        text += f" ({_number(p10)}-{_number(p90)})"
    if comparison.name in CLASS_MEDIANS and text != "n/a":
        text += f" (classes {_number(class_median_range(stats, comparison.name))})"
    return text


def _range(comparison: Comparison) -> str:
    low, high = comparison.reference.low, comparison.reference.high
    if low is None and high is None:
        return "any"
    if high is None:
        return f">= {low:g}"
    if low is None:
        return f"<= {high:g}"
    return f"{low:g}-{high:g}"
