"""The reduced-order model (ROM) of the drill-string and its right-hand side (SPEC §6–§7).

The response about the prestressed static state, ``q = q_S + q̄``, is projected on mass-normalised
normal modes of the prestressed linear system (:mod:`drillstring.modal`):
``q̄ = Φ η``, ``Φᵀ (M + M_f) Φ = I``, ``Φᵀ (K + K_g + K_f) Φ = diag(ω²)``. The basis holds the rigid
axial translation, ``n_a`` elastic axial modes, ``n_t`` torsional modes (top fixed) and ``n_l``
lateral modes in each plane. The reduced equations are

    η̈ + (D + Φᵀ C_f Φ) η̇ + diag(ω²) η = Φᵀ (f_NL(q, q̇) + wob e_bit,u) + g

where ``D`` is the structural damping and ``g`` the constant generalised force of the damping of the
imposed top rotation (:mod:`drillstring.damping`: by default ξ, c1 and c2 defined on the free–free
modes, giving a dense torsional block; or ``2 ξ ω_i`` on every basis mode), ``C_f`` the fluid
(Coriolis + viscous) damping, and ``wob e_bit,u`` removes the static bit reaction that ``q_S``
already balances (the hook force stays equal to the static weight-on-hook, SPEC §7). The top rotation
is imposed: ``θx(x, t) = Ω t + (Φ η)_θx``, so the total spin speed is ``Ω + (Φ η̇)_θx``.

``f_NL`` (case 2, ``nonlinear = "bit_and_contact"``) is the Tucker–Wang bit–rock force and torque at
the bit node and the borehole shocks and rubbing at every node, evaluated in physical DOFs and
projected. The right-hand side is a Numba-compiled kernel over preallocated arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from drillstring.damping import reduced_structural_damping
from drillstring.fem.assembly import THETA_X, THETA_Y, THETA_Z, U, V, W, dof
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


#: Let Numba reassociate sums (SIMD dot products) but keep IEEE NaN/inf semantics, so divergence
#: is still detected. Deterministic for a given build: same results for any worker count.
VECTOR_MATH = {"reassoc", "contract"}


@njit(cache=True, fastmath=VECTOR_MATH)
def _matvec(matrix, vector, offset, out):
    """out = matrix @ vector[offset:offset + matrix.shape[1]] with compiled loops (no BLAS, so no
    thread oversubscription when several worker processes run)."""
    for i in range(matrix.shape[0]):
        total = 0.0
        for j in range(matrix.shape[1]):
            total += matrix[i, j] * vector[offset + j]
        out[i] = total


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
def _physical_state(y, n, top_speed, bit_u, bit_t, phi_v, phi_w, phi_tx, v, w, v_dot, w_dot, spin):
    """Lateral displacements/velocities and spin speed at every node from modal state ``y``."""
    _matvec(phi_v, y, 0, v)
    _matvec(phi_w, y, 0, w)
    _matvec(phi_v, y, n, v_dot)
    _matvec(phi_w, y, n, w_dot)
    _matvec(phi_tx, y, n, spin)
    for i in range(spin.shape[0]):
        spin[i] += top_speed
    bit_velocity = 0.0
    bit_speed = top_speed
    for j in range(n):
        bit_velocity += bit_u[j] * y[n + j]
        bit_speed += bit_t[j] * y[n + j]
    return bit_velocity, bit_speed


@njit(cache=True)
def _rhs_kernel(
    y, out, omega2, damping, generalized_force, blocks, bit_u, bit_t, phi_v, phi_w, phi_tx, gap, outer_diameter,
    top_speed, weight_on_bit, bit_args, contact_args, tangential,
    v, w, contact_nodes, c_v, c_w, c_vd, c_wd, c_spin, c_gap, c_od, c_fv, c_fw, c_tq,
):
    """dy/dt of the ROM. Each physical quantity is read from its own mode family only
    (``blocks`` = [axial start, end, torsional start, end, lateral y start, end, lateral z start,
    end] column ranges; ``bit_u``, ``bit_t``, ``phi_v``, ``phi_w``, ``phi_tx`` hold only those
    columns, the last three and ``damping`` stored transposed so products run column by column),
    and contact work is done only at the nodes that touch the borehole."""
    n = omega2.shape[0]
    a0, a1, t0, t1, y0, y1, z0, z1 = blocks[0], blocks[1], blocks[2], blocks[3], blocks[4], blocks[5], blocks[6], blocks[7]
    eta = y[:n]
    eta_dot = y[n:]
    acc = out[n:]
    # linear part: -D η̇ - ω² η  (D: dense only where the fluid couples lateral modes)
    for i in range(n):
        out[i] = eta_dot[i]
        acc[i] = generalized_force[i] - omega2[i] * eta[i]
    _columns_matvec(damping, eta_dot, 0, acc, -1.0)  # ``damping`` holds Dᵀ
    # bit-rock interaction at the bit node
    bit_velocity = 0.0
    for j in range(a0, a1):
        bit_velocity += bit_u[j - a0] * eta_dot[j]
    bit_speed = top_speed
    for j in range(t0, t1):
        bit_speed += bit_t[j - t0] * eta_dot[j]
    axial_force, bit_torque = bit_rock_force_floored(
        bit_velocity, bit_speed, bit_args[0], bit_args[1], bit_args[2], bit_args[3], bit_args[4],
        bit_args[5], bit_args[6],
    )
    axial_force += weight_on_bit
    for j in range(a0, a1):
        acc[j] += bit_u[j - a0] * axial_force
    for j in range(t0, t1):
        acc[j] += bit_t[j - t0] * bit_torque
    # shocks and rubbing: find the nodes outside the gap
    n_nodes = v.shape[0]
    if y1 == y0 and z1 == z0:
        return
    v[:] = 0.0
    w[:] = 0.0
    _columns_matvec(phi_v, eta, y0, v, 1.0)  # phi_v, phi_w, phi_tx are stored transposed
    _columns_matvec(phi_w, eta, z0, w, 1.0)
    n_c = 0
    for i in range(n_nodes):
        if v[i] * v[i] + w[i] * w[i] > gap[i] * gap[i]:
            contact_nodes[n_c] = i
            n_c += 1
    if n_c == 0:
        return
    for c in range(n_c):
        i = contact_nodes[c]
        c_v[c] = v[i]
        c_w[c] = w[i]
        c_gap[c] = gap[i]
        c_od[c] = outer_diameter[i]
        spin = top_speed
        for j in range(t0, t1):
            spin += phi_tx[j - t0, i] * eta_dot[j]
        c_spin[c] = spin
        vd = 0.0
        wd = 0.0
        if tangential:
            for j in range(y0, y1):
                vd += phi_v[j - y0, i] * eta_dot[j]
            for j in range(z0, z1):
                wd += phi_w[j - z0, i] * eta_dot[j]
        c_vd[c] = vd
        c_wd[c] = wd
    contact_forces(c_v[:n_c], c_w[:n_c], c_vd[:n_c], c_wd[:n_c], c_spin[:n_c], c_gap[:n_c],
                   c_od[:n_c], contact_args[0], contact_args[1], contact_args[2], tangential,
                   c_fv[:n_c], c_fw[:n_c], c_tq[:n_c])
    for c in range(n_c):
        i = contact_nodes[c]
        for j in range(y0, y1):
            acc[j] += phi_v[j - y0, i] * c_fv[c]
        for j in range(z0, z1):
            acc[j] += phi_w[j - z0, i] * c_fw[c]
        for j in range(t0, t1):
            acc[j] += phi_tx[j - t0, i] * c_tq[c]


@njit(cache=True)
def _rhs_full_kernel(y, out, case2_args, basis, basis_t, theta_x_dofs, top_speed, inv_length, xi,
                     weights, slope, rotation, axial_stiffness, polar_inertia, tensor, active, q, qd,
                     f_se, f_vel, coupling, mass):
    """Case 1: the case-2 right-hand side plus the strain- and kinetic-energy forces f_se and f_ke
    (:mod:`drillstring.forces.nonlinear`), evaluated on the physical state ``q̄ = Φη``,
    ``q̇ = Φη̇ + Ω`` (θx DOFs), projected on the basis. ``f_ke = f_vel − M_nl(q) q̈``: the
    configuration-dependent mass correction is moved to the left-hand side and
    ``(I + Φᵀ M_nl(Φη) Φ) η̈ = …`` is solved at every evaluation (exact, no lagged accelerations)."""
    _rhs_kernel(y, out, *case2_args)
    n = basis.shape[1]
    eta = y[:n]
    q[:] = 0.0
    qd[:] = 0.0
    _columns_matvec(basis_t, y, 0, q, 1.0)
    _columns_matvec(basis_t, y, n, qd, 1.0)
    for i in range(theta_x_dofs.shape[0]):
        qd[theta_x_dofs[i]] += top_speed
    _strain_energy_forces_kernel(q, inv_length, weights, slope, axial_stiffness, f_se)
    _kinetic_forces_kernel(q, qd, xi, weights, rotation, polar_inertia, f_vel, coupling)
    for i in range(f_se.shape[0]):
        f_se[i] += f_vel[i]
    acc = np.empty(n)
    _matvec(basis_t, f_se, 0, acc)
    for i in range(n):
        acc[i] += out[n + i]
    contract_mass_tensor(tensor, active, eta, mass)
    for i in range(n):
        mass[i, i] += 1.0
    out[n:] = np.linalg.solve(mass, acc)


@njit(cache=True)
def rhs_dispatch(y, out, full, case2_args, full_args):
    """The ROM right-hand side: case 2 (``full`` False) or case 1. Both argument tuples always have
    the same types (case 2 carries empty placeholders for the case-1 data), so the compiled
    integrator has one cacheable specialisation."""
    if full:
        _rhs_full_kernel(y, out, case2_args, *full_args)
    else:
        _rhs_kernel(y, out, *case2_args)


def _placeholder_full_args():
    """Empty case-1 arguments with the exact types of real ones (see :func:`rhs_dispatch`)."""
    f2, f3, i1 = np.zeros((0, 0)), np.zeros((0, 0, 0)), np.zeros(0, dtype=np.int64)
    f1 = np.zeros(0)
    return (f2, f2, i1, 0.0, f1, f1, f2, f3, f3, f1, f1, f3, i1, f1, f1, f1, f1, f3, f2)


@njit(cache=True)
def _observe_kernel(
    y, out, omega2, bit_u, bit_t, phi_v, phi_w, phi_tx, gap, top_speed, bit_args, probe_nodes,
    v, w, v_dot, w_dot, spin, in_contact,
):
    n = omega2.shape[0]
    bit_velocity, bit_speed = _physical_state(
        y, n, top_speed, bit_u, bit_t, phi_v, phi_w, phi_tx, v, w, v_dot, w_dot, spin
    )
    axial_force, bit_torque = bit_rock_force_floored(
        bit_velocity, bit_speed, bit_args[0], bit_args[1], bit_args[2], bit_args[3], bit_args[4],
        bit_args[5], bit_args[6],
    )
    count = 0
    for i in range(v.shape[0]):
        in_contact[i] = np.sqrt(v[i] * v[i] + w[i] * w[i]) > gap[i]
        count += in_contact[i]
    out[0] = bit_velocity
    out[1] = bit_speed
    out[2] = -bit_torque
    out[3] = -axial_force
    depth = 0.0
    for j in range(n):
        depth += bit_u[j] * y[j]
    out[4] = depth
    out[5] = count
    for k in range(probe_nodes.shape[0]):
        j = probe_nodes[k]
        out[6 + k] = np.sqrt(v[j] * v[j] + w[j] * w[j])


@dataclass
class ReducedOrderModel:
    """Modal model of one drilling configuration (SI units).

    Attributes:
        angular_frequencies: ω of each basis vector [rad/s] (0 for the rigid axial mode).
        damping: reduced damping matrix (modal + rigid + fluid) [1/s].
        basis: Φ, (n_dofs, n) global mode shapes.
        family: family label of each basis vector.
        probe_positions: x of the radial-displacement probes [m].
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
        mesh = self.static.mesh
        self.generalized_force = np.ascontiguousarray(
            np.zeros(len(self.angular_frequencies)) if self.generalized_force is None
            else self.generalized_force, dtype=float)
        nodes = np.arange(mesh.n_nodes)
        phi = self.basis
        self.omega2 = np.ascontiguousarray(np.sign(self.angular_frequencies) * self.angular_frequencies**2)
        self.bit_u = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, U)])
        self.bit_t = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, THETA_X)])
        self.phi_v = np.ascontiguousarray(phi[dof(nodes, V)])
        self.phi_w = np.ascontiguousarray(phi[dof(nodes, W)])
        self.phi_tx = np.ascontiguousarray(phi[dof(nodes, THETA_X)])
        self.probe_nodes = np.array([mesh.node_index(x) for x in self.probe_positions], dtype=np.int64)
        self.bit_args = np.array(self.bit_rock.kernel_args(), dtype=float)
        c = self.contact
        self.contact_args = np.array([c.shock_stiffness, c.friction_coefficient,
                                      c.speed_regularization])
        n_nodes = mesh.n_nodes
        self._in_contact = np.zeros(n_nodes, dtype=np.bool_)
        # Arguments of the observation kernel after (y, out), shared by observe() and the
        # compiled integrator; the last one is the contact mask it fills.
        self.observe_args = (
            self.omega2, self.bit_u, self.bit_t, self.phi_v, self.phi_w, self.phi_tx, self.gap,
            float(self.top_speed), self.bit_args, self.probe_nodes,
            *(np.zeros(n_nodes) for _ in range(5)), self._in_contact,
        )
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
        contact_work = tuple(np.zeros(n_nodes) for _ in range(10))
        self._rhs_args = (
            self.omega2, np.ascontiguousarray(self.damping.T), self.generalized_force, self.blocks,
            np.ascontiguousarray(self.bit_u[a0:a1]), np.ascontiguousarray(self.bit_t[t0:t1]),
            np.ascontiguousarray(self.phi_v[:, y0:y1].T), np.ascontiguousarray(self.phi_w[:, z0:z1].T),
            np.ascontiguousarray(self.phi_tx[:, t0:t1].T),
            np.ascontiguousarray(self.gap), np.ascontiguousarray(self.outer_diameter),
            float(self.top_speed), float(self.weight_on_bit), self.bit_args, self.contact_args,
            bool(c.tangential_friction), np.zeros(n_nodes), np.zeros(n_nodes),
            np.zeros(n_nodes, dtype=np.int64), *contact_work,
        )
        self.full = False
        self.full_args = _placeholder_full_args()
        if self.nonlinear == "full":
            self._setup_full()
        elif self.nonlinear != "bit_and_contact":
            raise ValueError(f"nonlinear = {self.nonlinear!r}: must be 'bit_and_contact' or 'full'")

    def _setup_full(self) -> None:
        mesh = self.static.mesh
        self.elements: NonlinearElements = nonlinear_elements(mesh)
        basis = np.ascontiguousarray(self.basis)
        active, tensor = modal_mass_tensor(self.elements, basis, tol=1e-14)
        e = self.elements
        n_dofs, n = basis.shape
        self.full = True
        c = np.ascontiguousarray
        self.full_args = (
            basis, c(basis.T),
            dof(np.arange(mesh.n_nodes), THETA_X).astype(np.int64), float(self.top_speed),
            c(e.inv_length, dtype=float), c(e.xi, dtype=float), c(e.weights, dtype=float),
            c(e.slope, dtype=float), c(e.rotation, dtype=float), c(e.axial_stiffness, dtype=float),
            c(e.polar_inertia, dtype=float), c(tensor, dtype=float), c(active, dtype=np.int64),
            np.zeros(n_dofs), np.zeros(n_dofs), np.zeros(n_dofs), np.zeros(n_dofs),
            np.zeros((e.n_elements, 2, 4)), np.zeros((n, n)),
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
        rhs_dispatch(y, out, self.full, self._rhs_args, self.full_args)
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
                       + self.bit_u * (axial_force + self.weight_on_bit) + self.bit_t * bit_torque)
        acceleration = (generalized + self.generalized_force - self.damping @ eta_dot
                        - self.omega2 * eta)
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
        out = np.empty(len(OBSERVABLES) + len(self.probe_nodes))
        _observe_kernel(y, out, *self.observe_args)
        return out

    def contact_mask(self) -> np.ndarray:
        """Nodes in contact at the last :meth:`observe` call (a copy)."""
        return self._in_contact.copy()

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
