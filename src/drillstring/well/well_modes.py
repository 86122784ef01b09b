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
from drillstring.fem.fluid import FluidCoefficients
from drillstring.fem.geometry import direction_cosines
from drillstring.modal import (
    DENSE_LIMIT,
    LinearSystem,
    ModeFamily,
    coupled_dofs,
    coupled_modes,
)
from drillstring.well.stiff_string import StiffStringState, case_stiff_string

__all__ = ["WELL_MODE_FAMILIES", "WellModes", "case_well_mode_families", "case_well_modes", "case_well_system", "kinetic_energy_shares",
           "nodal_frames", "well_linear_system", "well_modes"]

#: The families a mode along the path is named by, and their nodal DOFs (in the nodes' frames).
WELL_MODE_FAMILIES = {"axial": (U,), "torsional": (THETA_X,), "lateral": (V, W, THETA_Y, THETA_Z)}


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
    return well_modes(case_well_system(case, state), count)


def case_well_system(case, state: StiffStringState | None = None) -> LinearSystem:
    """:func:`well_linear_system` of ``case`` about ``state`` (its
    :func:`~drillstring.well.stiff_string.case_stiff_string` when None), with its stabilizers and fluid."""
    from drillstring.fem.build import section_fluid_coefficients, stabilizers

    state = case_stiff_string(case) if state is None else state
    return well_linear_system(state, stabilizers(case), section_fluid_coefficients(case, state.mesh))


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
