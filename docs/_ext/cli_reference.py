"""The CLI reference, generated from the commands themselves.

``typer.main.get_command`` turns the Typer application of :mod:`drillstring.cli` into the click-style group it
runs; the directive ``.. drillstring-cli::`` walks its commands and writes, for each, its usage line, help text
and every argument and option with the help record ``--help`` prints (names, metavar, default). Recent Typer
releases carry their own copy of click (``typer._click``), which sphinx-click does not accept as a click
command, so the reference is written here from the same objects ``--help`` uses.
"""

from __future__ import annotations

import inspect
import re

import typer
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

_MARKUP = re.compile(r"\[/?(?:bold|dim|italic|red|green|yellow|blue|cyan|magenta|white|b|i)\]")


def command():
    """The command line as the click-style group Typer builds."""
    from drillstring.cli import app

    return typer.main.get_command(app)


def _plain(text: str | None) -> str:
    """Help text without rich markup, as plain reStructuredText (backslashes and stars escaped)."""
    text = _MARKUP.sub("", inspect.cleandoc(text or ""))
    return text.replace("\\", "\\\\").replace("*", "\\*").replace("|", "\\|").replace("`", "\\`")


def _lines(group) -> list[str]:
    root = type(group).context_class(group, info_name="drillstring")
    out = [_plain(group.help), ""]
    for name in group.list_commands(root):
        cmd = group.get_command(root, name)
        if cmd is None or getattr(cmd, "hidden", False):
            continue
        ctx = type(cmd).context_class(cmd, info_name=name, parent=root)
        out += [f".. _cli-{name}:", "", name, "-" * len(name), "", "::", "",
                "    " + cmd.get_usage(ctx).replace("\n", "\n    "), "", _plain(cmd.help), ""]
        for param in cmd.get_params(ctx):
            record = param.get_help_record(ctx)
            if record is None:  # an argument: click prints none
                out += [f"``{param.human_readable_name}``", "    argument", ""]
                continue
            names, help_text = record
            out += [f"``{names}``", "    " + (_plain(help_text).replace("\n", " ") or "(no help)"), ""]
    return out


class DrillstringCli(SphinxDirective):
    """``.. drillstring-cli::``: every command of ``drillstring`` with its options."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        container = nodes.section()
        container.document = self.state.document
        self.state.nested_parse(StringList(_lines(command()), source="drillstring --help"), self.content_offset,
                                container, match_titles=True)
        return container.children


def setup(app):
    app.add_directive("drillstring-cli", DrillstringCli)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
