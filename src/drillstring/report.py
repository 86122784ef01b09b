"""A self-contained HTML report of a Monte Carlo study (no physics here).

:func:`write_report` writes one HTML file with everything inline: CSS in a ``<style>`` element, figures as
base64 PNG ``data:`` URIs, no script and no external resource, so the page can be mailed or archived
alone. Every piece of text that comes from outside (case TOML, names, messages) is escaped.

The page holds the case (key numbers and the full TOML in a collapsible block), the study's size and
the laws of its random inputs with their dispersions, a dispersion table per observable (time-mean and
maximum dispersion after the transient in %, and their ratios to each input's dispersion), the run
information (failures, wall time, ...) and the figures.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import math
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from drillstring._version import __version__
from drillstring.files import write_text_atomic
from drillstring.units import display_unit

__all__ = ["write_map_report", "write_optimization_report", "write_report", "write_sensitivity_report",
           "write_torque_drag_page"]

_RPM = 60.0 / (2.0 * math.pi)
#: The interactive page written beside a report when it has interactive figures.
INTERACTIVE_PAGE = "interactive.html"

#: Display names of the study observables, in table order.
OBSERVABLE_NAMES = {
    "rate_of_penetration": "rate of penetration",
    "bit_speed": "bit speed",
    "torque_on_bit": "torque-on-bit",
    "force_on_bit": "force-on-bit",
    "quill_speed": "quill speed",
    "surface_torque": "surface torque",
    "radial_displacement": "radial displacement",
}

_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif;
       margin: 2em auto; max-width: 72em; padding: 0 1.5em; color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.25em; margin-top: 1.8em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; }
p.meta { color: #666; margin-top: 0; }
table { border-collapse: collapse; margin: 0.6em 0; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.7em; }
th { background: #f2f2f2; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
table.kv th { font-weight: normal; background: #f7f7f7; }
details { margin: 0.6em 0; }
summary { cursor: pointer; color: #1f4e99; }
pre { background: #f7f7f7; border: 1px solid #ddd; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { color: #555; font-size: 0.9em; }
ul.failures { font-size: 0.9em; }
"""


def _esc(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _num(value: Any, digits: int = 4) -> str:
    """A number for a table cell ('–' when missing or not finite)."""
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return f"{value:,}"
    try:
        v = float(value)
    except (TypeError, ValueError):
        return _esc(value)
    if not math.isfinite(v):
        return "–"
    return f"{v:.{digits}g}"


def _percent(value: Any) -> str:
    if value is None:
        return "–"
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "–"
    return f"{100.0 * v:.3g}" if math.isfinite(v) else "–"


def _kv_table(rows: list[tuple[str, str]]) -> str:
    """Two-column table; labels are escaped here, values must already be HTML."""
    body = "".join(f"<tr><th>{_esc(k)}</th><td>{v}</td></tr>" for k, v in rows)
    return f'<table class="kv">{body}</table>'


# ---------------------------------------------------------------------------------------------------------
# Sections
# ---------------------------------------------------------------------------------------------------------


def _case_rows(case_toml: str, units: str | None = None) -> list[tuple[str, str]]:
    """Key numbers of a case from its TOML (SI numbers, as written by ``Case.to_toml``), in the display units
    of ``units``. Missing or unparsable entries are left out: the full TOML is shown anyway."""
    length, diameter, force = (display_unit(k, units) for k in ("length", "diameter", "force"))
    stiffness, density = (display_unit(k, units) for k in ("stiffness", "density"))
    try:
        data = tomllib.loads(case_toml)
    except (tomllib.TOMLDecodeError, TypeError):
        return []
    rows: list[tuple[str, str]] = []

    def add(label: str, value: Any, unit: str = "", digits: int = 4) -> None:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            rows.append((label, f"{_num(value, digits)} {_esc(unit)}".strip()))
        elif value not in (None, ""):
            rows.append((label, _esc(value)))

    add("name", data.get("name"))
    add("description", data.get("description"))
    sections = data.get("sections") or []
    if sections:
        total = sum(float(s.get("length", 0.0)) for s in sections if isinstance(s, dict))
        add("string length", length(total), length.label, 6)
        for s in sections:
            if not isinstance(s, dict):
                continue
            parts = []
            if "length" in s:
                parts.append(f"{_num(length(float(s['length'])), 6)} {length.label}")
            if "outer_diameter" in s and "inner_diameter" in s:
                parts.append(f"OD/ID {_num(diameter(float(s['outer_diameter'])))}/"
                             f"{_num(diameter(float(s['inner_diameter'])))} {diameter.label}")
            rows.append((f"section: {s.get('name', '?')}", ", ".join(parts)))
    borehole = data.get("borehole") or {}
    if "diameter" in borehole:
        add("borehole diameter", diameter(float(borehole["diameter"])), diameter.label)
    for i, stab in enumerate(data.get("stabilizers") or []):
        if isinstance(stab, dict) and "position" in stab:
            k = stab.get("stiffness")
            text = f"x = {_num(length(float(stab['position'])), 6)} {length.label}"
            if k is not None:
                text += f", {_num(stiffness(float(k)))} {stiffness.label}"
            rows.append((f"stabilizer {i + 1}", _esc(text)))
    operation = data.get("operation") or {}
    if "top_speed" in operation:
        add("top speed", float(operation["top_speed"]) * _RPM, "rpm")
    if "weight_on_bit" in operation:
        add("weight-on-bit (static)", force(float(operation["weight_on_bit"])), force.label)
    fluid = data.get("fluid") or {}
    if "density" in fluid:
        add("mud density", density(float(fluid["density"])), density.label)
    damping = data.get("damping") or {}
    if "modal_damping_ratio" in damping:
        add("modal damping ratio ξ", damping["modal_damping_ratio"])
    model = data.get("model") or {}
    add("nonlinear forces", model.get("nonlinear"))
    mesh = data.get("mesh") or {}
    if "max_element_length" in mesh:
        add("max element length", length(float(mesh["max_element_length"])), length.label)
    reduced = data.get("reduced_model") or {}
    if reduced:
        rows.append(("modes (axial + rigid, torsional, lateral per plane)",
                     _esc(", ".join(str(reduced.get(k, "?"))
                                    for k in ("axial_modes", "torsional_modes", "lateral_modes")))))
    simulation = data.get("simulation") or {}
    if "rtol" in simulation:
        add("integrator tolerances (rtol, atol)", f"{simulation['rtol']:g}, {simulation.get('atol', '?')}")
    return rows


def _case_section(case_toml: str, units: str | None = None) -> str:
    rows = _case_rows(case_toml, units)
    table = _kv_table(rows) if rows else "<p>(no key numbers could be read from the case)</p>"
    return (
        "<h2>Case</h2>"
        f"{table}"
        "<details><summary>Full case file (TOML, SI units)</summary>"
        f"<pre>{_esc(case_toml)}</pre></details>"
    )


def _study_section(summary: Mapping[str, Any], units: str | None = None) -> str:
    force = display_unit("force", units)
    rows: list[tuple[str, str]] = []
    if "n_samples" in summary:
        rows.append(("realizations used (n_s)", _num(summary["n_samples"])))
    if "n_failed" in summary:
        rows.append(("failed realizations", _num(summary["n_failed"])))
    if "seed" in summary:
        rows.append(("seed", _num(summary["seed"])))
    for path, entry in (summary.get("inputs") or {}).items():
        unit = f" {entry.get('unit')}" if entry.get("unit") else ""
        rows.append((f"law of {path}", f"{_esc(entry.get('law'))} (SI: mean {_num(entry.get('mean'))}{_esc(unit)}, "
                                        f"std {_num(entry.get('std'))}{_esc(unit)}, dispersion "
                                        f"{_percent(entry.get('dispersion'))} %; sample: mean "
                                        f"{_num(entry.get('sample_mean'))}, std {_num(entry.get('sample_std'))})"))
    if summary.get("sigma") is not None:
        rows.append(("σ of the weight-on-hook", f"{_num(force(float(summary['sigma'])))} {force.label}"))
    if "weight_on_hook_mean" in summary:
        rows.append(("mean weight-on-hook",
                     f"{_num(force(float(summary['weight_on_hook_mean'])), 6)} {force.label}"))
    if summary.get("weight_on_hook_dispersion") is not None:
        rows.append(("weight-on-hook dispersion δ_WOH", f"{_percent(summary['weight_on_hook_dispersion'])} %"))
    if summary.get("weight_on_bit_dispersion") is not None:
        rows.append(("weight-on-bit dispersion δ_WOB", f"{_percent(summary['weight_on_bit_dispersion'])} %"))
    if "t_transient" in summary:
        rows.append(("summaries over", f"t ≥ {_num(summary['t_transient'])} s"))
    return "<h2>Study</h2>" + (_kv_table(rows) if rows else "")


#: Short labels of inputs in table headers (others: the parameter path).
INPUT_LABELS = {"weight_on_hook": "WOH", "weight_on_bit": "WOB"}


def input_label(name: str) -> str:
    """``δ_WOH``, ``δ_WOB``, or ``δ(path)`` for another random parameter."""
    return f"δ_{INPUT_LABELS[name]}" if name in INPUT_LABELS else f"δ({name})"


def _input_names(observables: Mapping[str, Any]) -> list[str]:
    """The inputs that the dispersion ratios refer to (those of the first observable)."""
    for entry in observables.values():
        return list((entry or {}).get("ratio_time_mean") or {})
    return []


def _dispersion_rows(observables: Mapping[str, Any], window: str | None, conv: Mapping[str, Any]) -> str:
    """Table rows of one summary window (``window`` None: the steady window, else the entry's key)."""
    body = []
    inputs = _input_names(observables)
    for name, entry in observables.items():
        entry = (entry or {}) if window is None else ((entry or {}).get(window) or {})
        rt = entry.get("ratio_time_mean") or {}
        rm = entry.get("ratio_max") or {}
        cells = [
            _num(entry.get("t_start")),
            _percent(entry.get("dispersion_time_mean")),
            _percent(entry.get("dispersion_max")),
            _num(entry.get("time_of_max")),
            *(_num(rt.get(key), 3) for key in inputs),
            *(_num(rm.get(key), 3) for key in inputs),
        ]
        if window is None:
            cells.append(_percent(conv.get(name)))
        label = OBSERVABLE_NAMES.get(str(name), str(name))
        body.append(f"<tr><td>{_esc(label)}</td>" + "".join(f'<td class="num">{c}</td>' for c in cells)
                    + "</tr>")
    return "".join(body)


def _dispersion_table(summary: Mapping[str, Any], units: str | None = None) -> str:
    observables = summary.get("observables") or {}
    if not observables:
        return ""
    conv = summary.get("convergence_change_second_half") or {}
    inputs = _input_names(observables)
    columns = ("<th>observable</th><th>from t [s]</th><th>time-mean δ [%]</th><th>max δ [%]</th>"
               "<th>time of max [s]</th>"
               + "".join(f"<th>mean δ / {_esc(input_label(k))}</th>" for k in inputs)
               + "".join(f"<th>max δ / {_esc(input_label(k))}</th>" for k in inputs))
    steady = (f"<h3>Steady window (t ≥ {_num(summary.get('t_transient'))} s)</h3>"
              f"<table><tr>{columns}<th>conv(n_s) change, 2nd half [%]</th></tr>"
              f"{_dispersion_rows(observables, None, conv)}</table>")
    whole = ""
    if any("whole_record" in (entry or {}) for entry in observables.values()):
        whole = ("<h3>Whole record</h3><p>From the first output time at which the mean response is away "
                 "from 0 (at least 10 % of its steady-window average): ROP starts at 0 in every "
                 "realization, so δ is undefined at t = 0.</p>"
                 f"<table><tr>{columns}</tr>{_dispersion_rows(observables, 'whole_record', conv)}</table>")
    return (
        "<h2>Dispersion of the response</h2>"
        "<p>Dispersion δ = std / |mean| over the realizations at each time, summarised over time (mean and "
        "maximum), and its ratio to the dispersion of each random input; ratios above 1 mean that the input "
        "uncertainty is amplified.</p>"
        + steady + whole + _indicators_html(summary, units)
    )


def _indicators_html(summary: Mapping[str, Any], units: str | None = None) -> str:
    """The per-realization cycle metrics (distribution table), the stability of the draws and the
    convergence of the dispersions in time, in the unit system ``units``."""
    from drillstring.quantities import METRIC_DISPLAY, metric_unit

    section = summary.get("realizations") or {}
    out = ""
    if section:
        rows = []
        for name, (_, label) in METRIC_DISPLAY.items():
            entry = section.get(name)
            if not entry:
                continue
            unit = metric_unit(name, units)
            cells = [_num(None if entry[k] is None else unit(entry[k]))
                     for k in ("mean", "std")] + [_percent(entry["dispersion"])]
            cells += [_num(None if entry[k] is None else unit(entry[k]))
                      for k in ("q2.5", "q50", "q97.5", "nominal")]
            rows.append(f"<tr><td>{_esc(label)}</td><td>{_esc(unit.label)}</td>"
                        + "".join(f'<td class="num">{c}</td>' for c in cells)
                        + f'<td class="num">{entry["n"]}</td></tr>')
        out += (f"<h3>Per realization (after t = {_num(section.get('t_transient'))} s)</h3>"
                "<p>Cycle metrics of each realization, computed from its own (realized) case; their "
                "distribution over the realizations. Stick-slip index (max − min)/(2·mean) of the bit speed; "
                "MSE = WOB/A + Ω·TOB/(A·ROP) (Teale) from the time means, A the borehole cross-section.</p>"
                "<table><tr><th>metric</th><th>unit</th><th>mean</th><th>std</th><th>δ [%]</th><th>2.5 %</th>"
                "<th>50 %</th><th>97.5 %</th><th>nominal</th><th>n</th></tr>" + "".join(rows) + "</table>")
        if "stick_slip_realizations" in section:
            out += _kv_table([("realizations in stick-slip (bit below 10 % of the top speed)",
                               _num(section["stick_slip_realizations"]))])
    stability = summary.get("stability") or {}
    if stability.get("unstable_fraction") is not None:
        boundary = stability.get("boundary") or {}
        rows = [("draws whose steady drilling is unstable (growth rate > 0)",
                 f"{stability['unstable_realizations']} of {stability['realizations_with_growth_rate']} "
                 f"({_percent(stability['unstable_fraction'])} %)"),
                ("growth rate [1/s]: mean, 2.5 – 97.5 %",
                 f"{_num(stability['growth_rate']['mean'])}, {_num(stability['growth_rate']['q2.5'])} – "
                 f"{_num(stability['growth_rate']['q97.5'])}"),
                ("nominal growth rate [1/s]", _num(stability.get("nominal_growth_rate")))]
        for family, entry in (stability.get("by_family") or {}).items():
            if entry["realizations_with_roots"]:
                rows.append((f"draws with a growing {family} root; its growth rate [1/s]: mean (nominal)",
                             f"{entry['unstable_realizations']} of {entry['realizations_with_roots']}; "
                             f"{_num(entry['growth_rate']['mean'])} ({_num(entry['nominal_growth_rate'])})"))
        if boundary.get("weight_on_bit") is not None:
            force = display_unit("force", units)
            rows.append((f"stability boundary of the nominal case along the weight-on-bit [{force.label}]",
                         _num(force(boundary["weight_on_bit"]))))
        out += "<h3>Linear stability of steady drilling at each draw</h3>" + _kv_table(rows)
    convergence = summary.get("time_convergence") or {}
    if convergence.get("observables"):
        rows = []
        for name, entry in convergence["observables"].items():
            windows = ", ".join(f"{_num(w['t_end'], 3)} s: {_percent(w['dispersion_max'])}" for w in entry["windows"])
            rows.append((OBSERVABLE_NAMES.get(name, name), _esc(windows)))
        note = convergence.get("warning")
        out += (f"<h3>Convergence in time (records growing by {_num(convergence['window'])} s)</h3>"
                f"<p>Maximum dispersion [%] over the record from t = {_num(convergence.get('t_start'))} s to each "
                "end.</p>" + _kv_table(rows)
                + (f"<p><b>Warning:</b> {_esc(note)}</p>" if note else ""))
    return out


def _value_html(value: Any) -> str:
    if isinstance(value, Mapping):
        if not value:
            return "none"
        items = "".join(f"<li><b>{_esc(k)}</b>: {_esc(v)}</li>" for k, v in value.items())
        return f'<details><summary>{len(value)}</summary><ul class="failures">{items}</ul></details>'
    if isinstance(value, (list, tuple)):
        return _esc(", ".join(str(v) for v in value))
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return _num(value, 6)
    return _esc(value)


def _run_section(run_info: Mapping[str, Any]) -> str:
    if not run_info:
        return ""
    rows = [(str(k), _value_html(v)) for k, v in run_info.items()]
    return "<h2>Run</h2>" + _kv_table(rows)


def _figure_html(name: str, path: str | Path) -> str:
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    label = _esc(name)
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{label}">'
            f"<figcaption>{label}</figcaption></figure>")


# ---------------------------------------------------------------------------------------------------------
# The page
# ---------------------------------------------------------------------------------------------------------


def _head(title: str) -> str:
    """The ``<head>`` content of every page: charset, viewport, title, the report's style."""
    return "\n".join(['<meta charset="utf-8">', '<meta name="viewport" content="width=device-width, initial-scale=1">',
                      f"<title>{_esc(title)}</title>", f"<style>{_CSS}</style>"])


def _heading(title: str) -> list[str]:
    """The title and the line under it (version, time written)."""
    stamp = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z").strip()
    return [f"<h1>{_esc(title)}</h1>", f'<p class="meta">drillstring {_esc(__version__)}, written {_esc(stamp)}</p>']


def _page(path: str | Path, title: str, case_toml: str, sections: list[str], figures: Mapping[str, str | Path],
          run_info: Mapping[str, Any], interactive: Sequence[Mapping[str, Any]] | None = None,
          units: str | None = None) -> Path:
    """One self-contained page: title, the case (in the unit system ``units``), ``sections`` (HTML), the run
    table and the figures. With ``interactive`` figures (:mod:`drillstring.interactive`), the same page with
    them, zoomable, is written beside it as ``interactive.html``, and this page links to it."""
    path = Path(path)
    head = _head(title)
    body = [
        *_heading(title),
        _case_section(case_toml, units),
        *sections,
        _run_section(run_info),
    ]
    if interactive is not None:
        from drillstring.interactive import write_interactive_page

        write_interactive_page(path.with_name(INTERACTIVE_PAGE), head, "\n".join(body), interactive)
        body.insert(2, f'<p>Zoomable figures (values on hover, single realizations on demand): '
                       f'<a href="{INTERACTIVE_PAGE}">{INTERACTIVE_PAGE}</a>, beside this page.</p>')
    parts = ["<!DOCTYPE html>", '<html lang="en"><head>', head, "</head><body>", *body]
    if figures:
        parts.append("<h2>Figures</h2>")
        parts.extend(_figure_html(name, fig) for name, fig in figures.items())
    parts.append("</body></html>")
    return write_text_atomic(path, "\n".join(parts) + "\n")


def write_report(
    path: str | Path,
    *,
    title: str,
    case_toml: str,
    summary: Mapping[str, Any],
    figures: Mapping[str, str | Path],
    run_info: Mapping[str, Any],
    interactive: Sequence[Mapping[str, Any]] | None = None,
    units: str | None = None,
) -> Path:
    """Write the study report as one self-contained HTML page at ``path``; returns the path.

    Args:
        title: page title.
        case_toml: the case's TOML text (e.g. the statistics' ``attrs["case"]``).
        summary: :func:`drillstring.stochastic.analysis.study_summary` (SI; dispersions as fractions,
            shown in %).
        figures: caption -> PNG file, embedded in this order as base64 ``data:`` URIs.
        run_info: label -> value rows of the "Run" table (e.g. wall time, workers, failures); a mapping
            value (such as the failures ``{realization: message}``) is shown as a collapsible list.
        interactive: figures of :func:`drillstring.interactive.study_figures`: the same page with them is
            written beside as ``interactive.html`` (see :func:`_page`).
        units: the unit system of the tables, ``"si"`` or ``"field"`` (None: ``$DRILLSTRING_UNITS``, else si).
    """
    return _page(path, title, case_toml, [_study_section(summary, units), _dispersion_table(summary, units)], figures,
                 run_info, interactive, units)


# ---------------------------------------------------------------------------------------------------------
# Sensitivity and operating maps
# ---------------------------------------------------------------------------------------------------------

#: Display names of the scalar outputs of a run.
OUTPUT_NAMES = {
    "mean_rate_of_penetration": "mean rate of penetration",
    "bit_speed_oscillation": "bit-speed oscillation",
    "mean_torque_on_bit": "mean torque-on-bit",
    "mean_force_on_bit": "mean force-on-bit",
    "std_rate_of_penetration": "rate of penetration, std in time",
    "std_torque_on_bit": "torque-on-bit, std in time",
    "std_force_on_bit": "force-on-bit, std in time",
    "stick_time_fraction": "stick time fraction",
    "bit_bounce_fraction": "bit bounce fraction",
}


def _interval(ci: Any) -> str:
    if not ci or None in ci:
        return "–"
    return f"[{_num(ci[0], 3)}, {_num(ci[1], 3)}]"


def _sobol_tables(indices: Mapping[str, Any]) -> str:
    parameters = list(indices.get("parameters") or {})
    rows = [("parameters and laws", _esc("; ".join(f"{p}: {law}" for p, law in indices["parameters"].items()))),
            ("base samples N", _num(indices.get("base_samples"))), ("runs N(k + 2)", _num(indices.get("runs"))),
            ("seed", _num(indices.get("seed"))),
            ("confidence level of the intervals", f"{_percent(indices.get('confidence_level'))} % "
                                                  f"({_num(indices.get('resamples'))} bootstrap resamples)")]
    parts = ["<h2>Design</h2>", _kv_table(rows),
             "<h2>Sobol' indices</h2><p>S1: share of the output's variance explained by the parameter alone; "
             "ST: with all its interactions. Intervals: bootstrap over the base samples. Convergence: the "
             "largest change of any index from N/4 to N/2 and from N/2 to N (the same runs).</p>"]
    head = "<tr><th>output</th><th>parameter</th><th>S1</th><th>S1 interval</th><th>ST</th><th>ST interval</th></tr>"
    body = []
    for name, entry in indices["outputs"].items():
        label = OUTPUT_NAMES.get(name, name)
        change = entry.get("convergence", {}).get("max_change") or []
        note = (f" (max change {', '.join(_num(c, 2) for c in change)}"
                f"{'; ' + _num(entry.get('dropped_base_samples')) + ' base samples dropped' if entry.get('dropped_base_samples') else ''})")
        for k, parameter in enumerate(parameters):
            first = (f'<td rowspan="{len(parameters)}">{_esc(label)}<br><small>{_esc(note)}</small></td>'
                     if k == 0 else "")
            body.append(f"<tr>{first}<td>{_esc(parameter)}</td>"
                        f'<td class="num">{_num(entry["S1"].get(parameter), 3)}</td>'
                        f'<td class="num">{_interval(entry["S1_ci"].get(parameter))}</td>'
                        f'<td class="num">{_num(entry["ST"].get(parameter), 3)}</td>'
                        f'<td class="num">{_interval(entry["ST_ci"].get(parameter))}</td></tr>')
    parts.append(f"<table>{head}{''.join(body)}</table>")
    notes = {name: entry.get("sample_notes") for name, entry in indices["outputs"].items() if entry.get("sample_notes")}
    if notes:
        parts.append(f"<p><b>The sample is too small</b> (N = {_num(indices.get('base_samples'))}): an index is known "
                     "to about its interval's half-width; increase N.</p><ul>"
                     + "".join(f"<li>{_esc(OUTPUT_NAMES.get(name, name))}: {_esc('; '.join(text))}</li>"
                               for name, text in notes.items()) + "</ul>")
    return "".join(parts)


def write_sensitivity_report(path: str | Path, *, title: str, case_toml: str, indices: Mapping[str, Any],
                             figures: Mapping[str, str | Path], run_info: Mapping[str, Any],
                             interactive: Sequence[Mapping[str, Any]] | None = None,
                             units: str | None = None) -> Path:
    """Write the report of a sensitivity analysis (one self-contained HTML page): the case, the design,
    a table of the Sobol' indices with their intervals and convergence per output (``indices``: the JSON
    form of a :class:`~drillstring.stochastic.sensitivity.SobolResult`), the run table and the figures."""
    return _page(path, title, case_toml, [_sobol_tables(indices)], figures, run_info, interactive, units)


def _axis(values: list[float], unit: str) -> str:
    """A map axis for a table cell: 'first to last unit (n values)'."""
    if not values:
        return "–"
    return f"{_num(min(values))} to {_num(max(values))} {unit} ({len(values)} values)"


def _map_section(summary: Mapping[str, Any], units: str | None = None) -> str:
    force, rop, pressure = (display_unit(k, units) for k in ("force", "rate_of_penetration", "pressure"))
    speeds = [v * _RPM for v in summary.get("top_speed", [])]
    weights = [force(v) for v in summary.get("weight_on_bit", [])]
    axis = _axis
    rows = [("top speed", axis(speeds, "rpm")), ("weight-on-bit", axis(weights, force.label)),
            ("points (done, failed)", f"{_num(summary.get('points'))} ({_num(summary.get('done'))}, "
                                      f"{_num(summary.get('failed'))})"),
            ("simulated time per point", f"{_num(summary.get('t_end'))} s, outputs over t ≥ "
                                         f"{_num(summary.get('t_transient'))} s"),
            ("critical weight-on-bit (lateral buckling)",
             f"{_num(force(float(summary.get('critical_weight_on_bit', math.nan))))} {force.label}"),
            ("bit area (borehole cross-section) for the MSE", f"{_num(summary.get('bit_area'))} m²"),
            ("points where steady drilling is linearly stable", _num(summary.get("linearly_stable_points"))),
            ("points without steady drilling (no penetration)", _num(summary.get("points_without_steady_drilling"))),
            ("points in stick-slip", _num(summary.get("stick_slip_points")))]
    for family, counts in (summary.get("linearly_stable_points_by_family") or {}).items():
        rows.insert(-2, (f"... whose {family} roots all decay",
                         f"{_num(counts['stable'])} of {_num(counts['stable'] + counts['unstable'])}"))
    if "coexisting_cycle_points" in summary:
        rows.append(("... in stick-slip although steady drilling is linearly stable (coexisting cycles)",
                     _num(summary["coexisting_cycle_points"])))
    best = summary.get("largest_rate_of_penetration")
    if best:
        rows.append(("largest mean rate of penetration",
                     f"{_num(rop(best['mean_rate_of_penetration']))} {rop.label} at "
                     f"{_num(best['top_speed'] * _RPM)} rpm, {_num(force(best['weight_on_bit']))} {force.label} "
                     f"(bit-speed oscillation {_num(best['bit_speed_oscillation'], 3)}, MSE "
                     f"{_num(pressure(best['mechanical_specific_energy']))} {pressure.label})"))
    return ("<h2>Map</h2><p>One simulation per point; outputs after the transient. MSE = WOB/A + Ω·TOB/(A·ROP) "
            "(Teale) from the time means. The stability boundary is where the leading growth rate of the model "
            "linearised about steady drilling crosses 0.</p>" + _kv_table(rows))


def write_map_report(path: str | Path, *, title: str, case_toml: str, summary: Mapping[str, Any],
                     figures: Mapping[str, str | Path], run_info: Mapping[str, Any],
                     interactive: Sequence[Mapping[str, Any]] | None = None,
                     units: str | None = None) -> Path:
    """Write the report of an operating map (one self-contained HTML page): the case, the grid and its
    highlights (``summary``: :func:`drillstring.stochastic.operating_map.map_summary`), the run table and
    the figures, in the unit system ``units``."""
    return _page(path, title, case_toml, [_map_section(summary, units)], figures, run_info, interactive, units)


#: Columns of the per-point table of a probabilistic map: summary key, header.
_PROBABILITY_COLUMNS = (("stick_slip_probability", "P(stick-slip)"), ("buckling_probability", "P(buckled)"),
                        ("impact_probability", "P(impact)"), ("instability_probability", "P(unstable)"),
                        ("bounce_probability", "P(bounce)"))


def _probability_map_section(summary: Mapping[str, Any], units: str | None = None) -> str:
    force, rop = display_unit("force", units), display_unit("rate_of_penetration", units)
    speeds, weights = list(summary.get("top_speed", [])), list(summary.get("weight_on_bit", []))
    sigma = summary.get("sigma")
    laws = ([f"weight_on_hook: normal around each point's hook load, σ = {_num(force(sigma))} {force.label}"]
            if sigma else [])
    laws += [str(v) for v in summary.get("laws", [])[1 if sigma else 0:]]
    rows = [("top speed", _axis([v * _RPM for v in speeds], "rpm")),
            ("weight-on-bit (nominal at each point)", _axis([force(v) for v in weights], force.label)),
            ("realizations per point", _num(summary.get("samples"))),
            ("random parameters", _esc("; ".join(f"{p}" for p in laws)) or "–"),
            ("realizations (done, failed)", f"{_num(summary.get('realizations'))} ({_num(summary.get('done'))}, "
                                            f"{_num(summary.get('failed'))})"),
            ("simulated time per realization", f"{_num(summary.get('t_end'))} s, outputs over t ≥ "
                                               f"{_num(summary.get('t_transient'))} s"),
            ("critical weight-on-bit (lateral buckling, nominal case)",
             f"{_num(force(float(summary.get('critical_weight_on_bit', math.nan))))} {force.label}")]
    probabilities = summary.get("probabilities", {})
    quantiles = summary.get("quantiles", {})
    head = (f"<tr><th>top speed [rpm]</th><th>WOB [{_esc(force.label)}]</th><th>n</th>"
            + "".join(f"<th>{_esc(h)}</th>" for _, h in _PROBABILITY_COLUMNS)
            + f"<th>mean ROP [{_esc(rop.label)}]: 50 % (2.5–97.5 %)</th>"
            + "<th>stick-slip index: 50 % (2.5–97.5 %)</th></tr>")

    def spread(name: str, i: int, j: int, factor: float) -> str:
        q = quantiles.get(name, {})
        low, mid, high = (q.get(k, [[None]])[i][j] for k in ("2.5", "50", "97.5"))
        scale = (lambda v: None if v is None else v * factor)
        return f"{_num(scale(mid), 3)} ({_num(scale(low), 3)}–{_num(scale(high), 3)})"

    body = []
    for i, speed in enumerate(speeds):
        for j, wob in enumerate(weights):
            cells = [_num(speed * _RPM), _num(force(wob)), _num(summary.get("samples_done", [[None]])[i][j])]
            for key, _ in _PROBABILITY_COLUMNS:
                value = probabilities.get(key, {}).get("values", [[None]])[i][j]
                error = probabilities.get(key, {}).get("standard_error", [[None]])[i][j]
                cells.append(f"{_num(value, 3)} ± {_num(error, 2)}")
            cells += [spread("rate_of_penetration_q", i, j, rop.scale), spread("stick_slip_index_q", i, j, 1.0)]
            body.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    return ("<h2>Map</h2><p>At each point, realizations of the declared uncertainty (one random stream per "
            "realization index, common to the points). Each probability is the share of the point's finished "
            "realizations with the event (± its binomial standard error): stick-slip, the bit below 10 % of the top "
            "speed; buckled, the lowest lateral eigenvalue of the realized string below 0; impact, a contact with "
            "the borehole wall; unstable, a positive growth rate of steady drilling.</p>" + _kv_table(rows)
            + f"<h2>Points</h2><table>{head}{''.join(body)}</table>")


def write_probability_map_report(path: str | Path, *, title: str, case_toml: str, summary: Mapping[str, Any],
                                 figures: Mapping[str, str | Path], run_info: Mapping[str, Any],
                                 interactive: Sequence[Mapping[str, Any]] | None = None,
                                 units: str | None = None) -> Path:
    """Write the report of a probabilistic operating map (one self-contained HTML page): the case, the grid,
    the random parameters, a table of every point's probabilities and quantiles (``summary``:
    :func:`drillstring.stochastic.probabilistic_map.sampled_map_summary`), the run table and the figures, in
    the unit system ``units``."""
    return _page(path, title, case_toml, [_probability_map_section(summary, units)], figures, run_info, interactive,
                 units)


# ---------------------------------------------------------------------------------------------------------
# Robust operating point
# ---------------------------------------------------------------------------------------------------------


def _optimization_section(summary: Mapping[str, Any], variable_units: Sequence[Any], objective_unit: Any) -> str:
    """The search (variables and bounds, objective, constraints, budget), the answer with its chance
    constraints, and every design point's estimates; ``variable_units`` and ``objective_unit``: display units
    (:class:`~drillstring.units.DisplayUnit`) of the decision variables and of the objective."""
    best = summary["recommended"]
    names = [path.rsplit(".", 1)[-1] for path in summary["variables"]]
    constraints = best["constraints"]
    rows = [(f"{name} ({path})", f"{_num(unit(lo))} to {_num(unit(hi))} {_esc(unit.label)}")
            for name, path, unit, (lo, hi) in zip(names, summary["variables"], variable_units, summary["bounds"])]
    rows += [("objective", f"{_esc(summary['objective'])} ({'maximised' if summary['maximize'] else 'minimised'})"),
             ("chance constraints", _esc(", ".join(f"P({c['event']}) ≤ {c['bound']:g}" for c in constraints))
              or "none"),
             ("design points (initial design, chosen by the surrogates)",
              f"{_num(summary['points'])} ({_num(summary['initial'])}, "
              f"{_num(summary['points'] - summary['initial'])})"),
             ("realizations per point, in all", f"{_num(summary['samples'])}, {_num(summary['realizations'])}")]
    state = "recommended point" if summary["feasible"] else "least-infeasible point (the constraints cannot be met)"
    shown = ", ".join(f"{name} = {_num(unit(v))} {unit.label}"
                      for name, unit, v in zip(names, variable_units, best["values"]))
    answer = [(state, _esc(f"{shown} (design point {best['point']})")),
              (f"objective [{objective_unit.label}]: Monte Carlo ± standard error",
               f"{_num(_scaled(objective_unit, best['objective']))} ± "
               f"{_num(_scaled(objective_unit, best['objective_standard_error']), 2)} "
               f"({_num(best['realizations'])} realizations)"),
              (f"objective [{objective_unit.label}]: surrogate ± standard deviation",
               f"{_num(_scaled(objective_unit, best['surrogate_objective']))} ± "
               f"{_num(_scaled(objective_unit, best['surrogate_objective_standard_deviation']), 2)}")]
    out = ("<h2>Search</h2><p>Gaussian-process surrogates of the objective and of each constraint's probability, "
           "fitted to the Monte Carlo estimates at the design points; after the initial design, points where the "
           "constrained expected improvement is largest.</p>" + _kv_table(rows)
           + "<h2>Answer</h2>" + _kv_table(answer))
    if constraints:
        head = "".join(f"<th>{h}</th>" for h in ("event", "bound", "P (Monte Carlo)", "binomial s.e.", "surrogate",
                                                 "surrogate s.d.", "combined s.d.", "confidence", "met"))
        body = "".join(
            f"<tr><td>{_esc(c['event'])}</td>" + "".join(f'<td class="num">{_num(c[k], 3)}</td>' for k in (
                "bound", "probability", "binomial_standard_error", "surrogate_mean", "surrogate_standard_deviation",
                "combined_standard_deviation", "confidence")) + f"<td>{'yes' if c['met'] else 'no'}</td></tr>"
            for c in constraints)
        out += ("<h3>Chance constraints at the answer</h3><p>Confidence: P(probability ≤ bound) from the binomial "
                f"and surrogate errors together.</p><table><tr>{head}</tr>{body}</table>")
    head = ("<tr><th>point</th>" + "".join(f"<th>{_esc(n)} [{_esc(u.label)}]</th>" for n, u in zip(names,
                                                                                                   variable_units))
            + "<th>realizations</th>" + f"<th>objective [{_esc(objective_unit.label)}]</th>"
            + "".join(f"<th>P({_esc(c['event'])})</th>" for c in constraints) + "</tr>")
    estimates = summary["estimates"]
    body = []
    for k, values in enumerate(summary["design"]):
        mark = ' style="font-weight: bold"' if k == best["point"] else ""
        cells = [_num(k)] + [_num(u(v)) for u, v in zip(variable_units, values)] + [
            _num(estimates["count"][k]), _num(_scaled(objective_unit, estimates["objective"][k]))]
        cells += [_num(p, 3) for p in estimates["probabilities"][k]]
        body.append(f"<tr{mark}>" + "".join(f'<td class="num">{c}</td>' for c in cells) + "</tr>")
    return out + f"<h2>Design points</h2><p>The answer in bold.</p><table>{head}{''.join(body)}</table>"


def write_optimization_report(path: str | Path, *, title: str, case_toml: str, summary: Mapping[str, Any],
                              figures: Mapping[str, str | Path], run_info: Mapping[str, Any],
                              variable_units: Sequence[Any], objective_unit: Any, units: str | None = None) -> Path:
    """Write the report of a robust operating point (one self-contained HTML page): the case, the search, the
    answer and its chance constraints, the design points (``summary``: as ``optimize.json``, SI), the run table
    and the figures, the variables in ``variable_units`` and the objective in ``objective_unit``."""
    return _page(path, title, case_toml, [_optimization_section(summary, variable_units, objective_unit)], figures,
                 run_info, None, units)


# ---------------------------------------------------------------------------------------------------------
# Torque and drag
# ---------------------------------------------------------------------------------------------------------


def _scaled(unit, value: float | None) -> float | None:
    return None if value is None else unit(value)


def _intervals(pairs: Sequence[Sequence[float]], length) -> str:
    return ", ".join(f"{length(a):,.0f}–{length(b):,.0f}" for a, b in pairs) or "none"


def _torque_drag_section(payload: Mapping[str, Any], units: str | None = None) -> str:
    """The operations table (hook load, surface torque, buckled intervals), the well and, when measured hook
    loads were given, the calibrated friction factors, in the unit system ``units``."""
    force, length, torque = (display_unit(k, units) for k in ("force", "length", "torque"))
    head = (f"<tr><th>operation</th><th>hook load [{_esc(force.label)}]</th><th>surface torque "
            f"[{_esc(torque.label)}]</th><th>sinusoidal buckling [{_esc(length.label)} MD]</th>"
            f"<th>helical buckling [{_esc(length.label)} MD]</th></tr>")
    body = []
    for op, row in payload["operations"].items():
        hook = "locked up" if row["locked_up"] else _num(_scaled(force, row["hook_load"]), 5)
        body.append(f"<tr><td>{_esc(op.replace('_', ' '))}</td><td class=\"num\">{hook}</td>"
                    f'<td class="num">{_num(_scaled(torque, row["surface_torque"]), 4)}</td>'
                    f"<td>{_esc(_intervals(row['sinusoidal_buckling'], length))}</td>"
                    f"<td>{_esc(_intervals(row['helical_buckling'], length))}</td></tr>")
    well = payload["well"]
    lockup = payload.get("lockup_depth")
    rows = [("measured depth", f"{_num(length(well['depth']), 6)} {_esc(length.label)}"),
            ("true vertical depth", f"{_num(length(well['true_vertical_depth']), 6)} {_esc(length.label)}"),
            ("survey stations", _num(well["stations"])),
            ("friction factors: cased hole, open hole",
             f"{_num(well['cased_hole_friction'])}, {_num(well['open_hole_friction'])}"),
            ("lock-up when sliding", "none" if lockup is None else
             f"bit at {_num(length(lockup), 6)} {_esc(length.label)}")]
    out = ("<h2>Loads</h2><p>Soft-string model (Johancsik et al. 1984): hook load and surface torque of each "
           f"operation, and the intervals where the string buckles.</p><table>{head}{''.join(body)}</table>"
           "<h2>Well</h2>" + _kv_table(rows))
    calibration = payload.get("calibration")
    if calibration:
        rows = [(f"{name.replace('_', ' ')}: posterior mean ± std (90 % interval)",
                 f"{_num(calibration[name]['mean'], 3)} ± {_num(calibration[name]['std'], 2)} "
                 f"({_num(calibration[name]['interval_90'][0], 3)}–{_num(calibration[name]['interval_90'][1], 3)})")
                for name in ("cased_hole_friction", "open_hole_friction")]
        rows.append(("residual of the hook loads", f"{_num(force(calibration['residual_sigma']))} "
                                                   f"{_esc(force.label)} ({_esc(calibration['noise'])})"))
        out += "<h2>Friction factors calibrated from measured hook loads</h2>" + _kv_table(rows)
    return out


def write_torque_drag_page(path: str | Path, *, title: str, case_toml: str, payload: Mapping[str, Any],
                           interactive: Sequence[Mapping[str, Any]], units: str | None = None) -> Path:
    """Write the interactive torque-and-drag page (one self-contained HTML file, the report's style): the case,
    the loads of each operation and the well (``payload``: :attr:`drillstring.well.analysis.TorqueDragAnalysis.
    payload`), then the ``interactive`` figures (:func:`drillstring.outputs.torque_drag_plots.well_figures`)."""
    from drillstring.interactive import write_interactive_page

    body = [*_heading(title), _case_section(case_toml, units), _torque_drag_section(payload, units)]
    return write_interactive_page(path, _head(title), "\n".join(body), interactive)
