"""``eskin sweep`` end to end on a local two-worker Dask cluster: caches, cubes, bad input."""

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from flows import server
from flows.assembly import summarize
from flows.cli import main
from flows.cluster import available_cores
from pipeline.run.stages import SPIKES
from storage import SweepStore, open_results
from storage.batches import BATCH_PREFIX, read_batch_keys
from tests.flows.helpers import api_headers, eskin, hermetic_env

SMOKE_SWEEPS = {"threshold", "window", "noise"}


@pytest.mark.slow
def test_cold_run_summary(smoke_sweep):
    root, summary, _ = smoke_sweep
    assert set(summary) == {
        "root",
        "cubes",
        "sweeps",
        "points",
        "cache_hits",
        "computed",
        "seconds",
        "flow_run_url",
        "dashboard",
        "prefect_record",
        "auth_string_file",
    }
    assert summary["prefect_record"] == "complete"
    # Where the local server's UI login string is, never the string itself.
    assert summary["auth_string_file"] == str(server.auth_file())
    assert server.auth_file().read_text().strip() not in json.dumps(summary)
    cubes = open_results(root)
    assert summary["sweeps"] == {name: summarize(cube) for name, cube in cubes.items()}
    assert summary["flow_run_url"].startswith("http://127.0.0.1:")
    assert "/runs/flow-run/" in summary["flow_run_url"]
    assert summary["dashboard"].startswith("http://127.0.0.1:")
    assert summary["points"] == 7  # 8 grid points, the operating point shared by two sweeps
    # Each worker loaded the one dataset once: one paid load per worker at most, however many
    # points it ran, and the paid seconds of the distinct points add up to no more than the
    # workers' time.
    paid = {}
    for cube in cubes.values():
        for key, seconds in zip(
            cube["result_key"].values.ravel(),
            cube["seconds"]
            .transpose(*cube["result_key"].dims, "stage", "charge")
            .values.reshape(-1, cube.sizes["stage"], cube.sizes["charge"]),
            strict=True,
        ):
            paid[str(key)] = seconds
    loads = [p[list(cube["stage"].values).index("load")].sum() for p in paid.values()]
    assert 1 <= sum(load > 0 for load in loads) <= available_cores()
    assert sum(p.sum() for p in paid.values()) <= summary["seconds"] * available_cores()
    assert summary["cache_hits"] == 0 and summary["computed"] == 7
    assert set(summary["cubes"]) == SMOKE_SWEEPS
    assert summary["root"] == str(root.resolve())


@pytest.mark.slow
def test_cubes_are_labelled(smoke_sweep):
    cubes = open_results(smoke_sweep[0])
    assert set(cubes) == SMOKE_SWEEPS
    threshold = cubes["threshold"]
    assert threshold["accuracy"].dims == ("threshold_v", "model", "repeat", "fold")
    assert list(threshold["threshold_v"].values) == [0.05, 0.09]
    assert threshold["threshold_v"].attrs == {
        "field": "readout.threshold_v",
        "units": "V",
        "long_name": "comparator threshold (level-crossing step)",
    }
    assert list(threshold["model"].values) == ["ffnn", "cnn"]
    assert threshold.sizes["fold"] == 4 and threshold.sizes["repeat"] == 1
    acc = threshold["accuracy"].values
    assert np.all((acc >= 0) & (acc <= 1))
    # Every recording's out-of-fold prediction: each is tested in exactly one fold, and the
    # fold accuracies are the fractions of their recordings predicted right.
    assert threshold.sizes["recording"] == 48
    assert threshold["correct"].dims == ("threshold_v", "model", "repeat", "recording")
    folds = threshold["test_fold"].values
    assert set(np.unique(folds)) == {0, 1, 2, 3}
    correct = threshold["correct"].values
    assert set(np.unique(correct)) <= {0, 1}
    for f in range(4):
        in_fold = folds[:, None, :, :] == f
        per_fold = (correct * in_fold).sum(-1) / in_fold.sum(-1)
        np.testing.assert_allclose(per_fold, acc[..., f])
    np.testing.assert_allclose(threshold["accuracy_mean"], correct.mean(axis=(-2, -1)))
    low, high = threshold["accuracy_low"].values, threshold["accuracy_high"].values
    assert np.all((low <= threshold["accuracy_mean"].values) & (threshold["accuracy_mean"] <= high))
    for name in ("ssnr_db", "ste_s2", "event_rate_hz", "data_rate_bps", "equivalent_bits"):
        assert threshold[name].dims == ("threshold_v",) and "units" in threshold[name].attrs
    # Paid seconds by charge, stated by every point of a fresh sweep; the work seconds of
    # every stage measured.
    assert threshold["seconds"].dims == ("threshold_v", "stage", "charge")
    assert np.all(threshold["seconds"].values >= 0)
    assert threshold["work_seconds"].dims == ("threshold_v", "stage")
    assert np.all(threshold["work_seconds"].values >= 0)
    assert threshold.attrs["grid"] == "smoke" and threshold.attrs["sweep"] == "threshold"
    assert "package_version" in threshold.attrs and threshold["array.rows"].item() == 2
    # What the recordings were, from the points' entries (and the store, for older entries).
    assert threshold.attrs["n_classes"] == len(threshold.attrs["class_names"]) == 12
    assert (threshold.attrs["dataset_name"], threshold.attrs["sampling_rate_hz"]) == (
        "synthetic",
        2000.0,
    )
    assert threshold["result_key"].dims == ("threshold_v",)
    np.testing.assert_allclose(
        threshold["equivalent_bits"].values, np.log2(1 / np.array([0.05, 0.09]))
    )


@pytest.mark.slow
def test_noise_sweep_correlates_spike_metrics_with_accuracy(smoke_sweep):
    noise = open_results(smoke_sweep[0])["noise"]
    assert noise["accuracy"].dims == ("amplifier_noise_sigma_v", "model", "repeat", "fold")
    assert "comparator_noise_sigma_v" in noise.coords
    assert noise["correlation_r"].dims == ("model", "metric", "coefficient")
    assert list(noise["metric"].values) == ["ssnr_db", "ste_s2"]
    assert list(noise["coefficient"].values) == ["pearson", "spearman"]
    assert np.all(np.isfinite(noise["ssnr_db"].values))  # noisy points: REAL differs from TRUE
    r = noise["correlation_r"].values
    assert np.all(np.isfinite(r) & (np.abs(r) <= 1))
    assert np.all(noise["correlation_n"].values == 4)
    # SSNR falls as the noise rises.
    assert np.all(np.diff(noise["ssnr_db"].values) < 0)


@pytest.mark.slow
def test_xarray_queries_from_the_readme(smoke_sweep):
    cubes = open_results(smoke_sweep[0])
    mean = cubes["threshold"]["accuracy_mean"]
    best = mean.sel(model="ffnn").idxmax("threshold_v")
    assert float(best) in (0.05, 0.09)
    window = cubes["window"].sel(window_s=0.2)["accuracy"]
    assert window.dims == ("model", "repeat", "fold")
    assert window.std(("repeat", "fold")).dims == ("model",)


@pytest.mark.slow
def test_window_sweep_reuses_spike_trains(smoke_sweep):
    folder = SweepStore.open(smoke_sweep[0]).path / SPIKES.name
    batches = [p for p in folder.iterdir() if p.name.startswith(BATCH_PREFIX)]
    written = [key for batch in batches for key in read_batch_keys(batch)]
    # thresholds 0.05 and 0.09 (shared by both windows) and four noise levels, each made once.
    assert len(written) == len(set(written)) == 6


@pytest.mark.slow
def test_warm_rerun_recomputes_nothing_and_gives_identical_cubes(smoke_sweep, tmp_path):
    root, env = tmp_path / "run", smoke_sweep[2]
    shutil.copytree(smoke_sweep[0], root)  # the session's root is shared: read, never written
    before = open_results(root)
    proc = eskin("sweep", "--grid", "smoke", "--root", str(root), env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "7 points (7 cached, 0 computed)" in proc.stdout
    assert "best accuracy" in proc.stdout and "open_results" in proc.stdout
    # The last lines: the Prefect link, then where the UI's login string is (not the string).
    *_, link, login = proc.stdout.strip().splitlines()
    assert link.startswith("Prefect flow run: http://127.0.0.1:")
    assert login == (
        "The Prefect UI asks once per browser for its auth string: paste the content of "
        f"{server.auth_file()} (eskin server status names it too)."
    )
    assert server.auth_file().read_text().strip() not in proc.stdout
    after = open_results(root)
    for name in SMOKE_SWEEPS:
        xr.testing.assert_identical(before[name], after[name])


@pytest.mark.slow
def test_extending_a_grid_computes_only_new_points(smoke_sweep, suite_cluster, tmp_path):
    # A copy: the extended grid rewrites the "threshold" cube, which other tests compare.
    root = tmp_path / "run"
    shutil.copytree(smoke_sweep[0], root)
    env = smoke_sweep[2]
    grid = tmp_path / "extended.toml"
    grid.write_text(
        'name = "extended"\nbase = "smoke"\n'
        '[sweeps.threshold]\naxes = { "readout.threshold_v" = [0.05, 0.09, 0.13] }\n'
    )
    proc = eskin(
        "sweep", "--grid", str(grid), "--root", str(root), *suite_cluster, "--json", env=env
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert (summary["points"], summary["cache_hits"], summary["computed"]) == (3, 2, 1)


# -- bad input: one line on stderr, exit 2, nothing written -------------------------------------


def listing(path):
    """What is at ``path``: its entries, a file's bytes, or None if absent."""
    if path.is_dir():
        return sorted(os.listdir(path))
    return path.read_bytes() if path.exists() else None


def refused(capsys, tmp_path, *argv, root=None):
    root = root or tmp_path / "root"
    before = listing(root)
    code = main(["sweep", *argv, "--root", str(root)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and err.startswith("eskin: error: ")
    assert listing(root) == before, "something was written under the root"
    return err


def grid_file(tmp_path, sweeps: str) -> str:
    path = tmp_path / "grid.toml"
    path.write_text('base = "smoke"\n' + sweeps)
    return str(path)


@pytest.mark.parametrize(
    ("sweeps", "expected"),
    [
        ('[sweeps.a]\naxes = { "readout.treshold_v" = [0.1] }\n', "not a scene field"),
        ('[sweeps.a]\naxes = { "coding.window_s" = [] }\n', "must be a non-empty list"),
        ('[sweeps.a]\naxes = { "coding.window_s" = [0.1, 0.1] }\n', "duplicate values 0.1"),
        ('[sweeps.a]\naxes = { "coding.window_s" = [0.1, 9.0] }\n', "do not fit the shortest"),
    ],
)
def test_bad_grids_are_refused_before_any_work(capsys, tmp_path, sweeps, expected):
    assert expected in refused(capsys, tmp_path, "--grid", grid_file(tmp_path, sweeps))


def test_all_grid_problems_are_listed_at_once(capsys, tmp_path):
    sweeps = (
        '[sweeps.a]\naxes = { "readout.treshold_v" = [0.1] }\n'
        '[sweeps.b]\naxes = { "coding.window_s" = [0.1, 0.1] }\n'
    )
    err = refused(capsys, tmp_path, "--grid", grid_file(tmp_path, sweeps))
    assert "2 problems" in err and "treshold_v" in err and "duplicate" in err


def test_unknown_grid_name(capsys, tmp_path):
    assert "built-in grids: paper, smoke" in refused(capsys, tmp_path, "--grid", "nope")


def test_a_root_that_is_a_file_is_refused(capsys, tmp_path):
    root = tmp_path / "file"
    root.write_text("mine")
    err = refused(capsys, tmp_path, "--grid", "smoke", root=root)
    assert str(root) in err
    assert root.read_text() == "mine"


def test_a_foreign_directory_is_refused_and_left_alone(capsys, tmp_path):
    root = tmp_path / "thesis"
    root.mkdir()
    (root / "chapter1.tex").write_text("precious")
    assert str(root) in refused(capsys, tmp_path, "--grid", "smoke", root=root)
    assert (root / "chapter1.tex").read_text() == "precious"


def test_unreachable_scheduler_fails_fast_with_a_clear_message(capsys, tmp_path):
    import time

    start = time.monotonic()
    err = refused(capsys, tmp_path, "--grid", "smoke", "--address", "tcp://127.0.0.1:9")
    assert time.monotonic() - start < 30
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err


def test_malformed_address(capsys, tmp_path):
    err = refused(capsys, tmp_path, "--grid", "smoke", "--address", "127.0.0.1:8786")
    assert "expected tcp://HOST:PORT" in err


@pytest.mark.slow
def test_the_cube_guide_queries_run_on_a_sweep(smoke_sweep):
    import re
    from pathlib import Path

    guide = (Path(__file__).resolve().parents[2] / "docs" / "how-to" / "cubes.md").read_text()
    block = next(
        b for b in re.findall(r"```python\n(.*?)```", guide, flags=re.S) if "open_results" in b
    )
    namespace: dict = {}
    exec(block.replace('"runs/paper"', repr(str(smoke_sweep[0]))), namespace)
    assert set(namespace["cubes"]) == SMOKE_SWEEPS


@pytest.mark.slow
def test_a_grid_swept_on_a_folder_dataset_with_its_report(suite_cluster, tmp_path):
    """``--dataset`` puts any grid on other recordings; ``--report`` ends with the report, and
    the flow run links to it in the Prefect UI."""
    import urllib.request

    from flows import server
    from flows.sweep import artifact_key

    data = tmp_path / "three textures"
    data.mkdir()
    (data / "dataset.toml").write_text("sampling_rate_hz = 500.0\nname = 'three'\n")
    rng = np.random.default_rng(1)
    t = np.arange(1000) / 500.0
    for k, texture in enumerate(("fine", "medium", "coarse")):
        (data / texture).mkdir()
        for r in range(4):
            ridges = np.sin(2 * np.pi * (5 + 10 * k) * t + rng.uniform(0, 2 * np.pi))
            np.save(data / texture / f"r{r}.npy", ridges + 0.3 * rng.standard_normal(t.size))
    grid = tmp_path / "grid.toml"
    grid.write_text(
        'name = "g"\nbase = "smoke"\n[sweeps.t]\naxes = { "readout.threshold_v" = [0.05, 0.2] }\n'
    )
    root = tmp_path / "run"
    env = hermetic_env(tmp_path)
    proc = eskin(
        "sweep",
        "--grid",
        str(grid),
        "--dataset",
        str(data),
        "--root",
        str(root),
        *suite_cluster,
        "--report",
        "--json",
        env=env,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads(proc.stdout)
    assert summary["computed"] == 2
    assert Path(summary["report"]) == root / "report" / "report.html"
    assert Path(summary["report"]).is_file()
    cube = open_results(root)["t"]
    assert cube.sizes["threshold_v"] == 2
    assert "three textures" in cube["dataset.path"].item()
    assert (cube.attrs["dataset_name"], cube.attrs["sampling_rate_hz"]) == ("three", 500.0)
    assert cube.attrs["class_names"] == ["coarse", "fine", "medium"]
    # Per-recording evidence of the folder's 12 recordings, and a report that opens with the
    # design answer for them.
    assert cube.sizes["recording"] == 12 and sorted(set(cube["label"].values)) == [0, 1, 2]
    markdown = (root / "report" / "report.md").read_text()
    assert markdown.index("## The answer") < markdown.index("## Against the paper")
    assert "Chance is 1/3 = 33.3 %" in markdown

    api = server.status().api_url  # the suite's server, which this sweep used
    request = urllib.request.Request(
        f"{api}/artifacts/filter",
        data=json.dumps(
            {"artifacts": {"key": {"any_": [artifact_key(root.name, "report")]}}}
        ).encode(),
        headers=api_headers(server.auth_file().read_text().strip()),
        method="POST",
    )
    with urllib.request.urlopen(request, timeout=60) as response:
        links = json.loads(response.read())
    assert any(Path(summary["report"]).as_uri() in a["data"] for a in links)


@pytest.mark.slow
def test_the_spiking_decoder_beside_the_ffnn_on_shared_chips(suite_cluster, tmp_path):
    """A sweep of ``ffnn`` and ``snn`` deployed ``shared`` on several chips runs end to end: every
    chip's accuracy for both models, and the yield over the chips (few chips, few epochs)."""
    grid = tmp_path / "grid.toml"
    grid.write_text(
        'name = "g"\nbase = "smoke"\n[sweeps.shared]\n'
        'set = { "chips.count" = 3, "chips.deployment" = "shared", '
        '"training.models" = ["ffnn", "snn"], "training.epochs" = 2, '
        '"training.snn.epochs" = 2, "readout.effects.threshold_mismatch.sigma_rel" = 0.2 }\n'
        'axes = { "readout.threshold_v" = [0.05, 0.09] }\n'
    )
    root = tmp_path / "run"
    proc = eskin(
        *("sweep", "--grid", str(grid), "--root", str(root), *suite_cluster, "--json"),
        env=hermetic_env(tmp_path),
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads(proc.stdout)["computed"] == 2
    cube = open_results(root)["shared"]
    assert cube["model"].values.tolist() == ["ffnn", "snn"]
    assert cube.sizes["chip"] == 3
    accuracy = cube["accuracy_mean"].transpose("threshold_v", "model", "chip").values
    assert accuracy.shape == (2, 2, 3) and np.all((accuracy >= 0) & (accuracy <= 1))
    assert np.all(np.isfinite(cube["accuracy_p05"].values))
