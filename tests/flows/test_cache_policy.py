"""The cache policy of the stored levels (:attr:`pipeline.run.stages.Level.kept`): a chip
scene's spike entry is not kept (its result is); a later task computes the trains again and
gets the same result."""

import pytest

import flows.work as work
from flows.scheduling import point_keys
from flows.work import ensure_entries
from pipeline.design.scene import Scene
from pipeline.run import stages
from pipeline.run.records import StepSeconds
from storage import SweepStore

ONE = Scene.builtin("smoke").replace(
    **{
        "training.models": ["ffnn"],
        "training.epochs": 1,
        "training.folds": 2,
        "dataset.recordings_per_class": 2,
        "readout.effects": {"threshold_mismatch": {"sigma_rel": 0.2}},
    }
)
CHIPS = ONE.replace(**{"chips.count": 3, "chips.deployment": "shared"})


def test_spike_entries_are_kept_unless_they_hold_chip_trains(monkeypatch, tmp_path):
    monkeypatch.setattr(work, "_kept", {})
    root = str(SweepStore.open_or_create(tmp_path / "run").root)
    points = [(scene, point_keys(scene)) for scene in (ONE, CHIPS)]
    ensure_entries(root, "results", points)
    store = SweepStore.open(root)
    spikes = store.complete_keys(stages.SPIKES.record)
    assert spikes == {point_keys(ONE)["spikes"]}  # the chip scene's trains are not kept
    results = store.complete_keys(stages.RESULTS.record)
    assert results == {keys["results"] for _, keys in points}
    first = store.read_many(stages.RESULTS.record, results, discard_corrupt=False)
    # A task that needs the chip scene's trains again computes them: the same chip accuracy.
    monkeypatch.setattr(work, "_kept", {})
    again = point_keys(CHIPS)
    store.discard(stages.RESULTS.record, again["results"])
    ensure_entries(root, "results", [(CHIPS, again)])
    second = SweepStore.open(root).read_valid(stages.RESULTS.record, again["results"])
    assert second.chips is not None and second.chips.n_chips == 3
    before = first[again["results"]].chips.fold_accuracy["ffnn"]
    assert second.chips.fold_accuracy["ffnn"].tobytes() == before.tobytes()


@pytest.mark.parametrize(("scene", "kept"), [(ONE, True), (CHIPS, False)])
def test_the_spike_level_declares_its_policy_on_the_entry(scene, kept):
    watch = stages.Stopwatch(None)
    outputs: dict = {}
    for level in (stages.RECORDINGS, stages.FRONT_END, stages.SPIKES):
        outputs[level.name] = level.run(scene, outputs, watch)
    entry = stages.SPIKES.record.make(outputs["spikes"], StepSeconds({}, {}, "0" * 32), outputs.get)
    assert stages.SPIKES.kept(entry) is kept
    assert stages.RESULTS.kept(object()) is True
