"""Space files: dimensions, objectives, every problem at once; trials as a grid."""

from pathlib import Path

import pytest

from pipeline.design.space import (
    MISMATCH_FIELD,
    Dimension,
    DimensionKind,
    Direction,
    Metric,
    Space,
    load_space,
)
from pipeline.errors import SceneError
from pipeline.run.grid_keys import keyed_points, unique_points

EXAMPLE = Path(__file__).parents[3] / "examples" / "design_space.toml"


def space(**changes) -> dict:
    data = {
        "name": "s",
        "base": "smoke",
        "space": {
            "readout.threshold_v": {"low": 0.02, "high": 0.3, "log": True},
            "coding.window_s": {"choices": [0.05, 0.1, 0.2]},
            "array.rows": {"low": 1, "high": 4, "step": 1},
        },
        "objectives": {"accuracy.ffnn": "max", "data_rate_bps": "min"},
    }
    for key, value in changes.items():
        data[key] = value
    return data


def problems(data: dict) -> list[str]:
    with pytest.raises(SceneError) as caught:
        Space.from_dict(data)
    return caught.value.problems


def test_the_example_space_loads_with_each_kind_of_dimension():
    loaded = load_space(EXAMPLE)
    assert loaded.name == "design" and loaded.base.name == "paper"
    threshold, window, rows = loaded.dimensions
    assert threshold == Dimension("readout.threshold_v", DimensionKind.FLOAT, 0.02, 0.3, None, True)
    assert window.kind is DimensionKind.CATEGORICAL and window.choices == (0.05, 0.1, 0.2)
    assert rows == Dimension("array.rows", DimensionKind.INT, 1, 4, 1, False)
    accuracy, rate = loaded.objectives
    assert (accuracy.metric, accuracy.model, accuracy.direction) == (
        Metric.ACCURACY,
        "ffnn",
        Direction.MAX,
    )
    assert (rate.name, rate.sign, accuracy.sign) == ("data_rate_bps", 1.0, -1.0)


def test_every_problem_is_reported_at_once():
    found = problems(
        space(
            seed=-1,
            sampler="cmaes",
            extra=1,
            space={
                "readout.nope": {"low": 1, "high": 2},
                "array.rows": {"low": 0.5, "high": 4},
                "readout.threshold_v": {"low": 0.3, "high": 0.1},
                "readout.full_scale_v": {"low": -1.0, "high": 1.0, "log": True},
                "coding.window_s": {"choices": [0.1, 0.1]},
                "coding.n_windows": {"low": 1, "high": 4, "step": 2},
                "training.epochs": {"low": 0, "high": 4},
                "array.cols": {"low": 1, "high": 3, "size": 2},
            },
            objectives={"accuracy.svm": "max", "accuracy.cnn": "up", "latency": "min"},
        )
    )
    expected = [
        "extra: unknown key",
        "seed: expected an integer",
        "sampler: 'cmaes' is not one of 'tpe', 'nsga2', 'random', 'gp', 'auto'",
        "'readout.nope' is not a scene field",
        "space.array.rows.low: expected an integer, got 0.5",
        "space.readout.threshold_v: low (0.3) must be below high (0.1)",
        "space.readout.full_scale_v: a log range needs low > 0",
        "space.coding.window_s.choices: duplicate values 0.1",
        "space.coding.n_windows.step: 4 - 1 is not a whole number of steps of 2",
        "space.array.cols.size: unknown key",
        "space.training.epochs = 0: training.epochs: 0 is out of range",
        "objectives.accuracy.svm: unknown model 'svm'",
        "objectives.accuracy.cnn: expected 'max' or 'min'",
        "objectives.latency: unknown objective",
    ]
    assert len(found) == len(expected), found
    for text, problem in zip(expected, found, strict=True):
        assert text in problem


def test_objectives_are_two_or_three_of_models_the_base_trains():
    assert any("two or three" in p for p in problems(space(objectives={"compute_s": "min"})))
    base = {"name": "one", "training": {"models": ["cnn"]}}
    assert any("trains cnn, not ffnn" in p for p in problems(space(base=base)))
    three = {"accuracy.ffnn": "max", "readout_power_w": "min", "compute_s": "min"}
    assert len(Space.from_dict(space(objectives=three)).objectives) == 3


def test_trials_are_the_points_of_one_zipped_sweep():
    loaded = Space.from_dict(space())
    trials = [
        {"readout.threshold_v": 0.05, "coding.window_s": 0.1, "array.rows": 2},
        {"readout.threshold_v": 0.05, "coding.window_s": 0.1, "array.rows": 2},
        {"readout.threshold_v": 0.2, "coding.window_s": 0.2, "array.rows": 1},
    ]
    grid = loaded.trial_grid(trials)
    points = grid.points()
    assert len(points) == 3 and len(unique_points(grid)) == 2  # one design, computed once
    assert points[2].scene == loaded.base.replace(**trials[2])
    assert grid.sweeps[0].dims == ("threshold_v",)


def test_the_exhaustive_grid_spreads_each_dimension():
    loaded = Space.from_dict(space())
    threshold, window, rows = loaded.exhaustive_grid(3).sweeps[0].axes
    assert threshold.values == pytest.approx((0.02, (0.02 * 0.3) ** 0.5, 0.3))
    assert window.values == (0.05, 0.1, 0.2)
    assert rows.values == (1, 2, 4)  # 4 steps do not fit in 3 values: 1, 2.5, 4 rounded
    assert loaded.exhaustive_grid(4).sweeps[0].axes[2].values == (1, 2, 3, 4)


def test_the_fingerprint_follows_what_shapes_the_search():
    a = Space.from_dict(space())
    assert a.fingerprint() == Space.from_dict(space()).fingerprint()
    assert a.fingerprint() != Space.from_dict(space(seed=1)).fingerprint()
    other = space(objectives={"accuracy.ffnn": "max", "compute_s": "min"})
    assert a.fingerprint() != Space.from_dict(other).fingerprint()


def test_the_encoder_is_a_categorical_dimension_of_its_choices():
    encoders = {"readout.encoder": {"choices": ["lcs", "decaying"]}}
    loaded = Space.from_dict(
        space(space={**encoders, "readout.threshold_v": {"low": 0.05, "high": 0.3}})
    )
    encoder, _ = loaded.dimensions
    assert encoder.kind is DimensionKind.CATEGORICAL and encoder.choices == ("lcs", "decaying")
    trials = [{"readout.encoder": e, "readout.threshold_v": 0.1} for e in ("lcs", "decaying")]
    points = keyed_points(loaded.trial_grid(trials))
    assert [p.scene.readout.encoder.value for p in points] == ["lcs", "decaying"]
    assert len({p.key for p in points}) == 2
    (found,) = problems(space(space={"readout.encoder": {"choices": ["lcs", "decay"]}}))
    assert "readout.encoder: 'decay' is not one of 'lcs', 'decaying'" in found


def test_area_needs_a_mismatch_and_yield_needs_chips():
    found = problems(space(objectives={"accuracy_p05.ffnn": "max", "array_area_m2": "min"}))
    assert any("array_area_m2: needs readout.effects.threshold_mismatch" in p for p in found)
    assert any("accuracy_p05.ffnn: needs chips.count above 1" in p for p in found)
    assert any(
        "accuracy_p05: unknown objective" in p
        for p in problems(space(objectives={"accuracy_p05": "max", "data_rate_bps": "min"}))
    )
    searched = space(objectives={"accuracy.ffnn": "max", "array_area_m2": "min"})
    searched["space"][f"{MISMATCH_FIELD}.sigma_rel"] = {"low": 0.05, "high": 0.5}
    assert Space.from_dict(searched).objectives[1].metric is Metric.AREA


def test_bounds_and_choices_are_checked_together_each_corner_a_whole_scene():
    chips = {
        "chips.deployment": {"choices": ["per_chip", "shared"]},
        "chips.count": {"low": 2, "high": 10},
    }
    mismatch = {f"{MISMATCH_FIELD}.sigma_rel": {"low": 0.05, "high": 0.3}}
    # Sharing chips needs an effect drawn per chip: the mismatch another dimension searches.
    loaded = Space.from_dict(space(base="paper", space={**chips, **mismatch}))
    assert (
        loaded.scene(
            {"chips.deployment": "shared", "chips.count": 4, f"{MISMATCH_FIELD}.sigma_rel": 0.1}
        ).chips.count
        == 4
    )
    # Without it, the choice that needs it is named once, with its value.
    assert problems(space(base="paper", space=chips)) == [
        "space.chips.deployment = 'shared': chips.deployment: 'shared' needs a readout effect "
        "drawn per chip (amplifier_offset, comparator_offset, threshold_mismatch); with none "
        "every chip is identical"
    ]
    # A combination two dimensions refuse together is named by both values.
    snn = {"name": "b", "training": {"models": ["ffnn", "snn"]}}
    steps = {
        "coding.window_s": {"choices": [0.01, 0.1]},
        "training.snn.step_s": {"choices": [0.001, 0.05]},
        "readout.threshold_v": {"low": 0.05, "high": 0.2},
    }
    assert problems(space(base=snn, space=steps)) == [
        "space at coding.window_s = 0.01, training.snn.step_s = 0.05: training.snn.step_s: "
        "0.05 s is longer than coding.window_s = 0.01 s"
    ]
