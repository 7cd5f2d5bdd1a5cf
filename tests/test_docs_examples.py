"""The documentation's examples are code: its TOML files load and its Python session runs."""

import doctest
import re
import tomllib
from pathlib import Path

import pytest

from pipeline.design.grid import Grid
from pipeline.design.scene import Scene
from pipeline.design.space import Space, load_space

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if not {"_build", "jupyter_execute"} & set(p.parts))


def blocks(page: Path, language: str) -> list[str]:
    """The fenced code blocks of one language on a page, in order."""
    return re.findall(rf"```{language}\n(.*?)```", page.read_text(), flags=re.S)


def block_with(page: str, marker: str) -> str:
    """The one TOML block of a page that contains ``marker``."""
    [block] = [b for b in blocks(DOCS / page, "toml") if marker in b]
    return block


def load_toml_example(text: str) -> Scene | Grid | Space:
    """A TOML example as what it shows: a design space, a grid or a scene."""
    table = tomllib.loads(text)
    if "objectives" in table:
        return Space.from_dict(table)
    if "sweeps" in table:
        return Grid.from_dict(table)
    return Scene.from_dict(table)


def test_the_scene_example_is_the_paper_scene():
    scene = Scene.from_dict(tomllib.loads(block_with("scenes.md", "[training]")))
    assert scene.canonical() == Scene.paper().canonical()


def test_the_grid_example_loads():
    grid = Grid.from_dict(tomllib.loads(block_with("how-to/grid.md", "[sweeps.")))
    assert [s.name for s in grid.sweeps] == ["threshold", "mismatch_by_size", "noise"]
    assert grid.sweeps[1].shape == (3, 2)


def test_the_space_example_is_the_example_space_file():
    shown = Space.from_dict(tomllib.loads(block_with("how-to/search.md", "[objectives]")))
    example = load_space(ROOT / "examples" / "design_space.toml")
    assert shown.fingerprint() == example.fingerprint()


@pytest.mark.parametrize(
    ("page", "index"),
    [
        (page.relative_to(DOCS).as_posix(), i)
        for page in PAGES
        for i in range(len(blocks(page, "toml")))
    ],
)
def test_every_toml_example_loads(page, index):
    load_toml_example(blocks(DOCS / page, "toml")[index])


def test_the_python_api_session_runs_as_shown(tmp_path, monkeypatch):
    page = DOCS / "how-to" / "python.md"
    session = "".join(blocks(page, "pycon"))
    assert session.count(">>>") >= 10
    monkeypatch.chdir(tmp_path)  # the examples write runs/api relative to where they run
    test = doctest.DocTestParser().get_doctest(session, {}, "Python API", str(page), 0)
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    report: list[str] = []
    runner.run(test, out=report.append)
    assert runner.summarize(verbose=False).failed == 0, "".join(report)
    assert (tmp_path / "runs" / "api" / "report" / "report.html").is_file()
