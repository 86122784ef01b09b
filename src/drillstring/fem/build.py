"""From a drilling case to finite-element ingredients (sections, mesh, fluid coefficients, loads).

This is the only module of :mod:`drillstring.fem` that reads a :class:`~drillstring.case.Case`; the
element and assembly functions take plain numbers and small dataclasses.
"""

from __future__ import annotations

import numpy as np

from drillstring.case import Case
from drillstring.fem.assembly import Stabilizer
from drillstring.fem.fluid import FluidCoefficients, fluid_coefficients
from drillstring.fem.mesh import Mesh, build_mesh
from drillstring.fem.sections import BeamSection, hollow_circle


def beam_sections(case: Case) -> list[BeamSection]:
    """One :class:`BeamSection` per case section, top to bottom."""
    out = []
    for s in case.sections:
        material = case.materials[s.material]
        out.append(
            hollow_circle(
                s.outer_diameter,
                s.inner_diameter,
                material.young_modulus,
                material.density,
                material.poisson_ratio,
                s.shear_factor,
            )
        )
    return out


def mesh_points(case: Case) -> list[float]:
    """Positions [m] that must be nodes: stabilizers and output probes."""
    return [s.position for s in case.stabilizers] + list(case.mesh.probes)


def case_mesh(case: Case, max_element_length: float | None = None) -> Mesh:
    """The case's mesh (``max_element_length`` overrides the case's mesh setting) [m]."""
    return build_mesh(
        [s.length for s in case.sections],
        beam_sections(case),
        case.mesh.max_element_length if max_element_length is None else max_element_length,
        mesh_points(case),
    )


def stabilizers(case: Case) -> list[Stabilizer]:
    return [Stabilizer(s.position, s.stiffness) for s in case.stabilizers]


def flow_rate(case: Case) -> float:
    """Mud volume flow Q = U_i A_i of the top section [m³/s] (U_i is the inlet velocity)."""
    return case.flow_rate


def section_fluid_coefficients(case: Case, mesh: Mesh) -> list[FluidCoefficients]:
    """Fluid coefficients of each section (switched-off terms are zero)."""
    f = case.fluid
    return [
        fluid_coefficients(
            section,
            case.borehole.diameter,
            f.density,
            flow_rate(case),
            f.friction_coefficient,
            f.viscous_coefficient,
            added_mass=f.added_mass,
            coriolis=f.coriolis,
            viscous_damping=f.viscous_damping,
            centrifugal=f.centrifugal,
            axial_loads=f.axial_loads,
        )
        for section in mesh.sections
    ]


def axial_load_per_length(case: Case, mesh: Mesh) -> np.ndarray:
    """Distributed axial load of each mesh section [N/m] along +x: weight (buoyed if switched on) plus
    the fluid skin-friction load when ``fluid.axial_loads`` is on — the case's own
    :attr:`~drillstring.case.Case.axial_load_per_length`, so the statics and ``Case.weight`` agree."""
    loads = np.array(case.axial_load_per_length)
    if len(loads) != len(mesh.sections):
        raise ValueError(f"the mesh has {len(mesh.sections)} sections, the case {len(loads)}")
    return loads
