"""``drillstring cases``, ``drillstring static`` and ``drillstring modes``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from drillstring.case import Case, CaseError, builtin_cases, load_case
from drillstring.cli.options import CaseArg, JsonOpt, UnitsOpt, _console, _fail, _load, _print_json, app
from drillstring.cli.tables import print_table
from drillstring.units import display_unit

if TYPE_CHECKING:
    from drillstring.buckling import BucklingMargin

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
    weight-on-bit (lateral buckling), axial force. A case with [well]: the stiff string along the well path
    (hook load, side forces, sinusoidal and helical buckling in the deviated hole)."""
    from drillstring import api

    the_case = _load(case)
    try:
        state, margin = api.static(the_case)
    except ValueError as error:  # a model too large to solve (modal.DENSE_FALLBACK_MEMORY), as `modes` says
        _fail(str(error))
    in_well = the_case.well is not None
    x = np.asarray(state.mesh.nodes, dtype=float)
    n = np.asarray(state.axial_force, dtype=float)
    if as_json:
        payload = {
            "weight": float(state.weight),
            "weight_on_hook": float(state.weight_on_hook),
            "weight_on_bit": float(state.weight_on_bit),
            "neutral_point_height": float(state.neutral_point_height),
            "critical_weight_on_bit": margin.critical_weight_on_bit,
            "axial_force": [[float(xi), float(ni)] for xi, ni in zip(x, n)],
        }
        if in_well:
            payload.update(_well_payload(state, margin))
        _print_json(payload)
        return

    console = _console()
    force, length = display_unit("force", units), display_unit("length", units)
    title = f"Static state: case {the_case.name!r}" + (" (stiff string along the well path)" if in_well else "")
    summary = Table(title=escape(title), title_justify="left")
    summary.add_column("quantity")
    summary.add_column("value", justify="right")
    summary.add_column("unit")
    summary.add_row("weight", f"{force(state.weight):,.2f}", force.label)
    summary.add_row("hook load (weight-on-hook)" if in_well else "weight-on-hook",
                    f"{force(state.weight_on_hook):,.2f}", force.label)
    summary.add_row("weight-on-bit", f"{force(state.weight_on_bit):,.2f}", force.label)
    summary.add_row("neutral point above the bit" + (" (along the string)" if in_well else ""),
                    f"{length(state.neutral_point_height):,.2f}", length.label)
    if in_well:
        _well_summary_rows(summary, state, margin, units)
    else:
        summary.add_row("critical weight-on-bit (lateral buckling)",
                        f"{force(margin.critical_weight_on_bit):,.2f}", force.label)
    summary.add_row("string length", f"{length(state.mesh.length):,.1f}", length.label)
    print_table(console, summary)
    for line in (_well_buckling_notes(margin, units) if in_well else [_buckling_note(margin, units)]):
        console.print(escape(line))

    forces = Table(title="Axial force N (tension > 0)" + (" and side force" if in_well else ""),
                   title_justify="left")
    forces.add_column("where")
    forces.add_column(escape(f"{'measured depth' if in_well else 'x'} [{length.label}]"), justify="right")
    forces.add_column(escape(f"above bit [{length.label}]"), justify="right")
    forces.add_column(escape(f"N [{force.label}]"), justify="right")
    if in_well:
        forces.add_column(escape(f"side force [{force.label}]"), justify="right")
        side = state.side_force_with_supports
    for label, position in _axial_force_landmarks(the_case, x):
        # N is continuous and linear inside each element, so interpolation between nodes is exact.
        value = float(np.interp(position, x, n))
        height = state.mesh.length - position
        cells = [f"{length(position):,.1f}", f"{length(height):,.1f}", f"{force(value):,.2f}"]
        if in_well:  # the landmarks are nodes: the wall's, a stabilizer's, the hook's or the bit's force there
            cells.append(f"{force(float(side[int(np.argmin(np.abs(x - position)))])):,.2f}")
        forces.add_row(escape(label), *cells)
    print_table(console, forces)
    console.print(escape(f"{len(x)} nodes; full profile: drillstring static {case} --json"))


def _well_payload(state, margin) -> dict:
    """The JSON keys a case with [well] adds (SI): side forces, and buckling along the path."""
    side = state.side_force_with_supports
    largest = int(np.argmax(side))
    return {
        "model": "stiff string along the well path",
        "hook_load": float(state.hook_load),
        "total_side_force": float(state.total_side_force),
        "max_side_force": float(side[largest]),
        "max_side_force_measured_depth": float(state.measured_depth[largest]),
        "side_force": [[float(xi), float(fi)] for xi, fi in zip(state.measured_depth, side)],
        "buckling": _well_buckling_payload(margin),
    }


def _well_buckling_payload(margin) -> dict:
    """Buckling along the well path (:class:`~drillstring.well.buckling.WellBucklingMargin`) as JSON (SI)."""
    return {
        "criterion": "sinusoidal (Dawson-Paslay; curved hole: Wu-Juvkam-Wold) and helical (Chen-Lin-Cheatham) "
                     "along the well path",
        "critical_weight_on_bit": margin.critical_weight_on_bit,
        "critical_measured_depth": margin.critical_measured_depth,
        "helical_weight_on_bit": margin.helical_weight_on_bit,
        "helical_measured_depth": margin.helical_measured_depth,
        "buckled": margin.buckled,
        "sinusoidal_intervals": [list(i) for i in margin.sinusoidal_intervals],
        "helical_intervals": [list(i) for i in margin.helical_intervals],
    }


def _well_summary_rows(summary: Table, state, margin, units: str) -> None:
    """The side-force and buckling rows of a case with [well]."""
    force, length = display_unit("force", units), display_unit("length", units)
    side = state.side_force_with_supports
    largest = int(np.argmax(side))
    summary.add_row("total side force (wall, stabilizers, bit, hook)", f"{force(state.total_side_force):,.2f}",
                    force.label)
    summary.add_row(escape(f"largest side force on a node (at {length(state.measured_depth[largest]):,.1f} "
                           f"{length.label} MD)"), f"{force(side[largest]):,.2f}", force.label)
    summary.add_row("critical weight-on-bit (sinusoidal buckling in the well)",
                    f"{force(margin.critical_weight_on_bit):,.2f}", force.label)
    summary.add_row("critical weight-on-bit (helical buckling in the well)",
                    f"{force(margin.helical_weight_on_bit):,.2f}", force.label)


def _well_buckling_notes(margin, units: str) -> list[str]:
    """Lines on buckling along the well path (:class:`~drillstring.well.buckling.WellBucklingMargin`)."""
    force, length = display_unit("force", units), display_unit("length", units)
    kn, m = force.label, length.label

    def spans(intervals):
        return ", ".join(f"{length(a):,.1f}-{length(b):,.1f} {m}" for a, b in intervals)

    wob, critical = force(margin.weight_on_bit), force(margin.critical_weight_on_bit)
    if margin.helical_intervals:
        first = f"HELICALLY BUCKLED at measured depths {spans(margin.helical_intervals)}"
    elif margin.buckled:
        first = f"SINUSOIDALLY BUCKLED at measured depths {spans(margin.sinusoidal_intervals)}"
    else:
        first = (f"Buckling along the well path: sinusoidal at weight-on-bit {critical:,.2f} {kn}, first at "
                 f"{length(margin.critical_measured_depth):,.1f} {m} MD: margin {critical - wob:,.2f} {kn} over "
                 f"the case's {wob:,.2f} {kn}")
    return [first + " (Dawson-Paslay; curved hole: Wu & Juvkam-Wold; the stiff string's axial force).",
            "The vertical string's lateral buckling criterion does not apply in the deviated hole."]


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
    """The lowest natural frequencies [Hz] of the prestressed string, per mode family. A case with [well]: the
    modes about the stiff string's static state along the well path, each named by its largest share of
    kinetic energy, and buckling along the path."""
    from drillstring import api

    the_case = _load(case)
    try:
        found, margin = api.modes(the_case, count=count)
    except ValueError as error:
        _fail(str(error))
    in_well = the_case.well is not None
    families = {
        "axial": [float(f) for f in found.axial.frequencies],
        "torsional": [float(f) for f in found.torsional.frequencies],
        "lateral": [float(f) for f in found.lateral.frequencies],
    }
    if as_json:
        _print_json({"model": WELL_MODES_MODEL, **families, **_well_modes_payload(found, margin)}
                    if in_well else families)
        return

    title = f"Natural frequencies: case {the_case.name!r}" + (f" ({WELL_MODES_MODEL})" if in_well else "")
    table = Table(title=escape(title), title_justify="left")
    table.add_column("mode", justify="right")
    for name in families:
        table.add_column(escape(f"{name} [Hz]"), justify="right")
    rows = max(len(v) for v in families.values())
    for i in range(rows):
        cells = [f"{v[i]:.4f}" if i < len(v) else "" for v in families.values()]
        table.add_row(str(i + 1), *cells)
    console = _console()
    print_table(console, table)
    if in_well:
        for note in _well_modes_notes(found, margin, units):
            console.print(escape(note))
        return
    for note in (
        "axial: both ends free; mode 1 is the rigid translation (0 Hz).",
        "torsional: top held, bit free. lateral: one plane of each y/z pair.",
        "Prestress (geometric stiffness) and drilling fluid included; a negative frequency is an unstable "
        "mode, -sqrt(|ω²|)/2π.",
        _buckling_note(margin, units),
    ):
        console.print(escape(note))


#: What the modes of a case with [well] are (the table's title, the JSON's "model").
WELL_MODES_MODEL = "about the stiff string's static state along the well path, families named by kinetic energy"


def _well_modes_payload(found, margin) -> dict:
    """The JSON keys of `modes` for a case with [well] beside the frequencies (SI): each listed mode's
    kinetic-energy shares, and buckling along the path."""
    return {
        "kinetic_energy_share": {name: [[float(e) for e in row] for row in shares]
                                 for name, shares in found.shares.items()},
        "kinetic_energy_share_columns": ["axial", "torsional", "lateral"],
        "modes_solved": int(found.solved),
        "buckling": _well_buckling_payload(margin),
    }


def _well_modes_notes(found, margin, units: str) -> list[str]:
    """The lines under the table of `modes` for a case with [well]."""
    least = min((float(s.max(axis=1).min()) for s in found.shares.values() if len(s)), default=1.0)
    return [(f"Coupled modes of the whole string (the {found.solved} lowest solved), each in the family with the "
             f"largest share of its kinetic energy (axial u, torsional θx, lateral v w θy θz in the nodes' frames; "
             f"the least such share listed: {least:.2f}; --json gives every share)."),
            ("Boundaries: top held across the path and in rotation, bit held across the path, both free along it "
             "(axial mode 1: the slide along the path, 0 Hz only in a straight hole); every lateral mode listed "
             "(the wall and the curvature split the y/z pairs)."),
            ("Prestress (the stiff string's axial force), the wall's linearised springs, stabilizers and drilling "
             "fluid included; a negative frequency is an unstable mode, -sqrt(|ω²|)/2π."),
            *_well_buckling_notes(margin, units)]
