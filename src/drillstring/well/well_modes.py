"""Small vibrations about the stiff string's static state in the well (issue 34 item 2, first step).

The linear system of :mod:`drillstring.modal` (mass ``M + M_f``, stiffness ``K + K_stab + K_g + K_f``, the
fluid's ``C_f``) is assembled with the elements rotated along the path (the rotations of
:class:`~drillstring.well.stiff_string.StiffStringState`), the geometric stiffness of its axial force
(``K_g(N)``, the plain one: a vibration's slide along the path is small), and the wall linearised at the
equilibrium: at each station in contact the penalty's tangent ``k [n nᵀ + (1 − g/r)(P − n nᵀ)]``, a stiff
radial spring and, across it, the spring ``k (r − g)/r = F/r`` (the station's force over its distance from
the hole's axis: the restoring force of a string lying on the wall and rolling round it, a pendulum).

The matrices are then written in each node's own frame (``Λ = diag(F_iᵀ, F_iᵀ)``, ``F_i`` the direction
cosines of the path's tangent at node ``i``, :func:`drillstring.fem.geometry.direction_cosines`):
``u`` along the tangent, ``v`` and ``w`` across it. The dynamic boundary conditions of
:func:`drillstring.modal.coupled_dofs` (top ``v = w = 0`` and ``θx`` held, the bit's ``v = w = 0``) then
hold across the path at the ends, and :func:`drillstring.modal.coupled_modes` solves the whole string on one
basis. Stabilizers are springs on the nodal ``v`` and ``w`` (across the path), as in the vertical string. A
vertical hole has every frame the identity and gives the vertical string's modes.

The families couple along the path, so :func:`case_well_mode_families` names each mode by the family that
holds the largest share of its kinetic energy (:func:`kinetic_energy_shares`): for the mass-normalised
shape ``φ`` split into its parts on the nodal DOFs of each family (axial ``u``, torsional ``θx``, lateral
``v, w, θy, θz``, in the nodes' frames), ``e_f = φ_fᵀ (M + M_f) φ_f / Σ_g φ_gᵀ (M + M_f) φ_g`` (the
cross-family terms, zero in a straight string, left out of both).

Units: SI (frequencies in rad/s in :class:`~drillstring.modal.ModeFamily`, ``.frequencies`` in Hz).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from drillstring.fem.assembly import (
    THETA_X,
    THETA_Y,
    THETA_Z,
    Stabilizer,
    U,
    V,
    W,
    fluid_matrices,
    stabilizer_stiffness,
    structural_matrices,
)
from drillstring.fem.dofs import DOFS_PER_NODE
from drillstring.fem.element import element_geometric_stiffness, element_mass, element_stiffness, place_planar
from drillstring.fem.fluid import FluidCoefficients, fluid_planar_matrices
from drillstring.fem.geometry import direction_cosines
from drillstring.modal import (
    DENSE_LIMIT,
    LinearSystem,
    ModeFamily,
    attachment_loads,
    coupled_dofs,
    coupled_modes,
    mass_normalised,
    residual_flexibility_vectors,
    with_attachments,
)
from drillstring.well.stiff_string import StiffStringState, case_stiff_string

__all__ = ["KINDS", "WELL_MODE_FAMILIES", "WellModes", "case_path_curvature", "case_well_mode_families",
           "case_well_modes", "case_well_system", "centreline_spin_matrix", "kinetic_energy_shares", "nodal_frames",
           "path_slide", "quota_modes", "well_linear_system", "well_modes"]

#: The families a mode along the path is named by, and their nodal DOFs (in the nodes' frames).
WELL_MODE_FAMILIES = {"axial": (U,), "torsional": (THETA_X,), "lateral": (V, W, THETA_Y, THETA_Z)}
#: The kinds of a well mode, in :func:`kinetic_energy_shares`' column order.
KINDS = tuple(WELL_MODE_FAMILIES)


def nodal_frames(tangent: np.ndarray) -> sp.csr_matrix:
    """Λ (n_dofs × n_dofs): global DOFs = Λ × nodal-frame DOFs, blocks ``F_iᵀ`` on each node's translations and
    rotations (``F_i`` the direction cosines of the unit ``tangent`` (n, 3) at node i)."""
    frames = direction_cosines(np.asarray(tangent, dtype=float))
    n = len(frames)
    blocks = np.zeros((n, 6, 6))
    blocks[:, :3, :3] = np.transpose(frames, (0, 2, 1))
    blocks[:, 3:, 3:] = np.transpose(frames, (0, 2, 1))
    base = DOFS_PER_NODE * np.arange(n)[:, None] + np.arange(6)
    rows = np.broadcast_to(base[:, :, None], blocks.shape)
    cols = np.broadcast_to(base[:, None, :], blocks.shape)
    return sp.coo_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(6 * n, 6 * n)).tocsr()


def well_linear_system(state: StiffStringState, stabilizers: Sequence[Stabilizer] = (),
                       fluid: Sequence[FluidCoefficients] | None = None, *, prestress: bool = True,
                       wall: bool = True, curvature: np.ndarray | None = None,
                       centreline_spin: bool = False) -> LinearSystem:
    """The linear system about ``state`` in the nodes' frames (module docstring); ``fluid``: one
    :class:`~drillstring.fem.fluid.FluidCoefficients` per mesh section (None: no fluid matrices);
    ``prestress=False`` drops K_g, ``wall=False`` the wall's springs.

    For the dynamics on this basis (``reduced_model.lateral_basis = "well"``, docs/stiff_string.md): with
    ``curvature`` (n, 3) [1/m], the path's curvature vectors at the nodes, the geometric stiffness acts on the
    deflection from the path only, ``Pᵀ K_g P`` as in the statics (eq. (2) of
    :mod:`drillstring.well.stiff_string`: the string's slide along the path, the rigid axial motion of drilling,
    is not read as a turn of its chords); ``centreline_spin``: K and K_g with each node's rotation about its
    tangent read as a twist of its elements (:func:`centreline_spin_matrix`)."""
    mesh = state.mesh
    n_dofs = mesh.n_dofs
    frames = nodal_frames(state.tangent)
    frames_t = frames.T.tocsr()

    def nodal(matrix):
        return (frames_t @ matrix @ frames).tocsr()

    k, m = structural_matrices(mesh, state.rotations)
    if fluid is None:
        zero = sp.csr_matrix((n_dofs, n_dofs))
        m_f, c_f, k_f = zero, zero, zero
    else:
        m_f, c_f, k_f = fluid_matrices(mesh, fluid, state.rotations)
    k_g = state.geometric_stiffness
    if centreline_spin:
        k, m, m_f, c_f, k_f, k_g = _spin_mapped_matrices(state, fluid)
    elastic = nodal(k + (state.wall_stiffness if wall else sp.csr_matrix((n_dofs, n_dofs))))
    elastic = (elastic + stabilizer_stiffness(mesh, stabilizers)).tocsr()
    if curvature is not None:
        from drillstring.well.stiff_string import _deflection_operator

        deflection = _deflection_operator(state.tangent, np.asarray(curvature, dtype=float))
        k_g = deflection.T @ k_g @ deflection
    k_g = nodal(k_g) if prestress else sp.csr_matrix((n_dofs, n_dofs))
    return LinearSystem(mesh, state.static_state(), nodal(m), nodal(m_f), elastic, k_g, nodal(k_f), nodal(c_f))


def well_modes(system: LinearSystem, count: int, cutoff: float = 0.0) -> ModeFamily:
    """The ``count`` lowest modes (and all below ``cutoff`` [rad/s]) of ``system`` on the coupled basis
    (:func:`drillstring.modal.coupled_modes`); shapes in the nodes' frames."""
    return coupled_modes(system, count, cutoff)


def case_well_modes(case, count: int = 10, state: StiffStringState | None = None) -> ModeFamily:
    """The lowest ``count`` modes of ``case`` about its stiff-string state in its well
    (:func:`drillstring.well.stiff_string.case_stiff_string` unless ``state`` is given), with its stabilizers
    and fluid."""
    return well_modes(case_well_system(case, state), count)


def case_path_curvature(case, state: StiffStringState) -> np.ndarray:
    """(n_nodes, 3) [1/m]: the curvature vectors of ``case``'s well path at the nodes of ``state``'s mesh."""
    from drillstring.well.stiff_string import path_frames
    from drillstring.well.torque_drag import case_trajectory

    return path_frames(state.mesh, case_trajectory(case))[2]


def case_well_system(case, state: StiffStringState | None = None,
                     curvature: np.ndarray | None = None) -> LinearSystem:
    """:func:`well_linear_system` of ``case`` about ``state`` (its
    :func:`~drillstring.well.stiff_string.case_stiff_string` when None), with its stabilizers and fluid, the
    path's ``curvature`` (:func:`case_path_curvature` when None) and the centreline spin: the one linear system
    of the string in its well, for its modes (``drillstring modes``) and the dynamics' well basis
    (``reduced_model.lateral_basis = "well"``)."""
    from drillstring.fem.build import section_fluid_coefficients, stabilizers

    state = case_stiff_string(case) if state is None else state
    curvature = case_path_curvature(case, state) if curvature is None else curvature
    return well_linear_system(state, stabilizers(case), section_fluid_coefficients(case, state.mesh),
                              curvature=curvature, centreline_spin=True)


def kinetic_energy_shares(system: LinearSystem, shapes: np.ndarray) -> np.ndarray:
    """(n_modes, 3): each mode's share of kinetic energy in the families of :data:`WELL_MODE_FAMILIES`
    (axial, torsional, lateral; module docstring: ``e_f = φ_fᵀ M φ_f / Σ_g φ_gᵀ M φ_g``, ``M`` the mass
    with the fluid's), rows summing to 1. ``shapes`` (n_dofs, n_modes) in the nodes' frames."""
    kind = np.arange(system.mesh.n_dofs) % DOFS_PER_NODE
    mass = system.mass
    energies = []
    for kinds in WELL_MODE_FAMILIES.values():
        part = np.where(np.isin(kind, kinds)[:, None], shapes, 0.0)
        energies.append(np.einsum("ij,ij->j", part, mass @ part))
    energies = np.array(energies).T
    return energies / energies.sum(axis=1, keepdims=True)


@dataclass(frozen=True)
class WellModes:
    """The lowest modes about the stiff string's static state, named by family (:func:`case_well_mode_families`).

    Attributes:
        axial, torsional, lateral: the ``count`` lowest modes of each family (ω [rad/s], ``.frequencies`` [Hz];
            shapes in the nodes' frames, mass-normalised); every lateral mode is listed (the wall and the
            curvature split the straight string's y/z pairs).
        shares: per family, (n, 3) its modes' kinetic-energy shares (axial, torsional, lateral).
        solved: the number of lowest modes of the whole string solved to find them.
    """

    axial: ModeFamily
    torsional: ModeFamily
    lateral: ModeFamily
    shares: dict[str, np.ndarray]
    solved: int


def case_well_mode_families(case, count: int = 10, state: StiffStringState | None = None) -> WellModes:
    """The ``count`` lowest modes of each family (:data:`WELL_MODE_FAMILIES`, by the largest kinetic-energy
    share: :func:`kinetic_energy_shares`) of ``case`` about its stiff-string state in its well, with its
    stabilizers and fluid. The whole string is solved at once (:func:`well_modes`): all its modes when it has
    at most :data:`~drillstring.modal.DENSE_LIMIT` free DOFs (one dense solve), else the lowest ``4 count``,
    then four times as many until every family has ``count`` (or every mode is solved)."""
    system = case_well_system(case, state)
    free = len(coupled_dofs(system.mesh))
    wanted = free if free <= DENSE_LIMIT else min(free, 4 * count)
    while True:
        found = well_modes(system, wanted)
        shares = kinetic_energy_shares(system, found.shapes)
        family = np.argmax(shares, axis=1)
        if wanted >= free or np.all(np.bincount(family, minlength=3) >= count):
            break
        wanted = min(free, 4 * wanted)
    picked, share_of = {}, {}
    for i, name in enumerate(WELL_MODE_FAMILIES):
        index = np.flatnonzero(family == i)[:count]
        picked[name] = ModeFamily(name, found.angular_frequencies[index], found.shapes[:, index])
        share_of[name] = shares[index]
    return WellModes(picked["axial"], picked["torsional"], picked["lateral"], share_of, len(found.angular_frequencies))


def centreline_spin_matrix(mesh, local: Sequence[np.ndarray], rotations: np.ndarray,
                           tangent: np.ndarray) -> sp.csr_matrix:
    """The element matrices ``local`` (12 × 12 each, element axes: K'_e, K'_g,e) assembled in global axes with each node's rotation about its own tangent read by each of its
    elements as a twist about the element's chord: ``θ -> θ + (c_e − t_i)(t_i·θ)`` on the rotations of node
    ``i`` seen from element ``e`` (``c_e`` its chord, ``t_i`` the node's tangent), ``K_e = Gᵀ Tᵀ K'_e T G``.
    The elements are straight chords and the string is bent to the path: read plainly, a rotation ``θ`` of a
    node about its tangent is, in an element whose chord turns by β at its nodes, a twist ``θ cos(β/2)`` and
    bending rotations ``±θ sin(β/2)`` at its ends, a ground spring ``EI κ² θ²`` per length (the energy of
    turning the plane of a pre-curved rod's curvature) and a coupling of twist and bending. A pipe straight when
    unloaded and bent to the hole keeps its curvature when it turns about its centreline (its bending energy
    reads |κ| only, a round section): the quadratic form of a twist field with the centreline still is
    ``GJ θ'²``, and its inertia the polar one. So mapped, a uniform spin stores nothing in K nor K_g (their
    element matrices see a rigid rotation about the chord) and the spin's inertia is the sections' polar
    inertia (read plainly, the element's consistent mass gives a bending rotation ``θ sin(β/2)`` its lateral
    inertia ``ρA h³/105``: +13 % on the first torsional mode's modal mass, plus the fluid's); a vertical string's matrices are unchanged (``c = t``). Read plainly, the
    ``deviated`` case's first torsional frequency is 26 % above the straight string's (1.590 vs 1.263 rad/s);
    removing the ground spring alone (the θx block's row sums) leaves the coupling, and a torsional mode of
    negative stiffness."""
    from drillstring.fem.geometry import rotate_element_matrices

    rotations = np.asarray(rotations, dtype=float)
    tangent = np.asarray(tangent, dtype=float)
    values = rotate_element_matrices(np.stack([np.asarray(m, dtype=float) for m in local]), rotations)
    n_el = len(values)
    mapping = np.tile(np.eye(12), (n_el, 1, 1))
    for end in range(2):
        t = tangent[np.arange(n_el) + end]
        block = np.eye(3) + np.einsum("ei,ej->eij", rotations[:, 0, :] - t, t)
        mapping[:, 6 * end + 3:6 * end + 6, 6 * end + 3:6 * end + 6] = block
    values = np.einsum("eji,ejk,ekl->eil", mapping, values, mapping)
    dofs = DOFS_PER_NODE * np.arange(n_el)[:, None] + np.arange(12)
    rows = np.broadcast_to(dofs[:, :, None], values.shape)
    cols = np.broadcast_to(dofs[:, None, :], values.shape)
    return sp.coo_matrix((values.ravel(), (rows.ravel(), cols.ravel())), shape=(mesh.n_dofs, mesh.n_dofs)).tocsr()


def _spin_mapped_matrices(state: StiffStringState, fluid):
    """``(K, M, M_f, C_f, K_f, K_g)`` of ``state`` in global axes, every element matrix assembled by
    :func:`centreline_spin_matrix` (the fluid's zero without ``fluid``)."""
    mesh = state.mesh
    pairs = list(zip(mesh.element_sections(), mesh.element_lengths))
    force = state.axial_force

    def assemble(local):
        return centreline_spin_matrix(mesh, local, state.rotations, state.tangent)

    k = assemble([element_stiffness(section, h) for section, h in pairs])
    m = assemble([element_mass(section, h) for section, h in pairs])
    k_g = assemble([element_geometric_stiffness(section, h, force[e], force[e + 1])
                    for e, (section, h) in enumerate(pairs)])
    if fluid is None:
        zero = sp.csr_matrix((mesh.n_dofs, mesh.n_dofs))
        return k, m, zero, zero, zero, k_g
    planar = [fluid_planar_matrices(section, h, fluid[i])
              for (section, h), i in zip(pairs, mesh.element_section)]
    m_f, c_f, k_f = (assemble([place_planar(p[j]) for p in planar]) for j in range(3))
    return k, m, m_f, c_f, k_f, k_g


def path_slide(state: StiffStringState, curvature: np.ndarray) -> np.ndarray:
    """The string's slide along the path in the nodes' frames (6 n): every node moved 1 m along its tangent
    and turned by ``t × κ`` (the path's tangent turns so), the rigid axial motion of a string in a curved
    hole (the statics' ``S``, :mod:`drillstring.well.stiff_string` eq. (2)); a vertical string's is u = 1."""
    tangent = np.asarray(state.tangent, dtype=float)
    slide = np.zeros((len(tangent), 6))
    slide[:, :3] = tangent
    slide[:, 3:] = np.cross(tangent, np.asarray(curvature, dtype=float))
    return nodal_frames(tangent).T @ slide.ravel()


def quota_modes(system: LinearSystem, slide: np.ndarray, axial: int, torsional: int, lateral: int,
                cutoff: float = 0.0, loads: Sequence[int] = (),
                patterns: np.ndarray | None = None) -> tuple[ModeFamily, np.ndarray]:
    """The modes of the whole string (nodes' frames, :func:`drillstring.modal.coupled_dofs`) chosen by kind
    (:func:`kinetic_energy_shares`, the largest share): the slide along the path first (``slide``, :func:`path_slide`,
    made an exact zero-energy motion: the stiffness is taken on its M-orthogonal complement,
    ``Qᵀ K Q``, ``Q = I − s sᵀ M / (sᵀ M s)``, which changes no mode orthogonal to it), then the ``axial``
    lowest axial modes, the ``torsional`` lowest torsional ones, the ``lateral`` lowest lateral ones and every
    lateral one below ``cutoff`` [rad/s], ordered by frequency; mass-normalised, a deterministic sign. Returns
    the modes and each one's kind (an index into :data:`KINDS`; the slide's: axial). Dense: at most
    :data:`drillstring.modal.DENSE_LIMIT` free DOFs.

    ``loads``: global DOFs (nodes' frames) whose unit loads get the static correction: the residual-flexibility
    attachment modes of :func:`drillstring.modal.residual_flexibility_vectors` (Craig & Chang 1977; the load
    balanced by the slide's inertia, the response M-orthogonal, so also ``Qᵀ K Q``-orthogonal, to the chosen
    modes) appended after them (``attachments`` counts them), each one's kind its largest kinetic-energy share;
    ``patterns`` ((n_dofs, p) load vectors in the nodes' frames, None: none) one more each
    (:func:`drillstring.modal.attachment_loads`). Loads on held DOFs, or responses the chosen modes already span, add nothing."""
    mesh = system.mesh
    dofs = coupled_dofs(mesh)
    if len(dofs) > DENSE_LIMIT:
        raise ValueError(f"reduced_model.lateral_basis = 'well' with {len(dofs)} free DOFs: at most {DENSE_LIMIT} "
                         "(the well basis is solved dense); use a coarser mesh.max_element_length")
    k = system.stiffness[dofs][:, dofs].toarray()
    m = system.mass[dofs][:, dofs].toarray()
    s = np.asarray(slide, dtype=float)[dofs]
    s = s / np.sqrt(s @ m @ s)
    ms, ks = m @ s, k @ s  # Qᵀ K Q = K − K s mᵀ − m sᵀ K + (sᵀ K s) m mᵀ, m = M s
    k = k - np.outer(ks, ms) - np.outer(ms, ks) + (s @ ks) * np.outer(ms, ms)
    k = 0.5 * (k + k.T)
    values, vectors = sla.eigh(k, m)
    closest = int(np.argmax(np.abs(vectors.T @ (m @ s))))
    vectors[:, closest] = s
    values[closest] = 0.0
    shapes = np.zeros((mesh.n_dofs, len(values)))
    shapes[dofs] = vectors
    kind = np.argmax(kinetic_energy_shares(system, shapes), axis=1)
    kind[closest] = 0
    order = np.argsort(values, kind="stable")
    chosen = [closest]
    for index, count in enumerate((axial, torsional, lateral)):
        candidates = [j for j in order if kind[j] == index and j != closest]
        below = sum(1 for j in candidates if index == 2 and values[j] < cutoff**2)
        chosen += candidates[:max(int(count), below)]
    chosen = [closest] + sorted(chosen[1:], key=lambda j: values[j])
    shapes = mass_normalised(shapes[:, chosen], system.mass)
    values = values[chosen]
    found, kinds = ModeFamily("coupled", np.sign(values) * np.sqrt(np.abs(values)), shapes), kind[chosen]
    load = attachment_loads(dofs, np.sort(np.asarray(loads, dtype=np.int64)), patterns)
    if load.shape[1] == 0 or len(chosen) >= len(dofs):
        return found, kinds
    # the slide first (the rigid motion of Qᵀ K Q), the response with the top's u (local DOF 0) held
    extra = residual_flexibility_vectors(sp.csc_matrix(k), sp.csr_matrix(m), shapes[dofs], load, 1, [0])
    if extra is None:
        return found, kinds
    corrected = with_attachments(found, dofs, *extra, system.mass)
    added = np.argmax(kinetic_energy_shares(system, corrected.shapes[:, len(chosen):]), axis=1)
    return corrected, np.concatenate([kinds, added])
