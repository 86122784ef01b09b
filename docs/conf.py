"""Sphinx configuration of the documentation site (build it with ``docs/build``).

Pages are MyST Markdown (the model and verification pages are the files of ``docs/`` themselves, also read on
the repository host), tutorials are Jupyter notebooks stored without outputs and executed by myst-nb at every
build, the API reference comes from the docstrings (autodoc) and the CLI reference from the Typer commands
themselves (``_ext/cli_reference.py``). ``docs/build`` runs Sphinx with ``-W``: a
broken internal link (a page, a heading anchor, a file), a docstring that does not parse or a notebook cell
that raises fails the build.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

project = "drillstring"
author = "the drillstring developers"
copyright = "the drillstring developers, BSD-3-Clause"

extensions = [
    "myst_nb",  # MyST Markdown pages and executed notebooks (includes myst_parser)
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",  # the docstrings' "Attributes:" / "Returns:" sections
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "cli_reference",
]

source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
exclude_patterns = ["_build", "_ext", "build", "README.md", "**/.ipynb_checkpoints", "jupyter_execute"]

# MyST: GitHub-style heading anchors, so the links the pages already use on the repository host
# (model.md#5-nonlinear-forces) are the site's links too, and each is checked.
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
suppress_warnings = []

# Notebooks: executed at every build, in order, each in its own kernel; a cell that raises fails the build.
nb_execution_mode = os.environ.get("DRILLSTRING_DOCS_EXECUTE", "force")
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

# The notebooks' kernels get CurveZMQ keys from the kernel manager (jupyter_client's transport encryption,
# "auto": where the kernel spec declares it, as ipykernel's does), so the build's traffic with them is encrypted and
# ipykernel has no "Kernel is running over TCP without encryption" warning to print, once per notebook, into the
# build's output. myst-nb creates the kernel manager without a configuration: it takes the policy's default.
import zmq
from jupyter_client.manager import KernelManager

_traits = KernelManager.class_traits()
if "transport_encryption" in _traits and zmq.has("curve"):  # jupyter_client 8.10 on; pyzmq with libsodium
    _traits["transport_encryption"].default_value = "auto"

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": False}

smartquotes = False  # help texts and code-like prose keep their "--" and quotes
html_theme = "furo"
html_title = "drillstring"
html_static_path: list[str] = []


# The docstrings are written to be read as text: ``|x|`` is an absolute value, not a reStructuredText
# substitution. Escape the bars outside inline literals before autodoc parses them.
_LITERAL = re.compile(r"(``.*?``|`[^`]*`)")


def _escape_bars(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        parts = _LITERAL.split(line)
        lines[i] = "".join(part if j % 2 else part.replace("|", "\\|") for j, part in enumerate(parts))


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars)
