"""The sweep scale benchmark's harness at a tiny size, on an in-process cluster: every point
goes through the real planner, store, Dask and cube assembly with the stand-ins, and the real
compute functions are back afterwards."""

import pytest

from benchmarks import sweep_scale
from pipeline.run import decoding, encoding, stages


def test_grids_have_the_points_asked_for_and_refuse_other_sizes():
    assert sweep_scale.axis_lengths(100_000) == [10] * 5
    assert sweep_scale.axis_lengths(12) == [6, 2]
    assert "set = " in sweep_scale.grid_text(1_000)  # the mismatch comes from the base then
    assert "set = " not in sweep_scale.grid_text(100_000)  # and is an axis here
    for refused in (0, 13, 10**6):
        with pytest.raises(ValueError):
            sweep_scale.axis_lengths(refused)


def test_a_tiny_sweep_computes_and_assembles_every_point(tmp_path, client):
    runs = sweep_scale.measure([12], client=client, folder=tmp_path)

    (run,) = runs
    assert (run.points, run.failures, run.cube_points) == (12, 0, 12)
    assert run.files > 0 and run.bytes > 0 and run.workers == 1
    table = sweep_scale.markdown_table(runs).splitlines()
    assert table[0].startswith("| points | plan s/pt | compute wall s/pt | overhead ms/pt")
    assert len(table) == 3 and table[2].startswith("| 12 | ")
    rows = sweep_scale.rows(runs)
    assert rows[0]["table"] == "\n".join(table)
    assert all({"benchmark", "ratio", "target", "detail"} <= row.keys() for row in rows)
    real = {
        "recordings": stages.load,
        "front_end": stages.fit,
        "spikes": encoding.encode_spikes,
        "rates": decoding.code_rates,
        "results": decoding.classify,
    }
    assert {level.name: level.compute for level in stages.LEVELS} == real
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scale12.toml"]
