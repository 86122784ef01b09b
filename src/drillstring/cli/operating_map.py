"""``drillstring map``: the operating map, deterministic or probabilistic."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from drillstring.cli.engine import _declared_laws, _engine_command, _model_dispersions
from drillstring.cli.options import (_RPM, CaseArg, CorrelationOption, JsonOpt, OutOption, ParamOption,
                                     RunTEndOption, SchedulerOption, TransientOption, UnitsOpt, WorkersOption,
                                     _check_output, _console, _fail, _load, _note_resumed, _print_json, app)
from drillstring.cli.tables import _fmt, print_table
from drillstring.stochastic import DEFAULT_MAP_TOP_SPEED, DEFAULT_MAP_WEIGHT_ON_BIT, DEFAULT_SEED, DEFAULT_SIGMA
from drillstring.units import display_unit

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
    if samples is None and (sigma is not None or param or correlation):
        _fail("--sigma, --param and --correlation declare the uncertainty of a probabilistic map: give --samples N")
    laws, correlated = _declared_laws(param, correlation)
    laws, model = _model_dispersions(laws)
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
        lambda run: api.operating_map(
            the_case, top_speed=settings.top_speed, weight_on_bit=settings.weight_on_bit, samples=samples, seed=seed,
            inputs=api.RandomInputs(sigma=sigma, parameters=laws, correlation=correlated, model=model),
            window=api.SimulationWindow(t_end=t_end, transient=transient), run=run),
        workers=workers, scheduler=scheduler, units=units)
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
    print_table(console, table)
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
    print_table(console, families)
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
    print_table(console, table)
    files = summary.get("files") or {}
    if files:
        console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
        console.print(escape(f"Map: {files['map']}, figures: {files['figure']}, {files['stability']}, report: {files['report']}, "
                             f"interactive: {files['interactive']}"), soft_wrap=True)
