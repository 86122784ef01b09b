"""The reduced model's observation (docs/model.md §9): the observables' columns (:data:`OBSERVABLES`), the compiled
observation of one state (:func:`observe_kernel`), the impacts (:func:`impacts_kernel`) and what the model does
after each accepted step (:func:`accepted_step_kernel`).

Impacts: a *contact zone* is a run of consecutive nodes in contact; an impact is a zone that appears
with no node in contact within one node of it at the previous accepted step
(:func:`new_contact_zones`). Counted zone by zone, not node by node, the number of impacts does not
grow as the mesh is refined.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from drillstring.dynamics.delay import record_bottom, view
from drillstring.dynamics.reduced.frame import frame_speed, lateral_displacements, station_spin
from drillstring.dynamics.reduced.rhs import _rhs_kernel
from drillstring.dynamics.reduced.terms import (
    _AXIAL_BIT,
    _TORSION_QUILL,
    _bit_rock,
    _bit_state,
    _delayed,
    _downhole_motor,
    _surely_clear,
    _top_motion,
    inner_kernel,
)
from drillstring.forces.registry import HISTORY, MOTOR_CODE, TOP_BOUNDARY_CODE, TOP_INERTIA, TopContext, top_boundary_torque

#: Order of the observables returned by :meth:`ReducedOrderModel.observe` before the probes.
OBSERVABLES = (
    "rate_of_penetration",  # m/s, u̇ at the bit
    "bit_speed",  # rad/s, θ̇x at the bit
    "torque_on_bit",  # N·m, torque the rock applies against the rotation (−t_xbit)
    "force_on_bit",  # N, axial force of the rock on the bit, upward positive (−f_xbit)
    "bit_depth",  # m, bit displacement from the static state (advance of the bit)
    "nodes_in_contact",  # number of nodes touching the borehole
    "contact_force",  # N, total normal force of the wall on the string, Σ k_i (r_i − g_i)₊ over stations
    "quill_speed",  # rad/s, θ̇x at the top (the set point with an imposed speed)
    "surface_torque",  # N·m, torque the string takes from the quill: τ_m − J_td θ̈₀ with a top drive (the quill's
                       # equation of motion); the elastic torque of the top element, (K q) at θx, with the speed imposed
    "depth_of_cut",  # m, depth of cut per blade of a delayed (Detournay) law; 0 for the other laws
    "motor_speed",  # rad/s, a downhole motor's rotor speed relative to its stator (0 without a motor)
    "motor_torque",  # N·m, the torque of a downhole motor's rotor on the string below it (0 without a motor)
)
#: Column of each observable in the observation kernel's output, derived from :data:`OBSERVABLES` (the
#: kernel writes by these names, so reordering the tuple reorders the output consistently).
OBSERVABLE_COLUMN = {name: column for column, name in enumerate(OBSERVABLES)}
_ROP = OBSERVABLE_COLUMN["rate_of_penetration"]
_BIT_SPEED = OBSERVABLE_COLUMN["bit_speed"]
_TOB = OBSERVABLE_COLUMN["torque_on_bit"]
_FOB = OBSERVABLE_COLUMN["force_on_bit"]
_DEPTH = OBSERVABLE_COLUMN["bit_depth"]
_CONTACTS = OBSERVABLE_COLUMN["nodes_in_contact"]
_CONTACT_FORCE = OBSERVABLE_COLUMN["contact_force"]
_QUILL_SPEED = OBSERVABLE_COLUMN["quill_speed"]
_SURFACE_TORQUE = OBSERVABLE_COLUMN["surface_torque"]
_DEPTH_OF_CUT = OBSERVABLE_COLUMN["depth_of_cut"]
_MOTOR_SPEED = OBSERVABLE_COLUMN["motor_speed"]
_MOTOR_TORQUE = OBSERVABLE_COLUMN["motor_torque"]
#: First column of the probes' displacements: after the observables, for ``n_p`` probes, ``n_p`` columns of
#: radial displacement r, then ``n_p`` of v (along y), then ``n_p`` of w (along z) [m]
#: (:func:`observation_width`).
PROBE_COLUMN = len(OBSERVABLES)


def observation_width(n_probes: int) -> int:
    """Columns of one observation row: the observables, then r, v and w at each probe."""
    return PROBE_COLUMN + 3 * n_probes


@inner_kernel()
def observes_rate(d):
    """Whether :func:`observe_kernel` reads dy/dt (its ``rate``) for the case-2 data ``d``: a driving top
    boundary's surface torque does. Compiled code; from Python, ``observes_rate.py_func(d)``."""
    return d.laws[TOP_BOUNDARY_CODE] != 0.0


@inner_kernel(inline="always")  # its one caller: no compiled function of its own (docs/performance.md)
def _surface_torque(d, t, y, rate):
    """The surface torque T_s [N·m] of a driving top boundary from the quill's equation of motion, ``J_td θ̈₀ =
    τ_m − T_s``: the boundary's motor torque (:func:`~drillstring.forces.registry.top_boundary_torque`) minus the
    quill's inertial torque, with ``θ̈₀ = qᵀη̈`` from ``rate``, the case-2 model's right-hand side at ``(t, y)``
    (:func:`observe_kernel`), and ``J_td`` the inertia the boundary lumps at the quill (the registry's header).
    For the same quill and bit motion it does not depend on ``J_td`` (the elastic torque of the top element,
    read from a truncated basis, does: the basis's shapes depend on ``J_td``)."""
    n = d.omega2.shape[0]
    t0, t1 = d.ranges.torsion_start, d.ranges.torsion_end
    quill, elastic = _top_motion(d, t, y)
    # the boundary writes its states' rates into ``rate`` (past η̈, the same values as the right-hand side's)
    torque = top_boundary_torque(d.laws, TopContext(t, quill, elastic), y, rate)
    acceleration = 0.0
    for j in range(t0, t1):
        acceleration += d.torsion_rows[_TORSION_QUILL, j - t0] * rate[n + j]
    return torque - d.laws[TOP_INERTIA] * acceleration


@inner_kernel()
def _contact_state(d, y, v, w, in_contact):
    """Fill ``v``, ``w`` (every node) and ``in_contact`` (nodes with a station outside its gap) for the
    state ``y``; returns the total normal force of the wall Σ k_i (r_i − g_i)₊ [N]."""
    lateral_displacements(d, y, v, w)
    in_contact[:] = False
    c = d.contact
    total = 0.0
    for k in range(c.node.shape[0]):
        i = c.node[k]
        r = math.sqrt(v[i] * v[i] + w[i] * w[i])
        if r > c.gap[k]:
            in_contact[i] = True
            total += c.stiffness[k] * (r - c.gap[k])
    return total


@njit(cache=True)
def new_contact_zones(in_contact, previous):
    """Number of contact zones (runs of consecutive nodes in contact) in ``in_contact`` with no node of
    ``previous`` in contact within one node of the zone: the impacts since ``previous``."""
    n = in_contact.shape[0]
    count = 0
    i = 0
    while i < n:
        if not in_contact[i]:
            i += 1
            continue
        j = i
        while j + 1 < n and in_contact[j + 1]:
            j += 1
        seen = False
        for k in range(max(i - 1, 0), min(j + 2, n)):
            if previous[k]:
                seen = True
                break
        if not seen:
            count += 1
        i = j + 1
    return count


@njit(cache=True)
def impacts_kernel(d, o, y):
    """Impacts at the accepted state ``y`` since the previous call (:func:`new_contact_zones`); keeps
    the nodes in contact in ``o.previous`` for the next call. Where the bound of
    :func:`~drillstring.dynamics.reduced.terms._surely_clear` says no node can touch (the right-hand side's
    own test, one pass over the lateral coordinates), no node is in contact and nothing else is computed."""
    ranges = d.ranges
    if ranges.lateral_y_end == ranges.lateral_y_start and ranges.lateral_z_end == ranges.lateral_z_start:
        return 0
    if _surely_clear(d, y):  # reads η = y[:n] only
        for i in range(o.current.shape[0]):
            o.current[i] = False
            o.previous[i] = False
        return 0
    _contact_state(d, y, o.v, o.w, o.current)
    new = new_contact_zones(o.current, o.previous)
    for i in range(o.current.shape[0]):  # a loop, not `previous[:] = current`: the slice assignment's
        o.previous[i] = o.current[i]     # shape-mismatch error message costs ~2.5 s of compilation
    return new


@njit(cache=True)
def observe_kernel(d, o, t, y, rate, out):
    """Observables (:data:`OBSERVABLES`, by their columns) and the radial displacement at the probes for
    the state ``y`` at time ``t`` [s], from the case-2 data ``d`` (:class:`RhsData`) and ``o``
    (:class:`ObserveData`, whose contact mask it fills). Returns the number of nodes in contact.

    ``rate``: where the top boundary drives the string (:func:`observes_rate`), dy/dt of the case-2 model at
    ``(t, y)`` (:func:`_rhs_kernel`), which the surface torque reads; not read otherwise. A driving boundary and a
    downhole motor write their states' rates into it (past η̈), so the kernel allocates nothing (it runs without
    Numba's reference counting, docs/performance.md). The caller evaluates
    it rather than this kernel: every compiled function that calls the right-hand side carries a copy of its
    whole call tree, which Numba optimizes and generates again (three such callers here cost a third more
    first compilation, measured, docs/performance.md)."""
    axial_force, bit_torque, depth_of_cut, depth, bit_velocity, bit_speed = _bit_rock(d, t, y)
    force = _contact_state(d, y, o.v, o.w, o.in_contact)
    count = 0
    for i in range(o.in_contact.shape[0]):
        count += o.in_contact[i]
    out[_ROP] = bit_velocity
    out[_BIT_SPEED] = bit_speed
    out[_TOB] = -bit_torque
    out[_FOB] = -axial_force
    out[_DEPTH] = depth
    out[_DEPTH_OF_CUT] = depth_of_cut
    out[_CONTACTS] = count
    out[_CONTACT_FORCE] = force
    out[_QUILL_SPEED], out[_SURFACE_TORQUE] = _top_motion(d, t, y)
    if observes_rate(d):  # a driving boundary: the torque from the quill's equation of motion
        out[_SURFACE_TORQUE] = _surface_torque(d, t, y, rate)
    out[_MOTOR_SPEED] = 0.0
    out[_MOTOR_TORQUE] = 0.0
    if d.laws[MOTOR_CODE] != 0.0:
        # the motor writes its states' rates into ``rate`` (scratch here, read above only)
        out[_MOTOR_SPEED], out[_MOTOR_TORQUE] = _downhole_motor(d, t, y, rate)
    n_p = o.probe_nodes.shape[0]
    for k in range(n_p):
        j = o.probe_nodes[k]
        out[PROBE_COLUMN + k] = np.sqrt(o.v[j] * o.v[j] + o.w[j] * o.w[j])
        out[PROBE_COLUMN + n_p + k] = o.v[j]
        out[PROBE_COLUMN + 2 * n_p + k] = o.w[j]
    return count


def observe_row(d, o, t, y, rate, out):
    """:func:`observe_kernel` called from Python: ``rate`` (scratch, like ``y``) filled with dy/dt first where
    the observation reads it (:func:`observes_rate`). The compiled loop does the same in its own code."""
    if observes_rate.py_func(d):
        _rhs_kernel(d, t, y, rate)
    return observe_kernel(d, o, t, y, rate, out)


@njit(cache=True)
def accepted_step_kernel(d, o, t_old, h, y_old, k_old, dense, y):
    """What the model does after each accepted step ``[t_old, t_old + h]`` of the integrator (never after a
    rejected one): count the impacts at the new state ``y`` (:func:`impacts_kernel`, returned) and, for a
    delayed bit–rock law, record the bit's position by angle over the step
    (:func:`~drillstring.dynamics.delay.record_bottom`) from the step's continuous extension: the stages
    ``k_old`` (s, len(y)) and the tableau's ``dense`` (s, p) coefficients, ``y(t_old + σh) = y_old +
    h Σ_i Σ_p dense[i, p] σ^(p+1) k_i``."""
    if _delayed(d):
        ranges = d.ranges
        a0, a1 = ranges.axial_start, ranges.axial_end
        bit = d.phi_tx_t.shape[1] - 1
        order = dense.shape[1]
        angle_coef = o.dense[0, :order]
        position_coef = o.dense[1, :order]
        angle_coef[:] = 0.0
        position_coef[:] = 0.0
        for i in range(k_old.shape[0]):
            rate = 0.0  # the bit's axial velocity at stage i (k holds dη/dt = η̇ first)
            for j in range(a0, a1):
                rate += d.axial_rows[_AXIAL_BIT, j - a0] * k_old[i, j]
            spin, _ = station_spin(d, 0.0, k_old[i], bit, 0.0)  # the frame's map of the stage's dη/dt: the
            # bit's spin relative to the frame's rotation Ω, added once below
            for p in range(order):
                position_coef[p] += h * dense[i, p] * rate
                angle_coef[p] += h * dense[i, p] * spin
        angle_coef[0] += frame_speed(d) * h
        position, angle, _, _ = _bit_state(d, t_old, y_old)
        record_bottom(view(d.laws[int(d.laws[HISTORY]):]), angle, angle_coef, position, position_coef)
    return impacts_kernel(d, o, y)
