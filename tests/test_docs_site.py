"""The documentation site builds with no warning, and its reference is the code's declarations.

The site is built once for the module, as ``make docs`` builds it (warnings are errors, the
tutorial notebook executes), into a temporary folder; the tests then read the built pages back.
"""

from __future__ import annotations

import html.parser
import importlib
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.flows.helpers import hermetic_env

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

pytestmark = pytest.mark.slow
#: ``make docs``'s build: any warning fails it; ``-E`` reads every page afresh.
SPHINX = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-E", "-b", "html"]


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The built site's folder (``index.html`` in it)."""
    base = tmp_path_factory.mktemp("docs")
    out = base / "html"
    proc = subprocess.run(
        [*SPHINX, "-d", str(base / "doctrees"), str(DOCS), str(out)],
        cwd=ROOT,
        env=hermetic_env(base, IPYTHONDIR=str(base / "ipython")),
        capture_output=True,
        text=True,
        timeout=1200,
    )
    # -W: any warning (a broken reference, an undocumented name, a failing cell) fails the build.
    assert proc.returncode == 0, proc.stderr[-5000:]
    return out


class _Tables(html.parser.HTMLParser):
    """Rows of the tables whose class attribute holds ``cls``: each row a list of cell texts."""

    def __init__(self, cls: str) -> None:
        super().__init__()
        self.cls, self.rows, self._depth, self._row, self._cell = cls, [], 0, None, None

    def handle_starttag(self, tag, attrs):
        classes = (dict(attrs).get("class") or "").split()
        if tag == "table" and (self._depth or self.cls in classes):
            self._depth += 1
        elif self._depth and tag == "tr":
            self._row = []
        elif self._depth and tag in ("td", "th") and self._row is not None:
            self._cell = []

    def handle_endtag(self, tag):
        if tag == "table" and self._depth:
            self._depth -= 1
        elif tag in ("td", "th") and self._cell is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.rows.append(self._row)
            self._row = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def table_rows(page: Path, cls: str) -> list[list[str]]:
    """Body rows of the tables of class ``cls`` on ``page`` (header rows left out)."""
    parser = _Tables(cls)
    parser.feed(page.read_text())
    return [row for row in parser.rows if row and row[0] not in ("field", "name")]


def test_the_scene_fields_page_lists_every_declared_field_as_declared(site):
    from pipeline.design.scene import scene_fields

    rows = table_rows(site / "reference" / "scene-fields.html", "eskin-scene-fields")
    declared = scene_fields()
    assert [row[0] for row in rows] == [info.path for info in declared]
    for row, info in zip(rows, declared, strict=True):
        assert row[1] == info.type
        assert row[3] == ("" if info.units == "1" else info.units), info.path
        assert row[4] == info.range and row[5] == info.description, info.path


def test_the_cube_variables_page_lists_every_declared_name_with_its_attributes(site):
    from pipeline.results.cube import declared_names, describe

    rows = table_rows(site / "reference" / "cube-variables.html", "eskin-cube-variables")
    assert [row[0] for row in rows] == list(declared_names())
    for name, units, meaning in rows:
        attrs = describe(name)
        assert (units or "1", meaning) == (attrs["units"], attrs["long_name"]), name


def test_every_name_of_a_built_cube_is_declared_for_the_reference():
    """The page is generated from the declarations; this checks the declarations cover every
    variable and coordinate a real cube holds (a swept axis is documented by its scene field, a
    table of fields such as ``readout.effects`` by its fields)."""
    from pipeline.design.scene import scene_fields
    from pipeline.results.cube import build_cube, declared_names
    from tests import golden_cubes as golden

    grid = golden.grid()
    records = golden.rich_entries(grid)
    fields = {info.path for info in scene_fields()}
    documented = set(declared_names()) | fields
    seen: set[str] = set()
    for sweep in grid.sweeps:
        cube = build_cube(grid, sweep, records)
        for name, variable in {**cube.data_vars, **cube.coords}.items():
            seen.add(name)
            swept = variable.attrs.get("field")
            table = any(field.startswith(f"{name}.") for field in fields)  # readout.effects
            assert name in documented or swept in fields or table, f"{sweep.name}: {name}"
    assert {"accuracy", "correlation_r", "predicted", "result_key"} <= seen


def test_the_command_line_page_lists_every_command_and_option(site):
    from flows.cli import build_parser

    page = (site / "reference" / "cli.html").read_text()
    parser = build_parser()
    commands = next(a for a in parser._actions if a.choices and isinstance(a.choices, dict))
    for name, command in commands.choices.items():
        assert f"eskin {name}" in page or f">{name}<" in page, name
        for action in command._actions:
            for option in action.option_strings:
                assert option in page, f"eskin {name} {option}"


def test_every_module_has_an_api_page(site):
    generated = site / "reference" / "generated"
    for package in ("pipeline", "storage", "flows"):
        module = importlib.import_module(package)
        names = [package] + [
            info.name for info in pkgutil.walk_packages(module.__path__, f"{package}.")
        ]
        missing = [name for name in names if not (generated / f"{name}.html").is_file()]
        assert not missing, missing


def test_the_tutorial_ran_and_shows_its_figure(site):
    """The build executes the notebook: its cells' outputs, the plot among them, are on the page."""
    page = (site / "tutorial.html").read_text()
    assert page.count('class="cell_output') >= 5
    assert "<img" in page, "the tutorial's plot is missing"
    assert "Traceback" not in page


def test_the_data_flow_figure_has_every_stage(site):
    from pipeline.run.stages import LEVELS

    page = (site / "model.html").read_text()
    figure = page.split("<svg", 1)[1].split("</svg>", 1)[0]
    for level in LEVELS:
        assert f">{level.name}</text>" in figure, level.name


def test_the_readme_is_a_front_door_whose_links_all_lead_somewhere():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) < 150
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", readme)
    assert "docs/index.md" in targets and "docs/reference/scene-fields.md" in targets
    missing = [target for target in targets if not (ROOT / target).exists()]
    assert not missing, missing
