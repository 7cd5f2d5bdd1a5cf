"""The run log of a run root: one JSON line per finished ``eskin sweep``, for the report.

``<root>/sweep-runs.jsonl`` holds objects ``{"finished", "grid", "points", "cache_hits",
"computed", "seconds"}`` (``finished`` an ISO 8601 UTC time, ``seconds`` the sweep's wall time).
Each record is appended with one ``write`` on a file opened with ``O_APPEND``, so concurrent sweeps
on one root do not interleave their lines; a line that is not a JSON object (a torn write after a
power loss) is skipped when reading. An object root cannot append: each record is an object of
its own there (:meth:`storage.object_root.ObjectRoot.append_run`). What a record means is the
report's business (:func:`pipeline.report.cost.sweep_runs`).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from storage.object_root import ObjectRoot
from storage.objects import is_object_url, objects_for

RUN_LOG = "sweep-runs.jsonl"


def append_sweep_run(root: str | Path, summary: Mapping[str, Any]) -> None:
    """Append one record from a sweep's summary (``grid``, ``points``, ``cache_hits``, ...)."""
    record = {
        "finished": datetime.now(UTC).isoformat(timespec="seconds"),
        **{k: summary[k] for k in ("grid", "points", "cache_hits", "computed", "seconds")},
    }
    line = (json.dumps(record, sort_keys=True) + "\n").encode()
    if is_object_url(root):
        ObjectRoot(objects_for(root)).append_run(line)
        return
    fd = os.open(Path(root) / RUN_LOG, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        os.write(fd, line)
    finally:
        os.close(fd)


def read_sweep_records(root: str | Path) -> list[dict[str, Any]]:
    """The logged sweeps of ``root`` as JSON objects, oldest first (none if there is no log)."""
    if is_object_url(root):
        text = b"".join(ObjectRoot(objects_for(root)).run_lines()).decode(errors="replace")
    else:
        path = Path(root) / RUN_LOG
        if not path.is_file():
            return []
        text = path.read_text(encoding="utf-8", errors="replace")
    records = []
    for line in text.splitlines():
        try:
            record = json.loads(line)
        except ValueError:
            continue
        if isinstance(record, dict):
            records.append(record)
    return records
