"""The README's Python examples: safe to save as scripts, and the first one prints what the README shows."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks(language: str) -> list[tuple[int, str]]:
    """(offset, code) of every fenced block of ``language`` in the README."""
    text = README.read_text(encoding="utf-8")
    return [(m.start(), m.group(1)) for m in re.finditer(rf"```{language}\n(.*?)```", text, re.S)]


def _is_main_guard(node: ast.stmt) -> bool:
    return (isinstance(node, ast.If) and isinstance(node.test, ast.Compare)
            and isinstance(node.test.left, ast.Name) and node.test.left.id == "__name__"
            and isinstance(node.test.comparators[0], ast.Constant)
            and node.test.comparators[0].value == "__main__")


def test_python_examples_run_nothing_on_import():
    """Saved as a script and imported again by a spawned worker process, an example must do nothing but
    imports and definitions: everything that runs sits under ``if __name__ == "__main__":``."""
    blocks = _blocks("python")
    assert len(blocks) >= 2
    for _, code in blocks:
        body = ast.parse(code).body
        assert any(_is_main_guard(node) for node in body), code
        for node in body:
            assert isinstance(node, (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.ClassDef)) or \
                _is_main_guard(node), ast.unparse(node)


@pytest.mark.parametrize("index", [0, 1])  # the quick ones: statics and modes, buckling margin
def test_example_prints_what_the_readme_shows(tmp_path, index):
    offset, code = _blocks("python")[index]
    shown = next(text for start, text in _blocks("text") if start > offset)
    script = tmp_path / "example.py"
    script.write_text(code, encoding="utf-8")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == shown.split()


def test_first_case_of_ones_own_loads_and_is_not_buckled(tmp_path):
    """The README's "first case of your own" is a valid case file in field units whose three stabilizers keep the
    bottom-hole assembly straight at its 25 klbf (the tutorial shows one stabilizer is not enough)."""
    from drillstring.buckling import case_buckling_margin
    from drillstring.case import load_case

    (code,) = [code for _, code in _blocks("toml")]
    path = tmp_path / "my_case.toml"
    path.write_text(code, encoding="utf-8")
    case = load_case(path)
    assert len(case.stabilizers) == 3
    assert case.operation.weight_on_bit == pytest.approx(25e3 * 4.4482216152605)
    margin = case_buckling_margin(case)
    assert not margin.buckled and margin.critical_weight_on_bit > case.operation.weight_on_bit


def _slug(heading: str) -> str:
    """The anchor a Markdown renderer (and the docs site, MyST's GitHub-style slugs) gives a heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def test_relative_links_point_to_files_and_headings_that_exist():
    """Every relative link of the README leads to a file of the repository and, with a #fragment into a
    Markdown page, to one of its headings (the docs site checks its own pages' links when it is built)."""
    text = README.read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    assert len(links) > 20
    for link in links:
        if re.match(r"[a-z]+://", link):
            continue
        target, _, fragment = link.partition("#")
        path = README.parent / target
        assert path.exists(), link
        if fragment and path.suffix == ".md":
            headings = re.findall(r"^#+ (.*)$", path.read_text(encoding="utf-8"), re.M)
            assert fragment in {_slug(h) for h in headings}, link


def test_the_guide_shows_the_readme_examples_unchanged():
    """docs/guide/python-api.md repeats the README's two checked examples with their output: the same text,
    so that what the tests above run is what the site shows."""
    guide = (README.parent / "docs" / "guide" / "python-api.md").read_text(encoding="utf-8")
    for language in ("python", "text"):
        shown = [code for _, code in _blocks(language)][:2]
        in_guide = re.findall(rf"```{language}\n(.*?)```", guide, re.S)[:2]
        assert in_guide == shown


def test_readme_is_short_and_keeps_both_quick_start_commands():
    """At most 250 lines (the developers' guide), with the two commands a newcomer runs first."""
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 250
    quick_start = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = [code.strip() for code in re.findall(r"```bash\n(.*?)```", quick_start, re.S)]
    assert commands == [
        "python3 -m venv .venv && .venv/bin/pip install -e . && .venv/bin/drillstring study reference --out study",
        'python3 -m venv .venv && .venv/bin/pip install -e ".[test]" && .venv/bin/python -m pytest -q -n auto']


def test_module_references_in_docstrings_and_docs_name_modules_that_exist():
    """Every :mod:`drillstring...` reference of the sources and the Markdown docs names an importable module."""
    import importlib.util

    root = README.parent
    files = [*root.joinpath("src", "drillstring").rglob("*.py"), *root.joinpath("docs").rglob("*.md"), README]
    names = {name for path in files
             for name in re.findall(r":mod:`~?(drillstring(?:\.\w+)*)`", path.read_text(encoding="utf-8"))}
    assert len(names) > 20
    missing = sorted(name for name in names if importlib.util.find_spec(name) is None)
    assert not missing, missing
