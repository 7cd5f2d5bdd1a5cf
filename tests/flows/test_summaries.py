"""``flows.summaries``: what ``eskin run`` and ``eskin sweep`` print, as plain functions."""

import json
import math
from types import SimpleNamespace

import numpy as np
import xarray as xr

from flows.summaries import (
    format_search_summary,
    format_summary,
    format_sweep_summary,
    json_safe,
    result_summary,
)
from pipeline.chain.training import CrossValidation
from pipeline.design.scene import Model, Scene
from pipeline.run.grid_keys import unique_points


def fake_result(ssnr_db: float, labels=None) -> SimpleNamespace:
    cv = CrossValidation(
        Model.FFNN,
        np.array([0.5, 0.5]),
        1.0,
        predicted=np.array([0, 1, 1, 1]),
        test_fold=np.array([0, 0, 1, 1]),
    )
    metrics = SimpleNamespace(
        ssnr_db=ssnr_db,
        ste_s2=0.0,
        ste_sign_safe_s2=0.0,
        event_rate_hz=10.0,
        data_rate_bps=30.0,
        equivalent_bits=3.5,
    )
    return SimpleNamespace(
        scene=Scene.load("smoke"),
        n_recordings=48,
        n_classes=12,
        n_windows=15,
        dropped_spikes=0,
        metrics=metrics,
        accuracy={Model.FFNN: cv},
        timings_s={"load": 0.25, "train_ffnn": 1.0},
        labels=labels,
    )


def test_result_summary_is_plain_json_once_infinities_are_strings():
    summary = result_summary(fake_result(math.inf))
    assert summary["accuracy"] == {
        "ffnn": {"mean": 0.5, "std": 0.0, "folds": [0.5, 0.5], "repeats": 1}
    }  # no labels: no interval
    assert (summary["taxels"], summary["chance"]) == (4, 1 / 12)
    text = json.dumps(json_safe(summary), allow_nan=False)
    assert json.loads(text)["ssnr_db"] == "inf"


def test_json_safe_names_every_non_finite_number_nested():
    value = {"a": [-math.inf, math.nan, 1.5], "b": {"c": math.inf}, "d": "inf"}
    assert json_safe(value) == {"a": ["-inf", "nan", 1.5], "b": {"c": "inf"}, "d": "inf"}


def test_format_summary_names_models_and_an_infinite_ssnr():
    text = format_summary(result_summary(fake_result(math.inf)))
    assert "FFNN  accuracy  50.0 %, fold spread +- 0.0 % over 2 folds" in text
    assert "SSNR inf (REAL = TRUE) dB" in text and "(total 1.2)" in text
    assert "SSNR 12.35 dB" in format_summary(result_summary(fake_result(12.345)))


def test_the_summary_gives_the_wilson_interval_over_recordings():
    """Two of four recordings right: scipy's Wilson interval for 2 of 4."""
    from scipy import stats

    summary = result_summary(fake_result(1.0, labels=np.array([0, 0, 1, 0])))
    ci = stats.binomtest(2, 4).proportion_ci(0.95, method="wilson")
    acc = summary["accuracy"]["ffnn"]
    assert (acc["low"], acc["high"]) == (ci.low, ci.high)
    assert acc["interval"].startswith("Wilson")
    text = format_summary(summary)
    assert f"50.0 % (95 % interval {100 * ci.low:.1f}-{100 * ci.high:.1f} %), fold spread" in text


def test_format_sweep_summary_uses_the_given_cubes_and_their_best_points(tmp_path):
    accuracy = np.array([[[0.2, 0.4], [0.9, 0.7]], [[0.6, 0.6], [0.1, 0.1]]])
    cube = xr.Dataset(
        {"accuracy_mean": (("threshold_v", "model"), accuracy.mean(axis=-1))},
        coords={"threshold_v": [0.05, 0.09], "model": ["ffnn", "cnn"]},
    )
    summary = {
        "root": str(tmp_path),
        "cubes": {"threshold": "somewhere"},
        "points": 2,
        "cache_hits": 1,
        "computed": 1,
        "seconds": 3.04,
        "report": "r.html",
    }
    lines = format_sweep_summary(summary, {"threshold": cube}).splitlines()
    assert lines[0] == "2 points (1 cached, 1 computed) in 3.0 s"
    best_ffnn = ["threshold", "threshold_v=2", "ffnn", "60.0", "%", "at", "threshold_v=0.09"]
    assert lines[2].split() == best_ffnn
    assert lines[3].split()[2:4] == ["cnn", "80.0"]
    assert lines[-1] == "report: r.html"


def test_format_sweep_summary_names_an_option_axis_by_its_value(tmp_path):
    cube = xr.Dataset(
        {"accuracy_mean": (("encoder", "model"), np.array([[0.5], [0.7]]))},
        coords={"encoder": ["lcs", "decaying"], "model": ["ffnn"]},
    )
    summary = {"root": str(tmp_path), "cubes": {"encoder": "x"}, "points": 2}
    summary |= {"cache_hits": 0, "computed": 2, "seconds": 1.0}
    lines = format_sweep_summary(summary, {"encoder": cube}).splitlines()
    assert lines[2].split()[-2:] == ["at", "encoder=decaying"]


def test_a_design_gets_one_bootstrap_interval_in_any_sweep_and_in_a_run():
    """With several repeats the interval is a bootstrap: seeded from the design's result key
    and the model, not from where the design sits in a grid, so two sweeps holding it at
    different positions and ``eskin run`` of it give the same interval."""
    from pipeline.design.grid import Grid
    from pipeline.results.cube import build_cube
    from pipeline.run.entries import OutOfFold, ResultEntry

    repeats = {"training.repeats": 3}
    grid = Grid.from_dict(
        {
            "base": "smoke",
            "sweeps": {
                "wide": {"set": repeats, "axes": {"readout.threshold_v": [0.05, 0.07, 0.09]}},
                "one": {"set": repeats, "axes": {"readout.threshold_v": [0.09]}},
            },
        }
    )
    n = 60
    labels = np.arange(n) % 3
    rng = np.random.default_rng(5)
    # Each repeat gets a different part of the recordings right: resampling matters.
    predicted = np.where(rng.random((3, n)) < 0.6, labels, (labels + 1) % 3)
    names = tuple(f"r{i}" for i in range(n))
    folds = np.tile(np.arange(n) % 4, (3, 1))
    entry = ResultEntry(
        {"ffnn": np.full((3, 4), 0.5)},
        {},
        fake_result(1.0).metrics,
        None,
        OutOfFold(names, labels, {"ffnn": predicted}, folds),
    )
    records = {key: entry for key in unique_points(grid)}
    cubes = {sweep.name: build_cube(grid, sweep, records) for sweep in grid.sweeps}
    wide = cubes["wide"].sel(threshold_v=0.09, model="ffnn")
    one = cubes["one"].sel(threshold_v=0.09, model="ffnn")
    assert "bootstrap" in wide["accuracy_low"].attrs["interval"]
    design = next(p.scene for p in grid.points() if p.sweep == "one")
    cv = CrossValidation(Model.FFNN, np.full((3, 4), 0.5), 1.0, predicted=predicted)
    run = SimpleNamespace(**{**vars(fake_result(1.0)), "scene": design, "labels": labels})
    run.accuracy = {Model.FFNN: cv}
    summary = result_summary(run)["accuracy"]["ffnn"]
    interval = (summary["low"], summary["high"])
    assert (wide["accuracy_low"].item(), wide["accuracy_high"].item()) == interval
    assert (one["accuracy_low"].item(), one["accuracy_high"].item()) == interval
    # Another design (threshold 0.07, same predictions) draws other resamples.
    other = cubes["wide"].sel(threshold_v=0.07, model="ffnn")
    assert (other["accuracy_low"].item(), other["accuracy_high"].item()) != interval
    # ... as the same design would at another grid position, were it seeded by position.
    from pipeline.results.stats import accuracy_interval

    by_position = [
        accuracy_interval(predicted == labels, labels, rng=np.random.default_rng([0, i, 0]))
        for i in (0, 2)
    ]
    assert (by_position[0].low, by_position[0].high) != (by_position[1].low, by_position[1].high)


def test_format_search_summary_names_the_sampler_and_marks_trials_off_the_front():
    summary = {
        "trials": 3,
        "new_trials": 2,
        "computed": 2,
        "cache_hits": 0,
        "seconds": 12.5,
        "search_seconds": 10.25,
        "sampler": "gp",
        "front": [
            {
                "trial": 0,
                "objectives": {"accuracy.ffnn": 0.5},
                "params": {"array.rows": 2},
                "on_front": True,
            },
            {
                "trial": 2,
                "objectives": {"accuracy.ffnn": 0.48},
                "params": {"array.rows": 1},
                "on_front": False,
            },
        ],
        "cubes": {"trials": "r/store.zarr/cubes/s.trials"},
    }
    lines = format_search_summary(summary).splitlines()
    assert lines[0] == (
        "3 trials (2 new: 2 points computed, 0 found in the store) in 12.5 s; "
        "10.2 stage seconds in all; sampler gp"
    )
    assert lines[2:4] == [
        "  trial 0: accuracy.ffnn 0.5 at array.rows=2",
        "  ~trial 2: accuracy.ffnn 0.48 at array.rows=1",
    ]
    assert lines[4] == "cube trials: r/store.zarr/cubes/s.trials"


def test_format_sweep_summary_keeps_columns_aligned_past_long_names(tmp_path):
    """A sweep name and dims longer than the header's keep every column starting in one
    place."""
    short = xr.Dataset(
        {"accuracy_mean": (("threshold_v", "model"), np.array([[0.5], [0.7]]))},
        coords={"threshold_v": [0.05, 0.09], "model": ["ffnn"]},
    )
    wide = xr.Dataset(
        {"accuracy_mean": (("sigma_rel", "chip", "model"), np.full((2, 3, 1), 0.6))},
        coords={"sigma_rel": [0.0, 0.1], "chip": [0, 1, 2], "model": ["ffnn"]},
    )
    summary = {"root": str(tmp_path), "cubes": {"t": "x", "mismatch_shared_chips": "y"}}
    summary |= {"points": 8, "cache_hits": 0, "computed": 8, "seconds": 1.0}
    cubes = {"t": short, "mismatch_shared_chips": wide}
    lines = format_sweep_summary(summary, cubes).splitlines()[1:4]
    assert lines[0].index("model") == lines[1].index("ffnn") == lines[2].index("ffnn")
    assert lines[1].index("%") == lines[2].index("%")
    assert lines[0].index("dims") == lines[2].index("sigma_rel=2")
