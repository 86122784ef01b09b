"""A full finite-element time integration of a deviated case's axial and torsional dynamics, no modal reduction:
the reference that the reduced model is checked against (tests/dynamics/test_full_fe_deviated.py,
benchmarks/full_fe_convergence.py, docs/stiff_string.md "Against a full finite-element integration").

Written apart from the reduced model's code (:mod:`drillstring.dynamics.reduced`): it uses the case's finite-element
matrices (:func:`drillstring.modal.case_linear_system` about the stiff string's static state in the well), the
force laws' own NumPy evaluations (``evaluate_at``, ``jacobian_at``: the bit–rock law, the along-string friction,
the hook load) and the damping matrix of the damping model (:func:`drillstring.damping.free_free_damping`, eq. (1)
of :mod:`drillstring.damping`), and integrates the nodal equations with SciPy's ``solve_ivp`` (Radau IIA, order 5)
— no mode, no projection, no compiled kernel.

The unknowns, along measured depth, relative to the static state and to the frame turning at the imposed top speed
Ω: the axial displacement ``u_i`` of every node (the top axially free: the hook holds it with a constant force)
and the twist ``θ_i`` of every node below the top (the top's rotation imposed)::

    M q̈ + (C_s + C_f + C_R) q̇ + K q = −Ω (C_s + C_R) r_θ + f_bit + f_hook + f_friction          (1)

with ``M, K`` the structural plus fluid mass and the prestressed stiffness (``K + K_stab + K_g + K_f``) restricted
to those DOFs, ``C_s`` the free–free structural damping of each family (``M Φ diag(c_i) Φᵀ M`` on all its modes,
restricted), ``C_f`` the fluid's damping, ``C_R = α M + β K`` the Rayleigh part, ``r_θ`` the unit rigid rotation
(the imposed spin's damping force, as the reduced model's constant generalised force), ``f_bit`` the bit–rock law
at the bit (its axial force plus the static weight on bit, and its torque), ``f_hook`` the hook load's change at
the top, ``f_friction`` the along-string Coulomb friction at the nodes on the wall (the nodal axial velocity
``u̇_i`` and spin ``Ω + θ̇_i``; normal forces the stiff string's static wall forces). The same damping model as the
reduced model's: with every mode kept the two solve the same equations, and their difference is the integration's.

**Laterally**: no lateral DOF. The straight string's lateral motion (the reduced model's lateral dynamics in a
deviated case, docs/stiff_string.md) couples with the axial and torsional DOFs only through the wall's contact
(and the turning loads, which the ``deviated`` case has none of); in a run where no node touches the wall
dynamically, leaving the lateral DOFs out is exact for the axial and torsional outputs. The wall's static normal
forces enter through the friction only.

Observables, as the reduced model defines them (:mod:`drillstring.dynamics.reduced.observation`): the bit speed
``Ω + θ̇_bit`` [rad/s], the surface torque (the top element's elastic torque, the stiffness row of the top's θx
times the displacements) [N·m], the force on bit ``−f`` (the law's axial force, upward positive) [N].

SI units throughout.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from drillstring.blas_threads import single_threaded_blas
from drillstring.damping import free_free_damping
from drillstring.dynamics.reduced.build import (
    case_friction_stations,
    case_hook_load,
    case_string_friction,
)
from drillstring.fem.dofs import THETA_X, U, dof
from drillstring.forces.bit_rock import case_bit_rock
from drillstring.forces.registry import BitContext, HookContext, StringFrictionContext
from drillstring.forces.string_friction import FrictionStations
from drillstring.forces.top_drive import case_top_drive
from drillstring.modal import case_linear_system
from drillstring.well.stiff_string import case_stiff_string


@dataclass
class FullFiniteElementModel:
    """Eq. (1) of the module docstring on the free axial and torsional DOFs of a mesh (SI units).

    Attributes:
        mass, stiffness, damping: (n, n) dense matrices on the DOFs ``dofs`` (global DOF numbers: the axial DOFs
            of every node, then the torsional ones of the nodes below the top).
        imposed_force: (n,) ``−Ω (C_s + C_R) r_θ`` [N, N·m].
        surface_torque_row: (n,) the stiffness row of the top's θx on ``dofs``.
        bit_axial, bit_torsion, top_axial: positions of those DOFs in ``dofs``.
        station_axial, station_torsion: (m,) positions of the friction stations' DOFs in ``dofs``; a station at
            the top has no torsional DOF (-1: it turns at Ω).
    """

    dofs: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    imposed_force: np.ndarray
    surface_torque_row: np.ndarray
    bit_axial: int
    bit_torsion: int
    top_axial: int
    top_speed: float
    weight_on_bit: float
    bit_rock: object
    hook_load: object
    string_friction: object
    stations: FrictionStations
    station_axial: np.ndarray
    station_torsion: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.dofs)
        self._inverse_mass = np.linalg.inv(self.mass)
        self._linear = np.zeros((2 * n, 2 * n))
        self._linear[:n, n:] = np.eye(n)
        self._linear[n:, :n] = -self._inverse_mass @ self.stiffness
        self._linear[n:, n:] = -self._inverse_mass @ self.damping

    @property
    def size(self) -> int:
        return len(self.dofs)

    def _station_motion(self, velocity: np.ndarray):
        axial = velocity[self.station_axial]
        twist_rate = np.where(self.station_torsion >= 0, velocity[np.maximum(self.station_torsion, 0)], 0.0)
        return axial, self.top_speed + twist_rate

    def _friction_context(self, velocity: np.ndarray) -> StringFrictionContext:
        axial, spin = self._station_motion(velocity)
        fs = self.stations
        return StringFrictionContext(axial, spin, fs.normal_force, fs.radius, fs.friction)

    def _bit_context(self, t: float, x: np.ndarray) -> BitContext:
        n = self.size
        return BitContext(t, x[self.bit_axial], self.top_speed * t + x[self.bit_torsion], x[n + self.bit_axial],
                          self.top_speed + x[n + self.bit_torsion], 0.0, self.weight_on_bit)

    def nodal_forces(self, t: float, x: np.ndarray) -> np.ndarray:
        """The right-hand side of eq. (1) less its linear terms: the imposed spin's damping, the bit, the hook
        and the friction [N, N·m] on ``dofs``, at time ``t`` [s] and state ``x = [q, q̇]``."""
        n = self.size
        force = self.imposed_force.copy()
        axial_force, bit_torque = self.bit_rock.evaluate_at(self._bit_context(t, x))
        force[self.bit_axial] += float(axial_force) + self.weight_on_bit
        force[self.bit_torsion] += float(bit_torque)
        force[self.top_axial] += float(np.asarray(self.hook_load.evaluate_at(HookContext(t, self.weight_on_bit))))
        if self.string_friction is not None and len(self.stations):
            f, tau = self.string_friction.evaluate_at(self._friction_context(x[n:]))
            np.add.at(force, self.station_axial, f)
            held = self.station_torsion >= 0
            np.add.at(force, self.station_torsion[held], np.asarray(tau)[held])
        return force

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """dx/dt of eq. (1), ``x = [q, q̇]``."""
        n = self.size
        out = self._linear @ x
        out[n:] += self._inverse_mass @ self.nodal_forces(t, x)
        return out

    def jacobian(self, t: float, x: np.ndarray) -> np.ndarray:
        """∂(dx/dt)/∂x: the linear part and the laws' own Jacobians (``jacobian_at``) at the bit and the
        stations (they read velocities only)."""
        n = self.size
        jac = self._linear.copy()
        local = np.zeros((n, n))
        bit = self.bit_rock.jacobian_at(self._bit_context(t, x))  # ∂(f, τ)/∂(u̇, θ̇)
        rows = (self.bit_axial, self.bit_torsion)
        for a in range(2):
            for b in range(2):
                local[rows[a], rows[b]] += bit[a][b]
        if self.string_friction is not None and len(self.stations):
            station = self.string_friction.jacobian_at(self._friction_context(x[n:]))
            held = self.station_torsion >= 0
            for k in range(len(self.stations)):
                dofs = [(self.station_axial[k], 0)] + ([(self.station_torsion[k], 1)] if held[k] else [])
                for i, a in dofs:
                    for j, b in dofs:
                        local[i, j] += station[k, a, b]
        jac[n:, n:] += self._inverse_mass @ local
        return jac

    def initial_state(self) -> np.ndarray:
        """The static state turning at Ω (the reduced model's reference start, ``initial.start = "on_bottom"``),
        twisted by the friction's steady torques ``K_θθ q_θ = τ(Ω)`` (no axial velocity) when there is friction."""
        n = self.size
        x = np.zeros(2 * n)
        if self.string_friction is None or not len(self.stations):
            return x
        _, tau = self.string_friction.evaluate_at(self._friction_context(np.zeros(n)))
        held = self.station_torsion >= 0
        load = np.zeros(n)
        np.add.at(load, self.station_torsion[held], np.asarray(tau)[held])
        torsion = np.arange(self.bit_axial + 1, n)  # the twist: the torsional DOFs (the axial ones take no load)
        x[torsion] = np.linalg.solve(self.stiffness[np.ix_(torsion, torsion)], load[torsion])
        return x

    def observe(self, t: np.ndarray, x: np.ndarray) -> dict[str, np.ndarray]:
        """The bit speed [rad/s], surface torque [N·m] and force on bit [N] at the times ``t`` (k,) of the
        states ``x`` (2n, k)."""
        n = self.size
        force = np.array([float(self.bit_rock.evaluate_at(self._bit_context(float(ti), x[:, j]))[0])
                          for j, ti in enumerate(t)])
        return {"bit_speed": self.top_speed + x[n + self.bit_torsion],
                "surface_torque": self.surface_torque_row @ x[:n],
                "force_on_bit": -force}


def full_fe_model(case) -> FullFiniteElementModel:
    """Eq. (1) for a case with ``[well]`` and its top speed imposed: the stiff string's static state at the case's
    weight on bit (:func:`~drillstring.well.stiff_string.case_stiff_string`), its prestressed linear system, the
    case's damping, bit–rock law, hook load and along-string friction at the nodes on the wall."""
    if case.well is None:
        raise ValueError("full_fe_model: the case has no [well]")
    if case.motor is not None or case.bit_rock.law == "detournay":
        raise ValueError("full_fe_model: a downhole motor or a delayed bit-rock law is not in the reference")
    if getattr(case_hook_load(case, case.operation.weight_on_bit), "active", False):
        raise ValueError("full_fe_model: initial.start = 'ramp'; the reference starts on bottom ('on_bottom')")
    if case_top_drive(case, lambda: 1.0).drives:
        raise ValueError(f"full_fe_model: top boundary {case.top_drive.boundary!r} drives the top; the reference "
                         "imposes the top speed")
    state = case_stiff_string(case)
    static = state.static_state()
    system = case_linear_system(case, static)
    mesh = static.mesh
    nodes = np.arange(mesh.n_nodes)
    axial = dof(nodes, U)
    torsion_all = dof(nodes, THETA_X)
    torsion = torsion_all[1:]  # the top's rotation imposed
    dofs = np.concatenate([axial, torsion])
    mass_all = system.mass.tocsr()
    stiffness_all = system.stiffness.tocsr()

    def block(matrix, rows, columns):
        return matrix[rows][:, columns].toarray()

    mass = block(mass_all, dofs, dofs)
    stiffness = block(stiffness_all, dofs, dofs)
    damping = block(system.fluid_damping.tocsr(), dofs, dofs)
    d = case.damping
    omega = float(case.operation.top_speed)
    n_axial = len(axial)
    imposed = np.zeros(len(dofs))
    if d.basis != "free_free":
        raise ValueError(f"full_fe_model: damping.basis = {d.basis!r}; the reference builds the free-free damping "
                         "matrix only (the 'constrained' one is defined on the reduced basis, not on the DOFs)")
    axial_damping = free_free_damping(block(mass_all, axial, axial), block(stiffness_all, axial, axial),
                                      d.modal_damping_ratio, d.rigid_axial).matrix
    torsion_damping = free_free_damping(block(mass_all, torsion_all, torsion_all),
                                        block(stiffness_all, torsion_all, torsion_all),
                                        d.modal_damping_ratio, d.rigid_rotation).matrix
    damping[:n_axial, :n_axial] += axial_damping
    damping[n_axial:, n_axial:] += torsion_damping[1:, 1:]
    imposed[n_axial:] -= omega * torsion_damping[1:, :].sum(axis=1)
    alpha, beta = float(d.mass_proportional), float(d.stiffness_proportional)
    if alpha or beta:
        rayleigh = alpha * mass_all + beta * stiffness_all
        damping += block(rayleigh, dofs, dofs)
        imposed[n_axial:] -= omega * np.asarray(rayleigh[torsion][:, torsion_all].sum(axis=1)).ravel()
    hook_load = case_hook_load(case, static.weight_on_bit)
    friction = case_string_friction(case)
    stations = case_friction_stations(case, state) if friction is not None else FrictionStations.empty()
    node = np.asarray(stations.node, dtype=np.int64)
    return FullFiniteElementModel(
        dofs=dofs, mass=mass, stiffness=stiffness, damping=damping, imposed_force=imposed,
        surface_torque_row=np.asarray(stiffness_all[torsion_all[0]][:, dofs].toarray()).ravel(),
        bit_axial=int(n_axial - 1), bit_torsion=int(len(dofs) - 1), top_axial=0, top_speed=omega,
        weight_on_bit=float(static.weight_on_bit), bit_rock=case_bit_rock(case),
        hook_load=hook_load, string_friction=friction, stations=stations,
        station_axial=node, station_torsion=np.where(node > 0, n_axial + node - 1, -1))


@dataclass
class FullRun:
    """A run of :func:`integrate`: the output times [s], the observables, the wall-clock time [s], the solver's
    right-hand-side evaluations and Jacobian evaluations."""

    times: np.ndarray
    observables: dict[str, np.ndarray]
    seconds: float
    evaluations: int
    jacobians: int


def integrate(model: FullFiniteElementModel, t_end: float, output_step: float, *, rtol: float = 1e-8,
              atol: float = 1e-10) -> FullRun:
    """Eq. (1) from :meth:`FullFiniteElementModel.initial_state` to ``t_end`` [s] by ``solve_ivp(method="Radau")``
    with the analytic Jacobian, the observables every ``output_step`` [s] (from 0). BLAS single-threaded (the
    dense solves of a few hundred unknowns: threads only wait for each other, 8× slower on a loaded machine)."""
    times = np.arange(0.0, t_end + 0.5 * output_step, output_step)
    start = time.perf_counter()
    with single_threaded_blas():
        solution = solve_ivp(model.rhs, (0.0, t_end), model.initial_state(), method="Radau", t_eval=times,
                             rtol=rtol, atol=atol, jac=model.jacobian)
    seconds = time.perf_counter() - start
    if not solution.success:
        raise RuntimeError(f"full finite-element integration failed: {solution.message}")
    return FullRun(solution.t, model.observe(solution.t, solution.y), seconds, int(solution.nfev), int(solution.njev))


__all__ = ["FullFiniteElementModel", "FullRun", "full_fe_model", "integrate"]
