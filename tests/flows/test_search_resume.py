"""A search begun before the default sampler became ``auto`` (its journal under the fingerprint of
its space with ``tpe``, every field of the base) is continued with ``tpe`` by the same space
file; other spaces stay refused."""

import dataclasses
import tomllib

import pytest

from flows.samplers import resolve_sampler
from flows.search import Search, resumed_space, run_optimize
from pipeline.design.fields import param, part
from pipeline.design.scene import ReadoutSpec, Scene
from pipeline.design.space import Sampler, Space
from storage import StoreError, SweepStore
from storage.search_log import SearchJournal
from tests.flows.test_optimize import SPACE, journal

PARAMS = {"readout.threshold_v": 0.05, "coding.window_s": 0.1, "array.rows": 1}


def space(**changes) -> Space:
    data = tomllib.loads(SPACE)  # names no sampler
    return Space.from_dict({**data, **changes})


@pytest.mark.slow
def test_a_search_begun_under_the_former_default_sampler_continues_with_it(
    client, tmp_path, capsys
):
    auto = space()
    assert auto.sampler is Sampler.AUTO and resolve_sampler(auto, 2) is Sampler.GP
    # The journal as a search of this space file wrote it before the default became auto:
    # under the fingerprint of the space with tpe, the base's every field.
    begun = auto.fingerprint(Sampler.TPE, every_field=True)
    assert begun not in (auto.fingerprint(), auto.fingerprint(every_field=True))
    root = SweepStore.open_or_create(tmp_path / "run").root
    old = SearchJournal.open(root, auto.name, begun)
    old.asked(0, PARAMS)
    old.told(0, [0.5, 100.0])
    before = journal(root)

    kinds = []
    summary = run_optimize(
        auto, root, budget=2, client=client, on_told=lambda s, _: kinds.append(s.proposer.kind)
    )
    assert (summary["trials"], summary["new_trials"]) == (2, 1)
    assert kinds == [Sampler.TPE]  # not auto's GP
    assert summary["sampler"] == "tpe"
    notes = [line for line in capsys.readouterr().err.splitlines() if "eskin: note" in line]
    assert len(notes) == 1
    assert "search-tiny.jsonl was begun with sampler 'tpe'" in notes[0]
    # The journal goes on under the fingerprint it was begun with; its first trial as it was.
    after = journal(root)
    assert after[: len(before)] == before and len(after) == len(before) + 2
    assert {record["space"] for record in after} == {begun}


@pytest.mark.parametrize("every_field", [False, True])
def test_only_the_former_default_of_the_same_space_is_resumed(tmp_path, every_field):
    auto = space()
    begun = auto.fingerprint(Sampler.TPE, every_field=every_field)
    SearchJournal.open(tmp_path, auto.name, begun).asked(0, PARAMS)
    resumed, fingerprint, note = resumed_space(space(sampler="auto"), tmp_path)  # the same
    assert (resumed.sampler, fingerprint) == (Sampler.TPE, begun) and note is not None
    search = Search(resumed, tmp_path, budget=2, fingerprint=fingerprint)
    assert search.proposer.kind is Sampler.TPE and search.journal.pending == [0]
    # Another sampler named, or another seed: another search, refused as before.
    for other in (space(sampler="gp"), space(sampler="random"), space(seed=4)):
        assert resumed_space(other, tmp_path) == (other, other.fingerprint(), None)
        with pytest.raises(StoreError, match="holds a search of another space named 'tiny'"):
            Search(other, tmp_path)
    # A search begun under auto goes on under auto, in the form its journal holds; a new one
    # starts in the canonical form.
    for root in (tmp_path / "auto", tmp_path / "new"):
        root.mkdir()
    held = auto.fingerprint(every_field=every_field)
    SearchJournal.open(tmp_path / "auto", auto.name, held).asked(0, PARAMS)
    assert resumed_space(auto, tmp_path / "auto") == (auto, held, None)
    assert resumed_space(auto, tmp_path / "new") == (auto, auto.fingerprint(), None)


@dataclasses.dataclass(frozen=True)
class ReadoutWithGain(ReadoutSpec):
    """The readout with a field added in this test alone, at a neutral default."""

    gain_db: float = param(0.0, "dB", "a test-only gain", neutral=True)


@dataclasses.dataclass(frozen=True)
class SceneWithGain(Scene):
    readout: ReadoutWithGain = part(ReadoutWithGain)


def test_a_scene_field_added_at_a_neutral_default_keeps_the_fingerprint():
    today = space()
    later = dataclasses.replace(today, base=SceneWithGain.from_dict(today.base.to_dict()))
    assert later.base.to_dict()["readout"]["gain_db"] == 0.0
    assert later.fingerprint() == today.fingerprint()
    # The form of older journals changed with it: those written from now on are safe.
    assert later.fingerprint(every_field=True) != today.fingerprint(every_field=True)


def test_a_search_begun_by_auto_keeps_its_sampler_when_a_larger_budget_extends_it(tmp_path):
    from flows.samplers import GP_MAX_TRIALS

    auto = space()
    large = GP_MAX_TRIALS + 100
    assert resolve_sampler(auto, 20) is Sampler.GP and resolve_sampler(auto, large) is Sampler.TPE
    root = SweepStore.open_or_create(tmp_path / "run").root
    first = Search(auto, root, budget=20)
    assert first.ask(1) == [0]
    assert first.journal.sampler == "gp"
    # Extended past auto's GP limit: the search goes on with the GP it began with.
    assert Search(auto, root, budget=large).proposer.kind is Sampler.GP
    # A new search of that budget: auto's choice for it.
    fresh = SweepStore.open_or_create(tmp_path / "fresh").root
    assert Search(auto, fresh, budget=large).proposer.kind is Sampler.TPE
