"""``drillstring study``: a Monte Carlo study and its tables."""

from __future__ import annotations

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
from drillstring.units import display_unit

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
    if workers is not None and scheduler:
        _fail("give --workers (local processes) or --scheduler (Dask cluster), not both")
    _check_output("--out", out, folder=True)
    outcome = _engine_command(
        out, "study.zarr", "study", "realizations",
        lambda progress, note: _api().monte_carlo_study(
            the_case, out=out, progress=progress, note=note, sigma=sigma, dispersion=dispersion, parameters=laws,
            correlation=correlated, model=model, samples=samples, seed=seed, workers=workers,
            scheduler=scheduler, t_end=t_end, transient=transient, units=units, stage=progress.stage))
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
    ), soft_wrap=True)
    for path, entry in (payload.get("inputs") or {}).items():
        unit = f" {entry['unit']}" if entry.get("unit") else ""
        console.print(escape(f"  {path}: {entry['law']} (mean {entry['mean']:.6g}{unit}, std "
                             f"{entry['std']:.4g}{unit}, dispersion {_fmt(entry['dispersion'], '.3g', 100.0)} %)"),
                      soft_wrap=True)
    print_table(console, _study_table(payload))
    metrics = _realizations_table(payload, units)
    if metrics is not None:
        print_table(console, metrics)
    line = _indicator_line(payload, units)
    if line:
        console.print(escape(line), soft_wrap=True)
    warning = (payload.get("time_convergence") or {}).get("warning")
    if warning:
        console.print(escape(f"warning: {warning}"), soft_wrap=True)
    start = (payload.get("start") or {}).get("warning")
    if start:
        console.print(escape(f"note: {start}"), soft_wrap=True)
    console.print(escape(_buckling_line(payload, units)), soft_wrap=True)
    if payload["failures"]:
        console.print(escape(f"{len(payload['failures'])} failure(s), causes in {files['summary']}"),
                      soft_wrap=True)
    console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
    console.print(escape(f"Summary: {files['summary']}, statistics: {files['statistics']}"), soft_wrap=True)
    console.print(escape(f"Figures and report: {files['report']}, interactive: {files['interactive']}"),
                  soft_wrap=True)
