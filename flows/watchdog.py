"""Stop a helper process when the process that started it dies, however it dies.

``python -m flows.watchdog PID MARKER`` blocks reading its stdin, a pipe whose other end only
the parent holds. End of file means the parent is gone (it exited, or was killed, SIGKILL
included); the watchdog then sends SIGTERM to ``PID``, and SIGKILL after ``GRACE_S``, but only
if ``/proc/PID/cmdline`` still contains ``MARKER``, so that a reused PID is left alone. Linux
only (elsewhere it finds no ``/proc`` entry and does nothing).

The sweep command uses it for Prefect's temporary server, which Prefect starts as a plain
subprocess that would otherwise outlive a killed sweep.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

GRACE_S = 5.0


def start(pid: int, marker: str) -> subprocess.Popen:
    """Start a watchdog for ``pid``; keep the returned object alive as long as ``pid`` should run.

    The watchdog runs in its own session, so a Ctrl-C in the terminal does not reach it.
    """
    return subprocess.Popen(
        [sys.executable, "-m", "flows.watchdog", str(pid), marker],
        stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )


def _matches(pid: int, marker: str) -> bool:
    try:
        cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return False
    return marker.encode() in cmdline


def main(argv: list[str]) -> int:
    pid, marker = int(argv[0]), argv[1]
    sys.stdin.buffer.read()  # returns at end of file: the parent is gone
    if not _matches(pid, marker):
        return 0
    os.kill(pid, signal.SIGTERM)
    deadline = time.monotonic() + GRACE_S
    while time.monotonic() < deadline:
        if not _matches(pid, marker):
            return 0
        time.sleep(0.1)
    if _matches(pid, marker):
        os.kill(pid, signal.SIGKILL)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
