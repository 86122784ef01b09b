"""The reduced model as a function of the weight-on-bit, built once for many (docs/model.md §3, §5, §6).

A Monte Carlo study solves the same string at many weights-on-bit ``w``. :func:`~drillstring.dynamics.reduced.
build.case_reduced_model` rebuilds everything each time (statics, the linear system, every family's modes, the
free–free damping's dense eigenproblems), yet ``w`` enters the linear system in one known way:

- **statics** (:func:`~drillstring.statics.solve_statics`): the static problem is linear with the upward bit
  force ``w`` as one load, so the displacement, the axial force ``N(x)`` and the hook load are affine in it,
  ``N(x; w) = N(x; w₀) − (w − w₀)`` along the hanging string (the unit response ``∂N/∂w`` is computed, not
  assumed);
- **geometric stiffness** ``K_g(N)`` (:func:`~drillstring.fem.assembly.geometric_stiffness`) is linear in the
  nodal forces, hence ``K(w) = K(w₀) + (w − w₀) K_g(∂N/∂w)``; it acts on the bending DOFs only, so the axial
  and torsional families, their free–free damping (:mod:`drillstring.damping`) and the constant generalised
  force do not depend on ``w`` at all (checked on the assembled matrices when built: a system where ``∂K/∂w``
  or the fluid damping reaches another family is refused);
- the **lateral modes** are the lowest eigenpairs of ``(K_ℓ(w), M_ℓ)`` on each plane's DOFs. They are computed by
  Rayleigh–Ritz on a fixed space ``V`` (M-orthonormal columns): the exact lateral modes at the range's lower
  end, its middle ``w₀`` and its upper end, each with a margin of modes above the count kept
  (:data:`SNAPSHOT_MARGIN`). Per ``w`` one small symmetric eigenproblem
  ``(Vᵀ K_ℓ(w₀) V + (w − w₀) Vᵀ K_g' V) y = ω² y`` gives the modes ``V y``; at the three snapshot weights they are
  the exact modes (to round-off), in between Ritz approximations from above (Rayleigh–Ritz: each Ritz value
  bounds its eigenvalue from above). The errors across the range are measured
  (tests/dynamics/test_parametric_model.py, benchmarks/bench_study_parametric.py);
- the **reduced damping**: the fluid damping ``Φᵀ C_f Φ`` and the Rayleigh part ``α ΦᵀMΦ + β ΦᵀK(w)Φ`` are
  projected once on the fixed columns ``W = [Φ_axial, Φ_torsion, V_y, V_z]`` and per ``w`` reduced with the
  small coefficient matrix ``T`` of ``Φ(w) = W T``; the structural damping keeps its axial and torsional blocks
  (independent of ``w``) and puts ``2 ξ |ω_i(w)|`` on the lateral modes, as
  :func:`~drillstring.damping.reduced_structural_damping` does.

Two more inputs may be covered (``flow``, ``speed``: the Sobol' design of the driller's three controls):

- the mud's **inlet velocity** ``U``: the fluid coefficients (:func:`~drillstring.fem.fluid.fluid_coefficients`)
  are affine in it (Coriolis and viscous damping) or in its square (centrifugal stiffness), the added mass does
  not depend on it, and all act on the bending DOFs only; so ``C_f(U) = C_f(U₀) + (U − U₀) C_f'`` and ``K(w, U) =
  K(w, U₀) + (U² − U₀²) K_f'``, the slopes from two more assemblies and a third checking the form when built. The
  lateral Ritz space is checked at the flow's ends too (at every snapshot weight and midpoint) and, where it does
  not hold them, takes every snapshot weight at both ends as well. A case whose mud loads the string axially
  (``fluid.axial_loads``) moves its statics with ``U``: refused;
- the **top speed** ``Ω``: the linear system does not depend on it; the generalised force of the damping at an
  imposed speed is proportional to it (:mod:`drillstring.damping`), and the top boundary and the turning loads are
  the realized case's. A lateral cut-off (its count of modes follows ``Ω``) is refused.

Everything else of the model (the bit–rock law, the contact law, the start's hook load) is built from the
realized case each time by the same functions as the rebuild. :meth:`ParametricReducedModel.model` returns a
plain :class:`~drillstring.dynamics.reduced.model.ReducedOrderModel`: simulations and analyses run unchanged.

What is covered: a straight string (families uncoupled), no downhole motor, every top boundary, either damping
definition, either truncation correction (its attachment modes are axial and torsional: independent of
``w``), and a lateral cut-off (the count of modes below it taken from the Ritz frequencies). A weight-on-bit
outside the built range is refused (:class:`NotCovered`): the caller rebuilds.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg as sla

from drillstring.damping import reduced_structural_damping
from drillstring.dynamics.reduced.build import case_hook_load, case_reduced_model
from drillstring.dynamics.reduced.model import ReducedOrderModel
from drillstring.fem.assembly import THETA_X, U, dof, fluid_matrices, geometric_stiffness
from drillstring.fem.build import section_fluid_coefficients
from drillstring.forces.bit_rock import case_bit_rock
from drillstring.forces.contact import case_contact
from drillstring.forces.top_drive import case_top_drive
from drillstring.forces.turning_loads import case_turning_loads
from drillstring.modal import LinearSystem, ModeFamily, Modes, family_dofs, family_modes
from drillstring.statics import StaticState, case_static_state

#: Modes above the kept count in each snapshot of the lateral Ritz space (per plane and snapshot weight).
SNAPSHOT_MARGIN = 10
#: Largest difference accepted between the Ritz and the exact lateral modes at the midpoints between
#: snapshots (:meth:`ParametricReducedModel.lateral_error`): the build adds snapshots until it holds.
RITZ_TOLERANCE = 1e-7
#: Most snapshot weights of the lateral Ritz space; a range needing more is not covered.
MAX_SNAPSHOTS = 9
#: A Ritz space column whose M-norm, after removing the previous columns, falls below this fraction of its
#: own is dropped (the snapshots share most of their span).
_INDEPENDENCE = 1e-10


class NotCovered(ValueError):
    """The parametric model does not cover this input (its message says why): rebuild the model instead."""


@dataclasses.dataclass(frozen=True)
class _Plane:
    """One lateral plane's Ritz space: its DOFs, the basis ``V`` on them (M-orthonormal columns), and the
    reduced matrices ``Vᵀ M V``, ``Vᵀ K(w₀, U₀) V``, ``Vᵀ K_g' V`` and ``Vᵀ K_f' V`` (the fluid stiffness's
    change per unit of ``U²``; zero when the inlet velocity is not a parameter)."""

    dofs: np.ndarray
    space: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    slope: np.ndarray
    flow: np.ndarray


class ParametricReducedModel:
    """The reduced model of ``case`` for any weight-on-bit in ``[low, high]`` [N] (module docstring), and for any
    inlet velocity in ``flow`` = ``(low, high)`` [m/s] (None: the case's only) and any top speed (``speed``; else
    the case's only).

    Built once (the nominal model at the case's weight-on-bit, the static unit response, the lateral Ritz spaces
    from snapshots at ``low``, the case's weight-on-bit and ``high``, and the projections); then
    :meth:`model` gives the model of a realized case (the same case but for its weight-on-bit and the
    parameters of its force laws) in a few milliseconds (2.5–6 ms on the reference case, 33–66 ms rebuilt).

    Raises :class:`NotCovered` when the case is outside the parametric form (a string whose families couple,
    a downhole motor, an off-bottom bit) or the range is empty or does not hold the case's weight-on-bit.
    """

    def __init__(self, case, low: float, high: float, *, flow: tuple[float, float] | None = None,
                 speed: bool = False) -> None:
        low, high = float(low), float(high)
        nominal_wob = float(case.operation.weight_on_bit)
        if not (np.isfinite(low) and np.isfinite(high) and 0.0 <= low <= nominal_wob <= high and low < high):
            raise ValueError(f"weight-on-bit range [{low!r}, {high!r}] N: must be finite, 0 <= low < high, and hold "
                             f"the case's weight_on_bit = {nominal_wob!r} N")
        #: the case's inlet velocity U₀ [m/s] and the range of U covered (None: U is fixed at U₀)
        self.inlet_velocity = float(case.fluid.inlet_velocity)
        if flow is not None:
            flow = (float(flow[0]), float(flow[1]))
            u0 = self.inlet_velocity
            if not (np.isfinite(flow[0]) and np.isfinite(flow[1]) and 0.0 <= flow[0] <= u0 <= flow[1]
                    and flow[0] < flow[1]):
                raise ValueError(f"inlet velocity range {list(flow)!r} m/s: must be finite, 0 <= low < high, and "
                                 f"hold the case's fluid.inlet_velocity = {u0!r} m/s")
            if case.fluid.axial_loads:
                raise NotCovered("fluid.axial_loads = true: the mud's skin friction moves the static axial force "
                                 "with the inlet velocity (not parametrised)")
        self.flow_range = flow
        #: the case's top speed Ω₀ [rad/s], and whether another top speed is covered
        self.top_speed = float(case.operation.top_speed)
        self.speed = bool(speed)
        if self.speed and case.reduced_model.lateral_cutoff > 0:
            raise NotCovered("reduced_model.lateral_cutoff > 0 with a random top speed: the count of lateral modes "
                             "follows the speed (not parametrised)")
        if case.bit_rock.law == "off_bottom":
            raise NotCovered("bit_rock.law = 'off_bottom': the weight-on-bit is always 0, nothing to parametrise")
        if case.motor is not None:
            raise NotCovered("a downhole motor: its released torsional basis is not parametrised")
        if case.well is not None:
            raise NotCovered("a case with [well]: its static state (the stiff string along the well path) is not "
                             "parametrised")
        self.case = case
        self.range = (low, high)
        nominal = case_reduced_model(case)
        if nominal.coupled:
            raise NotCovered("the string's families couple (a string out of its straight axis)")
        if self.speed and not nominal.top_drive.drives and self.top_speed == 0.0:
            raise NotCovered("an imposed top speed of 0 as the nominal: the generalised force's slope in the speed "
                             "is not known from it")
        self.nominal = nominal
        static, system = nominal.static, nominal.system
        self.weight_on_bit = static.weight_on_bit
        mesh = static.mesh
        # static unit response ∂(q_S, N, woh)/∂w: the difference of two solves of the linear static problem
        other = case_static_state(case, nominal_wob + 1.0 if nominal_wob < 1.0 else 0.0)
        dw = other.weight_on_bit - static.weight_on_bit
        self._static_slope = ((other.displacement - static.displacement) / dw,
                              (other.axial_force - static.axial_force) / dw,
                              (other.weight_on_hook - static.weight_on_hook) / dw)
        self._geometric_slope = geometric_stiffness(mesh, self._static_slope[1]).tocsr()
        nodes = np.arange(mesh.n_nodes)
        axial_torsional = np.concatenate([dof(nodes, U), dof(nodes, THETA_X)])
        _not_on(self._geometric_slope, axial_torsional, "the geometric stiffness's change with the weight-on-bit")
        _not_on(system.fluid_damping, axial_torsional, "the fluid damping")
        # the fluid damping's change per unit of U and the fluid stiffness's per unit of U² (module docstring)
        self._flow_slopes = None if flow is None else self._fluid_slopes(case)
        for matrix in self._flow_slopes or ():
            _not_on(matrix, axial_torsional, "the fluid matrices' change with the inlet velocity")
        self._first_torsional: float | None = None
        r = case.reduced_model
        #: lateral modes per plane: the nominal model's, and at least the case's count (more below a cut-off)
        self.lateral_count = nominal.modes.lateral_y.shapes.shape[1]
        self.lateral_minimum = int(r.lateral_modes)
        self.lateral_cutoff = (r.lateral_cutoff * case.operation.top_speed if r.lateral_cutoff > 0
                               else 0.0)
        # the axial and torsional columns of the nominal model, fixed
        labels = np.array(nominal.family)
        fixed = np.nonzero(~np.isin(labels, ("lateral_y", "lateral_z")))[0]
        if not np.array_equal(fixed, np.arange(len(fixed))):
            raise NotCovered("the axial and torsional columns do not come first in the basis")
        self._fixed = fixed
        if np.any(np.delete(nominal.generalized_force, fixed)):
            raise NotCovered("the constant generalised force acts on the lateral modes")
        self.snapshots = [low, self.weight_on_bit, high]
        #: inlet velocities other than U₀ at which each snapshot weight is also taken (the flow's ends, added
        #: when the space from U₀ alone does not hold the modes across the flow's range: :meth:`_refine`)
        self.flow_snapshots: list[float] = []
        self._planes = self._ritz_planes(self.snapshots)
        self.ritz_error = self._refine()
        # the fixed columns W = [Φ_fixed, V_y, V_z] and the projections on them
        n_dofs = mesh.n_dofs
        blocks = [nominal.basis[:, fixed]]
        for plane in self._planes:
            full = np.zeros((n_dofs, plane.space.shape[1]))
            full[plane.dofs] = plane.space
            blocks.append(full)
        w_columns = np.hstack(blocks)
        self._columns = w_columns
        self._fluid = w_columns.T @ (system.fluid_damping @ w_columns)
        if self._flow_slopes is not None:
            self._fluid_flow = w_columns.T @ (self._flow_slopes[0] @ w_columns)
            self._stiffness_flow = w_columns.T @ (self._flow_slopes[1] @ w_columns)
        alpha, beta = case.damping.mass_proportional, case.damping.stiffness_proportional
        self._rayleigh = (float(alpha), float(beta))
        self._mass = w_columns.T @ (system.mass @ w_columns)
        self._stiffness = w_columns.T @ (system.stiffness @ w_columns)
        self._stiffness_slope = w_columns.T @ (self._geometric_slope @ w_columns)
        # the structural damping without its Rayleigh part: axial and torsional blocks fixed, lateral 2 ξ |ω|
        drive = nominal.top_drive.drives
        structural = reduced_structural_damping(
            system.mass, system.stiffness, nominal.basis, nominal.family, nominal.angular_frequencies,
            damping_ratio=case.damping.modal_damping_ratio, rigid_axial=case.damping.rigid_axial,
            rigid_rotation=case.damping.rigid_rotation, top_speed=0.0 if drive else case.operation.top_speed,
            definition=case.damping.basis)
        self._structural_fixed = structural.matrix[np.ix_(fixed, fixed)].copy()
        self._damping_ratio = float(case.damping.modal_damping_ratio)

    def _ritz_planes(self, weights) -> list[_Plane]:
        """Each lateral plane's Ritz space spanned by its exact modes at ``weights`` [N] (the kept count plus
        :data:`SNAPSHOT_MARGIN` at each), and its reduced matrices."""
        system = self.nominal.system
        mesh = system.mesh
        count = self.lateral_count + SNAPSHOT_MARGIN
        systems = [system if w == self.weight_on_bit else self.system_at(w) for w in weights]
        systems += [self.system_at(w, u) for u in self.flow_snapshots for w in weights]
        planes = []
        for name in ("lateral_y", "lateral_z"):
            dofs = family_dofs(mesh, name)
            m = system.mass[dofs][:, dofs]
            space = _mass_orthonormal(np.hstack([family_modes(s, name, count).shapes[dofs] for s in systems]), m)
            k0 = system.stiffness[dofs][:, dofs]
            k1 = self._geometric_slope[dofs][:, dofs]
            flow = (_symmetric(space.T @ (self._flow_slopes[1][dofs][:, dofs] @ space))
                    if self._flow_slopes is not None else np.zeros((space.shape[1],) * 2))
            planes.append(_Plane(dofs, space, _symmetric(space.T @ (m @ space)),
                                 _symmetric(space.T @ (k0 @ space)), _symmetric(space.T @ (k1 @ space)), flow))
        return planes

    def _fluid_slopes(self, case):
        """``(∂C_f/∂U, ∂K_f/∂(U²))``, sparse, from the fluid matrices at two more inlet velocities U [m/s]: the
        Coriolis and viscous coefficients are affine in the flow, the centrifugal one is proportional to its
        square, the added mass does not depend on it (:func:`drillstring.fem.fluid.fluid_coefficients`). The
        third assembly checks that form (to 1e-9 of each matrix's largest entry), else :class:`NotCovered`."""
        system, mesh = self.nominal.system, self.nominal.static.mesh
        u0, (low, high) = self.inlet_velocity, self.flow_range
        u1 = high if high != u0 else low
        u2 = 0.5 * (u0 + u1) if low in (u0, u1) else low

        def at(u):  # the case's fluid matrices at another inlet velocity (its flow rate follows: Case.flow_rate)
            flowing = case.model_copy(update={"fluid": case.fluid.model_copy(update={"inlet_velocity": u})})
            return fluid_matrices(mesh, section_fluid_coefficients(flowing, mesh))

        m1, c1, k1 = at(u1)
        damping = ((c1 - system.fluid_damping) / (u1 - u0)).tocsr()
        stiffness = ((k1 - system.fluid_stiffness) / (u1**2 - u0**2)).tocsr()
        m2, c2, k2 = at(u2)
        for what, found, predicted in (
                ("mass", m1, system.fluid_mass), ("mass", m2, system.fluid_mass),
                ("damping", c2, system.fluid_damping + (u2 - u0) * damping),
                ("stiffness", k2, system.fluid_stiffness + (u2**2 - u0**2) * stiffness)):
            scale = max(abs(found).max(), abs(predicted).max())
            if abs(found - predicted).max() > 1e-9 * scale:
                raise NotCovered(f"the fluid {what} does not follow the inlet velocity as the parametric form "
                                 "assumes (affine damping, stiffness affine in U², constant mass)")
        return damping, stiffness

    def _refine(self) -> float:
        """Check the Ritz modes against the exact lateral modes (y plane) midway between consecutive snapshots,
        adding a snapshot there while they differ by more than :data:`RITZ_TOLERANCE` (largest of the relative
        eigenvalue error and the shapes' largest difference relative to their largest entry), at most
        :data:`MAX_SNAPSHOTS`; returns the largest difference left at the midpoints checked last."""
        while True:
            worst, add = 0.0, []
            for a, b in zip(self.snapshots[:-1], self.snapshots[1:]):
                error = self.lateral_error(0.5 * (a + b))
                worst = max(worst, error)
                if error > RITZ_TOLERANCE:
                    add.append(0.5 * (a + b))
            if not add:
                return max(worst, self._refine_flow())
            if len(self.snapshots) + len(add) > MAX_SNAPSHOTS:
                raise NotCovered(f"the lateral modes vary too much over the weight-on-bit range {self.range} N for "
                                 f"{MAX_SNAPSHOTS} snapshots (Ritz error {worst:.2g})")
            self.snapshots = sorted(self.snapshots + add)
            self._planes = self._ritz_planes(self.snapshots)

    def _refine_flow(self) -> float:
        """With the inlet velocity a parameter: the same check at the flow's two ends, at every snapshot weight
        and midpoint; where it fails, every snapshot weight is taken at both ends too (once), else
        :class:`NotCovered`. Returns the largest difference left (0 without the flow)."""
        if self.flow_range is None:
            return 0.0
        while True:
            points = sorted(self.snapshots + [0.5 * (a + b) for a, b in zip(self.snapshots[:-1], self.snapshots[1:])])
            worst = max(self.lateral_error(w, u) for u in self.flow_range for w in points)
            if worst <= RITZ_TOLERANCE:
                return worst
            if self.flow_snapshots:
                raise NotCovered(f"the lateral modes vary too much over the inlet velocity range {self.flow_range} m/s "
                                 f"(Ritz error {worst:.2g})")
            self.flow_snapshots = [u for u in self.flow_range if u != self.inlet_velocity]
            self._planes = self._ritz_planes(self.snapshots)

    def lateral_error(self, weight_on_bit: float, inlet_velocity: float | None = None) -> float:
        """The largest difference between the Ritz lateral modes (y plane) at ``weight_on_bit`` [N] (and
        ``inlet_velocity`` [m/s], None: the case's) and the exact ones (:func:`~drillstring.modal.family_modes`
        on the system there): the relative eigenvalue error, or the shapes' largest difference relative to
        their largest entry (signs aligned), whichever is larger."""
        ritz, _, _ = self.lateral_modes(weight_on_bit, inlet_velocity)
        count = len(ritz.angular_frequencies)
        exact = family_modes(self.system_at(weight_on_bit, inlet_velocity), "lateral_y", count)
        values = np.abs(ritz.eigenvalues / exact.eigenvalues - 1.0).max(initial=0.0)
        signs = np.sign(np.einsum("ij,ij->j", ritz.shapes, exact.shapes))
        shapes = np.abs(ritz.shapes * signs - exact.shapes).max(initial=0.0) / np.abs(exact.shapes).max(initial=1.0)
        return float(max(values, shapes))

    # --- the parts at one weight-on-bit -------------------------------------------------------------------

    def _check(self, weight_on_bit: float) -> float:
        w = float(weight_on_bit)
        low, high = self.range
        if not (low <= w <= high):
            raise NotCovered(f"weight_on_bit = {w!r} N is outside the parametric model's range [{low!r}, {high!r}] N")
        return w

    def _check_flow(self, inlet_velocity: float | None) -> float:
        """The inlet velocity [m/s] (None: the case's), refused (:class:`NotCovered`) outside the covered range."""
        u = self.inlet_velocity if inlet_velocity is None else float(inlet_velocity)
        if u == self.inlet_velocity:
            return u
        if self.flow_range is None:
            raise NotCovered(f"fluid.inlet_velocity = {u!r} m/s: the parametric model holds it at "
                             f"{self.inlet_velocity!r} m/s")
        low, high = self.flow_range
        if not (low <= u <= high):
            raise NotCovered(f"fluid.inlet_velocity = {u!r} m/s is outside the parametric model's range "
                             f"[{low!r}, {high!r}] m/s")
        return u

    def static_at(self, weight_on_bit: float) -> StaticState:
        """The static state at ``weight_on_bit`` [N]: affine in it (module docstring)."""
        w = self._check(weight_on_bit)
        s, dw = self.nominal.static, w - self.weight_on_bit
        du, dn, dh = self._static_slope
        return StaticState(s.mesh, s.displacement + dw * du, s.axial_force + dw * dn, s.weight,
                           s.weight_on_hook + dw * dh, w)

    def system_at(self, weight_on_bit: float, inlet_velocity: float | None = None) -> LinearSystem:
        """The linear system at ``weight_on_bit`` [N] (and ``inlet_velocity`` [m/s], None: the case's): the nominal
        one with ``K_g`` moved along its slope (and the fluid damping and stiffness along theirs)."""
        w = float(weight_on_bit)
        dw = w - self.weight_on_bit
        system = self.nominal.system
        static = self.static_at(w)
        changes = dict(static=static,
                       geometric_stiffness=(system.geometric_stiffness + dw * self._geometric_slope).tocsr())
        u = self._check_flow(inlet_velocity)
        if u != self.inlet_velocity:
            damping, stiffness = self._flow_slopes
            changes.update(fluid_damping=(system.fluid_damping + (u - self.inlet_velocity) * damping).tocsr(),
                           fluid_stiffness=(system.fluid_stiffness
                                            + (u**2 - self.inlet_velocity**2) * stiffness).tocsr())
        return dataclasses.replace(system, **changes)

    def lateral_modes(self, weight_on_bit: float, inlet_velocity: float | None = None
                      ) -> tuple[ModeFamily, ModeFamily, list[np.ndarray]]:
        """The lateral families at ``weight_on_bit`` [N] (and ``inlet_velocity`` [m/s], None: the case's)
        (Rayleigh–Ritz on the fixed space) and, per plane, the Ritz coefficients ``y`` (the modes are ``V y``)."""
        w = self._check(weight_on_bit)
        dw = w - self.weight_on_bit
        u = self._check_flow(inlet_velocity)
        dq = u**2 - self.inlet_velocity**2
        n_dofs = self.nominal.static.mesh.n_dofs
        out, coefficients, count = [], [], None
        for name, plane in zip(("lateral_y", "lateral_z"), self._planes):
            stiffness = plane.stiffness + dw * plane.slope
            if dq:
                stiffness = stiffness + dq * plane.flow
            values, vectors = sla.eigh(stiffness, plane.mass)
            if count is None:  # the z plane takes as many modes as the y plane (compute_modes)
                count = self.lateral_count
                if self.lateral_cutoff > 0.0:  # as family_modes_below: the case's count, more below the cut-off
                    count = max(self.lateral_minimum, int(np.count_nonzero(values < self.lateral_cutoff**2)))
                if count > plane.space.shape[1] - SNAPSHOT_MARGIN // 2:
                    raise NotCovered(f"{count} lateral modes below the cut-off: beyond the Ritz space's "
                                     f"{plane.space.shape[1]} columns")
            values, vectors = values[:count], vectors[:, :count]
            shapes = np.zeros((n_dofs, count))
            shapes[plane.dofs] = plane.space @ vectors
            pivot = np.argmax(np.abs(shapes), axis=0)  # the sign rule of family_modes
            signs = np.sign(shapes[pivot, np.arange(count)])
            out.append(ModeFamily(name, np.sign(values) * np.sqrt(np.abs(values)), shapes * signs))
            coefficients.append(vectors * signs)
        return out[0], out[1], coefficients

    def model(self, realized) -> ReducedOrderModel:
        """The reduced model of ``realized``: this model's case with another weight-on-bit (in the range), inlet
        velocity and top speed (where covered) and possibly other parameters of its bit–rock and contact laws and
        its start; which other parameters may differ is the caller's to check
        (:mod:`drillstring.stochastic.study_model`)."""
        w = self._check(realized.operation.weight_on_bit)
        u = self._check_flow(realized.fluid.inlet_velocity)
        top_speed = float(realized.operation.top_speed)
        if top_speed != self.top_speed and not self.speed:
            raise NotCovered(f"operation.top_speed = {top_speed!r} rad/s: the parametric model holds it at "
                             f"{self.top_speed!r} rad/s")
        nominal = self.nominal
        lateral_y, lateral_z, coefficients = self.lateral_modes(w, u)
        fixed = self._fixed
        modes = Modes(axial=nominal.modes.axial, torsional=nominal.modes.torsional, lateral_y=lateral_y,
                      lateral_z=lateral_z)
        basis = np.hstack([nominal.basis[:, fixed], lateral_y.shapes, lateral_z.shapes])
        omega = np.concatenate([nominal.angular_frequencies[fixed], lateral_y.angular_frequencies,
                                lateral_z.angular_frequencies])
        count = lateral_y.shapes.shape[1]
        family = tuple(nominal.family[i] for i in fixed) + ("lateral_y",) * count + ("lateral_z",) * count
        # Φ(w) = W T, T = blockdiag(I, y_y, y_z)
        n_fixed = len(fixed)
        sizes = [n_fixed] + [c.shape[0] for c in coefficients]
        t = np.zeros((sum(sizes), n_fixed + 2 * count))
        t[:n_fixed, :n_fixed] = np.eye(n_fixed)
        t[n_fixed:n_fixed + sizes[1], n_fixed:n_fixed + count] = coefficients[0]
        t[n_fixed + sizes[1]:, n_fixed + count:] = coefficients[1]
        n = n_fixed + 2 * count
        structural = np.zeros((n, n))
        structural[:n_fixed, :n_fixed] = self._structural_fixed
        lateral = np.arange(n_fixed, n)
        structural[lateral, lateral] = 2.0 * self._damping_ratio * np.abs(omega[n_fixed:])
        alpha, beta = self._rayleigh
        du, dq = u - self.inlet_velocity, u**2 - self.inlet_velocity**2
        if alpha or beta:
            dw = w - self.weight_on_bit
            stiffness = self._stiffness + dw * self._stiffness_slope
            if dq:
                stiffness = stiffness + dq * self._stiffness_flow
            rayleigh = t.T @ ((alpha * self._mass + beta * stiffness) @ t)
            structural = structural + 0.5 * (rayleigh + rayleigh.T)
        fluid = self._fluid + du * self._fluid_flow if du else self._fluid
        damping = t.T @ (fluid @ t) + structural
        static = self.static_at(w)
        system = self.system_at(w, u)
        # the top speed: the generalised force of the damping at the imposed speed is proportional to it
        # (drillstring.damping: −Ω c₂-term and −Ω α Ψᵀ M r), the top boundary and the turning loads are the case's
        force = nominal.generalized_force[fixed]
        top_drive, turning_loads = nominal.top_drive, nominal.turning_loads
        if top_speed != self.top_speed:
            if not nominal.top_drive.drives:
                force = force * (top_speed / self.top_speed)
            top_drive = case_top_drive(realized, self._stick_slip_frequency)
            turning_loads = case_turning_loads(realized, static.mesh)
        return ReducedOrderModel(
            static=static, system=system, modes=modes, basis=basis, family=family, angular_frequencies=omega,
            damping=damping, top_speed=top_speed, weight_on_bit=w, bit_rock=case_bit_rock(realized),
            contact=case_contact(realized), stations=nominal.stations, probe_positions=nominal.probe_positions,
            nonlinear=nominal.nonlinear,
            generalized_force=np.concatenate([force, np.zeros(2 * count)]),
            turning_loads=turning_loads, top_drive=top_drive,
            hook_load=case_hook_load(realized, w),
            residual_columns=np.concatenate([nominal.residual_columns[fixed], np.zeros(2 * count, dtype=bool)]),
            coupled=False, motor=None, rotor=None,
        )

    def _stick_slip_frequency(self) -> float:
        """The first torsional natural frequency with the top held [rad/s], as the build's top boundary reads it
        (independent of the weight-on-bit and the flow: their changes act on the lateral DOFs only)."""
        if self._first_torsional is None:
            self._first_torsional = float(family_modes(self.nominal.system, "torsional", 1).angular_frequencies[0])
        return self._first_torsional


def _symmetric(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + a.T)


def _not_on(matrix, dofs: np.ndarray, what: str) -> None:
    """Refuse (:class:`NotCovered`) a matrix with a nonzero entry in a row or column of ``dofs`` (the axial and
    torsional DOFs, which the parametric form keeps fixed)."""
    coo = matrix.tocoo()
    touched = np.zeros(matrix.shape[0], dtype=bool)
    touched[dofs] = True
    if ((touched[coo.row] | touched[coo.col]) & (coo.data != 0.0)).any():
        raise NotCovered(f"{what} reaches the axial or torsional DOFs")


def _mass_orthonormal(columns: np.ndarray, mass) -> np.ndarray:
    """An M-orthonormal basis of the span of ``columns`` (modified Gram–Schmidt in the M inner product, twice;
    columns dependent on the previous ones to :data:`_INDEPENDENCE` dropped)."""
    kept: list[np.ndarray] = []
    for j in range(columns.shape[1]):
        v = columns[:, j].copy()
        norm0 = np.sqrt(v @ (mass @ v))
        for _ in range(2):
            for u in kept:
                v -= (u @ (mass @ v)) * u
        norm = np.sqrt(v @ (mass @ v))
        if norm > _INDEPENDENCE * norm0:
            kept.append(v / norm)
    return np.column_stack(kept)
