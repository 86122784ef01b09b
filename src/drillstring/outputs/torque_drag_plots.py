"""Figures of the well and its torque and drag (no physics here): the vertical section and plan view, the
loads along the string, the broomstick chart with measured hook loads and posterior bands, the stiff string
in the well coloured by its contact force per node (Matplotlib), and the interactive 3-D well path (plotly
figure specs for :func:`drillstring.interactive.write_interactive_page`).

Inputs are the SI results of :mod:`drillstring.well`; axes are in the unit system ``units`` (``"si"``,
``"field"``; None: ``$DRILLSTRING_UNITS``, else si).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from drillstring.outputs.canvas import new_figure, save_png
from drillstring.units import display_unit

__all__ = ["plot_broomstick", "plot_string_in_well", "plot_torque_drag", "plot_well_path", "string_in_well_figure",
           "well_figures"]

_LABELS = {"trip_out": "trip out", "trip_in": "trip in", "rotating_off_bottom": "rotating off bottom",
           "sliding": "sliding", "drilling": "drilling"}
_COLORS = {"trip_out": "C3", "trip_in": "C0", "rotating_off_bottom": "C2", "sliding": "C4", "drilling": "C1"}


def plot_well_path(trajectory, path: str | Path, *, casing_shoe: float = 0.0, title: str = "Well path",
                   units: str | None = None) -> Path:
    """Vertical section (along the direction of the bottom hole) and plan view of a trajectory."""
    length = display_unit("length", units)
    fig, (section, plan) = new_figure(1, 2, (11.0, 5.0))
    vs = trajectory.vertical_section() * length.scale
    tvd = trajectory.true_vertical_depth * length.scale
    section.plot(vs, tvd, "-", color="C0", lw=2)
    section.plot(vs, tvd, ".", color="C0", ms=3, label="survey stations")
    if casing_shoe > 0.0:
        shoe = trajectory.locate([casing_shoe])[0][0]
        direction = np.arctan2(trajectory.position[-1, 1], trajectory.position[-1, 0])
        shoe_vs = (shoe[0] * np.cos(direction) + shoe[1] * np.sin(direction)) * length.scale
        section.plot([shoe_vs], [shoe[2] * length.scale], "k^", ms=8, label="casing shoe")
    section.invert_yaxis()
    section.set_xlabel(f"vertical section [{length.label}]")
    section.set_ylabel(f"true vertical depth [{length.label}]")
    section.set_title("Vertical section")
    section.set_aspect("equal", adjustable="datalim")
    section.legend(loc="upper right")
    plan.plot(trajectory.position[:, 1] * length.scale, trajectory.position[:, 0] * length.scale, "-", color="C0",
              lw=2)
    plan.plot([0], [0], "ko", ms=5, label="wellhead")
    plan.set_xlabel(f"east [{length.label}]")
    plan.set_ylabel(f"north [{length.label}]")
    plan.set_title("Plan view")
    plan.set_aspect("equal", adjustable="datalim")
    plan.legend(loc="best")
    fig.suptitle(title)
    return save_png(fig, path)


def string_in_well_figure(state, *, title: str = "String in the well", units: str | None = None):
    """The stiff string in its well (a :class:`~drillstring.well.stiff_string.StiffStringState`, or any object
    with its ``position`` (n, 3) global (TVD, north, east) [m], ``measured_depth`` (n,) [m], ``side_force`` (n,)
    [N]: the wall's and stabilizers' force on each node, and ``hook_load`` [N]): left, the 3-D path (east, north,
    TVD down) with each node in contact coloured by its contact (side) force; right, that force per node against
    measured depth. Returns the Matplotlib figure (Agg canvas)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    length, force = display_unit("length", units), display_unit("force", units)
    position = np.asarray(state.position, dtype=float) * length.scale
    side = np.asarray(state.side_force, dtype=float) * force.scale
    depth = np.asarray(state.measured_depth, dtype=float) * length.scale
    touching = side > 0.0
    fig = Figure(figsize=(13.0, 6.0), layout="constrained")
    FigureCanvasAgg(fig)
    path3d = fig.add_subplot(1, 2, 1, projection="3d")
    profile = fig.add_subplot(1, 2, 2)
    path3d.plot(position[:, 2], position[:, 1], position[:, 0], "-", color="0.55", lw=1.2, label="string")
    path3d.plot(position[~touching, 2], position[~touching, 1], position[~touching, 0], ".", color="0.75", ms=2,
                label="free nodes")
    high = float(side.max()) if side.size and side.max() > 0.0 else 1.0
    points = path3d.scatter(position[touching, 2], position[touching, 1], position[touching, 0], c=side[touching],
                            cmap="viridis", vmin=0.0, vmax=high, s=10, depthshade=False, label="nodes on the wall")
    path3d.set_aspect("equal")
    path3d.invert_zaxis()
    path3d.set_xlabel(f"east [{length.label}]")
    path3d.set_ylabel(f"north [{length.label}]")
    path3d.set_zlabel(f"TVD [{length.label}]", labelpad=12)
    path3d.set_title("String in the well")
    path3d.legend(loc="upper left", fontsize=8)
    fig.colorbar(points, ax=path3d, shrink=0.6, label=f"contact force per node [{force.label}]")
    profile.plot(side, depth, "-", color="0.6", lw=0.8)
    profile.scatter(side[touching], depth[touching], c=side[touching], cmap="viridis", vmin=0.0, vmax=high, s=10)
    profile.plot(np.zeros(np.count_nonzero(~touching)), depth[~touching], ".", color="0.75", ms=2)
    profile.invert_yaxis()
    profile.set_xlabel(f"contact (side) force per node [{force.label}]")
    profile.set_ylabel(f"measured depth [{length.label}]")
    profile.set_title(f"{int(touching.sum())} of {side.size} nodes on the wall, total {side.sum():,.1f} {force.label}")
    profile.grid(alpha=0.3)
    hook = getattr(state, "hook_load", None)
    fig.suptitle(title if hook is None else f"{title}: hook load {float(hook) * force.scale:,.2f} {force.label}")
    return fig


def plot_string_in_well(state, path: str | Path, *, title: str = "String in the well",
                        units: str | None = None) -> Path:
    """Write :func:`string_in_well_figure` of ``state`` as the PNG ``path``."""
    return save_png(string_in_well_figure(state, title=title, units=units), path)


def _axial_range(results: Mapping[str, Any]) -> tuple[float, float]:
    """The axial-force axis [N] of the loads: the largest compression with a margin, to the largest tension
    (the critical compressions of buckling, often far larger, are cut)."""
    low = min(float(np.min(r.axial_force)) for r in results.values())
    high = max(float(np.max(r.axial_force)) for r in results.values())
    return min(low * 1.3, -0.05 * high), high * 1.05


def plot_torque_drag(results: Mapping[str, Any], path: str | Path, *, critical: Mapping[str, np.ndarray] | None = None,
                     title: str = "Torque and drag", units: str | None = None) -> Path:
    """Effective axial force, torque and side force per length against measured depth for each operation;
    the critical compressions of sinusoidal and helical buckling drawn on the axial force."""
    force, length, torque = (display_unit(k, units) for k in ("force", "length", "torque"))
    fig, (axial, twist, side) = new_figure(1, 3, (14.0, 6.0))
    for op, r in results.items():
        depth = r.measured_depth * length.scale
        axial.plot(r.axial_force * force.scale, depth, color=_COLORS.get(op), label=_LABELS.get(op, op))
        if np.any(r.torque):
            twist.plot(r.torque * torque.scale, depth, color=_COLORS.get(op), label=_LABELS.get(op, op))
        side.plot(r.side_force * force.scale / length.scale, depth, color=_COLORS.get(op), lw=1)
    if critical is not None:
        depth = next(iter(results.values())).measured_depth * length.scale
        axial.plot(-critical["sinusoidal"] * force.scale, depth, "k--", lw=1, label="sinusoidal buckling")
        axial.plot(-critical["helical"] * force.scale, depth, "k:", lw=1, label="helical buckling")
        axial.set_xlim(left=_axial_range(results)[0] * force.scale)
    axial.axvline(0.0, color="0.6", lw=0.8)
    for ax, label in ((axial, f"effective axial force [{force.label}] (tension > 0)"),
                      (twist, f"torque [{torque.label}]"), (side, f"side force [{force.label}/{length.label}]")):
        ax.set_xlabel(label)
        ax.invert_yaxis()
        ax.set_ylabel(f"measured depth [{length.label}]")
        ax.grid(alpha=0.3)
    axial.legend(loc="upper left", fontsize=8)
    twist.legend(loc="lower left", fontsize=8)
    fig.suptitle(title)
    return save_png(fig, path)


def plot_broomstick(bit_depths, chart: Mapping[str, np.ndarray], frictions: Sequence[float], path: str | Path, *,
                    measurements=None, bands: Mapping[str, np.ndarray] | None = None,
                    title: str = "Broomstick chart", units: str | None = None) -> Path:
    """Hook load against bit depth for each operation and friction factor (:func:`drillstring.well.calibration.
    broomstick`), the measured hook loads as points, and posterior bands (5-95 %) if given."""
    force, length = display_unit("force", units), display_unit("length", units)
    fig, (ax,) = new_figure(1, 1, (8.0, 8.0))
    depth = np.asarray(bit_depths) * length.scale
    styles = ["-", "--", "-.", ":", (0, (5, 1, 1, 1, 1, 1))]
    for op, loads in chart.items():
        for j, mu in enumerate(frictions):
            label = f"{_LABELS.get(op, op)}, μ = {mu:g}" if op != "rotating_off_bottom" or j == 0 else None
            if op == "rotating_off_bottom":
                label = _LABELS[op] if j == 0 else None
            ax.plot(loads[:, j] * force.scale, depth, color=_COLORS.get(op), ls=styles[j % len(styles)], lw=1.2,
                    label=label)
    if bands is not None:
        for op in chart:
            if op in bands:
                q = bands[op] * force.scale
                ax.fill_betweenx(depth, q[:, 0], q[:, -1], color=_COLORS.get(op), alpha=0.25,
                                 label=f"{_LABELS.get(op, op)}: posterior 5-95 %")
    if measurements is not None:
        for op in sorted(set(measurements.operation)):
            pick = np.array([o == op for o in measurements.operation])
            ax.plot(measurements.hook_load[pick] * force.scale, measurements.bit_depth[pick] * length.scale, "o",
                    mfc="white", color=_COLORS.get(op, "k"), ms=6, label=f"measured, {_LABELS.get(op, op)}")
    ax.invert_yaxis()
    ax.set_xlabel(f"hook load [{force.label}]")
    ax.set_ylabel(f"bit measured depth [{length.label}]")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(title)
    return save_png(fig, path)


def _hex(color: str) -> str:
    """A Matplotlib colour (``"C3"``: the current cycle's) as ``#rrggbb``, so the page draws what the PNG does."""
    from matplotlib.colors import to_hex

    return to_hex(color)


def _profile_figure(title: str, caption: str, data: list[dict], xlabel: str, ylabel: str) -> dict:
    """A plotly figure of profiles against measured depth (downwards), like one panel of :func:`plot_torque_drag`."""
    return {"title": title, "caption": caption, "data": data,
            "layout": {"title": {"text": title}, "hovermode": "closest", "margin": {"t": 50, "r": 20},
                       "xaxis": {"title": {"text": xlabel}, "zeroline": True},
                       "yaxis": {"title": {"text": ylabel}, "autorange": "reversed"}}}


def _profiles(results: Mapping[str, Any], quantity: str, scale: float, depth_scale: float, *,
              skip_zero: bool = False) -> list[dict]:
    """One line per operation of ``results``: its ``quantity`` × ``scale`` against the measured depth ×
    ``depth_scale``, coloured as in the PNG (:data:`_COLORS`); ``skip_zero``: operations where it is 0
    throughout left out."""
    traces = []
    for op, r in results.items():
        values = np.asarray(getattr(r, quantity), dtype=float)
        if skip_zero and not np.any(values):
            continue
        traces.append({"type": "scatter", "mode": "lines", "name": _LABELS.get(op, op),
                       "line": {"color": _hex(_COLORS.get(op, "k")), "width": 1.8},
                       "x": np.nan_to_num(values * scale).tolist(),
                       "y": (np.asarray(r.measured_depth) * depth_scale).tolist()})
    return traces


def well_figures(trajectory, results: Mapping[str, Any] | None = None, *,
                 critical: Mapping[str, np.ndarray] | None = None, units: str | None = None) -> list[dict]:
    """Interactive figures (plotly specs, values in the display units of ``units``): the 3-D well path (north,
    east, TVD down), coloured by the side force of rotating off bottom when ``results`` are given, then the
    three panels of :func:`plot_torque_drag` in its colours: the effective axial force (with the ``critical``
    compressions of sinusoidal and helical buckling), the torque and the side force per length, against
    measured depth."""
    length, force, torque = (display_unit(k, units) for k in ("length", "force", "torque"))
    s = np.linspace(0.0, trajectory.depth, max(200, len(trajectory.measured_depth) * 5))
    points = trajectory.locate(s)[0] * length.scale
    trace: dict[str, Any] = {"type": "scatter3d", "mode": "lines", "x": points[:, 1].tolist(),
                             "y": points[:, 0].tolist(), "z": points[:, 2].tolist(), "name": "well path",
                             "line": {"width": 6, "color": _hex("C0")},
                             "text": [f"MD {v:.1f} {length.label}" for v in s * length.scale]}
    caption = "Minimum-curvature path; drag to rotate, scroll to zoom."
    if results is not None and "rotating_off_bottom" in results:
        r = results["rotating_off_bottom"]
        side = np.interp(s, r.measured_depth, r.side_force, right=np.nan) * force.scale / length.scale
        # A line coloured by values has no legend entry (plotly.js cannot draw its swatch): the colour bar names it.
        trace["showlegend"] = False
        trace["line"] = {"width": 6, "color": np.nan_to_num(side).tolist(), "colorscale": "Viridis",
                         "colorbar": {"title": {"text": f"side force [{force.label}/{length.label}]",
                                                "side": "right"}}}
        caption += " Colour: the side force per length when rotating off bottom."
    stations = trajectory.position * length.scale
    figures = [{"title": "Well path (3-D)", "caption": caption,
                "data": [trace, {"type": "scatter3d", "mode": "markers", "x": stations[:, 1].tolist(),
                                 "y": stations[:, 0].tolist(), "z": stations[:, 2].tolist(),
                                 "marker": {"size": 2, "color": "black"}, "name": "survey stations"}],
                "layout": {"title": {"text": "Well path"}, "height": 640, "margin": {"l": 0, "r": 0, "t": 50, "b": 0},
                           "legend": {"x": 0, "y": 1}, "scene": {
                               "xaxis": {"title": {"text": f"east [{length.label}]"}},
                               "yaxis": {"title": {"text": f"north [{length.label}]"}},
                               "zaxis": {"title": {"text": f"TVD [{length.label}]"}, "autorange": "reversed"},
                               "aspectmode": "data", "camera": {"eye": {"x": 1.9, "y": 1.9, "z": 0.9}}}}}]
    if not results:
        return figures
    depth_label = f"measured depth [{length.label}]"
    panels = (("axial_force", force.scale, False, "Effective axial force",
               f"effective axial force [{force.label}] (tension > 0)",
               "Effective axial force along the string for each operation"),
              ("torque", torque.scale, True, "Torque", f"torque [{torque.label}]",
               "Torque along the string (the operations that rotate)"),
              ("side_force", force.scale / length.scale, False, "Side force",
               f"side force [{force.label}/{length.label}]", "Side force per length between string and hole wall"))
    for quantity, scale, skip_zero, title, xlabel, caption in panels:
        data = _profiles(results, quantity, scale, length.scale, skip_zero=skip_zero)
        if quantity == "axial_force" and critical is not None:
            depth = (next(iter(results.values())).measured_depth * length.scale).tolist()
            for kind, dash in (("sinusoidal", "dash"), ("helical", "dot")):
                data.append({"type": "scatter", "mode": "lines", "name": f"{kind} buckling",
                             "line": {"color": "black", "width": 1, "dash": dash},
                             "x": np.nan_to_num(-np.asarray(critical[kind]) * force.scale).tolist(), "y": depth})
            caption += "; dashed and dotted: the critical compressions of sinusoidal and helical buckling"
        figure = _profile_figure(title, caption + ".", data, xlabel, depth_label)
        if quantity == "axial_force" and critical is not None:
            figure["layout"]["xaxis"]["range"] = [v * force.scale for v in _axial_range(results)]
        figures.append(figure)
    return figures
