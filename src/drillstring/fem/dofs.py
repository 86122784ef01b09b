"""Degree-of-freedom numbering of the beam model (docs/model.md §1): the one module that names DOF offsets.

Every node carries six DOFs, in this order: axial ``u``, lateral ``v`` (y), lateral ``w`` (z), torsion
``θx``, bending rotations ``θy`` and ``θz``. Node ``i`` (0 at the top) owns the global DOFs
``DOFS_PER_NODE · i + k`` for ``k`` in :data:`U` … :data:`THETA_Z`. A 2-node element holds the 12 DOFs
of its upper node (element-local 0–5) followed by those of its lower node (6–11); the element-local
offsets are named :data:`U1` … :data:`THETA_Z2`, so compiled kernels index an element's DOFs as
``DOFS_PER_NODE · e + V1`` and never by bare numbers.

Bending pairs: in the x–y plane ``(v, θz)``, in the x–z plane ``(w, θy)`` (right-hand rule: θy = −∂w/∂x,
see :mod:`drillstring.fem.element`).

This module depends on nothing; :mod:`drillstring.fem.assembly`, :mod:`drillstring.fem.element`,
:mod:`drillstring.forces.nonlinear` and :mod:`drillstring.dynamics.rom` take their offsets from it.
"""

from __future__ import annotations

import numpy as np

#: Nodal DOF kinds (offsets inside a node).
U, V, W, THETA_X, THETA_Y, THETA_Z = range(6)
DOFS_PER_NODE = 6
NODES_PER_ELEMENT = 2
DOFS_PER_ELEMENT = NODES_PER_ELEMENT * DOFS_PER_NODE

#: Element-local DOFs of the upper (1) and lower (2) node (plain ints: constants in compiled code).
U1, V1, W1, THETA_X1, THETA_Y1, THETA_Z1 = (U, V, W, THETA_X, THETA_Y, THETA_Z)
U2, V2, W2, THETA_X2, THETA_Y2, THETA_Z2 = (DOFS_PER_NODE + k for k in (U, V, W, THETA_X, THETA_Y, THETA_Z))

#: Element-local DOF indices of the axial displacement, torsion and the two bending planes.
AXIAL_DOFS = np.array([U1, U2])
TORSION_DOFS = np.array([THETA_X1, THETA_X2])
BENDING_Y_DOFS = np.array([V1, THETA_Z1, V2, THETA_Z2])  # (v1, θz1, v2, θz2): bending in the x–y plane
BENDING_Z_DOFS = np.array([W1, THETA_Y1, W2, THETA_Y2])  # (w1, θy1, w2, θy2): bending in the x–z plane
for _indices in (AXIAL_DOFS, TORSION_DOFS, BENDING_Y_DOFS, BENDING_Z_DOFS):
    _indices.setflags(write=False)


def dof(node: int | np.ndarray, kind: int) -> int | np.ndarray:
    """Global index of DOF ``kind`` (``U`` … ``THETA_Z``) of ``node``."""
    return DOFS_PER_NODE * np.asarray(node) + kind if np.ndim(node) else DOFS_PER_NODE * node + kind


def element_dofs(element: int) -> np.ndarray:
    """The 12 global DOFs of element ``element`` (its two nodes)."""
    return np.arange(DOFS_PER_NODE * element, DOFS_PER_NODE * element + DOFS_PER_ELEMENT)
