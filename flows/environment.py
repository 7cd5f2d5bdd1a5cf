"""Keep runs hermetic and offline: tool state under the run root, no telemetry.

Settings the user already made win (``setdefault``): a user with a real Prefect server keeps
``PREFECT_API_URL`` and their ``PREFECT_HOME``.
"""

from __future__ import annotations

import os
from pathlib import Path

STATE_DIR = ".state"


def hermetic_environment(root: Path, *, prefect: bool = True) -> None:
    """Point Prefect, Dask and matplotlib at folders under ``root/.state``; keep them offline.

    Must run before Prefect is imported (it reads its settings at import).
    """
    state = Path(root) / STATE_DIR
    defaults = {
        "DASK_TEMPORARY_DIRECTORY": state / "dask",
        "MPLCONFIGDIR": state / "matplotlib",
        "DO_NOT_TRACK": "1",
    }
    if prefect:
        defaults |= {
            "PREFECT_HOME": state / "prefect",
            "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
            "PREFECT_SERVER_API_HOST": "127.0.0.1",
        }
    for name, value in defaults.items():
        if name in os.environ:
            continue
        if isinstance(value, Path):  # the tools do not create their folders' parents
            value.mkdir(parents=True, exist_ok=True)
        os.environ[name] = str(value)
