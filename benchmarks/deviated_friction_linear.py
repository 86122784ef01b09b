"""The growth rate of the deviated case's first torsional mode with and without the along-string friction, by
the eigenvalues of the right-hand side's Jacobian (central differences of the compiled ``model.rhs``) at the
steady state, against the stability analysis's (``drillstring.dynamics.stability``: its steady state and state
matrix with the friction's load, axial resistance and closed-form Jacobian) (issue 34 item 4;
docs/stiff_string.md, "Torsional stability").

    PYTHONPATH=src python benchmarks/deviated_friction_linear.py

The steady state for the differences: the stability analysis's (its rate of penetration with the friction's
axial resistance, the static offsets of every load, the friction's too); off bottom the model's own start (its
steady twist, :meth:`ReducedOrderModel.friction_twist`), the same state.

Cases: drilling at 120 rpm (the case), friction off / kinetic; off bottom at 30 rpm, kinetic / static factor
1.5 with a Stribeck speed of 0.1 m/s. Printed: the first torsional root (the lowest root
below 1 Hz whose eigenvector is mostly torsional), its frequency [Hz] and growth rate [1/s], by differences and by
the stability analysis (its leading torsional root).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import stability, steady_drilling
from drillstring.forces.string_friction import CoulombStringFriction


def _steady(model):
    """The stability analysis's steady drilling, the friction's load, axial resistance and twist in it."""
    return np.array(steady_drilling(model).state, dtype=float)


def _jacobian(model, y, t=0.0):
    """Central differences of ``model.rhs`` about ``y``."""
    size = y.size
    jac = np.empty((size, size))
    for k in range(size):
        step = 1e-6 * max(abs(y[k]), 1e-3)
        up, down = y.copy(), y.copy()
        up[k] += step
        down[k] -= step
        jac[:, k] = (model.rhs(t, up) - model.rhs(t, down)) / (2.0 * step)
    return jac


def _first_torsional(model, jac):
    values, vectors = np.linalg.eig(jac)
    n = model.size
    torsional = np.array([f == "torsional" for f in model.family])
    best = None
    for value, vector in zip(values, vectors.T):
        if value.imag <= 0.0 or value.imag / (2 * np.pi) > 1.0:
            continue
        position = np.abs(vector[:n]) ** 2
        share = position[torsional].sum() / position.sum()
        if share > 0.5 and (best is None or value.imag < best.imag):
            best = value
    return best


def main() -> None:
    case = load_case("deviated")
    drilling = case_reduced_model(case)
    off = case.model_copy(update={"bit_rock": case.bit_rock.model_copy(update={"law": "off_bottom"}),
                                  "operation": case.operation.model_copy(update={"top_speed": np.pi})})
    off_bottom = case_reduced_model(off)
    print(f"{'case':<44}{'frequency [Hz]':>16}{'growth rate [1/s]':>19}{'analysis [Hz]':>15}{'analysis [1/s]':>16}")
    runs = (("drilling 120 rpm, no friction", dataclasses.replace(drilling, string_friction=None), False),
            ("drilling 120 rpm, kinetic friction", drilling, False),
            ("off bottom 30 rpm, no friction", dataclasses.replace(off_bottom, string_friction=None), True),
            ("off bottom 30 rpm, kinetic friction", off_bottom, True),
            ("off bottom 30 rpm, k_s 1.5, v_S 0.1 m/s",
             dataclasses.replace(off_bottom, string_friction=CoulombStringFriction(0.01, 1.5, 0.1)), True))
    for label, model, start in runs:
        y = model.initial_state(0.0, 0) if start else _steady(model)
        root = _first_torsional(model, _jacobian(model, y))
        analysis = stability(model).leading_by_family["torsional"]
        print(f"{label:<44}{root.imag / (2 * np.pi):>16.4f}{root.real:>19.5f}{analysis.frequency:>15.4f}"
              f"{analysis.growth_rate:>16.5f}")


if __name__ == "__main__":
    main()
