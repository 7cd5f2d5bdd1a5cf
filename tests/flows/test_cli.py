"""``eskin run``: the JSON contract, the summary, and one clear stderr line for each bad input."""

import contextlib
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flows.cli import main


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def tiny_scene(tmp_path):
    """A scene that runs in about a second: 4 recordings x 12 classes, 1.5 s, 4 folds, 3 epochs."""

    def write(extra: str = "", folds: int = 4):
        path = tmp_path / "tiny.toml"
        path.write_text(
            "[dataset]\nkind = 'synthetic'\nrecordings_per_class = 4\nduration_s = 1.5\n"
            "[array]\nrows = 2\ncols = 1\n"
            f"[training]\nepochs = 3\nfolds = {folds}\n" + extra
        )
        return str(path)

    return write


def test_json_has_the_documented_keys(capsys, tiny_scene):
    code, out, err = run_cli(capsys, "run", "--scene", tiny_scene(), "--json")
    assert code == 0, err
    result = json.loads(out)
    for model in ("ffnn", "cnn"):
        acc = result["accuracy"][model]
        assert 0.0 <= acc["mean"] <= 1.0 and acc["std"] >= 0.0
        assert len(acc["folds"]) == 4
    assert result["n_recordings"] == 48 and result["n_classes"] == 12
    assert result["ssnr_db"] == "inf"  # ideal readout: REAL equals TRUE
    assert math.isinf(float(result["ssnr_db"]))
    assert result["ste_s2"] == 0.0
    assert result["event_rate_hz"] > 0 and result["data_rate_bps"] > result["event_rate_hz"]
    assert result["equivalent_bits"] == pytest.approx(math.log2(1 / 0.09))
    stages = {"load", "front_end", "setup", "taxels", "readout", "metrics", "coding"}
    stages |= {"train_ffnn"}
    assert stages | {"train_cnn"} == set(result["timings_s"])
    assert all(v >= 0 for v in result["timings_s"].values())


def test_noisy_scene_reports_finite_spike_metrics(capsys, tiny_scene):
    extra = "[readout.effects]\namplifier_noise = { sigma_v = 0.02 }\n"
    code, out, err = run_cli(capsys, "run", "--scene", tiny_scene(extra), "--json")
    assert code == 0, err
    result = json.loads(out)
    assert math.isfinite(result["ssnr_db"]) and result["ste_s2"] != 0.0


def test_threshold_above_the_signal_range_trains_without_nan(capsys, tiny_scene):
    # Rails at +-0.4 V: no swing can reach a 0.99 V step, whatever the recordings' peaks.
    extra = "[readout]\nthreshold_v = 0.99\n[readout.effects]\nsaturation = { rail_v = 0.4 }\n"
    code, out, err = run_cli(capsys, "run", "--scene", tiny_scene(extra), "--json")
    assert code == 0, err
    result = json.loads(out)
    assert result["event_rate_hz"] == 0.0
    for model in ("ffnn", "cnn"):
        assert all(math.isfinite(a) for a in result["accuracy"][model]["folds"])


def test_readable_summary(capsys, tiny_scene):
    code, out, _ = run_cli(capsys, "run", "--scene", tiny_scene())
    assert code == 0
    assert re.search(r"FFNN +accuracy +\d+\.\d %", out)
    assert re.search(r"CNN +accuracy +\d+\.\d %", out)
    assert "seconds:" in out and "SSNR inf" in out


def one_error_line(capsys, *argv):
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("eskin: error: ")
    return lines[0]


@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        ("[readout]\nthreshhold_v = 0.1\n", "readout.threshhold_v: unknown key"),
        ("[readout]\nthreshold_v = 0.0\n", "readout.threshold_v: 0.0 is out of range"),
        ("[readout]\nthreshold_v = -0.05\n", "readout.threshold_v: -0.05 is out of range"),
        ("[coding]\nwindow_s = 10.0\n", "coding.window_s: 1 window(s) of 10.0 s do not fit"),
        (
            "[readout.effects]\namplifier_noise = { sigma_v = -0.1 }\n",
            "readout.effects.amplifier_noise.sigma_v: -0.1 is out of range",
        ),
    ],
)
def test_bad_scene_values(capsys, tiny_scene, extra, expected):
    assert expected in one_error_line(capsys, "run", "--scene", tiny_scene(extra), "--json")


def test_zero_taxels(capsys, tmp_path):
    path = tmp_path / "zero.toml"
    path.write_text("[array]\nrows = 0\ncols = 3\n")
    assert "array.rows: 0 is out of range" in one_error_line(capsys, "run", "--scene", str(path))


def test_class_with_fewer_recordings_than_folds(capsys, tiny_scene):
    # 4 recordings per class cannot fill 5 folds.
    line = one_error_line(capsys, "run", "--scene", tiny_scene(folds=5))
    assert "fewer" in line and "5" in line


def test_unknown_scene_name(capsys):
    assert "nope.toml" in one_error_line(capsys, "run", "--scene", "nope.toml")


def test_missing_dataset_path(capsys, tmp_path):
    line = one_error_line(capsys, "run", "--dataset", str(tmp_path / "absent"))
    assert "absent" in line


def make_folder_dataset(root, toml="sampling_rate_hz = 1000.0\n", files=None):
    root.mkdir()
    (root / "dataset.toml").write_text(toml)
    rng = np.random.default_rng(0)
    for cls in ("rough", "smooth"):
        (root / cls).mkdir()
        for i in range(3):
            np.savetxt(root / cls / f"rec{i}.csv", rng.standard_normal(3000))
    for name, text in (files or {}).items():
        (root / name).write_text(text)
    return root


def test_malformed_dataset_toml(capsys, tmp_path):
    root = make_folder_dataset(tmp_path / "data", toml="sampling_rate_hz = [\n")
    assert "dataset.toml" in one_error_line(capsys, "run", "--dataset", str(root))


def test_non_numeric_csv(capsys, tmp_path):
    root = make_folder_dataset(tmp_path / "data", files={"rough/rec9.csv": "1.0\nhello\n"})
    assert "rec9.csv" in one_error_line(capsys, "run", "--dataset", str(root))


def test_empty_recording(capsys, tmp_path):
    root = make_folder_dataset(tmp_path / "data", files={"smooth/empty.csv": ""})
    assert "empty.csv" in one_error_line(capsys, "run", "--dataset", str(root))


def test_folder_dataset_runs_and_small_classes_are_refused(capsys, tmp_path, tiny_scene):
    root = make_folder_dataset(tmp_path / "data")
    # 3 recordings per class cannot fill the scene's 4 folds.
    line = one_error_line(capsys, "run", "--scene", tiny_scene(), "--dataset", str(root))
    assert "rough" in line and "fewer" in line
    three_folds = tiny_scene(folds=3)
    code, out, err = run_cli(
        capsys, "run", "--scene", three_folds, "--dataset", str(root), "--json"
    )
    assert code == 0, err
    assert json.loads(out)["n_classes"] == 2


def test_console_script_exit_status_and_stderr(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[readout]\nthreshold_v = -1\n")
    proc = subprocess.run(
        [sys.executable, "-m", "flows.cli", "run", "--scene", str(bad)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.strip().count("\n") == 0
    assert "readout.threshold_v" in proc.stderr


def test_run_on_the_vibtac12_copy(capsys, tiny_scene, vibtac12):
    code, out, err = run_cli(
        capsys, "run", "--scene", tiny_scene(), "--dataset", str(vibtac12), "--json"
    )
    assert code == 0, err
    result = json.loads(out)
    assert result["dataset"] == "vibtac12"
    assert (result["n_recordings"], result["n_classes"]) == (120, 12)
    assert result["n_windows"] >= 15  # 399-sample segments at 200 Hz hold about 19 windows
    for model in ("ffnn", "cnn"):
        assert len(result["accuracy"][model]["folds"]) == 4


# -- command-line conventions ---------------------------------------------------------------------


def test_version(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out.strip() == f"eskin {version('eskin-sweep')}"


@pytest.mark.parametrize("workers", ["0", "-1", "two"])
def test_workers_must_be_a_positive_whole_number(capsys, workers):
    with pytest.raises(SystemExit) as exit_info:
        main(["sweep", "--grid", "smoke", "--workers", workers])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"argument --workers: {workers!r}: need a whole number" in err


def test_a_failed_run_exits_1_with_one_line(capsys, tmp_path, monkeypatch):
    """A sweep whose points failed is a failed run on good input, not bad input."""
    import flows.sweep
    from flows.progress import SweepFailed

    message = "2 of 7 points failed (the others are kept in ROOT): point-x: boom"

    def failing(**_):
        raise SweepFailed(message)

    monkeypatch.setattr(flows.sweep, "sweep", failing)
    monkeypatch.setattr("flows.server.prefect_server", lambda **_: contextlib.nullcontext("url"))
    code, out, err = run_cli(capsys, "sweep", "--grid", "smoke", "--root", str(tmp_path / "r"))
    assert code == 1 and out == ""
    assert (
        err == "eskin: error: 2 of 7 points failed (the others are kept in ROOT): point-x: boom\n"
    )


def test_dry_run_writes_nothing_and_reports_every_point(capsys, tmp_path):
    root = tmp_path / "not-there"
    code, out, err = run_cli(
        capsys, "sweep", "--grid", "smoke", "--root", str(root), "--dry-run", "--json"
    )
    assert code == 0, err
    plan = json.loads(out)
    assert (plan["points"], plan["cached"], plan["missing"], plan["unknown"]) == (7, 0, 7, 7)
    assert set(plan["sweeps"]) == {"threshold", "window", "noise"}
    assert not root.exists()
    code, out, _ = run_cli(capsys, "sweep", "--grid", "smoke", "--root", str(root), "--dry-run")
    assert code == 0 and "nothing written" in out and "unknown" in out
    assert not root.exists()


def test_dry_run_default_root_on_another_dataset_is_its_own(capsys, tmp_path, monkeypatch):
    data = make_folder_dataset(tmp_path / "my data")
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(
        capsys, "sweep", "--grid", "smoke", "--dataset", str(data), "--dry-run", "--json"
    )
    # The smoke grid's 4 folds do not fit 3 recordings per class: refused before any work.
    assert code == 2 and "class 'rough' has fewer (3)" in err
    three_folds = tmp_path / "grid.toml"
    three_folds.write_text(
        'name = "g"\n[base]\ntraining = { folds = 3, epochs = 2 }\n'
        '[sweeps.t]\naxes = { "readout.threshold_v" = [0.05, 0.1] }\n'
    )
    code, out, err = run_cli(
        capsys, "sweep", "--grid", str(three_folds), "--dataset", str(data), "--dry-run", "--json"
    )
    assert code == 0, err
    assert json.loads(out)["root"] == str(Path("runs") / "g-my-data")
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_help_lists_every_scene_field_from_its_declaration(capsys, command):
    from pipeline.design.scene import scene_fields

    with pytest.raises(SystemExit) as exit_info:
        main([command, "--help"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    fields = scene_fields()
    assert len(fields) > 30
    for field in fields:
        assert f"  {field.text()}\n" in out + "\n", field.path


def test_power_of_the_calibration_chip_through_the_installed_command():
    # Alea et al., IEEE TBioCAS 2024: 192 taxels, 2.2 kevent/s, 12.33 nW per taxel.
    chip = ["--taxels", "192", "--event-rate-hz", "2200", "--json"]
    proc = subprocess.run(
        [sys.executable, "-m", "flows.cli", "power", *chip],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["event_readout_per_taxel_w"] == pytest.approx(12.33e-9, rel=0.3)
    assert out["event_readout_w"] == pytest.approx(
        out["event_readout_static_w"] + out["event_readout_dynamic_w"], rel=1e-12
    )
    assert out["event_data_rate_bps"] == 2200 * 9  # 8 address bits and a polarity bit
    # No sampling rate: the frame readout is unknown, null rather than NaN.
    for key in ("frame_readout_w", "frame_data_rate_bps", "frame_readout_static_w"):
        assert out[key] is None
    assert "NaN" not in proc.stdout


def test_power_prints_both_readouts_and_takes_energy_options(capsys):
    argv = ["power", "--taxels", "4", "--event-rate-hz", "50", "--bits", "8"]
    argv += ["--sampling-rate-hz", "1000", "--front-end-nw", "3", "--comparator-nw", "1"]
    argv += ["--event-energy-pj", "20", "--adc-static-nw", "100", "--taxels-per-adc", "4"]
    argv += ["--adc-fom-fj", "5"]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # As tests/pipeline/results/test_readout_power.py works it out by hand.
    assert out["event_readout_w"] == pytest.approx(17.15e-9, rel=1e-12)
    assert out["frame_readout_w"] == pytest.approx(149.12e-9, rel=1e-12)
    assert out["frame_data_rate_bps"] == 32_000.0
    assert out["energy_model"]["taxels_per_adc"] == 4
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "event readout    17.1 nW (4.29 nW per taxel; static 16 nW, dynamic 1.15 nW)" in text
    assert "frame readout     149 nW (37.3 nW per taxel; static 112 nW, dynamic 37.1 nW)" in text
    assert "frame / event: 8.7x the power, 213x the data rate" in text
