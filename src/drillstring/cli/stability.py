"""``drillstring stability``: steady drilling and the linear stability about it."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from drillstring.cli.options import _RPM, CaseArg, JsonOpt, UnitsOpt, _console, _fail, _load, _print_json, app
from drillstring.cli.tables import print_table
from drillstring.units import display_unit

#: Roots of each family listed in the stability table, the lowest in frequency, besides every growing one
#: (all of them with --all and in --json): with the two other tables the output fits a screen.
_STABILITY_ROWS_PER_FAMILY = 4


@app.command()
def stability(
    case: CaseArg = "reference",
    boundary: Annotated[bool, typer.Option(
        "--boundary", help="Also find the stability boundary along the weight-on-bit at the case's top speed "
                           "(the weight-on-bit where the leading growth rate crosses 0).")] = False,
    every_root: Annotated[bool, typer.Option(
        "--all", help=f"List every root, not only the {_STABILITY_ROWS_PER_FAMILY} lowest of each family and the "
                      "growing ones.")] = False,
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
    if "motor_speed" in steady:  # a downhole motor: the bit turns at the string's speed above it plus its own
        pressure = display_unit("pressure", units)
        table.add_row("string speed above the motor", f"{steady['string_speed'] * _RPM:,.2f}", "rpm")
        table.add_row("motor speed", f"{steady['motor_speed'] * _RPM:,.2f}", "rpm")
        table.add_row("motor torque", f"{torque(steady['motor_torque']):,.3f}", torque.label)
        table.add_row("motor differential pressure", f"{pressure(steady['differential_pressure']):,.3f}",
                      pressure.label)
    drive = payload.get("top_drive")
    if drive and "controller" not in drive:  # another top boundary: its own summary (SI), whatever it holds
        table.add_row(escape(f"top boundary: {drive.get('top_boundary', '?')}"), "", "")
        for key, value in drive.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                table.add_row(escape(key.replace("_", " ")), f"{value:,.6g}", "SI")
    elif drive:
        tuned = set(drive.get("tuned", ()))
        mark = {name: " (tuned)" if name in tuned else "" for name in ("proportional_gain", "integral_gain")}
        table.add_row(escape(f"top drive: {drive['controller']}, inertia"), f"{drive['inertia']:,.1f}", "kg·m²")
        table.add_row("proportional gain" + mark["proportional_gain"], f"{drive['proportional_gain']:,.1f}",
                      "N·m·s/rad")
        table.add_row("integral gain" + mark["integral_gain"], f"{drive['integral_gain']:,.1f}", "N·m/rad")
        table.add_row("pipe impedance Z_p", f"{drive['pipe_impedance']:,.2f}", "N·m·s/rad")
        if "filter_frequency" in drive:
            table.add_row("high-pass corner" + (" (tuned)" if "filter_frequency" in tuned else ""),
                          f"{drive['filter_frequency']:.4f}", "rad/s")
    print_table(console, table)
    title = ("Characteristic roots of the linearised delay system (sorted by frequency)" if result.delay
             else "Eigenvalues of the linearised model (sorted by frequency)")
    modes_table = Table(title=title, title_justify="left")
    for column in ("family", "frequency [Hz]", "damping ratio [%]", "growth rate [1/s]",
                   "energy a/t/l [%]", "note"):
        modes_table.add_column(column, justify="left" if column in ("family", "note") else "right")
    shown: dict[str, int] = {}
    hidden = 0
    for mode in result.modes:
        if not every_root and shown.get(mode.family, 0) >= _STABILITY_ROWS_PER_FAMILY and mode.growth_rate < 0:
            hidden += 1
            continue
        shown[mode.family] = shown.get(mode.family, 0) + 1
        modes_table.add_row(mode.family, f"{mode.frequency:.4f}", f"{100 * mode.damping_ratio:.2f}",
                            f"{mode.growth_rate:.4g}", _shares_text(mode.shares),
                            ", ".join(n for n, on in (("UNSTABLE", mode.growth_rate > 0), ("mixed", mode.mixed),
                                                      ("beyond the basis", mode.beyond_basis)) if on))
    print_table(console, modes_table)
    if any(mode.beyond_basis for mode in result.modes):
        console.print(escape(_beyond_line(result.convergence, len(result.modes))))
    families = Table(title="Leading root of each family", title_justify="left")
    for column in ("family", "frequency [Hz]", "growth rate [1/s]", "energy a/t/l [%]", "family stable"):
        families.add_column(column, justify="left" if column in ("family", "family stable") else "right")
    for family, mode in result.leading_by_family.items():
        if mode is None:
            families.add_row(family, "-", "-", "-", "no root")
            continue
        families.add_row(family, f"{mode.frequency:.4f}", f"{mode.growth_rate:.4g}", _shares_text(mode.shares),
                         "yes" if result.family_stable(family) else "NO")
    print_table(console, families)
    if hidden:
        console.print(escape(f"+ {hidden} more (decaying) roots: drillstring stability {case} --all (or --json)"))
    if result.steady_state.note:
        console.print(escape(f"Note: {result.steady_state.note}."))
    leading = result.leading
    if result.stable:
        console.print(escape(f"Steady drilling is stable: slowest decay {leading.growth_rate:.4g} 1/s "
                             f"({leading.family}, {leading.frequency:.4f} Hz)."))
    else:
        console.print(escape(
            f"Steady drilling is UNSTABLE: the {leading.family} mode at {leading.frequency:.4f} Hz grows at "
            f"{leading.growth_rate:.4g} 1/s (e-folding time {1 / leading.growth_rate:.3g} s); the string "
            f"settles into a self-excited vibration."))
    if boundary:
        console.print(escape(_boundary_line(found, units)))


def _beyond_line(convergence: dict | None, roots: int) -> str:
    """What "beyond the basis" means in the table: the convergence check's rule, or the share rule without it."""
    if convergence is None:
        return ("beyond the basis: a root with half or more of its modal energy in the basis's attachment modes "
                "(a root of the basis's cut-off); left out of the leading root and the verdict.")
    unchecked = "" if convergence["checked"] >= roots else "; unchecked roots by their energy in the attachment modes"
    return (f"beyond the basis: no root within {100 * convergence['growth_tolerance']:.0f} % of its growth rate on "
            f"twice the basis (a root of the cut-off), left out of the verdict{unchecked} (--json: convergence).")


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
