"""Listings of a run root while a sweep writes under it: renamed and removed entries.

A sweep's workers rename ``.partial-*`` entries into place and remove abandoned ones at any
moment, so whatever walks a busy root (the tests' snapshots, the store's own listings) meets
entries that were listed and are gone a moment later. Here that moment is made deterministic: the
listing of one folder returns its entries as they were, then the folder changes before the
caller goes on.
"""

import os
import shutil
import threading
import time
from pathlib import Path

import pytest

from pipeline.run.stages import SPIKES
from storage import SweepStore
from tests.flows.helpers import live_tree

KEYS = [f"{i:032x}" for i in range(3)]


class _Listing:
    """A finished ``os.scandir`` iterator: iterable and a context manager."""

    def __init__(self, entries):
        self._entries = iter(entries)

    def __iter__(self):
        return self

    def __next__(self):
        return next(self._entries)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return None

    def close(self):
        return None


def change_after_listing(monkeypatch, folder: Path, change) -> None:
    """``folder`` is listed as it is now, then ``change()`` runs before the caller goes on.

    Later listings of ``folder`` return that same first listing, as if taken at the same moment
    (``Path.rglob`` lists a folder twice: for its names and for the folders to descend into).
    """
    real_scandir, real_listdir = os.scandir, os.listdir
    listed: list = []

    def matches(path) -> bool:
        # shutil.rmtree lists by file descriptor: never ``folder`` here.
        return not isinstance(path, int) and Path(os.fsdecode(path)) == folder

    def first_listing():
        if not listed:
            with real_scandir(folder) as listing:
                listed.extend(listing)
            change()
        return listed

    def scandir(path="."):
        return _Listing(first_listing()) if matches(path) else real_scandir(path)

    def listdir(path="."):
        return [e.name for e in first_listing()] if matches(path) else real_listdir(path)

    monkeypatch.setattr(os, "scandir", scandir)
    monkeypatch.setattr(os, "listdir", listdir)


def results_folder(root: Path) -> Path:
    """``store.zarr/results`` with a finished entry and two partial ones, each a small tree."""
    results = root / "store.zarr" / "results"
    for name in (KEYS[0], f".partial-{KEYS[1]}-aa", f".partial-{KEYS[2]}-bb"):
        (results / name / "accuracy" / "c").mkdir(parents=True)
        (results / name / "zarr.json").write_text("{}")
        (results / name / "accuracy" / "c" / "0").write_bytes(b"\x00")
    return results


def finish_one_abandon_one(results: Path):
    """What two workers do: rename one partial entry into place, remove another."""

    def change():
        os.rename(results / f".partial-{KEYS[1]}-aa", results / KEYS[1])
        shutil.rmtree(results / f".partial-{KEYS[2]}-bb")

    return change


def test_rglob_fails_where_live_tree_survives(monkeypatch, tmp_path):
    results = results_folder(tmp_path / "a")
    change_after_listing(monkeypatch, results, finish_one_abandon_one(results))
    with pytest.raises(FileNotFoundError):  # what the busy-root test met in CI
        list((tmp_path / "a").rglob("*"))

    monkeypatch.undo()
    root = tmp_path / "b"
    results = results_folder(root)
    change_after_listing(monkeypatch, results, finish_one_abandon_one(results))
    found = live_tree(root)
    # Listed entries count, whatever became of them; what came after the listing does not.
    finished = Path("store.zarr", "results", KEYS[0])
    assert found == {
        Path("store.zarr"),
        Path("store.zarr", "results"),
        finished,
        finished / "zarr.json",
        finished / "accuracy",
        finished / "accuracy" / "c",
        finished / "accuracy" / "c" / "0",
        Path("store.zarr", "results", f".partial-{KEYS[1]}-aa"),
        Path("store.zarr", "results", f".partial-{KEYS[2]}-bb"),
    }


def test_live_tree_survives_a_writer_renaming_and_removing_for_a_while(tmp_path):
    results = results_folder(tmp_path)
    partial, final = results / f".partial-{KEYS[1]}-aa", results / KEYS[1]
    stop = threading.Event()

    def writer():
        # Bounded: the walker below stops it after 0.5 s at most.
        while not stop.is_set():
            os.rename(partial, final)
            os.rename(final, partial)
            shutil.copytree(partial, results / f".partial-{KEYS[2]}-bb")
            shutil.rmtree(results / f".partial-{KEYS[2]}-bb")

    shutil.rmtree(results / f".partial-{KEYS[2]}-bb")
    thread = threading.Thread(target=writer)
    thread.start()
    walks = 0
    try:
        deadline = time.monotonic() + 0.5
        while time.monotonic() < deadline:
            found = live_tree(tmp_path)
            assert Path("store.zarr", "results", KEYS[0], "accuracy", "c", "0") in found
            walks += 1
    finally:
        stop.set()
        thread.join()
    assert walks > 1


def test_store_listings_survive_entries_renamed_or_removed_after_listing(monkeypatch, tmp_path):
    store = SweepStore.open_or_create(tmp_path / "root")
    spikes = store.path / SPIKES.name
    partial = spikes / f".partial-{KEYS[1]}-aa"
    (partial / "x").mkdir(parents=True)
    old = time.time() - 3600
    os.utime(partial, (old, old))

    def finished():  # the writer was slow, not dead: it renames its entry into place
        os.rename(partial, spikes / KEYS[1])

    change_after_listing(monkeypatch, spikes, finished)
    assert store.clean_partials(older_than_s=60) == 0
    assert (spikes / KEYS[1] / "x").is_dir()

    monkeypatch.undo()
    cubes = store.path / "cubes"
    for name in ("kept", "replaced"):
        (cubes / name).mkdir()
        (cubes / name / "zarr.json").write_text("{}")
    # Without renameat2 a cube is moved aside while its replacement goes in.
    change_after_listing(monkeypatch, cubes, lambda: shutil.rmtree(cubes / "replaced"))
    assert store.cube_names() == ["kept"]
