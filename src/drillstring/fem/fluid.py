"""Drilling-fluid (mud) element matrices: a pipe conveying fluid inside a confining annulus.

Model (docs/model.md §4), after Païdoussis, *Fluid–Structure Interactions: Slender Structures and Axial Flow*,
vol. 1 (2nd ed., 2014), ch. 3–4, and Païdoussis, Luu & Prabhakar, J. Fluids Struct. 24 (2008) 111–128
(tubular cantilevers conveying fluid with annular backflow), as used by Ritto, Soize & Sampaio (2009).
Mud flows **down** the bore at ``U_i`` and returns **up** the annulus at ``U_o``; for a volume flow
``Q`` continuity gives, section by section, ``U_i = Q / A_i`` and ``U_o = Q / (A_ch − A_o)``.

Lateral terms (one bending plane; the other follows by symmetry), per unit length:

- added mass ``m_f = ρ_f A_i + χ ρ_f A_o`` with the confinement factor
  ``χ = (D_ch² + D_o²)/(D_ch² − D_o²)`` -> ``[M_f] = m_f ∫ N_vᵀ N_v dx``;
- Coriolis ``c_cor = 2 ρ_f (A_i U_i − χ A_o U_o)`` -> ``c_cor ∫ N_vᵀ N_v' dx`` (non-symmetric);
- viscous damping ``c_v = ½ C_f ρ_f D_o U_o + k`` -> ``c_v ∫ N_vᵀ N_v dx``; both go to ``[C_f]``;
- centrifugal ``p = ρ_f A_i U_i² + χ ρ_f A_o U_o²`` acting as a compressive axial force
  -> ``[K_f] = −p ∫ N_v'ᵀ N_v' dx``.

Axial loads (optional): the skin friction of the two flows on the pipe walls,
``f_x = ½ C_f ρ_f π (D_i U_i² − D_o U_o²)`` [N/m] along +x (the bore flow drags the pipe down, the
annular flow drags it up). When enabled they enter the static state and so, through ``N(x)``, the
geometric stiffness: this is how the annular-friction stiffness terms of Païdoussis' model are
represented. Pressure resultants at the bit nozzles and at section changes are not modelled.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drillstring.derived import flow_velocities, fluid_skin_friction
from drillstring.fem.element import _frozen, _integrate, planar_shapes, shear_parameter
from drillstring.fem.sections import BeamSection


@dataclass(frozen=True)
class FluidCoefficients:
    """Per-unit-length fluid coefficients of one section (SI)."""

    inner_velocity: float  # U_i [m/s], down the bore
    annular_velocity: float  # U_o [m/s], up the annulus
    confinement: float  # χ [-]
    added_mass: float  # m_f [kg/m]
    coriolis: float  # c_cor [kg/s]
    viscous: float  # c_v [N·s/m²]
    centrifugal: float  # p [N]
    axial_load: float  # f_x [N/m], along +x


def fluid_coefficients(
    section: BeamSection,
    borehole_diameter: float,
    fluid_density: float,
    flow_rate: float,
    friction_coefficient: float,
    viscous_coefficient: float,
    *,
    added_mass: bool = True,
    coriolis: bool = True,
    viscous_damping: bool = True,
    centrifugal: bool = True,
    axial_loads: bool = False,
) -> FluidCoefficients:
    """Coefficients of the fluid terms for one section; a switched-off term is 0.

    Args:
        section: the tube.
        borehole_diameter: D_ch [m], larger than the tube's outer diameter.
        fluid_density: ρ_f [kg/m³].
        flow_rate: Q [m³/s], the mud volume flow.
        friction_coefficient: C_f [-].
        viscous_coefficient: k [N·s/m²].
    """
    d_ch, d_o, d_i = borehole_diameter, section.outer_diameter, section.inner_diameter
    if not d_ch > d_o:
        raise ValueError(
            f"borehole diameter {d_ch!r} m must exceed the outer diameter {d_o!r} m of the string"
        )
    u_i, u_o = flow_velocities(d_o, d_i, d_ch, flow_rate)
    chi = (d_ch**2 + d_o**2) / (d_ch**2 - d_o**2)
    rho, a_i, a_o = fluid_density, section.inner_area, section.outer_area
    return FluidCoefficients(
        inner_velocity=u_i,
        annular_velocity=u_o,
        confinement=chi,
        added_mass=(rho * a_i + chi * rho * a_o) if added_mass else 0.0,
        coriolis=2.0 * rho * (a_i * u_i - chi * a_o * u_o) if coriolis else 0.0,
        viscous=(0.5 * friction_coefficient * rho * d_o * u_o + viscous_coefficient)
        if viscous_damping
        else 0.0,
        centrifugal=(rho * a_i * u_i**2 + chi * rho * a_o * u_o**2) if centrifugal else 0.0,
        axial_load=fluid_skin_friction(d_o, d_i, d_ch, rho, flow_rate, friction_coefficient)
        if axial_loads
        else 0.0,
    )


@_frozen
def fluid_planar_matrices(
    section: BeamSection, length: float, coefficients: FluidCoefficients
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Planar (4×4, DOFs v1, ψ1, v2, ψ2) fluid mass, damping and stiffness of one element.

    Returns ``(M_f, C_f, K_f)`` with ``M_f = m_f ∫N_vᵀN_v``, ``C_f = c_cor ∫N_vᵀN_v' + c_v ∫N_vᵀN_v``,
    ``K_f = −p ∫N_v'ᵀN_v'`` (module docstring).
    """
    s = planar_shapes(length, shear_parameter(section, length))
    nn = _integrate(s.weights, s.displacement, s.displacement)
    n_dn = _integrate(s.weights, s.displacement, s.slope)
    dn_dn = _integrate(s.weights, s.slope, s.slope)
    c = coefficients
    return c.added_mass * nn, c.coriolis * n_dn + c.viscous * nn, -c.centrifugal * dn_dn
