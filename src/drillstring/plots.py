"""Matplotlib figures of one run and of a Monte Carlo study (no physics here).

Every function takes the Datasets produced by the package (SI units) and converts to engineering units
only for the axes, in the unit system ``units`` (``"si"``: ROP in m/h, torque in kN·m, force in kN,
displacements in mm, positions in m; ``"field"``: ft/h, kft·lbf, klbf, in, ft; bit speed in rpm in both;
None: ``$DRILLSTRING_UNITS``, else si; :mod:`drillstring.units`).

Figures are drawn on :class:`matplotlib.figure.Figure` objects rendered by the Agg canvas, without
``pyplot``: nothing here changes the global Matplotlib backend or leaves figures open, so the functions
are safe in scripts, notebooks, worker processes and tests.

* :func:`plot_run` — one simulation: ROP, bit speed, radial displacement at a probe, torque-on-bit, the
  whirl orbit at the probe with the borehole wall, the contact force.
* :func:`plot_compare` — the same six panels for case 1 (full) and case 2 (bit–rock + contact) overlaid.
* :func:`plot_convergence` — mean-square convergence ``conv(n_s)`` of each observable.
* :func:`plot_envelopes` — 95 % envelope, mean and nominal response of ROP, bit speed, TOB and FOB (and,
  with a top drive, of the quill speed and the surface torque).
* :func:`plot_dispersion` — dispersion [%] of the same observables vs time, transient shaded.
* :func:`plot_study` — the three study figures in one folder.
* :func:`plot_map` — an operating map: ROP, vibration, MSE, lateral displacement over top speed × WOB, with
  the linear stability boundary, the buckling limit and the simulated points.
* :func:`plot_campbell` — a Campbell diagram: frequencies of each family vs rotary speed, excitation lines,
  critical speeds, the operating speed.
* :func:`plot_sobol` — Sobol' indices (first order and total, with confidence intervals) per output;
  :func:`plot_sobol_convergence` — the indices at N/4, N/2, N.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from drillstring.files import atomic_output
from drillstring.quantities import DISPLAY_KINDS, STUDY_OBSERVABLES, stored_observables
from drillstring.units import DisplayUnit, display_unit

__all__ = [
    "TITLES",
    "plot_run",
    "plot_compare",
    "plot_convergence",
    "plot_realizations",
    "plot_envelopes",
    "plot_dispersion",
    "plot_study",
    "plot_map",
    "plot_sobol",
    "plot_sobol_convergence",
    "plot_campbell",
]

_RPM = 60.0 / (2.0 * math.pi)  # rpm per rad/s

#: name -> short title for the axes (units: drillstring.quantities.DISPLAY_KINDS in the chosen system).
TITLES: dict[str, str] = {
    "rate_of_penetration": "rate of penetration",
    "bit_speed": "bit speed",
    "torque_on_bit": "torque-on-bit",
    "force_on_bit": "force-on-bit",
    "radial_displacement": "radial displacement",
    "contact_force": "contact force",
    "quill_speed": "quill speed",
    "surface_torque": "surface torque",
    "depth_of_cut": "depth of cut",
    "hook_load": "hook load",
    "wear_flat_force": "wear-flat force",
    "motor_speed": "motor speed",
    "motor_torque": "motor torque",
    "differential_pressure": "differential pressure",
}
#: The run figure's panels of one observable: panel -> (observable, title or "").
_LINE_PANELS = {"hook_load": ("hook_load", ""),
                "motor_speed": ("motor_speed", "downhole motor: rotor speed relative to its stator"),
                "motor_pressure": ("differential_pressure", "downhole motor: differential pressure")}

#: The four observables of the study figures, in panel order (a study of a case with a top drive adds the
#: quill speed and the surface torque: :func:`~drillstring.quantities.stored_observables`).
STUDY_PANELS = STUDY_OBSERVABLES

_DPI = 120
_MEAN_COLOR = "C0"
_NOMINAL_COLOR = "C3"
_ENVELOPE_COLOR = "C0"


#: Fixed margins of the 3 × 2 run figures (11 × 10 in): laid out once by hand instead of by Matplotlib's
#: constrained layout, which measured every text twice and took half the drawing time.
_PANEL_MARGINS = {"left": 0.065, "right": 0.985, "bottom": 0.055, "top": 0.945, "wspace": 0.2, "hspace": 0.34}
_RUN_FIGURE = (11.0, 10.0)


def _figure(rows: int, cols: int, size: tuple[float, float], sharex: bool = False, *,
            margins: dict[str, float] | None = None) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=size, layout=None if margins else "constrained")
    FigureCanvasAgg(fig)
    axes = np.asarray(fig.subplots(rows, cols, squeeze=False, sharex=sharex)).ravel()
    if margins:
        fig.subplots_adjust(**margins)
    return fig, axes


def _save(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` as PNG, atomically (a reader never sees a partial file)."""
    path = Path(path)
    with atomic_output(path) as temporary:
        fig.savefig(temporary, dpi=_DPI, format="png")
    return path


def _label(name: str, units: str | None) -> str:
    return f"{TITLES[name]} [{display_unit(DISPLAY_KINDS[name], units).label}]"


def axis_unit(kind: str | None, units: str | None = None) -> DisplayUnit:
    """The display unit of a plotted quantity of display kind ``kind`` (:func:`drillstring.units.display_unit`)
    in the unit system ``units``; None: a plain number (``"-"``)."""
    return DisplayUnit("-", 1.0) if kind is None else display_unit(kind, units)


def _scaled(values, name: str, units: str | None) -> np.ndarray:
    return np.asarray(values, dtype=float) * display_unit(DISPLAY_KINDS[name], units).scale


def _probe_index(x: np.ndarray, probe_x: float) -> int:
    if x.size == 0:
        raise ValueError("the dataset has no probe")
    return int(np.argmin(np.abs(x - probe_x)))


def _probe_positions(ds: xr.Dataset) -> np.ndarray:
    if "x" in ds.coords or "x" in ds:
        return np.atleast_1d(np.asarray(ds["x"].values, dtype=float))
    n = ds.sizes.get("probe", 0)
    return np.full(n, np.nan)


# ---------------------------------------------------------------------------------------------------------
# One run
# ---------------------------------------------------------------------------------------------------------


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
    fig, grid = _figure(rows, 2, (_RUN_FIGURE[0], _RUN_FIGURE[1] * rows / 3), margins=_PANEL_MARGINS)
    for ax in grid[len(panels):]:
        ax.set_axis_off()
    axes = dict(zip(panels, grid))
    imposed = ds.attrs.get("top_drive", "imposed_speed") == "imposed_speed"

    ax_rop = axes["rop"]
    ax_rop.plot(t, _scaled(ds["rate_of_penetration"].values, "rate_of_penetration", units), lw=0.9)
    ax_rop.set_ylabel(_label("rate_of_penetration", units))

    ax_speed = axes["speed"]
    ax_speed.plot(t, _scaled(ds["bit_speed"].values, "bit_speed", units), lw=0.9, label="bit")
    top = ds.attrs.get("top_speed")
    if "quill_speed" in ds and not imposed:
        ax_speed.plot(t, _scaled(ds["quill_speed"].values, "quill_speed", units), lw=0.9, label="quill")
    if top is not None:
        ax_speed.axhline(float(top) * _RPM, color="k", ls="--", lw=0.9,
                         label="top (imposed)" if imposed else "set point")
    ax_speed.set_ylabel(_label("bit_speed", units))
    ax_speed.legend(loc="best", fontsize="small")

    if "radial" in axes:
        ax_radial = axes["radial"]
        x = _probe_positions(ds)
        if "radial_displacement" in ds and x.size:
            i = _probe_index(x, probe_x)
            r = ds["radial_displacement"].isel(probe=i).values
            r_mm = _scaled(r, "radial_displacement", units)
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
        ax_radial.set_ylabel(_label("radial_displacement", units))

    ax_tob = axes["torque"]
    ax_tob.plot(t, _scaled(ds["torque_on_bit"].values, "torque_on_bit", units), lw=0.9, label="on bit")
    if "surface_torque" in ds:
        ax_tob.plot(t, _scaled(ds["surface_torque"].values, "surface_torque", units), lw=0.9, label="surface")
    if "motor_torque" in ds:
        ax_tob.plot(t, _scaled(ds["motor_torque"].values, "motor_torque", units), lw=0.9, label="motor")
    if "surface_torque" in ds or "motor_torque" in ds:
        ax_tob.legend(loc="best", fontsize="small")
    ax_tob.set_ylabel(_label("torque_on_bit", units).replace("torque-on-bit", "torque"))

    if "orbit" in axes:
        _orbit_panel(axes["orbit"], ((ds, "orbit", {"lw": 0.6}),), probe_x, units)
        _contact_panel(axes["contact"], ((ds, None, {"lw": 0.8}),), units)
    if "force" in axes:
        ax = axes["force"]
        ax.plot(t, _scaled(ds["force_on_bit"].values, "force_on_bit", units), lw=0.9, label="on bit")
        ax.plot(t, _scaled(ds["wear_flat_force"].values, "wear_flat_force", units), lw=0.9,
                label="wear-flat part")
        ax.set_ylabel(_label("force_on_bit", units))
        ax.legend(loc="best", fontsize="small")
    if "depth_of_cut" in axes:
        ax = axes["depth_of_cut"]
        ax.plot(t, _scaled(ds["depth_of_cut"].values, "depth_of_cut", units), lw=0.9)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_ylabel(_label("depth_of_cut", units))
        ax.set_title("depth of cut per blade (≤ 0: the bit off the rock)", fontsize="medium")
    for panel, (name, title) in _LINE_PANELS.items():
        if panel in axes:
            axes[panel].plot(t, _scaled(ds[name].values, name, units), lw=0.9)
            axes[panel].set_ylabel(_label(name, units))
            axes[panel].set_title(title, fontsize="medium")
    for name, ax in axes.items():
        if name != "orbit":
            ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
    title = "Drilling run"
    name = _case_name(ds.attrs.get("case", ""))
    if name:
        title += f": case '{name}'"
    if ds.attrs.get("status", "success") != "success":
        title += f" ({ds.attrs.get('status')}, stopped at t = {t[-1]:.3g} s)" if t.size else " (failed)"
    fig.suptitle(title)
    return _save(fig, path)


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
    fig, axes = _figure(3, 2, _RUN_FIGURE, margins=_PANEL_MARGINS)
    ax_rop, ax_speed, ax_radial, ax_tob, ax_orbit, ax_contact = axes
    runs = ((full, *_COMPARE_STYLES[0]), (reduced, *_COMPARE_STYLES[1]))

    radial_max: list[str] = []
    probe_title = None
    gap = None
    for ds, label, style in runs:
        t = np.asarray(ds["time"].values, dtype=float)
        ax_rop.plot(t, _scaled(ds["rate_of_penetration"].values, "rate_of_penetration", units), label=label,
                    **style)
        ax_speed.plot(t, _scaled(ds["bit_speed"].values, "bit_speed", units), label=label, **style)
        ax_tob.plot(t, _scaled(ds["torque_on_bit"].values, "torque_on_bit", units), label=label, **style)
        x = _probe_positions(ds)
        if "radial_displacement" in ds and x.size:
            i = _probe_index(x, probe_x)
            r_mm = _scaled(ds["radial_displacement"].isel(probe=i).values, "radial_displacement", units)
            ax_radial.plot(t, r_mm, label=label, **style)
            if np.isfinite(r_mm).any():
                radial_max.append(f"{label.split(' (')[0]}: max r = {np.nanmax(r_mm):.3g} {small.label}")
            probe_title = f"probe at x = {length(x[i]):.0f} {length.label}"
            if gap is None and ("gap" in ds.coords or "gap" in ds):
                gap = float(np.atleast_1d(ds["gap"].values)[i])

    top = full.attrs.get("top_speed", reduced.attrs.get("top_speed"))
    if top is not None:
        ax_speed.axhline(float(top) * _RPM, color="k", ls=":", lw=0.9, label="top (imposed)")
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
        ax.set_ylabel(_label(name, units))
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
    name = _case_name(full.attrs.get("case", "")) or _case_name(reduced.attrs.get("case", ""))
    if name:
        title += f": case '{name}'"
    failed = [label.split(" (")[0] for ds, label, _ in runs if ds.attrs.get("status", "success") != "success"]
    if failed:
        title += f" ({' and '.join(failed)} failed)"
    fig.suptitle(title)
    return _save(fig, path)


def _orbit_panel(ax, runs, probe_x: float, units: str | None) -> None:
    """The whirl orbit (w against v [mm]) at the probe nearest ``probe_x`` [m] of each ``(ds, label, style)``,
    with the borehole wall (a circle of radius the probe's gap) and equal axes."""
    small, length = display_unit("small_length", units), display_unit("length", units)
    gap = None
    drawn = False
    for ds, label, style in runs:
        x = _probe_positions(ds)
        if "lateral_displacement" not in ds or not x.size:
            continue
        i = _probe_index(x, probe_x)
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
        ax.plot(t, _scaled(ds["contact_force"].values, "contact_force", units), label=label, **style)
        impacts = ds.attrs.get("impacts")
        if impacts is not None:
            notes.append(f"{label.split(' (')[0] + ': ' if label else ''}{int(impacts)} impacts")
    if notes:
        ax.text(0.02, 0.95, "\n".join(notes), transform=ax.transAxes, va="top", fontsize="small")
    ax.set_ylabel(_label("contact_force", units))
    if any(label for _, label, _ in runs):
        ax.legend(loc="upper right", fontsize="small")


def _case_name(case_toml: str) -> str:
    """The ``name = "..."`` of a case's TOML text ('' when absent), as plain text for a figure: its dollar
    signs escaped, so that Matplotlib never reads it as mathtext."""
    try:
        name = tomllib.loads(str(case_toml)).get("name", "")
    except (tomllib.TOMLDecodeError, RecursionError):
        name = _case_name_line(case_toml)
    return str(name).replace("$", r"\$")


def _case_name_line(case_toml: str) -> str:
    """The ``name = "..."`` line of a TOML text that does not parse ('' when absent)."""
    for line in str(case_toml).splitlines():
        stripped = line.strip()
        if stripped.startswith("name") and "=" in stripped:
            key, value = stripped.split("=", 1)
            if key.strip() == "name":
                return value.strip().strip('"').strip("'")
        if stripped.startswith("["):
            break
    return ""


# ---------------------------------------------------------------------------------------------------------
# A study
# ---------------------------------------------------------------------------------------------------------


def _study_title(stats: xr.Dataset, what: str, units: str | None = None) -> str:
    force = display_unit("force", units)
    parts = [what]
    n = stats.attrs.get("n_samples")
    if n is not None:
        parts.append(f"n_s = {int(n)}")
    sigma = stats.attrs.get("sigma")
    if sigma is not None and np.isfinite(float(sigma)):
        parts.append(f"σ_WOH = {force(float(sigma)):.4g} {force.label}")
    others = [str(p) for p in stats.attrs.get("parameters", []) if str(p) != "weight_on_hook"]
    if others:
        parts.append("random " + ", ".join(others))
    return ", ".join(parts)


def _input_dispersions(stats: xr.Dataset) -> list[tuple[str, float]]:
    """(label, dispersion) of each random input from the statistics' attributes: std/|mean| of each
    parameter's law, and δ_WOB when the weight-on-hook is random."""
    attrs = stats.attrs
    out = []
    for path, mean, std in zip(attrs.get("parameters", []), attrs.get("parameter_mean", []),
                               attrs.get("parameter_std", [])):
        if float(mean) != 0.0:
            label = "δ_WOH" if str(path) == "weight_on_hook" else f"δ({path})"
            out.append((label, float(std) / abs(float(mean))))
    dispersion = attrs.get("weight_on_bit_dispersion")
    if dispersion is not None and np.isfinite(float(dispersion)):
        out.append(("δ_WOB", float(dispersion)))
    return out


def plot_convergence(stats: xr.Dataset, path: str | Path, time_convergence: dict | None = None, *,
                     units: str | None = None) -> Path:
    """``conv(n_s)`` of each observable (``<v>_convergence``), divided by its last value so that all
    observables share one axis; the curves levelling off at 1 show that ``n_s`` suffices. With
    ``time_convergence`` (the summary's section, :func:`~drillstring.stochastic.analysis.time_convergence`),
    a second panel: the maximum and time-mean dispersion of each observable over records of growing
    length after the transient — curves still rising at the right show statistics not converged in time."""
    fig, axes = _figure(1, 2 if time_convergence else 1, (13.0 if time_convergence else 8.0, 4.8))
    ax = axes[0]
    names = [str(v)[: -len("_convergence")] for v in stats.data_vars if str(v).endswith("_convergence")]
    if not names:
        raise ValueError("stats has no <observable>_convergence variable")
    for name in names:
        conv = stats[f"{name}_convergence"]
        n = np.asarray(conv["n_samples"].values if "n_samples" in conv.coords else np.arange(1, conv.size + 1))
        values = np.asarray(conv.values, dtype=float)
        last = values[-1] if values.size else np.nan
        normalised = values / last if np.isfinite(last) and last != 0 else values
        title = TITLES.get(name, name)
        ax.plot(n, normalised, marker="." if n.size <= 60 else None, lw=1.1, label=title)
    ax.axhline(1.0, color="k", lw=0.7, ls=":")
    ax.set_xlabel("number of realizations $n_s$")
    ax.set_ylabel("conv($n_s$) / conv($n_s^{max}$)")
    ax.set_title("in the number of realizations", fontsize="medium")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    if time_convergence:
        ax = axes[1]
        for k, (name, entry) in enumerate(time_convergence["observables"].items()):
            ends = [w["t_end"] for w in entry["windows"]]
            title = TITLES.get(name, name)
            for key, style, label in (("dispersion_max", "-", "max"), ("dispersion_time_mean", "--", "time mean")):
                values = [np.nan if w[key] is None else 100.0 * w[key] for w in entry["windows"]]
                ax.plot(ends, values, style, marker="o", ms=3, color=f"C{k}", lw=1.1, label=f"{title}, {label}")
        ax.set_xlabel(f"end of the record t: dispersion over [{time_convergence.get('t_start', 0.0):g} s, t] [s]")
        ax.set_ylabel("dispersion [%]")
        ax.set_title(f"in time (records growing by {time_convergence['window']:g} s)", fontsize="medium")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize="x-small", ncol=2)
    fig.suptitle(_study_title(stats, "Convergence", units))
    return _save(fig, path)


def plot_realizations(stats: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """Histograms of the per-realization cycle metrics (``realization_<name>`` of :data:`~drillstring.
    quantities.METRIC_DISPLAY`) in the unit system ``units`` (:func:`~drillstring.quantities.metric_unit`), the
    mean (solid) and the nominal run's value (dashed); the panel of a metric without finite values says so."""
    from drillstring.quantities import METRIC_DISPLAY, metric_unit

    names = [name for name in METRIC_DISPLAY if f"realization_{name}" in stats]
    if not names:
        raise ValueError("stats has no realization_<metric> variable")
    rows, cols = _grid(len(names))
    fig, axes = _figure(rows, cols, (3.6 * cols, 2.8 * rows))
    for ax, name in zip(axes, names):
        unit, label = metric_unit(name, units), METRIC_DISPLAY[name][1]
        values = unit(np.asarray(stats[f"realization_{name}"].values, dtype=float))
        finite = values[np.isfinite(values)]
        if finite.size:
            ax.hist(finite, bins=min(30, max(5, int(np.sqrt(finite.size)))), color="C0", alpha=0.7)
            ax.axvline(finite.mean(), color="k", lw=1.0, label="mean")
        else:
            ax.text(0.5, 0.5, "undefined for every realization", ha="center", va="center", transform=ax.transAxes)
        nominal = unit(float(stats[f"realization_{name}"].attrs.get("nominal", np.nan)))
        if np.isfinite(nominal):
            ax.axvline(nominal, color=_NOMINAL_COLOR, lw=1.0, ls="--", label="nominal")
        ax.set_xlabel(f"{label} [{unit.label}]", fontsize="small")
        ax.set_ylabel("realizations", fontsize="small")
        ax.grid(True, alpha=0.3)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    axes[0].legend(loc="best", fontsize="x-small")
    t0 = stats.attrs.get("t_transient")
    fig.suptitle(_study_title(stats, "Per-realization cycle metrics" + (f" after t = {float(t0):g} s" if t0 is not None
                                                                         else ""), units))
    return _save(fig, path)


def plot_envelopes(stats: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """Four panels (ROP, bit speed, TOB, FOB; six with a top drive: also the quill speed and the surface
    torque): the envelope between ``<v>_lower`` and ``<v>_upper`` (the 95 % quantile envelope), the mean
    and the nominal (deterministic, mean weight-on-hook) response."""
    t = np.asarray(stats["time"].values, dtype=float)
    level = float(stats.attrs.get("level", 0.95))
    panels = stored_observables(stats)
    rows = (len(panels) + 1) // 2
    fig, axes = _figure(rows, 2, (11.0, 3.5 * rows))
    for ax, name in zip(axes, panels):
        lower = _scaled(stats[f"{name}_lower"].values, name, units)
        upper = _scaled(stats[f"{name}_upper"].values, name, units)
        ax.fill_between(t, lower, upper, color=_ENVELOPE_COLOR, alpha=0.3, lw=0,
                        label=f"{level:.0%} envelope")
        ax.plot(t, _scaled(stats[f"{name}_mean"].values, name, units), color=_MEAN_COLOR, lw=1.0, label="mean")
        if f"{name}_nominal" in stats:
            ax.plot(t, _scaled(stats[f"{name}_nominal"].values, name, units), color=_NOMINAL_COLOR, lw=0.9,
                    ls="--", label="nominal")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(_label(name, units))
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize="small")
    fig.suptitle(_study_title(stats, "Envelopes of the response", units))
    return _save(fig, path)


def plot_dispersion(stats: xr.Dataset, path: str | Path, t_transient: float, *,
                    units: str | None = None) -> Path:
    """Dispersion ``std/|mean|`` [%] vs time of ROP, bit speed, TOB and FOB (and, with a top drive, the
    quill speed and the surface torque; one panel each, shared time axis), the transient ``t < t_transient``
    [s] shaded."""
    t = np.asarray(stats["time"].values, dtype=float)
    panels = stored_observables(stats)
    fig, axes = _figure(len(panels), 1, (9.0, 2.125 * len(panels)), sharex=True)
    for ax, name in zip(axes, panels):
        ax.plot(t, 100.0 * np.asarray(stats[f"{name}_dispersion"].values, dtype=float), lw=0.9)
        if t.size:
            ax.axvspan(t[0], min(float(t_transient), t[-1]), color="0.85", lw=0,
                       label=f"transient (t < {t_transient:g} s)")
        ax.set_ylabel(f"{TITLES[name]}\ndispersion [%]")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    axes[0].legend(loc="upper right", fontsize="small")
    title = _study_title(stats, "Dispersion of the response", units)
    extra = ", ".join(f"{label} = {100 * value:.3g} %" for label, value in _input_dispersions(stats))
    fig.suptitle(f"{title}\n{extra}" if extra else title)
    return _save(fig, path)


def plot_study(stats: xr.Dataset, out_dir: str | Path, t_transient: float,
               time_convergence: dict | None = None, *, units: str | None = None) -> dict[str, Path]:
    """The study figures in ``out_dir``: ``convergence.png`` (in n_s, and in time with ``time_convergence``),
    ``envelopes.png``, ``dispersion.png`` and, when the statistics hold per-realization cycle metrics,
    ``realizations.png`` (returned by those names without the extension)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figures = {
        "convergence": plot_convergence(stats, out / "convergence.png", time_convergence, units=units),
        "envelopes": plot_envelopes(stats, out / "envelopes.png", units=units),
        "dispersion": plot_dispersion(stats, out / "dispersion.png", t_transient, units=units),
    }
    if any(str(v).startswith("realization_") for v in stats.data_vars):
        figures["realizations"] = plot_realizations(stats, out / "realizations.png", units=units)
    return figures


# ---------------------------------------------------------------------------------------------------------
# An operating map
# ---------------------------------------------------------------------------------------------------------

_FAMILY_COLORS = {"axial": "C0", "torsional": "C1", "lateral": "C2"}


def plot_campbell(diagram: dict, path: str | Path, title: str = "Campbell diagram") -> Path:
    """A Campbell diagram from :meth:`drillstring.critical_speeds.CampbellDiagram.to_dict` (SI): frequency [Hz]
    against rotary speed [rpm]; axial and torsional curves, lateral BHA modes (forward whirl solid,
    backward dashed; the drill-pipe lateral modes thin grey), the excitation lines, the critical speeds
    of the BHA modes (dots) and the operating speed."""
    rpm = np.asarray(diagram["speeds"], dtype=float) * _RPM
    top = float(diagram["max_frequency"])
    threshold = diagram["bha_share_threshold"]
    fig, axes = _figure(1, 1, (10.0, 7.0))
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
        ax.plot([c["speed"] * _RPM for c in shown], [c["frequency"] for c in shown], "o", ms=3.5, color="k",
                mfc="w", zorder=4, label="critical speeds")
    if diagram.get("operating_speed"):
        ax.axvline(diagram["operating_speed"] * _RPM, color="C3", lw=1.5, zorder=3,
                   label=f"operating speed {diagram['operating_speed'] * _RPM:.0f} rpm")
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_ylim(0.0, top)
    ax.set_xlabel("rotary speed [rpm]")
    ax.set_ylabel("natural frequency [Hz]")
    ax.set_title(f"{title} (grey: drill-pipe lateral modes)", fontsize="medium")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize="small", framealpha=0.9)
    return _save(fig, path)


#: Panels of :func:`plot_map`: variable, display kind (:func:`axis_unit`; None: a plain number), title,
#: colour map, logarithmic scale.
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

    x = np.asarray(ds["top_speed"].values, dtype=float) * _RPM
    force = display_unit("force", units)
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    growth = np.asarray(ds["growth_rate"].values, dtype=float)
    status = np.asarray(ds["status"].values)
    critical = force(float(ds.attrs.get("critical_weight_on_bit", np.nan)))
    fig, axes = _figure(2, 2, (12.0, 9.0))
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
    if _coexisting(ds).any():
        handles.append(COEXISTING_HANDLE())
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize="small")
    title = "Operating map"
    name = _case_name(ds.attrs.get("case", ""))
    if name:
        title += f": case '{name}'"
    t_end, t_tr = ds.attrs.get("t_end"), ds.attrs.get("t_transient")
    if t_end is not None and t_tr is not None:
        title += f" (runs of {float(t_end):g} s, outputs over t ≥ {float(t_tr):g} s)"
    fig.suptitle(title)
    return _save(fig, path)


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

    x = np.asarray(ds["top_speed"].values, dtype=float) * _RPM
    force = display_unit("force", units)
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    status = np.asarray(ds["status"].values)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    fig, axes = _figure(1, len(STABILITY_PANELS), (6.0 * len(STABILITY_PANELS), 5.6))
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
    if _coexisting(ds).any():
        handles.append(COEXISTING_HANDLE())
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize="small")
    title = "Linear stability of steady drilling per family"
    name = _case_name(ds.attrs.get("case", ""))
    if name:
        title += f": case '{name}'"
    fig.suptitle(title)
    return _save(fig, path)


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
    name = _case_name(ds.attrs.get("case", ""))
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
    x = np.asarray(ds["top_speed"].values, dtype=float) * _RPM
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    fig, axes = _figure(2, 4, (24.0, 9.0))
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
    return _save(fig, path)


def plot_quantile_map(ds: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """The 2.5, 50 and 97.5 % quantiles of the mean ROP (m/h or ft/h; top row) and of the stick-slip index
    (bottom row) over each point's realizations, over top speed [rpm] × weight-on-bit (kN or klbf), each panel
    on its own colour scale. Written to the PNG ``path``, in the units of ``units``."""
    force = display_unit("force", units)
    x = np.asarray(ds["top_speed"].values, dtype=float) * _RPM
    y = force(np.asarray(ds["weight_on_bit"].values, dtype=float))
    levels = [float(q) for q in ds["quantile"].values]
    fig, axes = _figure(2, len(levels), (5.0 * len(levels), 9.0))
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
    return _save(fig, path)


# ---------------------------------------------------------------------------------------------------------
# Sobol' indices
# ---------------------------------------------------------------------------------------------------------

#: Display names of the scalar outputs of a run, for the sensitivity figures.
OUTPUT_TITLES = {
    "mean_rate_of_penetration": "mean ROP",
    "bit_speed_oscillation": "bit-speed oscillation",
    "mean_torque_on_bit": "mean TOB",
    "mean_force_on_bit": "mean FOB",
    "std_rate_of_penetration": "ROP std in time",
    "std_torque_on_bit": "TOB std in time",
    "std_force_on_bit": "FOB std in time",
    "stick_time_fraction": "stick time fraction",
    "bit_bounce_fraction": "bit bounce fraction",
}


def short_labels(paths) -> list[str]:
    """The last part of each parameter path when that is unambiguous among ``paths``, else the path."""
    paths = [str(p) for p in paths]
    tails = [p.split(".")[-1] for p in paths]
    return [t if tails.count(t) == 1 else p for p, t in zip(paths, tails)]


def _grid(n: int) -> tuple[int, int]:
    cols = min(n, 4) if n > 4 else min(n, 2) if n > 1 else 1
    return math.ceil(n / cols), cols


def _values(mapping: dict, parameters: list[str]) -> np.ndarray:
    return np.array([np.nan if mapping.get(p) is None else float(mapping[p]) for p in parameters])


def plot_sobol(indices: dict, path: str | Path) -> Path:
    """Bar chart of Sobol' indices, one panel per output: first-order S1 (solid) and total ST (light) of
    each parameter with their confidence intervals as error bars. ``indices`` is the JSON form of a
    :class:`~drillstring.stochastic.sensitivity.SobolResult` (``to_dict()``, as in ``sensitivity.json``).
    Written to the PNG ``path``."""
    parameters = list(indices["parameters"])
    outputs = list(indices["outputs"])
    rows, cols = _grid(len(outputs))
    fig, axes = _figure(rows, cols, (3.3 * cols + 1.0, 3.2 * rows + 0.8))
    x = np.arange(len(parameters))
    width = 0.38
    labels = short_labels(parameters)
    for ax, name in zip(axes, outputs):
        entry = indices["outputs"][name]
        for shift, kind, style in ((-width / 2, "S1", dict(color="C0")),
                                   (width / 2, "ST", dict(color="C0", alpha=0.35, hatch="//", edgecolor="C0"))):
            values = _values(entry[kind], parameters)
            ci = np.array([[np.nan, np.nan] if entry[f"{kind}_ci"].get(p) is None
                           or None in entry[f"{kind}_ci"][p] else entry[f"{kind}_ci"][p] for p in parameters],
                          dtype=float)
            errors = np.abs(np.vstack([values - ci[:, 0], ci[:, 1] - values]))
            ax.bar(x + shift, np.nan_to_num(values), width, yerr=np.nan_to_num(errors), capsize=2,
                   label="first order S1" if kind == "S1" else "total ST", **style)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xticks(x, labels, rotation=30, ha="right", fontsize="small")
        ax.set_ylim(min(-0.1, ax.get_ylim()[0]), max(1.05, ax.get_ylim()[1]))
        ax.set_title(OUTPUT_TITLES.get(name, name), fontsize="medium")
        ax.grid(True, axis="y", alpha=0.3)
    for ax in axes[len(outputs):]:
        ax.set_visible(False)
    axes[0].legend(loc="upper left", fontsize="small")
    level = float(indices.get("confidence_level", 0.95))
    fig.suptitle(f"Sobol' indices, N = {indices['base_samples']} ({indices['runs']} runs); error bars: "
                 f"{level:.0%} bootstrap intervals")
    return _save(fig, path)


def plot_sobol_convergence(indices: dict, path: str | Path) -> Path:
    """The Sobol' indices of each output at N/4, N/2 and N base samples (S1 solid, ST dashed, one colour
    per parameter): converged indices are flat. ``indices`` as for :func:`plot_sobol`."""
    parameters = list(indices["parameters"])
    outputs = list(indices["outputs"])
    rows, cols = _grid(len(outputs))
    fig, axes = _figure(rows, cols, (3.3 * cols + 1.0, 3.0 * rows + 0.8))
    labels = short_labels(parameters)
    for ax, name in zip(axes, outputs):
        conv = indices["outputs"][name]["convergence"]
        n = np.asarray(conv["base_samples"], dtype=float)
        for k, parameter in enumerate(parameters):
            for kind, ls in (("S1", "-"), ("ST", "--")):
                values = np.array([np.nan if v is None else v for v in conv[kind][parameter]], dtype=float)
                ax.plot(n, values, ls=ls, marker="o", ms=3, color=f"C{k % 10}",
                        label=f"{labels[k]} {kind}" if kind == "S1" else None)
        ax.set_xscale("log", base=2)
        ax.set_xlabel("base samples N")
        ax.set_title(OUTPUT_TITLES.get(name, name), fontsize="medium")
        ax.grid(True, alpha=0.3)
    for ax in axes[len(outputs):]:
        ax.set_visible(False)
    axes[0].legend(loc="best", fontsize="x-small")
    fig.suptitle("Convergence of the Sobol' indices (S1 solid, ST dashed)")
    return _save(fig, path)
