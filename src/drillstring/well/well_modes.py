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

Units: SI (frequencies in rad/s in :class:`~drillstring.modal.ModeFamily`, ``.frequencies`` in Hz).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp

from drillstring.fem.assembly import (
    Stabilizer,
    fluid_matrices,
    stabilizer_stiffness,
    structural_matrices,
)
from drillstring.fem.dofs import DOFS_PER_NODE
from drillstring.fem.fluid import FluidCoefficients
from drillstring.fem.geometry import direction_cosines
from drillstring.modal import LinearSystem, ModeFamily, coupled_modes
from drillstring.well.stiff_string import StiffStringState, case_stiff_string

__all__ = ["case_well_modes", "nodal_frames", "well_linear_system", "well_modes"]


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
                       wall: bool = True) -> LinearSystem:
    """The linear system about ``state`` in the nodes' frames (module docstring); ``fluid``: one
    :class:`~drillstring.fem.fluid.FluidCoefficients` per mesh section (None: no fluid matrices);
    ``prestress=False`` drops K_g, ``wall=False`` the wall's springs."""
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
    elastic = nodal(k + (state.wall_stiffness if wall else sp.csr_matrix((n_dofs, n_dofs))))
    elastic = (elastic + stabilizer_stiffness(mesh, stabilizers)).tocsr()
    k_g = nodal(state.geometric_stiffness) if prestress else sp.csr_matrix((n_dofs, n_dofs))
    return LinearSystem(mesh, state.static_state(), nodal(m), nodal(m_f), elastic, k_g, nodal(k_f), nodal(c_f))


def well_modes(system: LinearSystem, count: int, cutoff: float = 0.0) -> ModeFamily:
    """The ``count`` lowest modes (and all below ``cutoff`` [rad/s]) of ``system`` on the coupled basis
    (:func:`drillstring.modal.coupled_modes`); shapes in the nodes' frames."""
    return coupled_modes(system, count, cutoff)


def case_well_modes(case, count: int = 10, state: StiffStringState | None = None) -> ModeFamily:
    """The lowest ``count`` modes of ``case`` about its stiff-string state in its well
    (:func:`drillstring.well.stiff_string.case_stiff_string` unless ``state`` is given), with its stabilizers
    and fluid."""
    from drillstring.fem.build import section_fluid_coefficients, stabilizers

    state = case_stiff_string(case) if state is None else state
    system = well_linear_system(state, stabilizers(case), section_fluid_coefficients(case, state.mesh))
    return well_modes(system, count)
