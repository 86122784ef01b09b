"""Which term of the reduced model makes it stiff: the diagnosis of a run whose step size collapsed.

An explicit Runge–Kutta method is stable for steps ``h ≲ ρ / λ``, with ``λ`` the largest modulus of the
eigenvalues of the Jacobian ``J = ∂f/∂y`` of the right-hand side and ``ρ`` the radius of the method's
stability region along the axes (about 3.3 for dopri5, 2.5 for bs32; Hairer & Wanner, *Solving ODEs II*,
§IV.2). When the step size collapses, the term with the largest ``λ`` is the likely cause. With the state
``y = [η, η̇]`` of the reduced model (:mod:`drillstring.dynamics.rom`) the terms are:

- ``modes``: the highest natural frequency of the basis, ``max |ω_i|`` (its stiffness: elastic, stabilizer
  springs, fluid centrifugal compression, prestress);
- ``structural damping`` and ``fluid damping`` (Coriolis and viscous, from the fluid velocity): the
  spectral radius of each part of the modal damping matrix ``D``;
- ``bit–rock law`` and ``borehole contact``: the spectral radius of the nonlinear part of ``J`` (finite
  differences of the right-hand side about ``y``, minus the linear part), on the axial–torsional rows and
  columns (the bit–rock law acts there) and on the lateral ones (contact, turning loads).
"""

from __future__ import annotations

import numpy as np

#: Radius of the explicit methods' stability regions along the axes, ``|h λ| ≲ ρ`` (Hairer & Wanner II,
#: §IV.2, Fig. 2.1: dopri5 ≈ 3.3 on the real axis, ≈ 3.4 on the imaginary one; bs32 ≈ 2.5, ≈ 1.7).
STABILITY_RADIUS = {"dopri5": 3.3, "bs32": 2.5}


def _radius(matrix: np.ndarray) -> float:
    if matrix.size == 0:
        return 0.0
    values = np.linalg.eigvals(matrix)
    return float(np.abs(values).max()) if np.all(np.isfinite(values)) else float("inf")


def stiffness_rates(model, t: float, y: np.ndarray) -> dict[str, float]:
    """The largest rate ``λ`` [1/s] each term of ``model`` (a
    :class:`~drillstring.dynamics.rom.ReducedOrderModel`) contributes at time ``t`` [s] and state ``y``
    (module docstring), largest first."""
    n = model.size
    y = np.asarray(y, dtype=float)
    fluid = model.basis.T @ (model.system.fluid_damping @ model.basis)
    rates = {
        "modes (highest natural frequency: stabilizers, fluid centrifugal force, prestress)":
            float(np.abs(model.angular_frequencies).max(initial=0.0)),
        "structural damping": _radius(model.damping - fluid),
        "fluid damping (Coriolis and viscous: the fluid velocity)": _radius(fluid),
    }
    # Jacobian of the right-hand side by central differences, minus its linear part
    base = model.rhs(t, y)
    jacobian = np.empty((2 * n, 2 * n))
    for j in range(2 * n):
        step = 1e-7 * max(1.0, abs(y[j]))
        plus, minus = y.copy(), y.copy()
        plus[j] += step
        minus[j] -= step
        # the modal rows only (a top drive's controller states follow them in the state)
        jacobian[:, j] = (model.rhs(t, plus)[:2 * n] - model.rhs(t, minus)[:2 * n]) / (2.0 * step)
    linear = np.zeros_like(jacobian)
    linear[:n, n:] = np.eye(n)
    linear[n:, :n] = -np.diag(model.omega2)
    linear[n:, n:] = -model.damping
    nonlinear = np.where(np.isfinite(jacobian), jacobian - linear, np.inf) if np.all(np.isfinite(base)) \
        else np.full_like(jacobian, np.inf)
    labels = np.asarray(model.family)
    lateral = np.char.startswith(labels, "lateral")
    for name, keep in (("bit–rock law (the nonlinear axial and torsional forces)", ~lateral),
                       ("borehole contact (the nonlinear lateral forces)", lateral)):
        index = np.concatenate([np.nonzero(keep)[0], n + np.nonzero(keep)[0]])
        rates[name] = _radius(nonlinear[np.ix_(index, index)])
    return dict(sorted(rates.items(), key=lambda item: -item[1]))


def stiffness_diagnosis(model, t: float, y: np.ndarray, method: str = "dopri5") -> str:
    """One phrase naming the likely stiff term at ``(t, y)``, the step size it allows and the next term, e.g.
    ``likely stiff term: fluid damping (...), λ = 1.2e+09 1/s, stable steps ≲ 2.7e-09 s (next: ...)``.
    The rates depend on the state: a stiffness that drove the state far (a huge stabilizer stiffness
    seen by the modes) may leave another term the stiffest where the run stops, so the next one is named."""
    try:
        rates = stiffness_rates(model, t, y)
    except (ValueError, FloatingPointError, np.linalg.LinAlgError):  # a state the model cannot evaluate
        return "likely stiff term: unknown (the right-hand side cannot be differentiated there)"
    (name, rate), (second, second_rate) = list(rates.items())[:2]
    radius = STABILITY_RADIUS.get(method, 3.3)
    allowed = radius / rate if rate > 0 else float("inf")
    return (f"likely stiff term: {name}, λ = {rate:.3g} 1/s, stable steps ≲ {allowed:.3g} s "
            f"(next: {second}, λ = {second_rate:.3g} 1/s)")
