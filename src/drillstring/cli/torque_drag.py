"""``drillstring torque-drag``: soft-string torque and drag along the case's well."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape
from rich.progress import Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from drillstring.case import Case
from drillstring.cli.options import (EXIT_INTERRUPTED, CaseArg, JsonOpt, UnitsOpt, _check_output, _console,
                                     _err_console, _fail, _load, _print_json, app)
from drillstring.cli.tables import print_table
from drillstring.units import display_unit

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
    for option, path in [("--plot", p) for p in _figure_paths(plot)] + [("--html", html_page)]:
        if path is not None:
            _check_output(option, path)
    from drillstring.units import FORCE, to_si
    from drillstring.well.analysis import analyse
    from drillstring.well.calibration import SIGMA_RANGE, read_measurements

    noise = None
    if sigma is not None:
        try:
            noise = to_si(sigma, FORCE)
        except ValueError as error:
            _fail(f"--sigma = {sigma}: {error}")
        low, high = SIGMA_RANGE
        if not (math.isfinite(noise) and low <= noise <= high):
            _fail(f"--sigma = {sigma}: must be a force within [{low:g}, {high:g}] N (e.g. '20 kN')")
    try:
        data = read_measurements(measurements) if measurements is not None else None
    except (OSError, ValueError) as error:
        _fail(f"--measurements = {measurements}: {error}")
    columns = (TextColumn("Calibrating the friction factors: bit depth {task.completed} of {task.total}"),
               TimeElapsedColumn())
    try:
        with Progress(*columns, console=_err_console(), transient=True, disable=data is None) as bar:
            task = bar.add_task("calibration", total=None)
            analysis = analyse(the_case, measurements=data, sigma=noise,
                               progress=lambda done, total: bar.update(task, completed=done, total=total))
    except KeyboardInterrupt:
        _fail("interrupted", EXIT_INTERRUPTED)
    except ValueError as error:
        _fail(str(error))
    payload = analysis.payload
    if plot is not None:
        _torque_drag_figures(the_case, analysis, plot, data, units)
        payload["figures"] = [str(plot), str(plot.with_name(plot.stem + "-path.png")),
                              str(plot.with_name(plot.stem + "-broomstick.png"))]
    if html_page is not None:
        from drillstring.report import write_torque_drag_page
        from drillstring.outputs.torque_drag_plots import well_figures

        write_torque_drag_page(html_page, title=f"Torque and drag: case {the_case.name}",
                               case_toml=the_case.to_toml(), payload=payload, units=units,
                               interactive=well_figures(analysis.trajectory, analysis.results,
                                                        critical=analysis.critical, units=units))
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
        hook = "locked up" if row["locked_up"] else _shown(row["hook_load"], force, ",.1f")
        table.add_row(op.replace("_", " "), hook, _shown(row["surface_torque"], torque, ",.2f"),
                      *map(escape, intervals))
    console = _console()
    print_table(console, table)
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
    for figure in payload.get("figures", []):
        console.print(escape(f"figure: {figure}"), soft_wrap=True)
    if "interactive" in payload:
        console.print(escape(f"interactive page: {payload['interactive']}"), soft_wrap=True)


def _figure_paths(plot: Path | None) -> tuple[Path, ...]:
    """The figures ``--plot FILE`` writes: FILE, FILE-path.png and FILE-broomstick.png beside it."""
    if plot is None:
        return ()
    return plot, plot.with_name(plot.stem + "-path.png"), plot.with_name(plot.stem + "-broomstick.png")


def _shown(value: float | None, unit, spec: str) -> str:
    """A load in display units; None (JSON null: beyond 1e14 in SI, the friction round the well's bends
    multiplying the tension without bound, as the capstan law says) as "unbounded"."""
    return "unbounded" if value is None else format(unit(value), spec)


def _torque_drag_figures(case: Case, analysis, plot: Path, measurements, units: str | None) -> None:
    from drillstring.outputs.torque_drag_plots import plot_broomstick, plot_torque_drag, plot_well_path
    from drillstring.well.calibration import broomstick, posterior_bands

    shoe = 0.0 if case.well is None else case.well.casing_shoe
    _, path_figure, broomstick_figure = _figure_paths(plot)
    plot_torque_drag(analysis.results, plot, critical=analysis.critical, units=units,
                     title=f"Torque and drag: case {case.name!r}")
    plot_well_path(analysis.trajectory, path_figure, casing_shoe=shoe, units=units,
                   title=f"Well path: case {case.name!r}")
    depths = np.linspace(case.length / 30.0, case.length, 30)
    frictions = (0.1, 0.2, 0.3, 0.4)
    bands = None if analysis.posterior is None else posterior_bands(case, analysis.posterior, depths)
    plot_broomstick(depths, broomstick(case, depths, frictions), frictions,
                    broomstick_figure, measurements=measurements, bands=bands,
                    units=units, title=f"Broomstick chart: case {case.name!r}")
