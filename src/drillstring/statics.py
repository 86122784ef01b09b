"""The prestressed static state of the hanging string (docs/model.md §3).

The string hangs from the hook (top axial DOF held), carries its weight, and rests on the bit with the
weight-on-bit ``wob`` (a concentrated upward force at the bit). Solving ``[K] q_S = f_g + f_c`` gives the
axial displacement, the axial force ``N(x)`` (tension positive: tension at the top, ``−wob`` at the bit),
and the hook reaction, the weight-on-hook ``woh = ∫ q dx − wob`` (``q`` the axial load per length).
Only axial DOFs are loaded in a vertical well, so only the axial sub-problem is solved. A weight-on-bit
above the string's weight (always so with gravity off) makes the hook push: ``woh < 0``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import math

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from drillstring.derived import string_axial_load
from drillstring.fem.assembly import U, dof, distributed_axial_load
from drillstring.fem.element import axial_matrices
from drillstring.fem.mesh import Mesh


@dataclass(frozen=True)
class StaticState:
    """Result of the static analysis (SI units).

    Attributes:
        mesh: the mesh.
        displacement: q_S, all 6 DOFs per node (only axial ones nonzero) [m].
        axial_force: N at each node [N], tension positive; linear inside each element.
        weight: total axial load ∫ q dx [N] (the string's weight, buoyed if requested, plus the fluid's
            skin friction if switched on; :func:`drillstring.derived.string_axial_load`, as ``Case.weight``).
        weight_on_hook: hook reaction [N], weight − weight_on_bit; negative when the hook pushes.
        weight_on_bit: bit reaction [N].
    """

    mesh: Mesh
    displacement: np.ndarray
    axial_force: np.ndarray
    weight: float
    weight_on_hook: float
    weight_on_bit: float

    @property
    def neutral_point(self) -> float:
        """Position x [m] where N changes sign (linear interpolation); nan if N keeps one sign."""
        n, x = self.axial_force, self.mesh.nodes
        crossing = np.nonzero((n[:-1] > 0) & (n[1:] <= 0))[0]
        if len(crossing) == 0:
            return float("nan")
        i = crossing[-1]
        return float(x[i] + (x[i + 1] - x[i]) * n[i] / (n[i] - n[i + 1]))

    @property
    def neutral_point_height(self) -> float:
        """Height of the neutral point above the bit, L − x_neutral [m]."""
        return self.mesh.length - self.neutral_point


def solve_statics(
    mesh: Mesh, load_per_length: Sequence[float], weight_on_bit: float
) -> StaticState:
    """Static equilibrium of the hanging string.

    Args:
        mesh: the mesh.
        load_per_length: distributed axial load q of each mesh section [N/m], along +x (down).
        weight_on_bit: the bit's upward reaction [N], >= 0. It may exceed the string's weight: the hook
            then pushes (negative weight-on-hook), as it must with gravity off.
    """
    load_per_length = np.asarray(load_per_length, dtype=float)
    lengths = mesh.element_lengths
    element_load = load_per_length[mesh.element_section] * lengths
    weight = string_axial_load(load_per_length[mesh.element_section], lengths)
    if not (math.isfinite(weight_on_bit) and weight_on_bit >= 0.0):
        raise ValueError(f"weight_on_bit = {weight_on_bit!r} N: must be a finite number >= 0")
    n = mesh.n_nodes
    # Axial sub-problem: tridiagonal stiffness on the nodal u; consistent loads; top node held.
    diag, off = np.zeros(n), np.zeros(n - 1)
    for e, (section, h) in enumerate(zip(mesh.element_sections(), lengths)):
        k = axial_matrices(section, h)[0]
        diag[e] += k[0, 0]
        diag[e + 1] += k[1, 1]
        off[e] += k[0, 1]
    k_axial = sp.diags([off, diag, off], [-1, 0, 1], format="csc")
    f = distributed_axial_load(mesh, load_per_length)[dof(np.arange(n), U)]
    f[-1] -= weight_on_bit
    u = np.zeros(n)
    u[1:] = spla.spsolve(k_axial[1:, 1:], f[1:])
    residual = k_axial @ u - f  # reaction forces: only the hook's is nonzero
    weight_on_hook = -float(residual[0])

    # Axial force at the nodes from each element's end forces (exact for the 1-D bar).
    axial_force = np.zeros(n)
    for e, (section, h) in enumerate(zip(mesh.element_sections(), lengths)):
        k = axial_matrices(section, h)[0]
        end_forces = k @ u[e : e + 2] - 0.5 * element_load[e]
        axial_force[e] = -end_forces[0]
        axial_force[e + 1] = end_forces[1]
    displacement = np.zeros(mesh.n_dofs)
    displacement[dof(np.arange(n), U)] = u
    return StaticState(mesh, displacement, axial_force, weight, weight_on_hook, weight_on_bit)


def case_static_state(case, weight_on_bit: float | None = None, mesh: Mesh | None = None) -> StaticState:
    """Static state of a :class:`~drillstring.case.Case` (``weight_on_bit`` [N] overrides the case's; off
    bottom, ``bit_rock.law = "off_bottom"``, it is 0 whatever is given: the hook carries the whole string)."""
    from drillstring.fem.build import axial_load_per_length, case_mesh

    mesh = case_mesh(case) if mesh is None else mesh
    wob = case.operation.weight_on_bit if weight_on_bit is None else weight_on_bit
    if case.bit_rock.law == "off_bottom":
        wob = 0.0
    return solve_statics(mesh, axial_load_per_length(case, mesh), wob)
