"""Hollow circular cross-sections of drill pipes and drill collars.

All quantities are SI: diameters in m, areas in m², second moments in m⁴, moduli in Pa,
densities in kg/m³.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class BeamSection:
    """Material and geometry of a hollow circular section (one tube of the string).

    Attributes:
        outer_diameter: D_o [m].
        inner_diameter: D_i [m] (0 for a solid bar).
        young_modulus: E [Pa].
        shear_modulus: G [Pa].
        density: ρ [kg/m³].
        shear_factor: Timoshenko shear coefficient k_s [-] (6/7 for thin tubes in the reference study).
    """

    outer_diameter: float
    inner_diameter: float
    young_modulus: float
    shear_modulus: float
    density: float
    shear_factor: float

    def __post_init__(self) -> None:
        if not self.outer_diameter > 0:
            raise ValueError(f"outer_diameter = {self.outer_diameter!r}: must be > 0 m")
        if not 0 <= self.inner_diameter < self.outer_diameter:
            raise ValueError(
                f"inner_diameter = {self.inner_diameter!r}: must be in [0, outer_diameter = "
                f"{self.outer_diameter!r}) m"
            )
        for name in ("young_modulus", "shear_modulus", "density", "shear_factor"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} = {getattr(self, name)!r}: must be > 0")

    @property
    def area(self) -> float:
        """Steel area A = π (D_o² − D_i²)/4 [m²]."""
        return math.pi * (self.outer_diameter**2 - self.inner_diameter**2) / 4.0

    @property
    def inner_area(self) -> float:
        """Bore area A_i = π D_i²/4 [m²] (where the mud flows down)."""
        return math.pi * self.inner_diameter**2 / 4.0

    @property
    def outer_area(self) -> float:
        """Area enclosed by the outer surface A_o = π D_o²/4 [m²]."""
        return math.pi * self.outer_diameter**2 / 4.0

    @property
    def second_moment(self) -> float:
        """Bending second moment of area I = π (D_o⁴ − D_i⁴)/64 [m⁴]."""
        return math.pi * (self.outer_diameter**4 - self.inner_diameter**4) / 64.0

    @property
    def polar_moment(self) -> float:
        """Polar moment I_p = 2 I [m⁴] (torsion constant of a circular tube)."""
        return 2.0 * self.second_moment

    @property
    def axial_stiffness(self) -> float:
        """EA [N]."""
        return self.young_modulus * self.area

    @property
    def bending_stiffness(self) -> float:
        """EI [N·m²]."""
        return self.young_modulus * self.second_moment

    @property
    def torsional_stiffness(self) -> float:
        """G I_p [N·m²]."""
        return self.shear_modulus * self.polar_moment

    @property
    def shear_stiffness(self) -> float:
        """k_s G A [N]."""
        return self.shear_factor * self.shear_modulus * self.area

    @property
    def mass_per_length(self) -> float:
        """ρA [kg/m]."""
        return self.density * self.area


def hollow_circle(
    outer_diameter: float,
    inner_diameter: float,
    young_modulus: float,
    density: float,
    poisson_ratio: float,
    shear_factor: float = 6.0 / 7.0,
) -> BeamSection:
    """Build a :class:`BeamSection` of an isotropic tube; G = E / (2 (1 + ν))."""
    if not 0.0 < poisson_ratio < 0.5:
        raise ValueError(f"poisson_ratio = {poisson_ratio!r}: must be in (0, 0.5)")
    return BeamSection(
        outer_diameter=outer_diameter,
        inner_diameter=inner_diameter,
        young_modulus=young_modulus,
        shear_modulus=young_modulus / (2.0 * (1.0 + poisson_ratio)),
        density=density,
        shear_factor=shear_factor,
    )
