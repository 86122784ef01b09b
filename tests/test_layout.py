"""The package's layout (docs/extending.md, "Where things live"): the pipeline's stages import only the stages
above them, no two modules import each other (directly or round a circle, lazy imports included), and no module
grows past 800 lines.

The import graph is read from the sources with :mod:`ast` (every ``import`` and ``from … import`` of a package
module, at any depth of the file), so the checks see lazy imports too. The few known exceptions are listed by
name below, each to be removed when its module is split; a new violation fails.
"""

from __future__ import annotations

import ast
from pathlib import Path

import drillstring

PACKAGE = Path(drillstring.__file__).resolve().parent
MAX_LINES = 800

#: Modules still over MAX_LINES (each to be split; none may be added).
KNOWN_LONG: set[str] = set()
#: Import circles still there, as sets of modules (none may be added).
KNOWN_CIRCLES: list[set[str]] = []
#: Circles between stages (a subpackage or a top-level module), e.g. fem -> case -> well -> fem.
KNOWN_STAGE_CIRCLES: list[set[str]] = []

#: The output and interface layers: figures, reports, the API's recipes and the command line. Nothing of the
#: physics or the statistics imports them.
OUTER = ("drillstring.plots", "drillstring.outputs", "drillstring.report", "drillstring.interactive", "drillstring.api",
         "drillstring.operating_point", "drillstring.cli")
#: The physics and statistics stages (the pipeline's inner layers).
INNER = ("drillstring.case", "drillstring.units", "drillstring.fem", "drillstring.well", "drillstring.statics",
         "drillstring.modal", "drillstring.forces", "drillstring.dynamics", "drillstring.stochastic",
         "drillstring.buckling", "drillstring.damping", "drillstring.rotor", "drillstring.critical_speeds",
         "drillstring.results")


def _modules() -> dict[str, Path]:
    modules = {}
    for path in PACKAGE.rglob("*.py"):
        parts = ("drillstring",) + path.relative_to(PACKAGE).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The package modules that ``name`` imports anywhere in its source."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            targets = [module] + [f"{module}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        else:
            continue
        found.update(t for t in targets if t in modules and t != name)
    return found


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def _circles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles = []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = set()
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.add(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        circles.append(component)
    return circles


def _stage(name: str) -> str:
    return ".".join(name.split(".")[:2])


def _stage_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    stages: dict[str, set[str]] = {}
    for module, targets in graph.items():
        stages.setdefault(_stage(module), set()).update(_stage(t) for t in targets if _stage(t) != _stage(module))
    for targets in list(stages.values()):
        for target in targets:
            stages.setdefault(target, set())
    return stages


def _within(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def test_circles_are_found():
    """The circle finder itself, on a small graph: a -> b -> c -> a is one circle, d alone is none."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set()}
    assert _circles(graph) == [{"a", "b", "c"}]


def test_no_new_import_circle():
    circles = _circles(_graph())
    new = [sorted(c) for c in circles if c not in KNOWN_CIRCLES]
    assert not new, f"modules that import each other: {new}"


def test_known_circles_still_exist():
    """A known exception that is gone must leave the list (the list only shrinks)."""
    circles = _circles(_graph())
    assert all(c in circles for c in KNOWN_CIRCLES), "remove the resolved circle from KNOWN_CIRCLES"


def test_no_new_circle_between_stages():
    circles = _circles(_stage_graph(_graph()))
    new = [sorted(c) for c in circles if c not in KNOWN_STAGE_CIRCLES]
    assert not new, f"stages that import each other: {new}"
    assert all(c in circles for c in KNOWN_STAGE_CIRCLES), "remove the resolved circle from KNOWN_STAGE_CIRCLES"


def test_physics_never_imports_outputs_or_interface():
    graph = _graph()
    up = sorted(f"{m} -> {t}" for m, targets in graph.items() if _within(m, INNER)
                for t in targets if _within(t, OUTER))
    assert not up, f"imports running up the layers: {up}"


def test_module_length():
    lengths = {name: path.read_text(encoding="utf-8").count("\n") for name, path in _modules().items()}
    long = {name for name, n in lengths.items() if n > MAX_LINES}
    assert not long - KNOWN_LONG, f"over {MAX_LINES} lines: {sorted((n, lengths[n]) for n in long - KNOWN_LONG)}"
    assert not KNOWN_LONG - long, f"now at most {MAX_LINES} lines, remove from KNOWN_LONG: {sorted(KNOWN_LONG - long)}"
