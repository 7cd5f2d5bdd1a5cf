"""The run log: one JSON line per sweep, torn lines skipped."""

from storage.runlog import RUN_LOG, append_sweep_run, read_sweep_runs


def test_run_log_round_trip_skips_torn_lines(tmp_path):
    assert read_sweep_runs(tmp_path) == []
    summary = {"grid": "smoke", "points": 7, "cache_hits": 2, "computed": 5, "seconds": 12.5}
    append_sweep_run(tmp_path, summary)
    with open(tmp_path / RUN_LOG, "a") as log:
        log.write('{"grid": "torn"\n')
    append_sweep_run(tmp_path, {**summary, "cache_hits": 7, "computed": 0})
    runs = read_sweep_runs(tmp_path)
    assert [(r.grid, r.points, r.cache_hits, r.computed, r.seconds) for r in runs] == [
        ("smoke", 7, 2, 5, 12.5),
        ("smoke", 7, 7, 0, 12.5),
    ]
