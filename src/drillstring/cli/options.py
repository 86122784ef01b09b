"""The application object and what every command shares: exit codes, the case argument, ``--json``,
``--units``, the options of the engine commands (``--param``, ``--out``, ``--workers`` ...), loading a case,
failing in one line, the consoles and the run window."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated, Any, NoReturn

import typer
from rich.console import Console
from rich.markup import escape

from drillstring._version import __version__
from drillstring.case import Case, CaseError, load_case
from drillstring.units import message_units, reset_message_units, unit_system

#: Exit code for an invalid case or bad input data (same as Click's usage errors).
EXIT_INVALID_INPUT = 2
#: Exit code for a run that failed (a simulation that stopped early, a study without statistics).
EXIT_RUN_FAILED = 1
#: Exit code after Ctrl-C (128 + SIGINT, the shell convention).
EXIT_INTERRUPTED = 130

_RPM = 60.0 / (2.0 * math.pi)  # rpm per rad/s

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


def _unit_system_option(ctx: typer.Context, value: str | None) -> str:
    """The ``--units`` value, else ``$DRILLSTRING_UNITS``, else ``si``; a bad one is a usage error (exit 2),
    except an unusable ``$DRILLSTRING_UNITS`` under ``--json`` (SI whatever the unit system): then a note on
    stderr and ``si`` for any figure or report the command also writes."""
    try:
        system = unit_system(value)
    except ValueError as error:
        if value is None and ctx.params.get("as_json"):
            typer.echo(f"note: {error}; ignored, --json output is SI", err=True)
            return "si"
        raise typer.BadParameter(str(error)) from None
    token = message_units(system)  # the command's messages (errors, notes) in its unit system
    ctx.call_on_close(lambda: reset_message_units(token))
    return system


#: The output unit system of tables, figures and reports: one definition for every command.
UnitsOpt = Annotated[
    str,
    typer.Option("--units", metavar="si|field", callback=_unit_system_option, show_default=False,
                 help="Units of tables, figures and reports: si (kN, m, m/h, kN·m, mm) or field (klbf, ft, ft/h, "
                      "kft·lbf, in); rpm and Hz in both. Default: $DRILLSTRING_UNITS, else si. JSON stays SI."),
]


def _fail(message: str, code: int = EXIT_INVALID_INPUT) -> NoReturn:
    """Print ``message`` to stderr (no traceback) and exit with ``code``."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def _note_resumed(already: int, total: int, noun: str, store: Path) -> None:
    """Say on stderr how many of the ``total`` items a resumed run found already in ``store``."""
    if already:
        _err_console().print(escape(f"resumed: {already} of {total} {noun} were already in {store}"),
                             soft_wrap=True)


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


def _err_console() -> Console:
    """Progress bars and notes: stderr, so that stdout keeps only the table or the JSON."""
    return Console(stderr=True, highlight=False)


def _run_window(case: Case, t_end: float | None):
    """The run window of ``case`` with ``--t-end`` (:func:`~drillstring.dynamics.simulate.run_window`; its
    ``transient``, min(10 s, t_end/2), starts the summaries); refused (exit code 2) in one line."""
    from drillstring.dynamics.simulate import run_window

    try:
        return run_window(case.simulation.t_end if t_end is None else t_end, case.simulation.output_step,
                          names={"t_end": "simulation.t_end" if t_end is None else "--t-end"})
    except ValueError as error:
        _fail(str(error))


def _check_output(option: str, path: Path, *, folder: bool = False) -> None:
    """End the command (exit code 2) before any computation when ``path`` cannot be written."""
    from drillstring.files import output_file_problem, output_folder_problem

    problem = output_folder_problem(path) if folder else output_file_problem(path)
    if problem:
        _fail(f"{option} = {path}: {problem}")


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


TEndOption = Annotated[
    float | None, typer.Option("--t-end", help="Simulated time [s] (default: the case's simulation.t_end).")
]


ParamOption = Annotated[
    list[str] | None,
    typer.Option("--param", "-p", metavar="PATH=LAW",
                 help='A random case parameter and its law, e.g. --param fluid.inlet_velocity="uniform 1.2 1.8 '
                      'm/s" (laws: uniform, normal, exponential, gamma, maxent; see docs/uncertainty.md); '
                      "repeat for several. Replaces the case file's uncertainty table."),
]
CorrelationOption = Annotated[
    list[str] | None,
    typer.Option("--correlation", metavar="PATH1,PATH2=R",
                 help="Correlation coefficient of two normal parameters, e.g. "
                      "operation.top_speed,weight_on_hook=-0.3; repeat for more pairs."),
]


OutOption = Annotated[Path, typer.Option("--out", "-o", help="Output folder; rerunning with the same folder "
                                                             "resumes. Locked while a run uses it.")]
WorkersOption = Annotated[
    int | None,
    typer.Option("--workers", "-j", help="Local worker processes (default: one per core); 1 runs in this process."),
]
SchedulerOption = Annotated[
    str | None, typer.Option("--scheduler", help="Dask scheduler address (tcp://host:8786) instead of local processes."),
]
RunTEndOption = Annotated[
    float | None, typer.Option("--t-end", help="Simulated time per run, in s (default: the case's t_end)."),
]
TransientOption = Annotated[
    float | None,
    typer.Option("--transient", help="Start of the window of the outputs, in s, in [0, t_end) (default: "
                                     "min(10 s, t_end/2))."),
]
