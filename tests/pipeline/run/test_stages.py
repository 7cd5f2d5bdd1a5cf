"""The stage registry: keys of earlier stores stay valid, a key follows exactly what its level
reads, and a scene run reports exactly the registry's steps."""

import enum
import inspect
from dataclasses import dataclass

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from pipeline.design import fields
from pipeline.design.fields import param, part
from pipeline.design.scene import ReadoutSpec, Scene
from pipeline.run.simulate import run_scene, stage_names
from pipeline.run.stages import (
    FRONT_END,
    LEVELS,
    RECORDINGS,
    SPIKES,
    Level,
    Read,
    _checked,
    cache_key,
    level_named,
    steps_through,
)
from pipeline.run.stopwatch import Stopwatch

SMOKE = Scene.builtin("smoke")
PAPER = Scene.paper()
NOISY = SMOKE.replace(
    seed=5, **{"readout.effects": {"amplifier_noise": {"sigma_v": 0.01}, "saturation": {}}}
)
SATURATING = PAPER.replace(
    **{"readout.effects": {"saturation": {"rail_v": 0.4}}, "coding.polarity": "split"}
)

# The keys of stores made at this MODEL_REVISION (5): a change of code that alters them without a
# revision bump would recompute every store made so far instead of reusing it. Those stores were
# trained for the decision at the end of the touch, now chosen by ``training.decisions``.
FULL_TOUCH = {"training.decisions": "full_touch"}
EARLIER_KEYS = {
    "smoke": (
        SMOKE.replace(**FULL_TOUCH),
        {
            "recordings": "2968b82159a109ae9ac360c701032406",
            "spikes": "686612a1c4a6e98cba240dc442796ae5",
            "rates": "f360ea80b69dceea47462814199dae90",
            "results": "99b4ffd4d8a131b8ae504dbad16ab6ae",
        },
    ),
    "paper": (
        PAPER.replace(**FULL_TOUCH),
        {
            "recordings": "66e9b24961439c432efb2acb38375f2a",
            "spikes": "3f34ef2df7005cfe1d2962c677d3af65",
            "rates": "2dfc3ab9c1487cbcbda32fa9fdd1a93a",
            "results": "b5eaee6f06413329e4a3a0f6c5c0ba7c",
        },
    ),
    "noisy": (
        NOISY.replace(**FULL_TOUCH),
        {
            "recordings": "2968b82159a109ae9ac360c701032406",
            "spikes": "990825bd220da61c59f30ea8949bbb37",
            "rates": "9cb4495a82414b813874f0e4f204c2b8",
            "results": "b9e956b1c0f09c55f8db886bd8c0b2ed",
        },
    ),
    "saturating": (
        SATURATING.replace(**FULL_TOUCH),
        {
            "recordings": "66e9b24961439c432efb2acb38375f2a",
            "spikes": "931dce318166d45fff94c4eff79ca735",
            "rates": "65a65fa92bece999d51f3fb49ed85058",
            "results": "90218021c91f3266803de3ec421230e8",
        },
    ),
}


@pytest.mark.parametrize("name", EARLIER_KEYS)
def test_keys_of_earlier_stores_stay_valid(name):
    scene, keys = EARLIER_KEYS[name]
    assert {stage: level_named(stage).key(scene) for stage in keys} == keys
    assert {stage: cache_key(scene, stage) for stage in keys} == keys


@pytest.mark.parametrize("name", EARLIER_KEYS)
def test_training_along_the_touch_changes_the_results_key_alone(name):
    scene, keys = EARLIER_KEYS[name]
    along = scene.replace(**{"training.decisions": "along_touch"})
    assert along.training.decisions != scene.training.decisions
    new = {stage: cache_key(along, stage) for stage in keys}
    assert {s: k for s, k in new.items() if s != "results"} == {
        s: k for s, k in keys.items() if s != "results"
    }
    assert new["results"] != keys["results"]


def test_the_default_scenes_train_along_the_touch_and_reuse_the_earlier_spikes_and_rates():
    for scene, full in ((SMOKE, EARLIER_KEYS["smoke"]), (PAPER, EARLIER_KEYS["paper"])):
        assert scene.training.decisions == "along_touch"
        assert cache_key(scene, "rates") == full[1]["rates"]
        assert cache_key(scene, "results") != full[1]["results"]


class Encoder(enum.StrEnum):
    """A test-only option: today's level-crossing encoder and another one."""

    LCS = "lcs"
    DECAYING = "decaying"


@dataclass(frozen=True)
class ReadoutWithEncoder(ReadoutSpec):
    """The readout with a field added in this test alone, whose default is what the readout
    does today, declared neutral."""

    encoder: Encoder = param(Encoder.LCS, "1", "encoder architecture", neutral=True)


@dataclass(frozen=True)
class SceneWithEncoder(Scene):
    readout: ReadoutWithEncoder = part(ReadoutWithEncoder)


@dataclass(frozen=True)
class ReadoutWithKeyedEncoder(ReadoutSpec):
    """The same field, its default not declared neutral."""

    encoder: Encoder = param(Encoder.LCS, "1", "encoder architecture")


@dataclass(frozen=True)
class SceneWithKeyedEncoder(Scene):
    readout: ReadoutWithKeyedEncoder = part(ReadoutWithKeyedEncoder)


@pytest.mark.parametrize("name", EARLIER_KEYS)
def test_a_new_field_at_its_neutral_default_leaves_every_key_unchanged(name):
    scene, keys = EARLIER_KEYS[name]
    extended = SceneWithEncoder.from_dict(scene.to_dict())
    assert extended.readout.encoder is Encoder.LCS
    assert extended.to_dict()["readout"]["encoder"] == "lcs"  # a field like any other
    assert {stage: level_named(stage).key(extended) for stage in keys} == keys
    assert {stage: cache_key(extended, stage) for stage in keys} == keys
    # Another value is part of the key of every level that reads the readout.
    other = extended.replace(**{"readout.encoder": "decaying"})
    assert isinstance(other, SceneWithEncoder) and other.readout.encoder is Encoder.DECAYING
    changed = {stage for stage in keys if level_named(stage).key(other) != keys[stage]}
    assert changed == {"spikes", "rates", "results"}
    # Named at its default, the field is still left out: the key is that of the scene.
    named = other.replace(**{"readout.encoder": "lcs"})
    assert {stage: level_named(stage).key(named) for stage in keys} == keys


def test_a_new_field_not_declared_neutral_changes_the_keys_that_read_it():
    scene, keys = EARLIER_KEYS["paper"]
    extended = SceneWithKeyedEncoder.from_dict(scene.to_dict())
    changed = {stage for stage in keys if level_named(stage).key(extended) != keys[stage]}
    assert changed == {"spikes", "rates", "results"}


# Which levels read each scene part, stated independently of the registry.
READ_BY = {
    "dataset": {"recordings", "front_end", "spikes", "rates", "results"},
    "array": {"spikes", "rates", "results"},
    "readout": {"spikes", "rates", "results"},
    "coding": {"rates", "results"},
    "training": {"results"},
    "name": set(),
}
FIELDS = {
    "dataset.duration_s": st.floats(0.5, 20.0),
    "dataset.seed": st.integers(0, 2**40),
    "array.rows": st.integers(1, 8),
    "array.pitch_mm": st.floats(0.1, 5.0),
    "readout.threshold_v": st.floats(0.01, 0.5),
    "readout.full_scale_v": st.floats(0.6, 5.0),
    "coding.window_s": st.floats(0.01, 1.0),
    "coding.polarity": st.sampled_from(["merged", "split"]),
    "training.epochs": st.integers(1, 500),
    "training.seed": st.integers(0, 2**40),
    "seed": st.integers(0, 2**40),
    "name": st.text(min_size=1, max_size=8),
}


def _readers(scene: Scene, field: str) -> set[str]:
    """The levels whose key must change with ``field``."""
    if field == "seed":  # the scene seed only seeds random readout effects
        return {"spikes", "rates", "results"} if scene.readout.is_random else set()
    if field == "readout.full_scale_v":  # the front end scales to the full scale
        return READ_BY["readout"] | {"front_end"}
    return READ_BY[field.split(".")[0]]


@settings(max_examples=60, deadline=None)
@given(
    base=st.sampled_from([SMOKE, NOISY, SATURATING]),
    field_and_value=st.sampled_from(sorted(FIELDS)).flatmap(
        lambda field: st.tuples(st.just(field), FIELDS[field])
    ),
)
def test_a_key_changes_exactly_when_a_field_its_level_reads_changes(base, field_and_value):
    field, value = field_and_value
    assume(fields.get(base.to_dict(), field) != value)
    changed = base.replace(**{field: value})
    differs = {level.name for level in LEVELS if level.key(changed) != level.key(base)}
    assert differs == _readers(base, field)


def test_a_compute_function_takes_only_what_its_level_declares():
    for level in LEVELS:
        parameters = inspect.signature(level.compute).parameters
        declared = {b.name for b in level.after} | {r.argument for r in level.reads} | {"watch"}
        assert set(parameters) == declared, level.name
        assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in parameters.values())


def test_the_seed_is_passed_only_when_a_random_effect_is_named():
    seed = next(read for read in SPIKES.reads if read.path == "seed")
    assert seed.value(SMOKE.replace(seed=3)) is None
    assert seed.value(NOISY) == 5
    assert "seed" not in SPIKES.key_parts(SATURATING)


def test_spike_steps_are_those_of_the_levels_up_to_the_spike_trains():
    assert steps_through("spikes") == (
        "load",
        "front_end",
        "setup",
        "taxels",
        "readout",
        "metrics",
    )
    with pytest.raises(ValueError, match="models"):
        steps_through("results")


def test_stage_names_follow_the_registry_and_the_models():
    scene = SMOKE.replace(**{"training.models": ["cnn"]})
    assert stage_names(scene) == (
        "load",
        "front_end",
        "setup",
        "taxels",
        "readout",
        "metrics",
        "coding",
        "train_cnn",
    )


def test_run_scene_times_exactly_the_stage_names():
    scene = SMOKE.replace(
        **{
            "dataset.recordings_per_class": 2,
            "dataset.duration_s": 1.0,
            "training.epochs": 1,
            "training.folds": 2,
        }
    )
    started = []
    result = run_scene(scene, on_stage=started.append)
    assert tuple(result.timings_s) == stage_names(scene) == tuple(started)
    assert set(result.accuracy) == set(scene.training.models)


def test_a_level_that_times_an_undeclared_step_fails():
    def compute(*, dataset, watch):
        with watch.stage("elsewhere"):
            return dataset

    level = Level("odd", (Read("dataset"),), (), compute, ("load",))
    with pytest.raises(RuntimeError, match="elsewhere"):
        level.run(SMOKE, {}, Stopwatch(None))


def test_the_registry_refuses_a_level_before_its_inputs():
    with pytest.raises(ValueError, match="runs after 'recordings'"):
        _checked(FRONT_END, RECORDINGS)


def test_shared_steps_are_declared_on_the_levels():
    from pipeline.run.records import Charge
    from pipeline.run.stages import shared_steps, step_charge

    assert shared_steps() == {"load", "front_end", "setup"}
    assert step_charge("readout") is Charge.OWN and step_charge("setup") is Charge.SHARED
    bad = Level("odd", (Read("dataset"),), (), None, ("load2",), shared=("load3",))
    with pytest.raises(ValueError, match="shared steps"):
        _checked(bad)
