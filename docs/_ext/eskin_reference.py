"""Sphinx directives that write the reference from the code's single declarations.

Nothing here restates a field, a variable or a stage: each directive reads the declaration the
code itself uses (the scene schema, the cube's variables, the stage registry) at build time, so
the pages cannot drift from the code.

``.. eskin-scene-fields::``
    One table per scene part: every field of :func:`pipeline.design.scene.scene_fields` with its
    type, default, unit, accepted range and meaning.
``.. eskin-cube-variables::``
    Every name a result cube declares (:data:`pipeline.results.cube.CUBE_VARIABLES`, the spike
    metrics and :data:`pipeline.results.variables.RESULT_VALUES`) with its unit and meaning, as
    :func:`pipeline.results.cube.describe` gives them to the cube's attributes.
``.. eskin-reexports:: module``
    The names a module's ``__all__`` imports from elsewhere (``pipeline.readout.level_crossings``,
    the whole of :mod:`flows.api`), listed with a link to where each is defined: a name is
    documented once. A reference to such a public name resolves to that definition
    (:func:`resolve_public_name`).

A public name that autodoc lists without a docstring is a warning (:func:`warn_undocumented`).

``.. eskin-dataflow::``
    The data flow from recording to cube as an SVG figure, drawn from
    :data:`pipeline.run.stages.LEVELS`: each level, the scene parts it reads, the steps it times,
    and whether the sweep store keeps its output.
"""

from __future__ import annotations

import html
import importlib
import inspect
import json
from collections.abc import Iterable, Sequence

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

LOGGER = logging.getLogger(__name__)

#: Table classes the docs test reads back from the built pages.
FIELDS_CLASS = "eskin-scene-fields"
VARIABLES_CLASS = "eskin-cube-variables"


def _cell(content: nodes.Node | str, code: bool = False) -> nodes.entry:
    entry = nodes.entry()
    if isinstance(content, str):
        content = nodes.literal(text=content) if code and content else nodes.Text(content)
    entry += nodes.paragraph("", "", content)
    return entry


def _table(
    headers: Sequence[str], rows: Iterable[Sequence[nodes.entry]], widths: Sequence[int], cls: str
) -> nodes.table:
    """A docutils table of ``rows`` (each a sequence of entries) under ``headers``."""
    table = nodes.table(classes=[cls])
    group = nodes.tgroup(cols=len(headers))
    table += group
    for width in widths:
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    header_row = nodes.row()
    for header in headers:
        header_row += _cell(header)
    head += header_row
    group += head
    body = nodes.tbody()
    for cells in rows:
        row = nodes.row()
        row.extend(cells)
        body += row
    group += body
    return table


def _units(units: str) -> str:
    return "" if units == "1" else units


class SceneFields(SphinxDirective):
    """Every scene field, one table per top-level part, in declaration order."""

    def run(self) -> list[nodes.Node]:
        from pipeline.design.scene import scene_fields

        parts: dict[str, list] = {}
        for info in scene_fields():
            part = info.path.split(".", 1)[0] if "." in info.path else "scene"
            parts.setdefault(part, []).append(info)
        found: list[nodes.Node] = []
        for part, infos in parts.items():
            section = nodes.section(ids=[nodes.make_id(f"fields-{part}")])
            title = nodes.title()
            title += nodes.Text("Top level") if part == "scene" else nodes.literal(text=part)
            section += title
            rows = (
                [
                    _cell(info.path, code=True),
                    _cell(info.type, code=True),
                    _cell("" if info.default is None else json.dumps(info.default), code=True),
                    _cell(_units(info.units)),
                    _cell(info.range),
                    _cell(info.description),
                ]
                for info in infos
            )
            section += _table(
                ("field", "type", "default", "unit", "range", "meaning"),
                rows,
                (24, 10, 10, 6, 14, 36),
                FIELDS_CLASS,
            )
            found.append(section)
        return found


class CubeVariables(SphinxDirective):
    """Every declared cube variable and coordinate with its unit and meaning."""

    def run(self) -> list[nodes.Node]:
        from pipeline.results.cube import declared_names, describe

        rows = []
        for name in declared_names():
            attrs = describe(name)
            rows.append(
                [_cell(name, code=True), _cell(_units(attrs["units"])), _cell(attrs["long_name"])]
            )
        return [_table(("name", "unit", "meaning"), rows, (24, 10, 66), VARIABLES_CLASS)]


#: Layout of the data-flow figure (top to bottom), in SVG user units: boxes, the gap between
#: two, the left margin, the room on the right for the arcs of outputs that skip a level.
_BOX_W, _BOX_H, _GAP, _MARGIN, _ARCS = 560, 62, 30, 10, 120


def _box(y: float, title: str, lines: Sequence[str], stored: bool) -> str:
    fill = "#e8f1fb" if stored else "#f4f4f4"
    stroke = "#2f6db5" if stored else "#777"
    out = [
        f'<rect x="{_MARGIN}" y="{y}" width="{_BOX_W}" height="{_BOX_H}" rx="8" '
        f'fill="{fill}" stroke="{stroke}" stroke-width="1.5"/>',
        f'<text x="{_MARGIN + 14}" y="{y + 22}" font-weight="bold" font-size="16">'
        f"{html.escape(title)}</text>",
    ]
    for i, line in enumerate(lines):
        out.append(
            f'<text x="{_MARGIN + 150}" y="{y + 22 + 19 * i}" font-size="14">'
            f"{html.escape(line)}</text>"
        )
    return "\n".join(out)


def _arrow(y1: float, y2: float) -> str:
    x = _MARGIN + 60
    return (
        f'<line x1="{x}" y1="{y1}" x2="{x}" y2="{y2}" stroke="#444" stroke-width="1.5" '
        f'marker-end="url(#arrow)"/>'
    )


def dataflow_svg() -> str:
    """The data flow of :data:`pipeline.run.stages.LEVELS`, then the cube, as one SVG document."""
    from pipeline.run.stages import LEVELS

    y_of = {level.name: i * (_BOX_H + _GAP) + _GAP / 2 for i, level in enumerate(LEVELS)}
    cube_y = len(LEVELS) * (_BOX_H + _GAP) + _GAP / 2
    width = _MARGIN * 2 + _BOX_W + _ARCS
    height = cube_y + _BOX_H + 56
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width} {height}" '
        f'role="img" font-family="sans-serif">',
        "<title>Data flow from recording to result cube</title>",
        '<defs><marker id="arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#444"/></marker></defs>',
    ]
    for level in LEVELS:
        y = y_of[level.name]
        reads = ", ".join(r.path + ("*" if r.when is not None else "") for r in level.reads)
        steps = ", ".join(step.replace("{model}", "<model>") for step in level.steps)
        kept = "kept in the Zarr store" if level.stored else "kept in a worker's memory"
        lines = [f"reads {reads}", f"times {steps}; {kept}"]
        parts.append(_box(y, level.name, lines, level.stored))
        for before in level.after:
            start = y_of[before.name] + _BOX_H
            if y - start == _GAP:  # the level before: a straight arrow
                parts.append(_arrow(start, y))
            else:  # a level further back: an arc on the right of the boxes between
                x, mid = _MARGIN + _BOX_W, (start + y) / 2
                out = _ARCS * min(1.0, (y - start) / (3 * (_BOX_H + _GAP)))
                parts.append(
                    f'<path d="M{x},{start - _BOX_H / 2} C{x + out},{start - _BOX_H / 2} '
                    f"{x + out},{mid} {x + out},{mid} S{x + out},{y + _BOX_H / 2} "
                    f'{x},{y + _BOX_H / 2}" fill="none" stroke="#444" stroke-width="1.2" '
                    f'stroke-dasharray="5,3" marker-end="url(#arrow)"/>'
                )
    parts.append(_arrow(y_of[LEVELS[-1].name] + _BOX_H, cube_y))
    cube_lines = [
        "one xarray Dataset per sweep, kept in the Zarr store;",
        "dims: swept axes, model, repeat, fold, recording",
    ]
    parts.append(_box(cube_y, "result cube", cube_lines, stored=True))
    legend = (
        "Solid arrows: the output of the level before; dashed: of a level further back.",
        "Blue: kept by the sweep store, keyed by the scene parts read up to that level.",
        "*: read only where the scene needs it (the seed, by a random effect).",
    )
    for i, line in enumerate(legend):
        y_line = cube_y + _BOX_H + 18 + 15 * i
        parts.append(f'<text x="{_MARGIN}" y="{y_line}" font-size="12" fill="#333">{line}</text>')
    parts.append("</svg>")
    return "\n".join(parts)


class DataFlow(SphinxDirective):
    """The data-flow figure, inline SVG (no image file to go stale)."""

    def run(self) -> list[nodes.Node]:
        figure = nodes.raw("", dataflow_svg(), format="html")
        return [nodes.container("", figure, classes=["eskin-dataflow"])]


def definition_of(dotted: str) -> object | None:
    """The object a dotted public name such as ``pipeline.readout.level_crossings`` refers to, or
    None where no importable module holds it."""
    parts = dotted.split(".")
    for split in range(len(parts) - 1, 0, -1):
        try:
            found = importlib.import_module(".".join(parts[:split]))
        except ImportError:
            continue
        for attribute in parts[split:]:
            found = getattr(found, attribute, None)
            if found is None:
                return None
        return found
    return None


def defined_name(obj: object) -> str | None:
    """``module.qualname`` where ``obj`` is defined, for functions and classes; None otherwise."""
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    return f"{module}.{qualname}" if module and qualname else None


class ReExports(SphinxDirective):
    """A list of the names ``__all__`` imports from elsewhere, each linking to its definition."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        module_name = self.arguments[0]
        module = importlib.import_module(module_name)
        items: list[str] = []
        for name in getattr(module, "__all__", ()):
            origin = defined_name(getattr(module, name))
            if origin is None or origin.rsplit(".", 1)[0] == module_name:
                continue
            role = "class" if inspect.isclass(getattr(module, name)) else "func"
            items.append(f"* ``{name}``: :py:{role}:`{origin}`")
        if not items:
            return []
        return [nodes.rubric(text="Re-exported names"), *self.parse_text_to_nodes("\n".join(items))]


def resolve_public_name(app: Sphinx, env, node, contnode):
    """Resolve a reference to a re-exported public name (``storage.open_results``,
    ``pipeline.readout.level_crossings``) to the object's one documented definition."""
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"]
    candidates = [target]
    if node.get("py:module") and "." not in target:
        candidates.insert(0, f"{node['py:module']}.{target}")
    domain = env.get_domain("py")
    for candidate in candidates:
        origin = defined_name(definition_of(candidate)) if "." in candidate else None
        if origin and origin != candidate:
            return domain.resolve_xref(
                env, node["refdoc"], app.builder, node["reftype"], origin, node, contnode
            )
    return None


def command_line_parser():
    """``eskin``'s parser (:func:`flows.cli_parser.build_parser`) for the command-line page, its
    commands' epilogs left out: they list the scene fields, which have a page of their own."""
    import argparse

    from flows.cli_parser import build_parser

    parser = build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for command in action.choices.values():
                command.epilog = None
    return parser


def warn_undocumented(app: Sphinx, what: str, name: str, obj: object, options, lines) -> None:
    """A public name the API reference lists without a docstring is a warning (an error under
    ``-W``): the reference is generated from docstrings, so a missing one is a hole in it."""
    if not any(line.strip() for line in lines) and not name.rsplit(".", 1)[-1].startswith("_"):
        LOGGER.warning("%s %s has no docstring", what, name, type="eskin", subtype="undocumented")


def setup(app: Sphinx) -> dict[str, object]:
    app.connect("autodoc-process-docstring", warn_undocumented)
    app.connect("missing-reference", resolve_public_name)
    app.add_directive("eskin-scene-fields", SceneFields)
    app.add_directive("eskin-cube-variables", CubeVariables)
    app.add_directive("eskin-dataflow", DataFlow)
    app.add_directive("eskin-reexports", ReExports)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
