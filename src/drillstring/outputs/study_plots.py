"""Matplotlib figures of a Monte Carlo study (no physics here)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from drillstring.outputs import canvas
from drillstring.outputs.canvas import ENVELOPE_COLOR, MEAN_COLOR, NOMINAL_COLOR, TITLES, axis_label, panel_grid, scaled
from drillstring.quantities import STUDY_OBSERVABLES, stored_observables
from drillstring.units import display_unit

#: The four observables of the study figures, in panel order (a study of a case with a top drive adds the
#: quill speed and the surface torque: :func:`~drillstring.quantities.stored_observables`).
STUDY_PANELS = STUDY_OBSERVABLES


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
    fig, axes = canvas.new_figure(1, 2 if time_convergence else 1, (13.0 if time_convergence else 8.0, 4.8))
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
    return canvas.save_png(fig, path)


def plot_realizations(stats: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """Histograms of the per-realization cycle metrics (``realization_<name>`` of :data:`~drillstring.
    quantities.METRIC_DISPLAY`) in the unit system ``units`` (:func:`~drillstring.quantities.metric_unit`), the
    mean (solid) and the nominal run's value (dashed); the panel of a metric without finite values says so."""
    from drillstring.quantities import METRIC_DISPLAY, metric_unit

    names = [name for name in METRIC_DISPLAY if f"realization_{name}" in stats]
    if not names:
        raise ValueError("stats has no realization_<metric> variable")
    rows, cols = panel_grid(len(names))
    fig, axes = canvas.new_figure(rows, cols, (3.6 * cols, 2.8 * rows))
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
            ax.axvline(nominal, color=NOMINAL_COLOR, lw=1.0, ls="--", label="nominal")
        ax.set_xlabel(f"{label} [{unit.label}]", fontsize="small")
        ax.set_ylabel("realizations", fontsize="small")
        ax.grid(True, alpha=0.3)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    axes[0].legend(loc="best", fontsize="x-small")
    t0 = stats.attrs.get("t_transient")
    fig.suptitle(_study_title(stats, "Per-realization cycle metrics" + (f" after t = {float(t0):g} s" if t0 is not None
                                                                         else ""), units))
    return canvas.save_png(fig, path)


def plot_envelopes(stats: xr.Dataset, path: str | Path, *, units: str | None = None) -> Path:
    """Four panels (ROP, bit speed, TOB, FOB; six with a top drive: also the quill speed and the surface
    torque): the envelope between ``<v>_lower`` and ``<v>_upper`` (the 95 % quantile envelope), the mean
    and the nominal (deterministic, mean weight-on-hook) response."""
    t = np.asarray(stats["time"].values, dtype=float)
    level = float(stats.attrs.get("level", 0.95))
    panels = stored_observables(stats)
    rows = (len(panels) + 1) // 2
    fig, axes = canvas.new_figure(rows, 2, (11.0, 3.5 * rows))
    for ax, name in zip(axes, panels):
        lower = scaled(stats[f"{name}_lower"].values, name, units)
        upper = scaled(stats[f"{name}_upper"].values, name, units)
        ax.fill_between(t, lower, upper, color=ENVELOPE_COLOR, alpha=0.3, lw=0,
                        label=f"{level:.0%} envelope")
        ax.plot(t, scaled(stats[f"{name}_mean"].values, name, units), color=MEAN_COLOR, lw=1.0, label="mean")
        if f"{name}_nominal" in stats:
            ax.plot(t, scaled(stats[f"{name}_nominal"].values, name, units), color=NOMINAL_COLOR, lw=0.9,
                    ls="--", label="nominal")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(axis_label(name, units))
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize="small")
    fig.suptitle(_study_title(stats, "Envelopes of the response", units))
    return canvas.save_png(fig, path)


def plot_dispersion(stats: xr.Dataset, path: str | Path, t_transient: float, *,
                    units: str | None = None) -> Path:
    """Dispersion ``std/|mean|`` [%] vs time of ROP, bit speed, TOB and FOB (and, with a top drive, the
    quill speed and the surface torque; one panel each, shared time axis), the transient ``t < t_transient``
    [s] shaded."""
    t = np.asarray(stats["time"].values, dtype=float)
    panels = stored_observables(stats)
    fig, axes = canvas.new_figure(len(panels), 1, (9.0, 2.125 * len(panels)), sharex=True)
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
    return canvas.save_png(fig, path)


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
