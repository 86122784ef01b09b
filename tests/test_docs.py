"""The documentation build fails on what it must not publish: a link to a page, a heading or a file that does not
exist, and a tutorial notebook whose cell raises. Each case builds a two-page site with the settings of the real
one (docs/conf.py) through the same entry point (docs/build.py). Needs the ``docs`` extra; without it these tests
are skipped (.ci/run runs them in the environment where it builds the site)."""

import importlib.util
import json
from pathlib import Path

import pytest

pytest.importorskip("myst_nb", reason="the docs extra is not installed (pip install -e '.[docs]')")

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _build_module():
    spec = importlib.util.spec_from_file_location("docs_build", DOCS / "build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _site(tmp_path: Path, page: str, notebook: list[str] | None = None) -> Path:
    """A site with the real site's configuration: an index, one page and optionally one notebook."""
    source = tmp_path / "site"
    source.mkdir()
    (source / "conf.py").write_text(
        f"import sys\nsys.path.insert(0, {str(DOCS)!r})\nfrom conf import *  # noqa: F401,F403\n", encoding="utf-8")
    entries = "page\nnotebook\n" if notebook is not None else "page\n"
    (source / "index.md").write_text(f"# Index\n\n```{{toctree}}\n{entries}```\n", encoding="utf-8")
    (source / "page.md").write_text(page, encoding="utf-8")
    (source / "data.csv").write_text("a,b\n1,2\n", encoding="utf-8")
    if notebook is not None:
        cells = [{"cell_type": "code", "execution_count": None, "id": f"c{i}", "metadata": {}, "outputs": [],
                  "source": code} for i, code in enumerate(notebook)]
        book = {"cells": [{"cell_type": "markdown", "id": "title", "metadata": {}, "source": "# Notebook"}, *cells],
                "metadata": {"kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"}},
                "nbformat": 4, "nbformat_minor": 5}
        (source / "notebook.ipynb").write_text(json.dumps(book), encoding="utf-8")
    return source


GOOD_PAGE = """# Page

## A heading

[the index](index.md), [the heading](#a-heading), [the index's heading](index.md#index),
[a file](data.csv).
"""


def _run(tmp_path, page, notebook=None):
    done = _build_module().build(_site(tmp_path, page, notebook), tmp_path / "html", capture=True)
    return done.returncode, done.stdout + done.stderr


def test_a_site_with_sound_links_and_a_sound_notebook_builds(tmp_path):
    code, log = _run(tmp_path, GOOD_PAGE, ["x = 6 * 7\nprint(x)"])
    assert code == 0, log
    assert "42" in (tmp_path / "html" / "notebook.html").read_text(encoding="utf-8")  # executed, output shown
    # the kernel gets CurveZMQ keys (docs/conf.py): no "Kernel is running over TCP without encryption" per notebook
    assert "without encryption" not in log and "IPKernelApp" not in log, log


def test_a_tutorial_runs_by_hand_with_the_docs_extra(tmp_path):
    """docs/tutorials/index.md's command (nbconvert, in the docs extra) executes a notebook outside the build."""
    import subprocess
    import sys

    source = _site(tmp_path, GOOD_PAGE, ["print(6 * 7)"]) / "notebook.ipynb"
    done = subprocess.run([sys.executable, "-m", "jupyter", "nbconvert", "--to", "notebook", "--execute", str(source),
                           "--output-dir", str(tmp_path / "out")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    executed = json.loads((tmp_path / "out" / "notebook.ipynb").read_text(encoding="utf-8"))
    assert "".join(executed["cells"][1]["outputs"][0]["text"]) == "42\n"


BROKEN = {"missing.md": "[a page]", "#no-such-heading": "[a heading here]",
          "index.md#no-such-other-heading": "[a heading there]", "missing.csv": "[a file]"}


def test_each_broken_internal_link_fails_the_build(tmp_path):
    """One build (``--keep-going`` reports every warning) of a page with four broken links: each is named."""
    links = "\n".join(f"{text}({target})" for target, text in BROKEN.items())
    code, log = _run(tmp_path, GOOD_PAGE + "\n" + links + "\n")
    assert code != 0, log
    warnings = [line for line in log.splitlines() if "WARNING" in line]
    for target in BROKEN:
        named = target.split("#")[-1]  # the missing page, file or heading
        assert any(named in line for line in warnings), (target, warnings)


def test_a_notebook_cell_that_raises_fails_the_build(tmp_path):
    code, log = _run(tmp_path, GOOD_PAGE, ["raise ValueError('a tutorial that no longer runs')"])
    assert code != 0
    assert "ExecutionError" in log and "notebook.ipynb" in log, log
