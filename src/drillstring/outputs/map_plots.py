"""Matplotlib figures of an operating map: deterministic, its stability, probabilistic (no physics here)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from drillstring.outputs import canvas
from drillstring.outputs.canvas import RPM, axis_unit, case_name
from drillstring.units import DisplayUnit, display_unit

MAP_PANELS = (
    ("mean_rate_of_penetration", "rate_of_penetration", "mean rate of penetration", "viridis", False),
    ("bit_speed_oscillation", None, "bit-speed oscillation (max − min)/2Ω", "magma_r", False),
    ("mechanical_specific_energy", "pressure", "mechanical specific energy", "cividis_r", True),
    ("max_radial_displacement", "small_length", "max radial displacement at the probes", "plasma", False),
)


def _map_panel(ax, fig, x: np.ndarray, y: np.ndarray, z: np.ndarray, label: str, cmap: str,
               log: bool = False) -> None:
    """Filled contours of ``z`` (shape (len(x), len(y))) over x (abscissa) and y (on a logarithmic colour
    scale when ``log`` and every value is positive), or coloured markers when an axis has a single value."""
    from matplotlib import ticker
    from matplotlib.colors import LogNorm

    finite = np.isfinite(z)
    if not finite.any():
        ax.text(0.5, 0.5, "no value", ha="center", va="center", transform=ax.transAxes)
        return
    lo, hi = float(np.min(z[finite])), float(np.max(z[finite]))
    scale = dict(norm=LogNorm(lo, hi)) if log and lo > 0 and hi > lo else {}
    ticks = {}
    levels = 12
    if scale:  # ten levels per decade, ticks 1-2-5 labelled in plain numbers
        def within(values):
            return values[(values > lo) & (values < hi)]

        marks = within(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)).tick_values(lo, hi))
        ticks = dict(ticks=marks, format=ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        fine = within(ticker.LogLocator(base=10, subs=10 ** (np.arange(10) / 10)).tick_values(lo, hi))
        levels = np.unique(np.concatenate([[lo], fine, [hi]]))
    if x.size >= 2 and y.size >= 2 and hi > lo:
        artist = ax.contourf(x, y, z.T, levels=levels, cmap=cmap, **scale)
    else:
        xx, yy = np.meshgrid(x, y, indexing="ij")
        artist = ax.scatter(xx.ravel(), yy.ravel(), c=z.ravel(), cmap=cmap, s=80, zorder=2, **scale)
    fig.colorbar(artist, ax=ax, label=label, **ticks)


def plot_map(ds: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """Operating map (a Dataset of :func:`drillstring.stochastic.operating_map.map_dataset`) as four panels
    over top speed [rpm] × weight-on-bit [kN]: mean ROP, bit-speed oscillation, mechanical specific energy
    and the largest radial displacement at the probes, each with the boundary of linear stability of
    steady drilling (growth rate 0; the unstable side hatched), the lateral buckling limit (critical
    weight-on-bit, dashed) and the simulated points (failed ones as crosses). Written to the PNG ``path``, in
    the units of ``units``."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    x = np.asarray(ds["top_speed"].values, dtype=float) * RPM
    force = display_unit("force", units)
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    growth = np.asarray(ds["growth_rate"].values, dtype=float)
    status = np.asarray(ds["status"].values)
    critical = force(float(ds.attrs.get("critical_weight_on_bit", np.nan)))
    fig, axes = canvas.new_figure(2, 2, (12.0, 9.0))
    xx, yy = np.meshgrid(x, y, indexing="ij")
    contour_ok = x.size >= 2 and y.size >= 2 and np.isfinite(growth).sum() >= 4
    for ax, (name, kind, title, cmap, log) in zip(axes, MAP_PANELS):
        shown = axis_unit(kind, units)
        label = f"{title} [{shown.label}]"
        values = shown(np.asarray(ds[name].values, dtype=float))
        values = np.where(status == 1, values, np.nan)
        _map_panel(ax, fig, x, y, values, label, cmap, log)
        if contour_ok and np.nanmax(growth) > 0 > np.nanmin(growth):
            ax.contour(x, y, growth.T, levels=[0.0], colors="k", linewidths=1.6)
        if contour_ok and np.nanmax(growth) > 0:
            ax.contourf(x, y, growth.T, levels=[0.0, np.inf], colors="none", hatches=["//"])
        if np.isfinite(critical) and y.min() <= critical <= y.max():
            ax.axhline(critical, color="C3", ls="--", lw=1.6)
        done = status == 1
        ax.plot(xx[done], yy[done], ".", color="k", ms=3, clip_on=False)
        if (~done).any():
            ax.plot(xx[~done], yy[~done], "x", color="C3", ms=6, clip_on=False)
        _mark_coexisting(ax, ds, xx, yy)
        ax.set_xlabel("top speed [rpm]")
        ax.set_ylabel(f"weight-on-bit [{force.label}]")
        ax.set_title(title, fontsize="medium")
    buckling = (f"lateral buckling, WOB = {critical:.4g} {force.label}" if np.isfinite(critical)
                and y.min() <= critical <= y.max()
                else f"lateral buckling at {critical:.4g} {force.label} (off the map)")
    handles = [Line2D([], [], color="k", lw=1.6, label="linear stability boundary (growth rate 0)"),
               Patch(facecolor="none", edgecolor="k", hatch="//", label="steady drilling linearly unstable"),
               Line2D([], [], color="C3", ls="--", lw=1.6, label=buckling),
               Line2D([], [], color="k", marker=".", ls="", label="simulated point")]
    if (status != 1).any():
        handles.append(Line2D([], [], color="C3", marker="x", ls="", label="failed point"))
    title = _legend_and_title(fig, ds, handles, "Operating map")
    t_end, t_tr = ds.attrs.get("t_end"), ds.attrs.get("t_transient")
    if t_end is not None and t_tr is not None:
        title += f" (runs of {float(t_end):g} s, outputs over t ≥ {float(t_tr):g} s)"
    fig.suptitle(title)
    return canvas.save_png(fig, path)


def _legend_and_title(fig, ds: xr.Dataset, handles: list, title: str) -> str:
    """Draw the legend of a map figure below its panels (``handles``, and the mark of coexisting cycles where the
    map has such points); return ``title`` with the case's name."""
    if _coexisting(ds).any():
        handles.append(COEXISTING_HANDLE())
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize="small")
    name = case_name(ds.attrs.get("case", ""))
    return f"{title}: case '{name}'" if name else title


def _coexisting(ds: xr.Dataset) -> np.ndarray:
    """Mask of the map's points where a stick-slip cycle coexists with stable steady drilling."""
    if "coexisting_cycles" not in ds:
        return np.zeros(ds["status"].shape, dtype=bool)
    return np.nan_to_num(np.asarray(ds["coexisting_cycles"].values, dtype=float)) > 0.0


def COEXISTING_HANDLE():  # noqa: N802 - a legend entry, built when drawn
    from matplotlib.lines import Line2D

    return Line2D([], [], color="C1", marker="o", mfc="none", ms=9, mew=1.6, ls="",
                  label="stick-slip although steady drilling is linearly stable (coexisting cycles)")


def _mark_coexisting(ax, ds: xr.Dataset, xx: np.ndarray, yy: np.ndarray) -> None:
    mask = _coexisting(ds)
    if mask.any():
        ax.plot(xx[mask], yy[mask], "o", mfc="none", color="C1", ms=9, mew=1.6, clip_on=False, zorder=3)


#: Families drawn by :func:`plot_map_stability`: family, title.
STABILITY_PANELS = (
    ("torsional", "torsional roots"),
    ("axial", "axial roots"),
    ("lateral", "lateral roots"),
)


def plot_map_stability(ds: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """The linear stability of steady drilling per family over a map (a Dataset of :func:`drillstring.
    stochastic.operating_map.map_dataset`): one panel per family of :data:`STABILITY_PANELS`, the growth rate
    of the family's leading root [1/s] on a diverging scale centred on 0 (blue: decays, red: grows), its
    zero contour (black) and unstable side hatched, so that the torsional and axial stability windows stay
    visible where a buckled string's lateral root leads the map's overall growth rate; the lateral buckling
    limit (red dashed), the points, and the points where a stick-slip cycle coexists with stable steady
    drilling (open orange circles). A family without roots on the map is left blank. Written to the PNG
    ``path``, weights-on-bit in the unit system ``units``."""
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    x = np.asarray(ds["top_speed"].values, dtype=float) * RPM
    force = display_unit("force", units)
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    status = np.asarray(ds["status"].values)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    fig, axes = canvas.new_figure(1, len(STABILITY_PANELS), (6.0 * len(STABILITY_PANELS), 5.6))
    for ax, (family, title) in zip(axes, STABILITY_PANELS):
        name = f"{family}_growth_rate"
        growth = np.asarray(ds[name].values, dtype=float) if name in ds else np.full(xx.shape, np.nan)
        finite = np.isfinite(growth)
        ax.set_title(title, fontsize="medium")
        _points_and_buckling(ax, ds, x, y, force)
        _mark_coexisting(ax, ds, xx, yy)
        if not finite.any():
            ax.text(0.5, 0.5, "no root of this family", ha="center", va="center", transform=ax.transAxes)
            continue
        bound = max(float(np.max(np.abs(growth[finite]))), 1e-12)
        norm = TwoSlopeNorm(vcenter=0.0, vmin=-bound, vmax=bound)
        if x.size >= 2 and y.size >= 2:
            artist = ax.contourf(x, y, growth.T, levels=np.linspace(-bound, bound, 21), cmap="RdBu_r", norm=norm)
            if finite.sum() >= 4 and np.nanmax(growth) > 0 > np.nanmin(growth):
                ax.contour(x, y, growth.T, levels=[0.0], colors="k", linewidths=1.6)
            if finite.sum() >= 4 and np.nanmax(growth) > 0:
                ax.contourf(x, y, growth.T, levels=[0.0, np.inf], colors="none", hatches=["//"])
        else:
            artist = ax.scatter(xx.ravel(), yy.ravel(), c=growth.ravel(), cmap="RdBu_r", norm=norm, s=80, zorder=2)
        stable = int(np.sum(growth[finite] < 0.0))
        ax.set_title(f"{title}: {stable} of {int(finite.sum())} points stable", fontsize="medium")
        fig.colorbar(artist, ax=ax, label=f"growth rate of the leading {family} root [1/s]")
    if (status != 1).any():
        for ax in axes:
            ax.plot(xx[status != 1], yy[status != 1], "x", color="C3", ms=6, clip_on=False)
    critical = force(float(ds.attrs.get("critical_weight_on_bit", np.nan)))
    handles = [Line2D([], [], color="k", lw=1.6, label="family's stability boundary (growth rate 0)"),
               Patch(facecolor="none", edgecolor="k", hatch="//", label="a root of the family grows"),
               Line2D([], [], color="C3", ls="--", lw=1.6,
                      label=f"lateral buckling, WOB = {critical:.4g} {force.label}"),
               Line2D([], [], color="k", marker=".", ls="", label="point")]
    fig.suptitle(_legend_and_title(fig, ds, handles, "Linear stability of steady drilling per family"))
    return canvas.save_png(fig, path)


#: Panels of a probabilistic map: variable, label.
PROBABILITY_PANELS = (
    ("stick_slip_probability", "probability of stick-slip"),
    ("buckling_probability", "probability of a buckled string"),
    ("impact_probability", "probability of wall impact"),
    ("instability_probability", "probability of unstable steady drilling"),
    ("torsional_instability_probability", "probability of a growing torsional root"),
    ("axial_instability_probability", "probability of a growing axial root"),
    ("coexistence_probability", "probability of stick-slip with stable steady drilling"),
    ("bounce_probability", "probability of bit bounce"),
)


def _sampled_map_title(ds: xr.Dataset, what: str) -> str:
    title = what
    name = case_name(ds.attrs.get("case", ""))
    if name:
        title += f": case '{name}'"
    return title + (f" ({int(ds.attrs['samples'])} realizations per point, runs of {float(ds.attrs['t_end']):g} s, "
                    f"outputs over t ≥ {float(ds.attrs['t_transient']):g} s)")


def _points_and_buckling(ax, ds: xr.Dataset, x: np.ndarray, y: np.ndarray, force: DisplayUnit) -> None:
    """The grid points (dots) and the nominal lateral buckling limit (red dashed) on a map panel whose
    weights-on-bit ``y`` are in the unit ``force``."""
    critical = force(float(ds.attrs.get("critical_weight_on_bit", np.nan)))
    if np.isfinite(critical) and y.min() <= critical <= y.max():
        ax.axhline(critical, color="C3", ls="--", lw=1.6)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    ax.plot(xx.ravel(), yy.ravel(), ".", color="k", ms=3, clip_on=False)
    ax.set_xlabel("top speed [rpm]")
    ax.set_ylabel(f"weight-on-bit [{force.label}]")


def _map_legend(fig, ds: xr.Dataset, force: DisplayUnit) -> None:
    from matplotlib.lines import Line2D

    critical = force(float(ds.attrs.get("critical_weight_on_bit", np.nan)))
    handles = [Line2D([], [], color="C3", ls="--", lw=1.6,
                      label=f"lateral buckling of the nominal string, WOB = {critical:.4g} {force.label}"),
               Line2D([], [], color="k", marker=".", ls="", label="grid point")]
    fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize="small")


def plot_probability_map(ds: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """Probabilistic operating map (a Dataset of :func:`drillstring.stochastic.probabilistic_map.
    sampled_map_dataset`) as eight panels over top speed [rpm] × the points' nominal weight-on-bit (kN or klbf):
    the probabilities of :data:`PROBABILITY_PANELS` — stick-slip, a buckled string, wall impact, unstable steady
    drilling (any root, then a torsional and an axial root), stick-slip with stable steady drilling
    (coexisting cycles) and bit bounce (colour scale 0–1), with the nominal lateral buckling limit (dashed) and the points. Written to the PNG ``path``, in
    the units of ``units``."""
    from matplotlib.colors import Normalize

    force = display_unit("force", units)
    x = np.asarray(ds["top_speed"].values, dtype=float) * RPM
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    fig, axes = canvas.new_figure(2, 4, (24.0, 9.0))
    for ax in axes[len(PROBABILITY_PANELS):]:
        ax.set_axis_off()
    levels = np.linspace(0.0, 1.0, 11)
    for ax, (name, label) in zip(axes, PROBABILITY_PANELS):
        z = np.asarray(ds[name].values, dtype=float)
        if x.size >= 2 and y.size >= 2:
            artist = ax.contourf(x, y, np.nan_to_num(z.T, nan=np.nan), levels=levels, cmap="RdYlGn_r",
                                 norm=Normalize(0.0, 1.0), extend="neither")
        else:
            xx, yy = np.meshgrid(x, y, indexing="ij")
            artist = ax.scatter(xx.ravel(), yy.ravel(), c=z.ravel(), cmap="RdYlGn_r", vmin=0.0, vmax=1.0, s=80,
                                zorder=2)
        fig.colorbar(artist, ax=ax, label=label, ticks=levels[::2])
        _points_and_buckling(ax, ds, x, y, force)
        ax.set_title(label, fontsize="medium")
    _map_legend(fig, ds, force)
    fig.suptitle(_sampled_map_title(ds, "Probabilistic operating map"))
    return canvas.save_png(fig, path)


def plot_quantile_map(ds: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """The 2.5, 50 and 97.5 % quantiles of the mean ROP (m/h or ft/h; top row) and of the stick-slip index
    (bottom row) over each point's realizations, over top speed [rpm] × weight-on-bit (kN or klbf), each panel
    on its own colour scale. Written to the PNG ``path``, in the units of ``units``."""
    force = display_unit("force", units)
    x = np.asarray(ds["top_speed"].values, dtype=float) * RPM
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    levels = [float(q) for q in ds["quantile"].values]
    fig, axes = canvas.new_figure(2, len(levels), (5.0 * len(levels), 9.0))
    rows = (("rate_of_penetration_q", "rate_of_penetration", "mean ROP", "viridis"),
            ("stick_slip_index_q", None, "stick-slip index", "magma_r"))
    for r, (name, kind, title, cmap) in enumerate(rows):
        unit = axis_unit(kind, units)
        values = unit(np.asarray(ds[name].values, dtype=float))
        for k, q in enumerate(levels):
            ax = axes[r * len(levels) + k]
            _map_panel(ax, fig, x, y, values[..., k], f"{title} [{unit.label}]", cmap)
            _points_and_buckling(ax, ds, x, y, force)
            ax.set_title(f"{title}: {100 * q:g} % quantile", fontsize="medium")
    _map_legend(fig, ds, force)
    fig.suptitle(_sampled_map_title(ds, "Quantiles over the realizations"))
    return canvas.save_png(fig, path)

