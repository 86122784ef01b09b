"""A rotor between two sections: the string below a downhole motor turns relative to the string above.

The motor's rotor station is a mesh node ``k`` (:func:`rotor_node`). The string is assembled on a **duplicated
node**: the element below the station (nodes ``k``, ``k+1``) is connected to a twin of node ``k`` instead of
node ``k`` itself, and every DOF of the twin is tied to node ``k``'s except its rotation θx,

    q_dup = T q,    q = [the mesh's DOFs, θ_r],

with ``θ_r`` the rotor side's rotation at the station (node ``k``'s own θx is the stator side's). The matrices of
the released string are ``Tᵀ K_dup T``, ``Tᵀ M_dup T``, ... (:func:`released_system`): those of the mesh, one
DOF longer, with the element below the station's torsional pair moved from node ``k``'s θx to ``θ_r``. Nothing
but the torsion sees the release (the other DOFs are tied; in a straight string the families are uncoupled,
:func:`drillstring.modal.family_coupling`), so the torsional family gains one DOF and one rigid motion: the
string below the station turning freely relative to the string above (:func:`released_torsional_modes`).

Every other row of the basis is the mesh's: the θx rows of the nodes below the station hold their absolute
rotation, so the bit's speed is the speed of the string above plus the rotor's relative speed without any
bookkeeping, and the motor's torque pair (+T at ``θ_r``, −T at node ``k``'s θx) projects on the modes through the
row ``φ_r − φ_k`` (:attr:`RotorRelease.relative`). SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from drillstring.fem.assembly import THETA_X, dof
from drillstring.fem.element import element_mass, element_stiffness
from drillstring.fem.mesh import Mesh
from drillstring.modal import (
    LinearSystem,
    ModeFamily,
    _eigen,
    check_truncation_correction,
    mass_normalised,
    family_coupling,
    family_dofs,
    residual_flexibility_vectors,
    top_inertia_matrix,
)

__all__ = ["RotorRelease", "released_system", "released_torsional_modes", "rotor_node"]

#: The local indices of the two nodes' θx in a 12 × 12 element matrix.
_THETA_X_PAIR = (THETA_X, 6 + THETA_X)


def rotor_node(mesh: Mesh, position: float) -> int:
    """The mesh node at ``position`` [m] (the rotor station); ValueError (one line) when no node lies there
    (within 1e-6 of the string's length) or it is the top or the bit."""
    node = int(mesh.node_index(position))
    if abs(float(mesh.nodes[node]) - position) > 1e-6 * mesh.length:
        raise ValueError(f"motor.position = {position:g} m: no mesh node there (the nearest at "
                         f"{float(mesh.nodes[node]):g} m): put the motor's bottom at a section boundary")
    if not 0 < node < mesh.n_nodes - 1:
        raise ValueError(f"motor.position = {position:g} m: must lie strictly between the top (0 m) and the bit "
                         f"({mesh.length:g} m)")
    return node


def _move_pair(matrix: sp.spmatrix, pair: np.ndarray, a: int, b: int, twin: int) -> sp.csr_matrix:
    """``matrix`` one row and column longer (the twin's), the element pair ``pair`` (2 × 2, on DOFs ``a``,
    ``b``) moved from ``a`` to ``twin``: ``Tᵀ A_dup T``."""
    n = matrix.shape[0]
    rows = [a, a, b, twin, twin, b]
    cols = [a, b, a, twin, b, twin]
    values = [-pair[0, 0], -pair[0, 1], -pair[1, 0], pair[0, 0], pair[0, 1], pair[1, 0]]
    moved = sp.coo_matrix((values, (rows, cols)), shape=(n + 1, n + 1))
    padded = sp.bmat([[sp.csr_matrix(matrix), None], [None, sp.csr_matrix((1, 1))]], format="csr")
    return (padded + moved).tocsr()


def released_system(system: LinearSystem, node: int) -> LinearSystem:
    """The linear system of the string released at the rotor station ``node`` (module docstring): every matrix
    ``(n_dofs + 1)²``, the last DOF the rotor side's θx. Only the structural stiffness and mass have a
    torsional pair (the geometric stiffness, the fluid's and the stabilizers' act on the lateral DOFs).
    ValueError when the families couple (the release assumes the torsion is a family of its own)."""
    coupling = family_coupling(system)
    if coupling != 0.0:
        raise ValueError(f"a downhole motor needs uncoupled mode families (largest coupling entry {coupling:.3g})")
    mesh = system.mesh
    section, length = mesh.element_sections()[node], float(mesh.element_lengths[node])
    a, b, twin = int(dof(node, THETA_X)), int(dof(node + 1, THETA_X)), mesh.n_dofs
    local = np.ix_(_THETA_X_PAIR, _THETA_X_PAIR)
    zero = np.zeros((2, 2))
    stiffness, mass = element_stiffness(section, length)[local], element_mass(section, length)[local]
    return replace(
        system,
        structural_mass=_move_pair(system.structural_mass, mass, a, b, twin),
        fluid_mass=_move_pair(system.fluid_mass, zero, a, b, twin),
        elastic_stiffness=_move_pair(system.elastic_stiffness, stiffness, a, b, twin),
        geometric_stiffness=_move_pair(system.geometric_stiffness, zero, a, b, twin),
        fluid_stiffness=_move_pair(system.fluid_stiffness, zero, a, b, twin),
        fluid_damping=_move_pair(system.fluid_damping, zero, a, b, twin),
    )


@dataclass(frozen=True)
class RotorRelease:
    """The torsional family of a released string and the rows the motor needs (per column of the family).

    Attributes:
        node: the rotor station (mesh node).
        family: the torsional modes on the mesh's DOFs (node ``node``'s θx row: the stator side).
        rotor: (n_t,) the rotor side's θx at the station, ``φ_r``.
        relative: (n_t,) ``φ_r − φ_k``: the rotor's rotation relative to the stator per unit modal coordinate;
            the motor's speed is ``relativeᵀ η̇``, its torque acts on the modes as ``relative · T``.
        lower_rotation: (n_t,) the modal coordinates of the unit rotation of the string below the station
            relative to the string above (``Φᵀ M r_lower``, exact: it is one of the family's rigid motions).
    """

    node: int
    family: ModeFamily
    rotor: np.ndarray
    relative: np.ndarray
    lower_rotation: np.ndarray


def released_torsional_modes(released: LinearSystem, node: int, count: int,
                             top_inertia: float | None = None, truncation_correction: str = "none") -> RotorRelease:
    """The ``count`` lowest torsional modes of the string ``released`` at ``node`` (:func:`released_system`),
    ``top_inertia`` [kg·m²]: the top free with that inertia (a top drive), None: held. The rigid motions come
    first, exact: with the top free the whole string's rotation, then the rotation of the string below the
    station (M-orthogonalised to it); with the top held the latter alone. ``count`` counts them.

    ``truncation_correction = "static"`` appends the residual-flexibility attachment modes of the released torsion
    (Craig & Chang 1977, :func:`drillstring.modal.residual_flexibility_vectors`) for the loads its laws apply: a
    torque at the bit's θx, the motor's torque pair (+1 at the rotor side ``θ_r``, −1 at the stator side: the load
    conjugate to the rotor's relative rotation) and, with a top drive, a torque at the top's θx. Each load is
    first balanced by the inertia of the rigid motions (inertia relief; the pair is balanced already) and solved
    with the rotor side held (and the top, when free): one held DOF per rigid motion. The attachment modes are
    M- and K-orthogonal to every kept mode (the rigid motions included, so ``lower_rotation`` is 0 on them)."""
    check_truncation_correction(truncation_correction)
    mesh = released.mesh
    top_free = top_inertia is not None
    rigid = 2 if top_free else 1
    if count < rigid:
        raise ValueError(f"reduced_model.torsional_modes: a downhole motor needs at least {rigid} torsional mode(s) "
                         f"(its rigid motions), got {count}")
    n_dofs = mesh.n_dofs
    dofs = np.concatenate([family_dofs(mesh, "torsional", top_free), [n_dofs]])
    mass = released.mass
    if top_free:
        extra = top_inertia_matrix(mesh, top_inertia)
        mass = mass + sp.bmat([[extra, None], [None, sp.csr_matrix((1, 1))]], format="csr")
    k = released.stiffness[dofs][:, dofs]
    m = mass[dofs][:, dofs]
    values, vectors = _eigen(k, m, count)
    values, vectors = np.array(values, dtype=float), np.array(vectors, dtype=float)
    lower = (dofs > dof(node, THETA_X)).astype(float)  # the nodes below the station and the rotor side
    shapes = [np.ones(len(dofs))] if top_free else []
    shapes.append(lower)
    for j, shape in enumerate(shapes):  # Gram–Schmidt in M
        for previous in shapes[:j]:
            shape = shape - previous * (previous @ (m @ shape))
        shapes[j] = shape / np.sqrt(shape @ (m @ shape))
    null = np.column_stack(shapes)
    vectors[:, :rigid] = null
    values[:rigid] = 0.0
    elastic = vectors[:, rigid:]
    vectors[:, rigid:] = elastic - null @ (null.T @ (m @ elastic))  # round-off of the eigensolver's null space
    mass_normalised(vectors, m)
    attachments = 0
    if truncation_correction == "static" and vectors.shape[1] < len(dofs):
        values, vectors, attachments = _with_attachment_modes(k, m, values, vectors, dofs, node, rigid)
    full = np.zeros((n_dofs + 1, vectors.shape[1]))
    full[dofs] = vectors
    omega = np.sign(values) * np.sqrt(np.abs(values))
    family = ModeFamily("torsional", omega, full[:n_dofs], attachments)
    rotor = full[n_dofs].copy()
    return RotorRelease(node=node, family=family, rotor=rotor, relative=rotor - full[dof(node, THETA_X)],
                        lower_rotation=vectors.T @ (m @ lower))


def _with_attachment_modes(k, m, values: np.ndarray, vectors: np.ndarray, dofs: np.ndarray, node: int,
                           rigid: int):
    """``(ω², vectors, count)``: the released torsion's kept modes (M-orthonormal, on its DOFs ``dofs``, sorted:
    the top's θx first when free, the rotor side's last) followed by their ``count`` attachment modes
    (:func:`released_torsional_modes`)."""
    n = len(dofs)
    rotor, stator = n - 1, int(np.searchsorted(dofs, dof(node, THETA_X)))
    load = np.zeros((n, 3 if rigid == 2 else 2))
    load[n - 2, 0] = 1.0  # the bit's θx: the last node's, just before the rotor side's
    load[rotor, 1], load[stator, 1] = 1.0, -1.0  # the motor's torque pair
    if rigid == 2:
        load[0, 2] = 1.0  # the top's θx (a top drive)
    ground = [rotor] + ([0] if rigid == 2 else [])
    found = residual_flexibility_vectors(sp.csc_matrix(k), sp.csr_matrix(m), vectors, load, rigid, ground)
    if found is None:
        return values, vectors, 0
    extra_values, extra = found
    mass_normalised(extra, m)
    return np.concatenate([values, extra_values]), np.hstack([vectors, extra]), extra.shape[1]


def released_modes(system: LinearSystem, position: float, axial: int, torsional: int, lateral: int,
                   lateral_cutoff: float = 0.0, top_inertia: float | None = None,
                   truncation_correction: str = "none"):
    """:func:`drillstring.modal.compute_modes` for a string with a downhole motor whose rotor station is at
    ``position`` [m]: the axial and lateral families as without it, the torsional family of the released string
    (``torsional`` counts its rigid motions). Returns ``(modes, release, released)``: the
    :class:`~drillstring.modal.Modes`, the :class:`RotorRelease` and the released system (for the damping, which
    is defined on the released string's free–free modes: :func:`drillstring.damping.reduced_structural_damping`
    reads the rotor side's row after the mesh's). ``truncation_correction``: "static" appends to the axial family
    its attachment mode at the bit (:func:`drillstring.modal.compute_modes`) and to the released torsion its own
    (:func:`released_torsional_modes`: the bit, the motor's torque pair, the top with a top drive)."""
    from drillstring.modal import compute_modes

    node = rotor_node(system.mesh, position)
    released = released_system(system, node)
    release = released_torsional_modes(released, node, torsional, top_inertia, truncation_correction)
    modes = compute_modes(system, axial, 0, lateral, lateral_cutoff, truncation_correction=truncation_correction)
    return replace(modes, torsional=release.family), release, released


def first_torsional_frequency(system: LinearSystem, position: float) -> float:
    """The lowest elastic torsional angular frequency [rad/s] of the string released at ``position`` [m], the top
    held: the stick-slip frequency that tunes a soft-torque top drive (:func:`drillstring.forces.top_drive.
    case_top_drive`) when a downhole motor separates the bit from the string."""
    node = rotor_node(system.mesh, position)
    release = released_torsional_modes(released_system(system, node), node, 2)
    return float(release.family.angular_frequencies[1])
