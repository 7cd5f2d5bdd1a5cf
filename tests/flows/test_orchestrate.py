"""Tests of flows.orchestrate's pure parts: the order in which points are submitted."""

from flows.orchestrate import training_cost
from pipeline.coding import MAX_AUTO_WINDOWS
from pipeline.scene import Scene


def test_training_cost_is_frame_size_per_model_with_auto_windows_at_their_most():
    paper = Scene.paper()  # 3x3 taxels, auto windows, FFNN and CNN
    assert training_cost(paper) == 9 * MAX_AUTO_WINDOWS * 2
    assert training_cost(paper.replace(**{"coding.n_windows": 160})) == 9 * 160 * 2
    assert training_cost(paper.replace(**{"array.rows": 5, "array.cols": 5})) == 25 * 40 * 2
    assert training_cost(paper.replace(**{"training.models": ["ffnn"]})) == 9 * 40
