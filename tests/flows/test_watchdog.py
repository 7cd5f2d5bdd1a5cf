"""flows.watchdog stops a process once its parent's pipe closes, and only the right process."""

import subprocess
import sys

from flows import watchdog

SLEEPER = "import time; time.sleep(120)  # {}"


def sleeper(tag: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", SLEEPER.format(tag)])


def test_the_watched_process_is_stopped_when_the_parent_goes_away():
    target = sleeper("watched-by-test")
    guard = watchdog.start(target.pid, "watched-by-test")
    try:
        guard.stdin.close()  # what the kernel does when the parent dies, however it dies
        assert guard.wait(timeout=30) == 0
        assert target.wait(timeout=30) != 0  # terminated by a signal
    finally:
        target.kill()
        target.wait()


def test_a_process_without_the_marker_is_left_alone():
    target = sleeper("someone-else")
    guard = watchdog.start(target.pid, "watched-by-test")
    try:
        guard.stdin.close()
        assert guard.wait(timeout=30) == 0
        assert target.poll() is None
    finally:
        target.kill()
        target.wait()
