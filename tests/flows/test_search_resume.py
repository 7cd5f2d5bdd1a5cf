"""A search begun before the default sampler became ``auto`` (its journal under the fingerprint of
its space with ``tpe``) is continued with ``tpe`` by the same space file; other spaces stay
refused."""

import dataclasses
import tomllib

import pytest

from flows.samplers import resolve_sampler
from flows.search import Search, resumed_space, run_optimize
from pipeline.design.space import Sampler, Space
from storage import StoreError
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
    # What a search of this space file wrote before the default became auto: its journal holds
    # the fingerprint of the space with tpe.
    begun = dataclasses.replace(auto, sampler=Sampler.TPE)
    assert begun.fingerprint() == auto.fingerprint(Sampler.TPE) != auto.fingerprint()
    root = tmp_path / "run"
    run_optimize(begun, root, budget=1, client=client)
    before = journal(root)
    capsys.readouterr()

    kinds = []
    summary = run_optimize(
        auto, root, budget=2, client=client, on_batch=lambda s, _: kinds.append(s.proposer.kind)
    )
    assert (summary["trials"], summary["new_trials"]) == (2, 1)
    assert kinds == [Sampler.TPE]  # not auto's GP
    notes = [line for line in capsys.readouterr().err.splitlines() if "eskin: note" in line]
    assert len(notes) == 1
    assert "search-tiny.jsonl was begun with sampler 'tpe'" in notes[0]
    # The journal goes on under the fingerprint it was begun with; its first trial as it was.
    after = journal(root)
    assert after[: len(before)] == before
    assert {record["space"] for record in after} == {begun.fingerprint()}


def test_only_the_former_default_of_the_same_space_is_resumed(tmp_path):
    auto = space()
    SearchJournal.open(tmp_path, auto.name, auto.fingerprint(Sampler.TPE)).asked(0, PARAMS)
    resumed, note = resumed_space(space(sampler="auto"), tmp_path)  # auto named: the same
    assert resumed.sampler is Sampler.TPE and note is not None
    search = Search(resumed, tmp_path, budget=2)
    assert search.proposer.kind is Sampler.TPE and search.journal.pending == [0]
    # Another sampler named, or another seed: another search, refused as before.
    for other in (space(sampler="gp"), space(sampler="random"), space(seed=4)):
        assert resumed_space(other, tmp_path) == (other, None)
        with pytest.raises(StoreError, match="holds a search of another space named 'tiny'"):
            Search(other, tmp_path)
    # A search begun under auto goes on under auto, and a new one starts with it.
    for root in (tmp_path / "auto", tmp_path / "new"):
        root.mkdir()
    SearchJournal.open(tmp_path / "auto", auto.name, auto.fingerprint()).asked(0, PARAMS)
    assert resumed_space(auto, tmp_path / "auto") == (auto, None)
    assert resumed_space(auto, tmp_path / "new") == (auto, None)
