"""The reduced-order model (ROM) of the drill-string and its right-hand side (SPEC §6–§7).

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
stays equal to the static weight-on-hook, SPEC §7). The top rotation is imposed:
``θx(x, t) = Ω t + (Φ η)_θx``, so the total spin speed is ``Ω + (Φ η̇)_θx``.

``f_NL`` (case 2, ``nonlinear = "bit_and_contact"``) is the Tucker–Wang bit–rock force and torque at
the bit node and the borehole shocks and rubbing at every node, evaluated in physical DOFs and
projected. The right-hand side is a Numba-compiled kernel over preallocated arrays; every compiled
kernel takes one structured argument (:class:`RhsData`, :class:`FullModelData`, :class:`ObserveData`,
named tuples built once by :class:`ReducedOrderModel`), and :func:`evaluate_rhs` picks the case-1 or
case-2 kernel by the type of that argument when it is compiled.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import overload

from drillstring.damping import reduced_structural_damping
from drillstring.fem.dofs import THETA_X, THETA_Y, THETA_Z, U, V, W, dof
from drillstring.forces.bit_rock import (
    BitRockParameters,
    bit_rock_force_floored,
    evaluate_bit_rock,
    stick_speed_floor_ratio,
)
from drillstring.forces.contact import ContactParameters, contact_forces, evaluate_contact
from drillstring.forces.nonlinear import (
    NonlinearElements,
    _kinetic_forces_kernel,
    _strain_energy_forces_kernel,
    contract_mass_tensor,
    modal_mass_tensor,
    nonlinear_elements,
)
from drillstring.modal import LinearSystem, Modes, case_linear_system, compute_modes
from drillstring.statics import StaticState, case_static_state

#: Order of the observables returned by :meth:`ReducedOrderModel.observe` before the probes.
OBSERVABLES = (
    "rate_of_penetration",  # m/s, u̇ at the bit
    "bit_speed",  # rad/s, θ̇x at the bit
    "torque_on_bit",  # N·m, torque the rock applies against the rotation (−t_xbit)
    "force_on_bit",  # N, axial force of the rock on the bit, upward positive (−f_xbit)
    "bit_depth",  # m, bit displacement from the static state (advance of the bit)
    "nodes_in_contact",  # number of nodes touching the borehole
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
#: First column of the probes' radial displacements.
PROBE_COLUMN = len(OBSERVABLES)


#: Let Numba reassociate sums (SIMD dot products) but keep IEEE NaN/inf semantics, so divergence
#: is still detected. Deterministic for a given build: same results for any worker count.
VECTOR_MATH = {"reassoc", "contract"}


# ---------------------------------------------------------------------------------------------------------
# Kernel data: everything a compiled kernel reads, built once per model by ReducedOrderModel
# ---------------------------------------------------------------------------------------------------------


class ContactWork(NamedTuple):
    """Scratch arrays of the contact search, one entry per node (the first ``n_c`` used)."""

    v: np.ndarray  # (n_nodes,) lateral displacement v [m]
    w: np.ndarray  # (n_nodes,) lateral displacement w [m]
    nodes: np.ndarray  # (n_nodes,) int64, indices of the nodes in contact
    v_c: np.ndarray  # the same quantities at the nodes in contact ...
    w_c: np.ndarray
    v_dot: np.ndarray
    w_dot: np.ndarray
    spin: np.ndarray
    gap: np.ndarray
    outer_diameter: np.ndarray
    force_v: np.ndarray  # ... and the contact forces [N] and torque [N·m] there
    force_w: np.ndarray
    torque: np.ndarray

    @classmethod
    def allocate(cls, n_nodes: int) -> ContactWork:
        return cls(*(np.zeros(n_nodes, dtype=np.int64 if name == "nodes" else np.float64)
                     for name in cls._fields))


class RhsData(NamedTuple):
    """What the case-2 right-hand side reads (SI units). Each physical quantity is read from its own
    mode family only: ``blocks`` = [axial start, end, torsional start, end, lateral y start, end,
    lateral z start, end] column ranges; ``bit_u``, ``bit_t`` hold only their family's columns and
    ``phi_v_t``, ``phi_w_t``, ``phi_tx_t`` (family columns × nodes) and ``damping_t`` are stored
    transposed so that products run column by column."""

    omega2: np.ndarray  # (n,) signed ω² [1/s²]
    damping_t: np.ndarray  # (n, n) Dᵀ [1/s]
    damping_blocks: np.ndarray  # (k, 2) int64: diagonal blocks [start, end) holding every nonzero of D
    generalized_force: np.ndarray  # (n,) constant modal force added to the modal acceleration
    blocks: np.ndarray  # (8,) int64
    bit_u: np.ndarray  # axial mode shapes at the bit's u
    bit_t: np.ndarray  # torsional mode shapes at the bit's θx
    phi_v_t: np.ndarray  # lateral-y shapes (v at every node)
    phi_w_t: np.ndarray  # lateral-z shapes (w at every node)
    phi_tx_t: np.ndarray  # torsional shapes (θx at every node)
    gap: np.ndarray  # (n_nodes,) radial gap [m]
    smallest_gap: float  # min(gap) [m]
    lateral_shape_max: np.ndarray  # max over nodes of |φ_v| (lateral y columns), then |φ_w| (z columns)
    outer_diameter: np.ndarray  # (n_nodes,) [m]
    top_speed: float  # Ω [rad/s]
    weight_on_bit: float  # static bit reaction [N]
    bit_rock: np.ndarray  # (7,) arguments of bit_rock_force_floored after the speeds
    contact: np.ndarray  # (3,) k_sh [N/m], μ [-], speed regularization [rad/s]
    tangential: bool  # tangential friction of the contact
    work: ContactWork


class FullModelData(NamedTuple):
    """What the case-1 right-hand side reads in addition to the case-2 data (``rhs``): the basis, the
    element data of :class:`~drillstring.forces.nonlinear.NonlinearElements`, the modal mass tensor,
    and scratch arrays."""

    rhs: RhsData
    basis: np.ndarray  # (n_dofs, n) Φ
    basis_t: np.ndarray  # (n, n_dofs) Φᵀ
    theta_x_dofs: np.ndarray  # int64, the θx DOF of every node
    inv_length: np.ndarray
    xi: np.ndarray
    weights: np.ndarray
    slope: np.ndarray
    rotation: np.ndarray
    axial_stiffness: np.ndarray
    polar_inertia: np.ndarray
    mass_tensor: np.ndarray  # (k, n, n), see modal_mass_tensor
    active: np.ndarray  # (k,) int64
    q: np.ndarray  # (n_dofs,) scratch: q̄ = Φη
    qd: np.ndarray  # (n_dofs,) scratch: q̇
    f_se: np.ndarray  # (n_dofs,) scratch
    f_vel: np.ndarray  # (n_dofs,) scratch
    coupling: np.ndarray  # (n_el, 2, 4) scratch
    mass: np.ndarray  # (n, n) scratch: I + Φᵀ M_nl Φ
    acceleration: np.ndarray  # (n,) scratch


class ObserveData(NamedTuple):
    """What the observation kernel reads besides the right-hand-side data, and fills."""

    probe_nodes: np.ndarray  # (n_probes,) int64
    v: np.ndarray  # (n_nodes,) scratch
    w: np.ndarray  # (n_nodes,) scratch
    in_contact: np.ndarray  # (n_nodes,) bool: which nodes touch the borehole (filled)


# ---------------------------------------------------------------------------------------------------------
# Kernels
# ---------------------------------------------------------------------------------------------------------


@njit(cache=True, fastmath=VECTOR_MATH)
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


@njit(cache=True)
def _block_damping(damping_t, blocks, velocity, out):
    """out −= D velocity, D block diagonal (``blocks`` from :func:`diagonal_blocks`, ``damping_t`` = Dᵀ)."""
    for b in range(blocks.shape[0]):
        start, end = blocks[b, 0], blocks[b, 1]
        for j in range(start, end):
            x = velocity[j]
            if x != 0.0:
                for i in range(start, end):
                    out[i] -= damping_t[j, i] * x


@njit(cache=True)
def _columns_matvec(matrix_t, vector, offset, out, sign):
    """out (+)= sign · matrix @ vector[offset:] given ``matrix_t`` = matrixᵀ (C order): column by
    column, so the inner loop is contiguous and vectorises without reassociating sums."""
    for j in range(matrix_t.shape[0]):
        x = sign * vector[offset + j]
        if x != 0.0:
            for i in range(matrix_t.shape[1]):
                out[i] += matrix_t[j, i] * x


@njit(cache=True)
def _bit_motion(d, y):
    """Axial velocity [m/s] and spin speed [rad/s] of the bit for the state ``y`` = [η, η̇]."""
    n = d.omega2.shape[0]
    a0, a1, t0, t1 = d.blocks[0], d.blocks[1], d.blocks[2], d.blocks[3]
    bit_velocity = 0.0
    for j in range(a0, a1):
        bit_velocity += d.bit_u[j - a0] * y[n + j]
    bit_speed = d.top_speed
    for j in range(t0, t1):
        bit_speed += d.bit_t[j - t0] * y[n + j]
    return bit_velocity, bit_speed


@njit(cache=True)
def _bit_rock(d, bit_velocity, bit_speed):
    b = d.bit_rock
    return bit_rock_force_floored(bit_velocity, bit_speed, b[0], b[1], b[2], b[3], b[4], b[5], b[6])


@njit(cache=True)
def _lateral_displacements(d, y, v, w):
    """v and w [m] at every node for the state ``y``."""
    v[:] = 0.0
    w[:] = 0.0
    _columns_matvec(d.phi_v_t, y, d.blocks[4], v, 1.0)
    _columns_matvec(d.phi_w_t, y, d.blocks[6], w, 1.0)


@njit(cache=True)
def _surely_clear(d, eta):
    """True when no node can touch the borehole: r_i ≤ |v_i| + |w_i| ≤ Σ_j (max_i |φ_ij|) |η_j| over
    both lateral families (triangle inequality) is below the smallest gap. Costs one pass over the
    lateral coordinates instead of the mode shapes at every node."""
    bound = 0.0
    for j in range(d.blocks[4], d.blocks[5]):
        bound += d.lateral_shape_max[j - d.blocks[4]] * abs(eta[j])
    offset = d.blocks[5] - d.blocks[4]
    for j in range(d.blocks[6], d.blocks[7]):
        bound += d.lateral_shape_max[offset + j - d.blocks[6]] * abs(eta[j])
    return bound < d.smallest_gap


@njit(cache=True)
def _rhs_kernel(d, y, out):
    """dy/dt of the case-2 ROM (module docstring) from :class:`RhsData` ``d``; contact work is done only
    at the nodes that touch the borehole."""
    n = d.omega2.shape[0]
    a0, a1, t0, t1, y0, y1, z0, z1 = (d.blocks[0], d.blocks[1], d.blocks[2], d.blocks[3], d.blocks[4],
                                      d.blocks[5], d.blocks[6], d.blocks[7])
    eta = y[:n]
    eta_dot = y[n:]
    acc = out[n:]
    # linear part: -D η̇ - ω² η + the constant generalized force (D dense only where the fluid couples)
    for i in range(n):
        out[i] = eta_dot[i]
        acc[i] = d.generalized_force[i] - d.omega2[i] * eta[i]
    _block_damping(d.damping_t, d.damping_blocks, eta_dot, acc)
    # bit-rock interaction at the bit node
    bit_velocity, bit_speed = _bit_motion(d, y)
    axial_force, bit_torque = _bit_rock(d, bit_velocity, bit_speed)
    axial_force += d.weight_on_bit
    for j in range(a0, a1):
        acc[j] += d.bit_u[j - a0] * axial_force
    for j in range(t0, t1):
        acc[j] += d.bit_t[j - t0] * bit_torque
    # shocks and rubbing: find the nodes outside the gap
    if y1 == y0 and z1 == z0:
        return
    if _surely_clear(d, eta):
        return
    c = d.work
    _lateral_displacements(d, eta, c.v, c.w)
    n_c = 0
    for i in range(c.v.shape[0]):
        if c.v[i] * c.v[i] + c.w[i] * c.w[i] > d.gap[i] * d.gap[i]:
            c.nodes[n_c] = i
            n_c += 1
    if n_c == 0:
        return
    for k in range(n_c):
        i = c.nodes[k]
        c.v_c[k] = c.v[i]
        c.w_c[k] = c.w[i]
        c.gap[k] = d.gap[i]
        c.outer_diameter[k] = d.outer_diameter[i]
        spin = d.top_speed
        for j in range(t0, t1):
            spin += d.phi_tx_t[j - t0, i] * eta_dot[j]
        c.spin[k] = spin
        vd = 0.0
        wd = 0.0
        if d.tangential:
            for j in range(y0, y1):
                vd += d.phi_v_t[j - y0, i] * eta_dot[j]
            for j in range(z0, z1):
                wd += d.phi_w_t[j - z0, i] * eta_dot[j]
        c.v_dot[k] = vd
        c.w_dot[k] = wd
    contact_forces(c.v_c[:n_c], c.w_c[:n_c], c.v_dot[:n_c], c.w_dot[:n_c], c.spin[:n_c], c.gap[:n_c],
                   c.outer_diameter[:n_c], d.contact[0], d.contact[1], d.contact[2], d.tangential,
                   c.force_v[:n_c], c.force_w[:n_c], c.torque[:n_c])
    for k in range(n_c):
        i = c.nodes[k]
        for j in range(y0, y1):
            acc[j] += d.phi_v_t[j - y0, i] * c.force_v[k]
        for j in range(z0, z1):
            acc[j] += d.phi_w_t[j - z0, i] * c.force_w[k]
        for j in range(t0, t1):
            acc[j] += d.phi_tx_t[j - t0, i] * c.torque[k]


@njit(cache=True)
def _cholesky_solve(a, b, x):
    """x = a⁻¹ b for a symmetric positive definite ``a`` (n, n), by Cholesky ``a = L Lᵀ`` computed in the
    lower triangle of ``a`` (overwritten). The case-1 mass ``I + Φᵀ M_nl Φ`` is positive definite wherever
    the model holds (:mod:`drillstring.forces.nonlinear`); elsewhere (a non-positive pivot) ``x`` is NaN,
    which the integrator treats as a rejected step. Compiled loops instead of ``np.linalg.solve``: no
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
def _rhs_full_kernel(f, y, out):
    """Case 1 from :class:`FullModelData` ``f``: the case-2 right-hand side plus the strain- and
    kinetic-energy forces f_se and f_ke (:mod:`drillstring.forces.nonlinear`), evaluated on the physical
    state ``q̄ = Φη``, ``q̇ = Φη̇ + Ω`` (θx DOFs), projected on the basis. ``f_ke = f_vel − M_nl(q) q̈``:
    the configuration-dependent mass correction is moved to the left-hand side and
    ``(I + Φᵀ M_nl(Φη) Φ) η̈ = …`` is solved at every evaluation (exact, no lagged accelerations)."""
    _rhs_kernel(f.rhs, y, out)
    n = f.basis.shape[1]
    eta = y[:n]
    f.q[:] = 0.0
    f.qd[:] = 0.0
    _columns_matvec(f.basis_t, y, 0, f.q, 1.0)
    _columns_matvec(f.basis_t, y, n, f.qd, 1.0)
    for i in range(f.theta_x_dofs.shape[0]):
        f.qd[f.theta_x_dofs[i]] += f.rhs.top_speed
    _strain_energy_forces_kernel(f.q, f.inv_length, f.weights, f.slope, f.axial_stiffness, f.f_se)
    _kinetic_forces_kernel(f.q, f.qd, f.xi, f.weights, f.rotation, f.polar_inertia, f.f_vel, f.coupling)
    for i in range(f.f_se.shape[0]):
        f.f_se[i] += f.f_vel[i]
    acc = f.acceleration
    _matvec(f.basis_t, f.f_se, 0, acc)
    for i in range(n):
        acc[i] += out[n + i]
    contract_mass_tensor(f.mass_tensor, f.active, eta, f.mass)
    for i in range(n):
        f.mass[i, i] += 1.0
    _cholesky_solve(f.mass, acc, out[n:])


def evaluate_rhs(data, y, out):
    """dy/dt of the ROM for the state ``y`` written into ``out``: case 2 for :class:`RhsData`, case 1 for
    :class:`FullModelData`. Callable from Python and from compiled code, where it is resolved by the type
    of ``data`` at compile time, so a case-2 run never compiles the case-1 kernel."""
    if isinstance(data, FullModelData):
        _rhs_full_kernel(data, y, out)
    else:
        _rhs_kernel(data, y, out)


def _is(numba_type, cls) -> bool:
    return isinstance(numba_type, types.BaseNamedTuple) and numba_type.instance_class is cls


@overload(evaluate_rhs)
def _evaluate_rhs_compiled(data, y, out):
    if _is(data, FullModelData):
        return lambda data, y, out: _rhs_full_kernel(data, y, out)
    if _is(data, RhsData):
        return lambda data, y, out: _rhs_kernel(data, y, out)
    return None


@njit(cache=True)
def _observe_kernel(d, o, y, out):
    """Observables (:data:`OBSERVABLES`, by their columns) and the radial displacement at the probes for
    the state ``y``, from the case-2 data ``d`` (:class:`RhsData`) and ``o`` (:class:`ObserveData`, whose
    contact mask it fills). Returns the number of nodes in contact."""
    bit_velocity, bit_speed = _bit_motion(d, y)
    axial_force, bit_torque = _bit_rock(d, bit_velocity, bit_speed)
    _lateral_displacements(d, y, o.v, o.w)
    count = 0
    for i in range(o.v.shape[0]):
        touching = o.v[i] * o.v[i] + o.w[i] * o.w[i] > d.gap[i] * d.gap[i]
        o.in_contact[i] = touching
        count += touching
    depth = 0.0
    a0, a1 = d.blocks[0], d.blocks[1]
    for j in range(a0, a1):
        depth += d.bit_u[j - a0] * y[j]
    out[_ROP] = bit_velocity
    out[_BIT_SPEED] = bit_speed
    out[_TOB] = -bit_torque
    out[_FOB] = -axial_force
    out[_DEPTH] = depth
    out[_CONTACTS] = count
    for k in range(o.probe_nodes.shape[0]):
        j = o.probe_nodes[k]
        out[PROBE_COLUMN + k] = np.sqrt(o.v[j] * o.v[j] + o.w[j] * o.w[j])
    return count


@dataclass
class ReducedOrderModel:
    """Modal model of one drilling configuration (SI units).

    Attributes:
        angular_frequencies: ω of each basis vector [rad/s] (0 for the rigid axial mode).
        damping: reduced damping matrix (modal + rigid + fluid) [1/s].
        basis: Φ, (n_dofs, n) global mode shapes.
        family: family label of each basis vector.
        probe_positions: x of the radial-displacement probes [m].
        generalized_force: (n,) constant generalized force added to the modal acceleration
            [N/√kg per unit modal mass, i.e. the right-hand side of η̈ = …]; ``None`` means zeros.

    Built from them: ``rhs_data`` (:class:`RhsData` for case 2, :class:`FullModelData` for case 1)
    and ``observe_data`` (:class:`ObserveData`), the one structured argument of each compiled kernel,
    shared by :meth:`rhs`, :meth:`observe` and the compiled integrator.
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
    bit_rock: BitRockParameters
    contact: ContactParameters
    gap: np.ndarray
    outer_diameter: np.ndarray
    probe_positions: np.ndarray
    nonlinear: str = "bit_and_contact"
    generalized_force: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.nonlinear not in ("bit_and_contact", "full"):
            raise ValueError(f"nonlinear = {self.nonlinear!r}: must be 'bit_and_contact' or 'full'")
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
        self.omega2 = np.ascontiguousarray(np.sign(self.angular_frequencies) * self.angular_frequencies**2)
        self.bit_u = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, U)])
        self.bit_t = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, THETA_X)])
        self.phi_v = np.ascontiguousarray(phi[dof(nodes, V)])
        self.phi_w = np.ascontiguousarray(phi[dof(nodes, W)])
        self.phi_tx = np.ascontiguousarray(phi[dof(nodes, THETA_X)])
        self.probe_nodes = np.array([mesh.node_index(x) for x in self.probe_positions], dtype=np.int64)
        labels = np.array(self.family)
        blocks = []
        for names in (("rigid_axial", "axial"), ("torsional",), ("lateral_y",), ("lateral_z",)):
            columns = np.nonzero(np.isin(labels, names))[0]
            start = int(columns[0]) if len(columns) else 0
            end = int(columns[-1]) + 1 if len(columns) else 0
            if len(columns) and not np.array_equal(columns, np.arange(start, end)):
                raise ValueError("mode families must be contiguous in the basis")
            blocks += [start, end]
        self.blocks = np.array(blocks, dtype=np.int64)
        a0, a1, t0, t1, y0, y1, z0, z1 = blocks
        c = self.contact
        transposed = np.ascontiguousarray
        self.case2_data = RhsData(
            omega2=self.omega2,
            damping_t=transposed(self.damping.T),
            damping_blocks=diagonal_blocks(self.damping),
            generalized_force=self.generalized_force,
            blocks=self.blocks,
            bit_u=transposed(self.bit_u[a0:a1]),
            bit_t=transposed(self.bit_t[t0:t1]),
            phi_v_t=transposed(self.phi_v[:, y0:y1].T),
            phi_w_t=transposed(self.phi_w[:, z0:z1].T),
            phi_tx_t=transposed(self.phi_tx[:, t0:t1].T),
            gap=np.ascontiguousarray(self.gap, dtype=float),
            smallest_gap=float(np.min(self.gap)),
            lateral_shape_max=np.concatenate([np.abs(self.phi_v[:, y0:y1]).max(axis=0, initial=0.0),
                                              np.abs(self.phi_w[:, z0:z1]).max(axis=0, initial=0.0)]),
            outer_diameter=np.ascontiguousarray(self.outer_diameter, dtype=float),
            top_speed=float(self.top_speed),
            weight_on_bit=float(self.weight_on_bit),
            bit_rock=np.array(self.bit_rock.kernel_args(), dtype=float),
            contact=np.array([c.shock_stiffness, c.friction_coefficient, c.speed_regularization],
                             dtype=float),
            tangential=bool(c.tangential_friction),
            work=ContactWork.allocate(mesh.n_nodes),
        )
        self.observe_data = ObserveData(
            probe_nodes=self.probe_nodes, v=np.zeros(mesh.n_nodes), w=np.zeros(mesh.n_nodes),
            in_contact=np.zeros(mesh.n_nodes, dtype=np.bool_),
        )
        self.full = self.nonlinear == "full"
        self.rhs_data: RhsData | FullModelData = (
            self._full_model_data(self.case2_data) if self.full else self.case2_data)

    def _full_model_data(self, case2: RhsData) -> FullModelData:
        mesh = self.static.mesh
        self.elements: NonlinearElements = nonlinear_elements(mesh)
        basis = np.ascontiguousarray(self.basis)
        active, tensor = modal_mass_tensor(self.elements, basis, tol=1e-14)
        e = self.elements
        n_dofs, n = basis.shape
        c = np.ascontiguousarray
        return FullModelData(
            rhs=case2, basis=basis, basis_t=c(basis.T),
            theta_x_dofs=dof(np.arange(mesh.n_nodes), THETA_X).astype(np.int64),
            inv_length=c(e.inv_length, dtype=float), xi=c(e.xi, dtype=float),
            weights=c(e.weights, dtype=float), slope=c(e.slope, dtype=float),
            rotation=c(e.rotation, dtype=float), axial_stiffness=c(e.axial_stiffness, dtype=float),
            polar_inertia=c(e.polar_inertia, dtype=float), mass_tensor=c(tensor, dtype=float),
            active=c(active, dtype=np.int64), q=np.zeros(n_dofs), qd=np.zeros(n_dofs),
            f_se=np.zeros(n_dofs), f_vel=np.zeros(n_dofs), coupling=np.zeros((e.n_elements, 2, 4)),
            mass=np.zeros((n, n)), acceleration=np.zeros(n),
        )

    @property
    def size(self) -> int:
        """Number of modal coordinates n (the state has 2n entries)."""
        return len(self.angular_frequencies)

    @property
    def observable_names(self) -> tuple[str, ...]:
        return OBSERVABLES

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt for y = [η, η̇] (t enters only through the imposed top rotation, which drops out)."""
        out = np.empty_like(y)
        evaluate_rhs(self.rhs_data, y, out)
        return out

    def rhs_reference(self, t: float, y: np.ndarray) -> np.ndarray:
        """The straightforward NumPy right-hand side (full basis, every node): the reference
        implementation that the compiled :meth:`rhs` is tested against; same equations."""
        n = self.size
        eta, eta_dot = y[:n], y[n:]
        bit_velocity = self.bit_u @ eta_dot
        bit_speed = self.top_speed + self.bit_t @ eta_dot
        axial_force, bit_torque = evaluate_bit_rock(bit_velocity, bit_speed, self.bit_rock)
        force_v, force_w, torque, _ = evaluate_contact(
            self.phi_v @ eta, self.phi_w @ eta, self.phi_v @ eta_dot, self.phi_w @ eta_dot,
            self.top_speed + self.phi_tx @ eta_dot, self.gap, self.outer_diameter, self.contact,
        )
        generalized = (self.phi_v.T @ force_v + self.phi_w.T @ force_w + self.phi_tx.T @ torque
                       + self.bit_u * (axial_force + self.weight_on_bit) + self.bit_t * bit_torque
                       + self.generalized_force)
        acceleration = generalized - self.damping @ eta_dot - self.omega2 * eta
        if self.nonlinear == "full":
            q = self.basis @ eta
            qd = self.basis @ eta_dot
            qd[dof(np.arange(self.static.mesh.n_nodes), THETA_X)] += self.top_speed
            f_se = self.elements.strain_energy_forces(q, np.zeros_like(q))
            f_vel = np.zeros_like(q)
            self.elements.kinetic_forces(q, qd, f_vel)
            mass_nl = self.elements.mass_correction_matrix(q)
            mass = np.eye(self.size) + self.basis.T @ (mass_nl @ self.basis)
            acceleration = np.linalg.solve(mass, acceleration + self.basis.T @ (f_se + f_vel))
        return np.concatenate([eta_dot, acceleration])

    def observe(self, t: float, y: np.ndarray) -> np.ndarray:
        """Observables (:data:`OBSERVABLES`) followed by the radial displacement at each probe [m]."""
        out = np.empty(PROBE_COLUMN + len(self.probe_nodes))
        _observe_kernel(self.case2_data, self.observe_data, np.ascontiguousarray(y, dtype=float), out)
        return out

    def contact_mask(self) -> np.ndarray:
        """Nodes in contact at the last :meth:`observe` call (a copy)."""
        return self.observe_data.in_contact.copy()

    def initial_state(self, lateral_perturbation: float, seed: int) -> np.ndarray:
        """Initial state (SPEC §7): the static state, the whole string spinning at Ω, zero axial
        speed (η̇ = 0), plus a seeded lateral perturbation defined physically, independent of the
        basis: ``v0(x) = Σ_k a_k sin(kπx/L)/k²``, ``w0`` likewise with ``b_k``, k = 1…10,
        ``a_k, b_k`` standard normal from ``numpy.random.default_rng(seed)``, scaled so that the largest
        radial displacement along the string is ``lateral_perturbation`` [m]; it is projected on the
        lateral modes (mass-orthogonal projection ``η0 = Φᵀ(M + M_f) q0``), so it converges to the
        physical shape as lateral modes are added."""
        y0 = np.zeros(2 * self.size)
        lateral = np.array([f.startswith("lateral") for f in self.family])
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
        y0[: self.size] = np.where(lateral, eta0, 0.0)
        return y0

    def energy(self, y: np.ndarray) -> float:
        """Linear mechanical energy ½ η̇ᵀη̇ + ½ Σ ω² η² [J] (conserved without damping and forcing)."""
        n = self.size
        return 0.5 * float(y[n:] @ y[n:] + self.omega2 @ (y[:n] ** 2))


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
    bit_rock: BitRockParameters,
    contact: ContactParameters,
    borehole_diameter: float,
    rigid_rotation_damping: float = 0.0,
    damping_basis: str = "free_free",
    probe_positions=(),
    nonlinear: str = "bit_and_contact",
) -> ReducedOrderModel:
    """Project the prestressed system on its modes (``axial_modes`` elastic + the rigid one).

    Args:
        modal_damping_ratio: ξ [-]; rigid_axial_damping: c1 [N·s/m], viscous resistance to the
            rigid axial motion; rigid_rotation_damping: c2 [N·m·s/rad], to the rigid rotation.
        damping_basis: "free_free" (ξ, c1, c2 on the free–free modes) or "constrained" (ξ on every
            basis mode); see :mod:`drillstring.damping`.
        top_speed: Ω [rad/s].
        borehole_diameter: D_ch [m].
    """
    modes = compute_modes(system, axial_modes + 1, torsional_modes, lateral_modes)
    families = [modes.axial, modes.torsional, modes.lateral_y, modes.lateral_z]
    basis = np.hstack([f.shapes for f in families])
    omega = np.concatenate([f.angular_frequencies for f in families])
    family = ["rigid_axial"] + ["axial"] * axial_modes
    family += ["torsional"] * torsional_modes + ["lateral_y"] * lateral_modes + ["lateral_z"] * lateral_modes
    structural = reduced_structural_damping(
        system.mass, system.stiffness, basis, family, omega, damping_ratio=modal_damping_ratio,
        rigid_axial=rigid_axial_damping, rigid_rotation=rigid_rotation_damping, top_speed=top_speed,
        definition=damping_basis,
    )
    damping = basis.T @ (system.fluid_damping @ basis) + structural.matrix
    mesh = static.mesh
    node_sections = mesh.node_section()
    outer = np.array([mesh.sections[i].outer_diameter for i in node_sections])
    return ReducedOrderModel(
        static=static, system=system, modes=modes, basis=basis, family=tuple(family),
        angular_frequencies=omega, damping=damping, top_speed=top_speed,
        weight_on_bit=static.weight_on_bit, bit_rock=bit_rock, contact=contact,
        gap=(borehole_diameter - outer) / 2.0, outer_diameter=outer,
        probe_positions=np.asarray(probe_positions, dtype=float),
        nonlinear=nonlinear, generalized_force=structural.generalized_force,
    )


def case_reduced_model(
    case,
    *,
    weight_on_bit: float | None = None,
    axial_modes: int | None = None,
    torsional_modes: int | None = None,
    lateral_modes: int | None = None,
    static: StaticState | None = None,
    nonlinear: str | None = None,
) -> ReducedOrderModel:
    """The ROM of a :class:`~drillstring.case.Case`; keyword arguments override the case's values
    (``nonlinear``: "bit_and_contact" = case 2, "full" = case 1, default the case's ``model.nonlinear``)."""
    static = case_static_state(case, weight_on_bit) if static is None else static
    system = case_linear_system(case, static)
    r = case.reduced_model
    b = case.bit_rock
    c = case.contact
    return reduced_model(
        static,
        system,
        axial_modes=r.axial_modes if axial_modes is None else axial_modes,
        torsional_modes=r.torsional_modes if torsional_modes is None else torsional_modes,
        lateral_modes=r.lateral_modes if lateral_modes is None else lateral_modes,
        modal_damping_ratio=case.damping.modal_damping_ratio,
        rigid_axial_damping=case.damping.rigid_axial,
        rigid_rotation_damping=case.damping.rigid_rotation,
        damping_basis=case.damping.basis,
        top_speed=case.operation.top_speed,
        bit_rock=BitRockParameters(
            b.a1, b.a2, b.a3, b.a4, b.a5, b.regularization,
            stick_speed_floor_ratio(b.regularization, case.operation.top_speed, b.stick_stiffening_limit),
        ),
        contact=ContactParameters(c.shock_stiffness, c.friction_coefficient, c.speed_regularization,
                                  c.tangential_friction),
        borehole_diameter=case.borehole.diameter,
        probe_positions=case.mesh.probes,
        nonlinear=case.model.nonlinear if nonlinear is None else nonlinear,
    )
