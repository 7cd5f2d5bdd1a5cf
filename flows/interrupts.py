"""How an ``eskin`` command ends when interrupted: within seconds, and with nothing left running.

SIGTERM unwinds like Ctrl-C (a ``KeyboardInterrupt``), so the local Dask cluster is closed and
the store keeps what was written. Run as the program (not called from Python), the first
interrupt also starts a deadline of :data:`UNWIND_S` seconds: whatever the command is stuck in
then (a server or a cluster that is gone, a write, a plan), it kills every process it started
(never the shared Prefect server) and exits with :data:`EXIT_INTERRUPTED`. A command that is
done is given :data:`EXIT_GRACE_S` seconds to exit, so that Prefect's flushes at interpreter
exit (to a server that may be gone, with no timeout of their own) never hold it.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from typing import Any

#: Exit status of an interrupted command (128 + SIGINT, as a shell reports Ctrl-C).
EXIT_INTERRUPTED = 130
#: Seconds from an interrupt (Ctrl-C, SIGTERM) to the hard stop of what the command started. The
#: promise is an exit within 10 s: the hard stop itself (killing, reaping, exiting) took 2.2 s on
#: 2 cores under a load average of 6, so 3 s are left for it.
UNWIND_S = 7.0
#: Seconds a command that is done has to exit before it exits at once.
EXIT_GRACE_S = 5.0

#: Whether an interrupt arrived (Prefect's handler may have turned it into another exception).
signalled = threading.Event()
#: Whether the command runs as the program: only then does it stop processes and exit hard.
_program = threading.Event()


def as_program(program: bool) -> None:
    """Say whether the command runs as the program (``eskin``) or is called from Python."""
    if program:
        _program.set()
    else:
        _program.clear()


def is_program() -> bool:
    """Whether the command runs as the program (:func:`as_program`)."""
    return _program.is_set()


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt(signal.Signals(signum).name)


def handle_interrupts() -> None:
    """SIGTERM unwinds like Ctrl-C, so the local Dask cluster is stopped (the default action
    would kill this process alone). Run as the program, the first interrupt also starts the
    deadline (:data:`UNWIND_S`) after which the command stops what it started and exits.

    The deadline is started from Python's signal wake-up file, written for every signal that
    has a Python handler, whichever handler runs: Prefect replaces this one with its own while a
    flow runs.
    """
    signal.signal(signal.SIGTERM, _interrupt)
    if not is_program():
        return
    read, write = os.pipe()
    os.set_blocking(write, False)
    signal.set_wakeup_fd(write, warn_on_full_buffer=False)

    def watch() -> None:
        while True:
            received = os.read(read, 64)
            if {signal.SIGINT, signal.SIGTERM} & set(received):
                signalled.set()
                exit_after(UNWIND_S, EXIT_INTERRUPTED)
                return

    threading.Thread(target=watch, name="eskin-interrupts", daemon=True).start()


def exit_after(seconds: float, status: int) -> None:
    """Exit with ``status`` in ``seconds`` unless the process has ended by then."""
    timer = threading.Timer(seconds, exit_now, args=(status,))
    timer.daemon = True
    timer.start()


def exit_now(status: int, *, quiet: bool = False) -> None:
    """Exit with ``status`` now; an interrupted command (unless ``quiet``: it said so) first
    kills what it started (never the Prefect server) and says why."""
    if status == EXIT_INTERRUPTED and not quiet:
        stop_started_processes(grace_s=0.0)
        print(
            f"eskin: interrupted (not unwound {UNWIND_S:.0f} s after the signal: what it "
            "started was killed)",
            file=sys.stderr,
        )
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(status)


def stop_started_processes(grace_s: float = 2.0) -> None:
    """Stop every process this command started that still runs (the local Dask workers and
    anything they started), SIGTERM then SIGKILL after ``grace_s``; the shared Prefect server,
    which outlives sweeps, and Python's resource tracker, which ends with this process, are
    left alone."""
    import psutil

    from flows.server import MARKER

    def command(process: psutil.Process) -> str:
        try:
            return " ".join(process.cmdline())
        except psutil.Error:
            return ""

    try:
        children = psutil.Process().children(recursive=True)
    except psutil.Error:
        return
    spared = set()
    for child in children:
        line = command(child)
        if MARKER in line:
            spared |= {child.pid, *(p.pid for p in _descendants(child))}
        elif "resource_tracker" in line:
            spared.add(child.pid)
    targets = [child for child in children if child.pid not in spared]
    for process in targets:
        with contextlib.suppress(psutil.Error):
            process.kill() if grace_s <= 0 else process.terminate()
    _, alive = psutil.wait_procs(targets, timeout=max(grace_s, 0.1))
    for process in alive:
        with contextlib.suppress(psutil.Error):
            process.kill()
    psutil.wait_procs(alive, timeout=1)
    _stop_resource_tracker()


def _stop_resource_tracker() -> None:
    """Stop Python's resource tracker now, while this command can still speak after it: it
    frees what the killed processes left (their semaphores) and warns of it on the shared
    stderr, which it would otherwise do after the command's last line."""
    from multiprocessing import resource_tracker

    with contextlib.suppress(Exception):
        resource_tracker._resource_tracker._stop()


def _descendants(process: Any) -> list[Any]:
    import psutil

    try:
        return process.children(recursive=True)
    except psutil.Error:
        return []
