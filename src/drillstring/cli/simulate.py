"""``drillstring simulate`` (one run) and ``drillstring compare`` (case 1 against case 2)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from drillstring.cli.options import (EXIT_INTERRUPTED, EXIT_RUN_FAILED, _RPM, CaseArg, JsonOpt, TEndOption, UnitsOpt,
                                     _check_output, _console, _err_console, _fail, _load, _print_json,
                                     _run_window, app)
from drillstring.cli.tables import _fmt, print_table
from drillstring.dynamics.indicators import STICK_SPEED_RATIO
from drillstring.units import DisplayUnit, display_unit

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
    ranges = {f"{name}_{end}": value for name in ("quill_speed", "surface_torque", *(r[0] for r in _MOTOR_ROWS))
              if name in ds or name in ("quill_speed", "surface_torque")
              for end, value in zip(("min", "max"), steady_range(name))}
    return {
        **indicators,
        **ranges,
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


def _start_window(case, ds, default: float, units: str | None) -> tuple[float, list[str]]:
    """The start of the summaries' window [s] and the notes on the run's start (docs/model.md §8). A ramped
    start's window begins when the bit speed's oscillation has settled, measured on the run
    (:func:`~drillstring.dynamics.simulate.settling_time`), if that is after ``default`` (min(10 s, t_end/2));
    a note says so, or that it never settled; another says when the rate of penetration was negative."""
    from drillstring.dynamics.simulate import start_facts

    t = np.asarray(ds["time"].values, dtype=float)
    if t.size < 3:
        return default, []
    ramp = case.initial.start == "ramp"
    ramp_end = max(case.initial.weight_ramp_time if ramp else 0.0, case.top_drive.ramp_time)
    facts = start_facts(t, {k: ds[k].values for k in ("rate_of_penetration", "force_on_bit", "bit_speed")},
                        default, ramp_end, case.operation.top_speed)
    notes, start = [], default
    if facts.negative_rop_until == facts.negative_rop_until:  # not NaN
        force = display_unit("force", units)
        why = (" the Tucker–Wang law, a law of rates, has the bit back off the rock under a light weight on bit"
               if case.bit_rock.law == "tucker_wang" else " the bit moved up")
        notes.append(f"the rate of penetration is negative until t = {facts.negative_rop_until:.2f} s (force on "
                     f"bit {force(facts.force_on_bit_then):,.3g} {force.label} then):{why} (docs/model.md §8)")
    if ramp and facts.window_before_settled:
        if facts.settled == facts.settled and facts.settled < t[-1]:
            start = facts.settled
            notes.append(f"summaries from t = {start:.2f} s, when the bit speed's oscillation settled after the "
                         f"{ramp_end:g} s ramp (each period's range within 15 % of the last's), not from "
                         f"t = {default:g} s")
        else:
            notes.append(f"the bit speed's oscillation has not settled by t = {t[-1]:g} s (its range per period "
                         f"still changes after the {ramp_end:g} s ramp): the summaries from t = {default:g} s mix "
                         "the start-up with what follows; a longer --t-end shows where it goes")
    return start, notes


#: The observables of a downhole motor: (key in the run's numbers, row label, display kind).
_MOTOR_ROWS = (("motor_speed", "motor speed min / max", "angular_speed"),
               ("motor_torque", "motor torque min / max", "torque"),
               ("differential_pressure", "motor Δp min / max", "pressure"))


def _min_max(numbers: dict[str, Any], key: str, unit, spec: str = ",.2f") -> str:
    """``min / max`` of ``numbers[key + "_min"]``, ``numbers[key + "_max"]`` in the display unit ``unit``."""
    return f"{_fmt(numbers[key + '_min'], spec, unit.scale)} / {_fmt(numbers[key + '_max'], spec, unit.scale)}"


def _simulation_table(name: str, numbers: dict[str, Any], units: str) -> Table:
    """The run's summary for a terminal of 80 columns: three columns (quantity, value, unit), every row after
    the transient (the title says from when); the solver's counts are in :func:`_solver_line`."""
    rpm = DisplayUnit("rpm", _RPM)
    rop, force, small, length, torque = (display_unit(k, units) for k in
                                         ("rate_of_penetration", "force", "small_length", "length", "torque"))
    table = Table(title=escape(f"Simulation: case {name!r}, t = 0 to {numbers['t_end']:g} s; summaries over "
                               f"t ≥ {numbers['t_transient']:g} s"), title_justify="left")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("unit")
    table.add_row("mean rate of penetration", _fmt(numbers["mean_rate_of_penetration"], ",.3f", rop.scale),
                  rop.label)
    table.add_row("bit speed min / max", _min_max(numbers, "bit_speed", rpm), "rpm")
    table.add_row(escape("bit speed oscillation (max − min)/2Ω"), _fmt(numbers["bit_speed_oscillation"], ".3f"), "")
    table.add_row(escape(f"stick time (bit below {STICK_SPEED_RATIO:.0%} of {numbers['top_speed'] * _RPM:g} rpm)"),
                  _fmt(numbers["stick_time_fraction"], ".1%"), "")
    table.add_row("bit bounce time (bit off the rock)", _fmt(numbers["bit_bounce_fraction"], ".1%"), "")
    table.add_row("quill speed min / max", _min_max(numbers, "quill_speed", rpm), "rpm")
    table.add_row("surface torque min / max", _min_max(numbers, "surface_torque", torque), torque.label)
    for key, label, kind in _MOTOR_ROWS:
        if numbers.get(key + "_min") is not None:
            unit = rpm if kind == "angular_speed" else display_unit(kind, units)
            table.add_row(escape(label), _min_max(numbers, key, unit), unit.label)
    for x, r, gap in zip(numbers["probe_x"], numbers["max_radial_displacement"], numbers["gap"]):
        table.add_row(escape(f"max radial displacement / gap at {length(x):,.0f} {length.label}"),
                      f"{_fmt(r, ',.3f', small.scale)} / {small(gap):,.1f}", small.label)
    table.add_row("impacts on the borehole wall", f"{numbers['impacts']:,}", "")
    table.add_row("largest contact force", _fmt(numbers["max_contact_force"], ",.1f", force.scale), force.label)
    table.add_row("mean contact force", _fmt(numbers["mean_contact_force"], ",.3f", force.scale), force.label)
    table.add_row("time in contact", _fmt(numbers["contact_time_fraction"], ".1%"), "")
    return table


def _solver_line(numbers: dict[str, Any]) -> str:
    """One line on the solver: right-hand sides, steps, its wall time and, on a first run, the compilation."""
    line = (f"Solver: {numbers['n_rhs']:,} right-hand sides, {numbers['n_accepted']:,} steps "
            f"({numbers['n_rejected']:,} rejected), {numbers['wall_time']:,.2f} s")
    if numbers["compiled"]:
        line += f"; kernels compiled in {numbers['compile_time']:,.2f} s (first run only)"
    return line + "."


@app.command()
def simulate(
    case: CaseArg = "reference",
    t_end: TEndOption = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="NetCDF file of the observables.")] = Path(
        "simulation.nc"
    ),
    plot: Annotated[Path, typer.Option("--plot", help="PNG file of the six-panel figure (ROP, bit speed, radial "
                                                      "displacement, TOB, whirl orbit, contact force); with "
                                                      "[well], also <name>-well.png: the string in the well "
                                                      "coloured by its contact force.")] = Path(
        "simulation.png"
    ),
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """One drilling run: ROP, bit speed, torque- and force-on-bit, radial displacements, whirl, contact.

    Writes the observables to NetCDF and a six-panel figure (with the whirl orbit at the probe and the
    contact force), then prints a summary: impacts on the borehole and contact forces too. After the transient
    (t >= min(10 s, t_end/2); after a ramped start, from when the bit speed's oscillation has settled if that
    is later, measured on the run, with a note): the bit-speed oscillation (max − min)/(2 × top speed) and the fraction of the time
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
        well_figure = _well_figure(the_case, plot, units)
    except OSError as error:  # disk full, no permission: the run is lost, the old files are left as they were
        from drillstring.files import write_error_message

        _fail(write_error_message(error), EXIT_RUN_FAILED)
    except NotARegularFile as error:  # an output that became a device or FIFO during the run
        _fail(str(error), EXIT_RUN_FAILED)
    t_summary, notes = _start_window(the_case, ds, window.transient, units)
    numbers = _run_numbers(ds, t_summary)
    numbers["start_notes"] = notes
    numbers["netcdf"] = str(netcdf)
    numbers["figure"] = None if figure is None else str(figure)
    numbers["well_figure"] = None if well_figure is None else str(well_figure)
    if failure is not None:
        numbers["message"] = str(failure)
    if as_json:
        _print_json(numbers)
    else:
        console = _console()
        print_table(console, _simulation_table(the_case.name, numbers, units))
        console.print(escape(_solver_line(numbers)))
        for text in notes:
            console.print(escape(f"note: {text}"))
        written = f"NetCDF: {netcdf}" + ("" if figure is None else f", figure: {figure}")
        console.print(escape(written + ("" if well_figure is None else f", the string in the well: {well_figure}")))
    if failure is not None:
        _fail(f"{failure} (the partial run is in {netcdf})", EXIT_RUN_FAILED)


def _well_figure(case, plot: Path, units) -> Path | None:
    """For a case with ``[well]``: the figure of its stiff string in the well, coloured by the contact force per
    node (:func:`~drillstring.outputs.torque_drag_plots.plot_string_in_well`), as ``<plot's stem>-well.png``
    beside ``plot``; None without ``[well]``."""
    if case.well is None:
        return None
    from drillstring.outputs.torque_drag_plots import plot_string_in_well
    from drillstring.well.stiff_string import case_stiff_string

    path = Path(plot).with_name(f"{Path(plot).stem}-well.png")
    return plot_string_in_well(case_stiff_string(case), path, title=f"{case.name}: the string in the well",
                               units=units)


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
    print_table(console, _compare_table(the_case.name, differences, units))
    print_table(console, _compare_times(differences))
    console.print(escape(f"Figure: {figure}"))
