"""The run log: one JSON line per sweep, torn lines skipped; records the report cannot read
skipped by the report."""

from pipeline.report.cost import sweep_runs
from storage.runlog import RUN_LOG, append_sweep_run, read_sweep_records


def test_run_log_round_trip_skips_torn_lines(tmp_path):
    assert read_sweep_records(tmp_path) == []
    summary = {"grid": "smoke", "points": 7, "cache_hits": 2, "computed": 5, "seconds": 12.5}
    append_sweep_run(tmp_path, summary)
    with open(tmp_path / RUN_LOG, "a") as log:
        log.write('{"grid": "torn"\n[1, 2]\n{"grid": "no counts"}\n')
    append_sweep_run(tmp_path, {**summary, "cache_hits": 7, "computed": 0})
    records = read_sweep_records(tmp_path)
    assert len(records) == 3 and records[1] == {"grid": "no counts"}
    runs = sweep_runs(records)
    assert [(r.grid, r.points, r.cache_hits, r.computed, r.seconds) for r in runs] == [
        ("smoke", 7, 2, 5, 12.5),
        ("smoke", 7, 7, 0, 12.5),
    ]
