"""write_report: a report and its figures rendered into a whole folder (self-contained HTML,
Markdown, PNG and SVG figures), replacing an old report but never a user's folder; the energy
options of ``eskin report``, checked before anything is read or written."""

import pytest

from flows.cli import main
from flows.report import write_report, write_run_report
from pipeline.errors import EskinError
from pipeline.report import Panel, build_report
from pipeline.report.figures import draw_report
from pipeline.results.hardware_constants import Constants
from pipeline.results.readout_constants import EnergyModel
from storage import StoreError
from storage.report import MARKER
from tests.report_helpers import PAPER_LIKE_SWEEPS, make_cubes


@pytest.fixture(scope="module")
def small_report():
    sweeps = {k: PAPER_LIKE_SWEEPS[k] for k in ("threshold", "mismatch")}
    report = build_report(make_cubes(sweeps))
    return report, draw_report(report)


def test_report_folder_holds_every_output(tmp_path, small_report):
    report, figures = small_report
    page = write_report(tmp_path / "out", report, figures)
    assert page == tmp_path / "out" / "report.html"
    for stem in figures:
        for ext in ("png", "svg"):
            assert (tmp_path / "out" / "figures" / f"{stem}.{ext}").stat().st_size > 1000
    html = page.read_text()
    assert html.count("<svg") == len(figures) and "src=" not in html and "<script" not in html
    markdown = (tmp_path / "out" / "report.md").read_text()
    assert f"(figures/{Panel.THRESHOLD.value}.png)" in markdown
    assert "Fig. 8: accuracy against the taxel count: not in this run" in markdown
    assert "| the paper | on-chip spikes (3.5 b, variable) |" in markdown
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no partial left behind


def test_a_report_replaces_an_old_report_but_never_a_users_folder(tmp_path, small_report):
    report, figures = small_report
    out = tmp_path / "out"
    write_report(out, report, figures)
    (out / "stale.txt").write_text("old")
    write_report(out, report, figures)
    assert not (out / "stale.txt").exists() and (out / MARKER).is_file()
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    with pytest.raises(StoreError, match="not a report"):
        write_report(mine, report, figures)
    assert [p.name for p in mine.iterdir()] == ["thesis.tex"]
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError, match="not a directory"):
        write_report(tmp_path / "file", report, figures)


def test_the_energy_options_of_eskin_report_become_its_energy_model(tmp_path, monkeypatch):
    seen = {}

    def fake(root, out=None, **kwargs):
        seen.update(kwargs)
        return tmp_path / "report.html"

    monkeypatch.setattr("flows.report.write_run_report", fake)
    argv = ["report", "--root", str(tmp_path), "--front-end-nw", "5", "--taxels-per-adc", "8"]
    assert main([*argv, "--event-energy-pj", "20"]) == 0
    assert seen["constants"].energy_model() == EnergyModel(
        front_end_w_per_taxel=5e-9, event_energy_j=20e-12, taxels_per_adc=8
    )
    assert seen["constants"].source("taxels_per_adc") == (
        "set on the command line (--taxels-per-adc)"
    )
    assert main(["report", "--root", str(tmp_path)]) == 0
    assert seen["constants"] == Constants()


def test_a_constants_file_of_eskin_report_overrides_its_constants_options_on_top(
    tmp_path, monkeypatch
):
    seen = {}
    monkeypatch.setattr(
        "flows.report.write_run_report",
        lambda root, out=None, **kwargs: seen.update(kwargs) or tmp_path / "report.html",
    )
    mine = tmp_path / "mine.toml"
    mine.write_text(
        'a_vt_v_m = { value = 2, unit = "mV um", source = "foundry X" }\n'
        'event_energy_j = { value = 4, unit = "pJ per event", source = "our comparator" }\n',
        encoding="utf-8",
    )
    argv = ["report", "--root", str(tmp_path), "--constants", str(mine)]
    assert main([*argv, "--event-energy-pj", "20"]) == 0
    constants = seen["constants"]
    assert constants.origin == str(mine) and constants.a_vt_v_m == pytest.approx(2e-9)
    assert constants.source("a_vt_v_m") == "foundry X"
    assert constants.value("event_energy_j") == 20e-12  # the option overrides the file
    assert constants.source("event_energy_j") == "set on the command line (--event-energy-pj)"


def test_a_bad_constants_file_is_one_line_naming_file_and_key_and_writes_nothing(tmp_path, capsys):
    root = tmp_path / "root"
    root.mkdir()
    mine = tmp_path / "mine.toml"
    mine.write_text('a_vt_v_m = { value = -2, unit = "V m", source = "x" }\n', encoding="utf-8")
    assert main(["report", "--root", str(root), "--constants", str(mine)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"eskin: error: invalid constants file {mine}")
    assert "a_vt_v_m.unit: 'V m' is not its unit" in err and "a_vt_v_m.value -2" in err
    assert list(root.iterdir()) == []


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--event-energy-pj", "-1"),
        ("--adc-fom-fj", "nan"),
        ("--link-energy-pj-per-bit", "inf"),
        ("--adc-fom-fj", "ten"),
        ("--front-end-nw", "-0.5"),
        ("--taxels-per-adc", "0"),
        ("--taxels-per-adc", "2.5"),
    ],
)
def test_a_bad_energy_option_is_one_line_naming_it_and_writes_nothing(
    option, value, tmp_path, capsys
):
    root = tmp_path / "root"
    root.mkdir()
    with pytest.raises(SystemExit) as exited:  # argparse reports a bad option value and exits
        main(["report", "--root", str(root), option, value])
    err = capsys.readouterr().err
    assert exited.value.code == 2
    assert err.count("\n") == 1 and err.startswith("eskin: error: ") and option in err
    assert list(root.iterdir()) == [] and [p.name for p in tmp_path.iterdir()] == ["root"]


def test_write_run_report_checks_the_adc_before_reading_anything(tmp_path):
    with pytest.raises(EskinError, match=r"--adc-bits 0: need 1 to 64; --adc-rate-hz -1: need"):
        write_run_report(tmp_path, adc_bits=0, adc_rate_hz=-1.0)
    assert list(tmp_path.iterdir()) == []


def test_report_answers_checks_the_adc_as_the_report_does():
    from flows.api import report_answers

    with pytest.raises(EskinError, match=r"--adc-bits 65: need 1 to 64; --adc-rate-hz 0: need"):
        report_answers({}, adc_bits=65, adc_rate_hz=0.0)
