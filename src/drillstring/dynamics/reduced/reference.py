"""The reduced model's NumPy right-hand side: the straightforward reference (full basis, every node, the
components' own NumPy ``evaluate_at``) that the compiled right-hand side (:mod:`drillstring.dynamics.reduced.rhs`)
is tested against, and the path of a component registered outside the package (docs/model.md §5–§9).
"""

from __future__ import annotations

import numpy as np

from drillstring.dynamics.delay import delayed_difference
from drillstring.fem.dofs import THETA_X, dof
from drillstring.fem.dofs import U
from drillstring.forces.registry import (
    BitContext,
    ContactContext,
    HookContext,
    MotorContext,
    StringFrictionContext,
    TopContext,
)


def reference_rhs(model, t: float, y: np.ndarray, history: np.ndarray | None = None) -> np.ndarray:
    """dy/dt of ``model`` (a :class:`~drillstring.dynamics.reduced.model.ReducedOrderModel`) at time ``t`` [s] for
    the state ``y`` = [η, η̇, s], by NumPy: same equations as the compiled right-hand side; ``history`` as in
    :meth:`~drillstring.dynamics.reduced.model.ReducedOrderModel.rhs`."""
    n = model.size
    eta, eta_dot = y[:n], y[n:2 * n]
    bit_velocity = model.bit_u @ eta_dot
    bit_speed = model.base_speed + model.bit_t @ eta_dot
    position, angle = model.bit_position(t, y)
    depth = 0.0
    if model.bit_rock.delayed:  # u minus the hole bottom one blade sector behind the bit
        depth = delayed_difference(model._history(history), angle, position)
    axial_force, bit_torque = model.bit_rock.evaluate_at(BitContext(
        t, position, angle, bit_velocity, bit_speed, depth, model.weight_on_bit))
    st = model.stations
    spin = model.base_speed + model.phi_tx @ eta_dot
    lateral_velocity = model.contact.reads_lateral_velocity
    force_v, force_w, torque = model.contact.evaluate_at(ContactContext(
        st.gather(model.phi_v @ eta) + model.station_rest[0], st.gather(model.phi_w @ eta) + model.station_rest[1],
        st.gather(model.phi_v @ eta_dot) if lateral_velocity else np.zeros(len(st)),
        st.gather(model.phi_w @ eta_dot) if lateral_velocity else np.zeros(len(st)),
        st.gather(spin), st.gap, st.outer_diameter, model.station_stiffness))
    n_nodes = model.static.mesh.n_nodes
    turning = model.basis.T @ model.turning_loads.forces(model.base_speed * t + model.phi_tx @ eta, spin)
    lateral = model.lateral_columns
    generalized = (model.phi_v.T @ st.scatter(force_v, n_nodes) + model.phi_w.T @ st.scatter(force_w, n_nodes)
                   + model.phi_tx.T @ st.scatter(torque, n_nodes)
                   + model.bit_u * (axial_force + model.weight_on_bit) + model.bit_t * bit_torque
                   + model.top_u * float(model.hook_load.evaluate_at(HookContext(t, model.weight_on_bit)))
                   + model.generalized_force + np.where(lateral, turning, 0.0))
    acceleration = generalized - model.damping @ eta_dot - model.omega2 * eta
    if model.active_friction is not None:  # the wall's friction along a string resting on it (a deviated well)
        fs = model.friction_stations
        axial_shapes = model.basis[dof(np.asarray(fs.node, dtype=np.int64), U)]
        force, torque = model.active_friction.evaluate_at(StringFrictionContext(
            axial_shapes @ eta_dot, spin[fs.node], fs.normal_force, fs.radius, fs.friction))
        acceleration = acceleration + axial_shapes.T @ force + model.phi_tx[fs.node].T @ torque
    states = np.zeros(model.state_size - 2 * n)
    if model.top_drive.drives:  # the motor torque of any driving boundary, its states where the registry put them
        first = model.layout.states["top_boundary"]
        torque, rates = model.top_drive.evaluate_at(
            TopContext(t, model.base_speed + model.quill_shapes @ eta_dot, model.surface_torque_shapes @ eta),
            y[first:first + model.top_drive.n_states])
        states[first - 2 * n:first - 2 * n + model.top_drive.n_states] = rates
        acceleration = acceleration + model.quill_shapes * torque
    if model.motor is not None:  # +T on the rotor side, -T on the stator side; its states where the layout puts them
        first = model.layout.states["motor"]
        torque, rates = model.motor.evaluate_at(MotorContext(t, model.motor_shapes @ eta_dot),
                                                y[first:first + model.motor.n_states])
        states[first - 2 * n:first - 2 * n + model.motor.n_states] = rates
        acceleration = acceleration + model.motor_shapes * float(torque)
    if model.nonlinear == "full":
        q = model.basis @ eta
        qd = model.basis @ eta_dot
        qd[dof(np.arange(model.static.mesh.n_nodes), THETA_X)] += model.base_speed
        f_se = model.elements.strain_energy_forces(q, np.zeros_like(q))
        f_vel = np.zeros_like(q)
        model.elements.kinetic_forces(q, qd, f_vel)
        mass_nl = model.elements.mass_correction_matrix(q)
        mass = np.eye(model.size) + model.basis.T @ (mass_nl @ model.basis)
        acceleration = np.linalg.solve(mass, acceleration + model.basis.T @ (f_se + f_vel))
    return np.concatenate([eta_dot, acceleration, states])
