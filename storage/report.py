"""The report folder on disk: written whole from its files, swapped in atomically.

The folder (``<root>/report`` by default) holds the files that
:func:`pipeline.report.document.report_files` makes, plus the marker ``.eskin-report``: this
folder is a report and may be replaced. It is built in full under a temporary name beside the
target and then swapped in with :func:`storage.cube_files.replace_folder`, so the target is always
a whole report, old or new, never half of one. A target that exists and is neither empty nor a
report (no marker) is refused: a user's own folder is never replaced.
"""

from __future__ import annotations

import shutil
import uuid
from collections.abc import Mapping
from pathlib import Path, PurePosixPath

from storage.store import StoreError, replace_folder

MARKER = ".eskin-report"


def check_report_folder(out: str | Path) -> None:
    """Refuse ``out`` unless it is missing, an empty folder or an earlier report.

    Raises
    ------
    StoreError
        ``out`` is a file or a symlink, or a non-empty folder without the report marker.
    """
    out = Path(out)
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise StoreError(f"refusing report folder {out}: it is not a directory")
    if out.is_dir():
        contents = sorted(p.name for p in out.iterdir())
        if contents and MARKER not in contents:
            shown = ", ".join(contents[:3]) + (", ..." if len(contents) > 3 else "")
            raise StoreError(f"refusing report folder {out}: not empty and not a report ({shown})")


def write_report_folder(out: str | Path, files: Mapping[str, bytes]) -> Path:
    """Replace the report folder ``out`` whole by ``files`` and the marker; return ``out``.

    Parameters
    ----------
    out
        The report folder; its parents are made as needed.
    files
        ``{relative POSIX path: content}``; folders in the paths are made.

    Raises
    ------
    StoreError
        ``out`` is refused (:func:`check_report_folder`), a path leaves the folder or is the
        marker, or the folder cannot be written.
    """
    out = Path(out)
    check_report_folder(out)
    for name in files:
        path = PurePosixPath(name)
        if path.is_absolute() or ".." in path.parts or not path.parts or name == MARKER:
            raise StoreError(f"cannot write the report to {out}: bad file name {name!r}")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.parent / f".{out.name}-partial-{uuid.uuid4().hex}"
        partial.mkdir()
    except OSError as error:
        raise StoreError(f"cannot write the report to {out}: {error}") from error
    try:
        for name, content in files.items():
            target = partial.joinpath(*PurePosixPath(name).parts)
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(content)
        (partial / MARKER).write_text("written by eskin report\n", encoding="utf-8")
        replace_folder(partial, out)
    except OSError as error:
        raise StoreError(f"cannot write the report to {out}: {error}") from error
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    return out
