"""Tests of the dataset sources: folder datasets, VibTac-12, dispatch and the CLI argument."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pipeline.design.scene import Axis, DatasetKind, DatasetSpec
from pipeline.errors import DatasetError, EskinError
from pipeline.recordings.sources import (
    MAX_LISTED,
    Recordings,
    load_folder,
    load_recordings,
    load_vibtac12,
    resolve_dataset_argument,
)

# ---------------------------------------------------------------------------------------------
# Helpers


def write_csv(path: Path, values) -> None:
    path.write_text("".join(f"{float(v)!r}\n" for v in values), encoding="utf-8")


def make_folder(root: Path, classes: dict, toml: str | None = "sampling_rate_hz = 100.0\n") -> Path:
    """A folder dataset: ``classes`` maps class name -> {file name: array | str | bytes}."""
    root.mkdir(parents=True, exist_ok=True)
    if toml is not None:
        (root / "dataset.toml").write_text(toml, encoding="utf-8")
    for class_name, files in classes.items():
        folder = root / class_name
        folder.mkdir()
        for file_name, content in files.items():
            path = folder / file_name
            if isinstance(content, bytes):
                path.write_bytes(content)
            elif isinstance(content, str):
                path.write_text(content, encoding="utf-8")
            elif file_name.endswith(".npy"):
                np.save(path, content, allow_pickle=False)
            else:
                write_csv(path, content)
    return root


def good_classes(rng: np.random.Generator) -> dict:
    return {
        "smooth": {"r1.csv": rng.normal(size=50), "r2.npy": rng.normal(size=60)},
        "rough": {"r1.npy": rng.normal(size=40).astype(np.float32), "r2.csv": rng.normal(size=7)},
    }


def dataset_error(path: Path) -> str:
    with pytest.raises(DatasetError) as info:
        load_folder(path)
    message = str(info.value)
    assert "\n" not in message
    return message


def write_vibtac(root: Path, rows: np.ndarray, axes=("X", "Y", "Z")) -> Path:
    """Fake VibTac-12 files with the real layout: 3 leading zeros, ``%.18e``, no header."""
    root.mkdir(parents=True, exist_ok=True)
    padded = np.concatenate([np.zeros((rows.shape[0], 3)), rows], axis=1)
    for k, axis in enumerate(axes):
        np.savetxt(root / f"{axis}.csv", padded + 100 * k, fmt="%.18e", delimiter=",")
    return root


# ---------------------------------------------------------------------------------------------
# The value object


def test_recordings_properties_and_read_only_copies():
    signal = np.arange(5.0)
    rec = Recordings(
        signals=(signal, [1, 2, 3]),
        labels=[1, 0],
        class_names=("a", "b"),
        fs_hz=10,
        names=("b/0", "a/0"),
        units="N",
        name="tiny",
    )
    assert rec.n_recordings == 2
    assert rec.n_classes == 2
    assert rec.min_samples == 3
    np.testing.assert_array_equal(rec.durations_s, [0.5, 0.3])
    assert rec.durations_s.dtype == np.float64
    assert rec.labels.dtype == np.int64
    assert all(s.dtype == np.float64 for s in rec.signals)
    assert isinstance(rec.fs_hz, float)
    with pytest.raises(ValueError):
        rec.signals[0][0] = 1.0
    signal[0] = 99.0  # the caller's array is copied, not shared
    assert rec.signals[0][0] == 0.0
    assert signal.flags.writeable


@pytest.mark.parametrize(
    "changes",
    [
        {"labels": [0]},
        {"names": ("x",)},
        {"labels": [0, 2]},
        {"fs_hz": 0.0},
        {"fs_hz": float("nan")},
        {"class_names": ("a", "a")},
        {"signals": (np.zeros((2, 2)), np.zeros(3))},
    ],
)
def test_recordings_rejects_inconsistent_structure(changes):
    fields = dict(
        signals=(np.zeros(3), np.zeros(3)),
        labels=[0, 1],
        class_names=("a", "b"),
        fs_hz=1.0,
        names=("a/0", "b/0"),
        units="N",
        name="t",
    )
    with pytest.raises(ValueError):
        Recordings(**{**fields, **changes})


def test_recordings_rejects_non_finite_and_short_signals_naming_them():
    with pytest.raises(DatasetError, match=r"dataset t \(2 problems\): a/0: non-finite value inf "):
        Recordings(
            signals=(np.array([0.0, np.inf]), np.array([1.0])),
            labels=[0, 1],
            class_names=("a", "b"),
            fs_hz=1.0,
            names=("a/0", "b/0"),
            units="N",
            name="t",
        )


# ---------------------------------------------------------------------------------------------
# Folder datasets: round trip


def test_folder_round_trip_csv_and_npy(tmp_path):
    rng = np.random.default_rng(1)
    classes = good_classes(rng)
    toml = 'sampling_rate_hz = 250\nname = "bench"\nunits = "N"\n'
    root = make_folder(tmp_path / "ds", classes, toml)
    (root / "README.md").write_text("top-level files are ignored")
    (root / ".git").mkdir()
    (root / "rough" / ".DS_Store").write_bytes(b"\x00junk")
    rec = load_folder(root)
    assert rec.class_names == ("rough", "smooth")  # sorted by name
    assert rec.names == ("rough/r1.npy", "rough/r2.csv", "smooth/r1.csv", "smooth/r2.npy")
    np.testing.assert_array_equal(rec.labels, [0, 0, 1, 1])
    assert rec.fs_hz == 250.0
    assert (rec.name, rec.units) == ("bench", "N")
    expected = [
        classes["rough"]["r1.npy"].astype(np.float64),
        classes["rough"]["r2.csv"],
        classes["smooth"]["r1.csv"],
        classes["smooth"]["r2.npy"],
    ]
    for got, want in zip(rec.signals, expected, strict=True):
        np.testing.assert_array_equal(got, want)  # exact: repr() round-trips float64
        assert got.dtype == np.float64
    np.testing.assert_array_equal(rec.durations_s, [40 / 250, 7 / 250, 50 / 250, 60 / 250])


def test_folder_defaults_and_csv_details(tmp_path):
    classes = {
        "a": {
            # BOM, CRLF, surrounding spaces, integers, exponent, trailing blank lines
            "x.csv": "\ufeff 1\r\n-2.5e1 \r\n+.5\r\n\r\n\n",
            "y.npy": np.array([3, 4], dtype=np.int16),
        }
    }
    root = make_folder(tmp_path / "plain", classes)
    rec = load_folder(root)
    assert rec.name == "plain"
    assert rec.units == "a.u."
    np.testing.assert_array_equal(rec.signals[0], [1.0, -25.0, 0.5])
    np.testing.assert_array_equal(rec.signals[1], [3.0, 4.0])


@settings(max_examples=25, deadline=None)
@given(
    values=hnp.arrays(
        np.float64,
        st.integers(2, 40),
        elements=st.floats(allow_nan=False, allow_infinity=False, width=64),
    )
)
def test_folder_round_trip_is_exact_for_any_finite_values(values):
    with tempfile.TemporaryDirectory() as tmp:
        root = make_folder(Path(tmp) / "ds", {"c": {"a.csv": values, "b.npy": values}})
        rec = load_folder(root)
    np.testing.assert_array_equal(rec.signals[0], values)
    np.testing.assert_array_equal(rec.signals[1], values)


# ---------------------------------------------------------------------------------------------
# Folder datasets: errors, each naming what and where


def test_dataset_toml_description_is_free_text_and_not_loaded(tmp_path):
    classes = {"c": {"a.csv": [1.0, 2.0]}}
    plain = load_folder(make_folder(tmp_path / "plain", classes))
    for name, text in [("long", '"""Bench rig, 2024.\n\nSecond paragraph."""'), ("empty", '""')]:
        toml = f"sampling_rate_hz = 100\ndescription = {text}\n"
        described = load_folder(make_folder(tmp_path / name, classes, toml))
        assert (described.fs_hz, described.units, described.name) == (100.0, "a.u.", name)
        np.testing.assert_array_equal(described.signals[0], plain.signals[0])


def test_dataset_toml_unknown_keys_are_still_refused(tmp_path):
    toml = 'sampling_rate_hz = 1\ndescriptoin = "typo"\n'
    message = dataset_error(make_folder(tmp_path / "ds", {"c": {"a.csv": [1.0, 2.0]}}, toml))
    known = "sampling_rate_hz, name, units, description, taxels, time_column, time_unit, "
    known += "taxel_positions_mm"
    assert f"dataset.toml: unknown key 'descriptoin' (known: {known})" in message


def test_missing_path_and_not_a_directory(tmp_path):
    with pytest.raises(DatasetError, match=re.escape(f"{tmp_path / 'nope'} does not exist")):
        load_folder(tmp_path / "nope")
    file = tmp_path / "file.txt"
    file.write_text("x")
    with pytest.raises(DatasetError, match=re.escape(f"{file} is not a directory")):
        load_folder(file)


@pytest.mark.parametrize(
    ("toml", "expected"),
    [
        (None, "dataset.toml: missing"),
        ("sampling_rate_hz = ", "dataset.toml: not valid TOML"),
        ('name = "x"\n', "dataset.toml: sampling_rate_hz is missing"),
        ("sampling_rate_hz = 0\n", "sampling_rate_hz = 0 is not a number > 0"),
        ("sampling_rate_hz = -5.0\n", "sampling_rate_hz = -5.0 is not a number > 0"),
        ("sampling_rate_hz = inf\n", "sampling_rate_hz = inf is not a number > 0"),
        ("sampling_rate_hz = true\n", "sampling_rate_hz = True is not a number > 0"),
        ('sampling_rate_hz = "100"\n', "sampling_rate_hz = '100' is not a number > 0"),
        ("sampling_rate_hz = 1\nrate = 2\n", "dataset.toml: unknown key 'rate'"),
        ('sampling_rate_hz = 1\nunits = ""\n', "units = '' is not a non-empty string"),
        ("sampling_rate_hz = 1\nname = 3\n", "name = 3 is not a non-empty string"),
        ("sampling_rate_hz = 1\ndescription = 3\n", "toml: description = 3 is not a string"),
        (
            "sampling_rate_hz = 1\n[description]\ntext = 'x'\n",
            "dataset.toml: description = {'text': 'x'} is not a string",
        ),
    ],
)
def test_malformed_dataset_toml(tmp_path, toml, expected):
    root = make_folder(tmp_path / "ds", {"c": {"a.csv": [1.0, 2.0]}}, toml)
    message = dataset_error(root)
    assert message.startswith(f"folder dataset {root}")
    assert expected in message


def test_non_numeric_csv_names_file_and_line(tmp_path):
    root = make_folder(
        tmp_path / "ds", {"c": {"late.csv": "1.0\n2.0\nforce\n", "mid.csv": "1\n2\nx\n3\nnan?\n"}}
    )
    message = dataset_error(root)
    assert "c/late.csv: line 3: 'force' is not a number" in message
    assert "c/mid.csv: line 3: 'x' is not a number (and 1 more bad lines)" in message
    assert "(2 problems)" in message


def test_a_header_line_makes_a_recording_of_named_taxels_among_plain_ones_refused(tmp_path):
    """A stray header among one-column files: the file with the header is named, not the rest."""
    plain = {f"p{i}.csv": [1, 2] for i in range(3)}
    root = make_folder(tmp_path / "ds", {"c": {"head.csv": "force\n1.0\n2.0\n", **plain}})
    message = dataset_error(root)
    assert message.endswith(
        "c/head.csv: named columns (force), where c/p0.csv and the dataset's other recordings "
        "hold one unnamed column (a header line only if every recording has one)"
    )


def test_csv_with_more_than_one_column(tmp_path):
    root = make_folder(tmp_path / "ds", {"c": {"two.csv": "1,2\n3,4\n"}})
    message = dataset_error(root)
    assert "c/two.csv: line 1 has 2 columns, expected one column (several taxels need a header" in (
        message
    )


def test_csv_with_an_interior_blank_line(tmp_path):
    root = make_folder(tmp_path / "ds", {"c": {"gap.csv": "1\n\n2\n"}})
    assert "c/gap.csv: line 2 is empty" in dataset_error(root)


@pytest.mark.parametrize("content", ["", "\n\n  \n"])
def test_empty_csv_recording(tmp_path, content):
    root = make_folder(tmp_path / "ds", {"c": {"empty.csv": content}})
    assert "c/empty.csv: empty recording" in dataset_error(root)


def test_empty_npy_recording(tmp_path):
    root = make_folder(tmp_path / "ds", {"c": {"empty.npy": np.zeros(0)}})
    assert "c/empty.npy: empty recording" in dataset_error(root)


@pytest.mark.parametrize("name", ["one.csv", "one.npy"])
def test_recording_shorter_than_two_samples(tmp_path, name):
    root = make_folder(tmp_path / "ds", {"c": {name: np.array([1.0])}})
    assert f"c/{name}: recording has 1 sample, needs at least 2" in dataset_error(root)


def test_nan_and_inf_name_recording_and_first_bad_sample(tmp_path):
    root = make_folder(
        tmp_path / "ds",
        {
            "c": {
                "a.csv": [0.0, 1.0, np.nan, np.inf],
                "b.npy": np.array([0.0, 0.0, 0.0, -np.inf]),
            }
        },
    )
    message = dataset_error(root)
    assert "c/a.csv: non-finite value nan at sample 2 (line 3) (2 non-finite samples in all)" in (
        message
    )
    assert "c/b.npy: non-finite value -inf at sample 3" in message


def test_binary_junk(tmp_path):
    root = make_folder(
        tmp_path / "ds",
        {
            "c": {
                "nul.csv": b"1\n\x00\x01\x02",
                "latin.csv": b"1\n\xff\xfe2\n",
                "junk.npy": b"this is not numpy at all",
                "short.npy": b"\x93NUMPY\x01\x00",
            }
        },
    )
    message = dataset_error(root)
    assert "c/junk.npy: not a .npy file (bad magic bytes)" in message
    assert "c/latin.csv: binary data, not UTF-8 text (byte 2)" in message
    assert "c/nul.csv: binary data, not text (NUL byte at offset 2)" in message
    assert "c/short.npy: unreadable .npy" in message


def test_npy_not_one_dimensional_or_not_numeric(tmp_path):
    root = make_folder(
        tmp_path / "ds",
        {
            "c": {
                "cube.npy": np.zeros((3, 2, 2)),
                "text.npy": np.array(["a", "b"]),
                "cplx.npy": np.zeros(3, dtype=complex),
                "flags.npy": np.ones(3, dtype=bool),
            }
        },
    )
    message = dataset_error(root)
    assert (
        "c/cube.npy: .npy array has shape (3, 2, 2), expected 1-D or (samples, taxels)" in message
    )
    assert "c/text.npy: .npy holds <U1 values, expected integers or floats" in message
    assert "c/cplx.npy: .npy holds complex128 values" in message
    assert "c/flags.npy: .npy holds bool values" in message


def test_pickled_npy_is_refused_not_unpickled(tmp_path):
    root = tmp_path / "ds"
    make_folder(root, {"c": {}})
    np.save(root / "c" / "obj.npy", np.array([1, "x", None], dtype=object), allow_pickle=True)
    message = dataset_error(root)
    assert "c/obj.npy: unreadable .npy (Object arrays cannot be loaded" in message


def test_no_class_folders(tmp_path):
    root = make_folder(tmp_path / "ds", {})
    (root / "loose.csv").write_text("1\n2\n")
    assert "no class folders" in dataset_error(root)


def test_class_folder_without_recordings_and_foreign_files(tmp_path):
    root = make_folder(
        tmp_path / "ds",
        {"empty": {".hidden.csv": "x"}, "ok": {"a.csv": [1, 2], "notes.txt": "hi"}},
    )
    (root / "ok" / "nested").mkdir()
    message = dataset_error(root)
    assert "empty/: class folder holds no recordings" in message
    assert "ok/notes.txt: not a recording (expected a .csv or .npy file)" in message
    assert "ok/nested/: a folder inside a class folder" in message


def test_every_problem_in_one_line_at_most_ten_listed(tmp_path):
    files = {f"bad{i:02d}.csv": "oops\n" for i in range(13)}
    root = make_folder(tmp_path / "ds", {"c": files}, toml="sampling_rate_hz = -1\n")
    message = dataset_error(root)
    assert "(14 problems)" in message
    assert message.count("; ") == MAX_LISTED
    assert message.endswith("; and 4 more")
    assert "dataset.toml: sampling_rate_hz = -1" in message
    assert "c/bad00.csv: empty recording (a header and no samples)" in message
    assert "c/bad09.csv" not in message  # the 11th problem is summarised


def test_dataset_error_is_an_eskin_error():
    assert issubclass(DatasetError, EskinError)


# ---------------------------------------------------------------------------------------------
# VibTac-12


def test_vibtac12_layout_on_a_small_fake(tmp_path):
    rng = np.random.default_rng(7)
    rows = rng.normal(size=(12, 43)) * 10  # 43 = 4 segments of 10 samples + a remainder of 3
    root = write_vibtac(tmp_path / "vt", rows)
    rec = load_vibtac12(root, sampling_rate_hz=50.0, axis="z", segments=4)
    assert rec.n_recordings == 48
    assert rec.class_names == tuple(f"Texture{i}" for i in range(1, 13))
    assert rec.names[:5] == (
        "Texture1/segment01",
        "Texture1/segment02",
        "Texture1/segment03",
        "Texture1/segment04",
        "Texture2/segment01",
    )
    np.testing.assert_array_equal(rec.labels, np.repeat(np.arange(12), 4))
    assert (rec.units, rec.name, rec.fs_hz) == ("counts", "vibtac12-z", 50.0)
    assert set(rec.lengths) == {10}
    for i in range(48):
        row, seg = divmod(i, 4)
        # Z is the third file (+200); %.18e round-trips float64 exactly.
        np.testing.assert_array_equal(rec.signals[i], rows[row, seg * 10 : seg * 10 + 10] + 200)
    x = load_vibtac12(root, sampling_rate_hz=50.0, axis=Axis.X, segments=4)
    np.testing.assert_array_equal(x.signals[5], rows[1, 10:20])


def test_vibtac12_reads_only_the_chosen_axis(tmp_path):
    root = write_vibtac(tmp_path / "vt", np.ones((12, 20)), axes=("Z",))
    assert load_vibtac12(root, segments=2).n_recordings == 24
    with pytest.raises(DatasetError, match=r"file Y\.csv for axis y does not exist"):
        load_vibtac12(root, axis="y")


def test_vibtac12_errors(tmp_path):
    with pytest.raises(DatasetError, match="does not exist"):
        load_vibtac12(tmp_path / "missing")
    root = write_vibtac(tmp_path / "rows", np.ones((11, 20)))
    with pytest.raises(DatasetError, match=r"Z\.csv has 11 rows, expected 12"):
        load_vibtac12(root)
    root = write_vibtac(tmp_path / "short", np.ones((12, 19)))
    with pytest.raises(DatasetError, match=r"too few for 10 segments"):
        load_vibtac12(root, segments=10)
    rows = np.ones((12, 20))
    rows[2, 13] = np.nan
    root = write_vibtac(tmp_path / "nan", rows)
    with pytest.raises(
        DatasetError,
        match=re.escape(
            "Texture3/segment07: non-finite value nan at sample 1 (Z.csv row 3, column 17)"
        ),
    ):
        load_vibtac12(root, segments=10)
    root = write_vibtac(tmp_path / "text", np.ones((12, 20)))
    lines = (root / "Z.csv").read_text().splitlines()
    fields = lines[4].split(",")
    fields[6] = "oops"
    lines[4] = ",".join(fields)
    (root / "Z.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(DatasetError, match=r"Z\.csv: line 5, column 7: 'oops' is not a number"):
        load_vibtac12(root)
    (root / "Z.csv").write_bytes(b"\x00\x01")
    with pytest.raises(DatasetError, match=r"Z\.csv: binary data"):
        load_vibtac12(root)
    for bad in ({"axis": "w"}, {"segments": 0}, {"sampling_rate_hz": 0.0}):
        with pytest.raises(DatasetError):
            load_vibtac12(root, **bad)


def test_vibtac12_real_copy(vibtac12):
    rec = load_vibtac12(vibtac12)
    assert rec.n_recordings == 120
    assert rec.n_classes == 12
    assert set(rec.lengths) == {399}
    assert rec.fs_hz == 200.0
    np.testing.assert_allclose(rec.durations_s, 399 / 200)
    assert all(np.isfinite(s).all() for s in rec.signals)


# ---------------------------------------------------------------------------------------------
# Dispatch and the command-line argument


def test_load_recordings_dispatches_on_kind(tmp_path):
    synthetic = load_recordings(DatasetSpec(recordings_per_class=2, duration_s=0.5))
    assert (synthetic.name, synthetic.n_recordings, synthetic.fs_hz) == ("synthetic", 24, 2000.0)
    synthetic_fs = load_recordings(
        DatasetSpec(recordings_per_class=1, duration_s=0.5, sampling_rate_hz=500.0)
    )
    assert synthetic_fs.fs_hz == 500.0
    assert synthetic_fs.min_samples == 250

    vt = write_vibtac(tmp_path / "vt", np.ones((12, 20)))
    spec = DatasetSpec(kind=DatasetKind.VIBTAC12, path=str(vt), segments=2, axis=Axis.Y)
    rec = load_recordings(spec)
    assert (rec.name, rec.n_recordings, rec.fs_hz) == ("vibtac12-y", 24, 200.0)

    folder = make_folder(tmp_path / "f", {"a": {"x.csv": [1, 2]}, "b": {"y.csv": [3, 4]}})
    rec = load_recordings(DatasetSpec(kind=DatasetKind.FOLDER, path=str(folder)))
    assert rec.class_names == ("a", "b")
    same = DatasetSpec(kind=DatasetKind.FOLDER, path=str(folder), sampling_rate_hz=100.0)
    assert load_recordings(same).fs_hz == 100.0
    other = DatasetSpec(kind=DatasetKind.FOLDER, path=str(folder), sampling_rate_hz=50.0)
    with pytest.raises(DatasetError, match=r"contradicts sampling_rate_hz = 100\.0 Hz"):
        load_recordings(other)
    with pytest.raises(DatasetError, match="needs a path"):
        load_recordings(DatasetSpec(kind=DatasetKind.FOLDER))


def test_every_source_names_each_recording_by_its_class(tmp_path):
    """Messages name a culprit recording by these names (e.g. one too short for a scene)."""
    vt = write_vibtac(tmp_path / "vt", np.ones((12, 20)))
    classes = {"a": {"x.csv": [1, 2], "y.npy": [3, 4]}, "b": {"z.csv": [5, 6]}}
    folder = make_folder(tmp_path / "f", classes)
    specs = [
        DatasetSpec(recordings_per_class=2, duration_s=0.5),
        DatasetSpec(kind=DatasetKind.VIBTAC12, path=str(vt), segments=2),
        DatasetSpec(kind=DatasetKind.FOLDER, path=str(folder)),
    ]
    synthetic, _, _ = recordings = [load_recordings(spec) for spec in specs]
    for rec in recordings:
        assert len(set(rec.names)) == rec.n_recordings
        classes = [name.split("/")[0] for name in rec.names]
        assert classes == [rec.class_names[label] for label in rec.labels]
    first = synthetic.class_names[0]
    assert synthetic.names[:2] == (f"{first}/rec01", f"{first}/rec02")


def test_resolve_dataset_argument(tmp_path, monkeypatch):
    assert resolve_dataset_argument("synthetic") == {"kind": "synthetic"}
    folder = make_folder(tmp_path / "f", {"a": {"x.csv": [1, 2]}})
    assert resolve_dataset_argument(str(folder)) == {"kind": "folder", "path": str(folder)}
    vt = write_vibtac(tmp_path / "vt", np.ones((12, 20)))
    monkeypatch.chdir(tmp_path)
    assert resolve_dataset_argument("vt") == {"kind": "vibtac12", "path": str(vt.resolve())}
    assert resolve_dataset_argument("./f/")["path"] == str(folder.resolve())

    with pytest.raises(DatasetError, match=r"--dataset vibtac12 needs a path") as info:
        resolve_dataset_argument("vibtac12")
    assert "./vibtac12" not in str(info.value)
    (tmp_path / "vibtac12").mkdir()
    with pytest.raises(DatasetError, match=r"pass it as \./vibtac12"):
        resolve_dataset_argument("vibtac12")

    with pytest.raises(DatasetError, match=re.escape(f"{tmp_path / 'gone'} does not exist")):
        resolve_dataset_argument("gone")
    (tmp_path / "file.csv").write_text("1\n")
    with pytest.raises(DatasetError, match="is not a directory"):
        resolve_dataset_argument("file.csv")
    (tmp_path / "neither").mkdir()
    (tmp_path / "neither" / "data.csv").write_text("1\n")
    with pytest.raises(DatasetError, match=r"is not a dataset: expected dataset\.toml"):
        resolve_dataset_argument("neither")
    with pytest.raises(DatasetError, match="empty"):
        resolve_dataset_argument("")
