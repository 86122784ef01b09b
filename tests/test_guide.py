"""The user guide's pages match the code they describe."""

import re
from importlib import resources
from pathlib import Path

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide"


def test_commands_page_lists_every_built_in_case():
    """The `drillstring cases` listing of docs/guide/commands.md names each case shipped in drillstring/cases (it
    once lacked `motor`)."""
    text = (GUIDE / "commands.md").read_text(encoding="utf-8")
    listing = re.search(r"\$ drillstring cases\n(.*?)```", text, re.S).group(1)
    listed = [line.split()[0] for line in listing.strip().splitlines()]
    shipped = sorted(entry.name[:-len(".toml")] for entry in resources.files("drillstring").joinpath("cases").iterdir()
                     if entry.name.endswith(".toml"))
    assert listed == shipped


def test_api_reference_is_one_page_per_stage():
    """docs/api.md is a contents page over docs/api/*.md (it was one page of every module, about 216,000 px
    tall): each page in its table of contents exists, no module is documented twice, none is on api.md itself,
    and no page holds more than six modules."""
    docs = GUIDE.parent
    index = (docs / "api.md").read_text(encoding="utf-8")
    assert "automodule" not in index
    pages = re.search(r"```\{toctree\}\n(?::.*\n)*\n(.*?)```", index, re.S).group(1).split()
    assert len(pages) >= 8
    modules = []
    for page in pages:
        found = re.findall(r"\.\. automodule:: (\S+)", (docs / f"{page}.md").read_text(encoding="utf-8"))
        assert 1 <= len(found) <= 6, (page, found)
        modules += found
    assert len(modules) == len(set(modules))
    assert {"drillstring.api", "drillstring.stochastic.optimize", "drillstring.well.torque_drag"} <= set(modules)
