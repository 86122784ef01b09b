"""The reduced model's compiled inner kernels, one per part of the right-hand side (docs/model.md §5–§9):
the linear part's products (block-diagonal damping), the bit's motion and the bit–rock law, the turning loads,
the top boundary and the downhole motor. The stations' motion they read comes from the frame
(:mod:`drillstring.dynamics.reduced.frame`). Each reads the case-2 data (:class:`~drillstring.dynamics.kernel_data.RhsData`) by name; the
right-hand side that assembles them is :mod:`drillstring.dynamics.reduced.rhs`, the observation
:mod:`drillstring.dynamics.reduced.observation`.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.extending import overload

from drillstring.dynamics.delay import delayed_difference, view
from drillstring.dynamics.kernel_data import AXIAL_ROW, TORSION_ROW, DelayedRhsData
from drillstring.dynamics.reduced.frame import bit_axial_motion, friction_station_axial_velocity, station_spin
from drillstring.forces.registry import (
    HISTORY,
    BitContext,
    MotorContext,
    StringFrictionContext,
    TopContext,
    bit_law_force,
    motor_torque,
    string_friction_forces,
    top_boundary_torque,
)
from drillstring.forces.turning_loads import turning_load

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
    """out −= D velocity, D block diagonal (``blocks`` from :func:`diagonal_blocks`, ``damping_t`` = Dᵀ).

    Column by column of D (a contiguous row of Dᵀ), two columns per pass where both velocities are non-zero:
    each ``out[i]`` takes the same subtractions in the same order as one column at a time (zero velocities
    skipped), over slices indexed from 0 (no negative-index handling, so the inner loop is vectorised): 3x
    faster than indexing the whole arrays on the reference case (docs/performance.md)."""
    for b in range(blocks.shape[0]):
        start, end = blocks[b, 0], blocks[b, 1]
        size = end - start
        part = out[start:end]
        j = start
        while j < end:
            x = velocity[j]
            if x != 0.0 and j + 1 < end and velocity[j + 1] != 0.0:
                x_next = velocity[j + 1]
                column = damping_t[j, start:end]
                column_next = damping_t[j + 1, start:end]
                for i in range(size):
                    part[i] = (part[i] - column[i] * x) - column_next[i] * x_next
                j += 2
                continue
            if x != 0.0:
                column = damping_t[j, start:end]
                for i in range(size):
                    part[i] -= column[i] * x
            j += 1


@inner_kernel()
def _bit_state(d, t, y):
    """Axial position u [m] (from the static state, down), angle θ [rad], axial velocity u̇ [m/s] and spin
    speed ω [rad/s] of the bit at time ``t`` [s] for the state ``y`` = [η, η̇], from the frame
    (:mod:`drillstring.dynamics.reduced.frame`)."""
    position, velocity = bit_axial_motion(d, y)
    angle, speed = station_spin(d, t, y, d.phi_tx_t.shape[1] - 1, 0.0)  # the bit: the last node
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
    ranges = d.ranges
    y0, y1, z0, z1 = ranges.lateral_y_start, ranges.lateral_y_end, ranges.lateral_z_start, ranges.lateral_z_end
    for k in range(r.node.shape[0]):
        angle, speed = station_spin(d, t, y, r.node[k], r.phase[k])
        turning_load(r, k, angle, speed, acc, y0, y1, z0, z1)


@inner_kernel()
def _string_friction(d, t, y, acc):
    """Add the along-string friction (the registered law, :func:`~drillstring.forces.registry.
    string_friction_forces`, reading the named context :class:`~drillstring.forces.registry.StringFrictionContext`)
    at its stations, projected on the axial (force) and torsional (torque) modes, to ``acc``. Each station's
    axial velocity and spin speed come from the frame."""
    n = d.omega2.shape[0]
    a0, a1, t0, t1 = d.ranges.axial_start, d.ranges.axial_end, d.ranges.torsion_start, d.ranges.torsion_end
    f = d.friction
    w = f.work
    for k in range(f.node.shape[0]):
        w.axial_velocity[k] = friction_station_axial_velocity(d, y, k)
        _, w.spin[k] = station_spin(d, t, y, f.node[k], 0.0)
    string_friction_forces(d.laws, StringFrictionContext(w.axial_velocity, w.spin, f.normal_force, f.radius,
                                                         f.friction), w.force, w.torque)
    for k in range(f.node.shape[0]):
        force = w.force[k]
        torque = w.torque[k]
        for j in range(a0, a1):
            acc[j] += f.axial_t[j - a0, k] * force
        i = f.node[k]
        for j in range(t0, t1):
            acc[j] += d.phi_tx_t[j - t0, i] * torque


@inner_kernel()
def _top_motion(d, t, y):
    """Quill speed θ̇₀ [rad/s] (the spin of the top node, :func:`~drillstring.dynamics.reduced.frame.station_spin`)
    and surface torque T_s [N·m] for the state ``y`` at time ``t`` [s]."""
    t0, t1 = d.ranges.torsion_start, d.ranges.torsion_end
    _, quill = station_spin(d, t, y, 0, 0.0)
    torque = 0.0
    for j in range(t0, t1):
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
    quill, surface = _top_motion(d, t, y)
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


def _is(numba_type, cls) -> bool:
    return isinstance(numba_type, types.BaseNamedTuple) and numba_type.instance_class is cls
