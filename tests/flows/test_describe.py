"""``eskin describe``: the text, --json and --export, round trips of the export, and refusals."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

import flows.describe as describe_module
from flows.cli import main
from flows.describe import ExportError, export_folder
from pipeline.design.scene import DatasetSpec
from pipeline.recordings.describe import folder_layout
from pipeline.recordings.sources import Recordings, load_folder, load_recordings, load_vibtac12
from pipeline.recordings.touch_statistics import REAL_TOUCHES
from tests.flows.helpers import eskin, hermetic_env

SEGMENTS = "are these segments of one recording?"


def _no_nan(text: str):
    def refuse(name):
        raise AssertionError(f"JSON holds {name}")

    return json.loads(text, parse_constant=refuse)


def _tree(path: Path):
    if not path.exists():
        return None
    return sorted((str(p.relative_to(path)), p.stat().st_size) for p in path.rglob("*"))


def _touch_folder(root: Path, per_class: int = 4, seconds: float = 4.5) -> Path:
    """A folder dataset at 500 Hz: two classes with their own time course, contact first."""
    rng = np.random.default_rng(7)
    t = np.arange(int(seconds * 500)) / 500
    root.mkdir(parents=True)
    (root / "dataset.toml").write_text('sampling_rate_hz = 500.0\nname = "made"\nunits = "N"\n')
    for label, freq in (("felt", 0.4), ("steel", 0.9)):
        (root / label).mkdir()
        envelope = np.where(t < 0.25, 4.0, 1 + 0.6 * np.sin(2 * np.pi * freq * t))
        for i in range(per_class):
            np.save(root / label / f"t{i}.npy", envelope * rng.standard_normal(t.size))
    return root


def _made(labels, class_names, names, seed=3) -> Recordings:
    rng = np.random.default_rng(seed)
    signals = [
        rng.standard_normal(int(rng.integers(2, 400))) * 10.0 ** rng.integers(-300, 300)
        for _ in labels
    ]
    signals[0][:3] = [-0.0, 5e-324, np.nextafter(1.0, 2.0)]  # bits that a text format would lose
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=tuple(class_names),
        fs_hz=1234.5678,
        names=tuple(names),
        units="m/s^2",
        name="made",
    )


def _assert_same(loaded: Recordings, original: Recordings, class_names) -> None:
    assert loaded.fs_hz == original.fs_hz and loaded.units == original.units
    assert loaded.name == original.name
    assert loaded.class_names == tuple(class_names)
    assert np.array_equal(loaded.labels, original.labels)
    assert len(loaded.signals) == len(original.signals)
    for a, b in zip(loaded.signals, original.signals, strict=True):
        assert a.dtype == np.float64 and a.tobytes() == b.tobytes()


# -- export ----------------------------------------------------------------------------------------


def test_export_round_trips_bit_for_bit(tmp_path):
    made = _made([0, 0, 0, 1, 1, 2], ["cork", "felt", "steel"], [f"r{i}" for i in range(6)])
    export = export_folder(made, tmp_path / "out")
    assert export.path == tmp_path / "out" and export.n_recordings == 6 and export.renamed == ()
    _assert_same(load_folder(tmp_path / "out"), made, ["cork", "felt", "steel"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no temporary left


def test_export_of_unsafe_names_round_trips_with_safe_class_folders(tmp_path):
    classes = ["b/../../x", ".git", "a"]  # unsafe, hidden, and out of sorted order
    made = _made([0, 0, 1, 2, 2], classes, ["b/../../x/1", "weird\nname", "q", "a/z", "a/y"])
    export = export_folder(made, tmp_path / "out")
    assert len(export.renamed) == 3
    loaded = load_folder(tmp_path / "out")
    _assert_same(loaded, made, ["1_b_.._.._x", "2__.git", "3_a"])
    assert loaded.names[3:] == ("3_a/1_z.npy", "3_a/2_y.npy")  # recordings kept in their order
    assert not any(p.name.startswith(".") for p in (tmp_path / "out").rglob("*"))


def test_export_into_an_empty_folder_and_refusals_leave_nothing(tmp_path):
    made = _made([0, 1], ["a", "b"], ["a/1", "b/1"])
    (tmp_path / "empty").mkdir()
    export_folder(made, tmp_path / "empty")
    assert load_folder(tmp_path / "empty").n_recordings == 2
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "thesis.tex").write_text("precious")
    (tmp_path / "file").write_text("mine")
    for target, expected in (
        (tmp_path / "full", r"is not empty \(thesis.tex\)"),
        (tmp_path / "file", "is not a directory"),
        (tmp_path / "gone" / "out", "parent folder"),
    ):
        before = _tree(tmp_path)
        with pytest.raises(ExportError, match=expected) as info:
            export_folder(made, target)
        assert str(target) in str(info.value) and "\n" not in str(info.value)
        assert _tree(tmp_path) == before


def test_a_failing_write_leaves_nothing_behind(tmp_path, monkeypatch):
    made = _made([0, 0, 1], ["a", "b"], ["a/1", "a/2", "b/1"])
    real_write = np.lib.format.write_array
    calls = []

    def disk_full(handle, array, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        real_write(handle, array, **kwargs)

    monkeypatch.setattr(describe_module.np.lib.format, "write_array", disk_full)
    with pytest.raises(ExportError, match="No space left on device"):
        export_folder(made, tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


def test_the_vibtac12_copy_exports_with_classes_numbered_in_order(tmp_path, vibtac12):
    vibtac = load_vibtac12(vibtac12)
    export = export_folder(vibtac, tmp_path / "vt", source=str(vibtac12))
    names = [f"{i:02d}_Texture{i}" for i in range(1, 13)]
    assert len(export.renamed) == 12
    _assert_same(load_folder(tmp_path / "vt"), vibtac, names)


# -- the command line ---------------------------------------------------------------------------


def test_text_on_a_folder_dataset(tmp_path):
    data = _touch_folder(tmp_path / "data")
    proc = eskin("describe", "--dataset", str(data), env=hermetic_env(tmp_path), timeout=120)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0] == "dataset     made: 8 recordings, 2 classes"
    assert "touches     4 per class" in lines and "sampling    500 Hz, units N" in lines
    assert "durations   4.5 / 4.5 / 4.5 s (min / median / max)" in lines
    assert "windows     40 of 0.1 s in the shortest recording (the paper codes 40)" in lines
    assert any(line.startswith("felt ") for line in lines)
    header = next(i for i, line in enumerate(lines) if line.startswith("statistic "))
    assert lines[header].split() == [
        "statistic",
        "this",
        "dataset",
        "real",
        "12x10",
        "real",
        "range",
        "judged",
    ]
    end = header + 1 + len(REAL_TOUCHES)
    rows = {line.split()[0]: line.split() for line in lines[header + 1 : end]}
    assert set(rows) == set(REAL_TOUCHES)
    assert rows["envelope_corr_within"][2:] == ["0.59", ">=", "0.4", "in"]
    assert rows["contact_transient"][-1] == "in"
    # 500 Hz: a 5 ms RMS holds 2 samples, too few to show 5-20 Hz modulation; the floor ratio
    # is measured, with its class medians beside it.
    assert rows["modulation_share"][1] == "n/a" and rows["modulation_share"][-1] == "n/a"
    assert rows["floor_ratio"][2] == "(classes" and rows["floor_ratio"][-1] in ("in", "out")
    warnings = lines[end + 1 :]
    assert warnings[0] == "warnings"
    assert "fewer touches per class than folds (10," in warnings[1] and "felt has 4" in warnings[1]
    assert not any(SEGMENTS in w or "no contact transient" in w for w in warnings)


def test_json_on_the_vibtac12_copy_warns_of_segments(tmp_path, vibtac12):
    proc = eskin(
        "describe",
        "--dataset",
        str(vibtac12),
        "--json",
        env=hermetic_env(tmp_path),
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    out = _no_nan(proc.stdout)
    assert out["dataset"] == "vibtac12-z"
    assert out["facts"]["sampling_rate_hz"] == 200.0 and out["facts"]["n_classes"] == 12
    assert out["facts"]["windows"]["n"] == 19
    assert out["statistics"]["slow_decay"]["value"] is None  # 2 s segments: null, not NaN
    assert out["statistics"]["envelope_corr_within"]["inside"] is False
    assert any(w.endswith(SEGMENTS) for w in out["warnings"]), out["warnings"]


def test_the_built_in_data_describes_and_exports(tmp_path, capsys):
    out = tmp_path / "builtin"
    code = main(["describe", "--json", "--export", str(out)])
    stdout, stderr = capsys.readouterr()
    assert code == 0, stderr
    result = _no_nan(stdout)
    assert result["dataset"] == "synthetic"
    assert set(result) == {"dataset", "facts", "statistics", "warnings", "export"}
    assert set(result["statistics"]) == set(REAL_TOUCHES)
    assert all(isinstance(w, str) for w in result["warnings"])
    assert result["export"]["path"] == str(out) and result["export"]["n_recordings"] == 120
    builtin = load_recordings(DatasetSpec())
    loaded = load_folder(out)
    assert loaded.fs_hz == builtin.fs_hz and np.array_equal(loaded.labels, builtin.labels)
    assert loaded.class_names == folder_layout(builtin).class_folders
    assert all(
        a.tobytes() == b.tobytes() for a, b in zip(loaded.signals, builtin.signals, strict=True)
    )


def test_export_in_text_says_where(tmp_path):
    data = _touch_folder(tmp_path / "data", per_class=2, seconds=1.0)
    proc = eskin(
        "describe",
        "--dataset",
        str(data),
        "--export",
        str(tmp_path / "copy"),
        env=hermetic_env(tmp_path),
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[-1] == f"exported 4 recordings to {tmp_path / 'copy'}"
    copy = load_folder(tmp_path / "copy")
    original = load_folder(data)
    assert copy.class_names == original.class_names and copy.name == "made"
    assert all(
        a.tobytes() == b.tobytes() for a, b in zip(copy.signals, original.signals, strict=True)
    )


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["--dataset", "nowhere"], "does not exist"),
        (["--dataset", "vibtac12"], "needs a path"),
        (["--export", "{tmp}/full"], "is not empty"),
    ],
    ids=["missing-path", "bare-vibtac12", "non-empty-export"],
)
def test_bad_input_through_the_installed_command(tmp_path, argv, expected):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "keep.txt").write_text("mine")
    before = _tree(tmp_path)
    argv = [a.format(tmp=tmp_path) for a in argv]
    proc = eskin("describe", *argv, env=hermetic_env(tmp_path / "env"), timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: ") and expected in lines[0]
    assert _tree(tmp_path) == before


def test_an_unwritable_export_folder_is_refused_in_one_line(tmp_path, capsys, monkeypatch):
    parent = tmp_path / "ro"
    parent.mkdir()
    parent.chmod(0o500)
    if os.geteuid() == 0:  # root ignores mode bits: fail the write as it would for a user

        def denied(*args, **kwargs):
            raise PermissionError(13, "Permission denied")

        monkeypatch.setattr(describe_module.tempfile, "mkdtemp", denied)
    try:
        code = main(["describe", "--export", str(parent / "out")])
    finally:
        parent.chmod(0o700)
    stdout, stderr = capsys.readouterr()
    assert code == 2 and stdout == ""
    assert stderr.splitlines() == [
        f"eskin: error: --export {parent / 'out'}: cannot write folder {parent / 'out'}: "
        "Permission denied"
    ]
    assert list(parent.iterdir()) == []


# -- a real taxel array ----------------------------------------------------------------------------


def _array(seed=5) -> Recordings:
    rng = np.random.default_rng(seed)
    labels = [0, 0, 0, 1, 1, 1]
    signals = [rng.standard_normal((int(rng.integers(500, 700)), 3)) * (1 + c) for c in labels]
    signals[0][:3, 0] = [-0.0, 5e-324, np.nextafter(1.0, 2.0)]  # bits a careless text would lose
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=("cork", "felt"),
        fs_hz=123.456,
        names=tuple(f"r{i}" for i in range(6)),
        units="counts",
        name="array",
        taxel_names=("left", "mid", "right"),
        taxel_positions_mm=np.array([[0.0, 0.0], [1.5, 0.0], [3.0, 0.25]]),
    )


def test_an_array_exports_as_csvs_with_a_header_and_loads_back_bit_for_bit(tmp_path):
    made = _array()
    export_folder(made, tmp_path / "out")
    assert (tmp_path / "out/cork/r0.csv").read_text().startswith("left,mid,right\n")
    loaded = load_folder(tmp_path / "out")
    _assert_same(loaded, made, ["cork", "felt"])
    assert loaded.taxel_names == made.taxel_names
    np.testing.assert_array_equal(loaded.taxel_positions_mm, made.taxel_positions_mm)


def test_text_on_an_array_lists_its_taxels_and_what_they_say(tmp_path, capsys):
    export_folder(_array(), tmp_path / "data")
    assert main(["describe", "--dataset", str(tmp_path / "data")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "taxels      3: left .. right (positions given)" in lines
    row = next(line for line in lines if line.startswith("mid "))
    assert row.split()[1:3] == ["1.5,", "0"]
    say = next(i for i, line in enumerate(lines) if line.startswith("taxels say  envelopes"))
    table = lines[say : lines.index("", say)]
    # Table rows are indented by two spaces, the wrapped sentence above them by twelve.
    reads = [line.split() for line in table if line.startswith("  ") and line[2] != " "]
    assert reads[0] == ["taxels", "read", "accuracy"]
    assert [r[0] for r in reads[1:4]] == ["1", "2", "3"]
    assert reads[3][1:4] == ["(left,", "mid,", "right)"]
    assert reads[4][:2] == ["each", "alone"] and reads[5] == ["chance", "50.0", "%"]
