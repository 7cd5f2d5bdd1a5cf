"""A sweep on a root that runs out of space: it stops at the first failed write with one line,
keeps what it wrote, and resumes once there is space.

The root is a small tmpfs the test mounts (root only; the suite runs as root in CI), grown with
``mount -o remount,size=...`` to free space, as a user would move or clean the disk.
"""

import json
import os
import re
import subprocess

import pytest

from pipeline.run.stages import RESULTS
from storage import SweepStore
from tests.flows.helpers import assert_same_cubes, eskin
from tests.reliability.test_interruption import POINTS, results

pytestmark = pytest.mark.slow

#: Room for the store and about half the smoke grid's batches (one worker writes them in a
#: fixed order), not for all of them and their cubes.
SMALL = "900k"
LARGE = "64m"


@pytest.fixture
def small_disk(tmp_path):
    """A tmpfs of :data:`SMALL` bytes mounted for the test, unmounted after it."""
    if os.geteuid() != 0:
        pytest.skip("mounting a size-limited tmpfs needs root")
    mount = tmp_path / "disk"
    mount.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={SMALL}", "tmpfs", str(mount)], check=True)
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=True)


def test_a_full_disk_stops_the_sweep_with_one_line_and_a_rerun_resumes(
    smoke_sweep, suite_cluster, small_disk, tmp_path
):
    _, _, env = smoke_sweep
    root = small_disk / "run"
    args = ("sweep", "--grid", "smoke", "--root", str(root), *suite_cluster, "--json")

    stopped = eskin(*args, env=env, timeout=600)
    assert stopped.returncode == 1 and stopped.stdout == ""
    assert "Traceback" not in stopped.stderr, stopped.stderr[-3000:]
    lines = stopped.stderr.strip().splitlines()
    assert [line for line in lines if line.startswith("eskin:")] == lines[-1:], lines
    found = re.fullmatch(
        rf"eskin: error: cannot write to run root {re.escape(str(root))}: no space left on the "
        rf"device; the sweep stopped, (\d+) of {POINTS} points are kept, and running it again "
        r"resumes from them",
        lines[-1],
    )
    assert found, lines[-1]
    kept = results(root)
    assert 1 <= len(kept) < POINTS and int(found[1]) == len(kept)
    # What is kept is whole: every entry passes its checksums, and nothing half-written is left.
    store = SweepStore.open(root)
    assert store.read_many(RESULTS.record, kept, discard_corrupt=False).keys() == kept.keys()
    assert not list((root / "store.zarr").glob("*/.partial-*"))

    subprocess.run(["mount", "-o", f"remount,size={LARGE}", str(small_disk)], check=True)
    resumed = eskin(*args, env=env, timeout=600)
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    summary = json.loads(resumed.stdout)
    assert summary["cache_hits"] == len(kept) and summary["computed"] == POINTS - len(kept)
    after = results(root)
    assert {key: after[key] for key in kept} == kept, "a kept point was written again"
    assert_same_cubes(smoke_sweep[0], root)
