"""What a grid costs: a point's training cost and cost kind, and the points a machine plans."""

from pipeline.design.grid_cost import (
    PLAN_BYTES_PER_POINT,
    cost_kind,
    plannable_points,
    training_cost,
)
from pipeline.design.scene import Scene
from pipeline.design.windows import MAX_AUTO_WINDOWS


def test_training_cost_is_frame_size_per_model_with_auto_windows_at_their_most():
    paper = Scene.paper()  # 3x3 taxels, auto windows, FFNN and CNN
    assert training_cost(paper) == 9 * MAX_AUTO_WINDOWS * 2
    assert training_cost(paper.replace(**{"coding.n_windows": 160})) == 9 * 160 * 2
    assert training_cost(paper.replace(**{"array.rows": 5, "array.cols": 5})) == 25 * 40 * 2
    assert training_cost(paper.replace(**{"training.models": ["ffnn"]})) == 9 * 40


def test_cost_kind_ignores_threshold_effect_values_and_seeds_but_not_effect_names():
    base = Scene.builtin("smoke")
    noisy = base.replace(**{"readout.effects.amplifier_noise.sigma_v": 0.01})
    same = [
        base.replace(**{"readout.threshold_v": 0.05}),
        base.replace(**{"seed": 3, "dataset.seed": 4, "training.seed": 5}),
    ]
    assert all(cost_kind(s) == cost_kind(base) for s in same)
    assert cost_kind(noisy) != cost_kind(base)
    assert cost_kind(noisy.replace(**{"readout.effects.amplifier_noise.sigma_v": 0.5})) == (
        cost_kind(noisy)
    )
    for change in ({"coding.window_s": 0.2}, {"array.rows": 1}, {"training.models": ["ffnn"]}):
        assert cost_kind(base.replace(**change)) != cost_kind(base)


def test_plannable_points_follow_memory_up_to_the_planning_time():
    assert plannable_points(2 * PLAN_BYTES_PER_POINT * 1000) == 1000
    assert plannable_points(24 * 2**30) == 6_000_000
