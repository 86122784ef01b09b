"""Lateral excitation that turns with the string: mass imbalance and a stress-free bow.

Both are fixed to the string's sections, so they turn with the local rotation of the section,
``θx(x, t) = Ω t + θ̄x(x, t)`` (the imposed top rotation plus the torsional response; SI units, θx about
+x, measured from y towards z). A direction fixed to the section at the angle ``φ`` [rad] from y at
``θx = 0`` points along ``(cos α, sin α)`` in the (y, z) plane, ``α = θx + φ``.

Mass imbalance
--------------
A section whose mass centre is offset by ``e`` [m] from its axis (an eccentric collar, a tool with an
off-centre mass) carries the centrifugal force per unit length

    f(x, t) = ρA e θ̇x² (cos α, sin α)                                                [N/m]

on its lateral DOFs (``ρA`` the steel mass per length [kg/m]). It is lumped on the nodes by nodal
(trapezoidal) quadrature of each element, like the distributed wall stiffness
(:mod:`drillstring.forces.contact`): each element of length ``h`` gives each of its nodes
``ρA e h/2``; a node at a section change gets one entry per adjacent section (each with its own ``e``
and ``φ``). **Decision:** the tangential inertia ``−ρA e θ̈x (−sin α, cos α)`` and the imbalance's moments
on the torsion (its weight and inertia about the axis) are left out: ``e θ̈x`` is below 5 % of
``e θ̇x²`` except during stick–slip's fastest accelerations, and ``ρA e²`` is far below the section's
polar inertia ``ρI_p``. The force is prescribed by the spin; it does work on the string, which the
imposed top rotation supplies.

Stress-free bow
---------------
A string whose unloaded shape is bowed by ``b(x)`` (a bent collar) has the strain energy
``½ (q − q_b)ᵀ K (q − q_b)`` with ``K`` the elastic stiffness of the beam elements (not the stabilizers'
springs, which hold the string to the borehole, not to its own shape, nor the geometric stiffness of
the axial load, which acts on the actual slope), so it adds the load ``K q_b`` to the equations of
motion. The bow turns with the section: ``v_b = b cos α``, ``w_b = b sin α`` and, for the bending
rotations, ``θz_b = ∂v_b/∂x ≈ b' cos α``, ``θy_b = −∂w_b/∂x ≈ −b' sin α`` (the term ``b α'`` of the twist
rate, ~1e-3 rad/m at most, is left out). The shape is the smooth bump

    b(x) = a sin²(π (x − x₀)/(x₁ − x₀))  on [x₀, x₁],  0 elsewhere

(``b`` and ``b'`` vanish at both ends: no kink), sampled at the nodes.

Both are :class:`TurningLoads`: the physical load is
``Σ_k s_k [cos α_k F_y[:, k] + sin α_k F_z[:, k]]`` with ``α_k = θx(node_k) + φ_k`` and ``s_k = θ̇x(node_k)²``
(imbalance) or 1 (bow). The reduced model projects ``F_y`` and ``F_z`` on its lateral modes once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from drillstring.fem.dofs import THETA_Y, THETA_Z, V, W, dof
from drillstring.fem.mesh import Mesh

__all__ = ["TurningLoads", "imbalance_loads", "bow_loads", "bow_shape"]


@dataclass(frozen=True)
class TurningLoads:
    """Loads fixed to the string's sections (module docstring). One entry ``k`` per column:

    Attributes:
        node: (m,) int64, the node whose rotation ``θx`` turns entry ``k``.
        phase: (m,) φ_k [rad], the entry's angle from y at ``θx = 0``.
        speed_squared: (m,) bool, the load scales with the local spin speed squared ``θ̇x²`` (imbalance)
            or is constant (bow).
        force_y, force_z: (n_dofs, m) sparse global force patterns [N, N·m per (rad/s)² for an
            imbalance, N, N·m for a bow] along y and z when ``α = 0`` and ``α = π/2``.
    """

    node: np.ndarray
    phase: np.ndarray
    speed_squared: np.ndarray
    force_y: sp.csc_matrix
    force_z: sp.csc_matrix

    def __len__(self) -> int:
        return len(self.node)

    @classmethod
    def empty(cls, n_dofs: int) -> TurningLoads:
        return cls(np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=bool),
                   sp.csc_matrix((n_dofs, 0)), sp.csc_matrix((n_dofs, 0)))

    def __add__(self, other: TurningLoads) -> TurningLoads:
        return TurningLoads(
            np.concatenate([self.node, other.node]).astype(np.int64),
            np.concatenate([self.phase, other.phase]),
            np.concatenate([self.speed_squared, other.speed_squared]).astype(bool),
            sp.hstack([self.force_y, other.force_y]).tocsc(),
            sp.hstack([self.force_z, other.force_z]).tocsc(),
        )

    def forces(self, rotation: np.ndarray, spin_speed: np.ndarray) -> np.ndarray:
        """The global load vector (n_dofs,) for the rotation θx [rad] and spin speed θ̇x [rad/s] of every
        node (arrays indexed by node)."""
        angle = np.asarray(rotation, dtype=float)[self.node] + self.phase
        scale = np.where(self.speed_squared, np.asarray(spin_speed, dtype=float)[self.node] ** 2, 1.0)
        return self.force_y @ (scale * np.cos(angle)) + self.force_z @ (scale * np.sin(angle))


def _columns(n_dofs: int, rows: list[np.ndarray], values: list[np.ndarray]) -> sp.csc_matrix:
    """A sparse (n_dofs, m) matrix whose column k has ``values[k]`` at ``rows[k]``."""
    cols = np.concatenate([np.full(len(r), k) for k, r in enumerate(rows)]) if rows else np.zeros(0, int)
    r = np.concatenate(rows) if rows else np.zeros(0, int)
    v = np.concatenate(values) if values else np.zeros(0)
    return sp.csc_matrix((v, (r, cols)), shape=(n_dofs, len(rows)))


def imbalance_loads(mesh: Mesh, eccentricity, angle) -> TurningLoads:
    """Centrifugal loads of eccentric sections (module docstring).

    Args:
        mesh: the string's mesh.
        eccentricity: e [m] of each mesh section (``mesh.sections`` order), mass centre offset from the axis.
        angle: φ [rad] of each mesh section, the direction of the offset from y at θx = 0.
    """
    e = np.asarray(eccentricity, dtype=float)
    phi = np.asarray(angle, dtype=float)
    if e.shape != (len(mesh.sections),) or phi.shape != e.shape:
        raise ValueError(f"need one eccentricity and one angle per mesh section ({len(mesh.sections)})")
    if not (np.all(np.isfinite(e)) and np.all(e >= 0) and np.all(np.isfinite(phi))):
        raise ValueError("eccentricities must be finite and >= 0 m, angles finite")
    # nodal quadrature: each element gives ρA e h/2 to each of its nodes, entries merged per (node, section)
    amounts: dict[tuple[int, int], float] = {}
    for element, (section_index, h) in enumerate(zip(mesh.element_section, mesh.element_lengths)):
        if e[section_index] == 0.0:
            continue
        section = mesh.sections[section_index]
        half = section.density * section.area * e[section_index] * h / 2.0
        for node in (element, element + 1):
            key = (node, int(section_index))
            amounts[key] = amounts.get(key, 0.0) + half
    if not amounts:
        return TurningLoads.empty(mesh.n_dofs)
    keys = sorted(amounts)
    nodes = np.array([k[0] for k in keys], dtype=np.int64)
    values = [np.array([amounts[k]]) for k in keys]
    return TurningLoads(
        node=nodes,
        phase=np.array([phi[k[1]] for k in keys]),
        speed_squared=np.ones(len(keys), dtype=bool),
        force_y=_columns(mesh.n_dofs, [np.array([dof(n, V)]) for n in nodes], values),
        force_z=_columns(mesh.n_dofs, [np.array([dof(n, W)]) for n in nodes], values),
    )


def bow_shape(x, amplitude: float, start: float, end: float) -> tuple[np.ndarray, np.ndarray]:
    """``(b, b')`` of the bump ``a sin²(π (x − x₀)/(x₁ − x₀))`` on [x₀, x₁], 0 elsewhere [m, -]."""
    x = np.asarray(x, dtype=float)
    length = end - start
    inside = (x >= start) & (x <= end)
    phase = math.pi * (x - start) / length
    b = np.where(inside, amplitude * np.sin(phase) ** 2, 0.0)
    slope = np.where(inside, amplitude * math.pi / length * np.sin(2.0 * phase), 0.0)
    return b, slope


def bow_loads(mesh: Mesh, elastic_stiffness: sp.spmatrix, amplitude: float, start: float, end: float,
              angle: float = 0.0) -> TurningLoads:
    """Load ``K q_b`` of a stress-free bow turning with the string (module docstring).

    Args:
        elastic_stiffness: K of the beam elements (global, no stabilizers, no prestress).
        amplitude: a [m], the largest offset of the bow; start, end: x₀ < x₁ [m], where it lies.
        angle: φ [rad], the direction of the bow from y at θx = 0.
    """
    if not (math.isfinite(amplitude) and amplitude >= 0.0):
        raise ValueError(f"bow amplitude = {amplitude!r} m: must be finite and >= 0")
    if amplitude == 0.0:
        return TurningLoads.empty(mesh.n_dofs)
    if not (0.0 <= start < end <= mesh.length + 1e-9):
        raise ValueError(f"bow from {start!r} to {end!r} m: need 0 <= start < end <= {mesh.length:g} m")
    b, slope = bow_shape(mesh.nodes, amplitude, start, end)
    nodes = np.nonzero((b != 0.0) | (slope != 0.0))[0]
    k = sp.csc_matrix(elastic_stiffness)
    columns_y, columns_z = [], []
    for node in nodes:
        q_y = np.zeros(mesh.n_dofs)
        q_y[dof(node, V)] = b[node]
        q_y[dof(node, THETA_Z)] = slope[node]  # θz = ∂v/∂x
        q_z = np.zeros(mesh.n_dofs)
        q_z[dof(node, W)] = b[node]
        q_z[dof(node, THETA_Y)] = -slope[node]  # θy = −∂w/∂x
        columns_y.append(k @ q_y)
        columns_z.append(k @ q_z)
    if not len(nodes):
        return TurningLoads.empty(mesh.n_dofs)
    return TurningLoads(
        node=nodes.astype(np.int64),
        phase=np.full(len(nodes), float(angle)),
        speed_squared=np.zeros(len(nodes), dtype=bool),
        force_y=sp.csc_matrix(np.column_stack(columns_y)),
        force_z=sp.csc_matrix(np.column_stack(columns_z)),
    )
