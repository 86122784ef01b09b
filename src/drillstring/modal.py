"""Natural modes of the prestressed linear system with the dynamic boundary conditions (docs/model.md §6).

Linear system (docs/model.md §2–§4): mass ``M + M_f``, stiffness ``K + K_stab + K_g(q_S) + K_f``.
Dynamic boundary conditions: top ``v = w = 0`` and ``θx`` imposed (so its relative rotation is 0),
top axially free; bit ``v = w = 0``, ``u`` and ``θx`` free; bending rotations free at both ends.

For a straight string the axial, torsional and the two lateral planes are uncoupled (the coupling
blocks of the matrices are exactly zero; :func:`family_coupling` measures it), so each family is solved
as its own generalised symmetric eigenproblem. This classifies modes without ambiguity and separates
the degenerate y/z lateral pairs cleanly. The axial family (both ends free) starts with the rigid
axial translation, frequency 0.

Families are a property of the assembled matrices, not an assumption: when they couple (elements rotated
out of the straight axis, :mod:`drillstring.fem.geometry`), :func:`coupled_modes` solves the whole system on
the union of the families' free DOFs, one basis whose every column may move every DOF (a
:class:`ModeFamily` named ``"coupled"``, its rigid axial translation first when the system has one).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from drillstring.fem.assembly import (
    THETA_X,
    THETA_Y,
    THETA_Z,
    U,
    V,
    W,
    Stabilizer,
    dof,
    fluid_matrices,
    geometric_stiffness,
    stabilizer_stiffness,
    structural_matrices,
)
from drillstring.derived import family_nodes
from drillstring.fem.fluid import FluidCoefficients
from drillstring.fem.mesh import Mesh
from drillstring.statics import StaticState

FAMILIES = ("axial", "torsional", "lateral_y", "lateral_z")
#: The nodal DOF kinds named by :func:`drillstring.derived.family_nodes`.
_DOF_KIND = {"u": U, "v": V, "w": W, "theta_x": THETA_X, "theta_y": THETA_Y, "theta_z": THETA_Z}
#: Above this many DOFs in a family, use sparse shift-invert Lanczos (eigsh) instead of dense eigh.
DENSE_LIMIT = 2500


@dataclass(frozen=True)
class LinearSystem:
    """Global linear matrices of the prestressed string (sparse, no boundary conditions applied)."""

    mesh: Mesh
    static: StaticState
    structural_mass: sp.csr_matrix  # M
    fluid_mass: sp.csr_matrix  # M_f
    elastic_stiffness: sp.csr_matrix  # K + K_stab
    geometric_stiffness: sp.csr_matrix  # K_g(q_S)
    fluid_stiffness: sp.csr_matrix  # K_f
    fluid_damping: sp.csr_matrix  # C_f (Coriolis + viscous), non-symmetric

    @property
    def mass(self) -> sp.csr_matrix:
        return (self.structural_mass + self.fluid_mass).tocsr()

    @property
    def stiffness(self) -> sp.csr_matrix:
        return (self.elastic_stiffness + self.geometric_stiffness + self.fluid_stiffness).tocsr()


def build_linear_system(
    mesh: Mesh,
    static: StaticState,
    stabilizers: list[Stabilizer],
    fluid: list[FluidCoefficients],
    *,
    prestress: bool = True,
    rotations: np.ndarray | None = None,
) -> LinearSystem:
    """Assemble the prestressed linear system (``prestress=False`` drops ``K_g``); ``rotations`` (n_el, 3, 3):
    each element's direction cosines (:mod:`drillstring.fem.geometry`), None: a straight string along x."""
    k, m = structural_matrices(mesh, rotations)
    m_f, c_f, k_f = fluid_matrices(mesh, fluid, rotations)
    k_g = geometric_stiffness(mesh, static.axial_force if prestress else np.zeros(mesh.n_nodes), rotations)
    return LinearSystem(mesh, static, m, m_f, (k + stabilizer_stiffness(mesh, stabilizers)).tocsr(),
                        k_g, k_f, c_f)


def family_dofs(mesh: Mesh, family: str, top_free: bool = False) -> np.ndarray:
    """Free DOFs of a mode family under the dynamic boundary conditions (sorted); ``top_free``: the top's
    rotation is free (a top drive) instead of imposed. The boundary conditions are those of
    :func:`drillstring.derived.family_nodes` (which :func:`drillstring.derived.mode_family_sizes` counts)."""
    if family not in FAMILIES:
        raise ValueError(f"family = {family!r}: must be one of {', '.join(FAMILIES)}")
    kinds = family_nodes(mesh.n_nodes, top_free)[family]
    return np.sort(np.concatenate([dof(np.asarray(nodes, dtype=np.int64), _DOF_KIND[kind])
                                   for kind, nodes in kinds]))


def coupled_dofs(mesh: Mesh) -> np.ndarray:
    """The free DOFs of the whole string under the dynamic boundary conditions (top held in rotation): the
    union of every family's (:func:`family_dofs`), sorted."""
    return np.unique(np.concatenate([family_dofs(mesh, f) for f in FAMILIES]))


def family_coupling(system: LinearSystem) -> float:
    """Largest |entry| of M, K or C_f that couples two different families: exactly 0 for a straight string,
    positive when elements are rotated out of the string's axis (:mod:`drillstring.fem.geometry`)."""
    n = system.mesh.n_dofs
    label = np.full(n, -1)
    for i, family in enumerate(FAMILIES):
        label[family_dofs(system.mesh, family)] = i
    worst = 0.0
    for matrix in (system.mass, system.stiffness, system.fluid_damping):
        coo = matrix.tocoo()
        mask = (label[coo.row] != label[coo.col]) & (label[coo.row] >= 0) & (label[coo.col] >= 0)
        if mask.any():
            worst = max(worst, float(np.abs(coo.data[mask]).max()))
    return worst


@dataclass(frozen=True)
class ModeFamily:
    """Modes of one family.

    Attributes:
        name: "axial", "torsional", "lateral_y" or "lateral_z".
        angular_frequencies: ω [rad/s], ascending; negative values flag unstable (ω² < 0) modes,
            reported as −sqrt(|ω²|).
        shapes: (n_dofs, n_modes) global mode shapes, zero on constrained DOFs, normalised to unit
            modal mass: φᵀ (M + M_f) φ = 1.
        attachments: the last ``attachments`` columns are not modes but the family's residual-flexibility
            attachment modes (Ritz vectors, their ω the Rayleigh quotients), 0 without a truncation correction.
    """

    name: str
    angular_frequencies: np.ndarray
    shapes: np.ndarray
    attachments: int = 0  # the last columns that are attachment modes (:func:`residual_flexibility_modes`)

    @property
    def frequencies(self) -> np.ndarray:
        """Natural frequencies [Hz]."""
        return self.angular_frequencies / (2.0 * np.pi)

    @property
    def eigenvalues(self) -> np.ndarray:
        """ω² [rad²/s²] (signed)."""
        return np.sign(self.angular_frequencies) * self.angular_frequencies**2


@dataclass(frozen=True)
class Modes:
    """Mode families of the prestressed string."""

    axial: ModeFamily
    torsional: ModeFamily
    lateral_y: ModeFamily
    lateral_z: ModeFamily
    #: the one basis of a system whose families couple (:func:`coupled_modes`); the four families are then empty
    coupled: ModeFamily | None = None

    @property
    def lateral(self) -> ModeFamily:
        """One plane of the degenerate lateral pairs (each pair listed once)."""
        return self.lateral_y


def count_below(k: sp.spmatrix, m: sp.spmatrix, sigma: float) -> int | None:
    """Number of eigenvalues of the pencil (K, M) below ``sigma`` (M positive definite), by Sylvester's law
    of inertia: the number of negative pivots of the LDLᵀ factorisation of ``K − σM``. SuperLU in its
    natural order with diagonal pivots (no row exchanges) is that factorisation for a symmetric matrix;
    for the banded family matrices it fills only the band. ``None`` if SuperLU exchanged rows anyway
    (a zero pivot) or ``σ`` is an eigenvalue."""
    shifted = sp.csc_matrix(k - sigma * m)
    try:
        lu = spla.splu(shifted, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError:  # exactly singular
        return None
    if not np.array_equal(lu.perm_r, np.arange(shifted.shape[0])):
        return None
    return int(np.count_nonzero(lu.U.diagonal() < 0.0))


#: Largest memory [bytes] the dense fallback of :func:`_eigen` may take (three n × n arrays).
DENSE_FALLBACK_MEMORY = 2 * 2**30


def _dense_eigen(k, m, count: int):
    n = k.shape[0]
    need = 3 * 8 * n * n
    if need > DENSE_FALLBACK_MEMORY:
        raise ValueError(f"the eigenproblem of a {n:,}-DOF family has no sparse solution here and would need "
                         f"{need / 2**30:.1f} GiB dense, more than the {DENSE_FALLBACK_MEMORY / 2**30:g} GiB "
                         "allowed: use a larger mesh.max_element_length")
    kd = k.toarray() if sp.issparse(k) else k
    md = m.toarray() if sp.issparse(m) else m
    return sla.eigh(kd, md, subset_by_index=[0, count - 1])


def _eigen(k: np.ndarray | sp.spmatrix, m: np.ndarray | sp.spmatrix, count: int):
    n = k.shape[0]
    count = min(count, n)
    if n <= DENSE_LIMIT or count >= n - 1:
        return _dense_eigen(k, m, count)
    # Shift-invert Lanczos returns the eigenvalues nearest the shift, so the shift must lie below the whole
    # spectrum: start at −1 rad²/s² (below a rigid mode's 0, where K is singular) and move it down by
    # decades while K − σM has negative pivots (eigenvalues below σ: a buckled string).
    k, m = sp.csc_matrix(k), sp.csc_matrix(m)
    sigma = -1.0
    for _ in range(40):
        below = count_below(k, m, sigma)
        if below == 0:
            break
        sigma *= 10.0
    else:
        below = None
    if below != 0:  # no inertia to go by: the dense solver is slower but always right
        return _dense_eigen(k, m, count)
    values, vectors = spla.eigsh(k, k=count, M=m, sigma=sigma, which="LM")
    order = np.argsort(values)
    values, vectors = values[order], vectors[:, order]
    # none skipped: exactly `count` eigenvalues lie below the largest one found (plus a rounding margin)
    top = values[-1] + 1e-9 * max(1.0, float(np.abs(values).max()))
    if count_below(k, m, top) != count:
        return _dense_eigen(k, m, count)
    return values, vectors


def top_inertia_matrix(mesh: Mesh, top_inertia: float) -> sp.csr_matrix:
    """The top drive's rotary inertia ``J_td`` [kg·m²] lumped at the top node's θx, as a global matrix."""
    i = int(dof(0, THETA_X))
    return sp.csr_matrix(([float(top_inertia)], ([i], [i])), shape=(mesh.n_dofs, mesh.n_dofs))


def family_modes(system: LinearSystem, family: str, count: int, top_inertia: float | None = None) -> ModeFamily:
    """The ``count`` lowest modes of one family (``count`` may be 0). ``top_inertia`` [kg·m²] (torsional
    family only): the top rotation is free, carrying that inertia (a top drive); the first mode is then the
    rigid rotation and the shapes are normalised with the top-drive inertia included."""
    top_free = top_inertia is not None and family == "torsional"
    dofs = family_dofs(system.mesh, family, top_free)
    n_dofs = system.mesh.n_dofs
    if count <= 0:
        return ModeFamily(family, np.zeros(0), np.zeros((n_dofs, 0)))
    mass = system.mass + top_inertia_matrix(system.mesh, top_inertia) if top_free else system.mass
    k = system.stiffness[dofs][:, dofs]
    m = mass[dofs][:, dofs]
    values, vectors = _eigen(k, m, count)
    shapes = np.zeros((n_dofs, len(values)))
    shapes[dofs] = vectors
    if family == "axial" or top_free:
        # Both ends free: the first mode is the rigid translation (rotation). Use it exactly.
        rigid = np.zeros(n_dofs)
        rigid[dofs] = 1.0
        rigid /= np.sqrt(rigid @ (mass @ rigid))
        shapes[:, 0] = rigid
        values = values.copy()
        values[0] = 0.0
    mass_normalised(shapes, mass)  # eigh already gives unit modal mass; eigsh may not
    omega = np.sign(values) * np.sqrt(np.abs(values))
    return ModeFamily(family, omega, shapes)


def family_modes_below(system: LinearSystem, family: str, count: int, cutoff: float) -> ModeFamily:
    """The lowest modes of one family: at least ``count``, and every mode with ``ω < cutoff`` [rad/s]
    (all modes with ``ω² < cutoff²``, unstable ones included), as many as the family has at most."""
    size = len(family_dofs(system.mesh, family))
    found = family_modes(system, family, count)
    if not cutoff > 0.0:
        return found
    wanted = max(count, 1)
    while wanted < size and (len(found.eigenvalues) < wanted or found.eigenvalues[-1] < cutoff**2):
        wanted = min(size, 2 * wanted)
        found = family_modes(system, family, wanted)
    keep = max(count, int(np.count_nonzero(found.eigenvalues < cutoff**2)))
    return ModeFamily(family, found.angular_frequencies[:keep], found.shapes[:, :keep])


#: The truncation corrections of :func:`compute_modes` (case key ``reduced_model.truncation_correction``).
TRUNCATION_CORRECTIONS = ("none", "static")


def residual_flexibility_vectors(k: sp.csc_matrix, m: sp.csr_matrix, phi: np.ndarray, load: np.ndarray,
                                 rigid: int = 0, ground=(0,)):
    """The residual-flexibility attachment vectors of one family on its own DOFs (the algorithm of
    :func:`residual_flexibility_modes`, Craig & Chang 1977): ``K⁻¹ f`` for each column ``f`` of ``load`` made
    M-orthogonal to the kept modes ``phi`` (M-orthonormal columns), then put in Rayleigh–Ritz form. ``rigid``:
    the first ``rigid`` columns of ``phi`` are the family's rigid motions (K singular): each load is balanced by
    their inertia, ``f − M R Rᵀ f`` (inertia relief), and the response taken with the local DOFs ``ground``
    held (one per rigid motion, so that the rest of K is regular). Returns ``(ω̃², vectors)`` (ascending, the
    vectors M-orthonormal up to rounding) or None when the kept modes already span every response."""
    n = k.shape[0]
    response = np.zeros_like(load)
    if rigid:
        r = phi[:, :rigid]
        load = load - m @ (r @ (r.T @ load))
        free = np.setdiff1d(np.arange(n), np.asarray(ground, dtype=np.int64))
        response[free] = spla.splu(k[free][:, free]).solve(load[free])
    else:
        response = spla.splu(k).solve(load)
    before = np.sqrt(np.einsum("ij,ij->j", response, m @ response))
    for _ in range(2):  # M-orthogonal to every kept mode (twice: classical Gram–Schmidt, re-orthogonalised)
        response -= phi @ (phi.T @ (m @ response))
    k_r = response.T @ (k @ response)
    m_r = response.T @ (m @ response)
    # a response the kept modes already span (all the family's modes kept) leaves only rounding
    keep = np.sqrt(np.maximum(np.diag(m_r), 0.0)) > 1e-8 * before
    if not keep.any():
        return None
    response, k_r, m_r = response[:, keep], k_r[np.ix_(keep, keep)], m_r[np.ix_(keep, keep)]
    values, q = sla.eigh(k_r, m_r)
    return values, response @ q


def mass_normalised(shapes: np.ndarray, mass) -> np.ndarray:
    """``shapes`` (one mode a column) scaled in place to unit modal mass ``φᵀ M φ = 1`` with ``mass``, each
    with a deterministic sign (its largest entry positive); returns it."""
    shapes /= np.sqrt(np.einsum("ij,ij->j", shapes, mass @ shapes))
    pivot = np.argmax(np.abs(shapes), axis=0)
    shapes *= np.sign(shapes[pivot, np.arange(shapes.shape[1])])
    return shapes


def check_truncation_correction(truncation_correction: str) -> None:
    """ValueError naming ``truncation_correction`` unless it is one of :data:`TRUNCATION_CORRECTIONS`."""
    if truncation_correction not in TRUNCATION_CORRECTIONS:
        raise ValueError(f"truncation_correction = {truncation_correction!r}: must be one of "
                         f"{', '.join(TRUNCATION_CORRECTIONS)}")


def attachment_loads(dofs: np.ndarray, load_dofs, patterns: np.ndarray | None = None) -> np.ndarray:
    """The loads of a static correction on a family's DOFs ``dofs`` (global numbers, ascending), one column each:
    a unit load at each of ``load_dofs`` (global DOFs, in their order) the family holds, then each column of ``patterns``
    ((n_dofs, p) global load vectors, e.g. the along-string friction's distribution,
    :func:`drillstring.dynamics.reduced.build.friction_load_patterns`) restricted to ``dofs``, those with no entry
    there left out. (len(dofs), count) [N or N·m per unit]."""
    wanted = np.asarray(load_dofs, dtype=np.int64)
    local = np.searchsorted(dofs, wanted)
    local = local[(local < len(dofs)) & (dofs[np.minimum(local, len(dofs) - 1)] == wanted)]
    load = np.zeros((len(dofs), len(local)))
    load[local, np.arange(len(local))] = 1.0
    if patterns is None:
        return load
    restricted = np.asarray(patterns, dtype=float)[dofs]
    return np.hstack([load, restricted[:, np.any(restricted != 0.0, axis=0)]])


def residual_flexibility_modes(system: LinearSystem, kept: ModeFamily, load_dofs, top_inertia: float | None = None,
                               rigid: bool = False, patterns: np.ndarray | None = None) -> ModeFamily:
    """``kept`` with the static correction for the modes left out at ``load_dofs`` (global DOFs of the family):
    its residual-flexibility attachment modes, appended after the kept modes.

    For a unit load ``f`` at each load DOF the residual flexibility response is
    ``ψ = (K⁻¹ − Φ Ω⁻² Φᵀ) f`` (Craig & Chang, "On the use of attachment modes in substructure coupling for
    dynamic analysis", AIAA paper 77-405, 1977; MacNeal, Comput. Struct. 1 (1971) 581): the static response
    ``K⁻¹ f`` less what the kept modes already carry, i.e. ``K⁻¹ f`` made M-orthogonal to the kept modes (then
    K-orthogonal too, since ``K Φ = M Φ Ω²``). With a rigid mode (``rigid``: the kept family's first column,
    ``K`` singular) the load is first balanced by the rigid body's inertia, ``f − M r rᵀ f`` (inertia relief),
    and the response taken with one DOF grounded; the M-orthogonalisation then removes the rigid part.
    The span of these responses is put in Rayleigh–Ritz form, ``Ψᵀ M Ψ = I``, ``Ψᵀ K Ψ = diag(ω̃²)``, so that
    the augmented basis ``[Φ Ψ]`` still diagonalises both matrices (the reduced model needs no other change)
    and each ω̃ lies above the highest kept ω. The augmented basis reproduces exactly the static (quasi-static)
    response to any load at ``load_dofs``, which a truncated modal basis does not.

    ``top_inertia``: the top-drive inertia [kg·m²] lumped at the top's θx (a torsional family free at the top),
    None when the top is held. ``patterns``: (n_dofs, p) load vectors (global DOFs) corrected as well, one
    attachment column each (:func:`attachment_loads`). Load DOFs the family does not hold, or responses the kept
    modes already span, add nothing."""
    family = kept.name
    top_free = top_inertia is not None and family == "torsional"
    dofs = coupled_dofs(system.mesh) if family == "coupled" else family_dofs(system.mesh, family, top_free)
    mass_global = system.mass + top_inertia_matrix(system.mesh, top_inertia) if top_free else system.mass
    k = sp.csc_matrix(system.stiffness[dofs][:, dofs])
    m = sp.csr_matrix(mass_global[dofs][:, dofs])
    load = attachment_loads(dofs, load_dofs, patterns)
    phi = kept.shapes[dofs]
    if load.shape[1] == 0 or phi.shape[1] >= len(dofs):
        return kept
    found = residual_flexibility_vectors(k, m, phi, load, 1 if rigid else 0, [0])  # grounded at the top
    if found is None:
        return kept
    return with_attachments(kept, dofs, *found, mass_global)


def with_attachments(kept: ModeFamily, dofs: np.ndarray, values: np.ndarray, vectors: np.ndarray,
                     mass: sp.spmatrix) -> ModeFamily:
    """``kept`` with the attachment vectors of :func:`residual_flexibility_vectors` (``vectors`` on ``dofs``,
    their ``values`` ω̃² [rad²/s²]) appended as its last columns: spread on the global DOFs, mass-normalised
    with ``mass`` (global), a deterministic sign (the largest entry positive)."""
    shapes = np.zeros((kept.shapes.shape[0], vectors.shape[1]))
    shapes[dofs] = vectors
    mass_normalised(shapes, mass)
    omega = np.sign(values) * np.sqrt(np.abs(values))
    return ModeFamily(kept.name, np.concatenate([kept.angular_frequencies, omega]),
                      np.hstack([kept.shapes, shapes]), kept.attachments + shapes.shape[1])


def compute_modes(system: LinearSystem, axial: int, torsional: int, lateral: int,
                  lateral_cutoff: float = 0.0, top_inertia: float | None = None,
                  truncation_correction: str = "none", load_patterns: np.ndarray | None = None) -> Modes:
    """Modes of every family: ``axial`` counts the rigid mode; ``lateral`` is per plane, at least, with every
    lateral mode below ``lateral_cutoff`` [rad/s] (:func:`family_modes_below`; the z plane takes as many
    modes as the y plane); ``top_inertia``: the torsion's top is free with that inertia [kg·m²] (a top drive;
    ``torsional`` then counts the rigid rotation), None: held (imposed speed).

    ``truncation_correction``: "none", the modes alone; "static", each of the axial and torsional families
    followed by its residual-flexibility attachment modes (:func:`residual_flexibility_modes`) at the DOFs
    where the laws act: the bit's u (axial), the bit's θx and, with a top drive, the top's θx (torsional), and
    for each column of ``load_patterns`` ((n_dofs, p) global load vectors, None: none; the along-string
    friction's axial and torsional distributions, :func:`drillstring.dynamics.reduced.build.friction_load_patterns`)
    one more in the family it loads (:func:`attachment_loads`). The lateral families are left as they are (the
    contact acts all along them)."""
    check_truncation_correction(truncation_correction)
    lateral_y = family_modes_below(system, "lateral_y", lateral, lateral_cutoff)
    axial_family = family_modes(system, "axial", axial)
    torsional_family = family_modes(system, "torsional", torsional, top_inertia)
    if truncation_correction == "static":
        bit = system.mesh.n_nodes - 1
        if axial > 0:
            axial_family = residual_flexibility_modes(system, axial_family, [dof(bit, U)], rigid=True,
                                                      patterns=load_patterns)
        if torsional > 0:
            loads = [dof(bit, THETA_X)] + ([dof(0, THETA_X)] if top_inertia is not None else [])
            torsional_family = residual_flexibility_modes(system, torsional_family, loads, top_inertia,
                                                          rigid=top_inertia is not None, patterns=load_patterns)
    return Modes(
        axial=axial_family,
        torsional=torsional_family,
        lateral_y=lateral_y,
        lateral_z=family_modes(system, "lateral_z", len(lateral_y.angular_frequencies)),
    )


def _rigid_translation(system: LinearSystem, dofs: np.ndarray) -> np.ndarray | None:
    """The unit axial translation ``u = 1`` on ``dofs`` (a vector on them) when it is a zero-energy motion of
    the stiffness there (``|K r| ≤ 1e-10 |K|₁ |r|``), else None."""
    k = system.stiffness[dofs][:, dofs]
    rigid = np.zeros(len(dofs))
    rigid[dofs % 6 == U] = 1.0
    scale = float(abs(k).sum(axis=0).max()) * float(np.abs(rigid).max())
    return rigid if np.abs(k @ rigid).max() <= 1e-10 * scale else None


def coupled_modes(system: LinearSystem, count: int, cutoff: float = 0.0,
                  truncation_correction: str = "none", load_patterns: np.ndarray | None = None) -> ModeFamily:
    """The ``count`` lowest modes of the whole string (families coupled: :func:`family_coupling` > 0) on its
    free DOFs (:func:`coupled_dofs`), and every mode with ``ω < cutoff`` [rad/s]; mass-normalised, a
    deterministic sign. When the axial translation is a zero-energy motion (:func:`_rigid_translation`) it is
    the first column, exact, at ω = 0 (it replaces the computed mode closest to it). ``truncation_correction =
    "static"`` appends the residual-flexibility attachment modes (:func:`residual_flexibility_modes`) at the
    bit's u and θx, and one per column of ``load_patterns`` (as :func:`compute_modes`), computed on the whole
    system."""
    check_truncation_correction(truncation_correction)
    mesh = system.mesh
    dofs = coupled_dofs(mesh)
    k = system.stiffness[dofs][:, dofs]
    m = system.mass[dofs][:, dofs]
    wanted = min(max(int(count), 1), len(dofs))
    while True:
        values, vectors = _eigen(k, m, wanted)
        if not cutoff > 0.0 or wanted >= len(dofs) or values[-1] >= cutoff**2:
            break
        wanted = min(len(dofs), 2 * wanted)
    keep = min(len(values), max(int(count), int(np.count_nonzero(values < cutoff**2)) if cutoff > 0.0 else 0))
    values, vectors = np.array(values[:keep]), np.array(vectors[:, :keep])
    rigid = _rigid_translation(system, dofs)
    if rigid is not None and keep:
        rigid = rigid / np.sqrt(rigid @ (m @ rigid))
        closest = int(np.argmax(np.abs(vectors.T @ (m @ rigid))))
        order = [closest] + [j for j in range(keep) if j != closest]
        values, vectors = values[order], vectors[:, order]
        vectors[:, 0] = rigid
        values[0] = 0.0
    shapes = np.zeros((mesh.n_dofs, keep))
    shapes[dofs] = vectors
    shapes /= np.sqrt(np.einsum("ij,ij->j", shapes, system.mass @ shapes))
    pivot = np.argmax(np.abs(shapes), axis=0)
    shapes *= np.sign(shapes[pivot, np.arange(keep)])
    found = ModeFamily("coupled", np.sign(values) * np.sqrt(np.abs(values)), shapes)
    if truncation_correction == "static" and keep:
        bit = mesh.n_nodes - 1
        found = residual_flexibility_modes(system, found, [dof(bit, U), dof(bit, THETA_X)], rigid=rigid is not None,
                                           patterns=load_patterns)
    return found


def case_linear_system(case, static: StaticState) -> LinearSystem:
    """The prestressed linear system of a :class:`~drillstring.case.Case` around ``static``."""
    from drillstring.fem.build import section_fluid_coefficients, stabilizers

    return build_linear_system(
        static.mesh, static, stabilizers(case), section_fluid_coefficients(case, static.mesh)
    )
