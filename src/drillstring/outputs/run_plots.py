"""Matplotlib figures of one case (no physics here): a run, the comparison of the two nonlinear models, the Campbell
diagram."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from drillstring.outputs import canvas
from drillstring.outputs.canvas import RPM, axis_label, case_name, probe_index, probe_positions, scaled
from drillstring.units import display_unit

#: The run figure's panels of one observable: panel -> (observable, title or "").
_LINE_PANELS = {"hook_load": ("hook_load", ""),
                "motor_speed": ("motor_speed", "downhole motor: rotor speed relative to its stator"),
                "motor_pressure": ("differential_pressure", "downhole motor: differential pressure")}


#: Fixed margins of the 3 × 2 run figures (11 × 10 in): laid out once by hand instead of by Matplotlib's
#: constrained layout, which measured every text twice and took half the drawing time.
_PANEL_MARGINS = {"left": 0.065, "right": 0.985, "bottom": 0.055, "top": 0.945, "wspace": 0.2, "hspace": 0.34}
_RUN_FIGURE = (11.0, 10.0)

def run_panels(ds: xr.Dataset) -> tuple[str, ...]:
    """The panels of :func:`plot_run` that fit the run's case, in order: ``rop``, ``speed`` (bit, and the
    quill with a top drive), ``radial`` (lateral modes only), ``torque`` (on bit, and at the surface with a
    top drive), ``orbit`` and ``contact`` (lateral modes only), ``force`` (a Detournay bit: the force on bit
    and its wear-flat part), ``depth_of_cut`` (a Detournay bit), ``hook_load`` (a ramped start), and with a
    downhole motor ``motor_speed`` (its rotor relative to its stator) and ``motor_pressure`` (its differential
    pressure; its torque is drawn in the ``torque`` panel). The case
    has lateral modes unless the Dataset's ``lateral_modes`` attribute says 0 (a Dataset without it is taken
    to have them, as runs written before)."""
    lateral = int(ds.attrs.get("lateral_modes", 1)) > 0
    panels = ["rop", "speed"] + (["radial"] if lateral else []) + ["torque"]
    panels += ["orbit", "contact"] if lateral else []
    if "wear_flat_force" in ds:
        panels.append("force")
    if "depth_of_cut" in ds:
        panels.append("depth_of_cut")
    if "hook_load" in ds:
        panels.append("hook_load")
    if "motor_speed" in ds:
        panels += ["motor_speed", "motor_pressure"]
    return tuple(panels)


def plot_run(ds: xr.Dataset, path: str | Path, probe_x: float = 1560.0, *, units: str | None = None) -> Path:
    """The panels of one simulation that fit its case (:func:`run_panels`), written to the PNG ``path``: ROP
    [m/h]; bit speed [rpm] with the top speed (``ds.attrs["top_speed"]`` [rad/s]) dashed and, with a top
    drive, the quill speed; with lateral modes the radial displacement [mm] at the probe nearest ``probe_x``
    [m] with its gap (coordinate ``gap``) dashed; the torque on bit [kN·m] and the surface torque; with lateral modes the whirl orbit at that probe (w against v [mm], the borehole wall a
    circle of radius the gap) and the wall's contact force [kN]; for a Detournay bit the force on bit with its
    wear-flat part [kN] and the depth of cut per blade [mm]; during a ramped start the hook load [kN]; with a
    downhole motor its speed [rpm], its torque (in the torque panel) and its differential pressure [MPa], all
    vs time [s]. A failed (partial) run is plotted as far as it went, with its status in the title. Units
    of ``units`` (see the module docstring).
    """
    small, length = display_unit("small_length", units), display_unit("length", units)
    t = np.asarray(ds["time"].values, dtype=float)
    panels = run_panels(ds)
    rows = (len(panels) + 1) // 2
    fig, grid = canvas.new_figure(rows, 2, (_RUN_FIGURE[0], _RUN_FIGURE[1] * rows / 3), margins=_PANEL_MARGINS)
    for ax in grid[len(panels):]:
        ax.set_axis_off()
    axes = dict(zip(panels, grid))
    imposed = ds.attrs.get("top_drive", "imposed_speed") == "imposed_speed"

    ax_rop = axes["rop"]
    ax_rop.plot(t, scaled(ds["rate_of_penetration"].values, "rate_of_penetration", units), lw=0.9)
    ax_rop.set_ylabel(axis_label("rate_of_penetration", units))

    ax_speed = axes["speed"]
    ax_speed.plot(t, scaled(ds["bit_speed"].values, "bit_speed", units), lw=0.9, label="bit")
    top = ds.attrs.get("top_speed")
    if "quill_speed" in ds and not imposed:
        ax_speed.plot(t, scaled(ds["quill_speed"].values, "quill_speed", units), lw=0.9, label="quill")
    if top is not None:
        ax_speed.axhline(float(top) * RPM, color="k", ls="--", lw=0.9,
                         label="top (imposed)" if imposed else "set point")
    ax_speed.set_ylabel(axis_label("bit_speed", units))
    ax_speed.legend(loc="best", fontsize="small")

    if "radial" in axes:
        ax_radial = axes["radial"]
        x = probe_positions(ds)
        if "radial_displacement" in ds and x.size:
            i = probe_index(x, probe_x)
            r = ds["radial_displacement"].isel(probe=i).values
            r_mm = scaled(r, "radial_displacement", units)
            ax_radial.plot(t, r_mm, lw=0.9, label="r")
            if np.isfinite(r_mm).any():
                # The gap line can dwarf a small orbit: say how large it is.
                ax_radial.text(0.02, 0.95, f"max r = {np.nanmax(r_mm):.3g} {small.label}",
                               transform=ax_radial.transAxes, va="top", fontsize="small")
            if "gap" in ds.coords or "gap" in ds:
                gap = float(np.atleast_1d(ds["gap"].values)[i])
                ax_radial.axhline(small(gap), color="k", ls="--", lw=0.9, label="gap")
            ax_radial.set_title(f"probe at x = {length(x[i]):.0f} {length.label}", fontsize="medium")
            ax_radial.legend(loc="best", fontsize="small")
        else:
            ax_radial.text(0.5, 0.5, "no probe", ha="center", va="center", transform=ax_radial.transAxes)
        ax_radial.set_ylabel(axis_label("radial_displacement", units))

    ax_tob = axes["torque"]
    ax_tob.plot(t, scaled(ds["torque_on_bit"].values, "torque_on_bit", units), lw=0.9, label="on bit")
    if "surface_torque" in ds:
        ax_tob.plot(t, scaled(ds["surface_torque"].values, "surface_torque", units), lw=0.9, label="surface")
    if "motor_torque" in ds:
        ax_tob.plot(t, scaled(ds["motor_torque"].values, "motor_torque", units), lw=0.9, label="motor")
    if "surface_torque" in ds or "motor_torque" in ds:
        ax_tob.legend(loc="best", fontsize="small")
    ax_tob.set_ylabel(axis_label("torque_on_bit", units).replace("torque-on-bit", "torque"))

    if "orbit" in axes:
        _orbit_panel(axes["orbit"], ((ds, "orbit", {"lw": 0.6}),), probe_x, units)
        _contact_panel(axes["contact"], ((ds, None, {"lw": 0.8}),), units)
    if "force" in axes:
        ax = axes["force"]
        ax.plot(t, scaled(ds["force_on_bit"].values, "force_on_bit", units), lw=0.9, label="on bit")
        ax.plot(t, scaled(ds["wear_flat_force"].values, "wear_flat_force", units), lw=0.9,
                label="wear-flat part")
        ax.set_ylabel(axis_label("force_on_bit", units))
        ax.legend(loc="best", fontsize="small")
    if "depth_of_cut" in axes:
        ax = axes["depth_of_cut"]
        ax.plot(t, scaled(ds["depth_of_cut"].values, "depth_of_cut", units), lw=0.9)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_ylabel(axis_label("depth_of_cut", units))
        ax.set_title("depth of cut per blade (≤ 0: the bit off the rock)", fontsize="medium")
    for panel, (name, title) in _LINE_PANELS.items():
        if panel in axes:
            axes[panel].plot(t, scaled(ds[name].values, name, units), lw=0.9)
            axes[panel].set_ylabel(axis_label(name, units))
            axes[panel].set_title(title, fontsize="medium")
    for name, ax in axes.items():
        if name != "orbit":
            ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
    title = "Drilling run"
    name = case_name(ds.attrs.get("case", ""))
    if name:
        title += f": case '{name}'"
    if ds.attrs.get("status", "success") != "success":
        title += f" ({ds.attrs.get('status')}, stopped at t = {t[-1]:.3g} s)" if t.size else " (failed)"
    fig.suptitle(title)
    return canvas.save_png(fig, path)


#: Line styles and legend labels of :func:`plot_compare`: case 1 solid, case 2 dashed.
_COMPARE_STYLES = (
    ("case 1 (full)", {"color": "C0", "ls": "-", "lw": 1.1}),
    ("case 2 (bit–rock + contact)", {"color": "C1", "ls": "--", "lw": 1.1}),
)


def plot_compare(full: xr.Dataset, reduced: xr.Dataset, path: str | Path, probe_x: float = 1560.0, *,
                 units: str | None = None) -> Path:
    """Case 1 (``full``: kinetic- and strain-energy forces included, solid) and case 2 (``reduced``: bit–rock
    and contact forces only, dashed) of the same case overlaid, in the six panels of :func:`plot_run`:
    ROP [m/h], bit speed [rpm] with the top speed, radial displacement [mm] at the probe nearest
    ``probe_x`` [m] with its gap, torque-on-bit [kN·m] vs time [s], the whirl orbits at that probe and the
    contact forces [kN] vs time. Written to the PNG ``path``, in the units of ``units``."""
    small, length = display_unit("small_length", units), display_unit("length", units)
    fig, axes = canvas.new_figure(3, 2, _RUN_FIGURE, margins=_PANEL_MARGINS)
    ax_rop, ax_speed, ax_radial, ax_tob, ax_orbit, ax_contact = axes
    runs = ((full, *_COMPARE_STYLES[0]), (reduced, *_COMPARE_STYLES[1]))

    radial_max: list[str] = []
    probe_title = None
    gap = None
    for ds, label, style in runs:
        t = np.asarray(ds["time"].values, dtype=float)
        ax_rop.plot(t, scaled(ds["rate_of_penetration"].values, "rate_of_penetration", units), label=label,
                    **style)
        ax_speed.plot(t, scaled(ds["bit_speed"].values, "bit_speed", units), label=label, **style)
        ax_tob.plot(t, scaled(ds["torque_on_bit"].values, "torque_on_bit", units), label=label, **style)
        x = probe_positions(ds)
        if "radial_displacement" in ds and x.size:
            i = probe_index(x, probe_x)
            r_mm = scaled(ds["radial_displacement"].isel(probe=i).values, "radial_displacement", units)
            ax_radial.plot(t, r_mm, label=label, **style)
            if np.isfinite(r_mm).any():
                radial_max.append(f"{label.split(' (')[0]}: max r = {np.nanmax(r_mm):.3g} {small.label}")
            probe_title = f"probe at x = {length(x[i]):.0f} {length.label}"
            if gap is None and ("gap" in ds.coords or "gap" in ds):
                gap = float(np.atleast_1d(ds["gap"].values)[i])

    top = full.attrs.get("top_speed", reduced.attrs.get("top_speed"))
    if top is not None:
        ax_speed.axhline(float(top) * RPM, color="k", ls=":", lw=0.9, label="top (imposed)")
    if probe_title is None:
        ax_radial.text(0.5, 0.5, "no probe", ha="center", va="center", transform=ax_radial.transAxes)
    else:
        if gap is not None:
            ax_radial.axhline(small(gap), color="k", ls=":", lw=0.9, label="gap")
        if radial_max:
            # The gap line can dwarf a small orbit: say how large it is.
            ax_radial.text(0.02, 0.95, "\n".join(radial_max), transform=ax_radial.transAxes, va="top",
                           fontsize="small")
        ax_radial.set_title(probe_title, fontsize="medium")

    for ax, name in ((ax_rop, "rate_of_penetration"), (ax_speed, "bit_speed"),
                     (ax_radial, "radial_displacement"), (ax_tob, "torque_on_bit")):
        ax.set_ylabel(axis_label(name, units))
        ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
    thin = [(ds, label, {**style, "lw": 0.6}) for ds, label, style in runs]
    _orbit_panel(ax_orbit, thin, probe_x, units)
    _contact_panel(ax_contact, thin, units)
    ax_contact.set_xlabel("time [s]")
    for ax in (ax_orbit, ax_contact):
        ax.grid(True, alpha=0.3)
    ax_rop.legend(loc="best", fontsize="small")
    ax_speed.legend(loc="best", fontsize="small")
    if probe_title is not None:
        ax_radial.legend(loc="center right", fontsize="small")

    title = "Case 1 (full) vs case 2 (bit–rock + contact)"
    name = case_name(full.attrs.get("case", "")) or case_name(reduced.attrs.get("case", ""))
    if name:
        title += f": case '{name}'"
    failed = [label.split(" (")[0] for ds, label, _ in runs if ds.attrs.get("status", "success") != "success"]
    if failed:
        title += f" ({' and '.join(failed)} failed)"
    fig.suptitle(title)
    return canvas.save_png(fig, path)


def _orbit_panel(ax, runs, probe_x: float, units: str | None) -> None:
    """The whirl orbit (w against v [mm]) at the probe nearest ``probe_x`` [m] of each ``(ds, label, style)``,
    with the borehole wall (a circle of radius the probe's gap) and equal axes."""
    small, length = display_unit("small_length", units), display_unit("length", units)
    gap = None
    drawn = False
    for ds, label, style in runs:
        x = probe_positions(ds)
        if "lateral_displacement" not in ds or not x.size:
            continue
        i = probe_index(x, probe_x)
        orbit = small(np.asarray(ds["lateral_displacement"].isel(probe=i).values, dtype=float))
        ax.plot(orbit[:, 0], orbit[:, 1], label=label, **style)
        drawn = True
        if gap is None and ("gap" in ds.coords or "gap" in ds):
            gap = float(np.atleast_1d(ds["gap"].values)[i])
        ax.set_title(f"whirl orbit at x = {length(x[i]):.0f} {length.label}", fontsize="medium")
    if not drawn:
        ax.text(0.5, 0.5, "no probe", ha="center", va="center", transform=ax.transAxes)
        return
    if gap is not None:
        angle = np.linspace(0.0, 2.0 * np.pi, 361)
        ax.plot(small(gap) * np.cos(angle), small(gap) * np.sin(angle), color="k", lw=1.0, label="borehole wall")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"v, along y [{small.label}]")
    ax.set_ylabel(f"w, along z [{small.label}]")
    ax.legend(loc="upper right", fontsize="small")


def _contact_panel(ax, runs, units: str | None) -> None:
    """The total contact force of the wall on the string [kN] vs time of each ``(ds, label, style)``, with
    the run's number of impacts."""
    notes = []
    for ds, label, style in runs:
        if "contact_force" not in ds:
            continue
        t = np.asarray(ds["time"].values, dtype=float)
        ax.plot(t, scaled(ds["contact_force"].values, "contact_force", units), label=label, **style)
        impacts = ds.attrs.get("impacts")
        if impacts is not None:
            notes.append(f"{label.split(' (')[0] + ': ' if label else ''}{int(impacts)} impacts")
    if notes:
        ax.text(0.02, 0.95, "\n".join(notes), transform=ax.transAxes, va="top", fontsize="small")
    ax.set_ylabel(axis_label("contact_force", units))
    if any(label for _, label, _ in runs):
        ax.legend(loc="upper right", fontsize="small")


_FAMILY_COLORS = {"axial": "C0", "torsional": "C1", "lateral": "C2"}


def plot_campbell(diagram: dict, path: str | Path, title: str = "Campbell diagram") -> Path:
    """A Campbell diagram from :meth:`drillstring.critical_speeds.CampbellDiagram.to_dict` (SI): frequency [Hz]
    against rotary speed [rpm]; axial and torsional curves, lateral BHA modes (forward whirl solid,
    backward dashed; the drill-pipe lateral modes thin grey), the excitation lines, the critical speeds
    of the BHA modes (dots) and the operating speed."""
    rpm = np.asarray(diagram["speeds"], dtype=float) * RPM
    top = float(diagram["max_frequency"])
    threshold = diagram["bha_share_threshold"]
    fig, axes = canvas.new_figure(1, 1, (10.0, 7.0))
    ax = axes[0]
    labelled: set[str] = set()
    for curve in diagram["curves"]:
        family, whirl, share = curve["family"], curve["whirl"], curve["bha_energy_share"]
        f = np.asarray(curve["frequencies"], dtype=float)
        if family == "lateral" and share < threshold:
            ax.plot(rpm, f, color="0.8", lw=0.4, zorder=1)
            continue
        key = f"{family} {whirl}".strip()
        ax.plot(rpm, f, color=_FAMILY_COLORS[family], lw=1.1, ls="--" if whirl == "backward" else "-",
                label=None if key in labelled else (f"lateral BHA, {whirl}" if family == "lateral" else family),
                zorder=2)
        labelled.add(key)
    for k, order in enumerate(diagram["orders"]):
        ax.plot(rpm, order * rpm / 60.0, color="k", lw=1.2, ls=(":", "-.", "--")[k % 3], label=f"{order}× excitation",
                zorder=3)
    shown = [c for c in diagram["critical_speeds"]
             if c["family"] != "lateral" or c["bha_energy_share"] >= threshold]
    if shown:
        ax.plot([c["speed"] * RPM for c in shown], [c["frequency"] for c in shown], "o", ms=3.5, color="k",
                mfc="w", zorder=4, label="critical speeds")
    if diagram.get("operating_speed"):
        ax.axvline(diagram["operating_speed"] * RPM, color="C3", lw=1.5, zorder=3,
                   label=f"operating speed {diagram['operating_speed'] * RPM:.0f} rpm")
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_ylim(0.0, top)
    ax.set_xlabel("rotary speed [rpm]")
    ax.set_ylabel("natural frequency [Hz]")
    ax.set_title(f"{title} (grey: drill-pipe lateral modes)", fontsize="medium")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize="small", framealpha=0.9)
    return canvas.save_png(fig, path)


#: Panels of :func:`plot_map`: variable, display kind (:func:`axis_unit`; None: a plain number), title,
