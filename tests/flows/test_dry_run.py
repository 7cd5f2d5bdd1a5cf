"""Tests of flows.dry_run: counts, the estimate, and that a dry run writes nothing."""

import hashlib
import json
import os
from pathlib import Path

import numpy as np
import pytest

from flows.dry_run import SweepCounts, dry_run, format_dry_run
from pipeline.design.grid import Grid
from pipeline.run.entries import ResultEntry
from pipeline.run.grid_keys import keyed_points
from pipeline.run.stages import RESULTS
from storage import StoreError
from storage.store import SweepStore
from tests.flows.helpers import METRICS
from tests.store_helpers import write_result


def dry_run_grid() -> Grid:
    return Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "threshold": {"axes": {"readout.threshold_v": [0.03, 0.05, 0.09, 0.2]}},
                # 0.1 s is the base point, shared with threshold 0.09.
                "window": {"axes": {"coding.window_s": [0.1, 0.2]}},
                "noise": {
                    "mode": "zip",
                    "axes": {
                        "readout.effects.amplifier_noise.sigma_v": [0.01, 0.02],
                        "seed": [1, 2],
                    },
                },
            },
        }
    )


def point_key(grid: Grid, sweep: str, i: int) -> str:
    return next(p.key for p in keyed_points(grid) if p.sweep == sweep and p.index == (i,))


def tree(root: Path) -> dict[str, tuple]:
    """Every path under ``root`` with its size, mtime and (for files) content digest."""
    found = {}
    for folder, dirs, files in os.walk(root):
        for name in dirs + files:
            path = Path(folder, name)
            stat = path.lstat()
            digest = hashlib.sha256(path.read_bytes()).hexdigest() if name in files else None
            found[str(path.relative_to(root))] = (stat.st_size, stat.st_mtime_ns, digest)
    stat = root.lstat()
    found["."] = (stat.st_size, stat.st_mtime_ns, None)
    return found


def test_dry_run_counts_cached_points_and_estimates_the_rest_writing_nothing(tmp_path):
    grid = dry_run_grid()
    root = tmp_path / "run"
    store = SweepStore.open_or_create(root)
    measured = {
        ("threshold", 0): {"readout": 0.25, "train_ffnn": 0.75},  # 1.0 s in all
        ("threshold", 1): {"readout": 1.0, "train_ffnn": 2.0},  # 3.0 s
        ("threshold", 2): {"readout": 5.0, "train_ffnn": 15.0},  # 20.0 s
        ("noise", 0): {"train_ffnn": 7.0},
    }
    for (sweep, i), seconds in measured.items():
        entry = ResultEntry({"ffnn": np.array([0.5, 0.75])}, seconds, METRICS)
        write_result(store, point_key(grid, sweep, i), entry)
    # A corrupt result (its attributes edited) counts as missing, and the dry run leaves it.
    corrupt = point_key(grid, "window", 1)
    write_result(store, corrupt, ResultEntry({"ffnn": np.array([0.5])}, {"a": 1.0}, METRICS))
    meta = store.entry_location(RESULTS.record, corrupt) / "zarr.json"
    data = json.loads(meta.read_text())
    data["attributes"]["entries"][0]["attrs"]["seconds"] = {"a": 100.0}
    meta.write_text(json.dumps(data))
    # So does a partial batch, as a killed writer leaves it.
    (root / "store.zarr" / "results" / ".partial-batch-0").mkdir()
    before = tree(root)

    d = dry_run(grid, root, workers=2)

    assert tree(root) == before
    assert (d.grid, d.root, d.points, d.cached, d.missing) == ("grid", str(root), 7, 4, 3)
    assert d.sweeps == (
        SweepCounts("threshold", 4, 3, 1),
        SweepCounts("window", 2, 1, 1),
        SweepCounts("noise", 2, 1, 1),
    )
    # threshold 0.2: median of 1, 3 and 20 s (its kind); noise[1]: 7 s; window 0.2: unknown.
    assert d.estimated_seconds == pytest.approx(3.0 + 7.0)
    assert (d.unknown, d.workers, d.wall_seconds) == (1, 2, pytest.approx(5.0))
    assert json.loads(json.dumps(d.to_json())) == d.to_json()
    assert d.to_json()["sweeps"]["window"] == {"points": 2, "cached": 1, "missing": 1}
    text = format_dry_run(d)
    assert "10 s of compute for 2 missing points" in text
    assert "5 s wall on 2 worker(s) if they stay busy" in text
    assert "1 more of unknown kind" in text
    assert "\nthreshold            4       3        1\n" in text
    assert "\nall (distinct)       7       4        3\n" in text


def test_dry_run_of_a_missing_root_has_nothing_cached_and_creates_nothing(tmp_path):
    root = tmp_path / "absent" / "run"
    d = dry_run(dry_run_grid(), root, workers=1)
    assert (d.cached, d.missing, d.unknown, d.estimated_seconds) == (0, 7, 7, 0.0)
    assert not (tmp_path / "absent").exists()
    assert "estimate: unknown (7 missing points" in format_dry_run(d)
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError, match="is a file"):
        dry_run(dry_run_grid(), tmp_path / "file", workers=1)
