"""What the ``eskin`` commands print: one JSON object or text on stdout, progress on stderr.

JSON numbers that are infinite or NaN are written as the strings ``"inf"``, ``"-inf"`` and
``"nan"`` (:func:`flows.summaries.json_safe`): JSON has neither, and ``float("inf")`` reads them
back. Output whose unknowns are already ``null`` is written strictly, refusing any NaN left.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Mapping
from typing import Any

from flows.summaries import json_safe

__all__ = ["StageProgress", "format_server_info", "print_out", "with_record_access"]

#: The summary's key for the file that holds the local Prefect server's auth string.
AUTH_STRING_FILE = "auth_string_file"


def print_out(
    as_json: bool, value: Any, text: Callable[[Any], str], *, strict: bool = False
) -> None:
    """Print ``value`` as one indented JSON object (``as_json``) or as ``text(value)``.

    ``strict``: ``value`` states its unknowns as ``None`` already; a NaN or infinity left in it
    raises ``ValueError`` instead of being written as a string.
    """
    if not as_json:
        print(text(value))
    elif strict:
        print(json.dumps(value, indent=2, allow_nan=False))
    else:
        print(json.dumps(json_safe(value), indent=2))


def format_server_info(info: Mapping[str, Any]) -> str:
    """The text ``eskin server start|status|stop`` prints of what it found or did (``info``:
    ``running``, and ``stopped``, ``api_url``, ``ui_url``, ``pid``, ``auth_string_file``,
    ``state_dir`` as the action gives them)."""
    if "stopped" in info:
        return "stopped the Prefect server" if info["stopped"] else "no Prefect server was running"
    if not info["running"]:
        return f"no Prefect server running (state in {info['state_dir']})"
    lines = [
        f"Prefect server: {info['ui_url']}" + (f" (PID {info['pid']})" if "pid" in info else "")
    ]
    if AUTH_STRING_FILE in info:
        lines.append(f"The UI asks for the auth string in {info[AUTH_STRING_FILE]}")
    return "\n".join(lines)


def with_record_access(text: str, summary: Mapping[str, Any]) -> str:
    """A run's printed summary ``text`` with, after its Prefect link, where the UI's login
    string is: the local server's UI asks for its auth string once per browser, and the file
    that holds it is named (never the string itself). Unchanged when the summary names no
    flow run or no such file (a server named by ``PREFECT_API_URL`` is the user's own)."""
    if not (summary.get("flow_run_url") and summary.get(AUTH_STRING_FILE)):
        return text
    return (
        f"{text}\nThe Prefect UI asks once per browser for its auth string: paste the content "
        f"of {summary[AUTH_STRING_FILE]} (eskin server status names it too)."
    )


class StageProgress:
    """A tqdm bar over a run's stages, on stderr, shown only on a terminal."""

    def __init__(self, stages: tuple[str, ...], enabled: bool):
        from tqdm import tqdm

        self.bar = tqdm(
            total=len(stages),
            unit="stage",
            file=sys.stderr,
            disable=None if enabled else True,
            leave=False,
        )
        self.started = 0

    def advance(self, stage: str) -> None:
        """Mark the stage before as done and ``stage`` as running."""
        if self.started:
            self.bar.update(1)
        self.started += 1
        self.bar.set_description(stage)

    def close(self) -> None:
        """Take the bar off the terminal."""
        self.bar.close()
