"""Scenes: validation naming every field at once, canonical form, built-ins, cache keys."""

import math

import pytest

from pipeline.design import scene as scene_module
from pipeline.design.effects import AmplifierNoise, Effect, ThresholdMismatch
from pipeline.design.scene import Model, Scene, builtin_scene_names, scene_fields
from pipeline.errors import SceneError
from pipeline.run.stages import cache_key, stage_fields


def test_paper_scene_is_the_papers_operating_point():
    scene = Scene.paper()
    assert (scene.array.rows, scene.array.cols) == (3, 3)
    assert scene.readout.threshold_v == 0.09
    assert scene.readout.full_scale_v == 1.0
    assert scene.readout.is_ideal
    assert scene.coding.window_s == 0.1
    assert scene.coding.n_windows == "auto"
    assert scene.training.models == (Model.FFNN, Model.CNN)
    assert scene.training.hidden_units == 100
    assert scene.training.epochs == 100
    assert scene.training.learning_rate == 1e-3
    assert scene.training.folds == 10
    assert math.isclose(scene.readout.equivalent_bits, 3.47, abs_tol=0.005)


def test_builtin_names():
    assert {"paper", "smoke"} <= set(builtin_scene_names())
    with pytest.raises(SceneError, match="no built-in scene 'nope'"):
        Scene.builtin("nope")


def test_effects_parse_into_typed_parameters():
    scene = Scene.from_dict(
        {
            "readout": {
                "effects": {
                    "threshold_mismatch": {"sigma_rel": 0.2},
                    "amplifier_noise": {},
                }
            }
        }
    )
    assert scene.readout.effects == {
        Effect.AMPLIFIER_NOISE: AmplifierNoise(),
        Effect.THRESHOLD_MISMATCH: ThresholdMismatch(sigma_rel=0.2),
    }
    assert not scene.readout.is_ideal and scene.readout.is_random


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"colour": 1}, "colour: unknown key"),
        ({"array": {"rowz": 3}}, "array.rowz: unknown key"),
        ({"readout": {"threshold_v": 0}}, "readout.threshold_v: 0 is out of range: must be > 0 V"),
        ({"readout": {"threshold_v": -0.1}}, "readout.threshold_v: -0.1 is out of range"),
        ({"array": {"rows": 0}}, "array.rows: 0 is out of range"),
        ({"readout": {"effects": {"amplifier_noise": {"sigma_v": -1}}}}, "sigma_v: -1 is out"),
        ({"readout": {"effects": {"wobble": {}}}}, "readout.effects.wobble: unknown effect"),
        ({"coding": {"window_s": "long"}}, "coding.window_s: expected a number"),
        ({"coding": {"polarity": "both"}}, "coding.polarity: 'both' is not one of"),
        ({"training": {"models": ["svm"]}}, "training.models: 'svm' is not one of"),
        ({"training": {"folds": 1}}, "training.folds: 1 is out of range"),
        ({"dataset": {"kind": "folder"}}, "dataset.path: required for kind 'folder'"),
        ({"readout": {"threshold_v": 2.0}}, "not below full_scale_v"),
        ({"readout": {"threshold_v": float("nan")}}, "expected a finite number"),
        ({"array": {"rows": True}}, "array.rows: expected an integer"),
        ({"readout": {"encoder": "n-lcs"}}, "readout.encoder: 'n-lcs' is not one of"),
        ({"readout": {"decay": {"theta_min_v": 0}}}, "readout.decay.theta_min_v: 0 is out of"),
        ({"readout": {"decay": {"tau_s": -1.0}}}, "readout.decay.tau_s: -1.0 is out of range"),
        (
            {"readout": {"encoder": "decaying", "decay": {"theta_min_v": 0.1}}},
            "readout.decay.theta_min_v: 0.1 V is above threshold_v = 0.09 V",
        ),
    ],
)
def test_bad_values_name_the_field(data, message):
    with pytest.raises(SceneError, match=message.replace("(", r"\(").replace(")", r"\)")):
        Scene.from_dict(data)


def test_every_problem_is_reported_at_once():
    with pytest.raises(SceneError) as info:
        Scene.from_dict({"array": {"rows": 0, "cols": -1}, "readout": {"threshold_v": 0}, "x": 1})
    message = str(info.value)
    assert "4 problems" in message
    for field in ("array.rows", "array.cols", "readout.threshold_v", "x: unknown key"):
        assert field in message
    assert "\n" not in message


def test_toml_round_trip(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text(
        "[array]\nrows = 4\ncols = 1\n[readout]\nthreshold_v = 0.05\n"
        "[readout.effects]\ncomparator_noise = { sigma_v = 0.01 }\n"
    )
    scene = Scene.from_toml(path)
    assert scene.name == "mine"
    assert scene.array.n_taxels == 4
    assert Scene.from_dict(scene.to_dict()) == scene


def test_toml_errors_name_the_file(tmp_path):
    with pytest.raises(SceneError, match="missing.toml: cannot read file"):
        Scene.from_toml(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[array\nrows=")
    with pytest.raises(SceneError, match="bad.toml: not valid TOML"):
        Scene.from_toml(bad)


def test_canonical_form_is_stable_and_sorted():
    a = Scene.from_dict({"readout": {"threshold_v": 0.05}, "array": {"rows": 2}})
    b = Scene.from_dict({"array": {"rows": 2}, "readout": {"threshold_v": 0.05}, "name": "other"})
    assert a.canonical() == b.canonical()
    assert '"threshold_v":0.05' in a.canonical()


def test_replace_revalidates():
    scene = Scene.paper().replace(**{"readout.threshold_v": 0.2})
    assert scene.readout.threshold_v == 0.2
    with pytest.raises(SceneError, match="readout.threshold_v"):
        Scene.paper().replace(**{"readout.threshold_v": -1.0})


def test_spike_key_ignores_window_and_model_but_not_threshold():
    base = Scene.paper()
    assert cache_key(base, "spikes") == cache_key(
        base.replace(**{"coding.window_s": 0.2}), "spikes"
    )
    assert cache_key(base, "rates") != cache_key(base.replace(**{"coding.window_s": 0.2}), "rates")
    assert cache_key(base, "rates") == cache_key(base.replace(**{"training.epochs": 3}), "rates")
    assert cache_key(base, "spikes") != cache_key(
        base.replace(**{"readout.threshold_v": 0.1}), "spikes"
    )
    assert cache_key(base, "spikes") == cache_key(base.replace(name="renamed"), "spikes")


def test_removing_an_effect_removes_it_from_the_key():
    ideal = Scene.paper()
    noisy = ideal.replace(**{"readout.effects": {"amplifier_noise": {"sigma_v": 0.01}}})
    back = noisy.replace(**{"readout.effects": {}})
    assert cache_key(noisy, "spikes") != cache_key(ideal, "spikes")
    assert cache_key(back, "spikes") == cache_key(ideal, "spikes")
    assert "amplifier_noise" not in ideal.canonical(stage_fields(ideal, "spikes"))


def test_seed_enters_the_spike_key_only_with_random_effects():
    ideal = Scene.paper()
    assert "seed" not in stage_fields(ideal, "spikes")
    assert cache_key(ideal, "spikes") == cache_key(ideal.replace(seed=7), "spikes")
    saturating = ideal.replace(**{"readout.effects": {"saturation": {}}})
    assert cache_key(saturating, "spikes") == cache_key(saturating.replace(seed=7), "spikes")
    noisy = ideal.replace(**{"readout.effects": {"amplifier_noise": {}}})
    assert cache_key(noisy, "spikes") != cache_key(noisy.replace(seed=7), "spikes")


def test_the_decay_is_keyed_only_for_the_decaying_encoder():
    fixed = Scene.paper()
    canonical = fixed.canonical()
    assert "encoder" not in canonical and "decay" not in canonical  # earlier keys stay valid
    # The decay of a fixed threshold is not simulated: any value, the same key, accepted even
    # above the threshold.
    idle = fixed.replace(**{"readout.decay.tau_s": 5.0, "readout.decay.theta_min_v": 0.5})
    assert idle.readout.theta_min_v == fixed.readout.threshold_v
    decaying = fixed.replace(**{"readout.encoder": "decaying"})
    assert decaying.readout.theta_min_v == 0.03
    for stage in ("recordings", "spikes", "rates", "results"):
        assert cache_key(idle, stage) == cache_key(fixed, stage)
    for stage in ("spikes", "rates", "results"):
        assert cache_key(decaying, stage) != cache_key(fixed, stage)
        slower = decaying.replace(**{"readout.decay.tau_s": 0.05})
        assert cache_key(slower, stage) != cache_key(decaying, stage)
    assert cache_key(decaying, "recordings") == cache_key(fixed, "recordings")
    assert '"decay":{"tau_s":0.02,"theta_min_v":0.03}' in decaying.canonical()
    assert cache_key(decaying.replace(**{"readout.encoder": "lcs"}), "spikes") == cache_key(
        fixed, "spikes"
    )


def test_the_snn_is_keyed_only_for_scenes_that_train_it():
    paper = Scene.paper()
    assert "snn" not in paper.canonical()  # earlier keys stay valid
    idle = paper.replace(**{"training.snn.step_s": 0.05, "training.snn.hidden_neurons": 7})
    spiking = paper.replace(**{"training.models": ["ffnn", "cnn", "snn"]})
    for stage in ("recordings", "spikes", "rates", "results"):
        assert cache_key(idle, stage) == cache_key(paper, stage)
    for stage in ("recordings", "spikes"):
        assert cache_key(spiking, stage) == cache_key(paper, stage)
    for stage in ("rates", "results"):  # the rates level counts the snn's steps
        finer = spiking.replace(**{"training.snn.step_s": 0.01})
        assert cache_key(finer, stage) != cache_key(spiking, stage)
    assert stage_fields(spiking, "rates")[-1] == "training.snn"
    assert "training.snn" not in stage_fields(paper, "rates")


@pytest.mark.parametrize(
    ("changes", "culprit"),
    [
        ({"training.snn.step_s": 0.2}, "is longer than coding.window_s"),
        ({"training.snn.step_s": 0.03}, "does not divide coding.window_s"),
        ({"coding.window_s": 0.125}, "does not divide coding.window_s = 0.125 s"),
    ],
)
def test_the_snn_step_must_divide_the_window(changes, culprit):
    spiking = {"training.models": ["snn"]}
    with pytest.raises(SceneError, match=f"training.snn.step_s: .*{culprit}"):
        Scene.paper().replace(**spiking, **changes)
    Scene.paper().replace(**changes)  # a scene without the snn does not mind its step
    assert Scene.paper().replace(**spiking, **{"training.snn.step_s": 0.025}).training.snn


def test_a_new_model_revision_changes_every_key(monkeypatch):
    scene = Scene.paper()
    stages = ("recordings", "spikes", "rates", "results")
    before = {stage: cache_key(scene, stage) for stage in stages}
    monkeypatch.setattr(scene_module, "MODEL_REVISION", scene_module.MODEL_REVISION + 1)
    assert all(cache_key(scene, stage) != before[stage] for stage in stages)


def test_every_field_is_listed_once_with_its_declaration():
    listed = {info.path: info for info in scene_fields()}
    assert len(listed) == len(scene_fields())
    threshold = listed["readout.threshold_v"]
    assert (threshold.type, threshold.default, threshold.units) == ("float", 0.09, "V")
    assert threshold.range == "> 0 V" and threshold.description
    noise = listed["readout.effects.amplifier_noise.sigma_v"]
    assert (noise.default, noise.units, noise.range) == (0.005, "V", ">= 0 V")
    assert listed["coding.n_windows"].type == "int | 'auto'"
    assert listed["coding.n_windows"].range == "'auto' or between 1 and 100000"
    assert listed["training.models"].default == ["ffnn", "cnn"]
    assert listed["dataset.path"].type == "str (optional)"
    assert "name" not in listed and "readout.effects" not in listed
    assert threshold.text() == (
        "readout.threshold_v: float = 0.09 V (> 0 V), comparator threshold (level-crossing step)"
    )
    assert (
        listed["coding.polarity"]
        .text()
        .startswith("coding.polarity: 'merged' | 'split' = \"merged\", how")
    )
    # Each listed field is one a scene reads, at its listed default.
    for path, info in listed.items():
        if info.default is not None and not path.startswith("readout.effects."):
            assert Scene().replace(**{path: info.default}) == Scene(), path


def test_a_value_out_of_its_declared_range_is_refused_with_the_range():
    for info in scene_fields():
        if info.range.startswith("between"):
            low = float(info.range.split()[1])
            value = int(low) - 1 if info.type in ("int", "int (optional)") else low / 2 - 1
            path = info.path
            with pytest.raises(SceneError, match=f"{path}: .* is out of range: must be between"):
                Scene().replace(**{path: value})
