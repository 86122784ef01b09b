"""``drillstring sensitivity``: Sobol' indices."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from drillstring.cli.engine import _declared_laws, _engine_command
from drillstring.cli.options import (CaseArg, JsonOpt, OutOption, ParamOption, RunTEndOption, SchedulerOption,
                                     TransientOption, UnitsOpt, WorkersOption, _check_output, _console,
                                     _load, _note_resumed, _print_json, app)
from drillstring.cli.tables import print_table
from drillstring.stochastic import DEFAULT_BASE_SAMPLES

@app.command("sensitivity")
def sensitivity_command(
    case: CaseArg = "reference",
    param: ParamOption = None,
    samples: Annotated[
        int, typer.Option("--samples", "-n", help="Base samples N, a power of 2 (>= 8): N(k + 2) runs for k "
                                                   "parameters; indices also at N/4 and N/2 (convergence). Adequate "
                                                   "when each index's interval is narrower than the index: the "
                                                   "reference study's 8 parameters need N = 512 (each index to "
                                                   "about ±0.05); a note says when N is too small.")
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
    _check_output("--out", out, folder=True)
    from drillstring import api

    outcome = _engine_command(
        out, "sensitivity.zarr", "sensitivity", "runs",
        lambda run: api.sensitivity(
            the_case, samples=samples, seed=seed, inputs=api.RandomInputs(parameters=laws),
            window=api.SimulationWindow(t_end=t_end, transient=transient), run=run),
        workers=workers, scheduler=scheduler, units=units)
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
    print_table(console, table)
    _print_sample_notes(console, payload)
    files = payload.get("files") or {}
    if files:
        console.print(escape(f"Store (rerun to resume): {files['store']}"), soft_wrap=True)
        console.print(escape(f"Indices: {files['indices']}, figures: {files['figure']}, report: "
                             f"{files['report']}, interactive: {files['interactive']}"), soft_wrap=True)


def _print_sample_notes(console, payload: dict[str, Any]) -> None:
    """One note per output whose indices say the sample is too small (intervals wider than the indices, negative
    indices, ST below S1, large changes from N/2 to N), then what to do."""
    from drillstring.plots import OUTPUT_TITLES

    flagged = {name: entry["sample_notes"] for name, entry in payload["outputs"].items()
               if entry.get("sample_notes")}
    for name, notes in flagged.items():
        console.print(escape(f"note: {OUTPUT_TITLES.get(name, name)}: {'; '.join(notes)}"))  # wrapped at words
    if flagged:
        console.print(escape(f"note: N = {payload['base_samples']} base samples are too few for these indices: "
                             f"run again with --samples {2 * payload['base_samples']} or more, in another --out "
                             "folder; the reference study needed N = 512"))
