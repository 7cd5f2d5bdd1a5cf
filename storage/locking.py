"""The sweep lock: one sweep per run root, held with ``fcntl.flock`` for the sweep's life.

The kernel drops the lock when its process ends, however it ends (SIGKILL included), so a killed
sweep never blocks the next one. ``flock`` is advisory and, on network file systems, only as
good as the file system's support for it.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import socket
import threading
from collections.abc import Iterator
from pathlib import Path

from storage.errors import StoreBusyError, StoreError, one_line

LOCK_NAME = "store.lock"

# Locks this process holds: resolved lock path -> [file descriptor, nesting depth].
_LOCKS: dict[str, list[int]] = {}
_LOCKS_GUARD = threading.Lock()


@contextlib.contextmanager
def hold_lock(root: Path) -> Iterator[None]:
    """Hold ``root``'s exclusive sweep lock for the ``with`` block (see
    :meth:`storage.store.SweepStore.lock`)."""
    path = root / LOCK_NAME
    name = str(path.resolve())
    with _LOCKS_GUARD:
        held = _LOCKS.get(name)
        if held is not None:
            held[1] += 1
        else:
            _LOCKS[name] = [_acquire(path, root), 1]
    try:
        yield
    finally:
        with _LOCKS_GUARD:
            held = _LOCKS[name]
            held[1] -= 1
            if held[1] == 0:
                del _LOCKS[name]
                os.close(held[0])  # closing the last descriptor releases the flock


def _acquire(path: Path, root: Path) -> int:
    """Open ``path`` and take its exclusive flock without waiting; return the descriptor."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as error:
        raise StoreError(f"cannot open the lock of run root {root}: {one_line(error)}") from error
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as error:
        os.close(fd)
        if error.errno not in (errno.EAGAIN, errno.EACCES):
            raise StoreError(f"cannot lock run root {root}: {one_line(error)}") from error
        try:
            holder = path.read_text(encoding="utf-8").strip() or "unknown"
        except (OSError, UnicodeDecodeError):
            holder = "unknown"
        raise StoreBusyError(
            f"run root {root} is in use by another sweep (PID {holder[:80]}); wait for it to "
            "finish or give another --root"
        ) from None
    # The holder, for the message a refused sweep prints. The flock alone is the lock: on a
    # full disk the note is left out (a refused sweep then names the holder "unknown"), and
    # the sweep stops at its first write of data instead, saying so.
    with contextlib.suppress(OSError):
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()} on {socket.gethostname()}\n".encode())
    return fd
