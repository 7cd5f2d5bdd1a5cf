"""Sweep store: layout, exact round trips, completeness by rename, checksums, root refusal."""

import errno
import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import threading
import uuid
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import storage
import storage.store as store_module
from pipeline.cube import OutOfFold, RecordingsInfo
from pipeline.errors import EskinError
from pipeline.metrics import SpikeMetrics
from pipeline.scene import Model
from pipeline.spikes import Encoded, SpikeTrains
from storage import (
    CorruptEntryError,
    EntryKind,
    RateEntry,
    ResultEntry,
    SpikeEntry,
    StoreBusyError,
    StoreError,
    SweepStore,
    open_results,
)

KEY = "0123456789abcdef0123456789abcdef"
OTHER_KEY = "fedcba9876543210fedcba9876543210"
NEG_NAN = -np.float64("nan")  # a NaN with the sign bit set, as x86 produces for 0/0


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


def listing(path: Path) -> list[tuple[str, int]]:
    """Every path below ``path`` with its size (0 for directories), to prove nothing changed."""
    out = []
    for dirpath, dirnames, filenames in os.walk(path):
        for name in dirnames:
            out.append((os.path.join(dirpath, name), 0))
        for name in filenames:
            full = os.path.join(dirpath, name)
            out.append((full, os.path.getsize(full)))
    return sorted(out)


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


# ---------------------------------------------------------------------------------------------
# Layout


def test_public_names_are_reexported():
    # The package is the store's public names plus the run root as one DataTree.
    assert set(storage.__all__) == set(store_module.__all__) | {"open_tree"}
    assert issubclass(CorruptEntryError, StoreError) and issubclass(StoreError, EskinError)
    assert [k.value for k in EntryKind] == ["spikes", "rates", "results"]


def test_layout_is_a_marked_zarr_v3_group_without_consolidated_metadata(tmp_path):
    root = tmp_path / "a" / "b" / "run"  # parents are created too
    store = SweepStore.open_or_create(root)
    assert store.root == root and store.path == root / "store.zarr"
    assert sorted(os.listdir(root)) == ["store.zarr"]  # no probe or partial left behind
    meta = json.loads((root / "store.zarr" / "zarr.json").read_text())
    assert meta["zarr_format"] == 3 and meta["node_type"] == "group"
    assert meta["attributes"] == {"eskin_sweep_store": 1}
    assert meta.get("consolidated_metadata") is None
    group = zarr.open_group(root / "store.zarr", mode="r", zarr_format=3, use_consolidated=False)
    assert sorted(name for name, _ in group.groups()) == ["cubes", "rates", "results", "spikes"]


def test_entries_are_subgroups_named_by_key(store, spike_entry):
    store.write_spikes(KEY, spike_entry)
    entry = store.path / "spikes" / KEY
    assert sorted(os.listdir(store.path / "spikes")) == sorted(["zarr.json", KEY])
    meta = json.loads((entry / "zarr.json").read_text())
    assert meta["node_type"] == "group" and meta["attributes"]["eskin_entry"] == "spikes"
    assert meta.get("consolidated_metadata") is None
    times = json.loads((entry / "true_times_s" / "zarr.json").read_text())
    assert times["data_type"] == "float64" and times["dimension_names"] == ["true_event"]


def test_store_pickles_for_workers(store, spike_entry):
    store.write_spikes(KEY, spike_entry)
    clone = pickle.loads(pickle.dumps(store))
    assert clone.root == store.root and clone.has(EntryKind.SPIKES, KEY)


# ---------------------------------------------------------------------------------------------
# Round trips


def test_spikes_round_trip_non_ideal(store, spike_entry):
    assert spike_entry.encoded.true.count[2].sum() == 0  # a recording without any spike
    assert (spike_entry.encoded.true.count == 0).any()  # and empty trains elsewhere
    store.write_spikes(KEY, spike_entry)
    assert store.has(EntryKind.SPIKES, KEY) and store.has("spikes", KEY)
    read = store.read_spikes(KEY)
    assert read.encoded.real is not read.encoded.true
    assert_trains_identical(read.encoded.true, spike_entry.encoded.true)
    assert_trains_identical(read.encoded.real, spike_entry.encoded.real)
    assert_metrics_identical(read.metrics, spike_entry.metrics)
    assert read.seconds == {"taxels": 0.25, "readout": 1.5}


def test_spikes_round_trip_ideal_keeps_real_is_true_and_stores_once(store, spike_entry):
    true = spike_entry.encoded.true
    entry = SpikeEntry(Encoded(true, true), metrics(ssnr_db=-np.inf, ste_s2=0.0), {})
    store.write_spikes(KEY, entry)
    read = store.read_spikes(KEY)
    assert read.encoded.real is read.encoded.true
    assert_trains_identical(read.encoded.true, true)
    assert_metrics_identical(read.metrics, entry.metrics)
    assert read.seconds == {}
    stored = sorted(os.listdir(store.path / "spikes" / KEY))
    assert not any(name.startswith("real_") for name in stored)
    assert {"true_times_s", "true_polarity", "true_start", "true_count"} <= set(stored)


def test_spikes_start_is_stored_for_lazy_readers(store, spike_entry):
    store.write_spikes(KEY, spike_entry)
    with xr.open_zarr(store.path / "spikes" / KEY, consolidated=False, zarr_format=3) as ds:
        np.testing.assert_array_equal(ds["true_start"].values, spike_entry.encoded.true.start)
        assert ds["true_start"].dims == ("recording", "taxel")
        assert ds.attrs["ideal"] is False


@st.composite
def ragged(draw) -> tuple[SpikeTrains, SpikeTrains | None]:
    n_recordings = draw(st.integers(0, 3))
    n_taxels = draw(st.integers(1, 4))
    finite = st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=True)

    def trains() -> list[tuple[np.ndarray, np.ndarray]]:
        out = []
        for _ in range(n_recordings * n_taxels):
            times = sorted(draw(st.lists(finite, max_size=5)))
            polarity = draw(st.lists(st.sampled_from([-1, 1]), min_size=len(times)))
            out.append((np.array(times, np.float64), np.array(polarity[: len(times)], np.int8)))
        return out

    durations = np.array(draw(st.lists(finite, min_size=n_recordings, max_size=n_recordings)))
    true = SpikeTrains.concatenate(trains(), n_taxels, durations)
    real = SpikeTrains.concatenate(trains(), n_taxels, durations) if draw(st.booleans()) else None
    return true, real


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    ragged(),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=6, max_size=6),
)
def test_property_ragged_spike_trains_round_trip(trains, values):
    true, real = trains
    names = ("ssnr_db", "ste_s2", "ste_sign_safe_s2", "event_rate_hz", "data_rate_bps")
    entry = SpikeEntry(
        Encoded(true, true if real is None else real),
        SpikeMetrics(**dict(zip((*names, "equivalent_bits"), values, strict=True))),
        {"readout": 0.5},
    )
    with tempfile.TemporaryDirectory() as tmp:
        store = SweepStore.open_or_create(tmp)
        store.write_spikes(KEY, entry)
        read = store.read_spikes(KEY)
    assert (read.encoded.real is read.encoded.true) == (real is None)
    assert_trains_identical(read.encoded.true, true)
    if real is not None:
        assert_trains_identical(read.encoded.real, real)
    for name in (*names, "equivalent_bits"):
        assert bits(getattr(read.metrics, name)) == bits(getattr(entry.metrics, name))


def test_rates_round_trip(store):
    rng = np.random.default_rng(3)
    entry = RateEntry(
        counts=rng.integers(0, 2**40, (3, 2, 4, 5)),
        dropped=np.array([[0, 1, 2, 3], [4, 5, 6, 7], [0, 0, 0, 0]], dtype=np.int32),
        labels=np.array([2, 0, 1]),
        class_names=("bark", "cloth", "µ-foam"),
        seconds={"coding": 0.125},
    )
    store.write_rates(KEY, entry)
    read = store.read_rates(KEY)
    for name in ("counts", "dropped", "labels"):
        assert getattr(read, name).dtype == np.int64
        np.testing.assert_array_equal(getattr(read, name), getattr(entry, name))
    assert read.class_names == ("bark", "cloth", "µ-foam")
    assert read.seconds == {"coding": 0.125}


def test_results_round_trip_keeps_model_order(store):
    entry = ResultEntry(
        {Model.FFNN: np.array([0.5, 1.0, 0.0, NEG_NAN]), "cnn": [0.25, 0.75, 1 / 3, -0.0]},
        {"train_ffnn": 1.2, "train_cnn": 5},
        metrics(ssnr_db=np.inf, ste_s2=-np.inf),
    )
    store.write_result(KEY, entry)
    read = store.read_result(KEY)
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
    with xr.open_zarr(store.path / "results" / KEY, consolidated=False, zarr_format=3) as ds:
        assert ds["accuracy"].dims == ("model", "repeat", "fold")
        assert ds["model"].values.tolist() == ["ffnn", "cnn"]
        assert "predicted" not in ds  # kept no predictions: none written
    assert read.recordings is None  # stated nothing: read as unknown, never as empty
    assert read.out_of_fold is None


OUT_OF_FOLD = OutOfFold(
    recording_names=("bark/01", "bark/02", "µ-foam/01"),
    labels=np.array([0, 0, 1]),
    predicted={"ffnn": np.array([[0, 1, 1], [0, 0, 1]]), "cnn": np.array([[1, 1, 1], [0, 0, 0]])},
    test_fold=np.array([[0, 1, 0], [1, 0, 0]]),
)


def test_results_round_trip_out_of_fold_predictions_exactly(store):
    accuracy = {"ffnn": [[0.5, 1.0], [1.0, 1.0]], "cnn": [[0.5, 0.5], [0.5, 0.5]]}
    store.write_result(KEY, ResultEntry(accuracy, {}, metrics(), None, OUT_OF_FOLD))
    read = store.read_result(KEY)
    np.testing.assert_array_equal(read.fold_accuracy["ffnn"], accuracy["ffnn"])
    oof = read.out_of_fold
    assert oof.recording_names == OUT_OF_FOLD.recording_names
    assert list(oof.predicted) == ["ffnn", "cnn"]
    for model, values in OUT_OF_FOLD.predicted.items():
        assert oof.predicted[model].dtype == np.int64
        np.testing.assert_array_equal(oof.predicted[model], values)
    np.testing.assert_array_equal(oof.labels, OUT_OF_FOLD.labels)
    np.testing.assert_array_equal(oof.test_fold, OUT_OF_FOLD.test_fold)


def test_out_of_fold_predictions_must_match_the_models_and_repeats(store):
    with pytest.raises(ValueError, match="predictions of"):
        store.write_result(
            KEY, ResultEntry({"ffnn": [[0.5], [0.5]]}, {}, metrics(), None, OUT_OF_FOLD)
        )
    with pytest.raises(ValueError, match="2 repeats, accuracy has 1"):
        store.write_result(
            KEY, ResultEntry({"ffnn": [0.5], "cnn": [0.5]}, {}, metrics(), None, OUT_OF_FOLD)
        )
    with pytest.raises(ValueError, match="labels"):
        OutOfFold(("a", "b"), np.array([0]), {}, np.zeros((1, 2)))
    assert not store.has("results", KEY)  # nothing half-written


def test_results_written_before_repeats_read_as_one_repeat(store):
    """An entry with ``accuracy`` (model, fold), as written before repeats existed."""
    store.write_result(KEY, ResultEntry({"ffnn": [0.5, 0.25]}, {}, metrics()))
    group = zarr.open_group(store.path / "results" / KEY, mode="r+")
    stored = group["accuracy"]
    old = stored[:][:, 0]  # (model, fold)
    attrs = dict(stored.attrs)
    del group["accuracy"]
    group.create_array("accuracy", data=old, dimension_names=["model", "fold"]).attrs.update(attrs)
    digests = dict(group.attrs["sha256"])
    digests["accuracy"] = store_module._digest(old)
    group.attrs["sha256"] = digests
    read = store.read_result(KEY)
    np.testing.assert_array_equal(read.fold_accuracy["ffnn"], [[0.5, 0.25]])


@pytest.mark.parametrize(
    "info",
    [
        RecordingsInfo("three", ("bark", "cloth", "µ-foam"), 500),
        RecordingsInfo(class_names=("a",)),  # what an entry does not state stays unknown
    ],
)
def test_results_round_trip_what_they_state_of_their_recordings(store, info):
    store.write_result(KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics(), info))
    read = store.read_result(KEY).recordings
    assert read == info
    assert read.sampling_rate_hz is None or type(read.sampling_rate_hz) is float


def test_malformed_recordings_facts_are_refused_or_corrupt(store):
    negative = RecordingsInfo(sampling_rate_hz=-1.0)
    with pytest.raises(ValueError, match="sampling_rate_hz"):
        store.write_result(KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics(), negative))
    store.write_result(KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics(), RecordingsInfo("d")))
    meta_path = store.path / "results" / KEY / "zarr.json"
    meta = json.loads(meta_path.read_text())
    meta["attributes"]["dataset_name"] = 3
    digests = meta["attributes"].pop("sha256")
    digests["@attrs"] = store_module._attrs_digest(meta["attributes"])  # a consistent writer
    meta["attributes"]["sha256"] = digests
    meta_path.write_text(json.dumps(meta))
    with pytest.raises(CorruptEntryError, match="dataset_name"):
        store.read_result(KEY)


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
        monkeypatch.setattr(store_module, "_renameat2", lambda: None)
    store.write_cube("grid", make_cube())
    store.write_cube("grid", make_cube(scale=0.5))
    xr.testing.assert_identical(store.read_cube("grid"), make_cube(scale=0.5))
    assert sorted(os.listdir(store.path / "cubes")) == ["grid", "zarr.json"]


def test_failed_cube_replacement_keeps_the_old_cube(store, monkeypatch):
    monkeypatch.setattr(store_module, "_renameat2", lambda: None)  # take the move-aside path
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
    store.write_spikes(KEY, spike_entry)  # entries are not cubes
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


def test_partial_entries_are_invisible_and_cleaned(store, spike_entry):
    partial = store.path / "spikes" / f".partial-{KEY}-{uuid.uuid4().hex}"
    store.write_spikes(OTHER_KEY, spike_entry)
    os.rename(store.path / "spikes" / OTHER_KEY, partial)  # a complete copy, never renamed
    assert not store.has(EntryKind.SPIKES, KEY)
    assert not store.has(EntryKind.SPIKES, OTHER_KEY)
    with pytest.raises(StoreError, match=f"no spikes entry {KEY}") as info:
        store.read_spikes(KEY)
    assert not isinstance(info.value, CorruptEntryError)
    assert store.clean_partials(older_than_s=3600) == 0  # too fresh to be abandoned
    assert partial.exists()
    assert store.clean_partials() == 1
    assert not partial.exists()


def test_same_key_written_twice_keeps_one_readable_entry(store, spike_entry):
    store.write_spikes(KEY, spike_entry)
    store.write_spikes(KEY, spike_entry)  # loses the rename race, discards its copy
    assert sorted(os.listdir(store.path / "spikes")) == sorted(["zarr.json", KEY])
    assert_trains_identical(store.read_spikes(KEY).encoded.real, spike_entry.encoded.real)


def test_concurrent_writers_of_one_key(store):
    entry = RateEntry(np.ones((2, 1, 3, 4), int), np.zeros((2, 3), int), [0, 1], ("a", "b"), {})
    errors = []

    def write():
        try:
            store.write_rates(KEY, entry)
        except Exception as error:  # pragma: no cover - reported below
            errors.append(error)

    threads = [threading.Thread(target=write) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    assert sorted(os.listdir(store.path / "rates")) == sorted(["zarr.json", KEY])
    np.testing.assert_array_equal(store.read_rates(KEY).counts, entry.counts)


def test_failed_write_leaves_nothing(store, spike_entry, monkeypatch):
    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(store_module.os, "rename", boom)
    with pytest.raises(OSError, match="disk full"):
        store.write_spikes(KEY, spike_entry)
    assert os.listdir(store.path / "spikes") == ["zarr.json"]


def test_discard(store, spike_entry):
    store.write_spikes(KEY, spike_entry)
    assert store.discard(EntryKind.SPIKES, KEY) is True
    assert not store.has(EntryKind.SPIKES, KEY)
    assert os.listdir(store.path / "spikes") == ["zarr.json"]
    assert store.discard(EntryKind.SPIKES, KEY) is False


# ---------------------------------------------------------------------------------------------
# Integrity


def chunk(store: SweepStore, key: str, variable: str) -> Path:
    files = [p for p in (store.path / "spikes" / key / variable / "c").rglob("*") if p.is_file()]
    assert len(files) == 1
    return files[0]


@pytest.mark.parametrize("offset", [0, 4, -8], ids=["header", "early", "late"])
def test_flipped_bytes_are_corruption(store, spike_entry, offset):
    store.write_spikes(KEY, spike_entry)
    path = chunk(store, KEY, "true_times_s")
    data = bytearray(path.read_bytes())
    data[offset] ^= 0xFF
    data[offset + 1] ^= 0x55
    path.write_bytes(bytes(data))
    with pytest.raises(CorruptEntryError, match=f"spikes entry {KEY}") as info:
        store.read_spikes(KEY)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("size", [0, 5], ids=["empty", "short"])
def test_truncated_chunk_is_corruption(store, spike_entry, size):
    store.write_spikes(KEY, spike_entry)
    path = chunk(store, KEY, "real_count")
    path.write_bytes(path.read_bytes()[:size])
    with pytest.raises(CorruptEntryError, match=f"spikes entry {KEY}"):
        store.read_spikes(KEY)


def test_missing_chunk_is_corruption(store, spike_entry):
    # Zarr reads a missing chunk as its fill value; only the checksum notices.
    store.write_spikes(KEY, spike_entry)
    chunk(store, KEY, "true_polarity").unlink()
    with pytest.raises(CorruptEntryError, match="'true_polarity' fails its sha256"):
        store.read_spikes(KEY)


def test_edited_attributes_are_corruption(store):
    store.write_result(KEY, ResultEntry({"ffnn": [0.5]}, {"train_ffnn": 1.0}, metrics()))
    meta_path = store.path / "results" / KEY / "zarr.json"
    meta = json.loads(meta_path.read_text())
    meta["attributes"]["seconds"]["train_ffnn"] = 2.0
    meta_path.write_text(json.dumps(meta))
    with pytest.raises(CorruptEntryError, match="attributes fail their sha256"):
        store.read_result(KEY)


def test_unreadable_metadata_is_corruption_and_discard_allows_recompute(store):
    entry = ResultEntry({"ffnn": [0.5, 0.25]}, {}, metrics())
    store.write_result(KEY, entry)
    (store.path / "results" / KEY / "accuracy" / "zarr.json").write_text("{not json")
    with pytest.raises(CorruptEntryError, match=f"results entry {KEY}"):
        store.read_result(KEY)
    store.discard(EntryKind.RESULTS, KEY)
    store.write_result(KEY, entry)
    np.testing.assert_array_equal(store.read_result(KEY).fold_accuracy["ffnn"], [[0.5, 0.25]])


def test_entry_of_another_kind_is_corruption(store):
    store.write_result(KEY, ResultEntry({"ffnn": [0.5]}, {}, metrics()))
    os.rename(store.path / "results" / KEY, store.path / "rates" / KEY)
    with pytest.raises(CorruptEntryError, match="not a rates entry"):
        store.read_rates(KEY)


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
    first.write_rates(
        KEY, RateEntry(np.zeros((1, 1, 1, 1), int), np.zeros((1, 1), int), [0], ("a",), {})
    )
    for extra in (".prefect", ".dask", "logs"):  # our own companions make it non-empty
        (tmp_path / extra).mkdir()
    again = SweepStore.open_or_create(tmp_path)
    assert again.has(EntryKind.RATES, KEY)
    assert SweepStore.open(tmp_path).has(EntryKind.RATES, KEY)


def test_leftover_store_build_does_not_block_creation(tmp_path):
    (tmp_path / f".store.zarr-partial-{uuid.uuid4().hex}").mkdir()
    store = SweepStore.open_or_create(tmp_path)
    assert store.clean_partials() == 1
    assert sorted(os.listdir(tmp_path)) == ["store.zarr"]


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


def make_newer_store(root: Path) -> Path:
    zarr.open_group(
        root / "store.zarr", mode="w", zarr_format=3, attributes={"eskin_sweep_store": 2}
    )
    return root


def make_zarr_array(root: Path) -> Path:
    zarr.create_array(root / "store.zarr", shape=(2,), dtype="int8", zarr_format=3)
    return root


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (make_file, "is a file"),
        (make_foreign_dir, "not empty and holds no store.zarr"),
        (make_foreign_zarr, "lacks the 'eskin_sweep_store' marker"),
        (make_newer_store, "unsupported sweep store version 2"),
        (make_zarr_array, "not a Zarr v3 group"),
    ],
)
def test_refused_roots_are_left_untouched(tmp_path, make, message):
    root = make(tmp_path / "run")
    before = listing(tmp_path)
    with pytest.raises(StoreError, match=message) as info:
        SweepStore.open_or_create(root)
    assert str(root) in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(StoreError):
        SweepStore.open(root)
    with pytest.raises(StoreError):
        open_results(root)
    assert listing(tmp_path) == before


@pytest.mark.skipif(
    hasattr(os, "geteuid") and os.geteuid() == 0,
    reason="root may write to a read-only directory, so permissions cannot make one unwritable",
)
def test_read_only_root_is_refused(tmp_path):
    root = tmp_path / "run"
    root.mkdir()
    root.chmod(0o555)
    try:
        with pytest.raises(StoreError, match="not writable"):
            SweepStore.open_or_create(root)
        assert os.listdir(root) == []
    finally:
        root.chmod(0o755)


def test_unwritable_root_by_access_check(tmp_path, monkeypatch):
    monkeypatch.setattr(store_module.os, "access", lambda *args, **kwargs: False)
    with pytest.raises(StoreError, match="not writable"):
        SweepStore.open_or_create(tmp_path)
    assert os.listdir(tmp_path) == []


def test_unwritable_root_by_probe(tmp_path, monkeypatch):
    # What a read-only mount looks like even to root: os.access says yes, writing fails.
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Read-only file system")

    monkeypatch.setattr(store_module.tempfile, "mkstemp", refuse)
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
def test_invalid_keys(store, key):
    with pytest.raises(ValueError, match="invalid spikes key"):
        store.has(EntryKind.SPIKES, key)
    with pytest.raises(ValueError, match="invalid results key"):
        store.read_result(key)


@pytest.mark.parametrize("name", ["", "a" * 65, "../x", "a/b", ".hidden", "a b", "é", None])
def test_invalid_cube_names(store, name):
    with pytest.raises(ValueError, match="invalid cube name"):
        store.write_cube(name, make_cube())
    with pytest.raises(ValueError, match="invalid cube name"):
        store.read_cube(name)


def test_unknown_kind(store):
    with pytest.raises(ValueError):
        store.has("cubes", KEY)


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
            store.write_spikes(KEY, entry)
    with pytest.raises(ValueError, match="cannot store float64"):
        store.write_rates(
            KEY, RateEntry(np.zeros((1, 1, 1, 1), int), np.zeros((1, 1), int), [0.5], (), {})
        )
    with pytest.raises(ValueError, match="values do not fit int8"):
        polarity = true.polarity.astype(np.int64) * 300
        trains = SpikeTrains(true.times_s, polarity, true.count, true.duration_s)
        store.write_spikes(KEY, SpikeEntry(Encoded(trains, trains), metrics(), {}))
    with pytest.raises(ValueError, match="same"):
        store.write_result(KEY, ResultEntry({"ffnn": [0.5], "cnn": [0.5, 1.0]}, {}, metrics()))
    for kind in EntryKind:
        assert os.listdir(store.path / kind.value) == ["zarr.json"]


# ---------------------------------------------------------------------------------------------
# The sweep lock and leftovers of killed writers

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


def test_lock_nests_within_one_process_and_is_released_by_the_outermost(store):
    with store.lock(), SweepStore.open(store.root).lock():
        pass
    child = hold_lock_in_child(store.root)  # free again
    child.kill()
    child.wait()


def test_read_valid_discards_a_corrupt_entry_with_a_warning(store, spike_entry):
    assert store.read_valid(EntryKind.SPIKES, KEY) is None
    store.write_spikes(KEY, spike_entry)
    assert store.read_valid(EntryKind.SPIKES, KEY) is not None
    path = chunk(store, KEY, "true_times_s")
    path.write_bytes(path.read_bytes()[:3])
    with pytest.warns(RuntimeWarning, match=f"corrupt spikes entry {KEY}.*recomputing"):
        assert store.read_valid(EntryKind.SPIKES, KEY) is None
    assert not (store.path / "spikes" / KEY).exists()


def test_junk_left_at_an_entry_name_is_replaced(store, spike_entry):
    # A writer killed while its partial copy was removed under it can leave a folder without
    # metadata at the final name: invisible, and replaced by the next write of that key.
    junk = store.path / "spikes" / KEY / "true_times_s" / "c"
    junk.mkdir(parents=True)
    (junk / "0").write_bytes(b"junk")
    assert not store.has(EntryKind.SPIKES, KEY)
    store.write_spikes(KEY, spike_entry)
    assert_trains_identical(store.read_spikes(KEY).encoded.true, spike_entry.encoded.true)
