"""Run roots on object storage (``s3://bucket/prefix``), against a loopback moto server.

The object interface is checked on both implementations (S3 and a local folder); the store on
an object root against the same entries and cubes on a folder root, exactly.
"""

import json
import pickle
import time

import numpy as np
import pytest
import xarray as xr

from pipeline.run.stages import RESULTS, SPIKES
from storage import (
    StoreBusyError,
    StoreError,
    StoreWriteError,
    SweepStore,
    lease,
    object_root,
    open_results,
)
from storage.locking import LOCK_NAME
from storage.objects import Conflict, PosixObjects, S3Objects, is_object_url, run_root
from storage.runlog import append_sweep_run, read_sweep_records
from tests.object_store import bucket, s3_server  # noqa: F401  (fixtures)
from tests.storage.test_store import (
    KEY,
    OTHER_KEY,
    assert_results_identical,
    assert_trains_identical,
    make_cube,
    result_entry,
    spike_entry,  # noqa: F401  (fixture)
)

SUMMARY = {"grid": "smoke", "points": 2, "cache_hits": 0, "computed": 2, "seconds": 1.5}


@pytest.fixture(params=["s3", "posix"])
def objects(request, tmp_path):
    if request.param == "posix":
        return PosixObjects(tmp_path)
    return S3Objects(request.getfixturevalue("bucket") + "/prefix")


@pytest.fixture
def s3_store(bucket) -> SweepStore:  # noqa: F811
    return SweepStore.open_or_create(f"{bucket}/runs/one/")


def stored_keys(store: SweepStore, prefix: str) -> list[str]:
    return sorted(o.key for o in store._objects.objects.list(f"store.zarr/{prefix}"))


# ---------------------------------------------------------------------------------------------
# The object interface


def test_objects_put_get_list_delete(objects):
    etag = objects.put("a/b.json", b"1")
    assert objects.get("a/b.json") == (b"1", etag)
    objects.put("a/c", b"22")
    objects.put("d", b"")
    assert [o.key for o in objects.list("a/")] == ["a/b.json", "a/c"]
    assert [o.key for o in objects.list("")] == ["a/b.json", "a/c", "d"]
    objects.delete(["a/b.json", "missing"])
    assert [o.key for o in objects.list("")] == ["a/c", "d"]
    with pytest.raises(FileNotFoundError):
        objects.get("a/b.json")


def test_objects_conditional_writes(objects):
    etag = objects.put_if_absent("lock", b"mine")
    with pytest.raises(Conflict):
        objects.put_if_absent("lock", b"theirs")
    newer = objects.put_if_match("lock", b"renewed", etag)
    assert objects.get("lock") == (b"renewed", newer)
    with pytest.raises(Conflict):
        objects.put_if_match("lock", b"stale", etag)  # the ETag it replaced
    objects.delete(["lock"])
    with pytest.raises(Conflict):
        objects.put_if_match("lock", b"gone", newer)
    with pytest.raises(FileNotFoundError):
        objects.get("lock")


def test_roots_are_folders_or_urls(tmp_path):
    assert is_object_url("s3://bucket/prefix") and not is_object_url(str(tmp_path))
    assert run_root("s3://bucket/prefix/") == "s3://bucket/prefix"
    assert run_root(str(tmp_path)) == tmp_path


def test_s3_objects_pickle_as_their_url(bucket):  # noqa: F811
    objects = S3Objects(bucket)
    objects.put("x", b"1")
    again = pickle.loads(pickle.dumps(objects))
    assert again.url == bucket and again.get("x")[0] == b"1"
    assert len(pickle.dumps(objects)) < 200


# ---------------------------------------------------------------------------------------------
# Opening an object root


def test_an_empty_prefix_becomes_a_store_and_a_foreign_one_is_refused(bucket):  # noqa: F811
    assert SweepStore.open_readonly(f"{bucket}/new") is None
    with pytest.raises(StoreError, match="not a sweep store"):
        SweepStore.open(f"{bucket}/new")
    store = SweepStore.open_or_create(f"{bucket}/new")
    assert store.root == f"{bucket}/new"
    assert SweepStore.open(f"{bucket}/new/").root == store.root
    meta = json.loads(store._objects.objects.get("store.zarr/zarr.json")[0])
    assert meta["attributes"] == {"eskin_sweep_store": 3}
    S3Objects(f"{bucket}/other").put("notes.txt", b"mine")
    with pytest.raises(StoreError, match=r"^refusing run root s3://.*/other: not empty"):
        SweepStore.open_or_create(f"{bucket}/other")
    S3Objects(f"{bucket}/foreign").put("store.zarr/zarr.json", b'{"zarr_format": 3}')
    with pytest.raises(StoreError, match="not a Zarr v3 group"):
        SweepStore.open(f"{bucket}/foreign")


# ---------------------------------------------------------------------------------------------
# Entries


def test_entries_round_trip_and_pickle_to_workers(s3_store, spike_entry):  # noqa: F811
    s3_store.write_entries(SPIKES.record, {KEY: spike_entry})
    s3_store.write_entries(RESULTS.record, {KEY: result_entry(1), OTHER_KEY: result_entry(2)})
    worker = pickle.loads(pickle.dumps(s3_store))
    assert worker.complete_keys(RESULTS.record) == {KEY, OTHER_KEY}
    assert worker.has(SPIKES.record, KEY) and not worker.has(SPIKES.record, OTHER_KEY)
    spikes = worker.read_many(SPIKES.record, [KEY], discard_corrupt=False)[KEY]
    assert_trains_identical(spikes.encoded.true, spike_entry.encoded.true)
    assert_trains_identical(spikes.encoded.real, spike_entry.encoded.real)
    results = worker.peek_many(RESULTS.record, [OTHER_KEY, KEY])
    assert_results_identical(results[KEY], result_entry(1))
    assert_results_identical(results[OTHER_KEY], result_entry(2))
    location = worker.entry_location(RESULTS.record, KEY)
    assert location.startswith(f"{s3_store.root}/store.zarr/results/batch-")


def test_batches_and_cubes_are_published_with_their_group_metadata_last(
    s3_store,
    spike_entry,  # noqa: F811
    monkeypatch,
):
    written = []
    put = S3Objects.put

    def recorded(self, key, data):
        written.append(key)
        return put(self, key, data)

    monkeypatch.setattr(S3Objects, "put", recorded)
    s3_store.write_entries(SPIKES.record, {KEY: spike_entry})
    batch = [k for k in written if "/batch-" in k]
    assert len(batch) > 2 and batch[-1].endswith("/zarr.json") and batch[-1].count("/") == 3
    written.clear()
    s3_store.write_cube("c", make_cube())
    assert written[-1] == "store.zarr/cubes/c/current"
    version = written[-2].split("/")[3]
    assert written[-2] == f"store.zarr/cubes/c/{version}/zarr.json"
    assert all(k.startswith(f"store.zarr/cubes/c/{version}/") for k in written[:-1])


def test_a_batch_without_its_metadata_is_invisible_and_cleaned(
    s3_store,
    spike_entry,  # noqa: F811
    monkeypatch,
):
    s3_store.write_entries(SPIKES.record, {KEY: spike_entry})
    objects = s3_store._objects.objects
    (batch,) = {k.split("/")[2] for k in stored_keys(s3_store, "spikes/batch-")}
    # A killed publisher: every object of a batch but its group metadata.
    for info in objects.list(f"store.zarr/spikes/{batch}/"):
        torn = info.key.replace(batch, "batch-" + "e" * 32)
        if not torn.endswith(f"{'e' * 32}/zarr.json"):
            objects.put(torn, objects.get(info.key)[0])
    assert s3_store.complete_keys(SPIKES.record) == {KEY}
    assert s3_store.clean_partials() == 0  # too young: may be being written
    monkeypatch.setattr(object_root, "PARTIAL_AGE_S", 0.0)
    assert s3_store.clean_partials(older_than_s=3600) == 0
    assert s3_store.clean_partials() == 1
    assert {k.split("/")[2] for k in stored_keys(s3_store, "spikes/batch-")} == {batch}
    assert s3_store.has(SPIKES.record, KEY)


def test_discard_removes_the_metadata_first_and_then_the_rest(s3_store, spike_entry):  # noqa: F811
    s3_store.write_entries(SPIKES.record, {KEY: spike_entry})
    assert s3_store.discard(SPIKES.record, KEY)
    assert not s3_store.has(SPIKES.record, KEY)
    assert stored_keys(s3_store, "spikes/batch-") == []
    assert not s3_store.discard(SPIKES.record, KEY)


def test_a_corrupt_batch_is_discarded_and_its_entries_recomputed(s3_store):
    s3_store.write_entries(RESULTS.record, {KEY: result_entry(1)})
    objects = s3_store._objects.objects
    chunk = next(k for k in stored_keys(s3_store, "results/") if "/c/" in k and "/accuracy" in k)
    data = bytearray(objects.get(chunk)[0])
    data[-1] ^= 0xFF
    objects.put(chunk, bytes(data))
    with pytest.warns(RuntimeWarning, match=r"corrupt results batch .* in s3://"):
        assert s3_store.read_valid(RESULTS.record, KEY) is None
    assert not s3_store.has(RESULTS.record, KEY)


# ---------------------------------------------------------------------------------------------
# Cubes


def test_cubes_are_identical_to_those_of_a_folder_root(s3_store, tmp_path):
    local = SweepStore.open_or_create(tmp_path / "run")
    for store in (local, s3_store):
        store.write_cube("threshold", make_cube(1.0), source="s1", note={"best": 1})
        store.write_cube("window", make_cube(2.0))
    assert s3_store.cube_names() == local.cube_names() == ["threshold", "window"]
    remote, here = open_results(s3_store.root), open_results(local.root)
    for name in here:
        xr.testing.assert_identical(remote[name], here[name])
        for var, variable in here[name].variables.items():
            np.testing.assert_array_equal(
                remote[name][var].values.view(np.uint8)
                if variable.dtype.kind in "fi"
                else remote[name][var].values,
                variable.values.view(np.uint8) if variable.dtype.kind in "fi" else variable.values,
            )
    lazy = open_results(s3_store.root, lazy=True)["threshold"]
    xr.testing.assert_identical(lazy.compute(), here["threshold"])
    assert s3_store.current_note("threshold", "s1") == {"best": 1}
    assert s3_store.current_note("threshold", "s2") is None
    assert s3_store.current_note("window", "s1") is None
    assert s3_store.current_note("missing", "s1") is None


def test_a_searchs_cubes_are_named_after_it_on_an_object_root_too(s3_store):
    s3_store.write_cube("design.trials", make_cube(1.0))
    s3_store.write_cube("design", make_cube(2.0))
    assert s3_store.cube_names() == ["design", "design.trials"]
    cubes = open_results(s3_store.root)
    assert list(cubes) == ["design", "design.trials"]
    xr.testing.assert_identical(cubes["design.trials"], make_cube(1.0))
    for bad in ("design.", ".trials", "a.b.c", "..", "a/b"):
        with pytest.raises(ValueError, match="invalid cube name"):
            s3_store.write_cube(bad, make_cube())


def test_a_cube_is_swapped_by_its_pointer_and_old_versions_go_after_a_grace(s3_store, monkeypatch):
    s3_store.write_cube("c", make_cube(1.0), source="s1", note={})
    objects = s3_store._objects.objects
    first = json.loads(objects.get("store.zarr/cubes/c/current")[0])["version"]
    s3_store.write_cube("c", make_cube(2.0), source="s2", note={})
    second = json.loads(objects.get("store.zarr/cubes/c/current")[0])["version"]
    assert first != second
    xr.testing.assert_identical(s3_store.read_cube("c"), make_cube(2.0))
    versions = {k.split("/")[3] for k in stored_keys(s3_store, "cubes/c/v-")}
    assert versions == {first, second}  # a reader of the old pointer still finds its version
    assert s3_store.clean_partials() == 0
    monkeypatch.setattr(object_root, "GRACE_S", 0.0)
    assert s3_store.clean_partials() == 1
    assert {k.split("/")[3] for k in stored_keys(s3_store, "cubes/c/v-")} == {second}
    xr.testing.assert_identical(s3_store.read_cube("c"), make_cube(2.0))


def test_a_changed_cube_object_is_not_current_and_fails_reading(s3_store):
    s3_store.write_cube("c", make_cube(), source="s1", note={"n": 1})
    objects = s3_store._objects.objects
    chunk = next(k for k in stored_keys(s3_store, "cubes/c/v-") if "/accuracy/c/" in k)
    data = bytearray(objects.get(chunk)[0])
    data[len(data) // 2] ^= 0xFF
    objects.put(chunk, bytes(data))
    assert s3_store.current_note("c", "s1") is None
    with pytest.raises(StoreError, match=r"corrupt cube c in s3://"):
        s3_store.read_cube("c")


def test_whether_a_cube_is_current_takes_a_listing_not_a_read_of_every_object(
    s3_store, monkeypatch
):
    s3_store.write_cube("c", make_cube(), source="s1", note={"n": 1})
    read, listed = [], []
    get, list_ = S3Objects.get, S3Objects.list
    monkeypatch.setattr(S3Objects, "get", lambda self, key: read.append(key) or get(self, key))
    monkeypatch.setattr(
        S3Objects, "list", lambda self, prefix: listed.append(prefix) or list_(self, prefix)
    )
    assert s3_store.current_note("c", "s1") == {"n": 1}
    version = json.loads(get(s3_store._objects.objects, "store.zarr/cubes/c/current")[0])
    prefix = f"store.zarr/cubes/c/{version['version']}/"
    assert read == ["store.zarr/cubes/c/current", f"{prefix}zarr.json"]
    assert listed == [prefix]
    assert set(version["etags"]) == {
        k.removeprefix(prefix) for k in stored_keys(s3_store, "cubes/c/v-")
    }


def test_a_pointer_without_etags_is_checked_against_the_manifest(s3_store):
    s3_store.write_cube("c", make_cube(), source="s1", note={"n": 1})
    objects = s3_store._objects.objects
    pointer = "store.zarr/cubes/c/current"
    version = json.loads(objects.get(pointer)[0])["version"]
    objects.put(pointer, f"{version}\n".encode())  # as stores written before ETags were kept
    assert s3_store.current_note("c", "s1") == {"n": 1}
    assert s3_store.current_note("c", "s2") is None
    xr.testing.assert_identical(s3_store.read_cube("c"), make_cube())
    chunk = next(k for k in stored_keys(s3_store, "cubes/c/v-") if "/accuracy/c/" in k)
    data = bytearray(objects.get(chunk)[0])
    data[len(data) // 2] ^= 0xFF
    objects.put(chunk, bytes(data))
    assert s3_store.current_note("c", "s1") is None
    objects.put(pointer, b"not a pointer")
    assert s3_store.current_note("c", "s1") is None
    assert s3_store.cube_names() == ["c"]
    with pytest.raises(StoreError, match="no cube 'c'"):
        s3_store.read_cube("c")


def test_many_objects_are_read_at_once(objects):
    keys = [f"many/{i:03d}" for i in range(40)]
    for i, key in enumerate(keys):
        objects.put(key, str(i).encode())
    assert objects.get_many(reversed(keys)) == {k: str(i).encode() for i, k in enumerate(keys)}
    with pytest.raises(FileNotFoundError):
        objects.get_many([keys[0], "many/missing"])


# ---------------------------------------------------------------------------------------------
# The lease


def lease_body(objects) -> dict:
    return json.loads(objects.get(LOCK_NAME)[0])


def test_a_held_lease_refuses_a_second_sweep_in_one_line(s3_store):
    objects = s3_store._objects.objects
    objects.put(
        LOCK_NAME,
        json.dumps(
            {"holder": "PID 1 on elsewhere", "token": "t", "expires_s": time.time() + 60}
        ).encode(),
    )
    with pytest.raises(StoreBusyError) as refused:
        with s3_store.lock():
            pass
    message = str(refused.value)
    assert "\n" not in message
    assert message.startswith(f"run root {s3_store.root} is in use by another sweep (PID 1 on")
    assert lease_body(objects)["token"] == "t"  # not touched


def test_an_expired_lease_is_taken_over_and_a_held_one_released(s3_store):
    objects = s3_store._objects.objects
    objects.put(
        LOCK_NAME,
        json.dumps(
            {"holder": "PID 1 on elsewhere", "token": "t", "expires_s": time.time() - 1}
        ).encode(),
    )
    with s3_store.lock(), s3_store.lock():  # taken over; nests within one process
        mine = lease_body(objects)
        assert mine["token"] != "t" and mine["expires_s"] > time.time()
    with pytest.raises(FileNotFoundError):
        objects.get(LOCK_NAME)  # released


def test_the_holder_renews_its_lease(s3_store, monkeypatch):
    monkeypatch.setenv("ESKIN_LEASE_S", "0.6")
    objects = s3_store._objects.objects
    with s3_store.lock():
        first = lease_body(objects)["expires_s"]
        deadline = time.monotonic() + 30
        while lease_body(objects)["expires_s"] == first and time.monotonic() < deadline:
            time.sleep(0.05)
        renewed = lease_body(objects)
        assert renewed["expires_s"] > first and renewed["token"] == lease_body(objects)["token"]
        # Renewed past its first expiry: another sweep is still refused.
        while time.time() < first + 0.1:
            time.sleep(0.05)
        other = lease._Lease(objects, 0.6)
        with pytest.raises(StoreBusyError):
            other.take()


def test_a_bad_lease_duration_is_refused(s3_store, monkeypatch):
    monkeypatch.setenv("ESKIN_LEASE_S", "soon")
    with pytest.raises(StoreError, match="ESKIN_LEASE_S='soon': expected a positive number"):
        with s3_store.lock():
            pass


# ---------------------------------------------------------------------------------------------
# The run log


def test_the_run_log_of_an_object_root(s3_store):
    assert read_sweep_records(s3_store.root) == []
    append_sweep_run(s3_store.root, SUMMARY)
    append_sweep_run(s3_store.root, {**SUMMARY, "computed": 0})
    records = read_sweep_records(s3_store.root)
    assert [r["computed"] for r in records] == [2, 0]
    assert set(records[0]) == {"finished", "grid", "points", "cache_hits", "computed", "seconds"}


def test_an_unreachable_object_store_is_one_short_line(monkeypatch):
    monkeypatch.setenv("AWS_ENDPOINT_URL", "http://127.0.0.1:1")  # nothing listens on port 1
    monkeypatch.setenv("AWS_ALLOW_HTTP", "true")
    monkeypatch.setenv("AWS_ACCESS_KEY_ID", "testing")
    monkeypatch.setenv("AWS_SECRET_ACCESS_KEY", "testing")
    monkeypatch.setenv("AWS_REGION", "us-east-1")
    with pytest.raises(StoreError) as refused:
        open_results("s3://eskin-nowhere/run")
    assert str(refused.value) == (
        "run root s3://eskin-nowhere/run: the object store at http://127.0.0.1:1 does not answer "
        "(error sending request): check AWS_ENDPOINT_URL and that the server is up"
    )


def test_the_lease_on_either_implementation(objects):
    def foreign(expires_s: float) -> None:
        body = {"holder": "PID 1 on elsewhere", "token": "t", "expires_s": expires_s}
        objects.put(LOCK_NAME, json.dumps(body).encode())

    foreign(time.time() + 60)
    with pytest.raises(StoreBusyError, match="in use by another sweep"):
        with lease.hold_lease(objects):
            pass
    foreign(time.time() - 1)
    with lease.hold_lease(objects):
        assert lease_body(objects)["token"] != "t"
    with pytest.raises(FileNotFoundError):
        objects.get(LOCK_NAME)


def test_a_refused_write_to_an_object_root_stops_like_a_full_disk(s3_store, monkeypatch):
    import obstore
    from obstore.exceptions import PermissionDeniedError

    def refused(*args, **kwargs):
        raise PermissionDeniedError("Access Denied")

    monkeypatch.setattr(obstore, "put", refused)
    with pytest.raises(StoreWriteError) as stopped:
        s3_store.write_entries(RESULTS.record, {KEY: result_entry(1)})
    assert str(stopped.value) == f"cannot write to run root {s3_store.root}: permission denied"
    with pytest.raises(StoreWriteError):
        s3_store.write_cube("c", make_cube())
