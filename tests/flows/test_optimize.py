"""``eskin optimize`` end to end: a search of a small space over the built-in data, continued
with a larger budget, killed and resumed; the trial cube, the front and the journal."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from storage import open_results
from tests.flows.helpers import eskin, hermetic_env, stop, wait_for
from tests.reliability.test_interruption import results

pytestmark = pytest.mark.slow

#: Three dimensions (continuous log-scaled, categorical, integer) on the smoke scene with one
#: model: about a second per point.
SPACE = """
name = "tiny"
seed = 3

[base]
name = "tiny"
[base.dataset]
kind = "synthetic"
recordings_per_class = 4
duration_s = 1.5
[base.array]
rows = 1
cols = 2
[base.training]
models = ["ffnn"]
epochs = 3
folds = 4

[space]
"readout.threshold_v" = { low = 0.03, high = 0.3, log = true }
"coding.window_s" = { choices = [0.1, 0.2] }
"array.rows" = { low = 1, high = 2 }

[objectives]
"accuracy.ffnn" = "max"
"data_rate_bps" = "min"
"""


def journal(root: Path) -> list[dict]:
    path = root / "search-tiny.jsonl"
    if not path.is_file():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.endswith("}")]


@pytest.fixture(scope="module")
def space(tmp_path_factory) -> tuple[Path, dict[str, str]]:
    base = tmp_path_factory.mktemp("optimize")
    path = base / "tiny.toml"
    path.write_text(SPACE)
    return path, hermetic_env(base)


def optimize(space: Path, root: Path, env: dict[str, str], *extra: str) -> dict:
    proc = eskin("optimize", "--space", str(space), "--root", str(root), *extra, "--json", env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout)


def test_a_budget_of_6_then_8_computes_only_the_2_new_trials(space, suite_cluster, tmp_path):
    path, env = space
    root = tmp_path / "run"
    first = optimize(path, root, env, "--budget", "6", *suite_cluster)
    assert {"root", "trials", "computed", "cache_hits", "seconds", "front"} <= set(first)
    assert first["trials"] == 6 and first["new_trials"] == 6
    assert first["sampler"] == "gp"  # auto, for a short search of ordered dimensions
    cubes = open_results(root)
    assert list(cubes) == ["tiny.front", "tiny.trials"]
    assert first["cubes"] == {
        kind: str(root / "store.zarr" / "cubes" / f"tiny.{kind}") for kind in ("trials", "front")
    }
    trials, front = cubes["tiny.trials"], cubes["tiny.front"]
    assert trials.sizes["trial"] == 6 and list(trials["trial"].values) == list(range(6))
    assert trials["threshold_v"].attrs["field"] == "readout.threshold_v"
    assert trials["threshold_v"].dims == trials["window_s"].dims == ("trial",)
    assert trials["dataset.kind"].item() == "synthetic"  # every other scene field
    distinct = set(trials["result_key"].values)
    assert first["computed"] == len(distinct) == len(results(root))
    # The front: its trials are not dominated by any trial (accuracy up, data rate down).
    on = front["trial"].values[front["on_front"].values]
    assert len(on) >= 1 and {r["trial"] for r in first["front"] if r["on_front"]} == set(on)
    accuracy = trials["accuracy_mean"].sel(model="ffnn").values
    rate = trials["data_rate_bps"].values
    for t in on:
        better = (accuracy >= accuracy[t]) & (rate <= rate[t])
        strictly = (accuracy > accuracy[t]) | (rate < rate[t])
        assert not (better & strictly).any()
    row = next(r for r in first["front"] if r["trial"] == on[0])
    assert row["objectives"]["data_rate_bps"] == pytest.approx(rate[on[0]])

    stored, thresholds = results(root), trials["threshold_v"].values
    second = optimize(path, root, env, "--budget", "8", *suite_cluster, "--report")
    assert second["trials"] == 8 and second["new_trials"] == 2
    # The report's answer section works on the search's designs.
    report = (Path(second["report"]).parent / "report.md").read_text()
    assert "## The answer" in report and "distinct designs" in report
    trials = open_results(root)["tiny.trials"]
    assert trials.sizes["trial"] == 8
    new = set(trials["result_key"].values) - distinct
    assert second["computed"] == len(new) and second["cache_hits"] == 2 - len(new)
    after = results(root)
    assert {k: after[k] for k in stored} == stored, "a stored point was recomputed"
    assert len(after) == len(stored) + len(new)
    # The first 6 trials are as they were: the journal replays them.
    np.testing.assert_array_equal(trials["threshold_v"].values[:6], thresholds)


def test_a_killed_search_resumes_without_recomputing_stored_points(space, tmp_path):
    path, env = space
    root = tmp_path / "run"
    command = [sys.executable, "-m", "flows.cli", "optimize", "--space", str(path)]
    command += ["--root", str(root), "--budget", "6", "--workers", "1", "--json"]
    search = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        # One worker: one trial at a time. Killed once a trial is told and the next asked.
        wait_for(
            lambda: any("values" in r for r in journal(root)) and journal(root)[-1].get("params"),
            600,
            "a told trial and an asked one",
            interval=0.05,
        )
        os.kill(search.pid, signal.SIGKILL)
        search.wait(timeout=30)
    finally:
        stop(search)
    before = journal(root)
    told = {r["trial"] for r in before if "values" in r}
    asked = {r["trial"]: r["params"] for r in before if "params" in r}
    assert 1 <= len(told) < 6, "the search was not killed mid-run"
    stored = results(root)

    summary = optimize(path, root, env, "--budget", "6", "--workers", "1")
    assert summary["trials"] == 6 and summary["new_trials"] == 6 - len(told)
    after = results(root)
    assert {k: after[k] for k in stored} == stored, "a stored point was recomputed"
    trials = open_results(root)["tiny.trials"]
    keys = list(trials["result_key"].values)
    assert summary["computed"] == len(set(keys) - set(stored))
    # Trials asked before the kill keep their values: the untold ones were asked again.
    for number, params in asked.items():
        assert trials["threshold_v"].values[number] == params["readout.threshold_v"]
    assert sorted(r["trial"] for r in journal(root) if "values" in r) == list(range(6))


def test_bad_spaces_are_refused_before_any_work(space, tmp_path):
    _, env = space
    bad = tmp_path / "bad.toml"
    bad.write_text(
        SPACE.replace(
            '"array.rows" = { low = 1, high = 2 }', '"array.rows" = { low = 3, high = 2 }'
        )
        .replace('"coding.window_s" = { choices = [0.1, 0.2] }', '"coding.window" = { low = 1 }')
        .replace('"data_rate_bps" = "min"', '"latency_s" = "min"')
    )
    root = tmp_path / "run"
    proc = eskin("optimize", "--space", str(bad), "--root", str(root), env=env)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: invalid space")
    for part in ("(3 problems)", "coding.window", "low (3) must be below high (2)", "latency_s"):
        assert part in lines[0]
    assert not root.exists()


def test_an_object_root_is_refused_in_one_line_before_any_work(space, capsys):
    from flows.cli import main

    path, _ = space
    # No S3 server is reachable: the refusal must come before any request.
    assert main(["optimize", "--space", str(path), "--root", "s3://bucket/run/"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.splitlines() == [
        "eskin: error: root s3://bucket/run: a search needs a folder root (its journal is "
        "appended to in place, which an object root cannot do); sweep to s3:// roots, search "
        "in a folder"
    ]
