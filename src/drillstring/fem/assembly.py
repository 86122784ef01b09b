"""DOF numbering, generic sparse assembly, and the global linear matrices of the string.

Global DOF numbering (defined in :mod:`drillstring.fem.dofs`, re-exported here): node ``i`` (0 at the
top) owns DOFs ``6 i + k`` with ``k = U, V, W, THETA_X, THETA_Y, THETA_Z`` (docs/model.md §1).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np
import scipy.sparse as sp

from drillstring.fem.dofs import (  # noqa: F401  (re-exported: the numbering's usual import path)
    DOFS_PER_ELEMENT,
    DOFS_PER_NODE,
    THETA_X,
    THETA_Y,
    THETA_Z,
    U,
    V,
    W,
    dof,
    element_dofs,
)
from drillstring.fem.element import (
    element_geometric_stiffness,
    element_gyroscopic,
    element_gravity_load,
    element_mass,
    element_stiffness,
    place_planar,
)
from drillstring.fem.fluid import FluidCoefficients, fluid_planar_matrices
from drillstring.fem.geometry import rotate_element_matrices
from drillstring.fem.mesh import Mesh

def assemble_matrix(n_dofs: int, element_matrices: Iterable[np.ndarray],
                    rotations: np.ndarray | None = None) -> sp.csr_matrix:
    """Sum 12×12 element matrices (element e on nodes e, e+1) into a sparse n_dofs × n_dofs matrix;
    ``rotations`` (n_el, 3, 3): each element's direction cosines (:mod:`drillstring.fem.geometry`), its matrix
    turned from element to global coordinates first; None: the elements lie along x (no rotation)."""
    blocks = [np.asarray(ke) for ke in element_matrices]
    if not blocks:
        return sp.csr_matrix((n_dofs, n_dofs))
    values = np.stack(blocks)  # (n_el, 12, 12)
    if rotations is not None:
        if np.shape(rotations) != (len(blocks), 3, 3):
            raise ValueError(f"rotations: must be one (3, 3) rotation per element ({len(blocks)}), got shape "
                             f"{np.shape(rotations)}")
        values = rotate_element_matrices(values, np.asarray(rotations, dtype=float))
    dofs = DOFS_PER_NODE * np.arange(len(blocks))[:, None] + np.arange(DOFS_PER_ELEMENT)  # (n_el, 12)
    rows = np.broadcast_to(dofs[:, :, None], values.shape)
    cols = np.broadcast_to(dofs[:, None, :], values.shape)
    return sp.coo_matrix((values.ravel(), (rows.ravel(), cols.ravel())),
                         shape=(n_dofs, n_dofs)).tocsr()


def assemble_vector(n_dofs: int, element_vectors: Iterable[np.ndarray]) -> np.ndarray:
    """Sum 12-component element vectors into a global vector."""
    out = np.zeros(n_dofs)
    for e, fe in enumerate(element_vectors):
        out[element_dofs(e)] += fe
    return out


@dataclass(frozen=True)
class Stabilizer:
    """A linear lateral spring ``stiffness`` [N/m] on v and w of the node at ``position`` [m]."""

    position: float
    stiffness: float


def stabilizer_stiffness(mesh: Mesh, stabilizers: Sequence[Stabilizer]) -> sp.csr_matrix:
    """Diagonal stiffness of the stabilizers' lateral springs."""
    diag = np.zeros(mesh.n_dofs)
    for s in stabilizers:
        node = mesh.node_index(s.position)
        diag[dof(node, V)] += s.stiffness
        diag[dof(node, W)] += s.stiffness
    return sp.diags(diag).tocsr()


def structural_matrices(mesh: Mesh, rotations: np.ndarray | None = None) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """Global elastic stiffness [K] and consistent mass [M] (no boundary conditions); ``rotations``: the
    elements' direction cosines (:func:`assemble_matrix`)."""
    pairs = list(zip(mesh.element_sections(), mesh.element_lengths))
    k = assemble_matrix(mesh.n_dofs, (element_stiffness(s, h) for s, h in pairs), rotations)
    m = assemble_matrix(mesh.n_dofs, (element_mass(s, h) for s, h in pairs), rotations)
    return k, m


def gyroscopic_matrix(mesh: Mesh) -> sp.csr_matrix:
    """Global gyroscopic matrix [G] per unit spin speed (skew-symmetric): a string spinning at Ω
    [rad/s] has ``M q̈ + Ω G q̇ + K q = f`` (:func:`~drillstring.fem.element.element_gyroscopic`)."""
    return assemble_matrix(
        mesh.n_dofs,
        (element_gyroscopic(s, h) for s, h in zip(mesh.element_sections(), mesh.element_lengths)),
    )


def geometric_stiffness(mesh: Mesh, nodal_axial_force: np.ndarray,
                        rotations: np.ndarray | None = None) -> sp.csr_matrix:
    """Global [K_g] from the axial force at the nodes [N] (tension positive), linear in each element;
    ``rotations``: the elements' direction cosines (:func:`assemble_matrix`)."""
    return assemble_matrix(
        mesh.n_dofs,
        (
            element_geometric_stiffness(s, h, nodal_axial_force[e], nodal_axial_force[e + 1])
            for e, (s, h) in enumerate(zip(mesh.element_sections(), mesh.element_lengths))
        ),
        rotations,
    )


def fluid_matrices(
    mesh: Mesh, coefficients: Sequence[FluidCoefficients], rotations: np.ndarray | None = None
) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
    """Global fluid ``(M_f, C_f, K_f)``; ``coefficients`` holds one entry per mesh section; ``rotations``: the
    elements' direction cosines (:func:`assemble_matrix`)."""
    per_element = [
        fluid_planar_matrices(s, h, coefficients[i])
        for s, h, i in zip(mesh.element_sections(), mesh.element_lengths, mesh.element_section)
    ]
    return tuple(  # type: ignore[return-value]
        assemble_matrix(mesh.n_dofs, (place_planar(m[k]) for m in per_element), rotations) for k in range(3)
    )


def distributed_axial_load(mesh: Mesh, load_per_length: Sequence[float]) -> np.ndarray:
    """Consistent nodal loads of a uniform axial load per section [N/m] along +x (gravity, fluid)."""
    return assemble_vector(
        mesh.n_dofs,
        (
            element_gravity_load(load_per_length[i], h, 1.0)
            for h, i in zip(mesh.element_lengths, mesh.element_section)
        ),
    )
