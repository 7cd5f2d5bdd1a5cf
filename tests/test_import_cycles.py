"""No import cycles among the project's modules, function-local imports included.

A module-level cycle breaks imports outright; one hidden in a function-local import works but
ties two modules into one (neither can be read, tested or moved without the other). Imports
under ``if TYPE_CHECKING:`` never run and are left out.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("pipeline", "storage", "flows")


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def project_modules() -> dict[str, Path]:
    return {
        module_name(path): path for package in PACKAGES for path in (ROOT / package).rglob("*.py")
    }


def is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def imports(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement of ``tree`` at any depth, but those under TYPE_CHECKING."""
    found = []
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and is_type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            found.append(node)
        stack.extend(ast.iter_child_nodes(node))
    return found


def graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the project modules it imports (a package means its ``__init__``)."""
    edges: dict[str, set[str]] = {}
    for name, path in modules.items():
        targets = set()
        for node in imports(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                candidates = [alias.name for alias in node.names]
            elif node.level:
                raise AssertionError(f"{name}: relative import (line {node.lineno})")
            else:
                base = node.module or ""
                candidates = [
                    f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                    for a in node.names
                ]
            for candidate in candidates:
                # ``import pipeline.run.stages`` imports ``pipeline`` too; only the module counts.
                while candidate and candidate not in modules:
                    candidate = candidate.rpartition(".")[0]
                if candidate and candidate != name:
                    targets.add(candidate)
        edges[name] = targets
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """One cycle through each strongly connected group of modules (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(edges.get(node, ())):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return sorted(groups)


def test_no_import_cycles():
    found = cycles(graph(project_modules()))
    assert found == [], "import cycles among: " + "; ".join(" <-> ".join(g) for g in found)


@pytest.mark.parametrize(
    ("edges", "expected"),
    [
        ({"a": {"b"}, "b": {"a"}}, [["a", "b"]]),
        ({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}, [["a", "b", "c"]]),
        ({"a": {"b"}, "b": {"c"}, "c": set()}, []),
    ],
)
def test_cycles_are_found(edges, expected):
    assert cycles(edges) == expected


def test_function_local_imports_count_and_type_checking_ones_do_not(tmp_path):
    source = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from pipeline.b import X\n"
        "def f():\n    from pipeline.c import y\n    return y\n"
    )
    found = {node.module for node in imports(ast.parse(source)) if isinstance(node, ast.ImportFrom)}
    assert found == {"typing", "pipeline.c"}


def test_the_walk_reaches_every_sub_package():
    names = project_modules().keys()
    assert {
        "pipeline.design.scene",
        "pipeline.design.scenes",
        "pipeline.recordings.sources",
    } <= names
    assert {"pipeline.chain.readout", "pipeline.run.stages", "pipeline.results.cube"} <= names
    assert {"pipeline.report.analysis", "storage.store", "flows.planning"} <= names


def test_storage_knows_no_science_and_pipeline_no_orchestration():
    """storage/ imports nothing of pipeline/ but its error base; pipeline/ imports nothing of
    storage/ or flows/."""
    edges = graph(project_modules())
    crossings = sorted(
        f"{source} -> {target}"
        for source, targets in edges.items()
        for target in targets
        if (source.startswith("storage") and target.startswith("pipeline"))
        or (source.startswith("pipeline") and target.startswith(("storage", "flows")))
    )
    assert crossings == ["storage.errors -> pipeline.errors"]
