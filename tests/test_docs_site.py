"""The documentation site builds with no warning, and its reference is the code's declarations.

The site is built once for the module, as ``make docs`` builds it (warnings are errors, the
tutorial notebook executes), into a temporary folder; the tests then read the built pages back.
"""

from __future__ import annotations

import functools
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
    from flows.cli_parser import build_parser

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


class _Resources(html.parser.HTMLParser):
    """What a page loads and links to, and whether it holds typeset math (an element of
    class ``math``). ``found``: ``(tag, value, loads)`` for every ``src`` and ``href``, where
    ``loads`` tells a resource the browser fetches with the page (a script, a style sheet, an
    image, a preloaded font) from a link to follow."""

    def __init__(self) -> None:
        super().__init__()
        self.found: list[tuple[str, str, bool]] = []
        self.math = False

    def handle_starttag(self, tag, attrs):
        values = dict(attrs)
        self.math |= "math" in (values.get("class") or "").split()
        if values.get("src"):
            self.found.append((tag, values["src"], True))
        if values.get("href"):
            rel = set((values.get("rel") or "").split())
            fetched = {"stylesheet", "preload", "modulepreload", "icon", "manifest"}
            self.found.append((tag, values["href"], tag == "link" and bool(rel & fetched)))


@functools.cache  # three tests read every page; a built page does not change
def resources(page: Path) -> _Resources:
    parser = _Resources()
    parser.feed(page.read_text())
    return parser


def pages(site: Path) -> list[Path]:
    """The site's pages (not the theme's templates that ship in ``_static``)."""
    found = sorted(p for p in site.rglob("*.html") if "_static" not in p.relative_to(site).parts)
    assert len(found) > 50
    return found


def test_no_page_loads_a_script_style_or_font_from_the_network(site):
    """The site works offline: every script, style sheet, image and font a page loads is a
    file of the site, and so is every ``url()`` of its style sheets."""
    remote = re.compile(r"^(https?:)?//", re.I)
    loaded = [
        f"{page.relative_to(site)}: <{tag}> {value}"
        for page in pages(site)
        for tag, value, loads in resources(page).found
        if loads and remote.match(value)
    ]
    for sheet in site.rglob("*.css"):
        for url in re.findall(r"url\(\s*['\"]?([^'\")]+)", sheet.read_text(errors="replace")):
            if remote.match(url):
                loaded.append(f"{sheet.relative_to(site)}: url({url})")
    assert not loaded, loaded


def test_math_is_typeset_by_the_mathjax_the_site_serves(site):
    """Every page with math loads MathJax by a relative path to the copy in ``_static``, and
    that copy holds what it loads next: the TeX extensions and the fonts."""
    mathjax = site / "_static" / "mathjax"
    with_math = []
    for page in pages(site):
        found = resources(page)
        if not found.math:
            continue
        with_math.append(page.relative_to(site).as_posix())
        scripts = [value for tag, value, _ in found.found if tag == "script" and "mathjax" in value]
        assert len(scripts) == 1, (page, scripts)
        path = (page.parent / scripts[0].split("?")[0]).resolve()
        assert path == (mathjax / "tex-chtml.js").resolve(), (page, scripts)
    assert {"model.html", "reference/generated/pipeline.chain.readout.html"} <= set(with_math)
    assert (mathjax / "tex-chtml.js").stat().st_size > 500_000
    assert (
        mathjax / "output" / "chtml" / "fonts" / "woff-v2" / "MathJax_Main-Regular.woff"
    ).is_file()
    assert (mathjax / "input" / "tex" / "extensions" / "ams.js").is_file()
    assert (mathjax / "LICENSE").is_file()


def test_no_page_points_outside_the_project(site):
    """Readers have this project, not the folders around it: no page names ``../shared`` or a
    folder of the machine that built it, and every relative link and resource of a page is a
    file of the site."""
    # The building machine's folder as a whole path: "/work" must not match "flows/work.html".
    outside = [rf"(?<![\w./-]){re.escape(str(ROOT.parent))}(?![\w.-])", re.escape("../shared")]
    found = []
    for page in pages(site):
        text = page.read_text()
        found += [
            f"{page.relative_to(site)}: {m.group()}" for p in outside if (m := re.search(p, text))
        ]
        for tag, value, _ in resources(page).found:
            if re.match(r"^([a-z][a-z0-9+.-]*:|#)", value, re.I):
                continue  # a URL, mailto: or a place on the same page
            target = (page.parent / value.split("#")[0].split("?")[0]).resolve()
            if not target.is_relative_to(site.resolve()) or not target.exists():
                found.append(f"{page.relative_to(site)}: <{tag}> {value}")
    assert not found, found


def test_the_readme_is_a_front_door_whose_links_all_lead_somewhere():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) < 150
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", readme)
    assert "docs/index.md" in targets and "docs/reference/scene-fields.md" in targets
    missing = [target for target in targets if not (ROOT / target).exists()]
    assert not missing, missing
