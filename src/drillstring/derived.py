"""Quantities derived from a case's plain numbers, needed both to validate a case and to build the model.

Validating a case (:mod:`drillstring.case`) needs a few numbers that the finite-element model also
builds on: where the mesh puts its nodes, how many DOFs each mode family has, and the distributed axial
load on the string (its weight, buoyed or not, plus the drilling fluid's skin friction); and the dogleg of
each survey course, which the well path (:mod:`drillstring.well.survey`) also builds on. Each is computed
here, once; :mod:`drillstring.case`, :mod:`drillstring.fem` and :mod:`drillstring.well` call these
functions, so the case's ``weight`` and the statics' weight, or the case's mode limits and the mesh, cannot
disagree.

Pure functions of numbers, SI units; this module imports nothing from the rest of ``drillstring``, and NumPy
only inside :func:`dogleg` (reading a case does not load it).
"""

from __future__ import annotations

import itertools
import math
from typing import Sequence

#: Two mesh break points closer than this [m] are the same node.
POSITION_TOLERANCE = 1e-9


# ---------------------------------------------------------------------------------------------------------
# Mesh layout (used by drillstring.fem.mesh.build_mesh)
# ---------------------------------------------------------------------------------------------------------


def mesh_breaks(section_lengths: Sequence[float], extra_points: Sequence[float] = ()) -> list[float]:
    """Positions x [m] that must be nodes, sorted, from 0 to the string length: the section ends and the
    ``extra_points`` (stabilizers, probes; clipped to the string), points closer than
    :data:`POSITION_TOLERANCE` merged."""
    boundaries = [0.0, *itertools.accumulate(float(length) for length in section_lengths)]
    total = boundaries[-1]
    points = sorted(set(boundaries) | {min(max(float(x), 0.0), total) for x in extra_points})
    breaks = [points[0]] + [x for previous, x in zip(points[:-1], points[1:])
                            if x - previous > POSITION_TOLERANCE]
    breaks[-1] = total
    return breaks


def element_counts(breaks: Sequence[float], max_element_length: float) -> list[int]:
    """Number of equal elements, each no longer than ``max_element_length`` [m], between consecutive
    break points (at least one)."""
    return [max(1, math.ceil((end - start) / max_element_length - 1e-9))
            for start, end in zip(breaks[:-1], breaks[1:])]


def family_nodes(n_nodes: int, top_free: bool = False) -> dict[str, tuple[tuple[str, range], ...]]:
    """The dynamic boundary conditions of the mode families of a mesh of ``n_nodes`` nodes (0 at the top),
    written once: for each family (``axial``, ``torsional``, ``lateral_y``, ``lateral_z``), the nodal DOF
    kinds it holds (``u``, ``v``, ``w``, ``theta_x``, ``theta_y``, ``theta_z``) and the nodes where each is
    free. Axial ``u`` at every node (both ends free; one of them the rigid translation); torsional ``θx``
    below the top (held), or at every node with ``top_free`` (a top drive; one of them the rigid rotation);
    lateral per plane ``v`` (``w``) at the inner nodes (ends pinned) and ``θz`` (``θy``) at every node.
    :func:`drillstring.modal.family_dofs` numbers these DOFs; :func:`mode_family_sizes` counts them."""
    every = range(n_nodes)
    inner = range(1, n_nodes - 1)
    return {"axial": (("u", every),),
            "torsional": (("theta_x", every if top_free else range(1, n_nodes)),),
            "lateral_y": (("v", inner), ("theta_z", every)),
            "lateral_z": (("w", inner), ("theta_y", every))}


def mode_family_sizes(n_nodes: int, top_free: bool = False) -> dict[str, int]:
    """DOFs of each mode family of a mesh of ``n_nodes`` nodes (the most modes a family can have), counted
    from :func:`family_nodes`: ``axial``, ``torsional`` and ``lateral`` (per plane)."""
    counts = {family: sum(len(nodes) for _, nodes in kinds)
              for family, kinds in family_nodes(n_nodes, top_free).items()}
    return {"axial": counts["axial"], "torsional": counts["torsional"], "lateral": counts["lateral_y"]}


# ---------------------------------------------------------------------------------------------------------
# Distributed axial load (used by drillstring.case.Case.weight and the statics)
# ---------------------------------------------------------------------------------------------------------


def circle_area(diameter: float) -> float:
    """π D² / 4 [m²]."""
    return math.pi * diameter**2 / 4.0


def flow_velocities(outer_diameter: float, inner_diameter: float, borehole_diameter: float,
                    flow_rate: float) -> tuple[float, float]:
    """Mean mud velocities [m/s] of a section for the volume flow ``flow_rate`` Q [m³/s]: ``U_i = Q / A_i``
    down the bore (0 for a solid section) and ``U_o = Q / (A_ch − A_o)`` up the annulus (continuity)."""
    inner = circle_area(inner_diameter)
    u_i = flow_rate / inner if inner > 0 else 0.0
    u_o = flow_rate / (circle_area(borehole_diameter) - circle_area(outer_diameter))
    return u_i, u_o


def fluid_skin_friction(outer_diameter: float, inner_diameter: float, borehole_diameter: float,
                        fluid_density: float, flow_rate: float, friction_coefficient: float) -> float:
    """Axial skin-friction load of the mud on a section [N/m] along +x (down):
    ``f_x = ½ C_f ρ_f π (D_i U_i² − D_o U_o²)`` — the bore flow drags the pipe down, the annular flow up
    (Païdoussis, *Fluid–Structure Interactions* vol. 1, 2nd ed., 2014, ch. 4; see
    :mod:`drillstring.fem.fluid`)."""
    u_i, u_o = flow_velocities(outer_diameter, inner_diameter, borehole_diameter, flow_rate)
    return 0.5 * friction_coefficient * fluid_density * math.pi * (
        inner_diameter * u_i**2 - outer_diameter * u_o**2)


def axial_load_per_length(*, steel_density: float, area: float, gravity: float, buoyancy_density: float,
                          skin_friction: float, solid_area: float | None = None) -> float:
    """Distributed axial load on a section [N/m] along +x (down): its buoyed weight ``(ρ A − ρ_b A_s) g``
    (Archimedes: the fluid displaced is the steel's volume ``A_s`` per length, ``area`` unless tool joints
    smeared over the section add steel outside it), with ``ρ_b`` the fluid density when buoyancy is on
    (else 0) and ``g`` 0 when gravity is off, plus the fluid's skin friction (0 when fluid axial loads are
    off). ``ρ A`` is the mass per length."""
    solid = area if solid_area is None else solid_area
    return (steel_density * area - buoyancy_density * solid) * gravity + skin_friction


def string_axial_load(loads_per_length: Sequence[float], lengths: Sequence[float]) -> float:
    """Total distributed axial load on the string [N], ``Σ q_i L_i``: the string's weight (plus the
    fluid's skin friction when switched on), which the hook and the bit carry together."""
    return math.fsum(q * length for q, length in zip(loads_per_length, lengths))


# ---------------------------------------------------------------------------------------------------------
# Survey courses (used by drillstring.case.survey_input and drillstring.well.survey)
# ---------------------------------------------------------------------------------------------------------


def dogleg(inc1, azi1, inc2, azi2):
    """Dogleg angle beta [rad] between two directions, eq. (2) of :mod:`drillstring.well.survey` (haversine
    with atan2)."""
    import numpy as np

    inc1, inc2 = np.asarray(inc1, dtype=float), np.asarray(inc2, dtype=float)
    h = np.sin((inc2 - inc1) / 2.0) ** 2 + np.sin(inc1) * np.sin(inc2) * np.sin(
        (np.asarray(azi2, dtype=float) - np.asarray(azi1, dtype=float)) / 2.0) ** 2
    h = np.clip(h, 0.0, 1.0)
    return 2.0 * np.arctan2(np.sqrt(h), np.sqrt(1.0 - h))
