"""Terminal tables at 80 columns and below (issue 28): no number, cell or header word cut with ``…``, whatever
the width; every command's tables at 80 and 60 columns."""

import re

import pytest
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from rich.text import Text
from typer.testing import CliRunner

from drillstring.case import load_case
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
    """Wide: the table as rich draws it; narrower: no borders (columns one space apart) with every cell on one
    line, rather than borders with cells wrapped over two or three lines (issue 38); narrower still: no
    borders and chosen widths (text cells wrap between words); then one block of 'header: value' lines per
    row. The table takes 104 columns unwrapped and its longest words 76, with 22 of borders and padding, or 6
    of spaces."""
    wide = _render(_table(), 126)
    assert wide.splitlines()[1].startswith("┏") and "│ rate of penetration " in wide
    for width in (125, 110):
        unwrapped = _render(_table(), width)
        assert "┏" not in unwrapped and "─" * 104 in unwrapped and "rate of penetration " in unwrapped
        assert len(unwrapped.splitlines()) == 1 + 1 + 1 + 3 + 1  # title, header, rule, one line per row, caption
    for width in (109, 82):
        wrapped = _render(_table(), width)
        assert "┏" not in wrapped and "│" not in wrapped and "─" * width in wrapped
        assert len(wrapped.splitlines()) > 7
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


# ---------------------------------------------------------------------------------------------------------
# Issue 38: the output designed for 80 columns, in the unit system asked for, results in plain sentences
# ---------------------------------------------------------------------------------------------------------

_AT_80 = {"COLUMNS": "80", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "TTY_INTERACTIVE": None,
          "DRILLSTRING_UNITS": None}
#: A screen: no table longer, unless asked for (--all, --json).
_SCREEN_LINES = 40
#: A quantity in an SI unit of output, after its number: what field units must never show.
SI_QUANTITY = re.compile(r"\d\s?(kN·m|N·m|kN|MN|N|m/h|m/s|rad/s|MPa|Pa|mm|m|kg/m³)(?![\w/·³])")


def _readme_first_case(folder):
    """The README's "first case of your own", saved as my_case.toml in ``folder``."""
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    (code,) = re.findall(r"```toml\n(.*?)```", readme, re.S)
    path = folder / "my_case.toml"
    path.write_text(code, encoding="utf-8")
    return str(path)


def _at_80(args) -> str:
    """stdout of a command at 80 columns, which must succeed and fit: no line wider than 80 (a wider one is
    broken by the terminal wherever the 80th column falls, mid-word: "steady dril/ling")."""
    from rich.cells import cell_len

    result = runner.invoke(app, list(args), env=_AT_80)
    assert result.exit_code == 0, result.output
    widest = max(cell_len(line.rstrip()) for line in result.stdout.splitlines())
    assert widest <= 80, (widest, result.stdout)
    assert "…" not in result.stdout
    return result.stdout


def test_first_case_static_and_stability_fit_a_screen_of_80_columns(tmp_path):
    """The README's first case in field units at 80 columns: the static state and the stability of steady
    drilling fit 80 columns and a screen (the stability table lists four roots per family and the growing
    ones; --all lists all of them)."""
    case = _readme_first_case(tmp_path)
    for command in ("static", "stability"):
        out = _at_80((command, case, "--units", "field"))
        assert len(out.splitlines()) <= _SCREEN_LINES, (command, len(out.splitlines()), out)
        assert not SI_QUANTITY.search(out), (command, SI_QUANTITY.search(out), out)
    shown = _at_80(("stability", case, "--units", "field"))
    every = _at_80(("stability", case, "--units", "field", "--all"))
    hidden = int(re.search(r"\+ (\d+) more \(decaying\) roots", shown).group(1))
    assert len(every.splitlines()) > hidden + 20 and "more (decaying) roots" not in every  # a row per root


def _near_critical_case(coarse_case, folder):
    """The coarse reference string at its critical weight-on-bit: with σ = 5 kN half the draws buckle it."""
    from drillstring.buckling import case_buckling_margin

    critical = case_buckling_margin(coarse_case).critical_weight_on_bit
    case = coarse_case.model_copy(update={"operation": coarse_case.operation.model_copy(
        update={"weight_on_bit": critical})})
    path = folder / "near_critical.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    return str(path), critical


def test_simulate_and_study_fit_80_columns_in_field_units(case_files, tmp_path):
    """simulate and study in field units at 80 columns: no line wider, the per-realization table a table (not
    the 130 lines of `key: value` it became) of at most a screen, and not a number in an SI unit."""
    torsional = str(case_files / "torsional.toml")
    run = _at_80(("simulate", torsional, "--units", "field", "--t-end", "1", "--out", str(tmp_path / "r.nc"),
                  "--plot", str(tmp_path / "r.png")))
    assert len(run.splitlines()) <= _SCREEN_LINES and not SI_QUANTITY.search(run), run
    assert "Solver: " in run and "right-hand sides" in run
    study = _at_80(("study", torsional, "--units", "field", "--samples", "3", "--t-end", "1", "--workers", "1",
                    "--out", str(tmp_path / "study")))
    assert not SI_QUANTITY.search(study), (SI_QUANTITY.search(study), study)
    assert "metric: " not in study and "  unit: " not in study  # no vertical layout
    lines = study.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Per realization"))
    end = next(i for i, line in enumerate(lines) if line.startswith("stick-slip index ("))
    assert end - start <= _SCREEN_LINES // 2, study
    assert "klbf" in next(line for line in lines if "weight_on_hook:" in line)  # the law in field units


def test_study_notes_are_results_in_the_unit_system(coarse_case, tmp_path):
    """A study where buckled draws are expected (issue 38): the note before the run and the result after it
    are sentences in the study's unit system (klbf, not the 117.4 kN beside 26.39 klbf of before), the
    result counts the buckled realizations of the summary, and nothing reads as a warning."""
    import json

    from drillstring.units import display_unit

    path, critical = _near_critical_case(coarse_case, tmp_path)
    out = tmp_path / "study"
    result = runner.invoke(app, ["study", path, "--units", "field", "--sigma", "5000", "--samples", "6",
                                 "--t-end", "0.4", "--workers", "1", "--out", str(out)], env=_AT_80)
    assert result.exit_code == 0, result.output
    klbf = f"{display_unit('force', 'field')(critical):,.2f} klbf"
    note = " ".join(result.stderr.split("note: ", 1)[1].split())
    assert klbf in note and "kN" not in result.stderr and "realizations" in note
    buckled = json.loads((out / "summary.json").read_text())["buckling"]["buckled_realizations"]
    text = " ".join(result.stdout.split())
    assert buckled > 0  # none of 6 with probability 1/64
    assert (f"Buckling: {buckled} of 6 realizations ({100 * buckled / 6:.3g} %) drew a weight-on-bit above "
            f"the critical {klbf}") in text
    assert "warning" not in result.output.lower()


def test_convergence_is_a_fact_with_what_would_settle_it():
    """The convergence of a study's dispersions in plain sentences: the record length that would show where
    they settle, and about how many realizations would bring their change below the threshold (a Monte
    Carlo change falls as 1/√n: 50 × (4 % / 2 %)² = 200)."""
    from drillstring.cli.study import _convergence_line

    windows = [{"t_end": 20.0}, {"t_end": 30.0}]
    summary = {"n_samples": 50,
               "time_convergence": {"threshold": 0.02, "observables": {
                   "rate_of_penetration": {"windows": windows, "change": {"dispersion_max": 0.13}},
                   "force_on_bit": {"windows": windows, "change": {"dispersion_max": 0.01}}}},
               "convergence_change_second_half": {"bit_speed": 0.04, "force_on_bit": 0.011}}
    line = _convergence_line(summary)
    assert "rate of penetration 13 %" in line and "force on bit" not in line.split("realizations")[0]
    assert "--t-end 60" in line and "about 200 realizations" in line
    settled = {"n_samples": 50, "time_convergence": {"threshold": 0.02, "observables": {}},
               "convergence_change_second_half": {"bit_speed": 0.01}}
    assert _convergence_line(settled) is None


def test_simulate_table_shows_the_motor(case_files):
    """A run with a downhole motor (issue 38): its speed, torque and differential pressure (min / max after
    the transient) in the printed table, in the unit system (field: rpm, kft·lbf, psi); none without one."""
    import numpy as np
    import xarray as xr

    from drillstring.cli.simulate import _run_numbers, _simulation_table

    t = np.linspace(0.0, 2.0, 201)
    ds = xr.Dataset(
        {"rate_of_penetration": ("time", np.full_like(t, 3e-3)), "bit_speed": ("time", 10.0 + np.sin(t)),
         "torque_on_bit": ("time", np.full_like(t, 4e3)), "force_on_bit": ("time", np.full_like(t, 1e5)),
         "radial_displacement": (("time", "probe"), np.zeros((t.size, 1))),
         "motor_speed": ("time", 5.0 + t), "motor_torque": ("time", 6e3 + 1e3 * t),
         "differential_pressure": ("time", 3e6 + 1e6 * t)},
        coords={"time": t, "x": ("probe", [100.0]), "gap": ("probe", [0.03])}, attrs={"top_speed": 10.0})
    numbers = _run_numbers(ds, 1.0)
    assert numbers["differential_pressure_min"] == pytest.approx(4e6) and numbers["motor_speed_max"] == 7.0
    text = _render(_simulation_table("motor", numbers, "field"), 80)
    rpm, torque, psi = 60 / (2 * np.pi), 1 / 1355.8179483314004, 1 / 6894.757293168361
    assert f"motor speed min / max  {6 * rpm:.2f} / {7 * rpm:.2f} rpm" in " ".join(text.split()) or \
        f"{6 * rpm:.2f} / {7 * rpm:.2f}" in text
    assert f"{7e3 * torque:,.2f} / {8e3 * torque:,.2f}" in text and "kft·lbf" in text
    assert f"{4e6 * psi:,.2f} / {5e6 * psi:,.2f}" in text and "psi" in text
    plain = _run_numbers(ds.drop_vars(["motor_speed", "motor_torque", "differential_pressure"]), 1.0)
    assert "motor" not in _render(_simulation_table("plain", plain, "field"), 80)


def test_a_study_without_notes_warns_of_nothing(small_case, tmp_path, recwarn):
    """Buckled draws are a result, not a misuse (issue 38): a study run from Python without a ``note``
    callback (the first tutorial) issues no RuntimeWarning (it pointed into the standard library); the
    summary still holds the probability, the expected count and the note's text."""
    from drillstring import api
    from drillstring.buckling import case_buckling_margin

    critical = case_buckling_margin(small_case).critical_weight_on_bit
    case = small_case.model_copy(update={"operation": small_case.operation.model_copy(
        update={"weight_on_bit": critical - 2e3})})
    outcome = api.monte_carlo_study(case, sigma=5000.0, samples=3, t_end=0.2, workers=1, out=tmp_path / "s")
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in recwarn]
    buckling = outcome.summary["buckling"]
    assert buckling["expected"] > 1.0 and "realizations" in buckling["warning"]
    assert set(buckling) >= {"buckled_realizations", "critical_weight_on_bit", "probability", "expected"}
    assert not set(buckling) & {"lateral", "source"}  # the JSON keeps its keys


def test_errors_in_the_unit_system_of_the_command(tmp_path):
    """An error's quantities in the command's unit system (issue 38): a weight-on-bit above the string's
    weight in klbf under --units field, in kN under si (the key's own value is echoed in SI, as a case file may
    give it)."""
    case = tmp_path / "heavy.toml"
    case.write_text(open(_readme_first_case(tmp_path)).read().replace('"25 klbf"', '"250 klbf"'), encoding="utf-8")
    for units, unit, other in (("field", "klbf", "kN"), ("si", "kN", "klbf")):
        result = runner.invoke(app, ["static", str(case), "--units", units], env=_AT_80)
        assert result.exit_code == 2
        line = result.stderr.strip()
        assert "must be less than the string's weight: weight_on_bit " in line, line
        reason = line.split("must be less than the string's weight: ", 1)[1]
        assert f" {unit}" in reason and f" {other}" not in reason, line
        klbf = 1000 * 0.45359237 * 9.80665  # N, by the pound's and standard gravity's definitions
        weight_klbf = load_case(_readme_first_case(tmp_path)).weight / klbf
        assert units == "si" or reason == f"weight_on_bit 250 klbf >= weight {weight_klbf:.6g} klbf", line


def test_a_warning_without_notes_points_at_the_callers_code():
    """A note given as a RuntimeWarning (no ``note`` callback: a stale lock taken over) names the caller's
    file and line, not ``contextlib.py`` of the decorator of the API functions (issue 38)."""
    import contextlib
    import warnings

    from drillstring.stochastic.execution import notify

    @contextlib.contextmanager
    def decorator():
        yield

    @decorator()
    def api_function():
        notify(None, "a stale lock was taken over")

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        api_function()
    (warning,) = caught
    assert warning.filename == __file__ and issubclass(warning.category, RuntimeWarning)
