"""``drillstring campbell``: the Campbell diagram and its critical speeds."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.progress import Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from drillstring.cli.options import (EXIT_INTERRUPTED, _RPM, CaseArg, JsonOpt, UnitsOpt, _check_output, _console,
                                     _err_console, _fail, _load, _print_json, app)
from drillstring.cli.tables import print_table

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
    print_table(console, table)
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
