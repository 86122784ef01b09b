"""Structural damping of the string, defined on its modes (docs/model.md §7).

The reference data give ``c1``, the "friction coefficient for the axial rigid body motion", ``c2``, the
"friction coefficient for the rotation rigid body motion", and ``ξ``, the damping ratio of "the i-th
mode". Rigid-body motions exist only for the **unconstrained** (free–free) string, so the damping of the
axial and torsional families is defined on their free–free modes ``Φ`` (mass-normalised,
``Φᵀ M Φ = I``, the rigid mode first) and built as a physical damping matrix (``free_free``)::

    C = M Φ diag(c_i) Φᵀ M,     c_i = 2 ξ ω_i (elastic),  c_0 = c / m_rigid (rigid)          (1)

with ``m_rigid = rᵀ M r`` the generalised mass of the unit rigid shape ``r`` (``r = 1`` on every axial or
torsional DOF: ``m_rigid`` is the string's mass, resp. its polar moment of inertia ``J``). Then
``Φᵀ C Φ = diag(c_i)``: every free–free mode has exactly its ratio ``ξ`` and the rigid motion the
resistance ``rᵀ C r = c`` [N·s/m, N·m·s/rad]. All the family's modes enter (1) (a dense eigenproblem on
the family's DOFs, one per node): ``C`` is a property of the string, not of a truncated basis.

The reduced model then projects ``C`` on the kinematic basis that the boundary conditions leave:

- **axial**: the top is axially free (constant hook force), so the basis is the free–free modes
  themselves (truncated) and the projection is diagonal, ``2 ξ ω_i`` and ``c1 / m``;
- **torsion**: the top rotation is imposed, ``θx = Ω t r + Ψ η`` with ``Ψ`` the top-held modes, so the
  damping force ``−C (Ω r + Ψ η̇)`` gives the dense block ``Ψᵀ C Ψ`` and a constant generalised force
  ``−Ω Ψᵀ C r = −(c2 Ω / J) Ψᵀ M r`` (the rigid-rotation friction that the rotary table overcomes). The
  first top-held mode, mostly a rigid rotation of the string about the held top, keeps only a fraction
  of ``ξ`` (≈ 0.088 instead of 0.3 on the reference string), which is what lets the bit–rock law drive
  the self-excited torsional vibration;
- **lateral**: top and bit are held laterally by the rig and the borehole bottom, so the string has no
  lateral rigid-body motion to which a ``c1``/``c2``-like coefficient could belong; the lateral family
  keeps modal damping ``2 ξ |ω_i|`` on its own (pinned–pinned, prestressed) modes, the ROM's basis.

Long strings and fine meshes: the projection ``ψᵀ C ψ`` needs every free–free mode of (1), a dense
eigenproblem of the family's size. Above :data:`DENSE_LIMIT` DOFs it is computed without any mode and
without forming ``C`` (:func:`projected_free_free_damping`): with the rigid part split off, the elastic part
of (1) is ``2 ξ M S`` with ``S = (M⁻¹K)^{1/2}`` (``M Φ diag(ω) Φᵀ M``), and for ``ψ'`` M-orthogonal to the
rigid shape

    ψ'ᵀ M S ψ' = (2/π) ∫₀^∞ (K ψ)ᵀ (t² M + K)⁻¹ (M ψ') dt,                                   (2)

(``(2/π) ∫ ω² dt / (t² + ω²) = ω`` on each mode), integrated by the trapezoidal rule in ``s = ln t``,
where the integrand of each mode is ``(ω/2) sech(s − ln ω)``: the rule converges like ``exp(−π²/Δs)``
(Trefethen & Weideman, SIAM Rev. 56 (2014) 385, §5), 6e-15 relative at ``Δs = 0.3``. Each node of the rule
is one sparse solve with the banded ``t² M + K``: memory and time linear in the family's size.

**Rayleigh damping** (``rayleigh = (α, β)``, optional, added to either definition): ``C_R = α M + β K``
(Rayleigh, *The Theory of Sound* I, §97, 1877; Clough & Penzien, *Dynamics of Structures*, §12-4), projected
on the basis as ``α Φᵀ M Φ + β Φᵀ K Φ`` (every family; ``K`` the linear stiffness, without prestress). On a
mode of circular frequency ω it gives the ratio ``ξ(ω) = α/(2ω) + βω/2``. ``α`` alone is viscous damping
proportional to mass: for a uniform rod ``ρA ü + α ρA u̇ = EA u''`` (and likewise in torsion), the distributed
damping of Aarsnes & van de Wouw's drill-string model (J. Sound Vib. 444 (2019) 127–151, their ``k`` [1/s]).
It acts on the absolute velocity, so the rigid motions feel it too (``C_R r = α M r``: the resistance
``α m`` to a rigid translation, ``α J`` to a rigid rotation) and, with the top rotation imposed, it adds the
constant generalised force ``−Ω α Ψᵀ M r``.

``constrained`` is the earlier definition: ``2 ξ |ω_i|`` on every elastic basis mode (torsional modes
top-held), ``c1 / m`` on the rigid axial mode, and ``c2`` unused. It over-damps the first torsional mode
(ξ = 0.3 instead of ≈ 0.09) and is kept as an option for comparison.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from drillstring.fem.assembly import THETA_X, U, dof

#: The damping definitions: on the free–free modes (default) or on the constrained basis modes.
DAMPING_BASES = ("free_free", "constrained")


@dataclass(frozen=True)
class FreeFreeDamping:
    """The physical damping matrix of one family built on its free–free modes, eq. (1).

    Attributes:
        matrix: ``C`` on the family's DOFs, (n, n), symmetric positive semi-definite
            [N·s/m for axial DOFs, N·m·s/rad for torsional DOFs].
        angular_frequencies: free–free ω_i [rad/s], rigid mode (0) first.
        shapes: free–free mode shapes Φ (n, n), mass-normalised, rigid mode first.
        modal_coefficients: c_i [1/s], the diagonal of ``Φᵀ C Φ``.
        rigid_mass: ``m_rigid = rᵀ M r`` [kg or kg·m²].
    """

    matrix: np.ndarray
    angular_frequencies: np.ndarray
    shapes: np.ndarray
    modal_coefficients: np.ndarray
    rigid_mass: float


#: A free–free eigenvalue ω² at most this fraction of the largest is a rigid motion's round-off (the family's
#: other rigid motions: the rotation of the string below a downhole motor, :mod:`drillstring.rotor`), 0 exactly.
RIGID_ROUND_OFF = 1e-12


def free_free_damping(mass, stiffness, damping_ratio: float, rigid_coefficient: float) -> FreeFreeDamping:
    """Damping matrix ``C = M Φ diag(c_i) Φᵀ M`` of a family with one rigid mode ``r = 1``, eq. (1).

    Args:
        mass, stiffness: the family's mass and stiffness on all its DOFs, no boundary condition
            (dense or sparse, n × n); ``stiffness @ 1`` must vanish (the rigid mode).
        damping_ratio: ξ of every elastic mode [-].
        rigid_coefficient: viscous resistance of the rigid motion, c1 [N·s/m] or c2 [N·m·s/rad].
    """
    m = mass.toarray() if sp.issparse(mass) else np.asarray(mass, dtype=float)
    k = stiffness.toarray() if sp.issparse(stiffness) else np.asarray(stiffness, dtype=float)
    rigid, rigid_mass = _has_rigid_mode(m, k)
    omega2, shapes = sla.eigh(k, m, driver="gvd")
    # Use the exact rigid shape; eigh's other vectors are already M-orthogonal to it to round-off.
    shapes[:, 0] = rigid / np.sqrt(rigid_mass)
    omega = np.sqrt(np.clip(omega2, 0.0, None))
    omega[0] = 0.0
    omega[omega2 <= RIGID_ROUND_OFF * omega2.max()] = 0.0  # other rigid motions (a motor's rotor): undamped, exactly
    coefficients = 2.0 * damping_ratio * omega
    coefficients[0] = rigid_coefficient / rigid_mass
    m_phi = (sp.csr_matrix(mass) if sp.issparse(mass) else m) @ shapes  # the family's mass is banded
    matrix = (m_phi * coefficients) @ m_phi.T
    return FreeFreeDamping(0.5 * (matrix + matrix.T), omega, shapes, coefficients, rigid_mass)


#: Families of more DOFs than this get the projection of eq. (2) instead of the dense eigenproblem (on 2 001
#: DOFs: 0.3 s instead of 39 s, agreeing to 8e-12; the reference string's 161 stay dense).
DENSE_LIMIT = 500
#: Step of the trapezoidal rule of eq. (2) in ``s = ln t``; relative error about ``exp(−π²/Δs)``.
_QUADRATURE_STEP = 0.3
#: The rule of eq. (2) stops on each side once a node adds less than this fraction of the sum so far.
_QUADRATURE_TAIL = 1e-16
#: ... or once its nodes decrease geometrically to this relative accuracy (the rest is then summed exactly).
_GEOMETRIC_TAIL = 1e-9


def _has_rigid_mode(mass, stiffness) -> tuple[np.ndarray, float]:
    """The unit rigid shape ``r = 1`` and its generalised mass ``rᵀ M r``; refuses a constrained family."""
    rigid = np.ones(mass.shape[0])
    residual = np.abs(stiffness @ rigid).max()
    largest = abs(stiffness).max()
    if residual > 1e-9 * largest:
        raise ValueError(f"the family has no rigid mode: |K r| = {residual:.3g} (K must be unconstrained)")
    return rigid, float(rigid @ mass @ rigid)


def _elastic_square_root_form(mass: sp.spmatrix, stiffness: sp.spmatrix, shapes: np.ndarray) -> np.ndarray:
    """``ψᵀ M S ψ`` with ``S = (M⁻¹K)^{1/2}`` by the quadrature of eq. (2) (``ψ`` the columns of
    ``shapes``; the family has the rigid shape ``r = 1``, on which ``S`` vanishes)."""
    m, k = sp.csc_matrix(mass), sp.csc_matrix(stiffness)
    rigid = np.ones(m.shape[0])
    m_rigid = m @ rigid
    elastic = shapes - np.outer(rigid, (m_rigid @ shapes) / (rigid @ m_rigid))  # ψ', M-orthogonal to r
    left, right = k @ shapes, m @ elastic  # K ψ = K ψ' (K r = 0)
    rayleigh = np.einsum("ij,ij->", elastic, k @ elastic) / max(np.einsum("ij,ij->", elastic, right), 1e-300)
    centre = 0.5 * np.log(max(rayleigh, 1e-300))

    # (t² M + K) x = M ψ' bordered by the constraint rᵀ M x = 0: regular down to t = 0 (K r = 0), and its
    # solution is the one of the unbordered system for t > 0 (M ψ' has no rigid component).
    # The border last and SuperLU in natural order: the banded family matrices fill only their band.
    border = sp.csc_matrix(m_rigid[:, None])
    bordered_m = sp.bmat([[m, None], [None, sp.csc_matrix((1, 1))]], format="csc")
    bordered_k = sp.bmat([[k, border], [border.T, None]], format="csc")
    rhs = np.vstack([right, np.zeros((1, right.shape[1]))])

    def node(s: float) -> np.ndarray:
        t = np.exp(s)
        lu = spla.splu((t * t * bordered_m + bordered_k).tocsc(), permc_spec="NATURAL")
        return t * (left.T @ lu.solve(rhs)[:-1])

    total = node(centre)
    scale = np.abs(total).max()
    ratio = np.exp(-_QUADRATURE_STEP)
    for direction in (1.0, -1.0):
        s, previous = centre, total
        while True:
            s += direction * _QUADRATURE_STEP
            term = node(s)
            total = total + term
            scale = max(scale, np.abs(total).max())
            if np.abs(term).max() <= _QUADRATURE_TAIL * scale:
                break
            # Far beyond the spectrum each node is the previous one times e^{−Δs} (the integrand goes like
            # ψᵀKψ'/t above it and t ψ'ᵀMψ' below it, to relative order (ω/t)²): add the geometric rest.
            if np.abs(term - ratio * previous).max() <= _GEOMETRIC_TAIL * np.abs(term).max():
                total = total + term * (ratio / (1.0 - ratio))
                break
            previous = term
    form = (2.0 / np.pi) * _QUADRATURE_STEP * total
    return 0.5 * (form + form.T)


def projected_free_free_damping(mass, stiffness, shapes: np.ndarray, damping_ratio: float,
                                rigid_coefficient: float, *, dense_limit: int = DENSE_LIMIT
                                ) -> tuple[np.ndarray, np.ndarray]:
    """``(ψᵀ C ψ, ψᵀ C r)`` of the damping matrix (1) of a family with one rigid mode ``r = 1``, for the
    columns ``ψ`` of ``shapes`` (n, p): [1/s] on a mass-normalised basis.

    Families of at most ``dense_limit`` DOFs build ``C`` from all their modes
    (:func:`free_free_damping`); larger ones never form it nor any mode (eq. (2), module docstring):
    ``ψᵀ C ψ = 2 ξ ψᵀ M S ψ + (c / m_r²) (ψᵀ M r)(rᵀ M ψ)`` and ``C r = (c / m_r) M r``.
    """
    n = mass.shape[0]
    if n <= dense_limit:
        c = free_free_damping(mass, stiffness, damping_ratio, rigid_coefficient).matrix
        return shapes.T @ c @ shapes, shapes.T @ (c @ np.ones(n))
    rigid, m_rigid = _has_rigid_mode(mass, stiffness)
    rigid_load = shapes.T @ (mass @ rigid)  # ψᵀ M r
    rigid_part = (rigid_coefficient / m_rigid**2) * np.outer(rigid_load, rigid_load)
    elastic = 2.0 * damping_ratio * _elastic_square_root_form(mass, stiffness, shapes)
    return elastic + rigid_part, (rigid_coefficient / m_rigid) * rigid_load


@dataclass(frozen=True)
class ReducedDamping:
    """Structural damping projected on a reduced basis.

    Attributes:
        matrix: (n, n) modal damping matrix [1/s] (the basis is mass-normalised).
        generalized_force: (n,) constant generalised force [same units as the modal acceleration,
            N/√kg…] from the damping of the imposed top rotation, ``−Ω Ψᵀ C r`` (0 for ``constrained``).
    """

    matrix: np.ndarray
    generalized_force: np.ndarray


def reduced_structural_damping(
    mass,
    stiffness,
    basis: np.ndarray,
    family: tuple[str, ...] | list[str],
    angular_frequencies: np.ndarray,
    *,
    damping_ratio: float,
    rigid_axial: float,
    rigid_rotation: float,
    top_speed: float,
    definition: str = "free_free",
    rayleigh: tuple[float, float] = (0.0, 0.0),
) -> ReducedDamping:
    """Structural damping of the reduced model (module docstring).

    Args:
        mass, stiffness: the global linear matrices (no boundary condition), n_dofs × n_dofs.
        basis: Φ (n_dofs, n), mass-normalised; ``family[i]`` labels column i ("rigid_axial",
            "axial", "torsional", "lateral_y", "lateral_z").
        angular_frequencies: ω of each basis column [rad/s] (signed: negative for ω² < 0).
        damping_ratio: ξ [-]; rigid_axial: c1 [N·s/m]; rigid_rotation: c2 [N·m·s/rad];
        top_speed: Ω [rad/s], imposed at the top.
        definition: "free_free" or "constrained".
        rayleigh: (α [1/s], β [s]) of the Rayleigh damping ``α M + β K`` added to the above (module docstring).
    """
    if definition not in DAMPING_BASES:
        raise ValueError(f"damping basis = {definition!r}: must be one of {', '.join(DAMPING_BASES)}")
    extra = rayleigh_damping(mass, stiffness, basis, family, rayleigh, top_speed)
    found = _reduced_structural_damping(mass, stiffness, basis, family, angular_frequencies,
                                        damping_ratio=damping_ratio, rigid_axial=rigid_axial,
                                        rigid_rotation=rigid_rotation, top_speed=top_speed, definition=definition)
    if extra is None:
        return found
    return ReducedDamping(found.matrix + extra.matrix, found.generalized_force + extra.generalized_force)


def rayleigh_damping(mass, stiffness, basis: np.ndarray, family, rayleigh: tuple[float, float],
                     top_speed: float) -> ReducedDamping | None:
    """Rayleigh damping ``α M + β K`` on the basis ``Φ`` (module docstring): ``α Φᵀ M Φ + β Φᵀ K Φ`` and, with
    the top rotation imposed at ``top_speed`` Ω [rad/s], the generalised force ``−Ω α Ψᵀ M r`` on the torsional
    columns (``r`` the unit rigid rotation; ``K r = 0``). None when α = β = 0."""
    alpha, beta = (float(v) for v in rayleigh)
    if not (alpha >= 0.0 and beta >= 0.0 and np.isfinite(alpha) and np.isfinite(beta)):
        raise ValueError(f"rayleigh = {rayleigh!r}: alpha [1/s] and beta [s] must be finite and >= 0")
    if alpha == 0.0 and beta == 0.0:
        return None
    matrix = alpha * (basis.T @ (mass @ basis)) + beta * (basis.T @ (stiffness @ basis))
    force = np.zeros(basis.shape[1])
    if alpha and top_speed:
        columns = np.nonzero(np.asarray(family) == "torsional")[0]
        rigid = np.zeros(basis.shape[0])
        rigid[_family_rows(basis.shape[0], THETA_X)] = 1.0
        force[columns] = -top_speed * alpha * (basis[:, columns].T @ (mass @ rigid))
    return ReducedDamping(0.5 * (matrix + matrix.T), force)


def _family_rows(rows: int, kind: int) -> np.ndarray:
    """The rows of the DOF ``kind`` (U, THETA_X) of every node of a basis of ``rows`` rows: 6 per node, and for
    THETA_X the rows past the nodes' too, the rotations a downhole motor releases (:mod:`drillstring.rotor`:
    the rotor side's θx at its station, a torsional DOF of its own)."""
    nodes = np.arange(rows // 6)
    found = dof(nodes, kind)
    return np.concatenate([found, np.arange(6 * len(nodes), rows)]) if kind == THETA_X else found


def _reduced_structural_damping(mass, stiffness, basis, family, angular_frequencies, *, damping_ratio: float,
                                rigid_axial: float, rigid_rotation: float, top_speed: float,
                                definition: str) -> ReducedDamping:
    """:func:`reduced_structural_damping` without the Rayleigh part."""
    labels = np.asarray(family)
    n = basis.shape[1]
    matrix = np.zeros((n, n))
    force = np.zeros(n)
    n_nodes = basis.shape[0] // 6
    nodes = np.arange(n_nodes)
    axial_dofs = dof(nodes, U)
    string_mass = float(mass[axial_dofs][:, axial_dofs].sum())
    modal = np.where(labels == "rigid_axial", 0.0, 2.0 * damping_ratio * np.abs(angular_frequencies))
    np.fill_diagonal(matrix, modal)
    matrix[labels == "rigid_axial", labels == "rigid_axial"] = rigid_axial / string_mass
    if definition == "constrained":
        return ReducedDamping(matrix, force)
    for names, kind, coefficient, imposed_speed in (
        (("rigid_axial", "axial"), U, rigid_axial, 0.0),
        (("torsional",), THETA_X, rigid_rotation, top_speed),
    ):
        columns = np.nonzero(np.isin(labels, names))[0]
        if len(columns) == 0:
            continue
        dofs = _family_rows(basis.shape[0], kind)
        block, rigid_force = projected_free_free_damping(
            mass[dofs][:, dofs], stiffness[dofs][:, dofs], basis[dofs][:, columns], damping_ratio, coefficient)
        matrix[np.ix_(columns, columns)] = block
        if imposed_speed:
            force[columns] = -imposed_speed * rigid_force
    return ReducedDamping(matrix, force)
