"""Every benchmark suite runs to its end at its tiny size, so that a suite the code has outgrown
(a baseline that no longer gives the same points, a renamed function) fails here and not half-way
through ``make bench``.

``run(tiny=True)`` takes each suite's own steps on small data, once each: the rows are checked
for their form (a name, a finite ratio, a target, a detail), not for their figures, which mean
nothing at that size.
"""

import importlib
import math
import pkgutil

import pytest

import benchmarks
from benchmarks import data_statistics
from benchmarks.__main__ import QUICK, SLOW
from pipeline.recordings.touch_statistics import REAL_TOUCHES

SUITES = (*QUICK, *SLOW)


def short(module) -> str:
    return module.__name__.rsplit(".", 1)[-1]


def test_make_bench_runs_every_suite():
    modules = [
        importlib.import_module(f"benchmarks.{m.name}")
        for m in pkgutil.iter_modules(benchmarks.__path__)
    ]
    assert {short(m) for m in modules if callable(getattr(m, "run", None))} == {
        short(m) for m in SUITES
    }


@pytest.mark.slow
@pytest.mark.usefixtures("suite_server_db")  # the sweeps' suites start the suite's server
@pytest.mark.parametrize("suite", SUITES, ids=short)
def test_a_suite_runs_at_its_tiny_size_and_gives_well_formed_rows(suite, tmp_path, monkeypatch):
    monkeypatch.setenv("DASK_TEMPORARY_DIRECTORY", str(tmp_path / "dask"))
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "mpl"))
    rows = suite.run(tiny=True)
    assert rows
    for row in rows:
        assert {"benchmark", "ratio", "target", "detail"} <= row.keys(), row
        assert isinstance(row["ratio"], float) and math.isfinite(row["ratio"]), row
        assert row["ratio"] > 0, row
        assert all(isinstance(row[k], str) and row[k] for k in ("benchmark", "target", "detail"))
        assert "table" not in row or row["table"].startswith("|")
    names = [row["benchmark"] for row in rows]
    assert len(set(names)) == len(names), names


def test_the_data_statistics_table_has_a_row_per_statistic(capsys):
    data_statistics.main(["--seeds", "1"])
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:2] == ["statistic", "real"]
    assert [line.split()[0] for line in lines[1:]] == list(REAL_TOUCHES)
