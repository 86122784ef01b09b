"""The ``drillstring`` command line (Typer).

Commands
--------
``drillstring static [CASE] [--json]``
    The prestressed static state: weight, weight-on-hook, weight-on-bit, neutral point, axial force.
``drillstring modes [CASE] [--count N] [--json]``
    The lowest natural frequencies of the axial, torsional and lateral mode families.
``drillstring cases``
    The built-in cases.

``CASE`` is a built-in case name (default ``reference``) or the path to a TOML case file.

Conventions for every command (follow them when adding one)
------------------------------------------------------------
- Load the case with :func:`_load`: an invalid case prints its message to stderr and exits with code 2.
- Physics stays out of this module: a command calls the package API and only formats the result.
- ``--json`` prints ``json.dumps(payload, indent=2)`` of SI values, and nothing else, on stdout.
- Human-readable output (rich tables) converts units here, at the edge: kN, m, Hz, ...
"""

from __future__ import annotations

import json
from typing import Annotated, Any, NoReturn

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from drillstring import __version__
from drillstring.case import Case, CaseError, builtin_cases, load_case
from drillstring.modal import case_linear_system, compute_modes
from drillstring.statics import case_static_state

#: Exit code for an invalid case or bad input data (same as Click's usage errors).
EXIT_INVALID_INPUT = 2

_KN = 1e3  # N per kN

app = typer.Typer(
    name="drillstring",
    help="Stochastic nonlinear dynamics of oil-well drill-strings.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


# ---------------------------------------------------------------------------------------------------------
# Shared helpers
# ---------------------------------------------------------------------------------------------------------

CaseArg = Annotated[
    str,
    typer.Argument(
        metavar="CASE",
        help="A built-in case name (see `drillstring cases`) or the path to a TOML case file.",
        show_default=True,
    ),
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON (SI units) on stdout instead of tables.")]


def _fail(message: str, code: int = EXIT_INVALID_INPUT) -> NoReturn:
    """Print ``message`` to stderr (no traceback) and exit with ``code``."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def _load(case_arg: str) -> Case:
    """The case named or pointed to by ``case_arg``; a :class:`CaseError` ends the command with exit code 2."""
    try:
        return load_case(case_arg)
    except CaseError as exc:
        _fail(str(exc))


def _print_json(payload: Any) -> None:
    """The one way a command writes JSON: indented, alone on stdout."""
    typer.echo(json.dumps(payload, indent=2))


def _console() -> Console:
    # Created per call so that the current sys.stdout is used (tests capture it).
    return Console(highlight=False)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"drillstring {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="Show the version and exit."),
    ] = False,
) -> None:
    """Stochastic nonlinear dynamics of oil-well drill-strings (SI units inside; kN, m, Hz in tables)."""


# ---------------------------------------------------------------------------------------------------------
# drillstring cases
# ---------------------------------------------------------------------------------------------------------


@app.command()
def cases() -> None:
    """List the built-in cases."""
    names = builtin_cases()
    if not names:
        typer.echo("no built-in cases found")
        return
    width = max(len(n) for n in names)
    for name in names:
        try:
            description = load_case(name).description
        except CaseError:
            description = "(invalid case file)"
        typer.echo(f"{name:<{width}}  {description}".rstrip())


# ---------------------------------------------------------------------------------------------------------
# drillstring static
# ---------------------------------------------------------------------------------------------------------


def _axial_force_landmarks(case: Case, x: np.ndarray) -> list[tuple[str, float]]:
    """(label, x) of the top, section changes, stabilizers and the bit, sorted by x, equal x merged."""
    points: list[tuple[float, str]] = [(0.0, "top (hook)")]
    end = 0.0
    for upper, lower in zip(case.sections[:-1], case.sections[1:]):
        end += upper.length
        points.append((end, f"{upper.name} / {lower.name}"))
    for i, stabilizer in enumerate(case.stabilizers):
        label = "stabilizer" if len(case.stabilizers) == 1 else f"stabilizer {i + 1}"
        points.append((stabilizer.position, label))
    length = float(x[-1])
    points.append((length, "bit"))
    tolerance = 1e-6 * max(1.0, length)
    merged: list[tuple[str, float]] = []
    for position, label in sorted(points, key=lambda p: p[0]):
        if merged and abs(merged[-1][1] - position) <= tolerance:
            merged[-1] = (f"{merged[-1][0]}, {label}", merged[-1][1])
        else:
            merged.append((label, position))
    return merged


@app.command()
def static(case: CaseArg = "reference", as_json: JsonOpt = False) -> None:
    """The prestressed static state: weight, weight-on-hook, weight-on-bit, neutral point, axial force."""
    the_case = _load(case)
    state = case_static_state(the_case)
    x = np.asarray(state.mesh.nodes, dtype=float)
    n = np.asarray(state.axial_force, dtype=float)
    if as_json:
        _print_json(
            {
                "weight": float(state.weight),
                "weight_on_hook": float(state.weight_on_hook),
                "weight_on_bit": float(state.weight_on_bit),
                "neutral_point_height": float(state.neutral_point_height),
                "axial_force": [[float(xi), float(ni)] for xi, ni in zip(x, n)],
            }
        )
        return

    console = _console()
    summary = Table(title=escape(f"Static state: case {the_case.name!r}"), title_justify="left")
    summary.add_column("quantity")
    summary.add_column("value", justify="right")
    summary.add_column("unit")
    summary.add_row("weight", f"{state.weight / _KN:,.2f}", "kN")
    summary.add_row("weight-on-hook", f"{state.weight_on_hook / _KN:,.2f}", "kN")
    summary.add_row("weight-on-bit", f"{state.weight_on_bit / _KN:,.2f}", "kN")
    summary.add_row("neutral point above the bit", f"{state.neutral_point_height:,.2f}", "m")
    summary.add_row("string length", f"{state.mesh.length:,.1f}", "m")
    console.print(summary)

    forces = Table(title="Axial force N (tension > 0)", title_justify="left")
    forces.add_column("where")
    forces.add_column(escape("x [m]"), justify="right")
    forces.add_column(escape("above bit [m]"), justify="right")
    forces.add_column(escape("N [kN]"), justify="right")
    for label, position in _axial_force_landmarks(the_case, x):
        # N is continuous and linear inside each element, so interpolation between nodes is exact.
        value = float(np.interp(position, x, n))
        height = state.mesh.length - position
        forces.add_row(escape(label), f"{position:,.1f}", f"{height:,.1f}", f"{value / _KN:,.2f}")
    console.print(forces)
    console.print(escape(f"{len(x)} nodes; full profile: drillstring static {case} --json"), soft_wrap=True)


# ---------------------------------------------------------------------------------------------------------
# drillstring modes
# ---------------------------------------------------------------------------------------------------------


@app.command()
def modes(
    case: CaseArg = "reference",
    count: Annotated[
        int, typer.Option("--count", "-n", min=1, help="Number of modes per family (axial includes the rigid mode).")
    ] = 10,
    as_json: JsonOpt = False,
) -> None:
    """The lowest natural frequencies [Hz] of the prestressed string, per mode family."""
    the_case = _load(case)
    state = case_static_state(the_case)
    found = compute_modes(case_linear_system(the_case, state), axial=count, torsional=count, lateral=count)
    families = {
        "axial": [float(f) for f in found.axial.frequencies],
        "torsional": [float(f) for f in found.torsional.frequencies],
        "lateral": [float(f) for f in found.lateral.frequencies],
    }
    if as_json:
        _print_json(families)
        return

    table = Table(title=escape(f"Natural frequencies: case {the_case.name!r}"), title_justify="left")
    table.add_column("mode", justify="right")
    for name in families:
        table.add_column(escape(f"{name} [Hz]"), justify="right")
    rows = max(len(v) for v in families.values())
    for i in range(rows):
        cells = [f"{v[i]:.4f}" if i < len(v) else "" for v in families.values()]
        table.add_row(str(i + 1), *cells)
    console = _console()
    console.print(table)
    for note in (
        "axial: both ends free; mode 1 is the rigid translation (0 Hz).",
        "torsional: top held, bit free. lateral: one plane of each y/z pair.",
        "Prestress (geometric stiffness) and drilling fluid included.",
    ):
        console.print(note)


if __name__ == "__main__":  # pragma: no cover
    app()
