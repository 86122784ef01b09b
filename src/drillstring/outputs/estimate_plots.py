"""Figures of an estimate (:mod:`drillstring.estimation`): the surface channels as measured against the
ensemble's prediction, and the downhole quantities and parameters with their 90 % bands (and the truth, for
a synthetic record). Reads the estimate's Dataset (:meth:`~drillstring.estimation.results.EstimationResult.
to_dataset`), no physics."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np
import xarray as xr

from drillstring.outputs import canvas
from drillstring.outputs.canvas import axis_unit, panel_grid

#: Surface channel -> (display kind, title).
SURFACE = {
    "top_speed": ("angular_speed", "top speed"),
    "surface_torque": ("torque", "surface torque"),
    "hook_load": ("force", "hook load"),
    "block_position": ("length", "block position"),
    "standpipe_pressure": ("pressure", "standpipe pressure"),
}
#: Downhole quantity -> (display kind, title); parameters are plotted as plain numbers.
DOWNHOLE = {
    "bit_speed": ("angular_speed", "bit speed"),
    "torque_on_bit": ("torque", "torque-on-bit"),
    "force_on_bit": ("force", "force-on-bit"),
    "rate_of_penetration": ("rate_of_penetration", "rate of penetration"),
    "stick_slip_index": (None, "stick-slip index"),
}
BAND_ALPHA = 0.3


def _band(ax, time, quantiles, scale, color, label):
    ax.fill_between(time, quantiles[:, 0] * scale, quantiles[:, 2] * scale, color=color, alpha=BAND_ALPHA, lw=0,
                    label=f"{label} 90 % band")


def plot_surface(estimate: xr.Dataset, path: str | Path, *, units: str | None = None, title: str = "") -> Path:
    """One panel per surface channel of the record: the measured samples (used: dots; flagged, not used:
    red crosses) and the ensemble's prediction before each analysis (mean and 90 % band)."""
    channels = [name for name in SURFACE if f"observed_{name}" in estimate]
    rows, cols = panel_grid(max(len(channels), 1))
    fig, axes = canvas.new_figure(rows, cols, (5.0 * cols, 2.8 * rows + 0.6), sharex=True)
    time = estimate["time"].values
    for ax, name in zip(axes, channels):
        kind, label = SURFACE[name]
        unit = axis_unit(kind, units)
        observed = estimate[f"observed_{name}"].values * unit.scale
        used = estimate[f"used_{name}"].values.astype(bool)
        if f"predicted_{name}" in estimate:
            _band(ax, time, estimate[f"predicted_{name}_quantile"].values, unit.scale, "C0", "predicted")
            ax.plot(time, estimate[f"predicted_{name}"].values * unit.scale, color="C0", lw=1.0,
                    label="predicted mean")
        ax.plot(time[used], observed[used], ".", color="k", ms=2.0, label="measured, used")
        flagged = ~used & np.isfinite(observed)
        if flagged.any():
            ax.plot(time[flagged], observed[flagged], "x", color="C3", ms=4.0, label="measured, flagged")
        ax.set_ylabel(f"{label} [{unit.label}]")
        ax.grid(alpha=0.3)
    for ax in axes[len(channels):]:
        ax.set_visible(False)
    for ax in axes[max(len(channels), 1) - cols:max(len(channels), 1)]:
        ax.set_xlabel("time [s]")
    if channels:
        axes[0].legend(fontsize="small", loc="best")
    fig.suptitle(title or "Surface channels: measured and predicted")
    return canvas.save_png(fig, path)


def plot_downhole(estimate: xr.Dataset, path: str | Path, *, truth: Mapping[str, np.ndarray] | None = None,
                  units: str | None = None, title: str = "") -> Path:
    """One panel per downhole quantity and estimated parameter: the ensemble mean and its 90 % band in time;
    ``truth`` (name -> values on the estimate's times, SI), where given, drawn over it."""
    parameters = [p for p in str(estimate.attrs.get("parameters", "")).split(",") if p]
    names = [name for name in DOWNHOLE if name in estimate] + [p for p in parameters if p in estimate]
    rows, cols = panel_grid(len(names))
    fig, axes = canvas.new_figure(rows, cols, (4.6 * cols, 2.7 * rows + 0.6), sharex=True)
    time = estimate["time"].values
    for ax, name in zip(axes, names):
        kind, label = DOWNHOLE.get(name, (None, name.replace("_", " ")))
        unit = axis_unit(kind, units)
        _band(ax, time, estimate[f"{name}_quantile"].values, unit.scale, "C0", "estimate")
        ax.plot(time, estimate[name].values * unit.scale, color="C0", lw=1.0, label="estimate (mean)")
        if truth is not None and name in truth:
            ax.plot(time, np.asarray(truth[name], dtype=float) * unit.scale, color="C3", lw=0.9, label="truth")
        ax.set_ylabel(label if kind is None else f"{label} [{unit.label}]")
        ax.grid(alpha=0.3)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    for ax in axes[len(names) - cols:len(names)]:
        ax.set_xlabel("time [s]")
    if names:
        axes[0].legend(fontsize="small", loc="best")
    fig.suptitle(title or "Downhole estimate: mean and 90 % band")
    return canvas.save_png(fig, path)
