"""A process killed while it writes a batch of entries leaves nothing a later reader trusts.

The writer runs in a subprocess that is SIGKILLed (1) once every byte of its batch is on disk
but before the batch is renamed into place (the last moment a kill can strike), and (2) at
seeded random moments during the write. Each time: none of the batch's keys is visible, the
entries stored before are intact, the next sweep's clean-up removes the leftover, and writing
the batch again gives exact entries.
"""

import dataclasses
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from pipeline.chain.metrics import SpikeMetrics
from pipeline.run.entries import OutOfFold, RecordingsInfo, ResultEntry
from pipeline.run.stages import RESULTS
from storage import SweepStore
from tests.store_helpers import read_result, write_result

pytestmark = pytest.mark.slow

N_ENTRIES = 400

WRITER = textwrap.dedent(
    """
    import os, sys, time
    from pipeline.run.stages import RESULTS
    from storage import SweepStore
    from tests.reliability.test_batched_write import batch_entries

    root, stall = sys.argv[1], sys.argv[2] == "stall"
    rename = os.rename

    def stalled_rename(source, target):
        if stall and ".partial-batch-" in str(source):
            print("written", flush=True)  # every byte is on disk; the rename is next
            time.sleep(600)
        rename(source, target)

    os.rename = stalled_rename
    import dask.array  # what xarray imports on its first write, so the kill hits the write
    entries = batch_entries()
    print("writing", flush=True)
    SweepStore.open(root).write_entries(RESULTS.record, entries)
    print("renamed", flush=True)
    """
)


def make_result_entry(seed: int) -> ResultEntry:
    """A result entry of the real shapes (2 models, 10 folds, 120 recordings), from ``seed``."""
    rng = np.random.default_rng(seed)
    labels = np.repeat(np.arange(12), 10)
    return ResultEntry(
        fold_accuracy={m: rng.uniform(size=(1, 10)) for m in ("ffnn", "cnn")},
        seconds={"readout": float(seed), "train_ffnn": 1.5},
        metrics=SpikeMetrics(*rng.normal(size=6)),
        recordings=RecordingsInfo("synthetic", tuple(f"c{i}" for i in range(12)), 2000.0),
        out_of_fold=OutOfFold(
            recording_names=tuple(f"r{i}" for i in range(120)),
            labels=labels,
            predicted={m: rng.integers(0, 12, size=(1, 120)) for m in ("ffnn", "cnn")},
            test_fold=rng.integers(0, 10, size=(1, 120)),
        ),
    )


def assert_results_identical(read: ResultEntry, written: ResultEntry) -> None:
    assert read.fold_accuracy.keys() == written.fold_accuracy.keys()
    for model, folds in written.fold_accuracy.items():
        assert read.fold_accuracy[model].tobytes() == folds.tobytes()
    assert (read.seconds, read.recordings) == (written.seconds, written.recordings)
    assert dataclasses.astuple(read.metrics) == dataclasses.astuple(written.metrics)
    mine, theirs = read.out_of_fold, written.out_of_fold
    assert mine.recording_names == theirs.recording_names
    np.testing.assert_array_equal(mine.labels, theirs.labels)
    np.testing.assert_array_equal(mine.test_fold, theirs.test_fold)
    for model, predicted in theirs.predicted.items():
        np.testing.assert_array_equal(mine.predicted[model], predicted)


def batch_entries() -> dict[str, ResultEntry]:
    """Many result entries (about 1 MB in all): writing them takes about 0.4 s."""
    return {f"{i:032x}": make_result_entry(seed=i) for i in range(1, N_ENTRIES + 1)}


def start_writer(root: Path, mode: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-c", WRITER, str(root), mode],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=Path(__file__).parents[2],
    )


def assert_nothing_half_written(store: SweepStore, before: ResultEntry) -> None:
    keys = store.complete_keys(RESULTS.record)
    assert keys == {"0" * 32} or keys == {"0" * 32, *batch_entries()}, "a torn batch is visible"
    assert_results_identical(read_result(store, "0" * 32), before)
    if len(keys) > 1:  # the kill came after the rename: the batch is whole
        found = store.read_many(RESULTS.record, batch_entries(), discard_corrupt=False)
        for key, entry in batch_entries().items():
            assert_results_identical(found[key], entry)


def rewrite_and_check(store: SweepStore) -> None:
    with store.lock():
        store.clean_partials()
    assert not list(store.path.glob("*/.partial-*"))
    store.write_entries(RESULTS.record, batch_entries())
    found = store.read_many(RESULTS.record, batch_entries(), discard_corrupt=False)
    assert found.keys() == batch_entries().keys()
    for key, entry in batch_entries().items():
        assert_results_identical(found[key], entry)


def test_kill_after_the_data_before_the_rename_leaves_only_a_partial(tmp_path):
    store = SweepStore.open_or_create(tmp_path / "run")
    before = make_result_entry(seed=0)
    write_result(store, "0" * 32, before)
    writer = start_writer(store.root, "stall")
    try:
        assert writer.stdout.readline().strip() == "writing"
        assert writer.stdout.readline().strip() == "written", writer.stderr.read()
        writer.send_signal(signal.SIGKILL)
        writer.wait(timeout=20)
    finally:
        writer.kill()
    partials = list((store.path / "results").glob(".partial-batch-*"))
    assert len(partials) == 1 and (partials[0] / "zarr.json").is_file()  # all data, no rename
    assert_nothing_half_written(store, before)
    rewrite_and_check(store)


def test_kills_at_random_moments_of_the_write_never_expose_a_torn_batch(tmp_path):
    rng = np.random.default_rng(20261124)
    for attempt, delay_s in enumerate(rng.uniform(0.0, 0.5, size=4)):
        store = SweepStore.open_or_create(tmp_path / f"run{attempt}")
        before = make_result_entry(seed=0)
        write_result(store, "0" * 32, before)
        writer = start_writer(store.root, "plain")
        try:
            assert writer.stdout.readline().strip() == "writing"
            time.sleep(delay_s)
            writer.send_signal(signal.SIGKILL)
            writer.wait(timeout=20)
        finally:
            writer.kill()
        assert_nothing_half_written(store, before)
        rewrite_and_check(store)
