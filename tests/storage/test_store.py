"""Sweep store: layout, exact round trips, batches complete by rename, checksums, root refusal."""

import dataclasses
import errno
import json
import os
import pickle
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import uuid
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import storage
import storage.index
import storage.store as store_module
from pipeline.chain.metrics import SpikeMetrics
from pipeline.chain.spikes import Encoded, SpikeTrains
from pipeline.design.scene import Model
from pipeline.errors import EskinError
from pipeline.run.entries import OutOfFold, RecordingsInfo, ResultEntry, SpikeEntry
from pipeline.run.stages import RESULTS, SPIKES
from storage import (
    CorruptEntryError,
    StoreBusyError,
    StoreError,
    StoreLayoutError,
    StoreWriteError,
    SweepStore,
    cube_files,
    layout,
    open_results,
)
from storage.batches import json_digest
from tests.store_helpers import peek_result, read_result, read_spikes, write_result, write_spikes

KEY = "0123456789abcdef0123456789abcdef"
OTHER_KEY = "fedcba9876543210fedcba9876543210"
THIRD_KEY = "00000000000000000000000000000003"
NEG_NAN = -np.float64("nan")  # a NaN with the sign bit set, as x86 produces for 0/0
BATCH_NAME = re.compile(r"batch-[0-9a-f]{32}")


def key(i: int) -> str:
    return f"{i:032x}"


def random_trains(
    rng: np.random.Generator, n_recordings: int, n_taxels: int, *, silent_recording: int = -1
) -> SpikeTrains:
    """Ragged trains with many empty trains; ``silent_recording`` has no spike at all."""
    trains = []
    for recording in range(n_recordings):
        for _ in range(n_taxels):
            n = 0 if recording == silent_recording else int(rng.choice([0, 0, 1, 3, 17]))
            times = np.sort(rng.uniform(0.0, 2.0, n))
            trains.append((times, rng.choice(np.array([-1, 1], np.int8), n)))
    durations = rng.uniform(1.0, 2.0, n_recordings)
    return SpikeTrains.concatenate(trains, n_taxels, durations)


def metrics(**overrides: float) -> SpikeMetrics:
    values = {
        "ssnr_db": np.inf,
        "ste_s2": -np.inf,
        "ste_sign_safe_s2": 1e-300,
        "event_rate_hz": 123.456,
        "data_rate_bps": 0.1 + 0.2,
        "equivalent_bits": NEG_NAN,
    }
    return SpikeMetrics(**(values | overrides))


def bits(value) -> np.ndarray:
    """Bit pattern of float64 values, so NaN payloads, signed zeros and infinities compare."""
    return np.asarray(value, dtype=np.float64).view(np.uint64)


def assert_trains_identical(actual: SpikeTrains, expected: SpikeTrains) -> None:
    assert actual.times_s.dtype == np.float64 and actual.polarity.dtype == np.int8
    assert actual.count.dtype == np.int64 and actual.duration_s.dtype == np.float64
    np.testing.assert_array_equal(bits(actual.times_s), bits(expected.times_s))
    np.testing.assert_array_equal(actual.polarity, expected.polarity)
    np.testing.assert_array_equal(actual.count, expected.count)
    np.testing.assert_array_equal(bits(actual.duration_s), bits(expected.duration_s))
    assert actual.count.shape == expected.count.shape


def assert_metrics_identical(actual: SpikeMetrics, expected: SpikeMetrics) -> None:
    for name in ("ssnr_db", "ste_s2", "ste_sign_safe_s2", "event_rate_hz", "data_rate_bps"):
        assert type(getattr(actual, name)) is float
        assert bits(getattr(actual, name)) == bits(getattr(expected, name)), name
    assert bits(actual.equivalent_bits) == bits(expected.equivalent_bits)


def assert_results_identical(actual: ResultEntry, expected: ResultEntry) -> None:
    """Equal models in order, accuracy bit for bit, seconds, metrics, recordings, predictions."""
    assert list(actual.fold_accuracy) == [str(model) for model in expected.fold_accuracy]
    for model, values in zip(
        actual.fold_accuracy.values(), expected.fold_accuracy.values(), strict=True
    ):
        assert model.dtype == np.float64
        np.testing.assert_array_equal(bits(model), bits(np.atleast_2d(values)))
    assert actual.seconds == {k: float(v) for k, v in expected.seconds.items()}
    assert_metrics_identical(actual.metrics, expected.metrics)
    assert actual.recordings == expected.recordings
    assert actual.n_windows_used == expected.n_windows_used
    if expected.out_of_fold is None:
        assert actual.out_of_fold is None
        return
    got, want = actual.out_of_fold, expected.out_of_fold
    assert got.recording_names == tuple(want.recording_names)
    assert list(got.predicted) == list(want.predicted)
    for model, values in want.predicted.items():
        assert got.predicted[model].dtype == np.int64
        np.testing.assert_array_equal(got.predicted[model], values)
    assert got.labels.dtype == np.int64 and got.test_fold.dtype == np.int64
    np.testing.assert_array_equal(got.labels, want.labels)
    np.testing.assert_array_equal(got.test_fold, want.test_fold)


def listing(path: Path) -> list[tuple[str, int]]:
    """Every path below ``path`` with its size (0 for directories), to prove nothing changed."""
    out = []
    for dirpath, dirnames, filenames in os.walk(path):
        for name in dirnames:
            out.append((os.path.relpath(os.path.join(dirpath, name), path), 0))
        for name in filenames:
            full = os.path.join(dirpath, name)
            out.append((os.path.relpath(full, path), os.path.getsize(full)))
    return sorted(out)


def batches(store: SweepStore, kind: str) -> list[Path]:
    """The complete batch folders of ``kind``, found by listing (not by the store's index)."""
    folder = store.path / kind
    return sorted(folder / name for name in os.listdir(folder) if name.startswith("batch-"))


def written(store: SweepStore, kind: str) -> list[str]:
    """What the folder of ``kind`` holds besides its group metadata (nothing if no folder)."""
    folder = store.path / kind
    return sorted(n for n in os.listdir(folder) if n != "zarr.json") if folder.is_dir() else []


def batch_meta(batch: Path) -> dict:
    return json.loads((batch / "zarr.json").read_text())["attributes"]


def batch_of(store: SweepStore, kind: str, key: str) -> Path:
    """The one batch of ``kind`` whose entry list names ``key``."""
    found = [
        batch
        for batch in batches(store, kind)
        if key in [entry["key"] for entry in batch_meta(batch)["entries"]]
    ]
    assert len(found) == 1, found
    return found[0]


def chunk(batch: Path, variable: str) -> Path:
    """The one chunk file of ``variable`` in ``batch``."""
    files = [p for p in (batch / variable / "c").rglob("*") if p.is_file()]
    assert len(files) == 1
    return files[0]


def edit_batch_attributes(batch: Path, change) -> None:
    meta_path = batch / "zarr.json"
    meta = json.loads(meta_path.read_text())
    change(meta["attributes"])
    meta_path.write_text(json.dumps(meta))


@pytest.fixture
def store(tmp_path: Path) -> SweepStore:
    return SweepStore.open_or_create(tmp_path / "run")


@pytest.fixture
def spike_entry() -> SpikeEntry:
    rng = np.random.default_rng(7)
    true = random_trains(rng, 4, 5, silent_recording=2)
    real = random_trains(rng, 4, 5)
    real = SpikeTrains(real.times_s, real.polarity, real.count, true.duration_s)
    return SpikeEntry(Encoded(true, real), metrics(), {"taxels": 0.25, "readout": 1.5})


def result_entry(i: int = 0) -> ResultEntry:
    """A small result entry whose values depend on ``i``."""
    return ResultEntry({"ffnn": [0.5, i / 8], "cnn": [0.25, -0.0]}, {"train_ffnn": i}, metrics())


# ---------------------------------------------------------------------------------------------
# Layout


def test_public_names_are_reexported():
    # The package is the store's public names plus the run root as one DataTree.
    assert set(storage.__all__) == set(store_module.__all__) | {"open_tree"}
    assert issubclass(CorruptEntryError, StoreError) and issubclass(StoreError, EskinError)
    assert issubclass(StoreLayoutError, StoreError) and issubclass(StoreWriteError, StoreError)


def test_storage_knows_no_stage():
    """Storage imports neither the stage registry nor the records it declares: a stored level
    hands its record declaration to the store (:mod:`storage.codec`)."""
    from tests.test_import_cycles import graph, project_modules

    edges = graph(project_modules())
    for module, targets in edges.items():
        if module.split(".")[0] == "storage":
            assert not targets & {
                "pipeline.run.stages",
                "pipeline.run.records",
                "pipeline.results.cube",
            }, module


def test_layout_is_a_marked_zarr_v3_group_without_consolidated_metadata(tmp_path):
    root = tmp_path / "a" / "b" / "run"  # parents are created too
    store = SweepStore.open_or_create(root)
    assert store.root == root and store.path == root / "store.zarr"
    assert sorted(os.listdir(root)) == ["store.zarr"]  # no probe or partial left behind
    meta = json.loads((root / "store.zarr" / "zarr.json").read_text())
    assert meta["zarr_format"] == 3 and meta["node_type"] == "group"
    assert meta["attributes"] == {"eskin_sweep_store": 3}
    assert meta.get("consolidated_metadata") is None
    group = zarr.open_group(root / "store.zarr", mode="r", zarr_format=3, use_consolidated=False)
    # A kind's group is made with its first batch: the store knows no kind of entry before.
    assert sorted(name for name, _ in group.groups()) == ["cubes"]


def test_entries_are_stored_in_batches(store, spike_entry):
    write_spikes(store, KEY, spike_entry)
    names = sorted(os.listdir(store.path / "spikes"))
    assert len(names) == 2 and names[1] == "zarr.json" and BATCH_NAME.fullmatch(names[0])
    batch = store.path / "spikes" / names[0]
    assert store.entry_location(SPIKES.record, KEY) == batch
    assert store.entry_location(SPIKES.record, OTHER_KEY) is None
    meta = json.loads((batch / "zarr.json").read_text())
    assert meta["node_type"] == "group" and meta.get("consolidated_metadata") is None
    attrs = meta["attributes"]
    assert attrs["eskin_batch"] == "spikes"
    assert [entry["key"] for entry in attrs["entries"]] == [KEY]
    assert attrs["entries"][0]["attrs"] == {
        "ideal": False,
        "seconds": {"taxels": 0.25, "readout": 1.5},
    }
    times = json.loads((batch / "true_times_s" / "zarr.json").read_text())
    assert times["data_type"] == "uint32" and times["dimension_names"] == ["flat_true_times_s"]
    assert times["attributes"]["dims"] == ["true_event"]
    assert times["attributes"]["units"] == "1"
    assert times["attributes"]["ticks_s"] == 1e-6
    assert times["attributes"]["ticks_runs"] == "true_count"
    assert times["attributes"]["ticks_sign"] == "true_polarity"
    # Core Zarr v3 codecs only: any Zarr v3 reader decodes the stored deltas.
    assert times["codecs"] == [
        {"name": "bytes", "configuration": {"endian": "little"}},
        {
            "name": "blosc",
            "configuration": {
                "typesize": 4, "cname": "zstd", "clevel": 5, "shuffle": "shuffle", "blocksize": 0
            },
        },
    ]  # fmt: skip
    assert not (batch / "true_polarity").exists()  # folded into the deltas' low bit


def test_a_batch_has_as_many_files_for_many_entries_as_for_one(store, spike_entry):
    def files(batch: Path) -> int:
        return sum(len(names) for _, _, names in os.walk(batch))

    write_spikes(store, KEY, spike_entry)
    store.write_entries(SPIKES.record, {key(i): spike_entry for i in range(20)})
    one, many = batch_of(store, "spikes", KEY), batch_of(store, "spikes", key(0))
    assert len(batch_meta(many)["entries"]) == 20
    assert files(many) == files(one)


def test_store_pickles_for_workers(store, spike_entry):
    write_spikes(store, KEY, spike_entry)
    clone = pickle.loads(pickle.dumps(store))
    assert clone.root == store.root and clone.has(SPIKES.record, KEY)


# ---------------------------------------------------------------------------------------------
# Round trips


def test_spikes_round_trip_non_ideal(store, spike_entry):
    assert spike_entry.encoded.true.count[2].sum() == 0  # a recording without any spike
    assert (spike_entry.encoded.true.count == 0).any()  # and empty trains elsewhere
    write_spikes(store, KEY, spike_entry)
    assert store.has(SPIKES.record, KEY) and store.has("spikes", KEY)
    read = read_spikes(store, KEY)
    assert read.encoded.real is not read.encoded.true
    assert_trains_identical(read.encoded.true, spike_entry.encoded.true)
    assert_trains_identical(read.encoded.real, spike_entry.encoded.real)
    assert_metrics_identical(read.metrics, spike_entry.metrics)
    assert read.seconds == {"taxels": 0.25, "readout": 1.5}


def test_spikes_round_trip_ideal_keeps_real_is_true_and_stores_once(store, spike_entry):
    true = spike_entry.encoded.true
    entry = SpikeEntry(Encoded(true, true), metrics(ssnr_db=-np.inf, ste_s2=0.0), {})
    write_spikes(store, KEY, entry)
    read = read_spikes(store, KEY)
    assert read.encoded.real is read.encoded.true
    assert_trains_identical(read.encoded.true, true)
    assert_metrics_identical(read.metrics, entry.metrics)
    assert read.seconds == {}
    stored = sorted(os.listdir(batch_of(store, "spikes", KEY)))
    assert not any(name.startswith("real_") for name in stored)
    assert {"true_times_s", "true_start", "true_count"} <= set(stored)


def test_one_batch_mixes_ideal_and_non_ideal_spike_entries(store, spike_entry):
    true = spike_entry.encoded.true
    ideal = SpikeEntry(Encoded(true, true), metrics(ssnr_db=1.0), {"readout": 2.0})
    store.write_entries(SPIKES.record, {KEY: spike_entry, OTHER_KEY: ideal})
    assert batch_of(store, "spikes", KEY) == batch_of(store, "spikes", OTHER_KEY)
    read = store.read_many(SPIKES.record, [OTHER_KEY, KEY], discard_corrupt=False)
    assert read[OTHER_KEY].encoded.real is read[OTHER_KEY].encoded.true
    assert read[KEY].encoded.real is not read[KEY].encoded.true
    assert_trains_identical(read[OTHER_KEY].encoded.true, true)
    assert_trains_identical(read[KEY].encoded.real, spike_entry.encoded.real)
    assert_metrics_identical(read[OTHER_KEY].metrics, ideal.metrics)
    assert read[OTHER_KEY].seconds == {"readout": 2.0}


def test_spikes_start_is_stored_for_lazy_readers(store, spike_entry):
    write_spikes(store, KEY, spike_entry)
    batch = batch_of(store, "spikes", KEY)
    with xr.open_zarr(batch, consolidated=False, zarr_format=3) as ds:
        start = ds["true_start"]
        np.testing.assert_array_equal(start.values, spike_entry.encoded.true.start.ravel())
        assert start.attrs["dims"] == ["recording", "taxel"]
    assert batch_meta(batch)["entries"][0]["shapes"]["true_start"] == [4, 5]


@st.composite
def ragged(draw) -> tuple[SpikeTrains, SpikeTrains | None]:
    n_recordings = draw(st.integers(0, 3))
    n_taxels = draw(st.integers(1, 4))
    finite = st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=True)
    since_start = st.floats(0.0, 1e3, allow_nan=False, allow_subnormal=True)  # t >= 0

    def trains() -> list[tuple[np.ndarray, np.ndarray]]:
        out = []
        for _ in range(n_recordings * n_taxels):
            times = sorted(draw(st.lists(since_start, max_size=5)))
            polarity = draw(st.lists(st.sampled_from([-1, 1]), min_size=len(times)))
            out.append((np.array(times, np.float64), np.array(polarity[: len(times)], np.int8)))
        return out

    durations = np.array(draw(st.lists(finite, min_size=n_recordings, max_size=n_recordings)))
    true = SpikeTrains.concatenate(trains(), n_taxels, durations)
    real = SpikeTrains.concatenate(trains(), n_taxels, durations) if draw(st.booleans()) else None
    return true, real


METRIC_NAMES = (
    "ssnr_db",
    "ste_s2",
    "ste_sign_safe_s2",
    "event_rate_hz",
    "data_rate_bps",
    "equivalent_bits",
)
METRIC_VALUES = st.lists(
    st.floats(allow_nan=True, allow_infinity=True), min_size=6, max_size=6
).map(lambda values: SpikeMetrics(**dict(zip(METRIC_NAMES, values, strict=True))))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(ragged(), METRIC_VALUES), min_size=1, max_size=3))
def test_property_ragged_spike_trains_round_trip_in_one_batch(points):
    entries = {
        key(i): SpikeEntry(Encoded(true, true if real is None else real), values, {"readout": i})
        for i, ((true, real), values) in enumerate(points)
    }
    with tempfile.TemporaryDirectory() as tmp:
        store = SweepStore.open_or_create(tmp)
        store.write_entries(SPIKES.record, entries)
        assert len(batches(store, "spikes")) == 1
        read = store.read_many(SPIKES.record, list(entries), discard_corrupt=False)
    assert list(read) == list(entries)
    for k, entry in entries.items():
        ideal = entry.encoded.real is entry.encoded.true
        assert (read[k].encoded.real is read[k].encoded.true) == ideal
        assert_trains_identical(read[k].encoded.true, entry.encoded.true)
        assert_trains_identical(read[k].encoded.real, entry.encoded.real)
        for name in METRIC_NAMES:
            assert bits(getattr(read[k].metrics, name)) == bits(getattr(entry.metrics, name))
        assert read[k].seconds == entry.seconds


def test_results_round_trip_keeps_model_order(store):
    entry = ResultEntry(
        {Model.FFNN: np.array([0.5, 1.0, 0.0, NEG_NAN]), "cnn": [0.25, 0.75, 1 / 3, -0.0]},
        {"train_ffnn": 1.2, "train_cnn": 5},
        metrics(ssnr_db=np.inf, ste_s2=-np.inf),
    )
    write_result(store, KEY, entry)
    read = read_result(store, KEY)
    assert list(read.fold_accuracy) == ["ffnn", "cnn"]
    assert all(type(model) is str for model in read.fold_accuracy)
    # A (folds,) row is one repeat: read back as (1, folds).
    np.testing.assert_array_equal(bits(read.fold_accuracy["ffnn"]), bits([[0.5, 1, 0, NEG_NAN]]))
    np.testing.assert_array_equal(
        bits(read.fold_accuracy["cnn"]), bits([[0.25, 0.75, 1 / 3, -0.0]])
    )
    assert read.seconds == {"train_ffnn": 1.2, "train_cnn": 5.0}
    for name in ("ssnr_db", "ste_s2", "equivalent_bits"):  # +inf, -inf, a negative NaN
        assert bits(getattr(read.metrics, name)) == bits(getattr(entry.metrics, name))
    batch = batch_of(store, "results", KEY)
    with xr.open_zarr(batch, consolidated=False, zarr_format=3) as ds:
        assert ds["accuracy"].attrs["dims"] == ["model", "repeat", "fold"]
        assert ds["model"].values.tolist() == ["ffnn", "cnn"]
        assert "predicted" not in ds  # kept no predictions: none written
    assert batch_meta(batch)["entries"][0]["shapes"]["accuracy"] == [2, 1, 4]
    assert read.recordings is None  # stated nothing: read as unknown, never as empty
    assert read.out_of_fold is None
    assert read.n_windows_used is None


def test_results_round_trip_the_resolved_window_count(store):
    entry = dataclasses.replace(result_entry(), n_windows_used=40)
    write_result(store, KEY, entry)
    assert read_result(store, KEY).n_windows_used == 40
    with xr.open_zarr(batch_of(store, "results", KEY), consolidated=False) as ds:
        assert ds["n_windows_used"].dtype == np.int64
        assert ds["n_windows_used"].attrs["units"] == "1"
    with pytest.raises(ValueError, match="cannot store float64"):
        write_result(store, OTHER_KEY, dataclasses.replace(entry, n_windows_used=40.5))


OUT_OF_FOLD = OutOfFold(
    recording_names=("bark/01", "bark/02", "µ-foam/01"),
    labels=np.array([0, 0, 1]),
    predicted={"ffnn": np.array([[0, 1, 1], [0, 0, 1]]), "cnn": np.array([[1, 1, 1], [0, 0, 0]])},
    test_fold=np.array([[0, 1, 0], [1, 0, 0]]),
)


def test_results_round_trip_out_of_fold_predictions_exactly(store):
    accuracy = {"ffnn": [[0.5, 1.0], [1.0, 1.0]], "cnn": [[0.5, 0.5], [0.5, 0.5]]}
    entry = ResultEntry(accuracy, {}, metrics(), None, OUT_OF_FOLD)
    write_result(store, KEY, entry)
    assert_results_identical(read_result(store, KEY), entry)


def test_one_batch_holds_results_of_different_shapes(store):
    # Entries of one batch differ in models, repeats, folds, recordings and what they kept.
    entries = {
        KEY: ResultEntry(
            {"ffnn": [[0.5, 1.0], [1.0, 1.0]], "cnn": [[0.5, 0.5], [0.5, 0.5]]},
            {"train_ffnn": 1.0},
            metrics(),
            RecordingsInfo("three", ("bark", "µ-foam"), 500.0),
            OUT_OF_FOLD,
        ),
        OTHER_KEY: ResultEntry({"svm": [0.1, 0.2, NEG_NAN]}, {}, metrics(ssnr_db=NEG_NAN)),
        THIRD_KEY: ResultEntry(
            {"ffnn": [1.0]},
            {},
            metrics(),
            RecordingsInfo(class_names=("a",)),
            OutOfFold(("x",), np.array([4]), {"ffnn": np.array([[4]])}, np.array([[0]])),
        ),
    }
    store.write_entries(RESULTS.record, entries)
    assert len(batches(store, "results")) == 1
    read = store.read_many(RESULTS.record, list(entries), discard_corrupt=False)
    assert set(read) == set(entries)
    for k, entry in entries.items():
        assert_results_identical(read[k], entry)


def test_out_of_fold_predictions_must_match_the_models_and_repeats(store):
    with pytest.raises(ValueError, match="predictions of"):
        write_result(
            store, KEY, ResultEntry({"ffnn": [[0.5], [0.5]]}, {}, metrics(), None, OUT_OF_FOLD)
        )
    with pytest.raises(ValueError, match="2 repeats, accuracy has 1"):
        write_result(
            store, KEY, ResultEntry({"ffnn": [0.5], "cnn": [0.5]}, {}, metrics(), None, OUT_OF_FOLD)
        )
    with pytest.raises(ValueError, match="labels"):
        OutOfFold(("a", "b"), np.array([0]), {}, np.zeros((1, 2)))
    assert not store.has("results", KEY)  # nothing half-written
    assert written(store, "results") == []


@pytest.mark.parametrize(
    "info",
    [
        RecordingsInfo("three", ("bark", "cloth", "µ-foam"), 500),
        RecordingsInfo(class_names=("a",)),  # what an entry does not state stays unknown
    ],
)
def test_results_round_trip_what_they_state_of_their_recordings(store, info):
    write_result(store, KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics(), info))
    read = read_result(store, KEY).recordings
    assert read == info
    assert read.sampling_rate_hz is None or type(read.sampling_rate_hz) is float


def test_malformed_recordings_facts_are_refused_or_corrupt(store):
    negative = RecordingsInfo(sampling_rate_hz=-1.0)
    with pytest.raises(ValueError, match="sampling_rate_hz"):
        write_result(store, KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics(), negative))
    write_result(store, KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics(), RecordingsInfo("d")))

    def consistent_writer(attrs):  # a wrong type, with the entry list's digest to match
        attrs["entries"][0]["attrs"]["dataset_name"] = 3
        attrs["sha256"]["@entries"] = json_digest(attrs["entries"])

    edit_batch_attributes(batch_of(store, "results", KEY), consistent_writer)
    with pytest.raises(CorruptEntryError, match="dataset_name"):
        read_result(store, KEY)


# ---------------------------------------------------------------------------------------------
# Cubes


def make_cube(scale: float = 1.0) -> xr.Dataset:
    accuracy = np.arange(2 * 3 * 2 * 4, dtype=np.float64).reshape(2, 3, 2, 4) / 48 * scale
    accuracy[0, 0, 0, 0] = np.nan  # a scene that did not run
    return xr.Dataset(
        {
            "accuracy": (("threshold_v", "effect", "model", "fold"), accuracy, {"units": "1"}),
            "ssnr_db": (("threshold_v", "effect"), [[np.inf, -np.inf, 3.0], [1.0, 2.0, -0.0]]),
            "seconds": (("threshold_v", "stage"), [[1.0, 2.0], [3.0, 4.0]], {"units": "s"}),
            "dropped": (("threshold_v",), np.array([0, 2**40], dtype=np.int64)),
            "ran": (("threshold_v",), np.array([True, False])),
        },
        coords={
            "threshold_v": ("threshold_v", [0.05, 0.09], {"units": "V"}),
            "effect": ["none", "amplifier_noise", "saturation"],
            "model": ["ffnn", "cnn"],
            "stage": ["readout", "train_ffnn"],
            "effect_label": ("effect", ["-", "noise", "clip"]),
        },
        attrs={"grid": "paper", "package_version": "0.1.0", "seed": 7, "scale": scale},
    )


def test_cube_round_trip_is_identical_and_loaded(store):
    cube = make_cube()
    store.write_cube("paper-grid_1", cube)
    assert "eskin_sha256" not in cube.attrs  # the caller's cube is not modified
    read = store.read_cube("paper-grid_1")
    xr.testing.assert_identical(read, cube)
    for name, variable in cube.variables.items():
        assert read[name].dtype == variable.dtype, name
    np.testing.assert_array_equal(bits(read["ssnr_db"]), bits(cube["ssnr_db"]))
    assert store.cube_names() == ["paper-grid_1"]
    shutil.rmtree(store.path / "cubes" / "paper-grid_1")  # loaded, not lazy: still readable
    xr.testing.assert_identical(read, cube)
    assert read.sel(model="cnn", effect="saturation").accuracy.shape == (2, 4)


@pytest.mark.parametrize("exchange", [True, False], ids=["renameat2", "move-aside"])
def test_write_cube_replaces_older_cube(store, monkeypatch, exchange):
    if not exchange:
        monkeypatch.setattr(cube_files, "_renameat2", lambda: None)
    store.write_cube("grid", make_cube())
    store.write_cube("grid", make_cube(scale=0.5))
    xr.testing.assert_identical(store.read_cube("grid"), make_cube(scale=0.5))
    assert sorted(os.listdir(store.path / "cubes")) == ["grid", "zarr.json"]


def test_failed_cube_replacement_keeps_the_old_cube(store, monkeypatch):
    monkeypatch.setattr(cube_files, "_renameat2", lambda: None)  # take the move-aside path
    store.write_cube("grid", make_cube())
    real_rename = os.rename
    failures = [OSError(errno.EIO, "I/O error")]

    def failing_rename(src, dst):
        # Fail once, moving the new cube in; the old one (moved aside) must come back.
        if Path(dst).name == "grid" and failures:
            raise failures.pop()
        real_rename(src, dst)

    monkeypatch.setattr(store_module.os, "rename", failing_rename)
    with pytest.raises(OSError, match="I/O error"):
        store.write_cube("grid", make_cube(scale=0.5))
    xr.testing.assert_identical(store.read_cube("grid"), make_cube())
    assert sorted(os.listdir(store.path / "cubes")) == ["grid", "zarr.json"]


def test_open_results_returns_every_cube(store, spike_entry):
    write_spikes(store, KEY, spike_entry)  # entries are not cubes
    store.write_cube("b", make_cube())
    store.write_cube("a", make_cube(scale=2.0))
    results = open_results(store.root)
    assert list(results) == ["a", "b"]
    xr.testing.assert_identical(results["a"], make_cube(scale=2.0))


def test_cube_refuses_reserved_attribute(store):
    with pytest.raises(ValueError, match="reserved"):
        store.write_cube("c", make_cube().assign_attrs(eskin_sha256="x"))


# ---------------------------------------------------------------------------------------------
# Completeness


def test_partial_batches_are_invisible_and_cleaned(store, spike_entry):
    write_spikes(store, OTHER_KEY, spike_entry)
    batch = batch_of(store, "spikes", OTHER_KEY)
    partial = batch.parent / f".partial-{batch.name}"
    os.rename(batch, partial)  # a complete copy, never renamed into place
    assert not store.has(SPIKES.record, KEY)
    assert not store.has(SPIKES.record, OTHER_KEY)
    assert store.complete_keys(SPIKES.record) == frozenset()
    assert store.read_many(SPIKES.record, [OTHER_KEY], discard_corrupt=True) == {}
    with pytest.raises(StoreError, match=f"no spikes entry {OTHER_KEY}") as info:
        read_spikes(store, OTHER_KEY)
    assert not isinstance(info.value, CorruptEntryError)
    assert store.clean_partials(older_than_s=3600) == 0  # too fresh to be abandoned
    assert partial.exists()
    assert store.clean_partials() == 1
    assert not partial.exists()
    assert written(store, "spikes") == []


def test_same_key_written_twice_stays_one_readable_entry(store, spike_entry):
    write_spikes(store, KEY, spike_entry)
    write_spikes(store, KEY, spike_entry)  # stored again, in a batch of its own
    assert len(batches(store, "spikes")) == 2
    assert store.complete_keys(SPIKES.record) == {KEY}
    assert_trains_identical(read_spikes(store, KEY).encoded.real, spike_entry.encoded.real)


def test_concurrent_writers_of_one_key(store):
    entry = ResultEntry({"ffnn": [[0.5, 1.0]]}, {"train_ffnn": 1.0}, metrics(), None, None)
    errors = []

    def write():
        try:
            write_result(store, KEY, entry)
        except Exception as error:  # pragma: no cover - reported below
            errors.append(error)

    threads = [threading.Thread(target=write) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    assert len(batches(store, "results")) == 4  # one whole batch per writer, none torn
    assert not [name for name in os.listdir(store.path / "results") if name.startswith(".")]
    assert store.complete_keys(RESULTS.record) == {KEY}
    assert_results_identical(read_result(store, KEY), entry)


def test_failed_write_leaves_nothing(store, spike_entry, monkeypatch):
    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(store_module.os, "rename", boom)
    with pytest.raises(OSError, match="disk full"):
        store.write_entries(SPIKES.record, {KEY: spike_entry, OTHER_KEY: spike_entry})
    assert written(store, "spikes") == []


@pytest.mark.parametrize(
    ("code", "cause"),
    [
        (errno.ENOSPC, "no space left on the device"),
        (errno.EDQUOT, "disk quota exceeded"),
        (errno.EACCES, "permission denied"),
        (errno.EPERM, "operation not permitted"),
        (errno.EROFS, "read-only file system"),
    ],
)
def test_a_write_without_space_or_permission_is_one_store_write_error(
    store, spike_entry, monkeypatch, code, cause
):
    """Raised deep in Zarr's writer thread, re-raised as one line naming the root and cause;
    it pickles (a Dask worker sends it back) and nothing of the batch is left."""

    def full(path, *args, **kwargs):
        (Path(path) / "zarr.json").parent.mkdir(parents=True)  # a half-written batch
        try:
            raise OSError(code, os.strerror(code))
        except OSError as error:
            raise RuntimeError("wrapped by a library") from error

    monkeypatch.setattr(store_module, "write_batch", full)
    with pytest.raises(StoreWriteError) as caught:
        store.write_entries(SPIKES.record, {KEY: spike_entry})
    assert str(caught.value) == f"cannot write to run root {store.root}: {cause}"
    assert caught.value.exit_status == 1
    again = pickle.loads(pickle.dumps(caught.value))
    assert type(again) is StoreWriteError and (again.root, again.cause) == (str(store.root), cause)
    assert written(store, "spikes") == []
    assert not list((store.path / "spikes").glob(".partial-*"))


def test_a_cube_without_space_is_a_store_write_error(store, monkeypatch):
    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_zarr", full)
    with pytest.raises(StoreWriteError, match="no space left on the device"):
        store.write_cube("grid", make_cube())
    assert store.cube_names() == []


def test_other_write_errors_pass_unchanged(store, spike_entry, monkeypatch):
    def broken(*args, **kwargs):
        raise OSError(errno.EIO, "I/O error")

    monkeypatch.setattr(store_module, "write_batch", broken)
    with pytest.raises(OSError, match="I/O error") as caught:
        store.write_entries(SPIKES.record, {KEY: spike_entry})
    assert not isinstance(caught.value, StoreError)


def test_write_entries_of_nothing_writes_nothing(store):
    store.write_entries(RESULTS.record, {})
    assert written(store, "results") == []


def test_discard(store, spike_entry):
    write_spikes(store, KEY, spike_entry)
    assert store.discard(SPIKES.record, KEY) is True
    assert not store.has(SPIKES.record, KEY)
    assert written(store, "spikes") == []
    assert store.discard(SPIKES.record, KEY) is False


def test_discard_removes_the_whole_batch_of_a_key(store):
    store.write_entries(RESULTS.record, {KEY: result_entry(1), OTHER_KEY: result_entry(2)})
    write_result(store, THIRD_KEY, result_entry(3))
    kept = batch_of(store, "results", THIRD_KEY)
    assert store.discard("results", KEY) is True
    assert not store.has("results", KEY)
    assert not store.has("results", OTHER_KEY)  # it shared the batch
    assert store.discard("results", OTHER_KEY) is False
    assert batches(store, "results") == [kept]
    assert store.complete_keys("results") == {THIRD_KEY}
    assert_results_identical(read_result(store, THIRD_KEY), result_entry(3))


def test_complete_keys_after_writing_many_keys(store, spike_entry):
    assert store.complete_keys(SPIKES.record) == frozenset()
    many = {key(i): result_entry(i) for i in range(40)}
    store.write_entries(RESULTS.record, many)
    write_result(store, KEY, result_entry())
    write_spikes(store, OTHER_KEY, spike_entry)
    found = store.complete_keys(RESULTS.record)
    assert isinstance(found, frozenset)
    assert found == {*many, KEY}
    assert store.complete_keys("spikes") == {OTHER_KEY}
    assert all(store.has(RESULTS.record, k) for k in many)


def test_read_many_reads_keys_from_one_batch_and_from_several(store, monkeypatch):
    first = {key(i): result_entry(i) for i in range(5)}
    store.write_entries(RESULTS.record, first)
    store.write_entries(RESULTS.record, {KEY: result_entry(9), OTHER_KEY: result_entry(8)})
    reads = []
    read_batch = store_module.read_batch

    def counting(path, kind):
        reads.append(Path(path).name)
        return read_batch(path, kind)

    monkeypatch.setattr(store_module, "read_batch", counting)
    wanted = [key(3), key(0), THIRD_KEY, key(3)]  # an absent key and a repeated one
    read = store.read_many(RESULTS.record, wanted, discard_corrupt=False)
    assert sorted(read) == sorted([key(0), key(3)])
    for k in read:
        assert_results_identical(read[k], first[k])
    assert reads == [batch_of(store, "results", key(0)).name]  # one batch, read once

    reads.clear()
    read = store.read_many(RESULTS.record, [OTHER_KEY, key(4), KEY], discard_corrupt=True)
    assert sorted(read) == sorted([OTHER_KEY, key(4), KEY])
    assert_results_identical(read[OTHER_KEY], result_entry(8))
    assert_results_identical(read[KEY], result_entry(9))
    assert_results_identical(read[key(4)], first[key(4)])
    assert sorted(reads) == sorted(b.name for b in batches(store, "results"))
    assert store.read_many(RESULTS.record, [], discard_corrupt=False) == {}


def truncate_a_chunk(batch: Path) -> None:
    path = chunk(batch, "accuracy")
    path.write_bytes(path.read_bytes()[:3])


def test_read_many_discards_a_corrupt_batch_whole_or_raises(store):
    store.write_entries(RESULTS.record, {KEY: result_entry(1), OTHER_KEY: result_entry(2)})
    write_result(store, THIRD_KEY, result_entry(3))
    corrupt = batch_of(store, "results", KEY)
    truncate_a_chunk(corrupt)
    keys = [KEY, THIRD_KEY]
    with pytest.raises(CorruptEntryError, match=f"corrupt results batch {corrupt.name}"):
        store.read_many(RESULTS.record, keys, discard_corrupt=False)
    assert corrupt.exists()  # raising discards nothing
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read = store.read_many(RESULTS.record, keys, discard_corrupt=True)
    assert [type(w.message) for w in caught] == [RuntimeWarning]  # one warning per batch
    assert corrupt.name in str(caught[0].message) and "recomputing" in str(caught[0].message)
    assert list(read) == [THIRD_KEY]
    assert_results_identical(read[THIRD_KEY], result_entry(3))
    assert not corrupt.exists()
    assert store.complete_keys(RESULTS.record) == {THIRD_KEY}  # OTHER_KEY went with it


def test_read_valid_discards_a_corrupt_entry_with_a_warning(store, spike_entry):
    assert store.read_valid(SPIKES.record, KEY) is None
    write_spikes(store, KEY, spike_entry)
    assert store.read_valid(SPIKES.record, KEY) is not None
    batch = batch_of(store, "spikes", KEY)
    path = chunk(batch, "true_times_s")
    path.write_bytes(path.read_bytes()[:3])
    with pytest.warns(RuntimeWarning, match=f"corrupt spikes batch {batch.name}.*recomputing"):
        assert store.read_valid(SPIKES.record, KEY) is None
    assert not batch.exists()
    assert written(store, "spikes") == []


def test_peek_results_skips_a_corrupt_batch_without_removing_it(store):
    store.write_entries(RESULTS.record, {KEY: result_entry(1), OTHER_KEY: result_entry(2)})
    write_result(store, THIRD_KEY, result_entry(3))
    truncate_a_chunk(batch_of(store, "results", KEY))
    before = listing(store.root)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning either
        found = store.peek_many(RESULTS.record, [KEY, THIRD_KEY, OTHER_KEY, key(7)])
        assert peek_result(store, KEY) is None
        assert_results_identical(peek_result(store, THIRD_KEY), result_entry(3))
    assert list(found) == [THIRD_KEY]
    assert_results_identical(found[THIRD_KEY], result_entry(3))
    assert listing(store.root) == before  # writes nothing, removes nothing
    assert store.has(RESULTS.record, KEY)


def test_a_batch_discarded_by_another_worker_reads_as_absent(store, monkeypatch):
    write_result(store, KEY, result_entry())
    listed = storage.index.index

    def listed_then_discarded(folder):
        found = listed(folder)
        for batch in set(found.values()):
            shutil.rmtree(folder / batch)  # another worker's discard
        return found

    monkeypatch.setattr(storage.index, "index", listed_then_discarded)
    assert store.read_valid(RESULTS.record, KEY) is None


def test_junk_in_a_kind_folder_is_invisible(store, spike_entry):
    # A batch-named folder without metadata and an entry folder of the old layout.
    junk = store.path / "spikes" / f"batch-{uuid.uuid4().hex}" / "true_times_s" / "c"
    junk.mkdir(parents=True)
    (junk / "0").write_bytes(b"junk")
    old = store.path / "spikes" / KEY
    old.mkdir()
    (old / "zarr.json").write_text(json.dumps({"zarr_format": 3, "node_type": "group"}))
    assert not store.has(SPIKES.record, KEY)
    assert store.complete_keys(SPIKES.record) == frozenset()
    assert store.read_valid(SPIKES.record, KEY) is None
    write_spikes(store, KEY, spike_entry)
    assert_trains_identical(read_spikes(store, KEY).encoded.true, spike_entry.encoded.true)


# ---------------------------------------------------------------------------------------------
# Integrity


@pytest.mark.parametrize("offset", [0, 4, -8], ids=["header", "early", "late"])
def test_flipped_bytes_are_corruption(store, spike_entry, offset):
    write_spikes(store, KEY, spike_entry)
    batch = batch_of(store, "spikes", KEY)
    path = chunk(batch, "true_times_s")
    data = bytearray(path.read_bytes())
    data[offset] ^= 0xFF
    data[offset + 1] ^= 0x55
    path.write_bytes(bytes(data))
    with pytest.raises(CorruptEntryError, match=f"corrupt spikes batch {batch.name}") as info:
        read_spikes(store, KEY)
    assert str(store.root) in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("size", [0, 5], ids=["empty", "short"])
def test_truncated_chunk_is_corruption(store, spike_entry, size):
    write_spikes(store, KEY, spike_entry)
    batch = batch_of(store, "spikes", KEY)
    path = chunk(batch, "real_count")
    path.write_bytes(path.read_bytes()[:size])
    with pytest.raises(CorruptEntryError, match=f"corrupt spikes batch {batch.name}"):
        read_spikes(store, KEY)


def test_missing_chunk_is_corruption(store, spike_entry):
    # Zarr reads a missing chunk as its fill value; only the checksum notices.
    write_spikes(store, KEY, spike_entry)
    chunk(batch_of(store, "spikes", KEY), "true_start").unlink()
    with pytest.raises(CorruptEntryError, match="'true_start' fails its sha256"):
        read_spikes(store, KEY)


def test_edited_attributes_are_corruption(store):
    write_result(store, KEY, ResultEntry({"ffnn": [0.5]}, {"train_ffnn": 1.0}, metrics()))

    def edit(attrs):
        attrs["entries"][0]["attrs"]["seconds"]["train_ffnn"] = 2.0

    edit_batch_attributes(batch_of(store, "results", KEY), edit)
    with pytest.raises(CorruptEntryError, match="entry list fails its sha256"):
        read_result(store, KEY)


def test_unreadable_metadata_is_corruption_and_discard_allows_recompute(store):
    entry = ResultEntry({"ffnn": [0.5, 0.25]}, {}, metrics())
    write_result(store, KEY, entry)
    (batch_of(store, "results", KEY) / "accuracy" / "zarr.json").write_text("{not json")
    with pytest.raises(CorruptEntryError, match=f"results batch .* in {store.root}"):
        read_result(store, KEY)
    assert store.discard(RESULTS.record, KEY) is True
    write_result(store, KEY, entry)
    np.testing.assert_array_equal(read_result(store, KEY).fold_accuracy["ffnn"], [[0.5, 0.25]])


def test_batch_of_another_kind_is_corruption(store):
    write_result(store, KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics()))
    batch = batch_of(store, "results", KEY)
    (store.path / "spikes").mkdir()
    os.rename(batch, store.path / "spikes" / batch.name)
    assert store.has(SPIKES.record, KEY)  # its entry list names the key
    with pytest.raises(CorruptEntryError, match="not a batch of spikes entries"):
        read_spikes(store, KEY)


def test_corrupt_cube(store):
    store.write_cube("grid", make_cube())
    path = store.path / "cubes" / "grid" / "accuracy" / "c" / "0" / "0" / "0" / "0"
    path.write_bytes(path.read_bytes()[:-3])
    with pytest.raises(CorruptEntryError, match="cube grid"):
        store.read_cube("grid")
    with pytest.raises(CorruptEntryError):
        open_results(store.root)


# ---------------------------------------------------------------------------------------------
# Root validation


def test_existing_empty_directory_becomes_a_store_and_reopens(tmp_path):
    first = SweepStore.open_or_create(tmp_path)
    write_result(first, KEY, result_entry())
    for extra in (".prefect", ".dask", "logs"):  # our own companions make it non-empty
        (tmp_path / extra).mkdir()
    again = SweepStore.open_or_create(tmp_path)
    assert again.has(RESULTS.record, KEY)
    assert SweepStore.open(tmp_path).has(RESULTS.record, KEY)
    assert SweepStore.open_readonly(tmp_path).has(RESULTS.record, KEY)


def test_leftover_store_build_does_not_block_creation(tmp_path):
    (tmp_path / f".store.zarr-partial-{uuid.uuid4().hex}").mkdir()
    store = SweepStore.open_or_create(tmp_path)
    assert store.clean_partials() == 1
    assert sorted(os.listdir(tmp_path)) == ["store.zarr"]


def test_open_readonly_writes_nothing(tmp_path):
    assert SweepStore.open_readonly(tmp_path / "missing") is None
    assert not (tmp_path / "missing").exists()
    assert SweepStore.open_readonly(tmp_path) is None  # empty: nothing cached
    assert os.listdir(tmp_path) == []
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(StoreError, match="not empty and holds no store.zarr"):
        SweepStore.open_readonly(tmp_path)
    assert os.listdir(tmp_path) == ["notes.txt"]


def make_file(root: Path) -> Path:
    root.write_text("not a directory")
    return root


def make_foreign_dir(root: Path) -> Path:
    root.mkdir()
    (root / "notes.txt").write_text("mine")
    (root / ".prefect").mkdir()
    return root


def make_foreign_zarr(root: Path) -> Path:
    zarr.open_group(root / "store.zarr", mode="w", zarr_format=3, attributes={"owner": "else"})
    return root


def marked_store(version):
    def make(root: Path) -> Path:
        zarr.open_group(
            root / "store.zarr", mode="w", zarr_format=3, attributes={"eskin_sweep_store": version}
        )
        return root

    return make


def make_zarr_array(root: Path) -> Path:
    zarr.create_array(root / "store.zarr", shape=(2,), dtype="int8", zarr_format=3)
    return root


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (make_file, "is a file"),
        (make_foreign_dir, "not empty and holds no store.zarr"),
        (make_foreign_zarr, "lacks the 'eskin_sweep_store' marker"),
        (marked_store(4), "unsupported sweep store version 4"),
        (marked_store(0), "unsupported sweep store version 0"),
        (marked_store(True), "unsupported sweep store version True"),
        (marked_store("1"), "unsupported sweep store version '1'"),
        (make_zarr_array, "not a Zarr v3 group"),
    ],
    ids=["file", "foreign-dir", "foreign-zarr", "newer", "zero", "bool", "str", "array"],
)
def test_refused_roots_are_left_untouched(tmp_path, make, message):
    root = make(tmp_path / "run")
    before = listing(tmp_path)
    with pytest.raises(StoreError, match=message) as info:
        SweepStore.open_or_create(root)
    assert str(root) in str(info.value) and "\n" not in str(info.value)
    assert not isinstance(info.value, StoreLayoutError)
    with pytest.raises(StoreError):
        SweepStore.open(root)
    with pytest.raises(StoreError):
        SweepStore.open_readonly(root)
    with pytest.raises(StoreError):
        open_results(root)
    assert listing(tmp_path) == before


def make_layout_1_store(root: Path) -> Path:
    """A store as layout 1 left it: the marker 1 and one group per entry."""
    store = root / "store.zarr"
    (store / "spikes" / KEY / "true_times_s" / "c").mkdir(parents=True)
    (store / "rates").mkdir()
    meta = {"zarr_format": 3, "node_type": "group", "attributes": {"eskin_sweep_store": 1}}
    (store / "zarr.json").write_text(json.dumps(meta))
    entry = {"zarr_format": 3, "node_type": "group", "attributes": {"eskin_entry": "spikes"}}
    (store / "spikes" / KEY / "zarr.json").write_text(json.dumps(entry))
    (store / "spikes" / KEY / "true_times_s" / "c" / "0").write_bytes(b"\x01\x02\x03")
    return root


def test_layout_1_store_is_set_aside_and_a_new_one_created(tmp_path, spike_entry):
    root = make_layout_1_store(tmp_path / "run")
    (root / "logs").mkdir()  # a companion stays where it is
    before = listing(root / "store.zarr")
    contents = (root / "store.zarr" / "spikes" / KEY / "true_times_s" / "c" / "0").read_bytes()
    with pytest.warns(RuntimeWarning, match="older eskin-sweep") as caught:
        store = SweepStore.open_or_create(root)
    assert len(caught) == 1
    names = sorted(os.listdir(root))
    kept = [name for name in names if name.startswith("store.zarr-layout-")]
    assert len(kept) == 1 and re.fullmatch(r"store\.zarr-layout-1-\d{8}T\d{6}", kept[0])
    assert kept[0] in str(caught[0].message)
    assert sorted(set(names) - set(kept)) == ["logs", "store.zarr"]
    old = root / kept[0]
    assert listing(old) == before  # kept whole, untouched
    assert (old / "spikes" / KEY / "true_times_s" / "c" / "0").read_bytes() == contents
    # The new store is of the current layout, empty and usable.
    assert json.loads((store.path / "zarr.json").read_text())["attributes"] == {
        "eskin_sweep_store": 3
    }
    assert not store.has(SPIKES.record, KEY)
    write_spikes(store, KEY, spike_entry)
    assert_trains_identical(read_spikes(store, KEY).encoded.real, spike_entry.encoded.real)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # opened again: nothing more is set aside
        assert SweepStore.open_or_create(root).has(SPIKES.record, KEY)
    assert sorted(os.listdir(root)) == names
    assert listing(old) == before


def test_a_root_holding_only_a_set_aside_store_is_accepted(tmp_path):
    root = make_layout_1_store(tmp_path / "run")
    with pytest.warns(RuntimeWarning):
        store = SweepStore.open_or_create(root)
    shutil.rmtree(store.path)
    assert SweepStore.open_readonly(root) is None  # nothing usable is cached
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        store = SweepStore.open_or_create(root)
    assert store.complete_keys(SPIKES.record) == frozenset()


def test_layout_1_store_is_refused_by_open_and_ignored_by_open_readonly(tmp_path):
    root = make_layout_1_store(tmp_path / "run")
    before = listing(tmp_path)
    with pytest.raises(StoreLayoutError) as info:
        SweepStore.open(root)
    message = str(info.value)
    assert str(root) in message and "store layout 1" in message and "\n" not in message
    assert info.value.layout == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert SweepStore.open_readonly(root) is None
    with pytest.raises(StoreLayoutError):
        open_results(root)
    assert listing(tmp_path) == before  # neither writes anything


@pytest.fixture
def read_only_root(tmp_path):
    """An empty folder no one may write to: a read-only tmpfs mounted there when the tests run as
    root (as CI does: root writes through a folder's permissions), else a folder of mode 0555."""
    root = tmp_path / "run"
    root.mkdir()
    if os.geteuid() == 0:
        mount = ["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(root)]
        subprocess.run(mount, check=True)
        try:
            yield root
        finally:
            subprocess.run(["umount", "-l", str(root)], check=True)
        return
    root.chmod(0o555)
    try:
        yield root
    finally:
        root.chmod(0o755)


def test_read_only_root_is_refused(read_only_root):
    with pytest.raises(StoreError, match="not writable"):
        SweepStore.open_or_create(read_only_root)
    assert os.listdir(read_only_root) == []


def test_unwritable_root_by_access_check(tmp_path, monkeypatch):
    monkeypatch.setattr(store_module.os, "access", lambda *args, **kwargs: False)
    with pytest.raises(StoreError, match="not writable"):
        SweepStore.open_or_create(tmp_path)
    assert os.listdir(tmp_path) == []


def test_unwritable_root_with_a_layout_1_store_is_refused_before_setting_it_aside(
    tmp_path, monkeypatch
):
    root = make_layout_1_store(tmp_path / "run")
    before = listing(tmp_path)
    monkeypatch.setattr(store_module.os, "access", lambda *args, **kwargs: False)
    with pytest.raises(StoreError, match="not writable"):
        SweepStore.open_or_create(root)
    assert listing(tmp_path) == before


def test_unwritable_root_by_probe(tmp_path, monkeypatch):
    # What a read-only mount looks like even to root: os.access says yes, writing fails.
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Read-only file system")

    monkeypatch.setattr(layout.tempfile, "mkstemp", refuse)
    with pytest.raises(StoreError, match="not writable: PermissionError"):
        SweepStore.open_or_create(tmp_path)
    assert os.listdir(tmp_path) == []


def test_open_requires_an_existing_store(tmp_path):
    with pytest.raises(StoreError, match="does not exist"):
        SweepStore.open(tmp_path / "missing")
    with pytest.raises(StoreError, match="has no store.zarr"):
        SweepStore.open(tmp_path)
    with pytest.raises(StoreError, match="not a sweep store"):
        open_results(tmp_path)
    assert os.listdir(tmp_path) == []  # open never creates


# ---------------------------------------------------------------------------------------------
# Validation of names and values


@pytest.mark.parametrize(
    "key",
    [KEY.upper(), KEY[:-1], KEY + "0", "../" + KEY[3:], f".partial-{KEY}", "", None, 12],
)
def test_invalid_keys(store, key, spike_entry):
    with pytest.raises(ValueError, match="invalid spikes key"):
        store.has(SPIKES.record, key)
    with pytest.raises(ValueError, match="invalid results key"):
        read_result(store, key)
    with pytest.raises(ValueError, match="invalid results key"):
        store.read_many(RESULTS.record, [KEY, key], discard_corrupt=True)
    with pytest.raises(ValueError, match="invalid results key"):
        store.peek_many(RESULTS.record, [key])
    with pytest.raises(ValueError, match="invalid spikes key"):
        store.discard(SPIKES.record, key)
    with pytest.raises(ValueError, match="invalid spikes key"):
        store.write_entries(SPIKES.record, {OTHER_KEY: spike_entry, key: spike_entry})
    assert written(store, "spikes") == []  # the valid key neither


@pytest.mark.parametrize("name", ["", "a" * 65, "../x", "a/b", ".hidden", "a b", "é", None])
def test_invalid_cube_names(store, name):
    with pytest.raises(ValueError, match="invalid cube name"):
        store.write_cube(name, make_cube())
    with pytest.raises(ValueError, match="invalid cube name"):
        store.read_cube(name)


@pytest.mark.parametrize("kind", ["cubes", "", "../x", "Spikes", "a b"])
def test_unknown_kind(store, kind):
    with pytest.raises(ValueError):
        store.has(kind, KEY)
    with pytest.raises(ValueError):
        store.complete_keys(kind)


def test_entries_of_the_wrong_type_are_refused(store, spike_entry):
    with pytest.raises(TypeError, match="must be a ResultEntry"):
        store.write_entries(RESULTS.record, {KEY: result_entry(), OTHER_KEY: spike_entry})
    with pytest.raises(TypeError, match="must be a SpikeEntry"):
        store.write_entries(SPIKES.record, {KEY: result_entry()})
    for kind in ("spikes", "results"):
        assert written(store, kind) == []


def test_inconsistent_values_are_refused_before_writing(store, spike_entry):
    true = spike_entry.encoded.true
    bad_count = SpikeTrains(true.times_s, true.polarity, true.count + 1, true.duration_s)
    other_duration = SpikeTrains(true.times_s, true.polarity, true.count, true.duration_s + 1)
    cases = [
        (SpikeEntry(Encoded(bad_count, bad_count), metrics(), {}), "sum to"),
        (SpikeEntry(Encoded(true, other_duration), metrics(), {}), "duration_s"),
        (SpikeEntry(Encoded(true, true), metrics(), {"readout": np.inf}), "not finite"),
    ]
    for entry, message in cases:
        with pytest.raises(ValueError, match=message):
            write_spikes(store, KEY, entry)
        with pytest.raises(ValueError, match=message):  # one bad entry refuses the batch
            store.write_entries(SPIKES.record, {OTHER_KEY: spike_entry, KEY: entry})
    with pytest.raises(ValueError, match="cannot store float64"):
        labels = OutOfFold(("a",), np.array([0.5]), {"ffnn": np.array([[0]])}, np.array([[0]]))
        write_result(store, KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics(), None, labels))
    with pytest.raises(ValueError, match="values do not fit int8"):
        polarity = true.polarity.astype(np.int64) * 300
        trains = SpikeTrains(true.times_s, polarity, true.count, true.duration_s)
        write_spikes(store, KEY, SpikeEntry(Encoded(trains, trains), metrics(), {}))
    with pytest.raises(ValueError, match="same"):
        write_result(store, KEY, ResultEntry({"ffnn": [0.5], "cnn": [0.5, 1.0]}, {}, metrics()))
    with pytest.raises(ValueError, match="no model"):
        write_result(store, KEY, ResultEntry({}, {}, metrics()))
    for kind in ("spikes", "results"):
        assert written(store, kind) == []


# ---------------------------------------------------------------------------------------------
# The sweep lock


HOLD_LOCK = """
import sys, time
from storage import SweepStore
with SweepStore.open(sys.argv[1]).lock():
    print("locked", flush=True)
    time.sleep(600)
"""


def hold_lock_in_child(root: Path) -> subprocess.Popen:
    child = subprocess.Popen(
        [sys.executable, "-c", HOLD_LOCK, str(root)], stdout=subprocess.PIPE, text=True
    )
    assert child.stdout.readline().strip() == "locked"
    return child


def test_lock_refuses_a_second_process_naming_root_and_pid(store):
    child = hold_lock_in_child(store.root)
    try:
        with pytest.raises(StoreBusyError) as info, store.lock():
            pass
        message = str(info.value)
        assert f"run root {store.root} is in use by another sweep (PID {child.pid} on" in message
        assert "\n" not in message
    finally:
        child.kill()
        child.wait()
    with store.lock():  # the kernel released the killed holder's lock
        pass


def test_lock_on_a_full_disk_is_taken_without_its_holder_note(store, monkeypatch):
    import storage.locking

    def full(fd, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(storage.locking.os, "write", full)
    with store.lock():
        monkeypatch.undo()
        child = subprocess.run(
            [sys.executable, "-c", HOLD_LOCK, str(store.root)], capture_output=True, text=True
        )
    assert child.returncode != 0 and "in use by another sweep (PID unknown)" in child.stderr


def test_lock_nests_within_one_process_and_is_released_by_the_outermost(store):
    with store.lock(), SweepStore.open(store.root).lock():
        pass
    child = hold_lock_in_child(store.root)  # free again
    child.kill()
    child.wait()
