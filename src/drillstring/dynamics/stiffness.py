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
- ``downhole motor``: its torque's slope ``dT/dω_m`` along the rotor's relative row (a viscous damper across
  the rotor, on the small inertia below it: the run's stiffest term when the rotor side is short);
- ``bit–rock law``, ``top drive`` and ``borehole contact``: the nonlinear part of ``J`` split by where each
  force acts (:func:`stiffness_rates`): the bit–rock law along the bit's shapes, from the law's own partial
  derivatives; the top drive's controller along the quill's; the rest of the finite-difference Jacobian
  (minus the linear part) is the contact's: its forces, and its friction torque on the torsion, which a
  split by coordinates would have blamed on the bit–rock law (a 50 µm radial gap, issue 26).
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


#: The terms named by :func:`stiffness_rates` besides the linear ones.
BIT_ROCK = "bit–rock law (the forces at the bit)"
TOP_DRIVE = "top drive (its controller's torque at the quill)"
MOTOR = "downhole motor (its torque's slope across the rotor, on the string below it)"
CONTACT = "borehole contact (the lateral contact forces and their friction torque; turning loads)"
BIT_ROCK_JUMP = "bit–rock law's jump (its force changes between neighbouring states faster than its derivatives)"


def _partials(function, point: np.ndarray) -> np.ndarray:
    """Central differences of the vector ``function(x)`` at ``point``: (outputs, inputs)."""
    columns = []
    for j in range(len(point)):
        step = 1e-7 * max(1.0, abs(point[j]))
        plus, minus = point.copy(), point.copy()
        plus[j] += step
        minus[j] -= step
        columns.append((np.asarray(function(plus), dtype=float) - np.asarray(function(minus), dtype=float))
                       / (2.0 * step))
    return np.column_stack(columns)


#: The bit law's inputs in :func:`_bit_law_at`'s point, with their units.
BIT_INPUTS = (("axial velocity", "m/s"), ("bit speed", "rad/s"), ("depth of cut", "m"))


def _bit_context_at(model, t: float, y: np.ndarray):
    """The bit–rock law's named context (:class:`~drillstring.forces.registry.BitContext`) at ``(t, y)``: the
    bit's velocity ``b_uᵀη̇`` [m/s], speed ``Ω + b_tᵀη̇`` [rad/s], depth of cut [m] (delayed laws, from the
    model's bit history), position, angle and the static weight on bit."""
    from drillstring.dynamics.delay import delayed_difference
    from drillstring.forces.registry import bit_context

    n = model.size
    eta_dot = y[n:2 * n]
    position, angle = model.bit_position(t, y)
    depth = delayed_difference(model.history, angle, position) if model.bit_rock.delayed else 0.0
    return bit_context(model.bit_u @ eta_dot, model.base_speed + model.bit_t @ eta_dot, depth, time=t,
                       position=position, angle=angle, weight_on_bit=model.weight_on_bit)


def _bit_law_at(model, t: float, y: np.ndarray):
    """The bit's inputs ``(u̇ [m/s], θ̇ [rad/s], d [m])`` at ``(t, y)`` and the law's ``(force, torque)`` as a
    function of them (its NumPy reference :meth:`~drillstring.forces.registry.BitLaw.evaluate_at` on the named
    context, the bit's position and angle held)."""
    ctx = _bit_context_at(model, t, y)
    point = np.array([ctx.axial_velocity, ctx.bit_speed, ctx.depth_of_cut], dtype=float)

    def forces(x: np.ndarray) -> np.ndarray:
        moved = ctx._replace(axial_velocity=x[0], bit_speed=x[1], depth_of_cut=x[2])
        return np.array(model.bit_rock.evaluate_at(moved), dtype=float).ravel()

    return point, forces


def bit_rock_jump(model, t: float, y: np.ndarray) -> str:
    """Where the bit–rock law jumps at ``(t, y)``: the input of the law (:data:`BIT_INPUTS`) whose step of the
    finite differences (``1e-7`` relative, at least ``1e-7`` absolute) each side changes the force on bit most,
    its value and the change of the force [kN] and torque [kN·m] across it, e.g. ``its force jumps by 71.3 kN across
    depth of cut = 1e-10 m (law 'detournay')``."""
    point, forces = _bit_law_at(model, t, y)
    best = None
    for k, (name, unit) in enumerate(BIT_INPUTS):
        step = 1e-7 * max(1.0, abs(point[k]))  # the steps of the finite differences that saw the jump
        plus, minus = point.copy(), point.copy()
        plus[k] += step
        minus[k] -= step
        change = np.abs(forces(plus) - forces(minus))
        if best is None or change[0] > best[0][0]:
            best = (change, name, unit, point[k])
    change, name, unit, value = best
    return (f"its force on bit changes by {change[0] / 1e3:.4g} kN and its torque by {change[1] / 1e3:.4g} kN·m "
            f"across {name} = {value:.3g} {unit} (law {model.bit_rock.name!r})")


def _bit_rock_rows(model, t: float, y: np.ndarray) -> np.ndarray:
    """The bit–rock law's part of ``∂(η̈)/∂y`` (n rows), from the law's own Jacobian at the state
    (:meth:`~drillstring.forces.registry.BitLaw.jacobian_at` on the named context and, for a delayed law,
    :meth:`depth_partials`, so any registered law): its force and torque act along the bit's shapes ``b_u``,
    ``b_t`` and depend on the bit's velocity ``b_uᵀη̇``, speed ``Ω + b_tᵀη̇`` and (delayed laws) depth of cut
    through the bit's position ``b_uᵀη``."""
    n = model.size
    bit = model.bit_rock
    ctx = _bit_context_at(model, t, y)
    law = np.zeros((2, 3))
    law[:, :2] = np.asarray(bit.jacobian_at(ctx), dtype=float)
    if bit.delayed:
        law[:, 2] = np.asarray(bit.depth_partials(ctx), dtype=float).ravel()
    shapes = np.column_stack([model.bit_u, model.bit_t])  # (n, 2): force along b_u, torque along b_t
    rows = np.zeros((n, len(y)))
    rows[:, n:2 * n] = shapes @ law[:, :2] @ shapes.T
    rows[:, :n] = shapes @ law[:, 2:3] @ model.bit_u[None, :]
    return rows


def _top_drive_rows(model, t: float, y: np.ndarray, jacobian: np.ndarray) -> np.ndarray:
    """The driving top boundary's part of ``∂(η̈, ż)/∂y``: its motor torque acts along the quill's shapes and
    depends on the quill speed, the surface torque and its states (its own Jacobian at the state,
    :meth:`~drillstring.forces.registry.TopBoundary.jacobian_at` on the named context, so any registered
    boundary, with states or without), and its states' own rows (from the finite-difference ``jacobian``)."""
    from drillstring.forces.registry import TopContext

    n, boundary = model.size, model.top_drive
    states = boundary.n_states if boundary.drives else 0
    rows = np.zeros((n + states, len(y)))
    if not boundary.drives:
        return rows
    first = model.layout.states["top_boundary"]
    point = np.array([model.base_speed + model.quill_shapes @ y[n:2 * n], model.surface_torque_shapes @ y[:n],
                      *y[first:first + states]])
    torque = np.asarray(boundary.jacobian_at(TopContext(t, point[0], point[1]), point[2:]), dtype=float)[0]
    rows[:n, n:2 * n] = np.outer(model.quill_shapes, torque[0] * model.quill_shapes)
    rows[:n, :n] = np.outer(model.quill_shapes, torque[1] * model.surface_torque_shapes)
    rows[:n, first:first + states] = np.outer(model.quill_shapes, torque[2:])
    rows[n:] = jacobian[n:]  # the jacobian holds the rows of η̈, then those of the states
    return rows


def _rate(rows: np.ndarray, n: int) -> float:
    """The spectral radius of ``[[0, I, 0], rows]``: the rates a term sets on its own with the kinematics
    ``η' = η̇`` (a stiffness-like part ``A`` gives ``sqrt|A|``, a damping-like one ``|B|``)."""
    size = rows.shape[1]
    matrix = np.zeros((size, size))
    matrix[:n, n:2 * n] = np.eye(n)
    matrix[n:n + len(rows)] = rows
    return _radius(matrix)


def _has_contact(model) -> bool:
    """Whether ``model`` has forces besides the bit's that the rest of the Jacobian could hold: lateral
    coordinates (the borehole contact acts on them) or loads turning with the string."""
    lateral = any(f.startswith("lateral") for f in model.family)
    turning = model.turning_loads is not None and bool(np.size(model.turning_loads.node))
    return lateral or turning


def stiffness_rates(model, t: float, y: np.ndarray) -> dict[str, float]:
    """The largest rate ``λ`` [1/s] each term of ``model`` (a
    :class:`~drillstring.dynamics.rom.ReducedOrderModel`) contributes at time ``t`` [s] and state ``y``
    (module docstring), largest first.

    The nonlinear terms are told apart by where their forces act, not by which coordinates they move: the
    bit–rock law's part of the Jacobian comes from the law's own derivatives along the bit's shapes, the top
    drive's from its controller's along the quill's, and the rest of the nonlinear Jacobian (finite
    differences of the right-hand side, minus the linear part and those two) is split by where it acts: along the
    bit's shapes a jump of the bit–rock law (:data:`BIT_ROCK_JUMP`), elsewhere the borehole contact's (its
    forces and their friction torque, which also acts on the torsion) with the turning loads (:data:`CONTACT`,
    named only for a model with lateral coordinates or turning loads). Each term's rate is the spectral radius
    of its part with the kinematic rows ``η' = η̇`` (a jump's "rate" grows as the difference step shrinks: it
    says the term is discontinuous there, not how stiff)."""
    from drillstring.forces.registry import MotorContext

    n = model.size
    y = np.asarray(y, dtype=float)
    size = len(y)
    fluid = model.basis.T @ (model.system.fluid_damping @ model.basis)
    rates = {
        "modes (highest natural frequency: stabilizers, fluid centrifugal force, prestress)":
            float(np.abs(model.angular_frequencies).max(initial=0.0)),
        "structural damping": _radius(model.damping - fluid),
        "fluid damping (Coriolis and viscous: the fluid velocity)": _radius(fluid),
    }
    base = model.rhs(t, y)
    if not np.all(np.isfinite(base)):
        rates.update({BIT_ROCK: np.inf, **({CONTACT: np.inf} if _has_contact(model) else {})})
        return dict(sorted(rates.items(), key=lambda item: -item[1]))
    jacobian = _partials(lambda x: model.rhs(t, x), y)[n:]  # the rows of η̈ and of the controller's states
    linear = np.zeros((n, size))
    linear[:, :n] = -np.diag(model.omega2)
    linear[:, n:2 * n] = -model.damping
    bit_rock = _bit_rock_rows(model, t, y)
    top_drive = _top_drive_rows(model, t, y, jacobian)
    motor = np.zeros((n, size))
    if model.motor is not None:  # its torque pair along the rotor's relative row, from the motor's own slope
        first = model.layout.states["motor"]
        slope = model.motor.jacobian_at(MotorContext(t, model.motor_shapes @ y[n:2 * n]),
                                        y[first:first + model.motor.n_states])[0, 0]
        motor[:, n:2 * n] = slope * np.outer(model.motor_shapes, model.motor_shapes)
        rates[MOTOR] = _rate(motor, n)
    rest = jacobian[:n] - linear - bit_rock - top_drive[:n] - motor
    rest = np.where(np.isfinite(rest), rest, np.inf)
    rates[BIT_ROCK] = _rate(bit_rock, n)
    shapes = np.column_stack([model.bit_u, model.bit_t])
    if np.all(np.isfinite(rest)) and np.any(shapes):  # the rest along the bit's shapes: the law's jump
        along_bit = shapes @ np.linalg.lstsq(shapes, rest, rcond=None)[0]
        rates[BIT_ROCK_JUMP] = _rate(along_bit, n)
        rest = rest - along_bit
    if _has_contact(model):
        rates[CONTACT] = _rate(rest, n)
    if model.top_drive.n_states:
        rates[TOP_DRIVE] = _rate(top_drive, n)
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
    if name == BIT_ROCK_JUMP:  # a discontinuity: say where, not a step size it allows
        return f"likely stiff term: {name}: {bit_rock_jump(model, t, y)} (next: {second}, λ = {second_rate:.3g} 1/s)"
    return (f"likely stiff term: {name}, λ = {rate:.3g} 1/s, stable steps ≲ {allowed:.3g} s "
            f"(next: {second}, λ = {second_rate:.3g} 1/s)")
