"""The README's examples are code: its TOML must load and its Python API session must run."""

import doctest
import re
import tomllib
from pathlib import Path

from pipeline.design.grid import Grid
from pipeline.design.scene import Scene

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()
TOML_BLOCKS = re.findall(r"```toml\n(.*?)```", README, flags=re.S)


def test_the_scene_example_is_the_paper_scene():
    scene_block = next(b for b in TOML_BLOCKS if "[training]" in b)
    scene = Scene.from_dict(tomllib.loads(scene_block))
    assert scene.canonical() == Scene.paper().canonical()


def test_the_grid_example_loads():
    grid_block = next(b for b in TOML_BLOCKS if "[sweeps." in b)
    grid = Grid.from_dict(tomllib.loads(grid_block))
    assert [s.name for s in grid.sweeps] == ["threshold", "mismatch_by_size", "noise"]
    assert grid.sweeps[1].shape == (3, 2)


def test_the_quick_start_has_exactly_the_two_commands():
    quick_start = README.split("## Quick start", 1)[1].split("##", 1)[0]
    commands = re.findall(r"^make \w+", quick_start, flags=re.M)
    assert commands == ["make run", "make test"]


def test_the_python_api_session_runs_as_shown(tmp_path, monkeypatch):
    section = README.split("\n## Python API\n", 1)[1].split("\n## ", 1)[0]
    session = "".join(re.findall(r"```pycon\n(.*?)```", section, flags=re.S))
    assert session.count(">>>") >= 10
    monkeypatch.chdir(tmp_path)  # the examples write runs/api relative to where they run
    test = doctest.DocTestParser().get_doctest(session, {}, "README Python API", "README.md", 0)
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    report: list[str] = []
    runner.run(test, out=report.append)
    assert runner.summarize(verbose=False).failed == 0, "".join(report)
    assert (tmp_path / "runs" / "api" / "report" / "report.html").is_file()


def test_the_space_example_is_the_example_space_file():
    from pipeline.design.space import Space, load_space

    block = next(b for b in TOML_BLOCKS if "[objectives]" in b)
    shown = Space.from_dict(tomllib.loads(block))
    example = load_space(Path(__file__).resolve().parents[1] / "examples" / "design_space.toml")
    assert shown.fingerprint() == example.fingerprint()
