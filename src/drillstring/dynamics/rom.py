"""The reduced-order model (ROM) of the drill-string and its right-hand side (docs/model.md §5–§9).

The response about the prestressed static state, ``q = q_S + q̄``, is projected on mass-normalised
normal modes of the prestressed linear system (:mod:`drillstring.modal`):
``q̄ = Φ η``, ``Φᵀ (M + M_f) Φ = I``, ``Φᵀ (K + K_g + K_f) Φ = diag(ω²)``. The basis holds the rigid
axial translation, ``n_a`` elastic axial modes, ``n_t`` torsional modes (top fixed) and ``n_l``
lateral modes in each plane. The reduced equations are

    η̈ + (D + Φᵀ C_f Φ) η̇ + diag(ω²) η = Φᵀ (f_NL(q, q̇) + wob e_bit,u) + g

where ``D`` is the structural damping and ``g`` the constant generalised force of the damping of the
imposed top rotation (:mod:`drillstring.damping`: by default ξ, c1 and c2 defined on the free–free
modes, giving a dense torsional block; or ``2 ξ ω_i`` on every basis mode;
:attr:`ReducedOrderModel.generalized_force`, zero when not given), ``C_f`` the fluid (Coriolis + viscous)
damping, and ``wob e_bit,u`` removes the static bit reaction that ``q_S`` already balances (the hook force
stays equal to the static weight-on-hook, docs/model.md §6). The top rotation is imposed:
``θx(x, t) = Ω t + (Φ η)_θx``, so the total spin speed is ``Ω + (Φ η̇)_θx``; or, with a top drive
(:mod:`drillstring.forces.top_drive`), the torsional family is free at the top (rigid rotation first, the
top drive's inertia lumped at the top node), ``θx = (Φ η)_θx`` carries the whole spin, the motor torque
``τ_m`` adds ``φ_top τ_m`` to the torsional equations and the controller's states follow the modal
coordinates in the state vector ``[η, η̇, s]``. ``bit_rock.law = "off_bottom"`` removes the bit–rock force.
A downhole motor (:mod:`drillstring.forces.motor`) releases the rotation at its rotor station
(:mod:`drillstring.rotor`: the torsional basis is that of the released string) and adds its torque ``T(ω_m)``
along the rotor's relative row ``φ_r − φ_k``, ``ω_m = (φ_r − φ_k)ᵀ η̇``.

``f_NL`` (case 2, ``nonlinear = "bit_and_contact"``) is the Tucker–Wang bit–rock force and torque at
the bit node, the borehole shocks and rubbing at the contact stations
(:class:`~drillstring.forces.contact.ContactStations`: the wall is a distributed stiffness ``k'_sh``
[N/m per m of string], lumped by nodal quadrature, so the contact law does not change with the mesh)
and the loads that turn with the string (mass imbalance, stress-free bow:
:mod:`drillstring.forces.excitation`), evaluated in physical DOFs and projected. The turning loads
follow the local rotation ``Ω t + (Φ η)_θx``, so the right-hand side depends on ``t``.

The right-hand side is a Numba-compiled kernel over preallocated arrays; every compiled kernel takes
one structured argument (:class:`RhsData`, :class:`FullModelData`, :class:`ObserveData`, named tuples
built once by :class:`ReducedOrderModel`), and :func:`evaluate_rhs` picks the case-1 or case-2 kernel by
the type of that argument when it is compiled.

**The model's interface to the compiled step loop** (:mod:`drillstring.dynamics.compiled`, which names
nothing else of this module): the run's :class:`KernelData` (:meth:`ReducedOrderModel.kernel_data`: the
model's data ``rhs_data``, ``case2_data``, read only, with the run's own scratch and bit history) and four
public functions of them — :func:`evaluate_rhs` (dy/dt), :func:`observe_kernel` (one observation row),
:func:`impacts_kernel` (impacts at an accepted step) and :func:`observation_width` (the row's columns).
The components are called inside these kernels, so the loop never names a law: every kind the registry
dispatches through its compiled dispatch (:mod:`drillstring.forces.registry`, their numbers in
``RhsData.laws``); the turning loads of every registered source through their one shared kernel
(:mod:`drillstring.forces.turning_loads`).

Impacts: a *contact zone* is a run of consecutive nodes in contact; an impact is a zone that appears
with no node in contact within one node of it at the previous accepted step
(:func:`new_contact_zones`). Counted zone by zone, not node by node, the number of impacts does not
grow as the mesh is refined.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np
from numba import njit, types
from numba.extending import overload

from drillstring.damping import reduced_structural_damping
from drillstring.fem.dofs import THETA_X, THETA_Y, THETA_Z, U, V, W, dof
from drillstring.dynamics.kernel_data import (  # the kernels' data, by name
    _DENSE_ORDER_MAX,
    AXIAL_ROW,
    AXIAL_ROWS,
    TORSION_ROW,
    TORSION_ROWS,
    ContactData,
    ContactWork,
    DelayedRhsData,
    FullModelData,
    KernelData,
    ModalRanges,
    ObserveData,
    RhsData,
)
from drillstring.dynamics.delay import allocate_storage, delayed_difference, record_bottom, view
from drillstring.dynamics.delay import start as start_history
from drillstring.forces.bit_rock import case_bit_rock
from drillstring.forces.contact import (
    ContactStations,
    case_contact,
    mesh_contact_stations,
)
from drillstring.forces.excitation import TurningLoads
from drillstring.forces.nonlinear import (
    NonlinearElements,
    _kinetic_forces_kernel,
    _strain_energy_forces_kernel,
    modal_mass_coupling,
    nonlinear_elements,
)
from drillstring.forces.hook_load import OnBottomStart
from drillstring.forces.motor import case_motor
from drillstring.forces.registry import (
    HISTORY,
    MOTOR_CODE,
    TOP_BOUNDARY_CODE,
    TOP_INERTIA,
    BitContext,
    BitLaw,
    ContactContext,
    ContactLaw,
    HookContext,
    HookLoad,
    TopBoundary,
    TopContext,
    bit_law_force,
    Motor,
    compiled,
    contact_law_forces,
    hook_load as registered_hook_load,
    hook_load_force,
    MotorContext,
    motor_torque,
    pack,
    top_boundary_torque,
)
from drillstring.forces.top_drive import TopDriveParameters, case_top_drive
from drillstring.forces.turning_loads import case_turning_loads, turning_load, turning_load_data
from drillstring.modal import (
    LinearSystem,
    ModeFamily,
    Modes,
    case_linear_system,
    compute_modes,
    coupled_modes,
    family_coupling,
    family_dofs,
    family_modes,
)
from drillstring.rotor import RotorRelease, first_torsional_frequency, released_modes
from drillstring.statics import StaticState, case_static_state

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


# the mode-shape rows the kernels read, by name (kernel_data.AXIAL_ROWS, TORSION_ROWS)
_AXIAL_BIT, _AXIAL_TOP = AXIAL_ROW["bit"], AXIAL_ROW["top"]
_TORSION_BIT, _TORSION_QUILL = TORSION_ROW["bit"], TORSION_ROW["quill"]
_TORSION_SURFACE_TORQUE, _TORSION_MOTOR = TORSION_ROW["surface_torque"], TORSION_ROW["motor"]

#: Let Numba reassociate sums (SIMD dot products) but keep IEEE NaN/inf semantics, so divergence
#: is still detected. Deterministic for a given build: same results for any worker count.
VECTOR_MATH = {"reassoc", "contract"}


def inner_kernel(**options):
    """``njit(cache=True)`` for a kernel called only from other compiled kernels: no CPython wrapper is
    generated for it (each wrapper unpacks the large structured arguments and cost about 0.15 s of the
    first compilation; 1.6 s in all). Such a kernel cannot be called from Python."""
    return njit(cache=True, no_cpython_wrapper=True, **options)




# ---------------------------------------------------------------------------------------------------------
# Kernels
# ---------------------------------------------------------------------------------------------------------


@inner_kernel(fastmath=VECTOR_MATH)
def _matvec(matrix, vector, offset, out):
    """out = matrix @ vector[offset:offset + matrix.shape[1]] with compiled loops (no BLAS, so no
    thread oversubscription when several worker processes run)."""
    for i in range(matrix.shape[0]):
        total = 0.0
        for j in range(matrix.shape[1]):
            total += matrix[i, j] * vector[offset + j]
        out[i] = total


def diagonal_blocks(matrix: np.ndarray) -> np.ndarray:
    """The finest contiguous diagonal blocks ``[start, end)`` of a square matrix outside which every
    entry is exactly 0, as a (k, 2) int64 array (all-zero blocks left out). The ROM's damping is block
    diagonal by mode family (the families are uncoupled in the linear model)."""
    nonzero = matrix != 0.0
    n = matrix.shape[0]
    reach = np.arange(n)
    for i in range(n):
        linked = np.nonzero(nonzero[i] | nonzero[:, i])[0]
        if linked.size:
            reach[i] = max(i, int(linked.max()))
    blocks, start, end = [], 0, 0
    for i in range(n):
        end = max(end, reach[i] + 1)
        if i + 1 == end:
            if nonzero[start:end, start:end].any():
                blocks.append((start, end))
            start = end
    return np.array(blocks, dtype=np.int64).reshape(-1, 2)


@inner_kernel()
def _block_damping(damping_t, blocks, velocity, out):
    """out −= D velocity, D block diagonal (``blocks`` from :func:`diagonal_blocks`, ``damping_t`` = Dᵀ)."""
    for b in range(blocks.shape[0]):
        start, end = blocks[b, 0], blocks[b, 1]
        for j in range(start, end):
            x = velocity[j]
            if x != 0.0:
                for i in range(start, end):
                    out[i] -= damping_t[j, i] * x


@inner_kernel()
def _columns_matvec(matrix_t, vector, offset, out, sign):
    """out (+)= sign · matrix @ vector[offset:] given ``matrix_t`` = matrixᵀ (C order): column by
    column, so the inner loop is contiguous and vectorises without reassociating sums."""
    for j in range(matrix_t.shape[0]):
        x = sign * vector[offset + j]
        if x != 0.0:
            for i in range(matrix_t.shape[1]):
                out[i] += matrix_t[j, i] * x


@inner_kernel()
def _bit_state(d, t, y):
    """Axial position u [m] (from the static state, down), angle θ [rad], axial velocity u̇ [m/s] and spin
    speed ω [rad/s] of the bit at time ``t`` [s] for the state ``y`` = [η, η̇]."""
    n = d.omega2.shape[0]
    ranges = d.ranges
    a0, a1, t0, t1 = ranges.axial_start, ranges.axial_end, ranges.torsion_start, ranges.torsion_end
    position = 0.0
    velocity = 0.0
    for j in range(a0, a1):
        position += d.axial_rows[_AXIAL_BIT, j - a0] * y[j]
        velocity += d.axial_rows[_AXIAL_BIT, j - a0] * y[n + j]
    angle = d.top_speed * t
    speed = d.top_speed
    for j in range(t0, t1):
        angle += d.torsion_rows[_TORSION_BIT, j - t0] * y[j]
        speed += d.torsion_rows[_TORSION_BIT, j - t0] * y[n + j]
    return position, angle, velocity, speed


@inner_kernel()
def _bit_rock(d, t, y):
    """The bit–rock law at the bit (the registered law of the model, :func:`~drillstring.forces.registry.
    bit_law_force`, reading the named context :class:`~drillstring.forces.registry.BitContext`): ``(axial force
    [N], torque [N·m], depth of cut per blade [m], bit position u [m], axial velocity [m/s], spin speed
    [rad/s])``. A delayed law's depth of cut is ``u(t)`` minus the hole bottom one blade sector behind
    (:func:`~drillstring.dynamics.delay.delayed_difference`); the other laws read none (0)."""
    position, angle, velocity, speed = _bit_state(d, t, y)
    depth = _depth_of_cut(d, position, angle)
    force, torque = bit_law_force(d.laws, BitContext(t, position, angle, velocity, speed, depth, d.weight_on_bit))
    return force, torque, depth, position, velocity, speed


def _depth_of_cut(d, position, angle):
    """The depth of cut per blade [m] of the bit at ``position`` u [m] and ``angle`` θ [rad]: ``u`` minus the
    hole bottom one blade sector behind (:func:`~drillstring.dynamics.delay.delayed_difference`) for
    :class:`DelayedRhsData`, 0 for :class:`RhsData` (resolved by type when compiled)."""
    raise NotImplementedError("compiled code only")


@overload(_depth_of_cut)
def _depth_of_cut_compiled(d, position, angle):
    if _is(d, DelayedRhsData):
        return lambda d, position, angle: delayed_difference(view(d.laws[int(d.laws[HISTORY]):]), angle, position)
    return lambda d, position, angle: 0.0


def _delayed(d):
    """True for :class:`DelayedRhsData` (a law that reads the bit's history), resolved when compiled."""
    raise NotImplementedError("compiled code only")


@overload(_delayed)
def _delayed_compiled(d):
    delayed = _is(d, DelayedRhsData)
    return lambda d: delayed


@inner_kernel()
def _lateral_displacements(d, y, v, w):
    """v and w [m] at every node for the state ``y``."""
    v[:] = 0.0
    w[:] = 0.0
    _columns_matvec(d.phi_v_t, y, d.ranges.lateral_y_start, v, 1.0)
    _columns_matvec(d.phi_w_t, y, d.ranges.lateral_z_start, w, 1.0)


@njit(cache=True)
def _surely_clear(d, eta):
    """True when no node can touch the borehole: r_i ≤ |v_i| + |w_i| ≤ Σ_j (max_i |φ_ij|) |η_j| over
    both lateral families (triangle inequality) is below the smallest gap. Costs one pass over the
    lateral coordinates instead of the mode shapes at every node."""
    bound = 0.0
    ranges = d.ranges
    for j in range(ranges.lateral_y_start, ranges.lateral_y_end):
        bound += d.lateral_shape_max[j - ranges.lateral_y_start] * abs(eta[j])
    offset = ranges.lateral_y_end - ranges.lateral_y_start
    for j in range(ranges.lateral_z_start, ranges.lateral_z_end):
        bound += d.lateral_shape_max[offset + j - ranges.lateral_z_start] * abs(eta[j])
    return bound < d.smallest_gap


@inner_kernel()
def _turning_loads(d, t, y, acc):
    """Add the projected loads that turn with the string (:class:`~drillstring.forces.turning_loads.TurningLoadData`)
    to ``acc``, each at the angle and spin speed of its node."""
    r = d.turning
    n = d.omega2.shape[0]
    ranges = d.ranges
    t0, t1, y0, y1, z0, z1 = (ranges.torsion_start, ranges.torsion_end, ranges.lateral_y_start, ranges.lateral_y_end,
                              ranges.lateral_z_start, ranges.lateral_z_end)
    for k in range(r.node.shape[0]):
        i = r.node[k]
        angle = d.top_speed * t + r.phase[k]
        speed = d.top_speed
        for j in range(t0, t1):
            angle += d.phi_tx_t[j - t0, i] * y[j]
            speed += d.phi_tx_t[j - t0, i] * y[n + j]
        turning_load(r, k, angle, speed, acc, y0, y1, z0, z1)


@inner_kernel()
def _top_motion(d, y):
    """Quill speed θ̇₀ [rad/s] and surface torque T_s [N·m] for the state ``y``."""
    n = d.omega2.shape[0]
    t0, t1 = d.ranges.torsion_start, d.ranges.torsion_end
    quill = d.top_speed
    torque = 0.0
    for j in range(t0, t1):
        quill += d.torsion_rows[_TORSION_QUILL, j - t0] * y[n + j]
        torque += d.torsion_rows[_TORSION_SURFACE_TORQUE, j - t0] * y[j]
    return quill, torque


@inner_kernel()
def _top_drive(d, t, y, out):
    """The top boundary's motor torque on the torsional modes; its kernel (the registered boundary,
    :func:`~drillstring.forces.registry.top_boundary_torque`, reading the named context
    :class:`~drillstring.forces.registry.TopContext`) reads its states in ``y`` and writes their rates in
    ``out`` where the registry put them."""
    n = d.omega2.shape[0]
    t0, t1 = d.ranges.torsion_start, d.ranges.torsion_end
    quill, surface = _top_motion(d, y)
    torque = top_boundary_torque(d.laws, TopContext(t, quill, surface), y, out)
    for j in range(t0, t1):
        out[n + j] += d.torsion_rows[_TORSION_QUILL, j - t0] * torque


@inner_kernel()
def _motor_speed(d, y):
    """A downhole motor's rotor speed relative to its stator ω_m [rad/s] (the torsional row
    :attr:`RotorRelease.relative`) for the state ``y``."""
    n = d.omega2.shape[0]
    t0, t1 = d.ranges.torsion_start, d.ranges.torsion_end
    speed = 0.0
    for j in range(t0, t1):
        speed += d.torsion_rows[_TORSION_MOTOR, j - t0] * y[n + j]
    return speed


@inner_kernel()
def _downhole_motor(d, t, y, out):
    """A downhole motor's ω_m [rad/s] (:func:`_motor_speed`) and its torque [N·m] (the registered motor,
    :func:`~drillstring.forces.registry.motor_torque`), for the state ``y`` at time ``t`` [s]; the motor reads
    its states in ``y`` and writes their rates in ``out`` where the registry put them."""
    speed = _motor_speed(d, y)
    return speed, motor_torque(d.laws, MotorContext(t, speed), y, out)


@njit(cache=True)
def _rhs_kernel(d, t, y, out):
    """dy/dt of the case-2 ROM (module docstring) at time ``t`` [s] from :class:`RhsData` ``d``; contact
    work is done only at the stations that touch the borehole."""
    n = d.omega2.shape[0]
    ranges = d.ranges
    a0, a1, t0, t1, y0, y1, z0, z1 = (ranges.axial_start, ranges.axial_end, ranges.torsion_start, ranges.torsion_end,
                                      ranges.lateral_y_start, ranges.lateral_y_end, ranges.lateral_z_start,
                                      ranges.lateral_z_end)
    eta = y[:n]
    eta_dot = y[n:]
    acc = out[n:]
    # linear part: -D η̇ - ω² η + the constant generalized force (D dense only where the fluid couples)
    for i in range(n):
        out[i] = eta_dot[i]
        acc[i] = d.generalized_force[i] - d.omega2[i] * eta[i]
    _block_damping(d.damping_t, d.damping_blocks, eta_dot, acc)
    if d.laws[TOP_BOUNDARY_CODE] != 0.0:
        _top_drive(d, t, y, out)
    if d.laws[MOTOR_CODE] != 0.0:  # a downhole motor: +T on the rotor side, -T on the stator side
        _, motor = _downhole_motor(d, t, y, out)
        for j in range(t0, t1):
            acc[j] += d.torsion_rows[_TORSION_MOTOR, j - t0] * motor
    # bit-rock interaction at the bit node; the hook's extra pull at the top during a ramped start
    axial_force, bit_torque, _, _, _, _ = _bit_rock(d, t, y)
    axial_force += d.weight_on_bit
    hook = hook_load_force(d.laws, HookContext(t, d.weight_on_bit))
    for j in range(a0, a1):
        acc[j] += d.axial_rows[_AXIAL_BIT, j - a0] * axial_force + d.axial_rows[_AXIAL_TOP, j - a0] * hook
    for j in range(t0, t1):
        acc[j] += d.torsion_rows[_TORSION_BIT, j - t0] * bit_torque
    if y1 == y0 and z1 == z0:
        return
    _turning_loads(d, t, y, acc)
    # shocks and rubbing: find the stations outside the gap (none when a bound says no node can touch)
    if _surely_clear(d, eta):
        return
    c = d.contact
    cw = c.work
    _lateral_displacements(d, eta, cw.v, cw.w)
    n_c = 0
    for k in range(c.node.shape[0]):
        i = c.node[k]
        if cw.v[i] * cw.v[i] + cw.w[i] * cw.w[i] > c.gap[k] * c.gap[k]:
            cw.stations[n_c] = k
            n_c += 1
    if n_c == 0:
        return
    for m in range(n_c):
        k = cw.stations[m]
        i = c.node[k]
        cw.v_c[m] = cw.v[i]
        cw.w_c[m] = cw.w[i]
        cw.gap[m] = c.gap[k]
        cw.outer_diameter[m] = c.outer_diameter[k]
        cw.stiffness[m] = c.stiffness[k]
        spin = d.top_speed
        for j in range(t0, t1):
            spin += d.phi_tx_t[j - t0, i] * eta_dot[j]
        cw.spin[m] = spin
        vd = 0.0
        wd = 0.0
        if c.tangential:
            for j in range(y0, y1):
                vd += d.phi_v_t[j - y0, i] * eta_dot[j]
            for j in range(z0, z1):
                wd += d.phi_w_t[j - z0, i] * eta_dot[j]
        cw.v_dot[m] = vd
        cw.w_dot[m] = wd
    contact_law_forces(d.laws, ContactContext(cw.v_c[:n_c], cw.w_c[:n_c], cw.v_dot[:n_c], cw.w_dot[:n_c],
                                              cw.spin[:n_c], cw.gap[:n_c], cw.outer_diameter[:n_c],
                                              cw.stiffness[:n_c]),
                       cw.force_v[:n_c], cw.force_w[:n_c], cw.torque[:n_c])
    for m in range(n_c):
        i = c.node[cw.stations[m]]
        fv = cw.force_v[m]
        fw = cw.force_w[m]
        tq = cw.torque[m]
        for j in range(y0, y1):
            acc[j] += d.phi_v_t[j - y0, i] * fv
        for j in range(z0, z1):
            acc[j] += d.phi_w_t[j - z0, i] * fw
        for j in range(t0, t1):
            acc[j] += d.phi_tx_t[j - t0, i] * tq


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
    quill, elastic = _top_motion(d, y)
    states_rate = np.empty(y.shape[0])  # the boundary writes its states' rates: not needed here
    torque = top_boundary_torque(d.laws, TopContext(t, quill, elastic), y, states_rate)
    acceleration = 0.0
    for j in range(t0, t1):
        acceleration += d.torsion_rows[_TORSION_QUILL, j - t0] * rate[n + j]
    return torque - d.laws[TOP_INERTIA] * acceleration


@inner_kernel()
def _expand(shapes_t, dofs, y, offset, out):
    """out[dofs] += shapesᵀ-columns · y[offset:offset + n_f] (one family's part of Φη)."""
    for j in range(shapes_t.shape[0]):
        x = y[offset + j]
        if x != 0.0:
            for i in range(dofs.shape[0]):
                out[dofs[i]] += shapes_t[j, i] * x


@inner_kernel()
def _project(shapes_t, dofs, force, offset, out):
    """out[offset + j] = Σ_i shapes_t[j, i] force[dofs[i]] (one family's part of Φᵀ f)."""
    for j in range(shapes_t.shape[0]):
        total = 0.0
        for i in range(dofs.shape[0]):
            total += shapes_t[j, i] * force[dofs[i]]
        out[offset + j] = total


@njit(cache=True)
def _cholesky_solve(a, b, x):
    """x = a⁻¹ b for a symmetric positive definite ``a`` (n, n), by Cholesky ``a = L Lᵀ`` computed in the
    lower triangle of ``a`` (overwritten); ``x`` may be ``b`` itself. The case-1 mass ``I + Φᵀ M_nl Φ`` (here
    its Schur complement ``I − B Bᵀ``) is positive definite wherever the model holds
    (:mod:`drillstring.forces.nonlinear`); elsewhere (a non-positive pivot) ``x`` is NaN, which the
    integrator treats as a rejected step. Compiled loops instead of ``np.linalg.solve``: no
    allocation per call, and a fraction of the latter's compile time."""
    n = a.shape[0]
    for j in range(n):
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k]
        if not d > 0.0:
            x[:] = np.nan
            return
        d = np.sqrt(d)
        a[j, j] = d
        for i in range(j + 1, n):
            s = a[i, j]
            for k in range(j):
                s -= a[i, k] * a[j, k]
            a[i, j] = s / d
    for i in range(n):  # L z = b
        s = b[i]
        for k in range(i):
            s -= a[i, k] * x[k]
        x[i] = s / a[i, i]
    for i in range(n - 1, -1, -1):  # Lᵀ x = z
        s = x[i]
        for k in range(i + 1, n):
            s -= a[k, i] * x[k]
        x[i] = s / a[i, i]


@njit(cache=True)
def _rhs_full_kernel(f, t, y, out):
    """Case 1 from :class:`FullModelData` ``f``: the case-2 right-hand side plus the strain- and
    kinetic-energy forces f_se and f_ke (:mod:`drillstring.forces.nonlinear`), evaluated on the physical
    state ``q̄ = Φη``, ``q̇ = Φη̇ + Ω`` (θx DOFs), projected on the basis. ``f_ke = f_vel − M_nl(q) q̈``:
    the configuration-dependent mass correction is moved to the left-hand side and
    ``(I + Φᵀ M_nl(Φη) Φ) η̈ = r`` is solved at every evaluation (exact, no lagged accelerations). Its only
    off-diagonal blocks are ``B`` (torsion × lateral y) and ``Bᵀ``: ``(I − B Bᵀ) a_t = r_t − B r_y``,
    ``a_y = r_y − Bᵀ a_t``, the other accelerations are ``r``."""
    _rhs_kernel(f.rhs, t, y, out)
    d = f.rhs
    n = d.omega2.shape[0]
    ranges = d.ranges
    a0, t0, t1, y0, y1, z0, z1 = (ranges.axial_start, ranges.torsion_start, ranges.torsion_end,
                                  ranges.lateral_y_start, ranges.lateral_y_end, ranges.lateral_z_start,
                                  ranges.lateral_z_end)
    f.q[:] = 0.0
    f.qd[:] = 0.0
    for shapes_t, dofs, offset in ((f.axial_shapes_t, f.axial_dofs, a0), (f.torsion_shapes_t, f.torsion_dofs, t0),
                                   (f.bending_y_shapes_t, f.bending_y_dofs, y0),
                                   (f.bending_z_shapes_t, f.bending_z_dofs, z0)):
        _expand(shapes_t, dofs, y, offset, f.q)
        _expand(shapes_t, dofs, y, n + offset, f.qd)
    for i in range(f.theta_x_dofs.shape[0]):
        f.qd[f.theta_x_dofs[i]] += d.top_speed
    _strain_energy_forces_kernel(f.q, f.inv_length, f.weights, f.slope, f.axial_stiffness, f.f_se)
    _kinetic_forces_kernel(f.q, f.qd, f.xi, f.weights, f.rotation, f.polar_inertia, f.f_vel, f.coupling)
    for i in range(f.f_se.shape[0]):
        f.f_se[i] += f.f_vel[i]
    acc = f.acceleration
    acc[:] = 0.0
    for shapes_t, dofs, offset in ((f.axial_shapes_t, f.axial_dofs, a0), (f.torsion_shapes_t, f.torsion_dofs, t0),
                                   (f.bending_y_shapes_t, f.bending_y_dofs, y0),
                                   (f.bending_z_shapes_t, f.bending_z_dofs, z0)):
        _project(shapes_t, dofs, f.f_se, offset, acc)
    for i in range(n):
        out[n + i] += acc[i]
    n_t = t1 - t0
    n_y = y1 - y0
    if n_t == 0 or n_y == 0 or z1 == z0:
        return
    # B(η) = Σ_k η_z,k T_k
    b = f.block
    b[:, :] = 0.0
    for k in range(z1 - z0):
        eta = y[z0 + k]
        if eta != 0.0:
            for i in range(n_t):
                for j in range(n_y):
                    b[i, j] += eta * f.coupling_tensor[k, i, j]
    r = out[n:]
    rt = f.torsion_rhs
    for i in range(n_t):
        v = r[t0 + i]
        for j in range(n_y):
            v -= b[i, j] * r[y0 + j]
        rt[i] = v
        for k in range(n_t):
            total = 0.0
            for j in range(n_y):
                total += b[i, j] * b[k, j]
            f.schur[i, k] = (1.0 if i == k else 0.0) - total
    _cholesky_solve(f.schur, rt, rt)
    for j in range(n_y):
        v = r[y0 + j]
        for i in range(n_t):
            v -= b[i, j] * rt[i]
        r[y0 + j] = v
    for i in range(n_t):
        r[t0 + i] = rt[i]


def evaluate_rhs(data, t, y, out):
    """dy/dt of the ROM at time ``t`` [s] for the state ``y`` written into ``out``: case 2 for
    :class:`RhsData`, case 1 for :class:`FullModelData`. Callable from Python and from compiled code,
    where it is resolved by the type of ``data`` at compile time, so a case-2 run never compiles the
    case-1 kernel."""
    if isinstance(data, FullModelData):
        _rhs_full_kernel(data, t, y, out)
    else:
        _rhs_kernel(data, t, y, out)


def _is(numba_type, cls) -> bool:
    return isinstance(numba_type, types.BaseNamedTuple) and numba_type.instance_class is cls


@overload(evaluate_rhs)
def _evaluate_rhs_compiled(data, t, y, out):
    if _is(data, FullModelData):
        return lambda data, t, y, out: _rhs_full_kernel(data, t, y, out)
    if _is(data, RhsData) or _is(data, DelayedRhsData):
        return lambda data, t, y, out: _rhs_kernel(data, t, y, out)
    return None


#: Relative step of the central differences of the bit law in :func:`stiff_part` [-], and the floors of the
#: differenced quantities' scales: axial velocity [m/s], bit speed [rad/s], bit position [m].
BIT_LAW_STEP = 1e-6
BIT_LAW_SCALES = (1e-3, 1.0, 1e-3)


@inner_kernel()
def _stiff_bit_law(d, t, y, shapes, partials):
    """:func:`stiff_part` for case-2 data ``d``."""
    n = d.omega2.shape[0]
    ranges = d.ranges
    a0, a1, t0, t1 = ranges.axial_start, ranges.axial_end, ranges.torsion_start, ranges.torsion_end
    for j in range(n):
        shapes[0, j] = 0.0
        shapes[1, j] = 0.0
    for j in range(a0, a1):
        shapes[0, j] = d.axial_rows[_AXIAL_BIT, j - a0]
    for j in range(t0, t1):
        shapes[1, j] = d.torsion_rows[_TORSION_BIT, j - t0]
    position, angle, velocity, speed = _bit_state(d, t, y)
    depth = _depth_of_cut(d, position, angle)
    moves_depth = 1.0 if _delayed(d) else 0.0
    values = (velocity, speed, position)
    for k in range(3):
        step = BIT_LAW_STEP * max(abs(values[k]), BIT_LAW_SCALES[k])
        force_sum = 0.0
        torque_sum = 0.0
        for sign in (1.0, -1.0):
            dv = sign * step if k == 0 else 0.0
            dw = sign * step if k == 1 else 0.0
            du = sign * step if k == 2 else 0.0
            force, torque = bit_law_force(d.laws, BitContext(t, position + du, angle, velocity + dv, speed + dw,
                                                             depth + moves_depth * du, d.weight_on_bit))
            force_sum += sign * force
            torque_sum += sign * torque
        partials[0, k] = force_sum / (2.0 * step)
        partials[1, k] = torque_sum / (2.0 * step)
    if shapes.shape[0] > 2:  # a third row: the downhole motor's (zero without one)
        for j in range(n):
            shapes[2, j] = 0.0
        for k in range(partials.shape[1]):
            partials[2, k] = 0.0
        if d.laws[MOTOR_CODE] != 0.0:
            for j in range(t0, t1):
                shapes[2, j] = d.torsion_rows[_TORSION_MOTOR, j - t0]
            relative_speed = _motor_speed(d, y)
            step = BIT_LAW_STEP * max(abs(relative_speed), BIT_LAW_SCALES[1])
            rates = np.empty(y.shape[0])  # the motor writes its states' rates: not needed here
            partials[2, 0] = (motor_torque(d.laws, MotorContext(t, relative_speed + step), y, rates)
                              - motor_torque(d.laws, MotorContext(t, relative_speed - step), y, rates)) / (2.0 * step)
    return d.omega2, d.damping_t, d.damping_blocks


def stiff_part(data, t, y, shapes, partials):
    """The model's stiff part, for an implicit step (:mod:`drillstring.dynamics.steps.imex_ark`), at time ``t``
    [s] and state ``y``: writes the bit's axial and torsional mode-shape rows (u and θx at the bit over the n
    modal coordinates, zero outside their families) into ``shapes[0, :n]``, ``shapes[1, :n]``, and into
    ``partials`` (2, 3) the partial derivatives of the bit law's (axial force [N], torque [N·m]) in the bit's
    (axial velocity u̇ [m/s], speed θ̇ [rad/s], position u [m]; the position moves a delayed law's depth of
    cut with it), by central differences of the registered compiled law (six scalar evaluations of
    :func:`~drillstring.forces.registry.bit_law_force`). The
    bit law's part of ``∂(η̈)/∂(η, η̇)`` is then ``Bᵀ P[:, 2] b_uᵀ`` and ``Bᵀ P[:, :2] B`` (``B = shapes``,
    ``P = partials``): the NumPy reference is :func:`drillstring.dynamics.stiffness._bit_rock_rows`. When
    ``shapes`` and ``partials`` have a third row, it gets a downhole motor's: the rotor's relative torsional row
    (:attr:`ReducedOrderModel.motor_shapes`) in ``shapes[2, :n]`` and ``dT/dω_m`` [N·m·s/rad] of the registered
    compiled motor by a central difference in ``partials[2, 0]`` (its part of ``∂(η̈)/∂η̇`` is
    ``m (dT/dω_m) mᵀ``; zeros without a motor). Returns the linear part's ``(ω², Dᵀ, damping blocks)``.
    Compiled code only; case 1 (:class:`FullModelData`) reads its case-2 part."""
    raise NotImplementedError("compiled code only")


@overload(stiff_part)
def _stiff_part_compiled(data, t, y, shapes, partials):
    if _is(data, FullModelData):
        return lambda data, t, y, shapes, partials: _stiff_bit_law(data.rhs, t, y, shapes, partials)
    if _is(data, RhsData) or _is(data, DelayedRhsData):
        return lambda data, t, y, shapes, partials: _stiff_bit_law(data, t, y, shapes, partials)
    return None


@inner_kernel()
def _contact_state(d, y, v, w, in_contact):
    """Fill ``v``, ``w`` (every node) and ``in_contact`` (nodes with a station outside its gap) for the
    state ``y``; returns the total normal force of the wall Σ k_i (r_i − g_i)₊ [N]."""
    _lateral_displacements(d, y, v, w)
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
    the nodes in contact in ``o.previous`` for the next call."""
    ranges = d.ranges
    if ranges.lateral_y_end == ranges.lateral_y_start and ranges.lateral_z_end == ranges.lateral_z_start:
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
    ``(t, y)`` (:func:`_rhs_kernel`), which the surface torque reads; not read otherwise. The caller evaluates
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
    out[_QUILL_SPEED], out[_SURFACE_TORQUE] = _top_motion(d, y)
    if observes_rate(d):  # a driving boundary: the torque from the quill's equation of motion
        out[_SURFACE_TORQUE] = _surface_torque(d, t, y, rate)
    out[_MOTOR_SPEED] = 0.0
    out[_MOTOR_TORQUE] = 0.0
    if d.laws[MOTOR_CODE] != 0.0:
        out[_MOTOR_SPEED], out[_MOTOR_TORQUE] = _downhole_motor(d, t, y, np.empty(y.shape[0]))
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
        a0, a1, t0, t1 = ranges.axial_start, ranges.axial_end, ranges.torsion_start, ranges.torsion_end
        order = dense.shape[1]
        angle_coef = o.dense[0, :order]
        position_coef = o.dense[1, :order]
        angle_coef[:] = 0.0
        position_coef[:] = 0.0
        for i in range(k_old.shape[0]):
            rate = 0.0  # the bit's axial velocity at stage i (k holds dη/dt = η̇ first)
            for j in range(a0, a1):
                rate += d.axial_rows[_AXIAL_BIT, j - a0] * k_old[i, j]
            spin = 0.0
            for j in range(t0, t1):
                spin += d.torsion_rows[_TORSION_BIT, j - t0] * k_old[i, j]
            for p in range(order):
                position_coef[p] += h * dense[i, p] * rate
                angle_coef[p] += h * dense[i, p] * spin
        angle_coef[0] += d.top_speed * h
        position, angle, _, _ = _bit_state(d, t_old, y_old)
        record_bottom(view(d.laws[int(d.laws[HISTORY]):]), angle, angle_coef, position, position_coef)
    return impacts_kernel(d, o, y)


@dataclass
class ReducedOrderModel:
    """Modal model of one drilling configuration (SI units).

    Attributes:
        angular_frequencies: ω of each basis vector [rad/s] (0 for the rigid axial mode).
        damping: reduced damping matrix (modal + rigid + fluid) [1/s].
        basis: Φ, (n_dofs, n) global mode shapes.
        family: family label of each basis vector.
        probe_positions: x of the radial-displacement probes [m].
        contact: the contact law; its ``shock_stiffness`` is read as the wall's distributed stiffness
            k'_sh [N/m per m of string], acting on ``stations`` with ``k_i = k'_sh ℓ_i``.
        stations: where the wall acts (:class:`~drillstring.forces.contact.ContactStations`).
        generalized_force: (n,) constant generalized force added to the modal acceleration
            [N/√kg per unit modal mass, i.e. the right-hand side of η̈ = …]; ``None`` means zeros.
        turning_loads: loads turning with the string (:class:`~drillstring.forces.excitation.TurningLoads`:
            mass imbalance, stress-free bow), or ``None``.
        top_drive: the top boundary (:class:`~drillstring.forces.top_drive.TopDriveParameters`); ``None``
            is the imposed speed ``top_speed``. With a top drive the torsional family is free at the top
            (its first column the rigid rotation), ``top_speed`` is the set point, the kernels' base spin
            speed is 0 (the rigid rotation carries the spin) and the state ``[η, η̇, s]`` holds the
            controller's states ``s`` after the modal coordinates (:attr:`state_size`).
        hook_load: the start, a hook load of the protocol (:class:`~drillstring.forces.registry.HookLoad`:
            :class:`~drillstring.forces.hook_load.HookLoadRamp`, ...): ``None``, :class:`~drillstring.forces.
            hook_load.OnBottomStart` or a zero ramp time is the reference start (on the static state at t = 0); a ramp starts off bottom, the bit
            its ``clearance`` above the rock, and transfers the weight-on-bit over the ramp time.
        history_bins: bins per blade sector of the bit's history (:mod:`drillstring.dynamics.delay`) for a
            delayed bit–rock law.
        residual_columns: (n,) True on the columns that are residual-flexibility attachment modes (the truncation
            correction, :func:`drillstring.modal.residual_flexibility_modes`), not modes; None: none are.
        motor: a downhole motor (:mod:`drillstring.forces.motor`) or None; with one, ``rotor`` is the release of
            its rotor's rotation (:class:`~drillstring.rotor.RotorRelease`, its rows over the torsional columns)
            and the basis is that of the released string (:func:`~drillstring.rotor.released_modes`).

    Built from them: ``rhs_data`` (:class:`RhsData` for case 2, :class:`FullModelData` for case 1) and its
    case-2 part ``case2_data``, the model's data as the compiled kernels read it, by name. The model holds no
    run's state: nothing of a run writes its arrays. Each run, and each call of :meth:`rhs` or :meth:`observe`,
    takes :meth:`kernel_data` — that data with scratch of its own (contact work, the observation's, case 1's)
    and its own bit history — and the run's state (time, state vector, bit history, contact, controller) is
    passed in and returned by :func:`drillstring.dynamics.compiled.advance`.
    """

    static: StaticState
    system: LinearSystem
    modes: Modes
    basis: np.ndarray
    family: tuple[str, ...]
    angular_frequencies: np.ndarray
    damping: np.ndarray
    top_speed: float
    weight_on_bit: float
    bit_rock: BitLaw
    contact: ContactLaw
    stations: ContactStations
    probe_positions: np.ndarray
    nonlinear: str = "bit_and_contact"
    generalized_force: np.ndarray | None = None
    turning_loads: TurningLoads | None = None
    top_drive: TopDriveParameters | None = None
    hook_load: HookLoad | None = None
    history_bins: int = 2048
    residual_columns: np.ndarray | None = None
    coupled: bool = False
    motor: Motor | None = None
    rotor: RotorRelease | None = None

    def __post_init__(self) -> None:
        if self.nonlinear not in ("bit_and_contact", "full"):
            raise ValueError(f"nonlinear = {self.nonlinear!r}: must be 'bit_and_contact' or 'full'")
        if self.top_drive is None:
            self.top_drive = TopDriveParameters("imposed_speed", float(self.top_speed))
        #: the kernels' base spin speed [rad/s]: Ω with the top speed imposed, 0 with a top drive
        self.base_speed = 0.0 if self.top_drive.drives else float(self.top_speed)
        if self.top_drive.drives and self.nonlinear == "full":
            raise ValueError("nonlinear = 'full' with a top drive is not supported yet: use 'bit_and_contact'")
        if self.coupled:
            _check_coupled(self)
        if (self.motor is None) != (self.rotor is None):
            raise ValueError("motor and rotor: give both (a downhole motor and the release of its rotor) or neither")
        if self.motor is not None and self.nonlinear == "full":
            raise ValueError("nonlinear = 'full' with a downhole motor is not supported yet: use 'bit_and_contact'")
        if self.coupled and self.motor is not None:
            raise ValueError("a downhole motor on a coupled basis (a string out of the straight axis) is not supported "
                             "yet: its rotor is released in the torsional family of a straight string")
        mesh = self.static.mesh
        nodes = np.arange(mesh.n_nodes)
        phi = self.basis
        n = len(self.angular_frequencies)
        if self.generalized_force is None:
            self.generalized_force = np.zeros(n)
        force = np.array(self.generalized_force, dtype=float)
        if force.shape != (n,) or not np.all(np.isfinite(force)):
            raise ValueError(f"generalized_force: must be {n} finite numbers (one per mode), got shape "
                             f"{force.shape}")
        self.generalized_force = force
        self.residual_columns = (np.zeros(n, dtype=bool) if self.residual_columns is None
                                 else np.asarray(self.residual_columns, dtype=bool))
        if self.residual_columns.shape != (n,):
            raise ValueError(f"residual_columns: must be {n} booleans (one per basis column), got shape "
                             f"{self.residual_columns.shape}")
        if self.turning_loads is None:
            self.turning_loads = TurningLoads.empty(mesh.n_dofs)
        if self.hook_load is None:
            self.hook_load = OnBottomStart()
        self.omega2 = np.ascontiguousarray(np.sign(self.angular_frequencies) * self.angular_frequencies**2)
        self.bit_u = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, U)])
        self.top_u = np.ascontiguousarray(phi[dof(0, U)])
        self.bit_t = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, THETA_X)])
        self.phi_v = np.ascontiguousarray(phi[dof(nodes, V)])
        self.phi_w = np.ascontiguousarray(phi[dof(nodes, W)])
        self.phi_tx = np.ascontiguousarray(phi[dof(nodes, THETA_X)])
        self.probe_nodes = np.array([mesh.node_index(x) for x in self.probe_positions], dtype=np.int64)
        if len(self.stations) and (self.stations.node.min() < 0 or self.stations.node.max() >= mesh.n_nodes):
            raise ValueError("contact stations must sit on the mesh's nodes")
        #: k_i = k'_sh ℓ_i [N/m] of each contact station
        self.station_stiffness = self.stations.stiffness(self.contact.shock_stiffness)
        labels = np.array(self.family)
        blocks = []
        for names in (("rigid_axial", "axial"), ("torsional",), ("lateral_y",), ("lateral_z",)):
            if self.coupled:  # every physical quantity reads every column
                blocks += [0, n]
                continue
            columns = np.nonzero(np.isin(labels, names))[0]
            start = int(columns[0]) if len(columns) else 0
            end = int(columns[-1]) + 1 if len(columns) else 0
            if len(columns) and not np.array_equal(columns, np.arange(start, end)):
                raise ValueError("mode families must be contiguous in the basis")
            blocks += [start, end]
        self.blocks = np.array(blocks, dtype=np.int64)
        #: (n,) True on the columns that move the lateral DOFs (every column when the families couple)
        self.lateral_columns = np.zeros(n, dtype=bool)
        self.lateral_columns[blocks[4]:blocks[5]] = True
        self.lateral_columns[blocks[6]:blocks[7]] = True
        a0, a1, t0, t1, y0, y1, z0, z1 = blocks
        #: column of the rigid rotation (a top drive), None when the top is held
        self.rigid_rotation_column = t0 if self.top_drive.drives else None
        top_dof = dof(0, THETA_X)
        self.quill_shapes = np.ascontiguousarray(phi[top_dof])
        self.surface_torque_shapes = np.zeros(n)
        self.surface_torque_shapes[t0:t1] = self.system.stiffness[top_dof] @ phi[:, t0:t1]
        #: the rotor's rotation relative to the stator per modal coordinate (a downhole motor; zeros without)
        self.motor_shapes = np.zeros(n)
        if self.rotor is not None:
            self.motor_shapes[t0:t1] = self.rotor.relative
        c = self.contact
        st = self.stations
        transposed = np.ascontiguousarray
        history = (allocate_storage(self.bit_rock.sector, self.history_bins) if self.bit_rock.delayed
                   else allocate_storage(1.0, 4))
        laws, self.layout = pack(self.bit_rock, self.top_drive, self.hook_load, history, 2 * n, contact=self.contact,
                                 motor=self.motor)
        self.case2_data = (DelayedRhsData if self.bit_rock.delayed else RhsData)(
            omega2=self.omega2,
            damping_t=transposed(self.damping.T),
            damping_blocks=diagonal_blocks(self.damping),
            generalized_force=self.generalized_force,
            ranges=ModalRanges(*(int(b) for b in self.blocks)),
            axial_rows=_named_rows(AXIAL_ROWS, {"bit": self.bit_u, "top": self.top_u}, a0, a1),
            torsion_rows=_named_rows(TORSION_ROWS, {"bit": self.bit_t, "quill": self.quill_shapes,
                                                    "surface_torque": self.surface_torque_shapes,
                                                    "motor": self.motor_shapes}, t0, t1),
            phi_v_t=transposed(self.phi_v[:, y0:y1].T),
            phi_w_t=transposed(self.phi_w[:, z0:z1].T),
            phi_tx_t=transposed(self.phi_tx[:, t0:t1].T),
            smallest_gap=float(np.min(st.gap)) if len(st) else np.inf,
            lateral_shape_max=np.concatenate([np.abs(self.phi_v[:, y0:y1]).max(axis=0, initial=0.0),
                                              np.abs(self.phi_w[:, z0:z1]).max(axis=0, initial=0.0)]),
            top_speed=self.base_speed,
            weight_on_bit=float(self.weight_on_bit),
            laws=laws,
            contact=ContactData(
                node=transposed(st.node, dtype=np.int64), gap=transposed(st.gap, dtype=float),
                outer_diameter=transposed(st.outer_diameter, dtype=float),
                stiffness=transposed(self.station_stiffness, dtype=float),
                tangential=bool(c.reads_lateral_velocity), work=ContactWork.allocate(0, 0),  # kernel_data's
            ),
            turning=turning_load_data(self.turning_loads, phi[:, y0:y1], phi[:, z0:z1]),
        )
        self.full = self.nonlinear == "full"
        self.rhs_data: RhsData | DelayedRhsData | FullModelData = (
            self._full_model_data(self.case2_data) if self.full else self.case2_data)

    def _full_model_data(self, case2: RhsData) -> FullModelData:
        mesh = self.static.mesh
        self.elements: NonlinearElements = nonlinear_elements(mesh)
        e = self.elements
        a0, a1, t0, t1, y0, y1, z0, z1 = (int(b) for b in self.blocks)
        c = np.ascontiguousarray
        rows = {}
        for name, (start, end) in {"axial": (a0, a1), "torsional": (t0, t1), "lateral_y": (y0, y1),
                                   "lateral_z": (z0, z1)}.items():
            dofs = family_dofs(mesh, name).astype(np.int64)
            rows[name] = (c(dofs), c(self.basis[dofs, start:end].T, dtype=float))
        tensor = modal_mass_coupling(e, self.basis[:, t0:t1], self.basis[:, y0:y1], self.basis[:, z0:z1])
        n_dofs = mesh.n_dofs
        n_t, n_y = t1 - t0, y1 - y0
        return FullModelData(
            rhs=case2,
            axial_dofs=rows["axial"][0], axial_shapes_t=rows["axial"][1],
            torsion_dofs=rows["torsional"][0], torsion_shapes_t=rows["torsional"][1],
            bending_y_dofs=rows["lateral_y"][0], bending_y_shapes_t=rows["lateral_y"][1],
            bending_z_dofs=rows["lateral_z"][0], bending_z_shapes_t=rows["lateral_z"][1],
            theta_x_dofs=dof(np.arange(mesh.n_nodes), THETA_X).astype(np.int64),
            inv_length=c(e.inv_length, dtype=float), xi=c(e.xi, dtype=float),
            weights=c(e.weights, dtype=float), slope=c(e.slope, dtype=float),
            rotation=c(e.rotation, dtype=float), axial_stiffness=c(e.axial_stiffness, dtype=float),
            polar_inertia=c(e.polar_inertia, dtype=float), coupling_tensor=c(tensor, dtype=float),
            **_full_model_scratch(0, 0, 0, 0, 0),  # each run's own: kernel_data
        )

    def kernel_data(self, history: np.ndarray | None = None) -> KernelData:
        """The compiled kernels' arguments for one run or one call (:class:`KernelData`): the model's data,
        which no kernel writes, with scratch of their own, and ``history`` (a storage of
        :mod:`drillstring.dynamics.delay`, e.g. :meth:`start_history`'s; copied in) as the bit's history of a
        delayed law (None: the model's own prehistory, :attr:`history`, read only). Two runs of one model
        with their own kernel data do not share a written array."""
        template = self.case2_data
        laws = template.laws
        if history is not None:
            offset = self.layout.numbers["history"]
            history = np.asarray(history, dtype=float)
            if history.shape != (laws.shape[0] - offset,):
                raise ValueError(f"history has shape {history.shape}: must be ({laws.shape[0] - offset},), a "
                                 f"storage of this model's bit history (ReducedOrderModel.start_history)")
            laws = laws.copy()
            laws[offset:] = history
        mesh = self.static.mesh
        case2 = template._replace(laws=laws, contact=template.contact._replace(
            work=ContactWork.allocate(mesh.n_nodes, len(self.stations))))
        rhs = case2
        if self.full:
            t0, t1, y0, y1 = (int(b) for b in self.blocks[2:6])
            rhs = self.rhs_data._replace(rhs=case2, **_full_model_scratch(
                mesh.n_dofs, self.elements.n_elements, t1 - t0, y1 - y0, self.size))
        return KernelData(rhs, case2, ObserveData.allocate(self.probe_nodes, mesh.n_nodes))

    @property
    def lowest_lateral_eigenvalue(self) -> float:
        """ω₁² [rad²/s²] of the lowest lateral mode of the basis (signed; negative: the straight string is
        statically buckled, :mod:`drillstring.buckling`); NaN without lateral modes. When the families couple:
        the lowest ω² of the basis's modes (the rigid axial translation left out)."""
        if self.coupled:
            elastic = self.omega2[(np.array(self.family) != "rigid_axial") & ~self.residual_columns]
            return float(elastic.min()) if len(elastic) else math.nan
        y0, y1 = int(self.blocks[4]), int(self.blocks[5])
        return float(self.omega2[y0]) if y1 > y0 else math.nan

    @property
    def size(self) -> int:
        """Number of modal coordinates n (the state has 2n entries, plus the top drive's states)."""
        return len(self.angular_frequencies)

    @property
    def state_size(self) -> int:
        """Entries of the state ``[η, η̇, s]``: 2n plus the components' states ``s`` (the top boundary's), laid
        out by the registry (:attr:`layout`)."""
        return self.layout.state_size

    @property
    def observable_names(self) -> tuple[str, ...]:
        return OBSERVABLES

    @property
    def gap(self) -> np.ndarray:
        """Radial clearance at each node [m]: the smallest of its stations' (at a section change, the
        wider section's), so a node touches the wall exactly when ``r > gap``."""
        gap = np.full(self.static.mesh.n_nodes, np.inf)
        np.minimum.at(gap, self.stations.node, self.stations.gap)
        return gap

    @property
    def compiled(self) -> bool:
        """True when the compiled kernels hold the model's components (the package's registered ones); a
        component registered outside the package runs through :meth:`rhs_reference` only
        (:mod:`drillstring.forces.registry`)."""
        return all(compiled(c) for c in (self.bit_rock, self.top_drive, self.hook_load, self.contact, self.motor)
                   if c is not None)

    def require_compiled(self) -> None:
        """ValueError naming the component when :attr:`compiled` is False."""
        for kind, component in (("bit law", self.bit_rock), ("top boundary", self.top_drive),
                                ("hook load", self.hook_load), ("contact law", self.contact), ("motor", self.motor)):
            if component is not None and not compiled(component):
                raise ValueError(
                    f"{kind} {component.name!r} is registered outside the drillstring package, so the compiled "
                    f"kernels do not hold it: use engine = 'reference' (docs/extending.md)")

    def rhs(self, t: float, y: np.ndarray, history: np.ndarray | None = None) -> np.ndarray:
        """dy/dt for y = [η, η̇] at time ``t`` [s] (t enters through the rotation Ω t that turns the
        turning loads); ``history``: the bit's history of a delayed law (a storage of
        :mod:`drillstring.dynamics.delay`; None: the model's prehistory, :attr:`history`)."""
        self.require_compiled()
        out = np.empty_like(y)
        evaluate_rhs(self.kernel_data(history).rhs, float(t), np.ascontiguousarray(y, dtype=float), out)
        return out

    def rhs_reference(self, t: float, y: np.ndarray, history: np.ndarray | None = None) -> np.ndarray:
        """The straightforward NumPy right-hand side (full basis, every node): the reference
        implementation that the compiled :meth:`rhs` is tested against; same equations (``history`` as
        there)."""
        n = self.size
        eta, eta_dot = y[:n], y[n:2 * n]
        bit_velocity = self.bit_u @ eta_dot
        bit_speed = self.base_speed + self.bit_t @ eta_dot
        position, angle = self.bit_position(t, y)
        depth = 0.0
        if self.bit_rock.delayed:  # u minus the hole bottom one blade sector behind the bit
            depth = delayed_difference(self._history(history), angle, position)
        axial_force, bit_torque = self.bit_rock.evaluate_at(BitContext(
            t, position, angle, bit_velocity, bit_speed, depth, self.weight_on_bit))
        st = self.stations
        spin = self.base_speed + self.phi_tx @ eta_dot
        lateral_velocity = self.contact.reads_lateral_velocity
        force_v, force_w, torque = self.contact.evaluate_at(ContactContext(
            st.gather(self.phi_v @ eta), st.gather(self.phi_w @ eta),
            st.gather(self.phi_v @ eta_dot) if lateral_velocity else np.zeros(len(st)),
            st.gather(self.phi_w @ eta_dot) if lateral_velocity else np.zeros(len(st)),
            st.gather(spin), st.gap, st.outer_diameter, self.station_stiffness))
        n_nodes = self.static.mesh.n_nodes
        turning = self.basis.T @ self.turning_loads.forces(self.base_speed * t + self.phi_tx @ eta, spin)
        lateral = self.lateral_columns
        generalized = (self.phi_v.T @ st.scatter(force_v, n_nodes) + self.phi_w.T @ st.scatter(force_w, n_nodes)
                       + self.phi_tx.T @ st.scatter(torque, n_nodes)
                       + self.bit_u * (axial_force + self.weight_on_bit) + self.bit_t * bit_torque
                       + self.top_u * float(self.hook_load.evaluate_at(HookContext(t, self.weight_on_bit)))
                       + self.generalized_force + np.where(lateral, turning, 0.0))
        acceleration = generalized - self.damping @ eta_dot - self.omega2 * eta
        states = np.zeros(self.state_size - 2 * n)
        if self.top_drive.drives:  # the motor torque of any driving boundary, its states where the registry put them
            first = self.layout.states["top_boundary"]
            torque, rates = self.top_drive.evaluate_at(
                TopContext(t, self.base_speed + self.quill_shapes @ eta_dot, self.surface_torque_shapes @ eta),
                y[first:first + self.top_drive.n_states])
            states[first - 2 * n:first - 2 * n + self.top_drive.n_states] = rates
            acceleration = acceleration + self.quill_shapes * torque
        if self.motor is not None:  # +T on the rotor side, -T on the stator side; its states where the layout puts them
            first = self.layout.states["motor"]
            torque, rates = self.motor.evaluate_at(MotorContext(t, self.motor_shapes @ eta_dot),
                                                   y[first:first + self.motor.n_states])
            states[first - 2 * n:first - 2 * n + self.motor.n_states] = rates
            acceleration = acceleration + self.motor_shapes * float(torque)
        if self.nonlinear == "full":
            q = self.basis @ eta
            qd = self.basis @ eta_dot
            qd[dof(np.arange(self.static.mesh.n_nodes), THETA_X)] += self.base_speed
            f_se = self.elements.strain_energy_forces(q, np.zeros_like(q))
            f_vel = np.zeros_like(q)
            self.elements.kinetic_forces(q, qd, f_vel)
            mass_nl = self.elements.mass_correction_matrix(q)
            mass = np.eye(self.size) + self.basis.T @ (mass_nl @ self.basis)
            acceleration = np.linalg.solve(mass, acceleration + self.basis.T @ (f_se + f_vel))
        return np.concatenate([eta_dot, acceleration, states])

    def observe(self, t: float, y: np.ndarray, history: np.ndarray | None = None) -> np.ndarray:
        """Observables (:data:`OBSERVABLES`) followed by the radial displacement r at each probe, then
        its v and w [m] (:func:`observation_width` columns); ``history`` as in :meth:`rhs`."""
        out = np.empty(observation_width(len(self.probe_nodes)))
        y = np.ascontiguousarray(y, dtype=float)
        data = self.kernel_data(history)
        observe_row(data.case2, data.observe, float(t), y, np.zeros_like(y), out)
        if not compiled(self.bit_rock):  # a law from outside the package: its force from its NumPy reference
            n = self.size
            position, angle = self.bit_position(t, y)
            depth = delayed_difference(self._history(history), angle, position) if self.bit_rock.delayed else 0.0
            force, torque = self.bit_rock.evaluate_at(BitContext(
                t, position, angle, out[_ROP], self.base_speed + self.bit_t @ y[n:2 * n], depth, self.weight_on_bit))
            out[_TOB], out[_FOB] = -float(torque), -float(force)
        if self.top_drive.drives and not compiled(self.top_drive):  # its motor torque from its NumPy reference
            n, first = self.size, self.layout.states["top_boundary"]
            torque, _ = self.top_drive.evaluate_at(TopContext(t, out[_QUILL_SPEED], self.surface_torque_shapes @ y[:n]),
                                                   y[first:first + self.top_drive.n_states])
            quill_acceleration = self.quill_shapes @ self.rhs_reference(t, y, history)[n:2 * n]
            out[_SURFACE_TORQUE] = float(torque) - self.top_drive.top_inertia * quill_acceleration
        return out

    def contact_mask(self, y: np.ndarray) -> np.ndarray:
        """(n_nodes,) bool: the nodes in contact with the borehole (a station outside its gap) at the state
        ``y``."""
        observe = ObserveData.allocate(self.probe_nodes, self.static.mesh.n_nodes)
        impacts_kernel(self.case2_data, observe, np.ascontiguousarray(y, dtype=float))
        return observe.current

    def impact_counter(self, in_contact: np.ndarray | None = None) -> ImpactCounter:
        """A counter of the impacts of one run (:class:`ImpactCounter`), from the nodes ``in_contact`` at its
        start (None: none, so that the contact zones of the first state counted are impacts)."""
        return ImpactCounter(self, in_contact)

    @property
    def history(self):
        """The model's own bit history (:class:`~drillstring.dynamics.delay.AngleHistory`): the flat
        prehistory that :meth:`rhs` and :meth:`observe` read when given none. A run reads and records its own
        (:meth:`start_history`, :meth:`kernel_data`); nothing of a run writes this one."""
        return view(self.case2_data.laws[self.layout.numbers["history"]:])

    def with_history(self, history: np.ndarray) -> ReducedOrderModel:
        """A shallow copy of this model whose own bit history (:attr:`history`, what :meth:`rhs` and
        :meth:`observe` read when given none) is a copy of ``history``: e.g. to analyse a run's state with code
        that takes a model (:mod:`drillstring.dynamics.stiffness`). This model is not changed."""
        data = self.kernel_data(history)
        other = copy.copy(self)
        other.case2_data = data.case2._replace(contact=self.case2_data.contact)
        other.rhs_data = self.rhs_data._replace(rhs=other.case2_data) if self.full else other.case2_data
        return other

    def _history(self, history: np.ndarray | None):
        """The :class:`~drillstring.dynamics.delay.AngleHistory` of a storage, or the model's own for None."""
        return self.history if history is None else view(np.asarray(history, dtype=float))

    def bit_position(self, t: float, y: np.ndarray) -> tuple[float, float]:
        """The bit's axial position u [m] (from the static state, down) and angle θ [rad] at time ``t``
        [s] for the state ``y``."""
        n = self.size
        return float(self.bit_u @ y[:n]), float(self.base_speed * t + self.bit_t @ y[:n])

    def start_history(self, y: np.ndarray, depth_of_cut: float | None = None) -> np.ndarray:
        """The bit's history at the start of a run from the state ``y`` at t = 0, a new storage of
        :mod:`drillstring.dynamics.delay` (the model's own is not changed): for a delayed bit–rock law, with a
        ramped start (:attr:`hook_load`) a flat bottom ``clearance`` below the bit; else the helical bottom of
        steady drilling with the depth of cut ``depth_of_cut`` [m] per blade under the bit — by default the
        law's own at the static weight-on-bit and the top speed (its ``start_depth_of_cut``; for the Detournay
        law the closed-form steady state, 0 when that weight does not exceed the wear flats' contact force).
        For a law without history: a copy of the model's (never read)."""
        storage = self.case2_data.laws[self.layout.numbers["history"]:].copy()
        if not self.bit_rock.delayed:
            return storage
        position, angle = self.bit_position(0.0, y)
        law = self.bit_rock
        if self.hook_load.active:
            start_history(view(storage), angle, position + self.hook_load.clearance, 0.0)
            return storage
        if depth_of_cut is None:
            speed = self.top_speed
            depth_of_cut = law.start_depth_of_cut(self.weight_on_bit, speed)
        start_history(view(storage), angle, position, depth_of_cut / law.sector)
        return storage

    def record_history(self, history: np.ndarray, t_old: float, h: float, y_old: np.ndarray,
                       coef: np.ndarray) -> None:
        """Record into ``history`` (a storage, :meth:`start_history`) the bit's position by angle over an
        accepted step from its dense-output polynomial ``y(t_old + σh) = y_old + Σ_p coef[p] σ^(p+1)``
        (``coef`` (p, len(y)): what :meth:`~drillstring.dynamics.runge_kutta.RungeKuttaStepper.dense_polynomial`
        gives): the NumPy path's counterpart of :func:`accepted_step_kernel`. Nothing for a law without
        history."""
        if not self.bit_rock.delayed:
            return
        n = self.size
        position, angle = self.bit_position(t_old, y_old)
        angle_coef = coef[:, :n] @ self.bit_t
        angle_coef[0] += self.base_speed * h
        record_bottom(view(history), angle, np.ascontiguousarray(angle_coef), position,
                      np.ascontiguousarray(coef[:, :n] @ self.bit_u))

    def turning_whirl(self) -> np.ndarray:
        """The steady lateral whirl [η, η̇] at t = 0 of the linear model spinning at Ω under the turning
        loads alone (mass imbalance, bow): with ``η_f(t) = Re(A_f e^{iΩt})`` in each lateral family,
        ``(diag(ω²) − Ω² I + iΩ D_ff) A_f = G_f``, ``G_y = Σ_k s_k e^{iφ_k} load_y[k]``,
        ``G_z = −i Σ_k s_k e^{iφ_k} load_z[k]`` (``s_k = Ω²`` for an imbalance, 1 for a bow). Zero
        without turning loads."""
        n = self.size
        y = np.zeros(2 * n)
        turning = self.case2_data.turning
        if not len(turning.node):
            return y
        omega = self.top_speed
        weight = np.exp(1j * turning.phase) * np.where(turning.speed_squared, omega**2, 1.0)
        _, _, _, _, y0, y1, z0, z1 = self.blocks
        if self.coupled:  # one system: both planes' loads on the whole basis, the full damping
            block = np.diag(self.omega2) - omega**2 * np.eye(n) + 1j * omega * self.damping
            amplitude = np.linalg.solve(block, weight @ turning.load_y - 1j * (weight @ turning.load_z))
            y[:n] = amplitude.real
            y[n:] = (1j * omega * amplitude).real
            return y
        for (start, end), load, factor in (((y0, y1), turning.load_y, 1.0), ((z0, z1), turning.load_z, -1j)):
            if end == start:
                continue
            rhs = factor * (weight @ load)
            block = np.diag(self.omega2[start:end]) - omega**2 * np.eye(end - start) \
                + 1j * omega * self.damping[start:end, start:end]
            amplitude = np.linalg.solve(block, rhs)
            y[start:end] = amplitude.real
            y[n + start:n + end] = (1j * omega * amplitude).real
        return y

    def initial_state(self, lateral_perturbation: float, seed: int) -> np.ndarray:
        """Initial state (docs/model.md §9): the static state, the whole string spinning at Ω, zero axial
        speed (η̇ = 0), in the steady whirl of its turning loads (:meth:`turning_whirl`; none without
        imbalance or bow: a string that has been spinning at Ω whirls so, and starting it straight would
        give it the impulse of a load switched on at t = 0), plus a seeded lateral perturbation defined
        physically, independent of the basis: ``v0(x) = Σ_k a_k sin(kπx/L)/k²``, ``w0`` likewise with
        ``b_k``, k = 1…10, ``a_k, b_k`` standard normal from ``numpy.random.default_rng(seed)``, scaled so
        that the largest radial displacement along the string is ``lateral_perturbation`` [m]; it is
        projected on the lateral modes (mass-orthogonal projection ``η0 = Φᵀ(M + M_f) q0``), so it
        converges to the physical shape as lateral modes are added. With a top drive the rigid rotation
        carries Ω (or the string starts at rest when the set point is ramped) and the controller's states
        start at 0 (the motor torque builds up from 0)."""
        at_rest = self.top_drive.starts_at_rest  # a ramped set point starts from rest: no spin, no whirl
        y0 = np.zeros(self.state_size)
        if not at_rest:
            y0[:2 * self.size] = self.turning_whirl()
        if self.hook_load.active:
            y0[:self.size] += self.off_bottom_offsets()
        if self.rigid_rotation_column is not None and not at_rest:
            r = self.rigid_rotation_column  # spinning at Ω: the rigid rotation carries it
            y0[self.size + r] = self.top_speed / self.quill_shapes[r]
        lateral = self.lateral_columns
        if not (lateral_perturbation > 0 and lateral.any()):
            return y0
        mesh = self.static.mesh
        x = mesh.nodes / mesh.length
        k = np.arange(1, 11)
        rng = np.random.default_rng(seed)
        a, b = rng.standard_normal(10), rng.standard_normal(10)
        shapes = np.sin(np.pi * np.outer(x, k)) / k**2
        slopes = np.pi / mesh.length * np.cos(np.pi * np.outer(x, k)) / k
        v0, w0 = shapes @ a, shapes @ b
        scale = lateral_perturbation / np.hypot(v0, w0).max()
        nodes = np.arange(mesh.n_nodes)
        q0 = np.zeros(mesh.n_dofs)
        q0[dof(nodes, V)] = scale * v0
        q0[dof(nodes, W)] = scale * w0
        q0[dof(nodes, THETA_Z)] = scale * (slopes @ a)  # θz = ∂v/∂x
        q0[dof(nodes, THETA_Y)] = -scale * (slopes @ b)  # θy = −∂w/∂x
        eta0 = self.basis.T @ (self.system.mass @ q0)
        y0[: self.size] += np.where(lateral, eta0, 0.0)
        return y0

    def off_bottom_offsets(self) -> np.ndarray:
        """Modal coordinates η [√kg·m] of the string hanging off bottom at the start of a ramped start
        (:class:`~drillstring.forces.hook_load.HookLoadRamp`): relative to the static state the bit no longer
        carries the weight-on-bit W and the hook carries it instead, so the elastic axial modes take the
        static offsets of a force W down at the bit and W up at the top, ``ω_j² η_j = W (φ_bit − φ_top)_j``;
        the rigid axial coordinate puts the bit ``clearance`` above its static position (the rock)."""
        eta = np.zeros(self.size)
        a0, a1 = int(self.blocks[0]), int(self.blocks[1])
        load = self.weight_on_bit * (self.bit_u - self.top_u)
        rigid = rigid_axial_column(self)
        for j in range(a0, a1):
            if j != rigid:
                eta[j] = load[j] / self.omega2[j]
        eta[rigid] = (-self.hook_load.clearance - self.bit_u @ eta) / self.bit_u[rigid]
        return eta

    def energy(self, y: np.ndarray) -> float:
        """Linear mechanical energy ½ η̇ᵀη̇ + ½ Σ ω² η² [J] (conserved without damping and forcing)."""
        n = self.size
        return 0.5 * float(y[n:2 * n] @ y[n:2 * n] + self.omega2 @ (y[:n] ** 2))


def _named_rows(names: tuple[str, ...], shapes: dict[str, np.ndarray], start: int, end: int) -> np.ndarray:
    """The rows ``names`` (:data:`~drillstring.dynamics.kernel_data.AXIAL_ROWS`, ...) of the kernels' data: each
    named shape over the columns ``[start, end)``, in the names' order; a name without a shape is refused."""
    missing = [name for name in names if name not in shapes]
    if missing:
        raise ValueError(f"no shape for the rows {missing}: the reduced model builds {sorted(shapes)}")
    return np.ascontiguousarray(np.vstack([shapes[name][start:end] for name in names]))


class ImpactCounter:
    """The impacts of one run, counted state by state (:func:`new_contact_zones`): it holds the nodes in
    contact at the last state counted (:attr:`in_contact`), not the model."""

    def __init__(self, model: ReducedOrderModel, in_contact: np.ndarray | None = None) -> None:
        self._data = model.case2_data
        self._observe = ObserveData.allocate(model.probe_nodes, model.static.mesh.n_nodes)
        if in_contact is not None:
            self._observe.previous[:] = in_contact

    def __call__(self, y: np.ndarray) -> int:
        """The impacts at the accepted state ``y`` since the previous call: the contact zones that
        appeared."""
        return int(impacts_kernel(self._data, self._observe, np.ascontiguousarray(y, dtype=float)))

    @property
    def in_contact(self) -> np.ndarray:
        """The nodes in contact at the last state counted (a copy)."""
        return self._observe.previous.copy()


def _full_model_scratch(n_dofs: int, n_elements: int, n_t: int, n_y: int, n: int) -> dict:
    """The scratch fields of :class:`FullModelData` for ``n_dofs`` DOFs, ``n_elements`` elements, ``n_t``
    torsional and ``n_y`` lateral-y modes of ``n`` modal coordinates."""
    return dict(q=np.zeros(n_dofs), qd=np.zeros(n_dofs), f_se=np.zeros(n_dofs), f_vel=np.zeros(n_dofs),
                coupling=np.zeros((n_elements, 2, 4)), block=np.zeros((n_t, n_y)), schur=np.zeros((n_t, n_t)),
                torsion_rhs=np.zeros(n_t), acceleration=np.zeros(n))


def _check_coupled(model: ReducedOrderModel) -> None:
    """ValueError for what a model whose families couple does not support yet, naming it."""
    if model.nonlinear == "full":
        raise ValueError("nonlinear = 'full' with coupled families (a string out of its straight axis) is not "
                         "supported: its mass correction is built family by family; use 'bit_and_contact'")
    if model.top_drive.drives:
        raise ValueError(f"top boundary {model.top_drive.name!r} with coupled families (a string out of its "
                         "straight axis) is not supported: the rigid rotation of a bent string is not a motion of "
                         "its global θx DOFs; use an imposed top speed")
    if model.base_speed != 0.0:
        raise ValueError(f"top_speed = {model.base_speed:g} rad/s with coupled families (a string out of its "
                         "straight axis): the spin of a bent string about its centreline is not a rotation of its "
                         "global θx DOFs (deviated-well dynamics); only 0 is supported")


def rigid_axial_column(model: ReducedOrderModel) -> int:
    """The column of the rigid axial translation in the model's basis."""
    columns = [i for i, f in enumerate(model.family) if f == "rigid_axial"]
    if len(columns) != 1:
        raise ValueError("the reduced model must hold exactly one rigid axial mode")
    return columns[0]


def reduced_model(
    static: StaticState,
    system: LinearSystem,
    *,
    axial_modes: int,
    torsional_modes: int,
    lateral_modes: int,
    modal_damping_ratio: float,
    rigid_axial_damping: float,
    top_speed: float,
    bit_rock: BitLaw,
    contact: ContactLaw,
    borehole_diameter: float,
    rigid_rotation_damping: float = 0.0,
    damping_basis: str = "free_free",
    probe_positions=(),
    nonlinear: str = "bit_and_contact",
    turning_loads: TurningLoads | None = None,
    lateral_cutoff: float = 0.0,
    top_drive: TopDriveParameters | None = None,
    hook_load: HookLoad | None = None,
    rayleigh: tuple[float, float] = (0.0, 0.0),
    truncation_correction: str = "none",
    motor: Motor | None = None,
) -> ReducedOrderModel:
    """Project the prestressed system on its modes (``axial_modes`` elastic + the rigid one;
    ``lateral_modes`` per plane at least, plus every lateral mode below ``lateral_cutoff`` [rad/s];
    ``torsional_modes`` elastic, plus the rigid rotation with a top drive).

    Args:
        modal_damping_ratio: ξ [-]; rigid_axial_damping: c1 [N·s/m], viscous resistance to the
            rigid axial motion; rigid_rotation_damping: c2 [N·m·s/rad], to the rigid rotation.
        damping_basis: "free_free" (ξ, c1, c2 on the free–free modes) or "constrained" (ξ on every
            basis mode); see :mod:`drillstring.damping`.
        top_speed: Ω [rad/s].
        contact: the contact law, ``shock_stiffness`` read as k'_sh [N/m per m of string].
        borehole_diameter: D_ch [m]; the contact stations follow from it and the mesh
            (:func:`~drillstring.forces.contact.mesh_contact_stations`).
        turning_loads: mass imbalance and bow (:mod:`drillstring.forces.excitation`), or None.
        top_drive: the top boundary; None: the top speed imposed.
        hook_load: the start (a :class:`~drillstring.forces.registry.HookLoad`); None: the reference start.
        rayleigh: (α [1/s], β [s]) of the Rayleigh damping ``α M + β K`` added to the above.
        truncation_correction: "none" (the modes alone) or "static" (each of the axial and torsional families
            followed by its residual-flexibility attachment modes at the bit, and at the top with a top drive:
            :func:`drillstring.modal.compute_modes`).
        motor: a downhole motor (:mod:`drillstring.forces.motor`), None without: the torsional family is then that
            of the string released at the motor's rotor station (:func:`drillstring.rotor.released_modes`;
            ``torsional_modes`` elastic modes plus its rigid motions).
    """
    drive = top_drive is not None and top_drive.drives
    coupled = family_coupling(system) > 0.0
    release, damped = None, system
    if coupled:
        if motor is not None:
            raise ValueError("a downhole motor on a coupled basis (a string out of the straight axis) is not "
                             "supported yet: its rotor is released in the torsional family of a straight string")
        modes, basis, omega, family, residual = _coupled_basis(
            system, axial_modes + 1 + torsional_modes + 2 * lateral_modes, lateral_cutoff, truncation_correction,
            damping_basis)
        released = basis
    else:
        if drive:
            torsional_modes += 1
        top_inertia = top_drive.top_inertia if drive else None
        if motor is None:
            modes = compute_modes(system, axial_modes + 1, torsional_modes, lateral_modes, lateral_cutoff,
                                  top_inertia=top_inertia, truncation_correction=truncation_correction)
        else:
            modes, release, damped = released_modes(system, motor.position, axial_modes + 1, torsional_modes + 1,
                                                    lateral_modes, lateral_cutoff, top_inertia, truncation_correction)
        families = [modes.axial, modes.torsional, modes.lateral_y, modes.lateral_z]
        basis = np.hstack([f.shapes for f in families])
        omega = np.concatenate([f.angular_frequencies for f in families])
        # the family's size, its attachment modes (truncation_correction = "static") included
        family = ["rigid_axial"] + ["axial"] * (len(modes.axial.angular_frequencies) - 1)
        for f in families[1:]:
            family += [f.name] * len(f.angular_frequencies)
        residual = np.concatenate([np.arange(len(f.angular_frequencies)) >= len(f.angular_frequencies)
                                   - f.attachments for f in families])
        released = basis if release is None else np.vstack([basis, np.concatenate(  # the rotor side's row after
            [np.zeros(f.shapes.shape[1]) if f is not modes.torsional else release.rotor for f in families])])
    structural = reduced_structural_damping(
        damped.mass, damped.stiffness, released, family, omega, damping_ratio=modal_damping_ratio,
        rigid_axial=rigid_axial_damping, rigid_rotation=rigid_rotation_damping,
        top_speed=0.0 if drive else top_speed, definition=damping_basis, rayleigh=rayleigh,
    )
    damping = basis.T @ (system.fluid_damping @ basis) + structural.matrix
    return ReducedOrderModel(
        static=static, system=system, modes=modes, basis=basis, family=tuple(family),
        angular_frequencies=omega, damping=damping, top_speed=top_speed,
        weight_on_bit=static.weight_on_bit, bit_rock=bit_rock, contact=contact,
        stations=mesh_contact_stations(static.mesh, borehole_diameter),
        probe_positions=np.asarray(probe_positions, dtype=float),
        nonlinear=nonlinear, generalized_force=structural.generalized_force, turning_loads=turning_loads,
        top_drive=top_drive, hook_load=hook_load, residual_columns=residual, coupled=coupled, motor=motor,
        rotor=release,
    )


def _coupled_basis(system: LinearSystem, count: int, cutoff: float, truncation_correction: str,
                   damping_basis: str):
    """The one basis of a system whose families couple (:func:`~drillstring.modal.coupled_modes`: the ``count``
    lowest modes of the whole string and every one below ``cutoff`` [rad/s], then its attachment modes):
    ``(modes, basis, ω, labels, residual)``, labels "rigid_axial" for the rigid translation and "coupled" for
    the others."""
    if damping_basis != "constrained":
        raise ValueError(f"damping.basis = {damping_basis!r} with coupled families (a string out of its straight "
                         "axis): the free-free damping is defined family by family; use 'constrained' (and "
                         "Rayleigh damping)")
    found = coupled_modes(system, count, cutoff, truncation_correction)
    empty = {name: ModeFamily(name, np.zeros(0), np.zeros((system.mesh.n_dofs, 0)))
             for name in ("axial", "torsional", "lateral_y", "lateral_z")}
    n = len(found.angular_frequencies)
    family = ["coupled"] * n
    if n and found.angular_frequencies[0] == 0.0:  # coupled_modes put the rigid axial translation first
        family[0] = "rigid_axial"
    residual = np.arange(n) >= n - found.attachments
    return Modes(**empty, coupled=found), found.shapes, found.angular_frequencies, family, residual


def _lateral_cutoff(case_value: float, lateral_modes: int | None, lateral_cutoff: float | None) -> float:
    if lateral_cutoff is not None:
        return lateral_cutoff
    return 0.0 if lateral_modes is not None else case_value


def case_reduced_model(
    case,
    *,
    weight_on_bit: float | None = None,
    axial_modes: int | None = None,
    torsional_modes: int | None = None,
    lateral_modes: int | None = None,
    static: StaticState | None = None,
    nonlinear: str | None = None,
    lateral_cutoff: float | None = None,
    bit_rock: BitLaw | None = None,
    top_drive: TopBoundary | None = None,
    motor: Motor | None = None,
) -> ReducedOrderModel:
    """The ROM of a :class:`~drillstring.case.Case`; keyword arguments override the case's values
    (``bit_rock``, ``top_drive``, ``motor``: a bit–rock law, a top boundary or a downhole motor instance, e.g.
    one registered outside the package, instead of the case's; the case's motor is its ``[motor]``)
    (``nonlinear``: "bit_and_contact" = case 2, "full" = case 1, default the case's ``model.nonlinear``;
    ``lateral_cutoff``: ratio to the rotation speed, as ``reduced_model.lateral_cutoff``). A
    ``lateral_modes`` given without ``lateral_cutoff`` asks for exactly that many lateral modes (no
    cut-off)."""
    static = case_static_state(case, weight_on_bit) if static is None else static
    system = case_linear_system(case, static)
    motor = case_motor(case) if motor is None else motor
    if top_drive is None:
        top_drive = case_top_drive(case, lambda: (
            float(family_modes(system, "torsional", 1).angular_frequencies[0]) if motor is None
            else first_torsional_frequency(system, motor.position)))
    r = case.reduced_model
    return reduced_model(
        static,
        system,
        axial_modes=r.axial_modes if axial_modes is None else axial_modes,
        torsional_modes=r.torsional_modes if torsional_modes is None else torsional_modes,
        lateral_modes=r.lateral_modes if lateral_modes is None else lateral_modes,
        modal_damping_ratio=case.damping.modal_damping_ratio,
        rigid_axial_damping=case.damping.rigid_axial,
        rigid_rotation_damping=case.damping.rigid_rotation,
        rayleigh=(case.damping.mass_proportional, case.damping.stiffness_proportional),
        damping_basis=case.damping.basis,
        top_speed=case.operation.top_speed,
        bit_rock=case_bit_rock(case) if bit_rock is None else bit_rock,
        contact=case_contact(case),
        borehole_diameter=case.borehole.diameter,
        probe_positions=case.mesh.probes,
        nonlinear=case.model.nonlinear if nonlinear is None else nonlinear,
        turning_loads=case_turning_loads(case, static.mesh),
        lateral_cutoff=_lateral_cutoff(r.lateral_cutoff, lateral_modes, lateral_cutoff) * case.operation.top_speed,
        top_drive=top_drive,
        hook_load=case_hook_load(case, static.weight_on_bit),
        truncation_correction=r.truncation_correction,
        motor=motor,
    )


def case_hook_load(case, weight_on_bit: float) -> HookLoad:
    """The start of a :class:`~drillstring.case.Case` (``[initial]``): the registered hook load that
    ``initial.start`` names (:func:`~drillstring.forces.registry.hook_load`), built from the case and the static
    ``weight_on_bit`` [N]: the ramp of it over ``weight_ramp_time`` with the bit ``clearance`` off bottom for
    ``start = "ramp"`` (:class:`~drillstring.forces.hook_load.HookLoadRamp`); the reference start for
    ``"on_bottom"``."""
    return registered_hook_load(case.initial.start).from_case(case, weight_on_bit)
