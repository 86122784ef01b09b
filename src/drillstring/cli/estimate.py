"""``drillstring estimate``: the downhole state from a surface record, with its uncertainty (the ensemble
estimator of :mod:`drillstring.estimation`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape
from rich.progress import Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from drillstring.cli.options import (EXIT_INTERRUPTED, EXIT_RUN_FAILED, CaseArg, JsonOpt, UnitsOpt, _check_output,
                                     _console, _err_console, _fail, _load, _print_json, app)
from drillstring.cli.tables import print_table
from drillstring.units import display_unit


@app.command("estimate")
def estimate_command(
    case: CaseArg = "stick_slip",
    surface: Annotated[Path | None, typer.Option("--surface", help="The surface record (CSV: a time column and "
                       "top speed, surface torque, hook load, block position by name or mnemonic, units in the "
                       "header). Default: the record shipped with a built-in case (stick_slip).")] = None,
    truth: Annotated[Path | None, typer.Option("--truth", help="The hidden truth of a synthetic record, to score "
                     "the estimate (default: the shipped record's).")] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder: estimate.nc, surface.png, downhole.png, "
                                      "report.html.")] = Path("estimate"),
    ensemble_size: Annotated[int | None, typer.Option("--ensemble-size", help="Members of the ensemble "
                             "(default: the case's [estimator] ensemble_size, else 256).")] = None,
    seed: Annotated[int | None, typer.Option("--seed", help="Seed of the estimator's random stream.")] = None,
    as_json: JsonOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Estimate bit speed, torque and force on bit, rate of penetration, the stick-slip index and the bit–rock
    coefficient and weight-on-bit bias in time, with 5–95 % bands, from the surface channels of a record (an
    ensemble Kalman filter on the case's reduced model; faults in the record flagged and never used)."""
    the_case = _load(case)
    _check_output("--out", out, folder=True)
    from drillstring.api.estimates import estimate

    overrides = {key: value for key, value in (("ensemble_size", ensemble_size), ("seed", seed)) if value is not None}
    columns = (TextColumn("Estimating: {task.completed:.1f} s of the record"), TimeElapsedColumn())
    try:
        with Progress(*columns, console=_err_console(), transient=True) as bar:
            task = bar.add_task("estimate", total=None)
            outcome = estimate(the_case, surface, truth=truth, **overrides,
                               progress=lambda t: bar.update(task, completed=t))
    except KeyboardInterrupt:  # before the record's first sample: nothing to keep
        _fail("interrupted", EXIT_INTERRUPTED)
    except (OSError, ValueError) as error:
        _fail(str(error))
    except RuntimeError as error:  # the ensemble diverged before the record's first sample
        _fail(str(error), EXIT_RUN_FAILED)
    payload = _write_outputs(the_case, outcome, out, units)
    if as_json:
        _print_json(payload)
    else:
        _print_summary(the_case, outcome, payload, units)
    stopped = outcome.result.stopped
    if stopped:  # what was computed is written; the exit code says the record was not finished
        _fail(f"{stopped} (the estimate up to there is in {out})",
              EXIT_INTERRUPTED if stopped.startswith("interrupted") else EXIT_RUN_FAILED)


def _write_outputs(case, outcome, out: Path, units: str | None) -> dict:
    """estimate.nc, the two figures and the report page in ``out``; the JSON payload (SI)."""
    from drillstring.outputs.estimate_plots import plot_downhole, plot_surface
    from drillstring.report_estimate import write_estimate_report
    from drillstring.results import write_netcdf

    out.mkdir(parents=True, exist_ok=True)
    result = outcome.result
    dataset = result.to_dataset()
    dataset.attrs["case"] = case.to_toml()
    write_netcdf(dataset, out / "estimate.nc")
    figures = {"Surface channels: measured and predicted": plot_surface(
                   dataset, out / "surface.png", units=units, title=f"Surface channels: case {case.name!r}"),
               "Downhole estimate and parameters": plot_downhole(
                   dataset, out / "downhole.png", truth=outcome.truth, units=units,
                   title=f"Downhole estimate: case {case.name!r}")}
    payload = {
        "case": case.name,
        "record": outcome.record.source,
        "samples": int(len(result.time)),
        "duration": float(result.time[-1] - result.time[0]),
        "wall_time": float(result.wall_time),
        "real_time_factor": float(outcome.real_time_factor),
        "replaced_members": result.replaced_members,
        "stopped": result.stopped or None,
        "notes": list(outcome.record.notes),
        "quantities": {name: {"mean": _finite(np.nanmean(result.mean[name])),
                              "band_width": _finite(np.nanmean(np.diff(result.quantiles[name][:, [0, 2]], axis=1)))}
                       for name in result.mean},
        "parameters": {name: {"final": _finite(result.mean[name][-1]),
                              "band": [_finite(v) for v in result.quantiles[name][-1, [0, 2]]]}
                       for name in result.parameters},
        "scores": outcome.scores,
        "files": {"dataset": str(out / "estimate.nc"), "figures": [str(p) for p in figures.values()]},
    }
    report = write_estimate_report(out / "report.html", title=f"Estimate: case {case.name}",
                                   case_toml=case.to_toml(), payload=payload, figures=figures, units=units)
    payload["files"]["report"] = str(report)
    return payload


def _finite(value) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None


def _print_summary(case, outcome, payload: dict, units: str | None) -> None:
    from drillstring.outputs.estimate_plots import DOWNHOLE  # the quantities' display kinds (Matplotlib: loaded here)

    console = _console()
    for note in payload["notes"]:
        console.print(escape(f"record: {note}"), soft_wrap=True)
    table = Table(title=escape(f"Downhole estimate: case {case.name!r} ({payload['samples']} samples, "
                               f"{payload['duration']:.1f} s)"), title_justify="left")
    for column in ("quantity", "time mean", "mean 90 % band width", "coverage of the truth", "RMSE"):
        table.add_column(column, justify="left" if column == "quantity" else "right")
    for name, row in payload["quantities"].items():
        kind = DOWNHOLE.get(name, (None, ""))[0]  # a parameter: a plain number
        unit = display_unit(kind, units) if kind else None
        scale, label = (unit.scale, f" {unit.label}") if unit else (1.0, "")
        score = payload["scores"].get(name, {})
        shown = [("-" if v is None else f"{v * scale:,.4g}{label}") for v in (row["mean"], row["band_width"])]
        table.add_row(name.replace("_", " "), *shown,
                      f"{100 * score['coverage_90']:.1f} %" if "coverage_90" in score else "-",
                      f"{score['rmse'] * scale:,.4g}{label}" if "rmse" in score else "-")
    print_table(console, table)
    bit = payload["scores"].get("bit_speed", {})
    if "surface_only_rmse" in bit:
        speed = display_unit("angular_speed", units)
        console.print(escape(f"Bit-speed RMSE {bit['rmse'] * speed.scale:.3g} {speed.label} against "
                             f"{bit['surface_only_rmse'] * speed.scale:.3g} {speed.label} for the surface-only guess "
                             "(bit speed = top speed)"), soft_wrap=True)
    console.print(escape(f"Real-time factor {payload['real_time_factor']:.2f} ({payload['wall_time']:.1f} s for "
                         f"{payload['duration']:.1f} s of record); members replaced: {payload['replaced_members']}"),
                  soft_wrap=True)
    for key in ("dataset", "report"):
        console.print(escape(f"{key}: {payload['files'][key]}"), soft_wrap=True)
    for figure in payload["files"]["figures"]:
        console.print(escape(f"figure: {figure}"), soft_wrap=True)
