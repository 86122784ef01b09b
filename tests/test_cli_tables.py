"""Terminal tables at 80 columns and below (issue 28): no number, cell or header word cut with ``…``, whatever
the width; every command's tables at 80 and 60 columns."""

import re

import pytest
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from rich.text import Text
from typer.testing import CliRunner

from drillstring.cli import app
from drillstring.cli.tables import print_table

runner = CliRunner()

#: A number as the tables print it: sign, thousands separators, decimals, exponent, percent.
NUMBER = re.compile(r"[-+−]?\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?%?")


def _render(table: Table, width: int) -> str:
    console = Console(width=width, record=True, file=open("/dev/null", "w"), highlight=False)  # noqa: SIM115
    print_table(console, table)
    console.file.close()
    return console.export_text()


def _table() -> Table:
    table = Table(title="A wide table", caption="its caption")
    table.add_column("observable")
    for header in ("mean δ [%]", "max δ [%]", "at t [s]", "P(stick-slip)", "mean/δ_WOH", "S1 ± half-width"):
        table.add_column(escape(header), justify="right")  # as the commands do: '[s]' is no markup
    table.add_row("rate of penetration", "0.64213", "0.0921847", "1,234.56", "0.500", "-1.2345e-05",
                  "0.123 ± 0.045")
    table.add_row("", "12,345,678.9", "-0.000123", "7.5", "1.000", "3.14159", "0.987 ± 0.001")
    table.add_row("torque-on-bit at x = 1,560 m / gap", "", "12.3 / 45.6", "0.1", "0.000", "2.5", "–")
    return table


@pytest.mark.parametrize("width", range(20, 131, 5))
def test_every_cell_and_header_word_stays_whole_at_any_width(width):
    """Every word of every cell and header (every number: '12,345,678.9', '-1.2345e-05') appears whole on one
    line, no '…', and no line is wider than the console, from 20 to 130 columns."""
    text = _render(_table(), width)
    assert "…" not in text
    lines = text.splitlines()
    assert max(len(line.rstrip()) for line in lines) <= width
    table = _table()
    for column in table.columns:
        for cell in column.cells:
            # Each word whole on a line: a number has no space, so no number is split or cut.
            for piece in cell.split():
                assert any(piece in line for line in lines), (width, piece, text)
        for word in Text.from_markup(column.header).plain.split():
            assert any(word in line for line in lines), (width, word, text)


def test_layouts_from_wide_to_vertical():
    """Wide: the table as rich draws it; narrower: chosen widths (text and number cells wrap between words),
    then no borders (columns one space apart), then one block of 'header: value' lines per row. The longest
    words of this table take 76 columns (104 unwrapped), with 22 of borders and padding, or 6 of spaces."""
    wide = _render(_table(), 200)
    assert wide.splitlines()[1].startswith("┏") and "│ rate of penetration " in wide
    fixed = _render(_table(), 98)
    assert fixed.splitlines()[1].startswith("┏") and "│ rate of penetration " not in fixed
    for width in (97, 82):
        borderless = _render(_table(), width)
        assert "┏" not in borderless and "│" not in borderless and "─" * width in borderless
    vertical = _render(_table(), 81)
    assert "observable: rate of penetration\n  mean δ [%]: 0.64213\n" in vertical
    assert "0.123 ± 0.045\n  mean δ [%]: 12,345,678.9\n" in vertical  # a row without a first cell: indented


@pytest.fixture(scope="module")
def case_files(coarse_case, torsional_case, tmp_path_factory):
    folder = tmp_path_factory.mktemp("cases")
    (folder / "coarse.toml").write_text(coarse_case.to_toml(), encoding="utf-8")
    (folder / "torsional.toml").write_text(torsional_case.to_toml(), encoding="utf-8")
    return folder


def _commands(folder, out):
    coarse, torsional = str(folder / "coarse.toml"), str(folder / "torsional.toml")
    engine = ("--t-end", "1", "--workers", "1")
    return {
        "static": ("static", coarse),
        "modes": ("modes", coarse),
        "stability": ("stability", coarse),
        "campbell": ("campbell", coarse, "--top-speed", "10:120:4"),
        "simulate": ("simulate", torsional, "--t-end", "1", "--out", str(out / "r.nc"), "--plot", str(out / "r.png")),
        "study": ("study", torsional, "--samples", "2", *engine, "--out", str(out / "study")),
        "map": ("map", torsional, "--top-speed", "80:160:2", "--weight-on-bit", "60 kN", *engine,
                "--out", str(out / "map")),
        "probabilistic map": ("map", torsional, "--top-speed", "80:160:2", "--weight-on-bit", "60 kN", *engine,
                              "--samples", "2", "--out", str(out / "pmap")),
        "sensitivity": ("sensitivity", torsional, "--param", "operation.top_speed=uniform 120 180 rpm",
                        "--samples", "8", *engine, "--out", str(out / "sensitivity")),
    }


@pytest.mark.parametrize("command", ["static", "modes", "stability", "campbell", "simulate", "study", "map",
                                     "probabilistic map", "sensitivity"])
def test_no_number_cut_at_80_and_60_columns(case_files, tmp_path, command):
    """The must-show of issue 28: each command's tables at 80 and at 60 columns (a plain terminal, a log) cut
    nothing: no '…' anywhere, and the same numbers at both widths (a number
    wrapped in two at 60 columns would count as two). The engine commands' second run resumes (figures and
    tables only)."""
    args = _commands(case_files, tmp_path)[command]
    numbers = {}
    for columns in ("80", "60"):
        result = runner.invoke(app, list(args), env={"COLUMNS": columns, "FORCE_COLOR": None, "TTY_COMPATIBLE": None,
                                                     "TTY_INTERACTIVE": None, "DRILLSTRING_UNITS": None})
        assert result.exit_code == 0, result.output
        assert "…" not in result.stdout, (columns, result.stdout)
        kept = [line for line in result.stdout.splitlines()  # the figures that vary from run to run left out
                if not any(word in line for word in ("wall time", "solver", "compilation", "right-hand"))]
        numbers[columns] = sorted(NUMBER.findall("\n".join(kept)))
    if command in ("static", "modes", "stability", "campbell"):  # deterministic: the same numbers
        assert numbers["80"] == numbers["60"]
