"""The report page of an estimate (``drillstring estimate``): the record's notes (faults flagged), the downhole
quantities' time means and band widths, the estimated parameters, the scores against a truth, and the figures;
one self-contained HTML page, written like the study report (:mod:`drillstring.report`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from drillstring.report import _esc, _kv_table, _num, _page
from drillstring.outputs.estimate_plots import DOWNHOLE
from drillstring.units import display_unit


def _shown(value: float | None, kind: str | None, units: str | None) -> str:
    if value is None:
        return "–"
    if kind is None:
        return _esc(_num(value))
    unit = display_unit(kind, units)
    return _esc(f"{_num(value * unit.scale)} {unit.label}")


def _estimate_section(payload: Mapping[str, Any], units: str | None) -> str:
    rows = []
    for name, row in payload["quantities"].items():
        kind = DOWNHOLE.get(name, (None, ""))[0]  # a parameter: a plain number
        score = payload["scores"].get(name, {})
        text = (f"mean {_shown(row['mean'], kind, units)}, 90 % band width {_shown(row['band_width'], kind, units)}")
        if "coverage_90" in score:
            text += _esc(f"; truth inside the band {100 * score['coverage_90']:.1f} % of the time, RMSE ")
            text += _shown(score["rmse"], kind, units)
        if "surface_only_rmse" in score:
            text += " (surface-only guess: " + _shown(score["surface_only_rmse"], kind, units) + ")"
        rows.append((name.replace("_", " "), text))
    for name, row in payload["parameters"].items():
        low, high = row["band"]
        rows.append((f"parameter {name}", _esc(f"final {_num(row['final'])}, 90 % band [{_num(low)}, {_num(high)}]")))
    notes = "".join(f"<li>{_esc(note)}</li>" for note in payload["notes"]) or "<li>none</li>"
    return ("<h2>Downhole estimate</h2>" + _kv_table(rows) + "<h2>The record</h2>"
            + f"<p>{_esc(payload['record'])}: {payload['samples']} samples over {_num(payload['duration'])} s</p>"
            + f"<ul>{notes}</ul>")


def write_estimate_report(path: str | Path, *, title: str, case_toml: str, payload: Mapping[str, Any],
                          figures: Mapping[str, str | Path], units: str | None = None) -> Path:
    """Write the estimate's report page at ``path`` (``payload``: the command's JSON payload, SI); returns it."""
    run = {"wall time [s]": f"{payload['wall_time']:.1f}", "real-time factor": f"{payload['real_time_factor']:.2f}",
           "members replaced": str(payload["replaced_members"])}
    if payload.get("stopped"):
        run["stopped early"] = payload["stopped"]
    return _page(path, title, case_toml, [_estimate_section(payload, units)], figures, run, units=units)
