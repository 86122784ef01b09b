"""``drillstring optimize``: the robust operating point under chance constraints."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from drillstring.cli.engine import _declared_laws, _engine_command, _model_dispersions
from drillstring.cli.options import (CaseArg, CorrelationOption, JsonOpt, OutOption, ParamOption, RunTEndOption,
                                     SchedulerOption, TransientOption, UnitsOpt, WorkersOption, _check_output,
                                     _console, _fail, _load, _note_resumed, _print_json, app)
from drillstring.cli.tables import print_table
from drillstring.stochastic import DEFAULT_SEED
from drillstring.stochastic import MAX_OPTIMIZE_POINTS as MAX_POINTS
from drillstring.stochastic import MAX_OPTIMIZE_SAMPLES as MAX_SAMPLES

#: Bare numbers of --vary: rpm for the top speed, N for forces.
_BARE_UNITS = {"top_speed": "rpm", "operation.top_speed": "rpm"}
#: The settings a refusal names -> the options that set them.
_OPTIONS = {"samples": "--samples", "points": "--points", "initial": "--initial", "batch": "--batch",
            "seed": "--seed", "objective": "--objective", "probability_mean": "--probability-mean"}


def _option_message(message: str) -> str:
    """A refusal of the settings (``"points = 5: must be ..."``) in the options' names (``"--points = 5: ..."``)."""
    name, sep, rest = message.partition(" = ")
    if not (sep and name in _OPTIONS):
        return message
    return f"{_OPTIONS[name]} = {rest.replace('from initial = ', 'from --initial = ')}"


@app.command("optimize")
def optimize_command(
    case: CaseArg = "reference",
    vary: Annotated[
        list[str] | None,
        typer.Option("--vary", "-v", metavar="NAME=LOW:HIGH",
                     help="A decision variable and its bounds: top_speed=60:140 (bare numbers in rpm), "
                          "weight_on_bit='80 kN:120 kN', weight_on_hook=..., proportional_gain=..., integral_gain=... "
                          "or any case path (SI); repeat for several.")
    ] = None,
    objective: Annotated[
        str, typer.Option("--objective", help="rate_of_penetration (expected, maximised), rate_of_penetration_qNN "
                                              "(its NN % quantile, maximised) or mechanical_specific_energy "
                                              "(expected, minimised).")
    ] = "rate_of_penetration",
    constraint: Annotated[
        list[str] | None,
        typer.Option("--constraint", "-c", metavar="EVENT<=P",
                     help="A chance constraint P(EVENT) <= P: EVENT one of stick_slip, buckling, bounce, impact, "
                          "instability, torsional_instability, axial_instability, coexistence, or OUTPUT>VALUE / "
                          "OUTPUT<VALUE (SI), e.g. 'surface_torque_amplitude>8000<=0.01'; repeat for several.")
    ] = None,
    samples: Annotated[int, typer.Option("--samples", "-n", help=f"Realizations per design point (2 to "
                                                                 f"{MAX_SAMPLES}).")] = 8,
    points: Annotated[
        int | None, typer.Option("--points", help=f"Design points in all, from --initial (the initial design alone: "
                                                  f"no point chosen by the surrogates) to {MAX_POINTS} (default "
                                                  "twice --initial).")] = None,
    initial: Annotated[
        int | None, typer.Option("--initial", help=f"Points of the initial design, 2 to {MAX_POINTS} (default 4 per "
                                                   "variable, at least 4).")
    ] = None,
    batch: Annotated[
        int | None,
        typer.Option("--batch", help="Design points chosen together after the initial design, their realizations "
                                     f"run in one pass of the workers (1 to {MAX_POINTS}; default 4).")
    ] = None,
    probability_mean: Annotated[
        str, typer.Option("--probability-mean", help="Prior mean of the probabilities' surrogates: constant, or "
                                                      "linear (a fitted plane, where they return far from data).")
    ] = "constant",
    sigma: Annotated[
        float | None,
        typer.Option("--sigma", help="Standard deviation [N] of the weight-on-hook, Normal around each point's hook "
                                     "load (default 5000 N when nothing else is declared).")
    ] = None,
    param: ParamOption = None,
    correlation: CorrelationOption = None,
    seed: Annotated[int, typer.Option("--seed", help="Root seed of the draws and of the design (>= 0).")
                    ] = DEFAULT_SEED,
    t_end: RunTEndOption = None,
    transient: TransientOption = None,
    out: OutOption = Path("optimize"),
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Robust operating point: the decision variables that maximise the expected ROP (or a quantile of it), or
    minimise the expected MSE, with the probability of each dysfunction below its bound.

    A Gaussian-process surrogate of each output is fitted to probabilistic-map runs (--samples realizations
    of the declared uncertainty per design point) and the points are chosen where the constrained expected
    improvement is largest. Writes OUT/optimize.zarr (resumable), OUT/optimize.json, OUT/optimize.nc and
    OUT/optimize.png (the feasible region, the answer marked) and OUT/report.html. Notes on stderr say when
    the surrogates choose the next points; Ctrl-C stops, and the same command resumes. Infeasible constraints:
    exit code 2 with the least-infeasible point.
    """
    the_case = _load(case)
    if not vary:
        _fail("give at least one decision variable: --vary top_speed=60:140 --vary weight_on_bit='80 kN:120 kN'")
    variables: dict[str, str] = {}
    for text in vary:
        name, sep, bounds = text.partition("=")
        if not sep or not name.strip():
            _fail(f"--vary {text!r}: write NAME=LOW:HIGH, e.g. top_speed=60:140")
        if name.strip() in variables:
            _fail(f"--vary {name.strip()} is given twice")
        variables[name.strip()] = bounds.strip()
    constraints: dict[str, float] = {}
    for text in constraint or []:
        event, sep, bound = text.rpartition("<=")
        try:
            value = float(bound)
        except ValueError:
            value = None
        if not sep or not event.strip() or value is None:
            _fail(f"--constraint {text!r}: write EVENT<=P, e.g. stick_slip<=0.05")
        constraints[event.strip()] = value
    laws, correlated = _declared_laws(param, correlation)
    laws, model = _model_dispersions(laws)
    from drillstring.api.settings import RandomInputs, SearchOptions, SimulationWindow
    from drillstring.operating_point import optimization_settings, optimize

    bare = {name: _BARE_UNITS.get(name, "") for name in variables}
    try:  # refused before the engine starts
        arguments = dict(
            variables=variables, objective=objective, constraints=constraints, seed=seed, default_units=bare,
            search=SearchOptions(samples=samples, points=points, initial=initial, batch=batch,
                                 probability_mean=probability_mean),
            inputs=RandomInputs(sigma=sigma, parameters=laws, correlation=correlated, model=model),
            window=SimulationWindow(t_end=t_end, transient=transient))
        settings = optimization_settings(the_case, **arguments)
    except (TypeError, ValueError) as error:
        _fail(_option_message(str(error)))
    _check_output("--out", out, folder=True)
    outcome = _engine_command(
        out, "optimize.zarr", "optimization", "realizations",
        lambda run: optimize(the_case, **arguments, run=run), workers=workers, scheduler=scheduler, units=units)
    _note_resumed(outcome.already, settings.realizations, "realizations", out / "optimize.zarr")
    if as_json:
        _print_json(outcome.summary)
    else:
        _print_answer(the_case, outcome.summary, units)
    if not outcome.feasible:
        _fail(f"constraints infeasible: no design point meets {_constraints_text(outcome.summary)} in the "
              f"surrogate; least-infeasible point {_point_text(the_case, outcome.summary, units)} "
              f"({_probabilities_text(outcome.summary)}); results in {out}")


def _point_text(case, summary: dict[str, Any], units) -> str:
    from drillstring.outputs.optimize_plots import decision_unit

    values = summary["recommended"]["values"]
    parts = []
    for path, value in zip(summary["variables"], values):
        unit = decision_unit(case, path, units)
        parts.append(f"{path.rsplit('.', 1)[-1]} = {unit(value):.4g} {unit.label}")
    return ", ".join(parts)


def _constraints_text(summary: dict[str, Any]) -> str:
    return ", ".join(f"P({c['event']}) <= {c['bound']:g}" for c in summary["recommended"]["constraints"])


def _probabilities_text(summary: dict[str, Any]) -> str:
    return ", ".join(f"P({c['event']}) = {c['probability']:.3g}" for c in summary["recommended"]["constraints"])


def _print_answer(case, summary: dict[str, Any], units) -> None:
    from drillstring.outputs.optimize_plots import objective_unit

    console = _console()
    best = summary["recommended"]
    shown, label = objective_unit(summary["objective"], units)
    state = "recommended" if summary["feasible"] else "least-infeasible"
    console.print(escape(
        f"Robust operating point: case {summary['case']!r}, {summary['points']} design points × {summary['samples']} "
        f"realizations ({summary['realizations']} runs), wall time {summary['wall_time']:,.1f} s"), soft_wrap=True)
    console.print(escape(f"{state} point: {_point_text(case, summary, units)} (design point {best['point']})"),
                  soft_wrap=True)
    console.print(escape(
        f"objective {summary['objective']} ({label}): {shown(best['objective']):.4g} ± "
        f"{shown(best['objective_standard_error']):.2g} {shown.label} (Monte Carlo, {best['realizations']} "
        f"realizations); surrogate {shown(best['surrogate_objective']):.4g} ± "
        f"{shown(best['surrogate_objective_standard_deviation']):.2g}"), soft_wrap=True)
    if best["constraints"]:
        _print_constraints(console, best["constraints"])
    files = summary.get("files") or {}
    if files:
        console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
        console.print(escape(f"Results: {files['summary']}, {files['results']}, figure: {files['figure']}, "
                             f"report: {files['report']}"), soft_wrap=True)


def _print_constraints(console, constraints: list[dict[str, Any]]) -> None:
    table = Table(title="Chance constraints at the answer", title_justify="left",
                  caption="confidence: P(probability <= bound) from the binomial and surrogate errors together",
                  caption_justify="left")
    for header in ("event", "bound", "P (Monte Carlo)", "binomial s.e.", "surrogate", "surrogate s.d.",
                   "combined s.d.", "confidence", "met"):
        table.add_column(escape(header), justify="right")
    for c in constraints:
        table.add_row(escape(c["event"]), f"{c['bound']:g}", f"{c['probability']:.3f}",
                      f"{c['binomial_standard_error']:.3f}", f"{c['surrogate_mean']:.3f}",
                      f"{c['surrogate_standard_deviation']:.3f}", f"{c['combined_standard_deviation']:.3f}",
                      f"{c['confidence']:.2f}", "yes" if c["met"] else "no")
    print_table(console, table)
