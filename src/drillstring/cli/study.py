"""``drillstring study``: a Monte Carlo study and its tables."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from drillstring.cli.engine import _api, _declared_laws, _engine_command, _model_dispersions
from drillstring.cli.options import (_RPM, CaseArg, CorrelationOption, JsonOpt, ParamOption, UnitsOpt,
                                     _check_output, _console, _fail, _load, _note_resumed, _print_json, app)
from drillstring.cli.tables import _fmt, print_table
from drillstring.dynamics.indicators import STICK_SPEED_RATIO
from drillstring.stochastic import DEFAULT_SAMPLES, DEFAULT_SEED, DEFAULT_SIGMA
from drillstring.units import display_unit, significant

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
    """Dispersions per observable over the steady window, in %, and their ratios to each input's dispersion:
    one row per observable (the whole record's are in ``--json`` and the report)."""
    inputs = summary.get("input_dispersion") or {}
    labels = _input_labels(inputs)
    title = (f"Dispersion over t ≥ {summary['t_transient']:g} s: "
             + ", ".join(f"{labels[k]} = {100 * v:.3g} %" for k, v in inputs.items()))
    table = Table(title=escape(title), title_justify="left")
    table.add_column("observable")
    for header in ("mean δ [%]", "max δ [%]", "at t [s]", *(f"mean/{labels[k]}" for k in inputs)):
        table.add_column(escape(header), justify="right")
    for name, values in summary["observables"].items():
        ratio = values.get("ratio_time_mean", {})
        table.add_row(
            escape(name.replace("_", " ")),
            _fmt(values.get("dispersion_time_mean"), ".3g", 100.0),
            _fmt(values.get("dispersion_max"), ".3g", 100.0),
            _fmt(values.get("time_of_max"), ".2f"),
            *(_fmt(ratio.get(k), ".3g") for k in inputs),
        )
    return table


def _buckling_line(summary: dict[str, Any], units: str | None = None) -> str:
    """The realizations' lateral buckling as a result: how many drew a weight-on-bit above the critical one
    (their string bows to the wall near the bit), and the probability of such a draw; forces in ``units``."""
    b, n, force = summary["buckling"], summary["n_samples"], display_unit("force", units)
    critical = f"{force(b['critical_weight_on_bit']):,.2f} {force.label}"
    count, chance = b["buckled_realizations"], _chance(b["probability"])
    if "criterion" in b:  # a case with [well]: two criteria, each said for what it is
        draws = (f"a draw puts the weight-on-bit above the critical {critical} ({b['criterion']}) {chance}"
                 if b["probability"] > 0.0 else
                 f"no draw puts the weight-on-bit above the critical {critical} ({b['criterion']})")
        return (f"Buckling: {draws}; {count} of {n} realizations have a buckled string in the reduced model "
                "(lowest lateral ω² < 0: a straight string's lateral dynamics under the well's axial force, not "
                "the curved hole's).")
    if count:
        return (f"Buckling: {count} of {n} realizations ({100 * count / n:.3g} %) drew a weight-on-bit above "
                f"the critical {critical}: their string buckles laterally near the bit and bows to the "
                f"borehole wall (a draw does so {chance}). Lower the weight-on-bit or its spread to avoid it; "
                "drillstring static CASE gives the margin.")
    if b["probability"] > 0.0:
        return (f"Buckling: none of the {n} realizations buckled; a draw puts the weight-on-bit above the "
                f"critical {critical} (lateral buckling near the bit) {chance}.")
    return f"Buckling: none of the {n} realizations can buckle (critical weight-on-bit {critical})."


def _chance(probability: float) -> str:
    """``probability`` in words: "with probability 0.235 % (1 in 425)"."""
    if probability >= 1.0:
        return "always"
    text = f"with probability {100 * probability:.3g} %"
    return text + (f" (1 in {1 / probability:,.0f})" if 0.0 < probability < 0.1 else "")


def _sig(value: float | None, scale: float = 1.0) -> str:
    """``value × scale`` with 4 significant digits (:func:`drillstring.units.significant`: ``59,860``,
    ``0.09439``), ``–`` for a missing value."""
    return "–" if value is None or not math.isfinite(value) else significant(value * scale)


def _realizations_table(summary: dict[str, Any], units: str | None = None) -> Table | None:
    """The distributions of the per-realization cycle metrics for a terminal of 80 columns: mean, dispersion,
    2.5 and 97.5 % quantiles and the nominal run's value, in the unit system ``units`` (the standard
    deviation, the median and the counts are in ``--json`` and the report). A metric no realization has (no
    period without a cycle) is named in the caption; one fewer realizations have says how many."""
    from drillstring.quantities import METRIC_DISPLAY, metric_unit

    section = summary.get("realizations") or {}
    if not section:
        return None
    n = summary["n_samples"]
    caption = ("stick-slip index (max − min)/(2 mean) of the bit speed; MSE (Teale) from the time means; stick: "
               "bit below 10 % of the top speed; oscillation/2Ω: (max − min)/(2 top speed)")
    if "surface_torque_amplitude" in section:
        caption += "; surface torque amplitude: (max − min)/2 of the top drive's surface torque"
    table = Table(title=escape(f"Per realization, after t = {section['t_transient']:g} s ({n} realizations)"),
                  title_justify="left")
    for header in ("metric", "unit", "mean", "δ [%]", "2.5 %", "97.5 %", "nominal"):
        table.add_column(escape(header), justify="left" if header in ("metric", "unit") else "right")
    missing = []
    for name, (_, label) in METRIC_DISPLAY.items():
        entry = section.get(name)
        if not entry:
            continue
        if not entry["n"]:
            missing.append(label)
            continue
        unit = metric_unit(name, units)
        if entry["n"] < n:
            label += f" (n = {entry['n']})"
        table.add_row(escape(label), escape(unit.label), _sig(entry["mean"], unit.scale),
                      _fmt(entry["dispersion"], ".3g", 100.0),
                      *(_sig(entry[key], unit.scale) for key in ("q2.5", "q97.5", "nominal")))
    if missing:
        caption += f"; no value in any realization: {', '.join(missing)}"
    table.caption, table.caption_justify = escape(caption), "left"
    return table


def _indicator_line(summary: dict[str, Any], units: str | None = None) -> str | None:
    """The realizations' stick-slip and the linear stability of their steady drilling, in plain sentences
    (forces in the unit system ``units``)."""
    section = summary.get("realizations") or {}
    n = summary["n_samples"]
    parts = []
    if "stick_slip_realizations" in section:
        count = section["stick_slip_realizations"]
        parts.append(f"Stick-slip: the bit stalls (below {STICK_SPEED_RATIO:.0%} of the top speed) in "
                     f"{count} of {n} realizations.")
    stability = summary.get("stability") or {}
    if stability.get("unstable_fraction") is not None:
        families = [f"{family} {entry['unstable_realizations']}" for family, entry in
                    (stability.get("by_family") or {}).items()
                    if entry["realizations_with_roots"] and entry["unstable_realizations"]]
        text = (f"Steady drilling is unstable in {stability['unstable_realizations']} of "
                f"{stability['realizations_with_growth_rate']} realizations"
                + (f" ({', '.join(families)})" if families else "")
                + ": those vibrate on their own, however small the disturbance")
        boundary = stability.get("boundary") or {}
        if boundary.get("weight_on_bit") is not None:
            force = display_unit("force", units)
            text += (f"; the nominal case turns unstable above a weight-on-bit of "
                     f"{force(boundary['weight_on_bit']):,.2f} {force.label} at {boundary['top_speed'] * _RPM:.4g} "
                     "rpm")
        parts.append(text + ".")
    return " ".join(parts) or None


def _convergence_line(summary: dict[str, Any]) -> str | None:
    """Whether the dispersions have settled, as a fact: with the record's length (the largest dispersion
    between the last two record lengths, :func:`~drillstring.stochastic.analysis.time_convergence`) and, when
    it moved more than that threshold over the second half of the realizations, about how many realizations
    would bring it below (a Monte Carlo change falls as 1/√n)."""
    found = summary.get("time_convergence") or {}
    threshold = found.get("threshold", 0.02)
    sentences = []
    moving = {name: entry["change"]["dispersion_max"] for name, entry in (found.get("observables") or {}).items()
              if (entry.get("change") or {}).get("dispersion_max") is not None
              and entry["change"]["dispersion_max"] > threshold}
    if moving:
        last = (found["observables"][next(iter(moving))]["windows"])[-2:]
        changes = ", ".join(f"{name.replace('_', ' ')} {100 * change:.2g} %" for name, change in moving.items())
        sentences.append(
            f"Not settled in time: the largest dispersion still changes with the record's length ({changes} "
            f"between records to {last[0]['t_end']:g} s and to {last[1]['t_end']:g} s, more than "
            f"{100 * threshold:g} %); a longer run (--t-end {2 * last[1]['t_end']:g}) shows where it settles.")
    samples = {name: change for name, change in (summary.get("convergence_change_second_half") or {}).items()
               if change is not None and change > threshold}
    if samples:
        n = summary["n_samples"]
        needed = max(math.ceil(n * (change / threshold) ** 2) for change in samples.values())
        worst = ", ".join(f"{name.replace('_', ' ')} {100 * change:.2g} %" for name, change in samples.items())
        sentences.append(f"Not settled in the number of realizations: the dispersions moved over the last half "
                         f"of them ({worst}); about {needed:,} realizations would bring that below "
                         f"{100 * threshold:g} %.")
    return " ".join(sentences) or None


def _inputs_line(path: str, entry: dict[str, Any], units: str | None = None) -> str:
    """One random parameter: its law's kind, mean, standard deviation and dispersion, in the unit system
    ``units`` (:func:`drillstring.units.display_unit_of`); the law as declared too when it was declared with
    its own unit (``normal 100 5 rpm``), else in ``--json`` (an SI law: ``normal 686960.95 5000``)."""
    from drillstring.units import display_unit_of

    unit = display_unit_of(entry.get("unit") or "", units)
    label = f" {unit.label}" if unit.label else ""
    words = str(entry.get("law") or "law").split()
    declared = len(words) > 1 and not re.fullmatch(r"[-+.\w]*=?[-+.\deE]+|inf", words[-1])  # with its own unit
    kind = " ".join(words) if declared else words[0]
    return (f"  {path}: {kind}, mean {_sig(entry['mean'], unit.scale)}{label}, std "
            f"{_sig(entry['std'], unit.scale)}{label} (dispersion {_fmt(entry['dispersion'], '.3g', 100.0)} %)")


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
    --dispersion × its mean). Nothing declared: the weight-on-hook Normal with σ = 5 kN. Model uncertainty
    (random reduced mass, stiffness and damping matrices): --param uncertainty.model.stiffness_dispersion=0.1
    (and mass_dispersion, damping_dispersion), else the case file's [uncertainty.model] table.

    Runs the realizations into OUT/study.zarr (an interrupted study resumes with the same command), then
    writes OUT/summary.json, OUT/statistics.nc, the figures convergence.png, envelopes.png, realizations.png and
    dispersion.png, and the self-contained report OUT/report.html. Settings, the output folder and the
    scheduler are checked before anything runs; a second study on the same OUT is refused while one runs.
    """
    the_case = _load(case)
    if sigma is not None and dispersion is not None:
        _fail("give --sigma or --dispersion, not both")
    laws, correlated = _declared_laws(param, correlation)
    laws, model = _model_dispersions(laws)
    _check_output("--out", out, folder=True)
    outcome = _engine_command(
        out, "study.zarr", "study", "realizations",
        lambda run: _api().monte_carlo_study(
            the_case, inputs=_api().RandomInputs(sigma=sigma, dispersion=dispersion, parameters=laws,
                                                 correlation=correlated, model=model),
            samples=samples, seed=seed, window=_api().SimulationWindow(t_end=t_end, transient=transient), run=run),
        workers=workers, scheduler=scheduler, units=units)
    _note_resumed(outcome.already, samples, "realizations", out / "study.zarr")

    payload = outcome.summary
    if as_json:
        _print_json(payload)
        return
    _print_study(the_case.name, payload, outcome.files, units)


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
    ))
    for path, entry in (payload.get("inputs") or {}).items():
        console.print(escape(_inputs_line(path, entry, units)))
    print_table(console, _study_table(payload))
    metrics = _realizations_table(payload, units)
    if metrics is not None:
        print_table(console, metrics)
    start = (payload.get("start") or {}).get("warning")
    for line in (_indicator_line(payload, units), _buckling_line(payload, units), _convergence_line(payload),
                 f"note: {start}" if start else None):
        if line:
            console.print(escape(line))
    if payload["failures"]:
        console.print(escape(f"{len(payload['failures'])} failure(s), causes in {files['summary']}"))
    console.print(escape(f"Store (rerun to resume): {files['store']}"))
    console.print(escape(f"Summary: {files['summary']}, statistics: {files['statistics']}"))
    console.print(escape(f"Figures and report: {files['report']}, interactive: {files['interactive']}"))
