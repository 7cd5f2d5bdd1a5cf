"""The report folder on disk: written whole, replacing an old report but never a user's folder."""

import pytest

from storage import StoreError, replace_folder
from storage.report import MARKER, check_report_folder, write_report_folder

FILES = {"report.md": b"# r\n", "report.html": b"<p>r</p>", "figures/a.png": b"\x89PNG"}


def test_the_folder_holds_the_files_and_the_marker(tmp_path):
    out = write_report_folder(tmp_path / "deep" / "out", FILES)
    assert out == tmp_path / "deep" / "out"
    assert {str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()} == {*FILES, MARKER}
    assert (out / "figures" / "a.png").read_bytes() == b"\x89PNG"
    assert [p.name for p in (tmp_path / "deep").iterdir()] == ["out"]  # no partial left behind


def test_a_report_replaces_an_old_report_but_never_a_users_folder(tmp_path):
    out = tmp_path / "out"
    write_report_folder(out, FILES)
    (out / "stale.txt").write_text("old")
    write_report_folder(out, {"report.md": b"new"})
    assert not (out / "stale.txt").exists() and (out / MARKER).is_file()
    assert (out / "report.md").read_bytes() == b"new" and not (out / "figures").exists()
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    with pytest.raises(StoreError, match="not a report"):
        write_report_folder(mine, FILES)
    assert [p.name for p in mine.iterdir()] == ["thesis.tex"]
    (tmp_path / "file").write_text("x")
    with pytest.raises(StoreError, match="not a directory"):
        write_report_folder(tmp_path / "file", FILES)
    (tmp_path / "link").symlink_to(out)
    with pytest.raises(StoreError, match="not a directory"):
        check_report_folder(tmp_path / "link")
    check_report_folder(tmp_path / "empty")  # missing: fine
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "link", "mine", "out"]


@pytest.mark.parametrize("name", ["../escape", "/abs", MARKER, ""])
def test_file_names_stay_inside_the_folder(tmp_path, name):
    with pytest.raises(StoreError, match="bad file name"):
        write_report_folder(tmp_path / "out", {name: b"x"})
    assert list(tmp_path.iterdir()) == []


def test_replace_folder_swaps_a_folder_in_whole(tmp_path):
    final, new = tmp_path / "final", tmp_path / "new"
    final.mkdir()
    (final / "old").write_text("old")
    new.mkdir()
    (new / "fresh").write_text("fresh")
    replace_folder(new, final)
    assert [p.name for p in final.iterdir()] == ["fresh"] and not new.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["final"]
