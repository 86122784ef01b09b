"""The figure of a robust operating point (:mod:`drillstring.stochastic.optimize`): the surrogate's objective over
the first two decision variables (the others at the answer), each chance constraint's boundary (its surrogate
probability equal to the bound), the region where some constraint fails hatched, the design points and the
answer marked. Units of the axes: the display units of each variable's dimension (rpm, kN, ...)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drillstring.case import Case
from drillstring.units import DisplayUnit, display_unit

__all__ = ["decision_unit", "plot_optimization"]

#: A case dimension's name -> the display kind of :func:`~drillstring.units.display_unit`.
_KINDS = {"angular speed": "angular_speed", "force": "force", "volume flow": "flow", "torque": "torque",
          "pressure": "pressure", "density": "density", "stiffness": "stiffness"}
#: Objectives' display: name prefix -> (display kind, label).
_OBJECTIVE_KIND = {"rate_of_penetration": ("rate_of_penetration", "ROP"),
                   "mechanical_specific_energy": ("pressure", "MSE")}


def decision_unit(case: Case, path: str, units: str | None = None) -> DisplayUnit:
    """The display unit of a decision variable: its dimension's unit in the system ``units`` (rpm, kN, L/min,
    ...), SI for other dimensions."""
    from drillstring.stochastic.parameters import WEIGHT_ON_HOOK, case_parameter

    if path == WEIGHT_ON_HOOK:
        return display_unit("force", units)
    dimension = case_parameter(case, path).dimension
    kind = _KINDS.get(dimension.name)
    return display_unit(kind, units) if kind else DisplayUnit(dimension.si or "1", 1.0)


def objective_unit(objective: str, units: str | None = None) -> tuple[DisplayUnit, str]:
    key = next(k for k in _OBJECTIVE_KIND if objective.startswith(k))
    kind, label = _OBJECTIVE_KIND[key]
    return display_unit(kind, units), label


def plot_optimization(case: Case, result: dict, path: str | Path, *, units: str | None = None,
                      resolution: int = 61) -> Path:
    """Draw the search's figure (module docstring) to ``path`` (PNG)."""
    from drillstring.outputs.canvas import new_figure, save_png

    problem, surrogates = result["problem"], result["surrogates"]
    names, bounds = result["variables"], np.asarray(result["bounds"], dtype=float)
    best = np.asarray(result["recommended"]["values"], dtype=float)
    design = np.asarray(result["design"], dtype=float)
    shown = [decision_unit(case, name, units) for name in names]
    value_unit, value_label = objective_unit(result["objective"], units)
    sign = 1.0 if result["maximize"] else -1.0
    fig, (ax,) = new_figure(1, 1, (7.0, 5.2))
    label = f"{'expected ' if '_q' not in result['objective'] else ''}{value_label}" + (
        f" (quantile {result['objective'].rsplit('_q', 1)[1]} %)" if "_q" in result["objective"] else "")
    if len(names) == 1:
        grid = np.linspace(bounds[0, 0], bounds[0, 1], resolution)[:, None]
        unit = problem.to_unit(grid)
        x = shown[0](grid[:, 0])
        if surrogates.objective is not None:
            mean, sd = surrogates.objective.predict(unit)
            ax.plot(x, value_unit(sign * mean), color="C0", label=f"surrogate {label}")
            ax.fill_between(x, value_unit(sign * mean - 2 * sd), value_unit(sign * mean + 2 * sd), color="C0",
                            alpha=0.2)
        ax.plot(shown[0](design[:, 0]), value_unit(np.asarray(result["estimates"]["objective"])), "k.",
                label="design points (Monte Carlo)")
        failing = np.zeros(len(grid), dtype=bool)
        for gp, limit in zip(surrogates.constraints, problem.limits):
            failing |= gp.predict(unit)[0] > limit
        for lo, hi in _runs(x, failing):
            ax.axvspan(lo, hi, color="0.5", alpha=0.25, hatch="//", lw=0)
        ax.axvline(shown[0](best[0]), color="C3", ls="--", label="recommended")
        ax.set_xlabel(_axis_label(names[0], shown[0]))
        ax.set_ylabel(f"{label} [{value_unit.label}]")
        ax.legend(fontsize=8)
    else:
        u0, u1 = np.meshgrid(np.linspace(0, 1, resolution), np.linspace(0, 1, resolution))
        unit = np.tile(problem.to_unit(best)[0], (u0.size, 1))
        unit[:, 0], unit[:, 1] = u0.ravel(), u1.ravel()
        values = problem.from_unit(unit)
        x, y = shown[0](values[:, 0]).reshape(u0.shape), shown[1](values[:, 1]).reshape(u0.shape)
        if surrogates.objective is not None:
            mean = sign * surrogates.objective.predict(unit)[0].reshape(u0.shape)
            filled = ax.contourf(x, y, value_unit(mean), levels=14, cmap="viridis")
            fig.colorbar(filled, ax=ax, label=f"surrogate {label} [{value_unit.label}]")
        failing = np.zeros(u0.shape, dtype=bool)
        for k, (gp, limit) in enumerate(zip(surrogates.constraints, problem.limits)):
            p = gp.predict(unit)[0].reshape(u0.shape)
            failing |= p > limit
            if p.min() < limit < p.max():
                ax.contour(x, y, p, levels=[limit], colors=[f"C{k + 1}"], linewidths=1.8)
                ax.plot([], [], color=f"C{k + 1}", label=f"P({result['recommended']['constraints'][k]['event']}) "
                                                          f"= {limit:g}")
        if failing.any():
            ax.contourf(x, y, failing.astype(float), levels=[0.5, 1.5], colors="none", hatches=["//"])
            ax.plot([], [], color="0.3", ls=":", label="hatched: a constraint fails (surrogate)")
        initial = result["initial"]
        ax.plot(shown[0](design[:initial, 0]), shown[1](design[:initial, 1]), "wo", mec="k", ms=5,
                label="initial design")
        ax.plot(shown[0](design[initial:, 0]), shown[1](design[initial:, 1]), "ks", ms=4, label="sequential points")
        ax.plot(shown[0](best[0]), shown[1](best[1]), "*", color="C3", mec="k", ms=16, label="recommended")
        ax.set_xlabel(_axis_label(names[0], shown[0]))
        ax.set_ylabel(_axis_label(names[1], shown[1]))
        ax.legend(fontsize=7, loc="best", framealpha=0.8)
        if len(names) > 2:
            ax.set_title("other variables at the recommended point", fontsize=9)
    return save_png(fig, path)


def _axis_label(path: str, unit: DisplayUnit) -> str:
    return f"{path.rsplit('.', 1)[-1].replace('_', ' ')} [{unit.label}]"


def _runs(x: np.ndarray, mask: np.ndarray) -> list[tuple[float, float]]:
    """Intervals of ``x`` where ``mask`` holds."""
    out, start = [], None
    for xi, m in zip(x, mask):
        if m and start is None:
            start = xi
        if not m and start is not None:
            out.append((start, xi))
            start = None
    if start is not None:
        out.append((start, x[-1]))
    return out
