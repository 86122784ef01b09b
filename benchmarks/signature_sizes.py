"""Sizes of the package's signatures (issue 33: settings objects instead of 15-25 keyword signatures).

    python benchmarks/signature_sizes.py            # with PYTHONPATH=<tree>/src

Prints the parameters of each public engine function as :func:`inspect.signature` gives them (``*args`` and
``**keywords`` count one each; ``study``'s signature is built by a decorator, which the source does not show),
then, read from the source with :mod:`ast`, the functions of ``src/drillstring`` with more than 8 parameters.
"""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "drillstring"
LIMIT = 8


def parameter_count(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Parameters of a function definition, ``self``/``cls`` included, ``*args``/``**kw`` one each."""
    a = node.args
    return (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + (a.vararg is not None)
            + (a.kwarg is not None))


def wide_functions(root: Path = PACKAGE, limit: int = LIMIT) -> list[tuple[str, int]]:
    """``("module.py:function", parameters)`` of every function with more than ``limit`` parameters."""
    found = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and parameter_count(node) > limit:
                found.append((f"{path.relative_to(root)}:{node.name}", parameter_count(node)))
    return found


def public_sizes() -> dict[str, int]:
    import drillstring

    return {name: len(inspect.signature(getattr(drillstring, name)).parameters)
            for name in ("monte_carlo_study", "study", "operating_map", "sensitivity", "optimize")}


if __name__ == "__main__":
    for name, count in public_sizes().items():
        print(f"{name:20s} {count:3d} parameters")
    wide = wide_functions()
    print(f"functions with more than {LIMIT} parameters: {len(wide)}")
    for where, count in sorted(wide, key=lambda item: -item[1]):
        print(f"  {count:3d}  {where}")
