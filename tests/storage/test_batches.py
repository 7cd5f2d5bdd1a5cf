"""Batches: many entries in one Zarr group, exact round trips, corruption detected."""

import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
import zarr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import storage.batches as batches
from storage.batches import (
    BatchEntry,
    BatchError,
    digest,
    json_digest,
    nbytes,
    read_batch,
    read_batch_keys,
    write_batch,
)

NEG_NAN = -np.float64("nan")  # a NaN with the sign bit set
# What reading a corrupt batch may raise: BatchError (a ValueError) when a digest or the entry
# list does not match, OSError or ValueError when a chunk cannot be read, and RuntimeError,
# which numcodecs' zstd raises for a chunk it cannot decompress.
CORRUPT = (ValueError, OSError, RuntimeError)


def records() -> list[BatchEntry]:
    """Two entries of every supported kind of variable; the second lacks some of them."""
    return [
        BatchEntry(
            "first",
            {
                "t": (("event",), np.array([0.5, -0.0, NEG_NAN, np.inf, -np.inf, 5e-324]), {}),
                "p": (("event",), np.array([1, -1, -128, 127, 0, 1], np.int8), {}),
                "c": (
                    ("recording", "taxel"),
                    np.array([[0, 2**62], [-(2**63), 2**63 - 1], [7, -1]], np.int64),
                    {"units": "1"},
                ),
                "name": (("recording",), np.array(["bark/01", "", "µ-foam"], dtype=object), {}),
                "score": ((), np.float64(-np.inf), {"units": "dB", "long_name": "a score"}),
                "level": ((), np.int8(-3), {}),
                "model": ((), np.array("ffnn", dtype=object), {}),
            },
            {"ideal": False, "seconds": {"readout": 1.5, "taxels": 0.25}, "names": ["a", "é"]},
        ),
        BatchEntry(
            "second",
            {
                "t": (("event",), np.array([], np.float64), {}),
                "c": (("recording", "taxel"), np.zeros((0, 2), np.int64), {}),
                "name": (("recording",), np.array(["x"], dtype=object), {}),
                "score": ((), np.float64(NEG_NAN), {}),
            },
            {},
        ),
    ]


def assert_records_identical(actual: list[BatchEntry], expected: list[BatchEntry]) -> None:
    """Same keys in order, same attrs, same variables with equal dims, dtypes and bits."""
    assert [r.key for r in actual] == [r.key for r in expected]
    for got, want in zip(actual, expected, strict=True):
        assert got.attrs == want.attrs
        assert set(got.variables) == set(want.variables), got.key
        for name, (dims, values, _) in want.variables.items():
            values = np.asarray(values)
            got_dims, got_values, _ = got.variables[name]
            assert got_dims == tuple(dims), name
            assert got_values.shape == values.shape, name
            if values.dtype.kind == "O":
                assert got_values.dtype.kind in "OTU", name
                assert got_values.tolist() == values.tolist(), name
            else:
                assert got_values.dtype == values.dtype, name
                assert got_values.tobytes() == values.tobytes(), name  # NaN payloads, -0.0


def edit_metadata(path: Path, change) -> None:
    """Apply ``change`` to the group attributes of the batch at ``path``."""
    meta_path = path / "zarr.json"
    meta = json.loads(meta_path.read_text())
    change(meta["attributes"])
    meta_path.write_text(json.dumps(meta))


def consistently(change):
    """``change`` as a writer would make it: the entry list's digest recomputed to match."""

    def apply(attrs):
        change(attrs)
        attrs["sha256"]["@entries"] = json_digest(attrs["entries"])

    return apply


@pytest.fixture
def batch(tmp_path: Path) -> Path:
    path = tmp_path / "batch-0"
    write_batch(path, "spikes", records())
    return path


# ---------------------------------------------------------------------------------------------
# Round trips


def test_round_trip_is_exact(batch):
    assert_records_identical(read_batch(batch, "spikes"), records())


def test_layout_is_one_flat_array_per_variable(batch):
    meta = json.loads((batch / "zarr.json").read_text())
    assert meta["zarr_format"] == 3 and meta["node_type"] == "group"
    attrs = meta["attributes"]
    assert attrs["eskin_batch"] == "spikes"
    assert [entry["key"] for entry in attrs["entries"]] == ["first", "second"]
    assert attrs["entries"][1]["shapes"] == {"t": [0], "c": [0, 2], "name": [1], "score": []}
    assert set(attrs["sha256"]) == {"t", "p", "c", "name", "score", "level", "model", "@entries"}
    arrays = sorted(name for name in os.listdir(batch) if name != "zarr.json")
    assert arrays == sorted(["t", "p", "c", "name", "score", "level", "model"])
    count = json.loads((batch / "c" / "zarr.json").read_text())
    assert count["data_type"] == "int64" and count["shape"] == [6]  # 3 x 2 + 0 x 2 values
    assert count["dimension_names"] == ["flat_c"]
    assert count["attributes"]["dims"] == ["recording", "taxel"]
    assert count["attributes"]["units"] == "1"
    score = json.loads((batch / "score" / "zarr.json").read_text())
    assert score["shape"] == [2] and score["attributes"]["long_name"] == "a score"


def test_the_number_of_files_grows_with_variables_not_entries(tmp_path):
    def files(n_entries: int) -> int:
        path = tmp_path / f"batch-{n_entries}"
        write_batch(
            path,
            "spikes",
            [
                BatchEntry(f"k{i}", {"x": (("r",), np.arange(i + 1, dtype=np.float64), {})}, {})
                for i in range(n_entries)
            ],
        )
        return sum(len(names) for _, _, names in os.walk(path))

    assert files(1) == files(50) == 3  # the group's metadata, the array's and its chunk


def test_entries_without_variables(tmp_path):
    path = tmp_path / "batch"
    expected = [BatchEntry("a", {}, {"q": [1, None]}), BatchEntry("b", {}, {})]
    write_batch(path, "results", expected)
    assert_records_identical(read_batch(path, "results"), expected)


def test_big_variables_are_chunked_and_still_exact(tmp_path, monkeypatch):
    monkeypatch.setattr(batches, "CHUNK_BYTES", 32)  # four float64 values a chunk
    expected = [
        BatchEntry("a", {"x": (("i",), np.arange(6, dtype=np.float64) - 0.5, {})}, {}),
        BatchEntry("b", {"x": (("i",), np.array([NEG_NAN, -0.0, 1e300, 2.0]), {})}, {}),
    ]
    path = tmp_path / "batch"
    write_batch(path, "spikes", expected)
    assert sorted(os.listdir(path / "x" / "c")) == ["0", "1", "2"]
    assert_records_identical(read_batch(path, "spikes"), expected)
    # A well-formed chunk with other values (the first chunk's bytes) is caught by the digest.
    (path / "x" / "c" / "1").write_bytes((path / "x" / "c" / "0").read_bytes())
    with pytest.raises(BatchError, match="'x' fails its sha256"):
        read_batch(path, "spikes")


def test_empty_string_variable_round_trips(tmp_path):
    path = tmp_path / "batch"
    expected = [BatchEntry("a", {"name": (("recording",), np.array([], dtype=object), {})}, {})]
    write_batch(path, "results", expected)
    assert_records_identical(read_batch(path, "results"), expected)


SPEC = {
    "times": (("event",), np.dtype(np.float64)),
    "polarity": (("event",), np.dtype(np.int8)),
    "count": (("recording", "taxel"), np.dtype(np.int64)),
    "name": (("recording",), np.dtype(object)),
    "score": ((), np.dtype(np.float64)),
}
JSON = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**63), 2**63 - 1)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=5),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner, max_size=3)
    ),
    max_leaves=6,
)


@st.composite
def ragged_records(draw) -> list[BatchEntry]:
    """1-4 entries, each with a random subset of the variables in random shapes."""
    keys = draw(st.lists(st.text(max_size=8), min_size=1, max_size=4, unique=True))
    out = []
    for key in keys:
        variables = {}
        for name in draw(st.permutations(sorted(SPEC))):
            if not draw(st.booleans()):
                continue
            dims, dtype = SPEC[name]
            # Strings: at least one (an empty string variable is a known failure, above).
            low = 1 if dtype.kind == "O" else 0
            shape = tuple(draw(st.integers(low, 3)) for _ in dims)
            if dtype.kind == "O":
                size = int(np.prod(shape))
                texts = draw(st.lists(st.text(max_size=6), min_size=size, max_size=size))
                values = np.array(texts, dtype=object).reshape(shape)
            else:
                values = draw(hnp.arrays(dtype, shape))
            variables[name] = (dims, values, {})
        attrs = draw(st.dictionaries(st.text(max_size=6), JSON, max_size=3))
        out.append(BatchEntry(key, variables, attrs))
    return out


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ragged_records())
def test_property_ragged_entries_round_trip(expected):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "batch"
        write_batch(path, "spikes", expected)
        assert read_batch_keys(path) == tuple(r.key for r in expected)
        actual = read_batch(path, "spikes")
    assert_records_identical(actual, expected)


# ---------------------------------------------------------------------------------------------
# Keys


def test_read_batch_keys_reads_the_group_metadata_alone(batch):
    for name in os.listdir(batch):
        if name != "zarr.json":
            shutil.rmtree(batch / name)  # no array left: the keys are still known
    assert read_batch_keys(batch) == ("first", "second")


def test_read_batch_keys_of_a_missing_batch(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_batch_keys(tmp_path / "batch")


# ---------------------------------------------------------------------------------------------
# Corruption


@pytest.mark.parametrize("offset", [0, 4, -8], ids=["header", "early", "late"])
def test_flipped_chunk_bytes_are_corruption(batch, offset):
    path = batch / "t" / "c" / "0"
    data = bytearray(path.read_bytes())
    data[offset] ^= 0xFF
    data[offset + 1] ^= 0x55
    path.write_bytes(bytes(data))
    with pytest.raises(CORRUPT):
        read_batch(batch, "spikes")


@pytest.mark.parametrize("size", [0, 5], ids=["empty", "short"])
def test_truncated_chunk_is_corruption(batch, size):
    path = batch / "c" / "c" / "0"
    path.write_bytes(path.read_bytes()[:size])
    with pytest.raises(CORRUPT):
        read_batch(batch, "spikes")


def test_missing_chunk_is_corruption(batch):
    # Zarr reads a missing chunk as the fill value; only the digest notices.
    (batch / "p" / "c" / "0").unlink()
    with pytest.raises(BatchError, match="'p' fails its sha256"):
        read_batch(batch, "spikes")


def test_rewritten_values_are_corruption(batch):
    array = zarr.open_array(batch / "c", mode="r+", zarr_format=3)
    array[0] = 1  # a well-formed chunk holding other values
    with pytest.raises(BatchError, match="'c' fails its sha256"):
        read_batch(batch, "spikes")


def test_rewritten_strings_are_corruption(batch):
    array = zarr.open_array(batch / "name", mode="r+", zarr_format=3)
    array[1] = "y"
    with pytest.raises(BatchError, match="'name' fails its sha256"):
        read_batch(batch, "spikes")


def set_seconds(attrs):
    attrs["entries"][0]["attrs"]["seconds"]["readout"] = 2.0


def rename_key(attrs):
    attrs["entries"][1]["key"] = "third"


def drop_digest(attrs):
    del attrs["sha256"]["t"]


def drop_entries(attrs):
    del attrs["entries"]


def change_digest(attrs):
    attrs["sha256"]["score"] = json_digest("another")


def grow_shape(attrs):
    attrs["entries"][0]["shapes"]["t"] = [7]  # more values than the array holds


def add_dimension(attrs):
    attrs["entries"][1]["shapes"]["t"] = [0, 0]  # as many values, one dimension too many


def drop_shape(attrs):
    del attrs["entries"][1]["shapes"]["name"]  # the last value of 'name' belongs to no entry


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (set_seconds, "entry list fails its sha256"),
        (rename_key, "entry list fails its sha256"),
        (drop_digest, "variables do not match its checksums"),
        (drop_entries, "lacks entries or digests"),
        (change_digest, "'score' fails its sha256"),
        (consistently(grow_shape), "'t' does not match its entries' shapes"),
        (consistently(add_dimension), "'t' does not match its entries' shapes"),
        (consistently(drop_shape), "holds values of no entry"),
    ],
)
def test_edited_metadata_is_corruption(batch, change, message):
    edit_metadata(batch, change)
    with pytest.raises(BatchError, match=message):
        read_batch(batch, "spikes")


def test_removed_or_added_variable_is_corruption(batch, tmp_path):
    shutil.copytree(batch, tmp_path / "added")
    shutil.rmtree(batch / "level")
    with pytest.raises(BatchError, match="variables do not match its checksums"):
        read_batch(batch, "spikes")
    zarr.create_array(
        tmp_path / "added" / "extra", data=np.zeros(2), dimension_names=["flat_extra"]
    )
    with pytest.raises(BatchError, match="variables do not match its checksums"):
        read_batch(tmp_path / "added", "spikes")


def test_a_batch_of_another_kind_is_refused(batch):
    with pytest.raises(BatchError, match="not a batch of results entries"):
        read_batch(batch, "results")


# ---------------------------------------------------------------------------------------------
# Refusals


def one(key: str, name: str, dims: tuple[str, ...], values) -> BatchEntry:
    return BatchEntry(key, {name: (dims, np.asarray(values), {})}, {})


@pytest.mark.parametrize(
    ("entries", "message"),
    [
        ([], "at least one entry"),
        ([one("a", "x", ("i", "j"), [1.0, 2.0])], r"x: dims \('i', 'j'\) do not match"),
        ([one("a", "x", ("i",), 1.0)], r"x: dims \('i',\) do not match shape \(\)"),
        (
            [one("a", "x", ("i",), np.zeros(2)), one("b", "x", ("i",), np.zeros(2, np.float32))],
            "x: float32 .* in entry b, float64",
        ),
        (
            [one("a", "x", ("i",), np.zeros(2)), one("b", "x", ("j",), np.zeros(2))],
            r"x: float64 \('j',\) in entry b, float64 \('i',\) in another",
        ),
        (
            [one("a", "x", ("i",), [1, 2]), one("b", "x", ("i",), np.array([1, 2], np.int8))],
            "x: int8",
        ),
    ],
    ids=["empty", "dims-too-many", "dims-0d", "dtype", "dims-differ", "int-width"],
)
def test_inconsistent_batches_are_refused_before_writing(tmp_path, entries, message):
    path = tmp_path / "batch"
    with pytest.raises(ValueError, match=message):
        write_batch(path, "spikes", entries)
    assert not path.exists()


def test_attributes_json_cannot_hold_are_refused_before_writing(tmp_path):
    path = tmp_path / "batch"
    with pytest.raises(ValueError, match="JSON"):
        write_batch(path, "spikes", [BatchEntry("a", {}, {"seconds": float("nan")})])
    assert not path.exists()


def test_an_existing_batch_is_never_overwritten(batch):
    before = (batch / "zarr.json").read_bytes()
    with pytest.raises(FileExistsError):
        write_batch(batch, "spikes", [one("other", "x", ("i",), [1.0])])
    assert (batch / "zarr.json").read_bytes() == before
    assert_records_identical(read_batch(batch, "spikes"), records())


# ---------------------------------------------------------------------------------------------
# Digests


def test_digest_covers_dtype_shape_and_bytes_but_not_byte_order():
    values = np.arange(6, dtype=np.float64)
    assert digest(values) == digest(values.astype(">f8"))  # byte order is not content
    square = values.reshape(2, 3)
    assert digest(square) == digest(np.asfortranarray(square))  # memory order is not content
    assert digest(values) != digest(square)
    assert digest(values) != digest(values.astype(np.float32))
    assert digest(values) != digest(values.astype(np.int64))
    assert digest(np.array([0.0])) != digest(np.array([-0.0]))


def test_digest_of_strings_is_by_value_not_width():
    texts = ["bark", "µ-foam", ""]
    assert digest(np.array(texts)) == digest(np.array(texts, dtype=object))
    assert digest(np.array(texts)) == digest(np.array(texts, dtype=np.dtypes.StringDType()))
    assert digest(np.array(texts)) != digest(np.array(["bark", "µ-foam", " "]))
    assert digest(np.array(texts)) != digest(np.array(texts).reshape(3, 1))


def test_digest_canonical_nan_ignores_only_nan_payloads():
    payload = np.array([1.0, np.nan, NEG_NAN])
    plain = np.array([1.0, np.nan, np.nan])
    assert digest(payload) != digest(plain)
    assert digest(payload, canonical_nan=True) == digest(plain, canonical_nan=True)
    before = payload.tobytes()
    digest(payload, canonical_nan=True)
    assert payload.tobytes() == before  # the caller's array is not changed
    assert digest(np.array([1.0, np.nan]), canonical_nan=True) != digest(
        np.array([2.0, np.nan]), canonical_nan=True
    )


def test_json_digest_is_canonical_and_refuses_nan():
    assert json_digest({"a": 1, "b": [1.5, "x"]}) == json_digest({"b": [1.5, "x"], "a": 1})
    assert json_digest({"a": 1}) != json_digest({"a": 1.5})
    with pytest.raises(ValueError):
        json_digest({"a": float("inf")})


def test_nbytes_counts_the_values_of_every_variable():
    variables = records()[0].variables
    assert nbytes(variables) == sum(np.asarray(v).nbytes for _, v, _ in variables.values())
    assert nbytes({"x": (("i",), np.zeros(10), {}), "y": ((), np.int8(1), {})}) == 81
