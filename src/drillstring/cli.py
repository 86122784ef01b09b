"""The ``drillstring`` command line (Typer).

Commands
--------
``drillstring static [CASE] [--json]``
    The prestressed static state: weight, weight-on-hook, weight-on-bit, neutral point, critical
    weight-on-bit (lateral buckling), axial force.
``drillstring modes [CASE] [--count N] [--json]``
    The lowest natural frequencies of the axial, torsional and lateral mode families.
``drillstring campbell [CASE] [--top-speed A:B:N] [--blades N] [--plot FILE.png] [--json]``
    Campbell diagram: frequencies of each family against rotary speed, excitation lines, critical speeds.
``drillstring cases``
    The built-in cases.
``drillstring simulate [CASE] [--t-end S] [--out FILE.nc] [--plot FILE.png] [--json]``
    One drilling run: NetCDF of the observables, a six-panel figure and a summary table.
``drillstring study [CASE] [--param PATH=LAW ...] [--sigma N | --dispersion D] [--samples N] [--out DIR] ...``
    Monte Carlo study of random case parameters (default: the weight-on-hook): Zarr store (resumable),
    statistics, figures, report.
``drillstring map [CASE] [--top-speed A:B:N] [--weight-on-bit A:B:N] [--t-end S] [--out DIR] ...``
    Operating map over top speed × weight-on-bit: performance, vibration, stability, buckling margin;
    with ``--samples N`` (and ``--sigma``/``--param``), probabilities of stick-slip, buckling, impact and
    instability at each point.
``drillstring sensitivity [CASE] --param PATH=LAW ... [--samples N] [--out DIR] ...``
    Global sensitivity: Sobol' indices of ROP, vibration, TOB, FOB.
``drillstring compare [CASE] [--t-end S] [--plot FILE.png] [--json]``
    Case 1 (full nonlinear model) against case 2 (bit–rock + contact): differences, wall times, figure.
``drillstring torque-drag [CASE] [--json] [--plot FILE.png] [--measurements CSV] [--html FILE]``
    Soft-string torque and drag along the well of the case's ``[well]`` survey: hook load and surface torque
    tripping out and in, rotating off bottom, sliding and drilling; buckling; lock-up; friction calibration.

``CASE`` is a built-in case name (default ``reference``) or the path to a TOML case file.

Conventions for every command (follow them when adding one)
------------------------------------------------------------
- Load the case with :func:`_load`: an invalid case prints its message to stderr and exits with code 2.
- Physics stays out of this module: a command calls the package API and only formats the result.
- ``--json`` prints ``json.dumps(payload, indent=2)`` of SI values, and nothing else, on stdout.
- Human-readable output (rich tables) converts units here, at the edge, into the unit system of the shared
  ``--units`` option (:data:`UnitsOpt`, every command that prints tables or draws figures has it): ``si``
  (kN, m, m/h, kN·m, mm) or ``field`` (klbf, ft, ft/h, kft·lbf, in); frequencies in Hz and speeds in rpm in
  both (:mod:`drillstring.units`). JSON stays SI.
- Progress bars and notes go to stderr, so that stdout holds only the table or the JSON.
- Exit codes: 0 success, 1 a run that failed, 2 invalid input, 130 interrupted (Ctrl-C).
- Heavy modules (SciPy, simulation, Monte Carlo, xarray, Matplotlib) are imported inside the commands
  that need them, so that each command loads only what it uses.
- Every dense linear-algebra problem of a command is small (a few hundred DOFs per mode family), so BLAS
  runs single-threaded here unless the environment says otherwise: its threads only add synchronisation
  (a 2-core machine under load computed the modes 4-40x slower with two threads).
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")  # before NumPy loads BLAS (see the module docstring)

import json  # noqa: E402
import math  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import TYPE_CHECKING, Annotated, Any, NoReturn  # noqa: E402

import numpy as np  # noqa: E402
import typer  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.markup import escape  # noqa: E402
from rich.progress import (  # noqa: E402
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table  # noqa: E402

from drillstring._version import __version__  # noqa: E402
from drillstring.case import Case, CaseError, builtin_cases, load_case  # noqa: E402
from drillstring.dynamics.indicators import STICK_SPEED_RATIO  # noqa: E402
from drillstring.units import display_unit, unit_system  # noqa: E402
from drillstring.stochastic import (  # noqa: E402
    DEFAULT_BASE_SAMPLES,
    DEFAULT_MAP_TOP_SPEED,
    DEFAULT_MAP_WEIGHT_ON_BIT,
    DEFAULT_SAMPLES,
    DEFAULT_SEED,
    DEFAULT_SIGMA,
)

if TYPE_CHECKING:
    from drillstring.buckling import BucklingMargin

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
        return unit_system(value)
    except ValueError as error:
        if value is None and ctx.params.get("as_json"):
            typer.echo(f"note: {error}; ignored, --json output is SI", err=True)
            return "si"
        raise typer.BadParameter(str(error)) from None


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


# ---------------------------------------------------------------------------------------------------------
# drillstring cases
# ---------------------------------------------------------------------------------------------------------


TEndOption = Annotated[
    float | None, typer.Option("--t-end", help="Simulated time [s] (default: the case's simulation.t_end).")
]


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
def static(case: CaseArg = "reference", as_json: JsonOpt = False, units: UnitsOpt = None) -> None:
    """The prestressed static state: weight, weight-on-hook, weight-on-bit, neutral point, critical
    weight-on-bit (lateral buckling), axial force."""
    from drillstring import api

    the_case = _load(case)
    try:
        state, margin = api.static(the_case)
    except ValueError as error:  # a model too large to solve (modal.DENSE_FALLBACK_MEMORY), as `modes` says
        _fail(str(error))
    x = np.asarray(state.mesh.nodes, dtype=float)
    n = np.asarray(state.axial_force, dtype=float)
    if as_json:
        _print_json(
            {
                "weight": float(state.weight),
                "weight_on_hook": float(state.weight_on_hook),
                "weight_on_bit": float(state.weight_on_bit),
                "neutral_point_height": float(state.neutral_point_height),
                "critical_weight_on_bit": margin.critical_weight_on_bit,
                "axial_force": [[float(xi), float(ni)] for xi, ni in zip(x, n)],
            }
        )
        return

    console = _console()
    force, length = display_unit("force", units), display_unit("length", units)
    summary = Table(title=escape(f"Static state: case {the_case.name!r}"), title_justify="left")
    summary.add_column("quantity")
    summary.add_column("value", justify="right")
    summary.add_column("unit")
    summary.add_row("weight", f"{force(state.weight):,.2f}", force.label)
    summary.add_row("weight-on-hook", f"{force(state.weight_on_hook):,.2f}", force.label)
    summary.add_row("weight-on-bit", f"{force(state.weight_on_bit):,.2f}", force.label)
    summary.add_row("neutral point above the bit", f"{length(state.neutral_point_height):,.2f}", length.label)
    summary.add_row("critical weight-on-bit (lateral buckling)",
                    f"{force(margin.critical_weight_on_bit):,.2f}", force.label)
    summary.add_row("string length", f"{length(state.mesh.length):,.1f}", length.label)
    console.print(summary)
    console.print(escape(_buckling_note(margin, units)), soft_wrap=True)

    forces = Table(title="Axial force N (tension > 0)", title_justify="left")
    forces.add_column("where")
    forces.add_column(escape(f"x [{length.label}]"), justify="right")
    forces.add_column(escape(f"above bit [{length.label}]"), justify="right")
    forces.add_column(escape(f"N [{force.label}]"), justify="right")
    for label, position in _axial_force_landmarks(the_case, x):
        # N is continuous and linear inside each element, so interpolation between nodes is exact.
        value = float(np.interp(position, x, n))
        height = state.mesh.length - position
        forces.add_row(escape(label), f"{length(position):,.1f}", f"{length(height):,.1f}", f"{force(value):,.2f}")
    console.print(forces)
    console.print(escape(f"{len(x)} nodes; full profile: drillstring static {case} --json"), soft_wrap=True)


def _buckling_note(margin: BucklingMargin, units: str) -> str:
    """One line: the lateral buckling margin of the case at its weight-on-bit."""
    force = display_unit("force", units)
    critical, wob, kn = force(margin.critical_weight_on_bit), force(margin.weight_on_bit), force.label
    if margin.buckled:
        return (f"BUCKLED: weight-on-bit {wob:,.2f} {kn} exceeds the critical {critical:,.2f} {kn}; the straight "
                "string is statically unstable (lowest lateral mode has ω² < 0).")
    return (f"Lateral buckling at weight-on-bit {critical:,.2f} {kn}: margin {critical - wob:,.2f} {kn} "
            f"({critical / wob:.2f} × the case's {wob:,.2f} {kn}).")


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
    units: UnitsOpt = None,
) -> None:
    """The lowest natural frequencies [Hz] of the prestressed string, per mode family."""
    from drillstring import api

    the_case = _load(case)
    try:
        found, margin = api.modes(the_case, count=count)
    except ValueError as error:
        _fail(str(error))
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
        "Prestress (geometric stiffness) and drilling fluid included; a negative frequency is an unstable "
        "mode, -sqrt(|ω²|)/2π.",
        _buckling_note(margin, units),
    ):
        console.print(escape(note), soft_wrap=True)


# ---------------------------------------------------------------------------------------------------------
# drillstring campbell
# ---------------------------------------------------------------------------------------------------------


@app.command()
def campbell(
    case: CaseArg = "reference",
    top_speed: Annotated[
        str | None, typer.Option("--top-speed", help="Rotary speeds: FROM:TO:N, a list a,b,c, or one value; bare "
                                                     "numbers in rpm, or with units (default 5 rpm:300 rpm:60).")
    ] = None,
    blades: Annotated[
        int | None, typer.Option("--blades", help="Blades (or cones) of the bit: the n× excitation line "
                                                  "(default 3).")
    ] = None,
    plot: Annotated[Path | None, typer.Option("--plot", help="Write the diagram as a PNG figure.")] = None,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Campbell diagram: natural frequencies of each family against rotary speed (prestress, drilling fluid,
    gyroscopic forward/backward whirl), the 1× and blade excitation lines, the critical speeds and the
    case's operating speed.

    Its table and figure are in rpm and Hz, the same in both unit systems: --units is accepted (and checked,
    as $DRILLSTRING_UNITS is) like on every command, and changes nothing here."""
    the_case = _load(case)
    if plot is not None:
        _check_output("--plot", plot)
    from drillstring import api

    columns = (TextColumn("Campbell diagram: lateral whirl solved exactly at {task.completed} speeds, "
                          "interpolated between them"), TimeElapsedColumn())
    try:
        with Progress(*columns, console=_err_console(), transient=True) as bar:
            task = bar.add_task("campbell", total=None)
            diagram = api.campbell(the_case, top_speed=top_speed, blades=blades, default_unit="rpm",
                                   progress=lambda done, total: bar.update(task, completed=done))
    except KeyboardInterrupt:
        _fail("interrupted", EXIT_INTERRUPTED)
    except ValueError as error:
        _fail(str(error).replace("top_speed = ", "--top-speed = ").replace("blades = ", "--blades = "))
    payload = diagram.to_dict()
    if plot is not None:
        from drillstring.plots import plot_campbell

        plot_campbell(payload, plot, f"Campbell diagram: case {the_case.name!r}")
        payload["figure"] = str(plot)
    if as_json:
        _print_json(payload)
        return
    _print_campbell(the_case.name, diagram, plot)


def _print_campbell(name: str, diagram, plot: Path | None) -> None:
    from drillstring.critical_speeds import BHA_SHARE

    console = _console()
    speeds = diagram.speeds * _RPM
    orders = ", ".join(f"{k}×" for k in diagram.orders)
    console.print(escape(f"Campbell diagram: case {name!r}, {len(speeds)} speeds {speeds[0]:g}–{speeds[-1]:g} rpm, "
                         f"lines {orders}, frequencies up to {diagram.max_frequency:.2f} Hz"), soft_wrap=True)
    rows: dict[tuple, dict] = {}
    skipped = 0
    for c in diagram.critical_speeds:
        if c.family == "lateral" and c.bha_energy_share < BHA_SHARE:
            skipped += 1
            continue
        row = rows.setdefault((c.family, c.mode, c.order), {"share": c.bha_energy_share})
        row[c.whirl or "speed"] = c.speed * _RPM
        if c.whirl != "backward":
            row["frequency"] = c.frequency
    table = Table(title="Critical speeds (excitation line × natural frequency)", title_justify="left")
    for title in ("line", "family", "mode", "frequency [Hz]", "critical speed [rpm]", "backward whirl [rpm]",
                  "BHA energy"):
        table.add_column(escape(title), justify="left" if title in ("line", "family") else "right")
    operating = diagram.operating_speed * _RPM if diagram.operating_speed else None
    ordered = sorted(rows.items(), key=lambda item: min(v for k, v in item[1].items() if k in ("speed", "forward",
                                                                                           "backward")))
    for (family, mode, order), row in ordered:
        main = row.get("speed", row.get("forward"))
        table.add_row(f"{order}×", family, str(mode), f"{row['frequency']:.3f}",
                      "" if main is None else f"{main:.1f}" + (" fwd" if family == "lateral" else ""),
                      f"{row['backward']:.1f}" if "backward" in row else "",
                      "" if row["share"] is None else f"{row['share']:.0%}")
    console.print(table)
    notes = [f"lateral: the BHA modes (at least {BHA_SHARE:.0%} of the kinetic energy below the top section); "
             f"{skipped} crossings with drill-pipe lateral modes are in --json."]
    if operating:
        below = [r for (_, r) in ordered if max(v for k, v in r.items() if k in ("speed", "forward", "backward"))
                 <= operating]
        above = [r for (_, r) in ordered if min(v for k, v in r.items() if k in ("speed", "forward", "backward"))
                 > operating]
        near = []
        if below:
            near.append(f"{max(r.get('speed', r.get('forward', 0.0)) for r in below):.1f} rpm below")
        if above:
            near.append(f"{min(r.get('speed', r.get('forward', math.inf)) for r in above):.1f} rpm above")
        notes.append(f"Operating speed {operating:.1f} rpm; nearest critical speeds: {', '.join(near) or 'none'}.")
    notes.append("Axial and torsional frequencies do not depend on the rotary speed in the linear model; gyroscopic "
                 "terms split each lateral pair into forward and backward whirl.")
    notes.extend(diagram.notes)
    if plot is not None:
        notes.append(f"Figure: {plot}")
    for note in notes:
        console.print(escape(note), soft_wrap=True)


# ---------------------------------------------------------------------------------------------------------
# drillstring stability
# ---------------------------------------------------------------------------------------------------------

#: Lateral modes listed in the stability table (all of them in --json).
_STABILITY_LATERAL_ROWS = 4


@app.command()
def stability(
    case: CaseArg = "reference",
    boundary: Annotated[bool, typer.Option(
        "--boundary", help="Also find the stability boundary along the weight-on-bit at the case's top speed "
                           "(the weight-on-bit where the leading growth rate crosses 0).")] = False,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Steady drilling (closed form) and its linear stability: eigenvalues of the reduced model
    linearised about it, bit–rock law included.

    A mode with a positive growth rate grows from any small perturbation of steady drilling: the string
    then settles into a self-excited vibration (the torsional one, through the bit–rock law). With
    --boundary, the weight-on-bit at which that happens (a Hopf bifurcation), everything else fixed.
    """
    the_case = _load(case)
    from drillstring import api

    try:
        result = api.stability(the_case)
        found = api.stability_boundary(the_case) if boundary else None
    except ValueError as error:  # no steady drilling (the law gives no penetration)
        _fail(str(error))
    payload = result.to_dict()
    if boundary:
        payload["boundary"] = found
    if as_json:
        _print_json(payload)
        return
    steady = payload["steady_state"]
    console = _console()
    table = Table(title=escape(f"Steady drilling: case {the_case.name!r}"), title_justify="left")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("unit")
    rop, torque, force = (display_unit(k, units) for k in ("rate_of_penetration", "torque", "force"))
    table.add_row("rate of penetration", f"{rop(steady['rate_of_penetration']):,.3f}", rop.label)
    table.add_row("bit speed", f"{steady['bit_speed'] * _RPM:,.2f}", "rpm")
    table.add_row("torque on bit", f"{torque(steady['torque_on_bit']):,.3f}", torque.label)
    table.add_row("force on bit", f"{force(steady['force_on_bit']):,.3f}", force.label)
    if "delay" in steady:
        table.add_row("depth of cut per blade", f"{steady['depth_of_cut'] * 1e3:,.3f}", "mm")
        table.add_row("delay (one blade passage)", f"{steady['delay']:,.4f}", "s")
    drive = payload.get("top_drive")
    if drive:
        tuned = set(drive["tuned"])
        mark = {name: " (tuned)" if name in tuned else "" for name in ("proportional_gain", "integral_gain")}
        table.add_row(escape(f"top drive: {drive['controller']}, inertia"), f"{drive['inertia']:,.1f}", "kg·m²")
        table.add_row("proportional gain" + mark["proportional_gain"], f"{drive['proportional_gain']:,.1f}",
                      "N·m·s/rad")
        table.add_row("integral gain" + mark["integral_gain"], f"{drive['integral_gain']:,.1f}", "N·m/rad")
        table.add_row("pipe impedance Z_p", f"{drive['pipe_impedance']:,.2f}", "N·m·s/rad")
        if "filter_frequency" in drive:
            table.add_row("high-pass corner" + (" (tuned)" if "filter_frequency" in tuned else ""),
                          f"{drive['filter_frequency']:.4f}", "rad/s")
    console.print(table)
    title = ("Characteristic roots of the linearised delay system (sorted by frequency)" if result.delay
             else "Eigenvalues of the linearised model (sorted by frequency)")
    modes_table = Table(title=title, title_justify="left")
    for column in ("family", "frequency [Hz]", "damping ratio [%]", "growth rate [1/s]",
                   "energy a/t/l [%]", "note"):
        modes_table.add_column(column, justify="left" if column in ("family", "note") else "right")
    lateral_shown = 0
    hidden = 0
    for mode in result.modes:
        if mode.family == "lateral":
            if lateral_shown >= _STABILITY_LATERAL_ROWS and mode.growth_rate < 0:
                hidden += 1
                continue
            lateral_shown += 1
        modes_table.add_row(mode.family, f"{mode.frequency:.4f}", f"{100 * mode.damping_ratio:.2f}",
                            f"{mode.growth_rate:.4g}", _shares_text(mode.shares),
                            ", ".join(n for n, on in (("UNSTABLE", mode.growth_rate > 0), ("mixed", mode.mixed),
                                                            ("beyond the basis", mode.beyond_basis)) if on))
    console.print(modes_table)
    families = Table(title="Leading root of each family", title_justify="left")
    for column in ("family", "frequency [Hz]", "growth rate [1/s]", "energy a/t/l [%]", "family stable"):
        families.add_column(column, justify="left" if column in ("family", "family stable") else "right")
    for family, mode in result.leading_by_family.items():
        if mode is None:
            families.add_row(family, "-", "-", "-", "no root")
            continue
        families.add_row(family, f"{mode.frequency:.4f}", f"{mode.growth_rate:.4g}", _shares_text(mode.shares),
                         "yes" if result.family_stable(family) else "NO")
    console.print(families)
    if hidden:
        console.print(escape(f"+ {hidden} more (stable) lateral modes: drillstring stability {case} --json"),
                      soft_wrap=True)
    if result.steady_state.note:
        console.print(escape(f"Warning: {result.steady_state.note}."), soft_wrap=True)
    leading = result.leading
    if result.stable:
        console.print(escape(f"Steady drilling is stable: slowest decay {leading.growth_rate:.4g} 1/s "
                             f"({leading.family}, {leading.frequency:.4f} Hz)."), soft_wrap=True)
    else:
        console.print(escape(
            f"Steady drilling is UNSTABLE: the {leading.family} mode at {leading.frequency:.4f} Hz grows at "
            f"{leading.growth_rate:.4g} 1/s (e-folding time {1 / leading.growth_rate:.3g} s); the string "
            f"settles into a self-excited vibration."), soft_wrap=True)
    if boundary:
        console.print(escape(_boundary_line(found, units)), soft_wrap=True)


def _shares_text(shares: dict | None) -> str:
    """The energy shares (axial/torsional/lateral) of a root in percent, e.g. ``98/2/0``."""
    if not shares:
        return "-"
    return "/".join(f"{100 * shares[f]:.0f}" for f in ("axial", "torsional", "lateral"))


def _boundary_line(found: dict, units: str | None = None) -> str:
    """One line on the stability boundary along the weight-on-bit, forces in the unit system ``units``."""
    at = f"at the top speed {found['top_speed'] * _RPM:.4g} rpm"
    force = display_unit("force", units)
    if found["weight_on_bit"] is None:
        return (f"Stability boundary {at}: the leading growth rate does not cross 0 between 0 and the string's "
                f"weight (weight-on-bit {force(found['nominal_weight_on_bit']):,.2f} {force.label}: "
                f"{found['nominal_growth_rate']:.4g} 1/s)")
    wob, nominal = found["weight_on_bit"], found["nominal_weight_on_bit"]
    return (f"Stability boundary {at}: weight-on-bit {force(wob):,.2f} {force.label} (steady drilling unstable "
            f"above it); the case's {force(nominal):,.2f} {force.label} is {force(abs(nominal - wob)):,.2f} "
            f"{force.label} {'above' if nominal > wob else 'below'} it (growth rate "
            f"{found['nominal_growth_rate']:.4g} 1/s)")


# ---------------------------------------------------------------------------------------------------------
# drillstring simulate
# ---------------------------------------------------------------------------------------------------------


def _run_numbers(ds, t_transient: float) -> dict[str, Any]:
    """Summary numbers of one run (SI): the drilling indicators after the transient
    (:func:`~drillstring.dynamics.indicators.drilling_indicators`), maximum radial displacement and gap
    per probe, impacts and solver statistics."""
    from drillstring.dynamics.indicators import drilling_indicators

    t = np.asarray(ds["time"].values, dtype=float)
    top = float(ds.attrs.get("top_speed", np.nan))
    radial = np.asarray(ds["radial_displacement"].values, dtype=float)
    steady = t >= t_transient - 1e-9 * max(1.0, t_transient)
    x = np.atleast_1d(np.asarray(ds["x"].values, dtype=float))
    gap = np.atleast_1d(np.asarray(ds["gap"].values, dtype=float))

    def largest(values: np.ndarray) -> float | None:
        finite = values[np.isfinite(values)]
        return float(finite.max()) if finite.size else None

    radial_max = [largest(radial[:, j]) for j in range(radial.shape[1])] if radial.ndim == 2 else []

    def steady_range(name: str) -> tuple[float | None, float | None]:
        values = np.asarray(ds[name].values, dtype=float)[steady] if name in ds else np.zeros(0)
        values = values[np.isfinite(values)]
        return (float(values.min()), float(values.max())) if values.size else (None, None)

    contact = np.asarray(ds["contact_force"].values, dtype=float) if "contact_force" in ds else np.zeros(0)
    indicators = drilling_indicators(t, ds["rate_of_penetration"].values, ds["bit_speed"].values, top,
                                     t_transient, ds["force_on_bit"].values)
    return {
        **indicators,
        "quill_speed_min": steady_range("quill_speed")[0], "quill_speed_max": steady_range("quill_speed")[1],
        "surface_torque_min": steady_range("surface_torque")[0],
        "surface_torque_max": steady_range("surface_torque")[1],
        "max_radial_displacement": radial_max,
        "gap": [float(g) for g in gap],
        "probe_x": [float(v) for v in x],
        "impacts": int(ds.attrs.get("impacts", 0)),
        "max_contact_force": largest(contact),
        "mean_contact_force": (float(np.nanmean(contact[steady])) if contact.size and steady.any() else None),
        "contact_time_fraction": (float(np.mean(contact[steady] > 0)) if contact.size and steady.any() else None),
        "n_rhs": int(ds.attrs.get("solver_n_rhs", 0)),
        "n_accepted": int(ds.attrs.get("solver_n_accepted", 0)),
        "n_rejected": int(ds.attrs.get("solver_n_rejected", 0)),
        "wall_time": float(ds.attrs.get("solver_wall_time", np.nan)),
        "compile_time": float(ds.attrs.get("solver_compile_time", 0.0)),
        "compiled": bool(ds.attrs.get("solver_compiled", False)),
        "t_transient": float(t_transient),
        "t_end": float(t[-1]) if t.size else 0.0,
        "top_speed": top,
        "status": str(ds.attrs.get("status", "")),
    }


def _fmt(value: float | None, spec: str, scale: float = 1.0) -> str:
    return "–" if value is None else format(value * scale, spec)


def _simulation_table(name: str, numbers: dict[str, Any], units: str) -> Table:
    t_tr = numbers["t_transient"]
    rop, force, small, length = (display_unit(k, units)
                                 for k in ("rate_of_penetration", "force", "small_length", "length"))
    table = Table(
        title=escape(f"Simulation: case {name!r}, t = 0 to {numbers['t_end']:g} s"), title_justify="left"
    )
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("unit")
    table.add_row(escape(f"mean rate of penetration (t ≥ {t_tr:g} s)"),
                  _fmt(numbers["mean_rate_of_penetration"], ",.3f", rop.scale), rop.label)
    table.add_row(escape(f"bit speed min / max (t ≥ {t_tr:g} s)"),
                  f"{_fmt(numbers['bit_speed_min'], ',.2f', _RPM)} / {_fmt(numbers['bit_speed_max'], ',.2f', _RPM)}",
                  "rpm")
    table.add_row(escape(f"bit speed oscillation (max − min) / 2Ω (t ≥ {t_tr:g} s)"),
                  _fmt(numbers["bit_speed_oscillation"], ".3f"), "")
    table.add_row(
        escape(f"stick time fraction (bit below {STICK_SPEED_RATIO:.0%} of {numbers['top_speed'] * _RPM:g} rpm)"),
        _fmt(numbers["stick_time_fraction"], ".1%"), "",
    )
    table.add_row(escape(f"bit bounce fraction (off the rock, t ≥ {t_tr:g} s)"),
                  _fmt(numbers["bit_bounce_fraction"], ".1%"), "")
    table.add_row(escape(f"quill speed min / max (t ≥ {t_tr:g} s)"),
                  f"{_fmt(numbers['quill_speed_min'], ',.2f', _RPM)} / {_fmt(numbers['quill_speed_max'], ',.2f', _RPM)}",
                  "rpm")
    torque = display_unit("torque", units)
    table.add_row(escape(f"surface torque min / max (t ≥ {t_tr:g} s)"),
                  f"{_fmt(numbers['surface_torque_min'], ',.2f', torque.scale)} / "
                  f"{_fmt(numbers['surface_torque_max'], ',.2f', torque.scale)}", torque.label)
    for x, r, gap in zip(numbers["probe_x"], numbers["max_radial_displacement"], numbers["gap"]):
        table.add_row(escape(f"max radial displacement at x = {length(x):g} {length.label} / gap"),
                      f"{_fmt(r, ',.3f', small.scale)} / {small(gap):,.1f}", small.label)
    table.add_row("impacts on the borehole", f"{numbers['impacts']:,}", "")
    table.add_row("largest contact force", _fmt(numbers["max_contact_force"], ",.1f", force.scale), force.label)
    table.add_row(escape(f"mean contact force / time in contact (t ≥ {t_tr:g} s)"),
                  f"{_fmt(numbers['mean_contact_force'], ',.3f', force.scale)} {force.label} / "
                  f"{_fmt(numbers['contact_time_fraction'], '.1%')}", "")
    table.add_row("right-hand-side evaluations", f"{numbers['n_rhs']:,}", "")
    table.add_row("steps accepted / rejected", f"{numbers['n_accepted']:,} / {numbers['n_rejected']:,}", "")
    table.add_row("solver wall time", f"{numbers['wall_time']:,.2f}", "s")
    if numbers["compiled"]:
        table.add_row("kernel compilation (first run only)", f"{numbers['compile_time']:,.2f}", "s")
    return table


@app.command()
def simulate(
    case: CaseArg = "reference",
    t_end: TEndOption = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="NetCDF file of the observables.")] = Path(
        "simulation.nc"
    ),
    plot: Annotated[Path, typer.Option("--plot", help="PNG file of the six-panel figure (ROP, bit speed, radial "
                                                      "displacement, TOB, whirl orbit, contact force).")] = Path(
        "simulation.png"
    ),
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """One drilling run: ROP, bit speed, torque- and force-on-bit, radial displacements, whirl, contact.

    Writes the observables to NetCDF and a six-panel figure (with the whirl orbit at the probe and the
    contact force), then prints a summary: impacts on the borehole and contact forces too. After the transient
    (t >= min(10 s, t_end/2)): the bit-speed oscillation (max − min)/(2 × top speed) and the fraction of the time
    the bit turns slower than 10 % of the top speed (stick). A run
    that stops early still writes what it computed, reports where it stopped and exits with code 1.
    """
    the_case = _load(case)
    window = _run_window(the_case, t_end)
    t_final = window.t_end
    _check_output("--out", out)
    _check_output("--plot", plot)
    if Path(out).resolve() == Path(plot).resolve():
        _fail(f"--out and --plot are the same file ({out}): give two file names")

    from drillstring import api
    from drillstring.dynamics.simulate import SimulationError
    from drillstring.files import NotARegularFile
    from drillstring.plots import plot_run
    from drillstring.results import write_netcdf

    failure: SimulationError | None = None
    columns = (TextColumn("simulating"), BarColumn(), TextColumn("{task.completed:.2f} / {task.total:g} s"),
               TimeElapsedColumn(), TextColumn("left"), TimeRemainingColumn())
    try:
        with Progress(*columns, console=_err_console()) as bar:
            task = bar.add_task("simulating", total=t_final)
            try:
                ds = api.simulate(the_case, t_end=t_final,
                                  progress=lambda t: bar.update(task, completed=min(float(t), t_final)))
            except SimulationError as error:
                failure = error
                ds = error.dataset
    except ValueError as error:  # refused before the run (a model too large to build), as `modes` says
        _fail(str(error))
    except KeyboardInterrupt:
        _fail("interrupted: nothing was written", EXIT_INTERRUPTED)

    try:
        netcdf = write_netcdf(ds, out)
        figure = plot_run(ds, plot, units=units) if ds.sizes.get("time", 0) else None  # probe nearest 1560 m
    except OSError as error:  # disk full, no permission: the run is lost, the old files are left as they were
        from drillstring.files import write_error_message

        _fail(write_error_message(error), EXIT_RUN_FAILED)
    except NotARegularFile as error:  # an output that became a device or FIFO during the run
        _fail(str(error), EXIT_RUN_FAILED)
    numbers = _run_numbers(ds, window.transient)
    numbers["netcdf"] = str(netcdf)
    numbers["figure"] = None if figure is None else str(figure)
    if failure is not None:
        numbers["message"] = str(failure)
    if as_json:
        _print_json(numbers)
    else:
        console = _console()
        console.print(_simulation_table(the_case.name, numbers, units))
        written = f"NetCDF: {netcdf}" + ("" if figure is None else f", figure: {figure}")
        console.print(escape(written), soft_wrap=True)
    if failure is not None:
        _fail(f"{failure} (the partial run is in {netcdf})", EXIT_RUN_FAILED)


# ---------------------------------------------------------------------------------------------------------
# drillstring compare
# ---------------------------------------------------------------------------------------------------------

#: Short label of each compared observable (its unit: drillstring.quantities.DISPLAY_KINDS).
_COMPARE_ROWS = {
    "rate_of_penetration": "ROP",
    "bit_speed": "bit speed",
    "torque_on_bit": "torque-on-bit",
    "force_on_bit": "force-on-bit",
    "radial_displacement": "r",
}
_COMPARE_LABELS = {"full": "case 1 (full)", "bit_and_contact": "case 2 (bit–rock + contact)"}


def _compare_table(name: str, differences: dict[str, Any], units: str) -> Table:
    from drillstring.quantities import DISPLAY_KINDS

    table = Table(
        title=escape(f"Case 1 (full) vs case 2 (bit–rock + contact): case {name!r}, "
                     f"t = 0 to {differences['t_end']:g} s"),
        title_justify="left",
        caption=escape(f"Δ = case 1 − case 2; RMS and means relative to case 2; means over "
                       f"t ≥ {differences['t_transient']:g} s."),
        caption_justify="left",
    )
    table.add_column("observable")
    for header in ("max |Δ|", "RMS Δ / RMS", "Δ mean", "Δ mean / mean"):
        table.add_column(escape(header), justify="right")
    for key, entry in differences["observables"].items():
        base = "radial_displacement" if key.startswith("radial_displacement") else key
        label, shown = _COMPARE_ROWS[base], display_unit(DISPLAY_KINDS[base], units)
        scale = shown.scale
        if "probe_x" in entry:
            length = display_unit("length", units)
            label += f" at x = {length(entry['probe_x']):g} {length.label}"
        table.add_row(
            escape(f"{label} [{shown.label}]"),
            _fmt(entry["max_abs_difference"], ".3g", scale),
            _fmt(entry["rms_relative_difference"], ".3g"),
            _fmt(entry["mean_difference"], ".3g", scale),
            _fmt(entry["mean_relative_difference"], ".3g"),
        )
    return table


def _compare_times(differences: dict[str, Any]) -> Table:
    table = Table(title="Wall time of each run (model build and integration)", title_justify="left")
    table.add_column("run")
    table.add_column(escape("wall time [s]"), justify="right")
    table.add_column(escape("solver [s]"), justify="right")
    table.add_column("right-hand sides", justify="right")
    for model, label in _COMPARE_LABELS.items():
        table.add_row(escape(label), f"{differences['wall_time'][model]:,.2f}",
                      f"{differences['solver_wall_time'][model]:,.2f}", f"{differences['n_rhs'][model]:,}")
    table.add_row("ratio case 1 / case 2", _fmt(differences["wall_time"]["ratio"], ".3g"), "", "")
    return table


@app.command()
def compare(
    case: CaseArg = "reference",
    t_end: TEndOption = None,
    plot: Annotated[Path, typer.Option("--plot", help="PNG file of the overlaid six-panel figure.")] = Path(
        "compare.png"
    ),
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Case 1 (full nonlinear model) against case 2 (bit–rock and contact forces only) on the same case.

    Runs both, writes a six-panel figure with both overlaid (case 1 solid, case 2 dashed) and prints, per
    observable, the largest difference, the RMS difference relative to case 2, and the difference of the
    means after the transient (t >= min(10 s, t_end/2)), then the wall time of each run and their ratio.
    A run that stops early ends the command with exit code 1.
    """
    the_case = _load(case)
    window = _run_window(the_case, t_end)
    t_final = window.t_end
    _check_output("--plot", plot)
    if the_case.top_drive.controller != "imposed_speed":
        _fail(f"top_drive.controller = {the_case.top_drive.controller!r}: compare runs case 1, which needs "
              f"\"imposed_speed\" (case 1 with a top drive is not supported yet)")

    from drillstring import api
    from drillstring.dynamics.simulate import SimulationError
    from drillstring.plots import plot_compare

    columns = (TextColumn("{task.description}"), BarColumn(),
               TextColumn("{task.completed:.2f} / {task.total:g} s"), TimeElapsedColumn(), TextColumn("left"),
               TimeRemainingColumn())
    try:
        with Progress(*columns, console=_err_console()) as bar:
            # Case 2's clock starts when its run does (after case 1's), so its time left is its own.
            tasks = {model: bar.add_task(escape(label), total=t_final, start=False)
                     for model, label in _COMPARE_LABELS.items()}
            started: set[str] = set()

            def progress(model: str, t: float) -> None:
                if model not in started:
                    started.add(model)
                    bar.start_task(tasks[model])
                bar.update(tasks[model], completed=min(float(t), t_final))

            full, reduced, differences = api.compare(the_case, t_end=t_final, progress=progress)
    except SimulationError as error:
        which = _COMPARE_LABELS.get(getattr(error, "nonlinear", ""), "a run")
        _fail(f"{which} failed: {error}", EXIT_RUN_FAILED)
    except KeyboardInterrupt:
        _fail("interrupted: nothing was written", EXIT_INTERRUPTED)

    figure = plot_compare(full, reduced, plot, units=units)  # the probe nearest x = 1560 m
    if as_json:
        _print_json({**differences, "figure": str(figure)})
        return
    console = _console()
    console.print(_compare_table(the_case.name, differences, units))
    console.print(_compare_times(differences))
    console.print(escape(f"Figure: {figure}"), soft_wrap=True)


# ---------------------------------------------------------------------------------------------------------
# drillstring study
# ---------------------------------------------------------------------------------------------------------

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


def _declared_laws(param: list[str] | None, correlation: list[str] | None):
    """The ``--param`` laws (None when none is given) and the ``--correlation`` table; a malformed value
    ends the command (exit code 2)."""
    from drillstring.stochastic.parameters import ParameterError
    from drillstring.stochastic.uncertainty import correlation_table, split_assignment, split_correlation

    try:
        laws = None
        if param:
            laws = {}
            for text in param:
                path, spec = split_assignment(text)
                if path in laws:
                    raise ParameterError(f"--param {path} is given twice")
                laws[path] = spec
        table = correlation_table([split_correlation(t) for t in correlation]) if correlation else None
    except ParameterError as error:
        _fail(str(error))
    return laws, table


class _StudyProgress:
    """``progress(done, failed, total)`` for the engine's runs: a rich bar (stderr) of the ``noun``
    (realizations, grid points, runs), failures and time left. The bar starts at the first call, so that
    a run refused before it starts prints no empty bar."""

    def __init__(self, console: Console, noun: str = "realizations") -> None:
        self.console = console
        self.noun = noun
        self.bar: Progress | None = None
        self.task = None

    def __call__(self, done: int, failed: int, total: int) -> None:
        if self.bar is None:
            columns = (TextColumn(escape(self.noun)), BarColumn(), MofNCompleteColumn(),
                       TextColumn("{task.fields[failed]} failed"), TimeElapsedColumn(), TextColumn("left"),
                       TimeRemainingColumn())
            self.bar = Progress(*columns, console=self.console)
            self.bar.start()
            self.task = self.bar.add_task(self.noun, total=total, completed=done + failed, failed=failed)
        else:
            self.bar.update(self.task, completed=done + failed, failed=failed)

    def stop(self) -> None:
        if self.bar is not None:
            self.bar.stop()


def _input_labels(names) -> dict[str, str]:
    """Short table labels of the random inputs: δ_WOH, δ_WOB, or δ(last part of the path) when that is
    unambiguous, else δ(path)."""
    from drillstring.report import INPUT_LABELS

    names = list(names)
    short = {n: n.split(".")[-1] for n in names}
    labels = {}
    for n in names:
        if n in INPUT_LABELS:
            labels[n] = f"δ_{INPUT_LABELS[n]}"
        else:
            unique = sum(1 for m in names if short[m] == short[n]) == 1
            labels[n] = f"δ({short[n] if unique else n})"
    return labels


def _study_table(summary: dict[str, Any]) -> Table:
    """Dispersions per observable over the steady window and over the whole record, in %, and their
    ratios to each input's dispersion."""
    inputs = summary.get("input_dispersion") or {}
    labels = _input_labels(inputs)
    title = "Dispersion: " + ", ".join(f"{labels[k]} = {100 * v:.3g} %" for k, v in inputs.items())
    table = Table(title=escape(title), title_justify="left",
                  caption="whole record: from the first time the mean response leaves 0", caption_justify="left")
    table.add_column("observable")
    table.add_column("window")
    for header in ("mean δ [%]", "max δ [%]", "at t [s]", *(f"mean/{labels[k]}" for k in inputs)):
        table.add_column(escape(header), justify="right")
    for name, entry in summary["observables"].items():
        whole = entry.get("whole_record")
        windows = [(escape(name.replace("_", " ")), f"t ≥ {summary['t_transient']:g} s", entry)]
        if whole:
            windows.append(("", f"whole, t ≥ {whole['t_start']:g} s", whole))
        for label, window, values in windows:
            ratio = values.get("ratio_time_mean", {})
            table.add_row(
                label, escape(window),
                _fmt(values.get("dispersion_time_mean"), ".3g", 100.0),
                _fmt(values.get("dispersion_max"), ".3g", 100.0),
                _fmt(values.get("time_of_max"), ".2f"),
                *(_fmt(ratio.get(k), ".3g") for k in inputs),
            )
    return table


def _buckling_line(summary: dict[str, Any], units: str) -> str:
    """One line on the realizations' lateral buckling margin."""
    b, force = summary["buckling"], display_unit("force", units)
    return (f"Buckled strings (lowest lateral ω² < 0): {b['buckled_realizations']} of {summary['n_samples']} "
            f"realizations; critical weight-on-bit {force(b['critical_weight_on_bit']):,.2f} {force.label}, "
            "probability "
            f"of a buckled draw {b['probability']:.3g}")


def _realizations_table(summary: dict[str, Any], units: str | None = None) -> Table | None:
    """The distributions of the per-realization cycle metrics: mean, std, dispersion, 2.5/50/97.5 %
    quantiles and the nominal run's value, in the unit system ``units``."""
    from drillstring.quantities import METRIC_DISPLAY, metric_unit

    section = summary.get("realizations") or {}
    if not section:
        return None
    caption = ("stick-slip index (max − min)/(2 mean) of the bit speed; MSE (Teale) from the time means; stick: "
               "bit below 10 % of the top speed; oscillation/2Ω: (max − min)/(2 top speed)")
    if "surface_torque_amplitude" in section:
        caption += "; surface torque amplitude: (max − min)/2 of the top drive's surface torque"
    table = Table(title=escape(f"Per realization, after t = {section['t_transient']:g} s (cycle metrics)"),
                  title_justify="left", caption=escape(caption), caption_justify="left")
    for header in ("metric", "unit", "mean", "std", "δ [%]", "2.5 %", "50 %", "97.5 %", "nominal", "n"):
        table.add_column(escape(header), justify="left" if header in ("metric", "unit") else "right")
    for name, (_, label) in METRIC_DISPLAY.items():
        entry = section.get(name)
        if not entry:
            continue
        unit = metric_unit(name, units)
        cells = [_fmt(entry[key], ".4g", unit.scale) for key in ("mean", "std")]
        cells.append(_fmt(entry["dispersion"], ".3g", 100.0))
        cells += [_fmt(entry[key], ".4g", unit.scale) for key in ("q2.5", "q50", "q97.5", "nominal")]
        table.add_row(escape(label), escape(unit.label), *cells, str(entry["n"]))
    return table


def _indicator_line(summary: dict[str, Any], units: str | None = None) -> str | None:
    """One line on the realizations' stick-slip and the linear stability of their steady drilling (forces in
    the unit system ``units``)."""
    section = summary.get("realizations") or {}
    parts = []
    if "stick_slip_realizations" in section:
        parts.append(f"Stick-slip (bit below {STICK_SPEED_RATIO:.0%} of the top speed) in "
                     f"{section['stick_slip_realizations']} of {summary['n_samples']} realizations")
    stability = summary.get("stability") or {}
    if stability.get("unstable_fraction") is not None:
        text = (f"steady drilling unstable (growth rate > 0) in {stability['unstable_realizations']} of "
                f"{stability['realizations_with_growth_rate']} ({100 * stability['unstable_fraction']:.3g} %)")
        families = [f"{family} {entry['unstable_realizations']}" for family, entry in
                    (stability.get("by_family") or {}).items() if entry["realizations_with_roots"]]
        if families:
            text += f" (a growing root per family: {', '.join(families)})"
        boundary = stability.get("boundary") or {}
        if boundary.get("weight_on_bit") is not None:
            force = display_unit("force", units)
            text += (f"; nominal case's boundary at weight-on-bit {force(boundary['weight_on_bit']):,.2f} "
                     f"{force.label} "
                     f"(top speed {boundary['top_speed'] * _RPM:.4g} rpm)")
        parts.append(text)
    return "; ".join(parts) or None


@app.command()
def study(
    case: CaseArg = "reference",
    sigma: Annotated[
        float | None,
        typer.Option("--sigma", help=f"Standard deviation of the weight-on-hook [N] (default {DEFAULT_SIGMA:g} N)."),
    ] = None,
    dispersion: Annotated[
        float | None,
        typer.Option("--dispersion", help="Dispersion σ/mean of the weight-on-hook, instead of --sigma."),
    ] = None,
    param: ParamOption = None,
    correlation: CorrelationOption = None,
    samples: Annotated[int, typer.Option("--samples", "-n", help="Number of realizations n_s (>= 2).")
                       ] = DEFAULT_SAMPLES,
    seed: Annotated[int, typer.Option("--seed", help="Root seed of the random draws (>= 0).")] = DEFAULT_SEED,
    out: Annotated[
        Path,
        typer.Option("--out", "-o", help="Output folder (study.zarr, summary.json, statistics.nc, figures, "
                                         "report.html); rerunning with the same folder resumes. Locked "
                                         "while a study runs on it."),
    ] = Path("study"),
    workers: Annotated[
        int | None,
        typer.Option("--workers", "-j",
                     help="Local worker processes (default: one per core); 1 runs in this process."),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", help="Dask scheduler address (tcp://host:8786) instead of local processes."),
    ] = None,
    t_end: Annotated[
        float | None,
        typer.Option("--t-end", help="Simulated time per realization [s] (default: the case's t_end)."),
    ] = None,
    transient: Annotated[
        float | None,
        typer.Option("--transient", help="Start of the steady regime for the summaries, in s, in [0, t_end) "
                                         "(default: min(10 s, t_end/2))."),
    ] = None,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Monte Carlo study of random case parameters (laws by the Maximum Entropy Principle).

    The random parameters: each --param PATH=LAW (else the case file's uncertainty table), correlated
    normals by --correlation, and the weight-on-hook, Normal of standard deviation --sigma (or
    --dispersion × its mean). Nothing declared: the weight-on-hook Normal with σ = 5 kN.

    Runs the realizations into OUT/study.zarr (an interrupted study resumes with the same command), then
    writes OUT/summary.json, OUT/statistics.nc, the figures convergence.png, envelopes.png, realizations.png and
    dispersion.png, and the self-contained report OUT/report.html. Settings, the output folder and the
    scheduler are checked before anything runs; a second study on the same OUT is refused while one runs.
    """
    the_case = _load(case)
    if sigma is not None and dispersion is not None:
        _fail("give --sigma or --dispersion, not both")
    laws, correlated = _declared_laws(param, correlation)
    if workers is not None and scheduler:
        _fail("give --workers (local processes) or --scheduler (Dask cluster), not both")
    _check_output("--out", out, folder=True)
    outcome = _engine_command(
        out, "study.zarr", "study", "realizations",
        lambda progress, note: _api().monte_carlo_study(
            the_case, out=out, progress=progress, note=note, sigma=sigma, dispersion=dispersion, parameters=laws,
            correlation=correlated, samples=samples, seed=seed, workers=workers, scheduler=scheduler,
            t_end=t_end, transient=transient, units=units))
    _note_resumed(outcome.already, samples, "realizations", out / "study.zarr")

    payload = outcome.summary
    if as_json:
        _print_json(payload)
        return
    _print_study(the_case.name, payload, outcome.files, units)


def _api():
    from drillstring import api

    return api


def _engine_command(out: Path, store_name: str, what: str, noun: str, call):
    """Run ``call(progress, note)`` (an API function of the study engine) for a command writing to ``out``:
    the store's lock is taken before loading the engine (a second run on the folder is refused at once),
    a progress bar and notes go to stderr, and every error ends the command with one line: exit 130 when
    interrupted (what finished is saved), 1 for a run that started and failed (an output write that failed:
    disk full, no permission), 2 for refused input (settings, store, scheduler, lock, another kind of run in
    the folder, an output path that is not a regular file). Temporary files left in ``out`` by a killed run
    are removed. A folder created here and left empty is removed."""
    from drillstring.files import LockedError, remove_stale_temporaries, write_error_message
    from drillstring.stochastic import execution
    from drillstring.stochastic.locks import StudyLock, StudyLocked

    err = _err_console()

    def note(text: str) -> None:
        err.print(escape(f"note: {text}"), soft_wrap=True)

    created = not out.exists()
    lock = StudyLock(out / store_name, what=what)
    try:  # taken before loading the engine: a second run on this folder is refused at once
        lock.__enter__()
    except StudyLocked as error:
        _fail(str(error))
    if lock.note:
        note(lock.note)
    tracker = _StudyProgress(err, noun)
    try:
        remove_stale_temporaries(out)
        try:
            return call(tracker, note)
        finally:
            tracker.stop()
    except execution.Interrupted as error:
        _fail(str(error), EXIT_INTERRUPTED)
    except KeyboardInterrupt:
        _fail(f"interrupted; finished {noun} are saved in {out / store_name}; run the same command again to "
              "resume", EXIT_INTERRUPTED)
    except (execution.WorkersLost, _api().StudyFailed) as error:
        _fail(str(error), EXIT_RUN_FAILED)
    except OSError as error:  # an output write that failed: disk full, no permission, read-only filesystem
        _fail(write_error_message(error, f"finished {noun} are kept in {out / store_name}"), EXIT_RUN_FAILED)
    except (ValueError, LockedError) as error:  # settings, store, scheduler or lock refused
        _fail(str(error))
    finally:
        lock.__exit__(None, None, None)
        if created and out.is_dir() and not any(out.iterdir()):  # refused before anything was written
            out.rmdir()


def _print_study(name: str, payload: dict[str, Any], files: dict[str, Path], units: str) -> None:
    console = _console()
    used = payload["workers"]
    where = f"Dask cluster at {used}" if isinstance(used, str) else f"{used} worker{'s' if used != 1 else ''}"
    timing = f"wall time {payload['wall_time']:,.1f} s ({where})"
    if payload["realizations_this_run"] == 0:
        timing += f"; this run only recomputed the statistics ({payload['wall_time_this_run']:,.2f} s)"
    elif len(payload["sessions"]) > 1:
        timing += f" over {len(payload['sessions'])} runs"
    console.print(escape(
        f"Monte Carlo study: case {name!r}, n_s = {payload['n_samples']} finished"
        f" ({payload['n_failed']} failed), seed {payload['seed']}, {timing}"
    ), soft_wrap=True)
    for path, entry in (payload.get("inputs") or {}).items():
        unit = f" {entry['unit']}" if entry.get("unit") else ""
        console.print(escape(f"  {path}: {entry['law']} (mean {entry['mean']:.6g}{unit}, std "
                             f"{entry['std']:.4g}{unit}, dispersion {_fmt(entry['dispersion'], '.3g', 100.0)} %)"),
                      soft_wrap=True)
    console.print(_study_table(payload))
    metrics = _realizations_table(payload, units)
    if metrics is not None:
        console.print(metrics)
    line = _indicator_line(payload, units)
    if line:
        console.print(escape(line), soft_wrap=True)
    warning = (payload.get("time_convergence") or {}).get("warning")
    if warning:
        console.print(escape(f"warning: {warning}"), soft_wrap=True)
    console.print(escape(_buckling_line(payload, units)), soft_wrap=True)
    if payload["failures"]:
        console.print(escape(f"{len(payload['failures'])} failure(s), causes in {files['summary']}"),
                      soft_wrap=True)
    console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
    console.print(escape(f"Summary: {files['summary']}, statistics: {files['statistics']}"), soft_wrap=True)
    console.print(escape(f"Figures and report: {files['report']}, interactive: {files['interactive']}"),
                  soft_wrap=True)


# ---------------------------------------------------------------------------------------------------------
# drillstring map
# ---------------------------------------------------------------------------------------------------------

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


@app.command("map")
def map_command(
    case: CaseArg = "reference",
    top_speed: Annotated[
        str | None, typer.Option("--top-speed", help="Top speeds: FROM:TO:N (N values from FROM to TO), a list "
                                                     "a,b,c, or one value; bare numbers in rpm, or with units: "
                                                     "'40 rpm:200 rpm:17', '4:21:17 rad/s' (default "
                                                     f"{DEFAULT_MAP_TOP_SPEED}).")
    ] = None,
    weight_on_bit: Annotated[
        str | None, typer.Option("--weight-on-bit", help="Weights-on-bit, same forms; bare numbers in N, or with "
                                                         f"units: '60 kN,80 kN' (default {DEFAULT_MAP_WEIGHT_ON_BIT}).")
    ] = None,
    t_end: RunTEndOption = None,
    transient: TransientOption = None,
    out: OutOption = Path("map"),
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    samples: Annotated[
        int | None,
        typer.Option("--samples", "-n", help="Realizations per point (>= 2): a probabilistic map of the declared "
                                             "uncertainty (default: deterministic, one run per point).")
    ] = None,
    sigma: Annotated[
        float | None,
        typer.Option("--sigma", help="With --samples: standard deviation [N] of the weight-on-hook, Normal around "
                                     f"each point's hook load (default {DEFAULT_SIGMA:g} N when nothing else is "
                                     "declared).")
    ] = None,
    param: ParamOption = None,
    correlation: CorrelationOption = None,
    seed: Annotated[int, typer.Option("--seed", help="With --samples: root seed of the random draws (>= 0).")
                    ] = DEFAULT_SEED,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Operating map over top speed × weight-on-bit: one simulation per grid point.

    With --samples N: N realizations per point of the declared uncertainty (--sigma for the weight-on-hook
    around each point's hook load, --param PATH=LAW and --correlation, else the case file's uncertainty table)
    and per point the probabilities of stick-slip, of a buckled string, of wall impact and of unstable steady
    drilling, with the 2.5/50/97.5 % quantiles of the mean ROP and of the stick-slip index; OUT/probabilities.png
    and OUT/quantiles.png instead of OUT/map.png.

    Per point: mean ROP, bit-speed oscillation, stick time, mean TOB and FOB, mechanical specific energy,
    largest radial displacement and impacts, the leading growth rate of the linear stability of steady
    drilling and the buckling margin. Writes OUT/map.zarr (resumable), OUT/map.nc, OUT/map.json,
    OUT/map.png (contours with the stability boundary, the buckling limit and the points; open circles where
    a run ends in stick-slip although steady drilling is linearly stable), OUT/stability.png (the growth rate
    of the leading torsional, axial and lateral root per point) and OUT/report.html.
    """
    the_case = _load(case)
    if workers is not None and scheduler:
        _fail("give --workers (local processes) or --scheduler (Dask cluster), not both")
    if samples is None and (sigma is not None or param or correlation):
        _fail("--sigma, --param and --correlation declare the uncertainty of a probabilistic map: give --samples N")
    laws, correlated = _declared_laws(param, correlation)
    from drillstring import api

    try:  # bare numbers of the options are in rpm and N; the grid is passed on in SI
        settings = api.map_settings(the_case, top_speed=top_speed, weight_on_bit=weight_on_bit, t_end=t_end,
                                    transient=transient, default_units=("rpm", "N"))
    except ValueError as error:
        _fail(str(error).replace("top_speed = ", "--top-speed = ").replace("weight_on_bit = ", "--weight-on-bit = "))
    _check_output("--out", out, folder=True)
    noun = "grid points" if samples is None else "realizations"
    outcome = _engine_command(
        out, "map.zarr", "map", noun,
        lambda progress, note: api.operating_map(
            the_case, top_speed=settings.top_speed, weight_on_bit=settings.weight_on_bit, t_end=t_end,
            transient=transient, out=out, workers=workers, scheduler=scheduler, progress=progress, note=note,
            samples=samples, sigma=sigma, parameters=laws, correlation=correlated, seed=seed, units=units))
    _note_resumed(outcome.already, settings.points * (samples or 1), noun, out / "map.zarr")
    if as_json:
        _print_json(outcome.summary)
        return
    if samples is None:
        _print_map(the_case.name, outcome.summary, units)
    else:
        _print_probability_map(the_case.name, outcome.summary, units)


def _print_probability_map(name: str, summary: dict[str, Any], units: str) -> None:
    console = _console()
    speeds, weights = summary["top_speed"], summary["weight_on_bit"]
    console.print(escape(
        f"Probabilistic operating map: case {name!r}, {_grid_text(summary, units)}, {summary['samples']} "
        "realizations per "
        f"point: {summary['done']} done, {summary['failed']} failed; wall time {summary['wall_time']:,.1f} s"),
        soft_wrap=True)
    table = Table(title="Probabilities per point and quantiles 50 % (2.5–97.5 %)", title_justify="left",
                  caption="binomial standard errors of the probabilities in map.json and the report",
                  caption_justify="left")
    force, rop = display_unit("force", units), display_unit("rate_of_penetration", units)
    for header in ("rpm", f"WOB [{force.label}]", "n", "P(stick-slip)", "P(buckled)", "P(impact)", "P(unstable)",
                   "P(bounce)", f"mean ROP [{rop.label}]", "stick-slip index"):
        table.add_column(escape(header), justify="right")
    probabilities, quantiles = summary["probabilities"], summary["quantiles"]

    def spread(key: str, i: int, j: int, scale: float) -> str:
        low, mid, high = (quantiles[key][k][i][j] for k in ("2.5", "50", "97.5"))
        return f"{_fmt(mid, '.3g', scale)} ({_fmt(low, '.3g', scale)}–{_fmt(high, '.3g', scale)})"

    for i, speed in enumerate(speeds):
        for j, wob in enumerate(weights):
            cells = [f"{speed * _RPM:g}", f"{force(wob):g}", f"{summary['samples_done'][i][j]}"]
            for key in ("stick_slip_probability", "buckling_probability", "impact_probability",
                        "instability_probability", "bounce_probability"):
                cells.append(_fmt(probabilities[key]["values"][i][j], ".3f"))
            cells += [spread("rate_of_penetration_q", i, j, rop.scale), spread("stick_slip_index_q", i, j, 1.0)]
            table.add_row(*cells)
    console.print(table)
    families = Table(title="Stability per family and coexisting cycles per point", title_justify="left",
                     caption="P(coexisting): stick-slip although the torsional and axial roots of steady drilling "
                             "all decay", caption_justify="left")
    for header in ("rpm", f"WOB [{force.label}]", "P(torsional root grows)", "P(axial root grows)", "P(coexisting)"):
        families.add_column(escape(header), justify="right")
    for i, speed in enumerate(speeds):
        for j, wob in enumerate(weights):
            families.add_row(f"{speed * _RPM:g}", f"{force(wob):g}",
                             *(_fmt(probabilities[key]["values"][i][j], ".3f") for key in (
                                 "torsional_instability_probability", "axial_instability_probability",
                                 "coexistence_probability")))
    console.print(families)
    console.print(escape(f"critical weight-on-bit (lateral buckling, nominal case): "
                         f"{force(summary['critical_weight_on_bit']):,.1f} {force.label}"), soft_wrap=True)
    files = summary.get("files") or {}
    if files:
        console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
        console.print(escape(f"Map: {files['map']}, figures: {files['figure']}, {files['quantiles']}, report: "
                             f"{files['report']}"), soft_wrap=True)


def _grid_text(summary: dict[str, Any], units: str) -> str:
    """'N top speeds (a–b rpm) × M weights-on-bit (c–d kN)' of a map's summary, in the unit system ``units``."""
    speeds, weights, force = summary["top_speed"], summary["weight_on_bit"], display_unit("force", units)
    return (f"{len(speeds)} top speeds ({min(speeds) * _RPM:g}–{max(speeds) * _RPM:g} rpm) × {len(weights)} "
            f"weights-on-bit ({force(min(weights)):.4g}–{force(max(weights)):.4g} {force.label})")


def _print_map(name: str, summary: dict[str, Any], units: str) -> None:
    console = _console()
    force, rop = display_unit("force", units), display_unit("rate_of_penetration", units)
    console.print(escape(
        f"Operating map: case {name!r}, {_grid_text(summary, units)}, "
        f"{summary['done']} points done, {summary['failed']} failed; wall time {summary['wall_time']:,.1f} s"
    ), soft_wrap=True)
    table = Table(title="Highlights", title_justify="left")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("points where steady drilling is linearly stable", f"{summary['linearly_stable_points']}")
    for family, counts in summary.get("linearly_stable_points_by_family", {}).items():
        table.add_row(f"  ... whose {family} roots all decay", f"{counts['stable']} of "
                                                               f"{counts['stable'] + counts['unstable']}")
    table.add_row("points in stick-slip", f"{summary['stick_slip_points']}")
    table.add_row("  ... although steady drilling is linearly stable (coexisting cycles)",
                  f"{summary.get('coexisting_cycle_points', 0)}")
    table.add_row("points without steady drilling (no penetration)", f"{summary['points_without_steady_drilling']}")
    table.add_row("critical weight-on-bit (lateral buckling)",
                  f"{force(summary['critical_weight_on_bit']):,.1f} {force.label}")
    best = summary.get("largest_rate_of_penetration")
    if best:
        pressure = display_unit("pressure", units)
        table.add_row("largest mean ROP", f"{rop(best['mean_rate_of_penetration']):.2f} {rop.label} at "
                                          f"{best['top_speed'] * _RPM:.0f} rpm, {force(best['weight_on_bit']):.0f} "
                                          f"{force.label}")
        table.add_row("  its bit-speed oscillation / MSE", f"{best['bit_speed_oscillation']:.3f} / "
                                                          f"{pressure(best['mechanical_specific_energy']):,.0f} "
                                                          f"{pressure.label}")
    console.print(table)
    files = summary.get("files") or {}
    if files:
        console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
        console.print(escape(f"Map: {files['map']}, figures: {files['figure']}, {files['stability']}, report: {files['report']}, "
                             f"interactive: {files['interactive']}"), soft_wrap=True)


# ---------------------------------------------------------------------------------------------------------
# drillstring sensitivity
# ---------------------------------------------------------------------------------------------------------


@app.command("sensitivity")
def sensitivity_command(
    case: CaseArg = "reference",
    param: ParamOption = None,
    samples: Annotated[
        int, typer.Option("--samples", "-n", help="Base samples N, a power of 2 (>= 8): N(k + 2) runs for k "
                                                   "parameters; indices also at N/4 and N/2 (convergence).")
    ] = DEFAULT_BASE_SAMPLES,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the Sobol' sequence and the bootstrap (>= 0).")] = 0,
    t_end: RunTEndOption = None,
    transient: TransientOption = None,
    out: OutOption = Path("sensitivity"),
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Global sensitivity: first-order and total Sobol' indices (Saltelli design, SALib estimators,
    bootstrap confidence intervals) of the time-mean ROP, bit-speed oscillation, mean TOB and FOB and the
    standard deviations in time of ROP, TOB and FOB.

    The parameters: each --param PATH=LAW (independent laws), else the case file's uncertainty table.
    Writes OUT/sensitivity.zarr (resumable), OUT/sensitivity.json (per output: S1, ST, their intervals,
    per parameter; the convergence at N/4, N/2, N), OUT/sobol.png, OUT/sobol_convergence.png and
    OUT/report.html.
    """
    the_case = _load(case)
    laws, _ = _declared_laws(param, None)
    if workers is not None and scheduler:
        _fail("give --workers (local processes) or --scheduler (Dask cluster), not both")
    _check_output("--out", out, folder=True)
    from drillstring import api

    outcome = _engine_command(
        out, "sensitivity.zarr", "sensitivity", "runs",
        lambda progress, note: api.sensitivity(
            the_case, parameters=laws, samples=samples, seed=seed, t_end=t_end, transient=transient, out=out,
            workers=workers, scheduler=scheduler, progress=progress, note=note, units=units))
    _note_resumed(outcome.already, outcome.payload["runs"], "runs", out / "sensitivity.zarr")
    if as_json:
        _print_json(outcome.payload)
        return
    _print_sensitivity(the_case.name, outcome.payload)


def _print_sensitivity(name: str, payload: dict[str, Any]) -> None:
    from drillstring.plots import OUTPUT_TITLES, short_labels

    console = _console()
    console.print(escape(
        f"Global sensitivity: case {name!r}, N = {payload['base_samples']} ({payload['runs']} runs, "
        f"{payload['failed_runs']} failed), wall time {payload['wall_time']:,.1f} s"), soft_wrap=True)
    for path, law in payload["parameters"].items():
        console.print(escape(f"  {path}: {law}"), soft_wrap=True)
    parameters = list(payload["parameters"])
    labels = short_labels(parameters)
    level = payload["confidence_level"]
    table = Table(title=escape(f"Sobol' indices (± half-width of the {level:.0%} interval)"), title_justify="left",
                  caption="change: largest change of an index from N/4 to N/2, N/2 to N", caption_justify="left")
    table.add_column("output")
    table.add_column("parameter")
    for header in ("S1", "ST"):
        table.add_column(header, justify="right")
    table.add_column("change", justify="right")

    def cell(value, ci) -> str:
        if value is None:
            return "–"
        half = None if not ci or None in ci else (ci[1] - ci[0]) / 2
        return f"{value:.3f}" + ("" if half is None else f" ± {half:.3f}")

    for output, entry in payload["outputs"].items():
        change = entry["convergence"]["max_change"]
        for k, parameter in enumerate(parameters):
            table.add_row(escape(OUTPUT_TITLES.get(output, output)) if k == 0 else "", escape(labels[k]),
                          cell(entry["S1"][parameter], entry["S1_ci"][parameter]),
                          cell(entry["ST"][parameter], entry["ST_ci"][parameter]),
                          (", ".join("–" if c is None else f"{c:.3f}" for c in change)) if k == 0 else "")
    console.print(table)
    files = payload.get("files") or {}
    if files:
        console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
        console.print(escape(f"Indices: {files['indices']}, figures: {files['figure']}, report: "
                             f"{files['report']}, interactive: {files['interactive']}"), soft_wrap=True)


# ---------------------------------------------------------------------------------------------------------
# drillstring torque-drag
# ---------------------------------------------------------------------------------------------------------


@app.command("torque-drag")
def torque_drag_command(
    case: CaseArg = "deviated",
    plot: Annotated[Path | None, typer.Option("--plot", help="PNG of the loads along the string; the well path "
                                              "(FILE-path.png) and the broomstick chart (FILE-broomstick.png) "
                                              "are written beside it.")] = None,
    measurements: Annotated[Path | None, typer.Option("--measurements", help="CSV of measured hook loads "
                            "(bit_depth [unit], operation, hook_load [unit]): calibrate the friction factors.")] = None,
    sigma: Annotated[str | None, typer.Option("--sigma", help="With --measurements: the noise standard deviation "
                     "of a hook load (e.g. '20 kN'; bare numbers in N); default: estimated.")] = None,
    html_page: Annotated[Path | None, typer.Option("--html", help="Interactive page: 3-D well path, loads.")] = None,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Soft-string torque and drag (Johancsik et al. 1984) along the case's well: hook load, surface torque,
    axial and side forces for tripping out and in, rotating off bottom, sliding and drilling; sinusoidal and
    helical buckling; lock-up when sliding; friction factors calibrated from measured hook loads."""
    the_case = _load(case)
    for option, path in (("--plot", plot), ("--html", html_page)):
        if path is not None:
            _check_output(option, path)
    from drillstring.units import FORCE, to_si
    from drillstring.well.analysis import analyse
    from drillstring.well.calibration import read_measurements

    noise = None
    if sigma is not None:
        try:
            noise = to_si(sigma, FORCE)
        except ValueError as error:
            _fail(f"--sigma = {sigma}: {error}")
        if not (math.isfinite(noise) and noise > 0.0):
            _fail(f"--sigma = {sigma}: must be a force > 0 (e.g. '20 kN')")
    try:
        data = read_measurements(measurements) if measurements is not None else None
    except (OSError, ValueError) as error:
        _fail(f"--measurements = {measurements}: {error}")
    try:
        analysis = analyse(the_case, measurements=data, sigma=noise)
    except ValueError as error:
        _fail(str(error))
    payload = analysis.payload
    if plot is not None:
        _torque_drag_figures(the_case, analysis, plot, data, units)
        payload["figures"] = [str(plot), str(plot.with_name(plot.stem + "-path.png")),
                              str(plot.with_name(plot.stem + "-broomstick.png"))]
    if html_page is not None:
        from drillstring.interactive import write_interactive_page
        from drillstring.torque_drag_plots import well_figures

        head = f"<meta charset='utf-8'><title>Torque and drag: {escape(the_case.name)}</title>"
        write_interactive_page(html_page, head, f"<h1>Torque and drag: case {the_case.name}</h1>",
                               well_figures(analysis.trajectory, analysis.results, units=units))
        payload["interactive"] = str(html_page)
    if as_json:
        _print_json(payload)
        return
    force, length, torque = (display_unit(k, units) for k in ("force", "length", "torque"))
    table = Table(title=escape(f"Torque and drag: case {the_case.name!r}"), title_justify="left")
    for column in ("operation", f"hook load [{force.label}]", f"surface torque [{torque.label}]",
                   "sinusoidal buckling", "helical buckling"):
        table.add_column(escape(column), justify="left" if column in ("operation",) else "right")
    for op, row in payload["operations"].items():
        intervals = [", ".join(f"{length(a):,.0f}–{length(b):,.0f}" for a, b in row[key]) or "none"
                     for key in ("sinusoidal_buckling", "helical_buckling")]
        hook = "locked up" if row["locked_up"] else f"{force(row['hook_load']):,.1f}"
        table.add_row(op.replace("_", " "), hook, f"{torque(row['surface_torque']):,.2f}", *map(escape, intervals))
    console = _console()
    console.print(table)
    well = payload["well"]
    console.print(escape(f"Well: {length(well['depth']):,.1f} {length.label} MD, "
                         f"{length(well['true_vertical_depth']):,.1f} {length.label} TVD, {well['stations']} stations; friction factors cased "
                         f"{well['cased_hole_friction']:g}, open hole {well['open_hole_friction']:g}; lock-up when "
                         "sliding: " + ("none" if payload["lockup_depth"] is None else
                                         f"bit at {length(payload['lockup_depth']):,.0f} {length.label}")),
                  soft_wrap=True)
    if "calibration" in payload:
        cal = payload["calibration"]
        console.print(escape("Calibrated friction factors (posterior mean ± std, 90 % interval): " + "; ".join(
            f"{name.replace('_', ' ')} {cal[name]['mean']:.3f} ± {cal[name]['std']:.3f} "
            f"[{cal[name]['interval_90'][0]:.3f}, {cal[name]['interval_90'][1]:.3f}]"
            for name in ("cased_hole_friction", "open_hole_friction"))
            + f"; residual {force(cal['residual_sigma']):,.2f} {force.label} ({cal['noise']})"), soft_wrap=True)
    for key in ("figures", "interactive"):
        if key in payload:
            console.print(escape(f"{key}: {payload[key]}"), soft_wrap=True)


def _torque_drag_figures(case: Case, analysis, plot: Path, measurements, units: str | None) -> None:
    from drillstring.torque_drag_plots import plot_broomstick, plot_torque_drag, plot_well_path
    from drillstring.well.calibration import broomstick, posterior_bands

    shoe = 0.0 if case.well is None else case.well.casing_shoe
    plot_torque_drag(analysis.results, plot, critical=analysis.critical, units=units,
                     title=f"Torque and drag: case {case.name!r}")
    plot_well_path(analysis.trajectory, plot.with_name(plot.stem + "-path.png"), casing_shoe=shoe, units=units,
                   title=f"Well path: case {case.name!r}")
    depths = np.linspace(case.length / 30.0, case.length, 30)
    frictions = (0.1, 0.2, 0.3, 0.4)
    bands = None if analysis.posterior is None else posterior_bands(case, analysis.posterior, depths)
    plot_broomstick(depths, broomstick(case, depths, frictions), frictions,
                    plot.with_name(plot.stem + "-broomstick.png"), measurements=measurements, bands=bands,
                    units=units, title=f"Broomstick chart: case {case.name!r}")


#: Commands that run in their own process only and never use Dask. With Dask installed, xarray imports
#: dask.array and dask.distributed (about 0.4 s of start-up) for ordinary Dataset operations and NetCDF
#: writes; the console script hides Dask from these commands so that xarray treats it as absent.
#: (``study``, ``map`` and ``sensitivity`` may run on a Dask cluster and keep it.)
NO_DASK_COMMANDS = frozenset({"cases", "static", "modes", "stability", "simulate", "compare", "torque-drag"})


def run() -> None:
    """The ``drillstring`` console script: :data:`app`, with Dask hidden from the commands that do not
    use it (:data:`NO_DASK_COMMANDS`). Only the console script does this: a process that imports the
    package (a notebook, the tests) keeps Dask."""
    import sys

    command = next((arg for arg in sys.argv[1:] if not arg.startswith("-")), None)
    if command in NO_DASK_COMMANDS and "dask" not in sys.modules:
        sys.modules["dask"] = None  # `import dask` raises ImportError, find_spec("dask") is None
    app()


if __name__ == "__main__":  # pragma: no cover
    run()
