"""Matplotlib figures of a global sensitivity run: Sobol' indices and their convergence."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drillstring.outputs import canvas
from drillstring.outputs.canvas import panel_grid

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


def _values(mapping: dict, parameters: list[str]) -> np.ndarray:
    return np.array([np.nan if mapping.get(p) is None else float(mapping[p]) for p in parameters])


def plot_sobol(indices: dict, path: str | Path) -> Path:
    """Bar chart of Sobol' indices, one panel per output: first-order S1 (solid) and total ST (light) of
    each parameter with their confidence intervals as error bars. ``indices`` is the JSON form of a
    :class:`~drillstring.stochastic.sensitivity.SobolResult` (``to_dict()``, as in ``sensitivity.json``).
    Written to the PNG ``path``."""
    parameters = list(indices["parameters"])
    outputs = list(indices["outputs"])
    rows, cols = panel_grid(len(outputs))
    fig, axes = canvas.new_figure(rows, cols, (3.3 * cols + 1.0, 3.2 * rows + 0.8))
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
    return canvas.save_png(fig, path)


def plot_sobol_convergence(indices: dict, path: str | Path) -> Path:
    """The Sobol' indices of each output at N/4, N/2 and N base samples (S1 solid, ST dashed, one colour
    per parameter): converged indices are flat. ``indices`` as for :func:`plot_sobol`."""
    parameters = list(indices["parameters"])
    outputs = list(indices["outputs"])
    rows, cols = panel_grid(len(outputs))
    fig, axes = canvas.new_figure(rows, cols, (3.3 * cols + 1.0, 3.0 * rows + 0.8))
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
    return canvas.save_png(fig, path)
