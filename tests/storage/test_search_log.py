"""The search journal: trials asked and told, replayed; torn lines skipped; other spaces refused."""

import pytest

from storage import StoreError
from storage.search_log import SearchJournal, journal_fingerprint


def test_a_journal_replays_what_was_asked_and_told(tmp_path):
    journal = SearchJournal.open(tmp_path, "design", "abc")
    journal.asked(0, {"readout.threshold_v": 0.05, "coding.window_s": 0.1})
    journal.asked(1, {"readout.threshold_v": 0.2, "coding.window_s": 0.2})
    journal.asked(2, {"readout.threshold_v": 0.1, "coding.window_s": 0.05})
    journal.told(0, [0.5, 120.0])
    journal.told_failed(2, "point 1234: out of memory")
    again = SearchJournal.open(tmp_path, "design", "abc")
    assert again.params == journal.params
    assert again.sampler is None  # not recorded
    assert again.values == {0: [0.5, 120.0]}
    assert again.failed == {2: "point 1234: out of memory"}
    assert again.pending == [1]


def test_a_torn_last_line_is_skipped(tmp_path):
    journal = SearchJournal.open(tmp_path, "design", "abc")
    journal.asked(0, {"array.rows": 2})
    journal.told(0, [0.5, 1.0])
    with open(journal.path, "a") as file:
        file.write('{"space": "abc", "trial": 1, "par')  # a kill mid-write
    again = SearchJournal.open(tmp_path, "design", "abc")
    assert again.params == {0: {"array.rows": 2}} and again.values == {0: [0.5, 1.0]}


def test_a_journal_of_another_space_is_refused(tmp_path):
    SearchJournal.open(tmp_path, "design", "abc").asked(0, {"array.rows": 2})
    with pytest.raises(StoreError, match="another space named 'design'"):
        SearchJournal.open(tmp_path, "design", "other")
    assert SearchJournal.open(tmp_path, "elsewhere", "other").params == {}


def test_a_journals_fingerprint_is_its_first_readable_lines(tmp_path):
    assert journal_fingerprint(tmp_path, "design") is None
    journal = SearchJournal.open(tmp_path, "design", "abc")
    journal.path.write_text('{"space": "abc", "tri\n[1, 2]\n')  # torn, then not a record
    assert journal_fingerprint(tmp_path, "design") is None
    journal.asked(0, {"array.rows": 2})
    assert journal_fingerprint(tmp_path, "design") == "abc"
    assert journal_fingerprint(tmp_path, "elsewhere") is None


def test_a_journal_keeps_the_sampler_that_asked_its_first_trial(tmp_path):
    journal = SearchJournal.open(tmp_path, "design", "abc")
    journal.asked(0, {"array.rows": 2}, sampler="gp")
    journal.asked(1, {"array.rows": 1}, sampler="tpe")
    assert journal.sampler == "gp"
    assert SearchJournal.open(tmp_path, "design", "abc").sampler == "gp"
