"""Static lateral buckling margin of the prestressed string: the critical weight-on-bit.

Layer: after :mod:`drillstring.statics` and :mod:`drillstring.modal` (uses their results only).

The lateral stiffness of the prestressed string (one bending plane; the other is identical) is

    K(wob) = K + K_stab + K_f + K_g(N),          N(x) = N_0(x) − wob                        (1)

with the elastic stiffness ``K``, the stabilizer springs ``K_stab``, the fluid stiffness ``K_f``
(centrifugal compression of the mud), and the geometric stiffness
``K_g(N) = ∫ N(x) N_v'ᵀ N_v' dx`` (docs/model.md §2), on the lateral DOFs left free by the dynamic boundary
conditions (:func:`drillstring.modal.family_dofs`: top and bit pinned, ``v = 0``). The axial problem
is linear and its top is held, so a bit reaction ``wob`` adds the same compression ``wob`` to every
section: ``N_0`` is the axial force at ``wob = 0`` and (1) is exact for the finite-element static
state (:func:`drillstring.statics.solve_statics`). ``K_g`` is linear in ``N``, hence ``K`` is affine
in ``wob``::

    K(wob) = K(w_s) − (wob − w_s) G,        G = K_g(N ≡ 1) = ∫ N_v'ᵀ N_v' dx  (positive semi-definite)

about any state ``w_s``. ``K`` decreases with ``wob`` (in the order of symmetric matrices), and the
**critical weight-on-bit** is the first ``wob`` at which ``K(wob)`` stops being positive definite:
the smallest eigenvalue ``λ`` of the generalized symmetric eigenproblem ``K(w_s) φ = λ G φ`` plus
``w_s``. It is solved directly as ``G φ = μ K(w_s) φ`` with ``K(w_s)`` positive definite,
``wob_cr = w_s + 1/μ_max`` (dense ``eigh``, or ``eigsh`` for large families); no bisection.
If the string is already buckled at ``w_s``, the reference state is moved to a smaller weight-on-bit
(a pull at the bit) where it is not.

At the case's own weight-on-bit, the lowest lateral eigenvalue ``ω₁²`` of ``(K(wob), M + M_f)``
(signed) says the same thing dynamically: ``ω₁² < 0`` exactly when ``wob > wob_cr``.

Everything else is fixed: gravity, buoyancy, fluid flow, stabilizers. The critical load is that of
the straight string in the centre of the borehole (the wall is not a constraint until the string
reaches it), i.e. the bifurcation of Lubinski's "first-order buckling"; see
``docs/verification.md`` for the heavy-column checks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from drillstring.fem.assembly import V, dof, geometric_stiffness
from drillstring.modal import DENSE_LIMIT, LinearSystem, family_dofs, family_modes
from drillstring.statics import StaticState

__all__ = [
    "BucklingMargin",
    "unit_compression_stiffness",
    "critical_weight_on_bit",
    "buckling_margin",
    "case_buckling_margin",
    "case_critical_weight_on_bit",
    "buckling_probability",
]

#: Bit pulls [N] tried, in order, as the reference state when the string is buckled at its own
#: weight-on-bit (``K(w_s)`` must be positive definite).
_PULLS = (0.0,) + tuple(10.0**k for k in range(3, 13))
#: The family used: both lateral planes are identical, so one suffices.
_FAMILY = "lateral_y"


def unit_compression_stiffness(system: LinearSystem) -> sp.csr_matrix:
    """``G = ∂K/∂(−wob) = K_g(N ≡ 1)``: the geometric stiffness of a unit tension everywhere
    (global, sparse; stiffness per newton of axial force, [1/m] on displacements).
    ``K(wob) = K(w_s) − (wob − w_s) G``."""
    return geometric_stiffness(system.mesh, np.ones(system.mesh.n_nodes))


def _banded_upper(k: sp.spmatrix) -> np.ndarray:
    """Upper banded storage of a symmetric sparse matrix (for ``scipy.linalg.cholesky_banded``)."""
    coo = sp.triu(k).tocoo()
    bandwidth = int(np.max(coo.col - coo.row)) if coo.nnz else 0
    ab = np.zeros((bandwidth + 1, k.shape[0]))
    ab[bandwidth + coo.row - coo.col, coo.col] = coo.data
    return ab


def _is_positive_definite(k: sp.spmatrix) -> bool:
    """Banded Cholesky succeeds (lateral family matrices are banded: nodes are numbered in order)."""
    try:
        sla.cholesky_banded(_banded_upper(k), lower=False, check_finite=False)
    except sla.LinAlgError:
        return False
    return True


def _largest_mu(g: sp.spmatrix, k: sp.spmatrix, dense_limit: int) -> tuple[float, np.ndarray]:
    """Largest eigenvalue and vector of ``G φ = μ K φ`` (``K`` positive definite, ``G`` semi-definite)."""
    if k.shape[0] <= dense_limit:
        values, vectors = sla.eigh(g.toarray(), k.toarray(), subset_by_index=[k.shape[0] - 1] * 2)
        return float(values[0]), vectors[:, 0]
    values, vectors = spla.eigsh(sp.csc_matrix(g), k=1, M=sp.csc_matrix(k), which="LA")
    return float(values[0]), vectors[:, 0]


def _critical(system: LinearSystem, dense_limit: int) -> tuple[float, np.ndarray]:
    dofs = family_dofs(system.mesh, _FAMILY)
    k_s = system.stiffness[dofs][:, dofs]
    g = unit_compression_stiffness(system)[dofs][:, dofs]
    for pull in _PULLS:
        k_ref = (k_s + pull * g).tocsr()  # K(w_s − pull)
        if _is_positive_definite(k_ref):
            break
    else:
        raise ValueError(
            "the lateral stiffness is not positive definite for any weight-on-bit down to a "
            f"pull of {_PULLS[-1]:.0e} N at the bit: the string buckles without weight-on-bit "
            "(check the fluid centrifugal compression and the stabilizers)"
        )
    mu, vector = _largest_mu(g, k_ref, dense_limit)
    reference = system.static.weight_on_bit - pull
    critical = math.inf if mu <= 0.0 else reference + 1.0 / mu
    mode = np.zeros(system.mesh.n_dofs)
    mode[dofs] = vector
    lateral = mode[dof(np.arange(system.mesh.n_nodes), V)]
    scale = lateral[np.argmax(np.abs(lateral))]
    return critical, mode / scale if scale != 0.0 else mode


def critical_weight_on_bit(system: LinearSystem, *, dense_limit: int = DENSE_LIMIT) -> float:
    """Weight-on-bit [N] at which the prestressed lateral stiffness loses positive definiteness.

    ``system`` is the linear system of the case at any weight-on-bit ``w_s`` (its static state
    ``system.static``); the result does not depend on ``w_s``. The stiffness is
    ``system.stiffness`` = K + K_stab + K_g + K_f as the system was built, with the lateral boundary
    conditions of :func:`drillstring.modal.family_dofs`. Families with more than ``dense_limit``
    DOFs use sparse Lanczos (``eigsh``). ``inf`` if no compression can buckle the string.
    Model and method: module docstring, eq. (1).
    """
    return _critical(system, dense_limit)[0]


@dataclass(frozen=True)
class BucklingMargin:
    """Lateral buckling margin of a string at its weight-on-bit (SI units).

    Attributes:
        critical_weight_on_bit: wob_cr [N] (:func:`critical_weight_on_bit`).
        weight_on_bit: the state's weight-on-bit [N].
        weight: the string's weight ∫ q dx [N] (buoyed if the case says so).
        lowest_lateral_eigenvalue: ω₁² [rad²/s²] of the lateral family at ``weight_on_bit``, signed
            (negative: statically buckled).
        mode: buckling mode at ``wob_cr`` (global DOF vector, lateral y plane, largest |v| = 1).
    """

    critical_weight_on_bit: float
    weight_on_bit: float
    weight: float
    lowest_lateral_eigenvalue: float
    mode: np.ndarray

    @property
    def buckled(self) -> bool:
        """True when the straight string is statically unstable at its weight-on-bit (ω₁² < 0)."""
        return self.lowest_lateral_eigenvalue < 0.0

    @property
    def margin(self) -> float:
        """wob_cr − wob [N]: extra weight-on-bit the string takes before buckling (negative: buckled)."""
        return self.critical_weight_on_bit - self.weight_on_bit

    @property
    def critical_weight_on_hook(self) -> float:
        """Weight-on-hook [N] at buckling, weight − wob_cr: a smaller hook load buckles the string."""
        return self.weight - self.critical_weight_on_bit


def buckling_margin(system: LinearSystem, *, dense_limit: int = DENSE_LIMIT) -> BucklingMargin:
    """Critical weight-on-bit, and lowest lateral eigenvalue at the system's own weight-on-bit."""
    critical, mode = _critical(system, dense_limit)
    lowest = family_modes(system, _FAMILY, 1).eigenvalues[0]
    static: StaticState = system.static
    return BucklingMargin(float(critical), float(static.weight_on_bit), float(static.weight),
                          float(lowest), mode)


def case_buckling_margin(case, static: StaticState | None = None) -> BucklingMargin:
    """:func:`buckling_margin` of a :class:`~drillstring.case.Case` at its weight-on-bit (or at
    ``static``'s) with its mesh, stabilizers, fluid, gravity and buoyancy."""
    from drillstring.modal import case_linear_system
    from drillstring.statics import case_static_state

    static = case_static_state(case) if static is None else static
    return buckling_margin(case_linear_system(case, static))


def case_critical_weight_on_bit(case) -> float:
    """The critical weight-on-bit [N] that a study or a map compares its weights-on-bit with. Without
    ``[well]``: the straight string's, :func:`case_buckling_margin` (eq. (1)). With ``[well]``: sinusoidal
    buckling along the well path on the stiff string's axial force
    (:func:`drillstring.well.stiff_string.case_well_buckling_margin`, eq. (3) of :mod:`drillstring.well.buckling`:
    Dawson–Paslay, in curved sections Wu & Juvkam-Wold), the criterion of the deviated hole, where the
    straight string's does not apply."""
    if case.well is None:
        return case_buckling_margin(case).critical_weight_on_bit
    from drillstring.well.stiff_string import (
        case_stiff_string,
        case_well_buckling_margin,
    )

    return case_well_buckling_margin(case, case_stiff_string(case)).critical_weight_on_bit


def buckling_probability(weight_on_hook_law, weight: float, critical_weight_on_bit: float) -> float:
    """Probability that a random weight-on-hook draw buckles the string.

    A draw ``woh`` gives ``wob = weight − woh`` (docs/model.md §3), beyond the margin when
    ``wob > wob_cr``, i.e. ``woh < weight − wob_cr``. Returns ``P(woh < weight − wob_cr)``.

    Args:
        weight_on_hook_law: any law with a ``cdf`` method [N → probability], e.g. the density of a
            study's ``weight_on_hook`` law (a :class:`drillstring.stochastic.maxent.MaxEntDensity`) or a
            frozen ``scipy.stats`` distribution.
        weight: the string's weight [N].
        critical_weight_on_bit: wob_cr [N].
    """
    if not math.isfinite(weight):
        raise ValueError(f"weight = {weight!r} N: must be finite")
    if math.isnan(critical_weight_on_bit):
        raise ValueError("critical_weight_on_bit = nan N: must be a number (or inf)")
    if critical_weight_on_bit == math.inf:
        return 0.0
    return float(weight_on_hook_law.cdf(weight - critical_weight_on_bit))
