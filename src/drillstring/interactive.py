"""The interactive report: one self-contained HTML page with zoomable figures (no physics here).

:func:`write_interactive_page` writes the page that :mod:`drillstring.report` builds (the case, the tables,
the run) with interactive figures in place of the static ones: zoom and pan, values on hover, series shown
or hidden from the legend — a study's single realizations are in the legend, hidden until clicked. The
figures are drawn by plotly.js, inlined in the page (from the ``plotly`` package, imported only here, when
a page is written), so the page works offline, alone: no network, no other file. The static PNG figures
stay beside it.

A figure is a plain mapping ``{"title", "caption", "data", "layout"}`` (plotly.js traces and layout, values
already in display units): :func:`study_figures`, :func:`map_figures`, :func:`probability_map_figures` and
:func:`sensitivity_figures` build them from the package's results (SI), axes and values in the unit system
``units`` (``"si"``, ``"field"``; None: ``$DRILLSTRING_UNITS``, else si; :func:`drillstring.units.display_unit`).
A layout ``height`` [px] sets the height of the figure's element too (default 480 px).
The page sets ``data-plots-rendered`` on ``<body>`` to the number of figures drawn once plotly.js has drawn them
all, and ``data-plot-error`` if drawing one failed.
"""

from __future__ import annotations

import html
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from drillstring.files import write_text_atomic
from drillstring.quantities import DISPLAY_KINDS
from drillstring.units import display_unit

__all__ = ["REALIZATIONS_SHOWN", "map_figures", "sensitivity_figures", "study_figures", "write_interactive_page"]

#: Realizations of a study carried in the page (the first ones finished), each hidden until clicked.
REALIZATIONS_SHOWN = 20

_RPM = 60.0 / (2.0 * math.pi)
_CONFIG = {"responsive": True, "displaylogo": False, "scrollZoom": True}
_CSS = """
.plot { width: 100%; height: 480px; border: 1px solid #eee; margin: 0.4em 0 0.2em; }
p.hint { color: #555; font-size: 0.9em; }
"""


def _values(values, factor: float = 1.0) -> list[float | None]:
    """Numbers for the page: scaled, 6 significant digits, ``None`` (a gap) where not finite."""
    array = np.asarray(values, dtype=float).ravel() * factor
    return [float(f"{v:.6g}") if math.isfinite(v) else None for v in array]


def _grid(values, factor: float = 1.0) -> list[list[float | None]]:
    return [_values(row, factor) for row in np.atleast_2d(np.asarray(values, dtype=float))]


def _figure(title: str, caption: str, data: list[dict], xlabel: str, ylabel: str, **layout: Any) -> dict:
    base = {"title": {"text": title}, "xaxis": {"title": {"text": xlabel}}, "yaxis": {"title": {"text": ylabel}},
            "hovermode": "closest", "margin": {"t": 50, "r": 20},
            "legend": {"groupclick": "toggleitem", "traceorder": "grouped"}}
    for key, value in layout.items():
        base[key] = {**base[key], **value} if isinstance(base.get(key), dict) else value
    return {"title": title, "caption": caption, "data": data, "layout": base}


# ---------------------------------------------------------------------------------------------------------
# Figures from the package's results
# ---------------------------------------------------------------------------------------------------------


def study_figures(stats, realizations=None, *, units: str | None = None) -> list[dict]:
    """Figures of a Monte Carlo study: per observable the 95 % envelope, mean and nominal response with the
    single ``realizations`` (a Dataset with dimension ``realization``, at most :data:`REALIZATIONS_SHOWN`
    used, each hidden until clicked in the legend); the dispersion [%] against time with the transient
    shaded; the convergence ``conv(n_s)``; the stick-slip index of each realization against its drawn
    inputs. ``stats``: :func:`drillstring.stochastic.analysis.study_statistics`; values in ``units``."""
    from drillstring.plots import TITLES
    from drillstring.quantities import stored_observables

    time = _values(stats["time"].values)
    t_transient = float(stats.attrs.get("t_transient", 0.0))
    figures = []
    shown = None
    if realizations is not None and "realization" in realizations.dims:
        shown = realizations.isel(realization=slice(0, REALIZATIONS_SHOWN))
    panels = stored_observables(stats)
    for name in panels:
        unit, title = display_unit(DISPLAY_KINDS[name], units), TITLES[name]
        factor, label = unit.scale, f"{title} [{unit.label}]"
        data = [
            {"type": "scatter", "mode": "lines", "x": time, "y": _values(stats[f"{name}_upper"].values, factor),
             "line": {"width": 0}, "name": "95 % envelope", "legendgroup": "envelope", "showlegend": False,
             "hovertemplate": "upper %{y:.4g}<extra></extra>"},
            {"type": "scatter", "mode": "lines", "x": time, "y": _values(stats[f"{name}_lower"].values, factor),
             "line": {"width": 0}, "fill": "tonexty", "fillcolor": "rgba(31,119,180,0.25)", "name": "95 % envelope",
             "legendgroup": "envelope", "hovertemplate": "lower %{y:.4g}<extra></extra>"},
            {"type": "scatter", "mode": "lines", "x": time, "y": _values(stats[f"{name}_mean"].values, factor),
             "line": {"color": "#1f77b4", "width": 1.6}, "name": "mean"},
            {"type": "scatter", "mode": "lines", "x": time, "y": _values(stats[f"{name}_nominal"].values, factor),
             "line": {"color": "#d62728", "width": 1.2, "dash": "dash"}, "name": "nominal"},
        ]
        if shown is not None and name in shown:
            for j, index in enumerate(shown["realization"].values):
                data.append({"type": "scatter", "mode": "lines", "x": time,
                             "y": _values(shown[name].isel(realization=j).values, factor),
                             "line": {"width": 0.9}, "opacity": 0.8, "visible": "legendonly",
                             "name": f"realization {int(index)}", "legendgroup": "realizations",
                             "legendgrouptitle": {"text": "realizations (click)"}})
        figures.append(_figure(f"{title}: envelope, mean, nominal", f"{label} against time; the single "
                               "realizations are in the legend, hidden until clicked.", data, "time [s]", label))
    dispersion = []
    for name in panels:
        key = f"{name}_dispersion"
        if key in stats:
            dispersion.append({"type": "scatter", "mode": "lines", "x": time, "y": _values(stats[key].values, 100.0),
                               "name": TITLES[name]})
    shapes = [{"type": "rect", "xref": "x", "yref": "paper", "x0": float(stats["time"].values[0]), "x1": t_transient,
               "y0": 0, "y1": 1, "fillcolor": "rgba(128,128,128,0.15)", "line": {"width": 0}}]
    figures.append(_figure("Dispersion std/|mean|", f"Dispersion [%] against time; shaded: the transient "
                           f"(t < {t_transient:g} s).", dispersion, "time [s]", "dispersion [%]", shapes=shapes))
    convergence = []
    for name in list(panels) + ["radial_displacement"]:
        key = f"{name}_convergence"
        if key in stats:
            values = np.asarray(stats[key].values, dtype=float)
            last = values[-1] if values.size and np.isfinite(values[-1]) and values[-1] != 0 else 1.0
            convergence.append({"type": "scatter", "mode": "lines+markers", "marker": {"size": 4},
                                "x": _values(stats[key]["n_samples"].values), "y": _values(values / last),
                                "name": TITLES.get(name, name)})
    figures.append(_figure("Mean-square convergence", "conv(n_s) / conv(n_s max): levelling off at 1 shows that "
                           "the number of realizations suffices.", convergence, "number of realizations n_s",
                           "conv(n_s) / conv(n_s max)"))
    metric = "realization_stick_slip_index"
    if metric in stats and "input_values" in stats and stats["input_values"].size:
        inputs = stats["input_values"]
        data = []
        for k, path in enumerate(inputs["parameter"].values):
            unit = str(inputs["parameter_unit"].values[k]) if "parameter_unit" in inputs.coords else ""
            data.append({"type": "scatter", "mode": "markers", "x": _values(inputs.isel(parameter=k).values),
                         "y": _values(stats[metric].values),
                         "text": [f"realization {int(r)}" for r in inputs["realization"].values],
                         "name": f"{path} [{unit}]" if unit else str(path), "visible": True if k == 0 else "legendonly",
                         "hovertemplate": "%{text}<br>input %{x:.6g}<br>stick-slip index %{y:.4g}<extra></extra>"})
        figures.append(_figure("Stick-slip index of each realization", "(max − min)/(2·mean) of the bit speed after "
                               "the transient against each drawn input (SI units; one input shown at a time from "
                               "the legend).", data, "drawn input [SI]", "stick-slip index [-]"))
    return figures


def map_figures(ds, *, units: str | None = None) -> list[dict]:
    """Figures of an operating map (:func:`drillstring.stochastic.operating_map.map_dataset`): one heat map per
    panel of the static figure over top speed [rpm] × weight-on-bit (kN or klbf, by ``units``), with the
    stability boundary of steady drilling (growth rate 0) and the lateral buckling limit; failed points are
    gaps."""
    from drillstring.plots import MAP_PANELS, axis_unit

    force = display_unit("force", units)
    speeds = np.asarray(ds["top_speed"].values, dtype=float) * _RPM
    weights = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    done = np.asarray(ds["status"].values) == 1
    growth = np.asarray(ds["growth_rate"].values, dtype=float)
    critical = force(float(ds.attrs.get("critical_weight_on_bit", np.nan)))
    figures = []
    for name, kind, title, _, _ in MAP_PANELS:
        unit = axis_unit(kind, units)
        label = f"{title} [{unit.label}]"
        values = np.where(done, unit(np.asarray(ds[name].values, dtype=float)), np.nan)
        data = [_heatmap(speeds, weights, values, label, title, force.label)]
        if speeds.size >= 2 and weights.size >= 2 and np.nanmax(growth) > 0 > np.nanmin(growth):
            data.append({"type": "contour", "x": _values(speeds), "y": _values(weights), "z": _grid(growth.T),
                         "contours": {"start": 0, "end": 0, "size": 1, "coloring": "none"}, "showscale": False,
                         "line": {"color": "black", "width": 2}, "name": "stability boundary (growth rate 0)",
                         "showlegend": True, "hoverinfo": "skip"})
        figures.append(_figure(title, f"{label} over the map; black: linear stability boundary of steady drilling; "
                               f"red dashed: lateral buckling limit ({critical:.4g} {force.label}).", data,
                               "top speed [rpm]", f"weight-on-bit [{force.label}]",
                               shapes=_buckling_line(critical, weights),
                               legend={"orientation": "h", "y": -0.2}))
    figures += _family_figures(ds, speeds, weights, critical, force.label)
    return figures


def _family_figures(ds, speeds, weights, critical: float, force: str) -> list[dict]:
    """One heat map per family of :data:`~drillstring.plots.STABILITY_PANELS` whose growth rate the map holds
    (``<family>_growth_rate`` [1/s], on a blue–red scale centred on 0, with its zero contour): the torsional
    and axial stability that a buckled string's lateral root hides in the overall growth rate."""
    from drillstring.plots import STABILITY_PANELS

    figures = []
    for family, title in STABILITY_PANELS:
        name = f"{family}_growth_rate"
        if name not in ds or not np.isfinite(np.asarray(ds[name].values, dtype=float)).any():
            continue
        growth = np.asarray(ds[name].values, dtype=float)
        label = f"growth rate of the leading {family} root [1/s]"
        data = [_heatmap(speeds, weights, growth, label, title, force, colorscale="RdBu", reversescale=True,
                         zmid=0.0)]
        if speeds.size >= 2 and weights.size >= 2 and np.nanmax(growth) > 0 > np.nanmin(growth):
            data.append({"type": "contour", "x": _values(speeds), "y": _values(weights), "z": _grid(growth.T),
                         "contours": {"start": 0, "end": 0, "size": 1, "coloring": "none"}, "showscale": False,
                         "line": {"color": "black", "width": 2}, "name": f"{family} stability boundary",
                         "showlegend": True, "hoverinfo": "skip"})
        figures.append(_figure(f"stability of the {title}", f"{label} over the map (blue decays, red grows); "
                               f"black: where it crosses 0; red dashed: lateral buckling limit ({critical:.4g} "
                               f"{force}).", data, "top speed [rpm]", f"weight-on-bit [{force}]",
                               shapes=_buckling_line(critical, weights), legend={"orientation": "h", "y": -0.2}))
    return figures


def _heatmap(speeds, weights, values, label: str, title: str, force: str, **extra: Any) -> dict:
    """A heat map of ``values`` (top speed × weight-on-bit) over ``speeds`` [rpm] × ``weights`` [``force``, the
    force unit's label]."""
    return {"type": "heatmap", "x": _values(speeds), "y": _values(weights), "z": _grid(np.asarray(values).T),
            "colorscale": "Viridis", "colorbar": {"title": {"text": label, "side": "right"}}, "name": title,
            "hovertemplate": f"%{{x:.4g}} rpm, %{{y:.4g}} {html.escape(force)}<br>" + html.escape(title)
                             + " %{z:.4g}<extra></extra>",
            **extra}


def _buckling_line(critical: float, weights) -> list[dict]:
    """The lateral buckling limit ``critical`` as a dashed line, when it lies on the map (both in one force
    unit)."""
    if np.isfinite(critical) and np.min(weights) <= critical <= np.max(weights):
        return [{"type": "line", "xref": "paper", "x0": 0, "x1": 1, "yref": "y", "y0": critical, "y1": critical,
                 "line": {"color": "#d62728", "dash": "dash", "width": 2}}]
    return []


def probability_map_figures(ds, *, units: str | None = None) -> list[dict]:
    """Figures of a probabilistic operating map (:func:`drillstring.stochastic.probabilistic_map.
    sampled_map_dataset`): one heat map per probability (scale 0–1) over top speed [rpm] × weight-on-bit (kN or
    klbf, by ``units``), the hover showing each point's value and binomial standard error, with the nominal
    lateral buckling limit."""
    from drillstring.plots import PROBABILITY_PANELS

    force = display_unit("force", units)
    speeds = np.asarray(ds["top_speed"].values, dtype=float) * _RPM
    weights = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    critical = force(float(ds.attrs.get("critical_weight_on_bit", np.nan)))
    figures = []
    for name, label in PROBABILITY_PANELS:
        error = _grid(np.asarray(ds[f"{name}_standard_error"].values, dtype=float).T)
        data = [_heatmap(speeds, weights, ds[name].values, label, label, force.label, zmin=0.0, zmax=1.0,
                         colorscale="RdYlGn", reversescale=True, customdata=error,
                         hovertemplate=f"%{{x:.4g}} rpm, %{{y:.4g}} {html.escape(force.label)}<br>"
                         + html.escape(label) + " %{z:.3f} ± %{customdata:.3f}<extra></extra>")]
        figures.append(_figure(label, f"{label.capitalize()} over the map, from {int(ds.attrs['samples'])} "
                               "realizations per point (± binomial standard error); red dashed: lateral buckling "
                               f"limit of the nominal string ({critical:.4g} {force.label}).", data,
                               "top speed [rpm]", f"weight-on-bit [{force.label}]",
                               shapes=_buckling_line(critical, weights)))
    return figures


def sensitivity_figures(indices: Mapping[str, Any]) -> list[dict]:
    """Figures of a sensitivity analysis (the JSON form of a :class:`~drillstring.stochastic.sensitivity.
    SobolResult`): first-order and total Sobol' indices per output and parameter, with their confidence
    intervals as error bars."""
    from drillstring.plots import OUTPUT_TITLES, short_labels

    parameters = list(indices["parameters"])
    outputs = list(indices["outputs"])
    names = [OUTPUT_TITLES.get(o, o) for o in outputs]
    figures = []
    for kind, title in (("S1", "First-order Sobol' indices S1"), ("ST", "Total Sobol' indices ST")):
        data = []
        for parameter, label in zip(parameters, short_labels(parameters)):
            values = [indices["outputs"][o][kind].get(parameter) for o in outputs]
            intervals = [indices["outputs"][o][f"{kind}_ci"].get(parameter) or [None, None] for o in outputs]
            plus = [None if v is None or ci[1] is None else ci[1] - v for v, ci in zip(values, intervals)]
            minus = [None if v is None or ci[0] is None else v - ci[0] for v, ci in zip(values, intervals)]
            data.append({"type": "bar", "x": names, "y": _values([np.nan if v is None else v for v in values]),
                         "name": label, "error_y": {"type": "data", "symmetric": False,
                                                    "array": _values([np.nan if v is None else v for v in plus]),
                                                    "arrayminus": _values([np.nan if v is None else v for v in minus])},
                         "hovertemplate": "%{x}: %{y:.3f}<extra>" + html.escape(label) + "</extra>"})
        figures.append(_figure(title, f"{kind} of each output per parameter, with the bootstrap confidence "
                               "intervals.", data, "output", kind, barmode="group"))
    return figures


# ---------------------------------------------------------------------------------------------------------
# The page
# ---------------------------------------------------------------------------------------------------------


def _json(value: Any) -> str:
    """JSON for an inline ``<script>``: no ``</`` that would end the element, no NaN (invalid JSON)."""
    return json.dumps(value, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")


_DRAW = """
(function () {
  var specs = document.querySelectorAll('script.figure-spec');
  var drawn = [];
  specs.forEach(function (element) {
    var spec = JSON.parse(element.textContent);
    var div = document.getElementById(element.dataset.target);
    drawn.push(Plotly.newPlot(div, spec.data, spec.layout, spec.config));
  });
  Promise.all(drawn).then(function () {
    document.body.dataset.plotsRendered = String(drawn.length);
  }, function (error) {
    document.body.dataset.plotError = String(error);
    console.error('drawing a figure failed: ' + error);
  });
})();
"""


def figures_html(figures: Sequence[Mapping[str, Any]]) -> str:
    """The figures' elements and their data (no script that draws them: see :func:`write_interactive_page`)."""
    parts = ['<h2>Figures</h2><p class="hint">Drag to zoom (double-click to reset), hover for values, click a '
             "legend entry to show or hide it. The static figures are the PNG files beside this page.</p>"]
    for k, fig in enumerate(figures):
        target = f"figure-{k}"
        spec = {"data": list(fig["data"]), "layout": dict(fig["layout"]), "config": _CONFIG}
        height = spec["layout"].get("height")  # a taller figure gets a taller element, else it is cut off
        style = f' style="height: {int(height)}px"' if height else ""
        parts.append(f'<figure><div class="plot" id="{target}"{style}></div>'
                     f'<figcaption>{html.escape(str(fig.get("caption", "")))}</figcaption></figure>'
                     f'<script type="application/json" class="figure-spec" data-target="{target}">'
                     f"{_json(spec)}</script>")
    return "\n".join(parts)


def write_interactive_page(path: str | Path, head: str, body: str, figures: Sequence[Mapping[str, Any]]) -> Path:
    """Write the page: ``head`` (HTML for ``<head>``: title, charset, style), ``body`` (the report's sections),
    then the ``figures`` drawn by the inlined plotly.js. Atomic; returns the path."""
    from plotly.offline import get_plotlyjs

    library = get_plotlyjs().replace("</script", "<\\/script")
    page = "\n".join([
        "<!DOCTYPE html>",
        '<html lang="en"><head>',
        head,
        f"<style>{_CSS}</style>",
        f"<script>{library}</script>",
        "</head><body>",
        body,
        figures_html(figures),
        f"<script>{_DRAW}</script>",
        "</body></html>",
    ])
    return write_text_atomic(Path(path), page + "\n")
