"""The run log of a run root: one JSON line per finished ``eskin sweep``, for the report.

``<root>/sweep-runs.jsonl`` holds objects ``{"finished", "grid", "points", "cache_hits",
"computed", "seconds"}`` (``finished`` an ISO 8601 UTC time, ``seconds`` the sweep's wall time).
Each record is appended with one ``write`` on a file opened with ``O_APPEND``, so concurrent sweeps
on one root do not interleave their lines; a line that does not parse (a torn write after a power
loss) is skipped when reading.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from pipeline.report.cost import SweepRun, sweep_run_from_record

RUN_LOG = "sweep-runs.jsonl"


def append_sweep_run(root: str | Path, summary: Mapping[str, Any]) -> None:
    """Append one record from a sweep's summary (``grid``, ``points``, ``cache_hits``, ...)."""
    record = {
        "finished": datetime.now(UTC).isoformat(timespec="seconds"),
        **{k: summary[k] for k in ("grid", "points", "cache_hits", "computed", "seconds")},
    }
    line = (json.dumps(record, sort_keys=True) + "\n").encode()
    fd = os.open(Path(root) / RUN_LOG, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        os.write(fd, line)
    finally:
        os.close(fd)


def read_sweep_runs(root: str | Path) -> list[SweepRun]:
    """The logged sweeps of ``root``, oldest first (none if there is no log)."""
    path = Path(root) / RUN_LOG
    if not path.is_file():
        return []
    runs = []
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            runs.append(sweep_run_from_record(json.loads(line)))
        except (ValueError, KeyError, TypeError):
            continue
    return runs
