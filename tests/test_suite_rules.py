"""The rules the suite runs by (tests/conftest.py, tests/shared_data.py) catch what they are for."""

import subprocess
import sys

import pytest

from tests import shared_data


def test_an_unmarked_test_that_starts_a_sweep_fails_before_it_starts(tmp_path):
    command = [sys.executable, "-m", "flows.cli", "sweep", "--grid", "smoke"]
    with pytest.raises(pytest.fail.Exception, match="mark it @pytest.mark.slow"):
        subprocess.Popen([*command, "--root", str(tmp_path / "run")])
    assert not (tmp_path / "run").exists()


def test_an_unmarked_test_that_starts_a_cluster_of_processes_fails():
    from distributed import LocalCluster

    with pytest.raises(pytest.fail.Exception, match="Dask cluster of worker processes"):
        LocalCluster(n_workers=1, dashboard_address=None)


def test_commands_that_start_nothing_are_not_end_to_end():
    proc = subprocess.run(
        [sys.executable, "-m", "flows.cli", "sweep", "--help"], capture_output=True, timeout=300
    )
    assert proc.returncode == 0


@pytest.mark.slow
def test_a_marked_test_may_start_a_sweep(tmp_path):
    command = [sys.executable, "-m", "flows.cli", "sweep", "--grid", "nonexistent-grid"]
    proc = subprocess.run([*command, "--root", str(tmp_path / "run")], capture_output=True)
    assert proc.returncode == 2


def test_a_missing_vibtac12_copy_skips_here_and_fails_under_ci(monkeypatch, tmp_path):
    monkeypatch.setattr(shared_data, "VIBTAC12", tmp_path / "absent")
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match="absent"):
        shared_data.vibtac12_copy()
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="CI always has ../shared"):
        shared_data.vibtac12_copy()


class _Item:
    """A collected test as :func:`tests.conftest.run_order` reads it."""

    def __init__(self, nodeid: str, slow: bool = False) -> None:
        self.nodeid, self.slow = nodeid, slow

    def get_closest_marker(self, name: str) -> object | None:
        return object() if name == "slow" and self.slow else None


def test_modules_run_whole_with_end_to_end_ones_first_most_first_and_small_ones_last():
    from tests.conftest import run_order

    items = [
        _Item("tests/a.py::quick"),
        _Item("tests/b.py::one", slow=True),
        _Item("tests/c.py::first"),
        _Item("tests/c.py::second"),
        _Item("tests/d.py::first", slow=True),
        _Item("tests/d.py::quick"),
        _Item("tests/d.py::second", slow=True),
        _Item("tests/e.py::quick"),
    ]
    assert [item.nodeid for item in run_order(items)] == [
        "tests/d.py::first",
        "tests/d.py::quick",
        "tests/d.py::second",
        "tests/b.py::one",
        "tests/c.py::first",
        "tests/c.py::second",
        "tests/a.py::quick",
        "tests/e.py::quick",
    ]
