"""Folder datasets of a real taxel array: named columns, a time column, positions, and the
problems each names by file and column."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from pipeline.design.scene import DatasetKind, DatasetSpec
from pipeline.errors import DatasetError
from pipeline.recordings.sources import load_folder, load_recordings
from tests.pipeline.recordings.test_sources import dataset_error
from tests.shared_data import fabricslide_copy

CLASSES = ("rough", "smooth")


def write_table(path: Path, header: list[str], columns: list[np.ndarray]) -> None:
    """A CSV with a header line; values written exactly (``repr``), text columns as they are."""
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = zip(*columns, strict=True)
    lines = [",".join(header)] + [",".join(str(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def array_folder(
    root: Path,
    toml: str = "sampling_rate_hz = 500.0\n",
    *,
    n_per_class: int = 3,
    n_samples: int = 200,
    seed: int = 0,
) -> dict[str, np.ndarray]:
    """A seeded folder of two classes: CSVs with columns ``a, label, b, c`` (``label`` text).

    Returns each recording's ``(n_samples, 3)`` signal of taxels ``a, b, c`` by its name.
    """
    rng = np.random.default_rng(seed)
    root.mkdir(parents=True, exist_ok=True)
    (root / "dataset.toml").write_text(toml, encoding="utf-8")
    signals = {}
    for label in CLASSES:
        for i in range(n_per_class):
            values = rng.normal(size=(n_samples, 3))
            name = f"{label}/r{i}.csv"
            text = np.array(["x"] * n_samples)
            write_table(
                root / name, ["a", "label", "b", "c"], [values[:, 0], text, *values[:, 1:].T]
            )
            signals[name] = values
    return signals


def replace_cell(path: Path, line: int, column: int, text: str) -> None:
    """Put ``text`` in ``column`` (0-based) of file line ``line`` (1-based)."""
    lines = path.read_text().splitlines()
    fields = lines[line - 1].split(",")
    fields[column] = text
    lines[line - 1] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n")


def test_every_numeric_column_is_a_taxel_by_default_values_exact(tmp_path):
    signals = array_folder(tmp_path / "ds")
    rec = load_folder(tmp_path / "ds")
    assert rec.is_array and rec.n_taxels == 3
    assert rec.taxel_names == ("a", "b", "c")
    assert rec.taxel_positions_mm is None
    assert rec.fs_hz == 500.0
    assert rec.names == tuple(signals)
    for name, signal in zip(rec.names, rec.signals, strict=True):
        np.testing.assert_array_equal(signal, signals[name])


def test_declared_taxels_in_declared_order_with_positions_and_columns_in_any_order(tmp_path):
    toml = (
        'sampling_rate_hz = 500.0\ntaxels = ["c", "a"]\n'
        "taxel_positions_mm = [[0.0, 0.0], [2.5, 0.0]]\n"
    )
    signals = array_folder(tmp_path / "ds", toml)
    # One recording's columns in another order: taxels are found by name.
    values = signals["smooth/r1.csv"]
    write_table(
        tmp_path / "ds/smooth/r1.csv", ["c", "b", "a"], [values[:, 2], values[:, 1], values[:, 0]]
    )
    rec = load_folder(tmp_path / "ds")
    assert rec.taxel_names == ("c", "a")
    np.testing.assert_array_equal(rec.taxel_positions_mm, [[0.0, 0.0], [2.5, 0.0]])
    for name, signal in zip(rec.names, rec.signals, strict=True):
        np.testing.assert_array_equal(signal, signals[name][:, [2, 0]])


def test_two_dimensional_npy_columns_are_taxels(tmp_path):
    rng = np.random.default_rng(1)
    root = tmp_path / "ds"
    root.mkdir()
    (root / "dataset.toml").write_text('sampling_rate_hz = 40.0\ntaxels = ["column2", "column4"]\n')
    arrays = {}
    for label in CLASSES:
        (root / label).mkdir()
        arrays[label] = rng.normal(size=(30, 4)).astype(np.float32)
        np.save(root / label / "r.npy", arrays[label])
    rec = load_folder(root)
    assert rec.taxel_names == ("column2", "column4")
    for signal, label in zip(rec.signals, CLASSES, strict=True):
        np.testing.assert_array_equal(signal, arrays[label][:, [1, 3]].astype(np.float64))


@pytest.mark.parametrize(
    ("fs_hz", "unit", "scale"), [(20.0, "s", 1.0), (35.7, "ms", 1e3), (2000.0, "us", 1e6)]
)
def test_a_time_column_sets_the_rate_from_tens_of_hz_to_khz(tmp_path, fs_hz, unit, scale):
    """Jittered times (each interval off by up to 4 %): the rate is the pooled mean interval's, and
    each recording is resampled at its own start by linear interpolation (a ramp stays exact)."""
    rng = np.random.default_rng(2)
    root = tmp_path / "ds"
    root.mkdir()
    (root / "dataset.toml").write_text(f'time_column = "t"\ntime_unit = "{unit}"\n')
    times = {}
    for label, n in zip(CLASSES, (120, 90), strict=True):
        steps = (1 + rng.uniform(-0.04, 0.04, n - 1)) / fs_hz
        t = 3.0 + np.concatenate([[0.0], np.cumsum(steps)])
        times[label] = t - t[0]
        ramp = 5.0 * (t - t[0])
        write_table(
            root / label / "r.csv", ["t", "ramp", "wave"], [t * scale, ramp, np.sin(40 * t)]
        )
    rec = load_folder(root)
    expected_fs = (119 + 89) / (times["rough"][-1] + times["smooth"][-1])
    assert rec.fs_hz == pytest.approx(expected_fs, rel=1e-9)
    assert rec.fs_hz == pytest.approx(fs_hz, rel=0.01)
    for signal, label in zip(rec.signals, CLASSES, strict=True):
        t = times[label]
        n = int(np.floor(t[-1] * rec.fs_hz + 1e-9)) + 1
        grid = np.arange(n) / rec.fs_hz
        assert signal.shape == (n, 2)
        np.testing.assert_allclose(signal[:, 0], 5.0 * grid, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(
            signal[:, 1], np.interp(grid, t, np.sin(40 * (t + 3.0))), atol=1e-9
        )


# -- bad input, each naming the file and the column ------------------------------------------


def test_recordings_with_different_taxel_sets(tmp_path):
    signals = array_folder(tmp_path / "ds")
    values = signals["smooth/r2.csv"]
    write_table(tmp_path / "ds/smooth/r2.csv", ["a", "b", "d"], list(values.T))
    message = dataset_error(tmp_path / "ds")
    assert "smooth/r2.csv: its taxels differ from rough/r0.csv's (lacks c; adds d)" in message


def test_a_one_column_recording_among_taxel_recordings(tmp_path):
    array_folder(tmp_path / "ds")
    (tmp_path / "ds/smooth/plain.csv").write_text("1\n2\n3\n")
    assert "smooth/plain.csv: one unnamed column, where the dataset's recordings hold named" in (
        dataset_error(tmp_path / "ds")
    )


def test_a_taxel_column_that_is_not_numeric_names_line_and_column(tmp_path):
    array_folder(tmp_path / "ds")
    replace_cell(tmp_path / "ds/rough/r1.csv", 6, 2, "oops")
    message = dataset_error(tmp_path / "ds")
    assert "rough/r1.csv: line 6, column b: 'oops' is not a number" in message


def test_a_declared_taxel_column_of_text_is_refused(tmp_path):
    array_folder(tmp_path / "ds", 'sampling_rate_hz = 500.0\ntaxels = ["a", "label"]\n')
    message = dataset_error(tmp_path / "ds")
    assert "rough/r0.csv: line 2, column label: 'x' is not a number" in message


def test_a_taxel_column_holding_nan_names_sample_line_and_column(tmp_path):
    array_folder(tmp_path / "ds")
    replace_cell(tmp_path / "ds/smooth/r0.csv", 12, 3, "nan")
    assert "smooth/r0.csv: column c: non-finite value nan at sample 10 (line 12)" in dataset_error(
        tmp_path / "ds"
    )


def test_a_missing_declared_taxel(tmp_path):
    array_folder(tmp_path / "ds", 'sampling_rate_hz = 500.0\ntaxels = ["a", "z"]\n')
    message = dataset_error(tmp_path / "ds")
    assert "rough/r0.csv: no column 'z' (the header names a, label, b, c)" in message


@pytest.mark.parametrize(
    ("toml", "expected"),
    [
        (
            "sampling_rate_hz = 500.0\ntaxel_positions_mm = [[0, 0], [1, 0]]\n",
            "dataset.toml: taxel_positions_mm gives 2 positions for 3 taxels (a, b, c)",
        ),
        (
            'sampling_rate_hz = 500.0\ntaxels = ["a"]\ntaxel_positions_mm = [[0, 0], [1, 0]]\n',
            "dataset.toml: taxel_positions_mm gives 2 positions for 1 taxels (a)",
        ),
        (
            "sampling_rate_hz = 500.0\ntaxel_positions_mm = [[0, 0], [1], [2, 0]]\n",
            "dataset.toml: taxel_positions_mm must be a list of [x, y] pairs",
        ),
        (
            'sampling_rate_hz = 500.0\ntime_column = "a"\ntime_unit = "ms"\n',
            "dataset.toml: sampling_rate_hz and time_column both give the rate",
        ),
        ('time_column = "a"\n', "dataset.toml: time_column and time_unit go together"),
        ('time_column = "a"\ntime_unit = "min"\n', "dataset.toml: time_unit = 'min' is not one of"),
        (
            'sampling_rate_hz = 500.0\ntaxels = ["a", "a"]\n',
            "dataset.toml: taxels names a column twice",
        ),
        ("sampling_rate_hz = 500.0\ntaxels = []\n", "dataset.toml: taxels = [] is not a list"),
    ],
)
def test_bad_array_declarations(tmp_path, toml, expected):
    array_folder(tmp_path / "ds", toml)
    assert expected in dataset_error(tmp_path / "ds")


def test_a_time_column_that_does_not_increase_names_file_column_and_line(tmp_path):
    root = tmp_path / "ds"
    root.mkdir()
    (root / "dataset.toml").write_text('time_column = "ms"\ntime_unit = "ms"\n')
    write_table(root / "a/r.csv", ["ms", "p"], [np.array([0, 28, 56, 84]), np.ones(4)])
    write_table(root / "b/r.csv", ["ms", "p"], [np.array([0, 28, 28, 84]), np.arange(4.0)])
    write_table(root / "c/r.csv", ["ms", "p"], [np.array([0, 28, 84, 56]), np.arange(4.0)])
    message = dataset_error(root)
    assert "b/r.csv: time column ms does not increase at sample 2 (line 4): 28 after 28" in message
    assert "c/r.csv: time column ms does not increase at sample 3 (line 5): 56 after 84" in message


def test_a_row_written_twice_is_one_sample(tmp_path):
    """As FabricSlide's logger left at the end of two files: the same time, the same values."""
    root = tmp_path / "ds"
    root.mkdir()
    (root / "dataset.toml").write_text('time_column = "ms"\ntime_unit = "ms"\n')
    times, values = np.array([0, 25, 50, 75, 75]), np.array([1, 2, 3, 4, 4])
    write_table(root / "a/r.csv", ["ms", "p"], [times, values])
    times, values = np.array([0, 25, 50, 50, 75]), np.array([1, 2, 3, 3, 5])
    write_table(root / "b/r.csv", ["ms", "p"], [times, values])
    rec = load_folder(root)
    assert rec.fs_hz == 40.0
    np.testing.assert_array_equal(rec.signals[0][:, 0], [1, 2, 3, 4])
    np.testing.assert_array_equal(rec.signals[1][:, 0], [1, 2, 3, 5])


# -- the real array --------------------------------------------------------------------------

FABRICSLIDE_TOML = """\
name = "fabricslide"
units = "counts"
time_column = "timestamp"
time_unit = "ms"
taxels = [{taxels}]
"""


def fabricslide_subset(tmp: Path, per_class: int, classes: int = 7) -> Path:
    """The first ``per_class`` recordings of the first ``classes`` fabrics, with a dataset.toml
    naming the 16 capacitive channels as taxels (the proximity sensors left out)."""
    source = fabricslide_copy()
    root = tmp / "fabricslide"
    root.mkdir()
    taxels = ", ".join(f'"channel{k}"' for k in range(1, 17))
    (root / "dataset.toml").write_text(FABRICSLIDE_TOML.format(taxels=taxels))
    for folder in sorted(p for p in source.iterdir() if p.is_dir())[:classes]:
        (root / folder.name).mkdir()
        for file in sorted(folder.glob("*.csv"))[:per_class]:
            shutil.copyfile(file, root / folder.name / file.name)
    return root


def test_a_few_real_fabricslide_recordings_load_as_16_taxels_at_their_mean_rate(tmp_path):
    root = fabricslide_subset(tmp_path, per_class=2, classes=3)
    rec = load_folder(root)
    assert rec.taxel_names == tuple(f"channel{k}" for k in range(1, 17))
    assert rec.n_recordings == 6 and rec.n_classes == 3
    # Rows 27-29 ms apart: the pooled mean interval is about 28 ms.
    assert 34.5 < rec.fs_hz < 36.5
    first = next(root.glob("*/*.csv"))
    table = np.loadtxt(first, delimiter=",", skiprows=1)
    times_s = (table[:, 0] - table[0, 0]) / 1e3
    n = int(np.floor(times_s[-1] * rec.fs_hz + 1e-9)) + 1
    index = rec.names.index(f"{first.parent.name}/{first.name}")
    assert rec.signals[index].shape == (n, 16)
    # The first sample is the file's first row, channels 1-16 being columns 4-19.
    np.testing.assert_array_equal(rec.signals[index][0], table[0, 3:])
    assert rec.durations_s.min() >= 4.0 - 0.1
    assert rec.class_names == ("BeigeCotton", "BrownCotton", "Canvas")


def test_an_absurd_magnitude_names_the_recording_sample_and_taxel(tmp_path):
    array_folder(tmp_path / "ds")
    replace_cell(tmp_path / "ds/smooth/r1.csv", 4, 3, "1e300")
    spec = DatasetSpec(kind=DatasetKind.FOLDER, path=str(tmp_path / "ds"))
    expected = "smooth/r1.csv: absurd magnitude 1e+300 at sample 2, taxel c (more than"
    with pytest.raises(DatasetError, match=re.escape(expected)):
        load_recordings(spec)
