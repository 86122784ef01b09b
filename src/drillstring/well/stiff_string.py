"""Stiff-string statics along the well path: the beam model of the string resting on the borehole wall.

The soft string (:mod:`drillstring.well.torque_drag`) is a cable on the hole's axis. Here the string is the
finite-element beam of the dynamics (:mod:`drillstring.fem`) laid along the well path: its nodes at their
measured depths on the minimum-curvature path (:meth:`drillstring.well.survey.Trajectory.locate`), each
element rotated to the chord between its nodes (:func:`drillstring.fem.geometry.direction_cosines`; the element
code unchanged, the assembler turns its matrices, ``K_e = Tᵀ K'_e T``). It bends, deflects laterally inside
the hole until it touches the wall, and carries its buoyed weight to the hook and the bit.

Global frame: ``x`` the true vertical depth (down), ``y`` north, ``z`` east (right-handed; a vertical string
lies along ``x`` and every rotation is the identity, as in the vertical model). Displacements ``q`` are small
and measured from the reference configuration, the string on the hole's axis.

Equilibrium (small displacements about the path, second order in the axial force)::

    (K + K_stab + K_g(N)) q + f_0 + f_c(q) = f_g + f_bit                                            (1)

- ``K`` the elastic stiffness of the rotated elements; ``K_stab`` the stabilizers' lateral springs,
  ``k (I - t tᵀ)`` on the translations of their node (``t`` the path's unit tangent there).
- ``f_0 = Σ_e Tᵀ K'_e q_0,e``: the pipe is straight when unloaded, the path curved. At ``q = 0`` the string
  follows the path, its axis along the path's tangent ``t_i`` at every node; seen from element ``e`` (local
  axes the rows of ``R_e``) that tangent is ``a = R_e t_i``, the end rotations ``θz = a_y``, ``θy = -a_z``
  (:mod:`drillstring.fem.element`'s signs). ``q_0,e`` holds these rotations at both ends (translations 0):
  the elastic energy ``½ (T q + q_0)ᵀ K' (T q + q_0)``. On an arc of curvature κ the element's end
  rotations are ``±κh/2`` and its bending moment is ``EI κ`` (the pipe bent to the hole).
- ``K_g(N)`` the geometric stiffness of the effective axial force ``N`` (tension positive,
  :func:`drillstring.fem.assembly.geometric_stiffness` with the rotations); ``N`` is the solution's own
  axial force, updated in an outer loop until it changes by less than the tolerance. It acts on the
  string's deflection from the path, ``P q``, with the slide along the path taken out::

      K_g  ->  Pᵀ K_g P,      P = I − S,   S: (d, θ) -> ((d·t) t, (d·t) t × κ)   at each node      (2)

  (a node moved by ``u = d·t`` along the tangent and turned by ``u t × κ`` stays on the path, its shape
  unchanged). The string stretches by up to a metre along a curved path; the plain ``K_g q`` would read
  that slide as a turn ``u κ`` of every chord and push the string along the path by ``N κ² u`` per length
  (a spurious 525 N in the build of the ``deviated`` case's hook load; 3e-4 of the side force on an arc,
  the axial strain). ``K_g`` does not act on ``q_0``: the tension's turn along the path is already carried
  by the chords' change of direction at the nodes, ``N β`` per node = ``N κ h``.
- ``f_g``: the buoyed weight ``w`` per length [N/m] along ``+x`` (as :mod:`drillstring.well.torque_drag`
  computes it: ``w = g (m + ρ_i A_i − ρ_o A_o)``), plus the mud's skin friction along the element's axis
  when the case switches it on, as consistent element loads in the element's axes (axial: half to each
  node; lateral: the interpolation's own ``∫ N_v dx``).
- ``f_bit = F_bit t_bit`` at the bit, ``F_bit = −WOB`` (the effective axial force there).
- ``f_c``: the wall, a unilateral penalty at stations (two per element, one at each node, tributary length
  ``h/2``, as :mod:`drillstring.forces.contact`): with the node's lateral offset from the hole's axis
  ``δ = d − (d·t) t`` (``d`` its translation), ``r = |δ|`` and the radial clearance ``g = (D_hole − D_o)/2``
  (the casing's bore above the casing shoe), the station pushes ``−k (r − g)₊ δ/r`` with
  ``k = k'_sh h/2`` (``k'_sh`` the case's ``contact.shock_stiffness`` [N/m per m]).

Boundary conditions: the hook holds the top node's three translations (its lateral ones: the string is
centred at the rotary table) and its rotation about the path's tangent (no torque in statics); the bit is
held laterally (bit in gauge on the hole bottom: its two displacements across the path are 0), free axially
(it carries ``F_bit``); bending rotations are free at both ends.

Solution: (1) is the stationarity of a convex energy while ``K + K_g`` is positive (tension, or
compression below buckling). Newton's method with the penalty's tangent, ``k [n nᵀ + (1 − g/r)(P − n nᵀ)]``
(``n = δ/r``, ``P = I − t tᵀ``), its steps moving the nodes in contact round the wall (the step's radial
part kept, its tangential part turned into an arc: along the chord a stiff wall would be pressed
``|Δ_t|²/(2r)`` and the iteration creep round the hole), and an exact line search on the directional
derivative (secant), starting from the soft string's side-load direction; the outer loop updates ``N`` and
``K_g``. The friction of the side forces is NOT in the statics: the axial force is the frictionless one
(the soft string's ``rotating`` operations, or any operation with friction factors 0). A case whose
iterations do not converge raises ValueError naming the iteration count and the residual.

Outputs per node (:class:`StiffStringState`): positions, displacements, the axial force, the bending
moment, the wall's force (wall contact and stabilizers; the bit's and the hook's lateral reactions apart),
per node [N] and per length [N/m], and the geometric stiffness ``K_g(N)`` and the wall's linearised springs
in global coordinates (what a modal analysis about this state needs).

Units: SI throughout (m, N, N·m, rad). References: Cook, Malkus, Plesha & Witt (2002) §2.9, §7.2, §18.2
(rotation of element matrices, geometric stiffness); Johancsik, Friesen & Dawson (1984), SPE 11380 (the soft
string this reduces to away from the ends).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from drillstring.fem.assembly import Stabilizer, assemble_matrix, geometric_stiffness
from drillstring.fem.dofs import DOFS_PER_NODE, THETA_Y, THETA_Z, U
from drillstring.fem.element import (
    PLANE_Z_SIGNS,
    element_geometric_stiffness,
    element_stiffness,
    planar_shapes,
    shear_parameter,
)
from drillstring.fem.geometry import centreline_directions, direction_cosines
from drillstring.fem.mesh import Mesh
from drillstring.statics import StaticState
from drillstring.well.survey import Trajectory

if TYPE_CHECKING:
    from drillstring.well.buckling import WellBucklingMargin

__all__ = [
    "StiffStringState",
    "WallStations",
    "case_static_state_in_well",
    "case_stiff_string",
    "case_well_buckling_margin",
    "case_hole_diameters",
    "hole_diameters",
    "path_frames",
    "solve_stiff_string",
    "wall_stations",
]

#: Column order taking the survey's (north, east, TVD) to the model's global (x = TVD, y = north, z = east).
_GLOBAL = [2, 0, 1]
#: Exact line-search iterations (secant on the directional derivative).
_LINE_SEARCH = 40


@dataclass(frozen=True)
class WallStations:
    """Where the wall acts: station ``j`` on node ``node[j]`` with radial ``clearance`` [m], penalty
    ``stiffness`` [N/m] and tributary ``length`` [m]."""

    node: np.ndarray
    clearance: np.ndarray
    stiffness: np.ndarray
    length: np.ndarray


def hole_diameters(x: np.ndarray, hole_diameter: float, casing_shoe: float = 0.0,
                   casing_diameter: float | None = None) -> np.ndarray:
    """The hole's diameter [m] at measured depths ``x`` [m]: ``casing_diameter`` (default the hole's) above
    ``casing_shoe`` [m], the open hole's ``hole_diameter`` at and below it."""
    casing = hole_diameter if casing_diameter is None else casing_diameter
    return np.where(np.asarray(x, dtype=float) < casing_shoe, casing, hole_diameter)


def case_hole_diameters(case, x: np.ndarray) -> np.ndarray:
    """:func:`hole_diameters` of ``case`` (its ``[borehole]`` and ``[well]`` casing) at ``x`` [m]."""
    well = case.well
    return hole_diameters(x, case.borehole.diameter, 0.0 if well is None else well.casing_shoe,
                          None if well is None else well.casing_inner_diameter)


def wall_stations(mesh: Mesh, outer_diameter: Sequence[float], hole_diameter: float, wall_stiffness: float, *,
                  casing_shoe: float = 0.0, casing_diameter: float | None = None) -> WallStations:
    """Two stations per element (one at each node, tributary length h/2, the element's own clearance):
    ``outer_diameter`` of each mesh section [m], the open hole's ``hole_diameter`` [m] below ``casing_shoe``
    [m] and ``casing_diameter`` (default the hole's) above, ``wall_stiffness`` k'_sh [N/m per m]."""
    outer = np.asarray(outer_diameter, dtype=float)
    if outer.shape != (len(mesh.sections),):
        raise ValueError(f"outer_diameter: must give one diameter per mesh section ({len(mesh.sections)}), got "
                         f"shape {outer.shape}")
    if not (math.isfinite(wall_stiffness) and wall_stiffness > 0.0):
        raise ValueError(f"wall_stiffness = {wall_stiffness!r} N/m per m: must be a finite number > 0")
    h = mesh.element_lengths
    middle = 0.5 * (mesh.nodes[:-1] + mesh.nodes[1:])
    hole = hole_diameters(middle, hole_diameter, casing_shoe, casing_diameter)
    gap = (hole - outer[mesh.element_section]) / 2.0
    if np.any(gap < 0.0):
        e = int(np.argmin(gap))
        raise ValueError(f"outer_diameter = {outer[mesh.element_section[e]]:g} m at x = {middle[e]:g} m: must "
                         f"not exceed the hole's diameter ({hole[e]:g} m)")
    e = np.arange(mesh.n_elements)
    return WallStations(node=np.concatenate([e, e + 1]), clearance=np.concatenate([gap, gap]),
                        stiffness=np.concatenate([wall_stiffness * h / 2.0] * 2),
                        length=np.concatenate([h / 2.0] * 2))


def path_frames(mesh: Mesh, path: Trajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The nodes placed on ``path`` at measured depths ``mesh.nodes`` (the top at the surface): global
    positions (n, 3) [m], the path's unit tangents (n, 3) and curvature vectors (n, 3) [1/m] at the nodes,
    and each element's direction cosines (n_el, 3, 3) from its chord. ValueError when the string is longer
    than the path."""
    if mesh.length > path.depth * (1.0 + 1e-12):
        raise ValueError(f"mesh length = {mesh.length:g} m: the string must fit in the well ({path.depth:g} m)")
    position, tangent, curvature, _ = path.locate(np.minimum(mesh.nodes, path.depth))
    position, tangent, curvature = position[:, _GLOBAL], tangent[:, _GLOBAL], curvature[:, _GLOBAL]
    return position, tangent, curvature, direction_cosines(centreline_directions(position))


@dataclass(frozen=True)
class StiffStringState:
    """The stiff string's static equilibrium in the well (SI units; node arrays from the top to the bit).

    Attributes:
        mesh: the mesh (x = measured depth of the nodes).
        position: reference positions of the nodes on the path, global (TVD, north, east) [m], (n, 3).
        tangent: the path's unit tangent at the nodes (global), (n, 3).
        rotations: each element's direction cosines (n_el, 3, 3) (:func:`drillstring.fem.geometry.direction_cosines`).
        displacement: q, 6 DOFs per node in global axes [m, rad].
        axial_force: effective axial force N at the nodes [N], tension positive (the prestress).
        bending_moment: |M| at the nodes [N·m].
        wall_force: the wall's and stabilizers' force on each node, global (n, 3) [N] (the supports apart).
        tributary_length: the length of string each node stands for [m].
        top_reaction, bit_reaction: the supports' forces on the string, global (3,) [N].
        weight: the string's buoyed weight plus skin friction, ∫ q ds [N].
        weight_on_bit: the bit's axial reaction [N] (−N at the bit).
        geometric_stiffness: K_g(N) in global axes (sparse, no boundary conditions; the plain K_g of the
            prestress, for small vibrations about this state; the statics used Pᵀ K_g P, eq. (2)).
        wall_stiffness: the wall's linearised springs at the equilibrium, global (sparse; the tangent of f_c).
        iterations: Newton iterations, all outer loops together.
        tangent_stiffness: the statics' tangent K + K_stab + Pᵀ K_g P + the wall's, global (sparse).
        free_basis: Z, q = Z y satisfying the supports (n_dofs × n_free).
    """

    mesh: Mesh
    position: np.ndarray
    tangent: np.ndarray
    rotations: np.ndarray
    displacement: np.ndarray
    axial_force: np.ndarray
    bending_moment: np.ndarray
    wall_force: np.ndarray
    tributary_length: np.ndarray
    top_reaction: np.ndarray
    bit_reaction: np.ndarray
    weight: float
    weight_on_bit: float
    geometric_stiffness: sp.csr_matrix
    wall_stiffness: sp.csr_matrix
    iterations: int
    tangent_stiffness: sp.csr_matrix | None = None
    free_basis: sp.csr_matrix | None = None

    @property
    def measured_depth(self) -> np.ndarray:
        return self.mesh.nodes

    @property
    def translation(self) -> np.ndarray:
        """Node translations (n, 3), global [m]."""
        return self.displacement.reshape(-1, DOFS_PER_NODE)[:, :3]

    @property
    def deflected_position(self) -> np.ndarray:
        return self.position + self.translation

    @property
    def lateral_offset(self) -> np.ndarray:
        """Distance of each node from the hole's axis, across the path [m]."""
        d = self.translation
        return np.linalg.norm(d - np.einsum("ij,ij->i", d, self.tangent)[:, None] * self.tangent, axis=1)

    @property
    def side_force(self) -> np.ndarray:
        """|wall force| on each node [N]."""
        return np.linalg.norm(self.wall_force, axis=1)

    @property
    def side_force_per_length(self) -> np.ndarray:
        """|wall force| / tributary length [N/m] (a stabilizer's point force shows as a spike)."""
        return self.side_force / self.tributary_length

    @property
    def in_contact(self) -> np.ndarray:
        return self.side_force > 0.0

    @property
    def hook_load(self) -> float:
        """The hook's pull along the path's tangent at the top [N] (weight on hook)."""
        return float(-self.top_reaction @ self.tangent[0])

    @property
    def weight_on_hook(self) -> float:
        """:attr:`hook_load` [N], under :class:`drillstring.statics.StaticState`'s name."""
        return self.hook_load

    @property
    def neutral_point_height(self) -> float:
        """Length of string [m] between the bit and the point where the axial force changes sign (its
        :meth:`static_state`'s); nan if it keeps one sign."""
        return self.static_state().neutral_point_height

    @property
    def lateral_reactions(self) -> tuple[float, float]:
        """The hook's and the bit's reactions across the path's tangent there, |F − (F·t) t| [N]."""
        def lateral(force, t):
            return float(np.linalg.norm(force - (force @ t) * t))
        return lateral(self.top_reaction, self.tangent[0]), lateral(self.bit_reaction, self.tangent[-1])

    @property
    def side_force_with_supports(self) -> np.ndarray:
        """:attr:`side_force` [N] with the hook's and the bit's lateral reactions added at the top and the bit
        (the force across the path on each node; its sum is :attr:`total_side_force`)."""
        out = self.side_force.copy()
        top, bit = self.lateral_reactions
        out[0] += top
        out[-1] += bit
        return out

    @property
    def total_side_force(self) -> float:
        """Σ |wall force| + the hook's and the bit's lateral reactions [N] (comparable with ∫ n ds)."""
        top, bit = self.lateral_reactions
        return float(self.side_force.sum() + top + bit)

    def unstable_directions(self) -> int:
        """The number of negative eigenvalues of the tangent stiffness on the free DOFs, ``Zᵀ K_t Z``
        (dense): 0 for a stable equilibrium; positive when the string found is past buckling (the
        iteration finds the equilibrium on the low side, stable or not: a straight string in a straight
        hole stays on its low side past the Dawson–Paslay load, 2 sqrt(EI w sin I / r))."""
        if self.tangent_stiffness is None or self.free_basis is None:
            raise ValueError("tangent_stiffness: not stored with this state")
        z = self.free_basis
        reduced = (z.T @ self.tangent_stiffness @ z).toarray()
        values = np.linalg.eigvalsh(0.5 * (reduced + reduced.T))
        return int(np.count_nonzero(values < -1e-12 * np.abs(values).max()))

    def static_state(self) -> StaticState:
        """The axial part as :class:`drillstring.statics.StaticState` (the prestress for
        :func:`drillstring.modal.build_linear_system`); its displacement is the full global q."""
        return StaticState(self.mesh, self.displacement, self.axial_force, self.weight, self.hook_load,
                           self.weight_on_bit)


def _to_local(vectors: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """(n_el, 12) global element vectors in element axes: each 3-block times R."""
    blocks = vectors.reshape(len(rotations), 4, 3)
    return np.einsum("eji,eai->eaj", rotations, blocks).reshape(-1, 12)


def _to_global(vectors: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """(n_el, 12) element-axes vectors in global axes: each 3-block times Rᵀ."""
    blocks = vectors.reshape(len(rotations), 4, 3)
    return np.einsum("eji,eaj->eai", rotations, blocks).reshape(-1, 12)


def _scatter(n_dofs: int, element_vectors: np.ndarray) -> np.ndarray:
    out = np.zeros(n_dofs)
    index = DOFS_PER_NODE * np.arange(len(element_vectors))[:, None] + np.arange(12)
    np.add.at(out, index, element_vectors)
    return out


def _element_loads(mesh: Mesh, rotations: np.ndarray, weight: np.ndarray, skin: np.ndarray) -> np.ndarray:
    """Consistent loads (n_el, 12) in element axes of the weight w [N/m] along global +x and the skin
    friction along the element's axis [N/m]."""
    out = np.zeros((mesh.n_elements, 12))
    sections = mesh.element_sections()
    for e, (section, h) in enumerate(zip(sections, mesh.element_lengths)):
        w, q = weight[mesh.element_section[e]], skin[mesh.element_section[e]]
        load = rotations[e] @ np.array([w, 0.0, 0.0])  # per length, element axes
        shapes = planar_shapes(h, shear_parameter(section, h))
        lateral = shapes.weights @ shapes.displacement  # ∫ N_v dx over (v1, ψ1, v2, ψ2)
        out[e, [0, 6]] = 0.5 * h * (load[0] + q)
        out[e, [1, 5, 7, 11]] = load[1] * lateral
        out[e, [2, 4, 8, 10]] = load[2] * PLANE_Z_SIGNS * lateral
    return out


def _initial_rotations(tangent: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """q_0 (n_el, 12) of eq. (1): the path's tangents at each element's ends in its axes as end rotations."""
    q0 = np.zeros((len(rotations), 12))
    for end, offset in ((0, 0), (1, 6)):
        a = np.einsum("eij,ej->ei", rotations, tangent[end:len(tangent) - 1 + end])
        q0[:, offset + THETA_Z] = a[:, 1]
        q0[:, offset + THETA_Y] = -a[:, 2]
    return q0


def _free_basis(n_nodes: int, tangent: np.ndarray) -> sp.csr_matrix:
    """Z (n_dofs × n_free): q = Z y satisfies the boundary conditions (module docstring)."""
    n_dofs = DOFS_PER_NODE * n_nodes
    frame_top = direction_cosines(tangent[:1])[0]
    frame_bit = direction_cosines(tangent[-1:])[0]
    columns: list[np.ndarray] = []
    rows: list[np.ndarray] = []
    for i in range(n_nodes):
        base = DOFS_PER_NODE * i
        if i == 0:  # translations held; rotation about t held: the two across it free
            rows += [base + 3 + np.arange(3)] * 2
            columns += [frame_top[1], frame_top[2]]
            continue
        if i == n_nodes - 1:  # translation along t free; rotations free
            rows.append(base + np.arange(3))
            columns.append(frame_bit[0])
            rows += [np.array([base + 3 + k]) for k in range(3)]
            columns += [np.ones(1)] * 3
            continue
        rows += [np.array([base + k]) for k in range(DOFS_PER_NODE)]
        columns += [np.ones(1)] * DOFS_PER_NODE
    r = np.concatenate(rows)
    c = np.concatenate([np.full(len(v), j) for j, v in enumerate(columns)])
    return sp.csr_matrix((np.concatenate(columns), (r, c)), shape=(n_dofs, len(columns)))


def _wall(q: np.ndarray, stations: WallStations, tangent: np.ndarray, n_dofs: int, with_stiffness: bool = True):
    """The wall's term f_c of eq. (1) at q (the string's push on the wall, minus the wall's force on the
    string) (n_dofs,), its penalty energy and its tangent stiffness (sparse)."""
    d = q.reshape(-1, DOFS_PER_NODE)[stations.node, :3]
    t = tangent[stations.node]
    lateral = d - np.einsum("ij,ij->i", d, t)[:, None] * t
    r = np.linalg.norm(lateral, axis=1)
    active = r > stations.clearance
    force = np.zeros(n_dofs)
    if not np.any(active):
        return force, 0.0, (sp.csr_matrix((n_dofs, n_dofs)) if with_stiffness else None)
    k, g, ra = stations.stiffness[active], stations.clearance[active], r[active]
    n = lateral[active] / ra[:, None]
    push = k * (ra - g)
    dofs = DOFS_PER_NODE * stations.node[active][:, None] + np.arange(3)
    np.add.at(force, dofs, push[:, None] * n)  # the wall pushes the string back by -push n
    energy = 0.5 * float(np.sum(k * (ra - g) ** 2))
    if not with_stiffness:
        return force, energy, None
    ta = t[active]
    nn = np.einsum("si,sj->sij", n, n)
    projector = np.eye(3)[None] - np.einsum("si,sj->sij", ta, ta)
    blocks = k[:, None, None] * (nn + (1.0 - g / ra)[:, None, None] * (projector - nn))
    rows = np.broadcast_to(dofs[:, :, None], blocks.shape)
    cols = np.broadcast_to(dofs[:, None, :], blocks.shape)
    stiffness = sp.coo_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(n_dofs, n_dofs)).tocsr()
    return force, energy, stiffness


def _stabilizer_matrix(mesh: Mesh, stabilizers: Sequence[Stabilizer], tangent: np.ndarray) -> sp.csr_matrix:
    """``k (I − t tᵀ)`` on the translations of each stabilizer's node."""
    n = mesh.n_dofs
    out = sp.csr_matrix((n, n))
    for s in stabilizers:
        node = mesh.node_index(s.position)
        t = tangent[node]
        block = s.stiffness * (np.eye(3) - np.outer(t, t))
        dofs = DOFS_PER_NODE * node + np.arange(3)
        out = out + sp.coo_matrix((block.ravel(), (np.repeat(dofs, 3), np.tile(dofs, 3))), shape=(n, n)).tocsr()
    return out


def _initial_axial_force(mesh: Mesh, tangent: np.ndarray, weight: np.ndarray, skin: np.ndarray,
                         bit_force: float) -> np.ndarray:
    """The frictionless soft string's N (dN/ds = −(w cos I + q_f)) from the bit up: the outer loop's start."""
    cos_i = 0.5 * (tangent[:-1, 0] + tangent[1:, 0])
    step = (weight[mesh.element_section] * cos_i + skin[mesh.element_section]) * mesh.element_lengths
    return bit_force + np.concatenate([np.cumsum(step[::-1])[::-1], [0.0]])


def _soft_string_start(mesh, curvature, stations, tangent, weight, axial_force) -> np.ndarray:
    """Newton's start: each inner node pressed into the wall along the soft string's side load
    ``p = N κ + w (x̂ − (x̂·t) t)`` [N/m] (the wall's penalty depth ``|p| ℓ / k``), the ends on the axis; a
    node with no side load stays on the axis. Starting from the axis instead, the first steps, with no
    contact, throw the string far out of the hole and the line search creeps back."""
    w = weight[mesh.node_section()]
    vertical = np.array([1.0, 0.0, 0.0])
    load = axial_force[:, None] * curvature + w[:, None] * (vertical - tangent[:, :1] * tangent)
    size = np.linalg.norm(load, axis=1)
    n = mesh.n_nodes
    clearance = np.full(n, np.inf)
    np.minimum.at(clearance, stations.node, stations.clearance)
    stiffness = np.bincount(stations.node, weights=stations.stiffness, minlength=n)
    tributary = np.bincount(stations.node, weights=stations.length, minlength=n)
    depth = np.where(np.isfinite(clearance), clearance, 0.0) + size * tributary / np.maximum(stiffness, 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        offset = np.where(size[:, None] > 0.0, depth[:, None] * load / size[:, None], 0.0)
    offset[[0, -1]] = 0.0
    q = np.zeros(mesh.n_dofs)
    q.reshape(-1, DOFS_PER_NODE)[:, :3] = offset
    return q


def _deflection_operator(tangent: np.ndarray, curvature: np.ndarray) -> sp.csr_matrix:
    """P = I − S: q less its slide along the path. A node moved by ``u = d·t`` along its tangent and turned
    by ``θ = u t × κ`` (the path's tangent turns by κ u) is still on the path, its shape unchanged; the
    geometric stiffness acts on ``P q`` only (eq. (2) of the module docstring)."""
    n = len(tangent)
    binormal = np.cross(tangent, curvature)
    blocks = np.zeros((n, 6, 6))
    blocks[:, :3, :3] = np.einsum("ni,nj->nij", tangent, tangent)
    blocks[:, 3:, :3] = np.einsum("ni,nj->nij", binormal, tangent)
    base = DOFS_PER_NODE * np.arange(n)[:, None] + np.arange(6)
    rows = np.broadcast_to(base[:, :, None], blocks.shape)
    cols = np.broadcast_to(base[:, None, :], blocks.shape)
    slide = sp.coo_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(6 * n, 6 * n)).tocsr()
    return (sp.identity(6 * n, format="csr") - slide).tocsr()


def _recover(q, deflection, mesh, rotations, local_k, q0, loads, axial_force):
    """Element end forces in element axes (n_el, 12): K'(T q + q_0) + K'_g T (P q) − f_e (``deflection`` =
    P q, :func:`_deflection_operator`); the axial force
    [N] and |bending moment| [N·m] at the nodes (each node from the element below it, the bit from the last)."""
    index = DOFS_PER_NODE * np.arange(mesh.n_elements)[:, None] + np.arange(12)
    local = _to_local(q[index], rotations)
    bent = _to_local(deflection[index], rotations)
    kg = np.stack([element_geometric_stiffness(s, h, axial_force[e], axial_force[e + 1])
                   for e, (s, h) in enumerate(zip(mesh.element_sections(), mesh.element_lengths))])
    end = (np.einsum("eij,ej->ei", local_k, local + q0) + np.einsum("eij,ej->ei", kg, bent) - loads)
    force = np.append(-end[:, U], end[-1, 6 + U])
    moment = np.append(np.linalg.norm(end[:, [THETA_Y, THETA_Z]], axis=1),
                       np.linalg.norm(end[-1, [6 + THETA_Y, 6 + THETA_Z]]))
    return force, moment


def _rounding_floor(q: np.ndarray, stations: WallStations) -> float:
    """The wall forces' rounding [N]: a station's offset from the axis is the node's translation less its
    part along the path (up to a metre: the stretch), known to ``ε |d|``, times the station's stiffness."""
    largest = float(np.abs(q.reshape(-1, DOFS_PER_NODE)[:, :3]).max()) if len(q) else 0.0
    return 16.0 * np.finfo(float).eps * float(stations.stiffness.max(initial=0.0)) * largest


def _on_the_wall(q: np.ndarray, dq: np.ndarray, stations: WallStations, tangent: np.ndarray) -> np.ndarray:
    """Newton's step with the nodes on the wall moved round it: a node in contact keeps the step's radial
    change ``n·Δ`` and turns by its tangential part, ``δ' = (r + n·Δ) (δ + Δ_t)/|δ + Δ_t|``, instead of
    going along the chord (which would press it ``|Δ_t|²/(2r)`` into the wall: with a stiff wall, forces
    far off the linearisation and a Newton iteration creeping round the hole)."""
    d = q.reshape(-1, DOFS_PER_NODE)[:, :3]
    step = dq.reshape(-1, DOFS_PER_NODE)[:, :3]
    lateral = d - np.einsum("ij,ij->i", d, tangent)[:, None] * tangent
    r = np.linalg.norm(lateral, axis=1)
    clearance = np.full(len(d), np.inf)
    np.minimum.at(clearance, stations.node, stations.clearance)
    touching = np.nonzero(r > clearance)[0]
    if not len(touching):
        return dq
    out = dq.copy()
    t = tangent[touching]
    n = lateral[touching] / r[touching, None]
    delta = step[touching] - np.einsum("ij,ij->i", step[touching], t)[:, None] * t
    radial = np.einsum("ij,ij->i", delta, n)
    turned = lateral[touching] + delta - radial[:, None] * n
    moved = (r[touching] + radial)[:, None] * turned / np.linalg.norm(turned, axis=1)[:, None]
    out.reshape(-1, DOFS_PER_NODE)[touching, :3] += moved - lateral[touching] - delta
    return out


def _line_search(q, dq, residual) -> float:
    """Step α in (0, 1] where the energy along dq stops decreasing: a root of dqᵀ r(q + α dq), increasing
    in α for a convex energy (Illinois secant; α = 1 when the full step still descends)."""
    g0, g1 = float(dq @ residual(q)), float(dq @ residual(q + dq))
    if not (g0 < 0.0 < g1):
        return 1.0
    a, b, ga, gb, side = 0.0, 1.0, g0, g1, 0
    for _ in range(_LINE_SEARCH):
        c = b - gb * (b - a) / (gb - ga)
        gc = float(dq @ residual(q + c * dq))
        if gc > 0.0:
            b, gb = c, gc
            ga = ga / 2.0 if side == -1 else ga
            side = -1
        else:
            a, ga = c, gc
            gb = gb / 2.0 if side == 1 else gb
            side = 1
        if abs(gc) <= 1e-6 * abs(g0) or b - a <= 1e-12:
            break
    return c


def solve_stiff_string(mesh: Mesh, path: Trajectory, weight: Sequence[float], stations: WallStations, *,
                       skin_friction: Sequence[float] | None = None, bit_force: float = 0.0,
                       stabilizers: Sequence[Stabilizer] = (), tolerance: float = 1e-9,
                       max_iterations: int = 200) -> StiffStringState:
    """Static equilibrium (1) of the string ``mesh`` (x = measured depth, top at the surface) in the well
    ``path``.

    Args:
        weight: buoyed weight per length w of each mesh section [N/m], along the vertical.
        stations: the wall (:func:`wall_stations`).
        skin_friction: the mud's axial load per length of each mesh section [N/m], along the string (0).
        bit_force: effective axial force at the bit [N], tension positive (−WOB on bottom).
        stabilizers: lateral springs (:class:`drillstring.fem.assembly.Stabilizer`).
        tolerance: the equilibrium's residual allowed, relative to the largest nodal load (never below the
            wall forces' rounding, 16 ε k |d|); the axial force's change between outer loops allowed,
            relative to its largest value.
        max_iterations: Newton iterations allowed (all outer loops together).

    Raises ValueError for bad input and when the iterations do not converge (naming their count and the
    residual)."""
    weight = np.asarray(weight, dtype=float)
    skin = np.zeros(len(mesh.sections)) if skin_friction is None else np.asarray(skin_friction, dtype=float)
    for name, values in (("weight", weight), ("skin_friction", skin)):
        if values.shape != (len(mesh.sections),) or not np.all(np.isfinite(values)):
            raise ValueError(f"{name}: must be {len(mesh.sections)} finite values (one per mesh section) [N/m], "
                             f"got {values!r}")
    if not math.isfinite(bit_force):
        raise ValueError(f"bit_force = {bit_force!r} N: must be finite")
    if not (math.isfinite(tolerance) and 0.0 < tolerance < 1.0):
        raise ValueError(f"tolerance = {tolerance!r}: must be in (0, 1)")
    if not (isinstance(max_iterations, int) and max_iterations >= 1):
        raise ValueError(f"max_iterations = {max_iterations!r}: must be an integer >= 1")
    position, tangent, curvature, rotations = path_frames(mesh, path)
    deflection = _deflection_operator(tangent, curvature)
    n, n_dofs = mesh.n_nodes, mesh.n_dofs
    pairs = list(zip(mesh.element_sections(), mesh.element_lengths))
    local_k = np.stack([element_stiffness(s, h) for s, h in pairs])
    k = assemble_matrix(n_dofs, local_k, rotations) + _stabilizer_matrix(mesh, stabilizers, tangent)
    loads = _element_loads(mesh, rotations, weight, skin)
    f_ext = _scatter(n_dofs, _to_global(loads, rotations))
    f_ext[DOFS_PER_NODE * (n - 1) + np.arange(3)] += bit_force * tangent[-1]
    q0 = _initial_rotations(tangent, rotations)
    f0 = _scatter(n_dofs, _to_global(np.einsum("eij,ej->ei", local_k, q0), rotations))
    z = _free_basis(n, tangent)
    zt = z.T.tocsr()
    scale = max(float(np.abs(f_ext).max()), float(np.abs(f0).max()), abs(bit_force), 1.0)
    tol = tolerance * scale
    axial = _initial_axial_force(mesh, tangent, weight, skin, bit_force)
    q = _soft_string_start(mesh, curvature, stations, tangent, weight, axial)
    iterations, residual_norm = 0, math.inf
    for _outer in range(max_iterations):
        a = (k + deflection.T @ geometric_stiffness(mesh, axial, rotations) @ deflection).tocsr()

        def residual(x, a=a):
            return a @ x + f0 + _wall(x, stations, tangent, n_dofs, False)[0] - f_ext

        while True:
            fc, _, kc = _wall(q, stations, tangent, n_dofs)
            r = a @ q + f0 + fc - f_ext
            residual_norm = float(np.abs(zt @ r).max())
            if residual_norm <= max(tol, _rounding_floor(q, stations)):
                break
            if iterations >= max_iterations:
                raise ValueError(f"stiff-string statics did not converge in {iterations} Newton iterations: "
                                 f"residual {residual_norm:.3g} N > tolerance {tol:.3g} N")
            jacobian = (zt @ (a + kc) @ z).tocsc()
            dq = _on_the_wall(q, z @ spla.spsolve(jacobian, -(zt @ r)), stations, tangent)
            q = q + _line_search(q, dq, residual) * dq
            iterations += 1
        new_axial, moment = _recover(q, deflection @ q, mesh, rotations, local_k, q0, loads, axial)
        change = float(np.abs(new_axial - axial).max())
        axial = new_axial
        if change <= tolerance * max(float(np.abs(axial).max()), 1.0):
            break
    else:  # the axial force kept changing through max_iterations outer loops
        raise ValueError(f"stiff-string statics did not converge in {max_iterations} outer loops "
                         f"({iterations} Newton iterations): the axial force still changing by {change:.3g} N")
    fc, _, kc = _wall(q, stations, tangent, n_dofs)
    kg = geometric_stiffness(mesh, axial, rotations)
    reaction = (k + deflection.T @ kg @ deflection) @ q + f0 + fc - f_ext
    stabilizer_force = -(_stabilizer_matrix(mesh, stabilizers, tangent) @ q)
    wall = (-fc + stabilizer_force).reshape(-1, DOFS_PER_NODE)[:, :3]
    tributary = np.bincount(stations.node, weights=stations.length, minlength=n)
    weight_total = math.fsum(((weight + skin)[mesh.element_section] * mesh.element_lengths).tolist())
    return StiffStringState(mesh, position, tangent, rotations, q, axial, moment, wall, tributary,
                            reaction[:3].copy(), reaction[DOFS_PER_NODE * (n - 1):DOFS_PER_NODE * (n - 1) + 3].copy(),
                            weight_total, -bit_force, kg.tocsr(), kc, iterations,
                            (k + deflection.T @ kg @ deflection + kc).tocsr(), z)


def case_stiff_string(case, *, weight_on_bit: float | None = None, wall_stiffness: float | None = None,
                      mesh: Mesh | None = None, path: Trajectory | None = None, tolerance: float = 1e-9,
                      max_iterations: int = 200) -> StiffStringState:
    """The stiff-string statics of a :class:`~drillstring.case.Case` in its well (``[well]``; a vertical hole
    as deep as the string without one): its mesh (:func:`drillstring.fem.build.case_mesh`), the weights
    and skin friction of the soft string (:mod:`drillstring.well.torque_drag`), its stabilizers, the wall's
    stiffness ``contact.shock_stiffness`` [N/m per m] unless ``wall_stiffness`` is given, the casing's bore
    above the shoe, and the case's weight on bit (0 off bottom, ``bit_rock.law = "off_bottom"``) unless
    ``weight_on_bit`` [N] is given."""
    from drillstring.fem.build import case_mesh, stabilizers
    from drillstring.well.torque_drag import _section_table, case_trajectory

    mesh = case_mesh(case) if mesh is None else mesh
    path = case_trajectory(case) if path is None else path
    table = _section_table(case)
    if len(table) != len(mesh.sections):
        raise ValueError(f"the mesh has {len(mesh.sections)} sections, the case {len(table)}")
    wob = case.operation.weight_on_bit if weight_on_bit is None else float(weight_on_bit)
    if weight_on_bit is None and case.bit_rock.law == "off_bottom":
        wob = 0.0
    if not (math.isfinite(wob) and wob >= 0.0):
        raise ValueError(f"weight_on_bit = {weight_on_bit!r} N: must be a finite number >= 0")
    well = case.well
    stiffness = case.contact.shock_stiffness if wall_stiffness is None else wall_stiffness
    stations = wall_stations(mesh, [row[6] for row in table], case.borehole.diameter, stiffness,
                             casing_shoe=0.0 if well is None else well.casing_shoe,
                             casing_diameter=None if well is None else well.casing_inner_diameter)
    return solve_stiff_string(mesh, path, [row[2] for row in table], stations,
                              skin_friction=[row[3] for row in table], bit_force=-wob,
                              stabilizers=stabilizers(case), tolerance=tolerance, max_iterations=max_iterations)


def case_static_state_in_well(case) -> StaticState:
    """The case's static state, selected by ``[well]``: without it the vertical statics exactly as before
    (:func:`drillstring.statics.case_static_state`); with it the stiff string's (:func:`case_stiff_string`)."""
    if case.well is None:
        from drillstring.statics import case_static_state

        return case_static_state(case)
    return case_stiff_string(case).static_state()


def case_well_buckling_margin(case, state: StiffStringState) -> WellBucklingMargin:
    """:func:`~drillstring.well.buckling.margin_along_path` (eq. (3) there) of the stiff string ``state``
    (:func:`case_stiff_string`) of ``case`` in its well: the critical compressions of the
    soft string's discretisation (:func:`~drillstring.well.torque_drag.string_in_well`, elements of at most
    1 m, the pipe body's clearance), the stiff string's axial force interpolated linearly onto its nodes."""
    from drillstring.well.buckling import critical_loads, margin_along_path
    from drillstring.well.torque_drag import case_trajectory, string_in_well

    string = string_in_well(case, case_trajectory(case))
    md = string.measured_depth
    force = np.interp(md, state.measured_depth, state.axial_force)
    if not math.isclose(float(md[-1]), float(state.measured_depth[-1]), rel_tol=1e-9):
        raise ValueError(f"the stiff string ends at {state.measured_depth[-1]:g} m, the string in the well at "
                         f"{md[-1]:g} m: they must be the same string")
    return margin_along_path(md, force, critical_loads(string), weight_on_bit=state.weight_on_bit,
                             weight=state.weight)
