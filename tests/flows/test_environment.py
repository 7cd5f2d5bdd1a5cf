"""Tests of flows.environment: the allocator settings that keep training off fresh mmap pages."""

import json
import subprocess
import sys

import pytest

# Allocates and frees a 4 MiB buffer (a CNN activation's size) in a loop; reports the minor
# page faults that caused.
PROBE = """
import json, resource, sys
import numpy as np
from flows.environment import tune_allocator
tuned = tune_allocator() if sys.argv[1] == "tuned" else None
np.ones(2**19)  # the heap grows once
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    np.ones(2**19)
faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
print(json.dumps({"tuned": tuned, "faults": faults}))
"""


def probe(mode: str) -> dict:
    env = {"MALLOC_TRIM_THRESHOLD_": "65536", "PATH": "/usr/bin:/bin"}  # Dask's nanny default
    out = subprocess.run(
        [sys.executable, "-c", PROBE, mode], capture_output=True, text=True, check=True, env=env
    )
    return json.loads(out.stdout)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mallopt is glibc's")
def test_tuned_allocator_reuses_pages_instead_of_faulting_them_in_again():
    plain, tuned = probe("plain"), probe("tuned")
    assert tuned["tuned"] is True
    pages = 4 * 2**20 // 4096  # one buffer's pages
    # each of the 20 buffers is a fresh mapping (the kernel faults a few pages at a time in)
    assert plain["faults"] >= 20 * pages / 4
    assert tuned["faults"] < pages / 10  # the heap keeps the pages


def test_a_root_without_space_for_the_tools_state_is_one_line(tmp_path, monkeypatch):
    import errno
    from pathlib import Path

    from flows.environment import hermetic_environment
    from storage import StoreWriteError

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    for name in ("DASK_TEMPORARY_DIRECTORY", "MPLCONFIGDIR", "PREFECT_HOME"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(Path, "mkdir", full)
    with pytest.raises(StoreWriteError, match=r"no space left on the device$"):
        hermetic_environment(tmp_path)


# Leaves one object in a reference cycle for the collector (automatic collection is off) and
# says, as the interpreter exits, whether a collection reached it.
CYCLE_AT_EXIT = """
import gc, os, sys
from flows.environment import skip_exit_collection
gc.disable()
if sys.argv[1] == "skipped":
    skip_exit_collection()

class Cycle:
    def __del__(self, write=os.write):
        write(1, b"collected")

cycle = Cycle()
cycle.itself = cycle
del cycle
"""


@pytest.mark.parametrize("mode, said", [("skipped", b""), ("default", b"collected")])
def test_exit_leaves_the_collectors_passes_out_when_asked(mode, said):
    """Without the exit handler the interpreter's last collection reaches the cycle (so the
    probe can tell); with it, the exit passes leave every object alone."""
    out = subprocess.run(
        [sys.executable, "-c", CYCLE_AT_EXIT, mode], capture_output=True, check=True, timeout=60
    )
    assert out.stdout == said, out.stderr
