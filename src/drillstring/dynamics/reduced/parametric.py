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
from drillstring.fem.assembly import THETA_X, U, dof, geometric_stiffness
from drillstring.forces.bit_rock import case_bit_rock
from drillstring.forces.contact import case_contact
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
    reduced matrices ``Vᵀ M V``, ``Vᵀ K(w₀) V``, ``Vᵀ K_g' V``."""

    dofs: np.ndarray
    space: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    slope: np.ndarray


class ParametricReducedModel:
    """The reduced model of ``case`` for any weight-on-bit in ``[low, high]`` [N] (module docstring).

    Built once (the nominal model at the case's weight-on-bit, the static unit response, the lateral Ritz spaces
    from snapshots at ``low``, the case's weight-on-bit and ``high``, and the projections); then
    :meth:`model` gives the model of a realized case (the same case but for its weight-on-bit and the
    parameters of its force laws) in a few milliseconds (2.5–6 ms on the reference case, 33–66 ms rebuilt).

    Raises :class:`NotCovered` when the case is outside the parametric form (a string whose families couple,
    a downhole motor, an off-bottom bit) or the range is empty or does not hold the case's weight-on-bit.
    """

    def __init__(self, case, low: float, high: float) -> None:
        low, high = float(low), float(high)
        nominal_wob = float(case.operation.weight_on_bit)
        if not (np.isfinite(low) and np.isfinite(high) and 0.0 <= low <= nominal_wob <= high and low < high):
            raise ValueError(f"weight-on-bit range [{low!r}, {high!r}] N: must be finite, 0 <= low < high, and hold "
                             f"the case's weight_on_bit = {nominal_wob!r} N")
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
        planes = []
        for name in ("lateral_y", "lateral_z"):
            dofs = family_dofs(mesh, name)
            m = system.mass[dofs][:, dofs]
            space = _mass_orthonormal(np.hstack([family_modes(s, name, count).shapes[dofs] for s in systems]), m)
            k0 = system.stiffness[dofs][:, dofs]
            k1 = self._geometric_slope[dofs][:, dofs]
            planes.append(_Plane(dofs, space, _symmetric(space.T @ (m @ space)),
                                 _symmetric(space.T @ (k0 @ space)), _symmetric(space.T @ (k1 @ space))))
        return planes

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
                return worst
            if len(self.snapshots) + len(add) > MAX_SNAPSHOTS:
                raise NotCovered(f"the lateral modes vary too much over the weight-on-bit range {self.range} N for "
                                 f"{MAX_SNAPSHOTS} snapshots (Ritz error {worst:.2g})")
            self.snapshots = sorted(self.snapshots + add)
            self._planes = self._ritz_planes(self.snapshots)

    def lateral_error(self, weight_on_bit: float) -> float:
        """The largest difference between the Ritz lateral modes (y plane) at ``weight_on_bit`` [N] and the exact
        ones (:func:`~drillstring.modal.family_modes_below` on the system there): the relative eigenvalue error,
        or the shapes' largest difference relative to their largest entry (signs aligned), whichever is
        larger."""
        ritz, _, _ = self.lateral_modes(weight_on_bit)
        count = len(ritz.angular_frequencies)
        exact = family_modes(self.system_at(weight_on_bit), "lateral_y", count)
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

    def static_at(self, weight_on_bit: float) -> StaticState:
        """The static state at ``weight_on_bit`` [N]: affine in it (module docstring)."""
        w = self._check(weight_on_bit)
        s, dw = self.nominal.static, w - self.weight_on_bit
        du, dn, dh = self._static_slope
        return StaticState(s.mesh, s.displacement + dw * du, s.axial_force + dw * dn, s.weight,
                           s.weight_on_hook + dw * dh, w)

    def system_at(self, weight_on_bit: float) -> LinearSystem:
        """The linear system at ``weight_on_bit`` [N]: the nominal one with ``K_g`` moved along its slope."""
        w = float(weight_on_bit)
        dw = w - self.weight_on_bit
        system = self.nominal.system
        static = self.static_at(w)
        return dataclasses.replace(system, static=static,
                                   geometric_stiffness=(system.geometric_stiffness + dw * self._geometric_slope).tocsr())

    def lateral_modes(self, weight_on_bit: float) -> tuple[ModeFamily, ModeFamily, list[np.ndarray]]:
        """The lateral families at ``weight_on_bit`` [N] (Rayleigh–Ritz on the fixed space) and, per plane, the
        Ritz coefficients ``y`` (the modes are ``V y``)."""
        w = self._check(weight_on_bit)
        dw = w - self.weight_on_bit
        n_dofs = self.nominal.static.mesh.n_dofs
        out, coefficients, count = [], [], None
        for name, plane in zip(("lateral_y", "lateral_z"), self._planes):
            values, vectors = sla.eigh(plane.stiffness + dw * plane.slope, plane.mass)
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
        """The reduced model of ``realized``: this model's case with another weight-on-bit (in the range) and
        possibly other parameters of its bit–rock and contact laws and its start; which other parameters may
        differ is the caller's to check (:mod:`drillstring.stochastic.study_model`)."""
        w = self._check(realized.operation.weight_on_bit)
        nominal = self.nominal
        lateral_y, lateral_z, coefficients = self.lateral_modes(w)
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
        if alpha or beta:
            dw = w - self.weight_on_bit
            rayleigh = t.T @ ((alpha * self._mass + beta * (self._stiffness + dw * self._stiffness_slope)) @ t)
            structural = structural + 0.5 * (rayleigh + rayleigh.T)
        damping = t.T @ (self._fluid @ t) + structural
        static = self.static_at(w)
        system = self.system_at(w)
        return ReducedOrderModel(
            static=static, system=system, modes=modes, basis=basis, family=family, angular_frequencies=omega,
            damping=damping, top_speed=nominal.top_speed, weight_on_bit=w, bit_rock=case_bit_rock(realized),
            contact=case_contact(realized), stations=nominal.stations, probe_positions=nominal.probe_positions,
            nonlinear=nominal.nonlinear,
            generalized_force=np.concatenate([nominal.generalized_force[fixed], np.zeros(2 * count)]),
            turning_loads=nominal.turning_loads, top_drive=nominal.top_drive,
            hook_load=case_hook_load(realized, w),
            residual_columns=np.concatenate([nominal.residual_columns[fixed], np.zeros(2 * count, dtype=bool)]),
            coupled=False, motor=None, rotor=None,
        )


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
