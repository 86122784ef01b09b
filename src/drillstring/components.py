"""Strings from components: a drill-string described as engineers list it, expanded into model sections.

A case may describe its string by a ``[[components]]`` list instead of ``[[sections]]``: from the top to the
bit, each component a drill pipe, heavy-weight drill pipe, drill collar, MWD, motor, stabilizer or bit, with its
length and its outer and inner diameter or its weight per length (the fields are validated, units and all, by
:class:`drillstring.case.Component`). :func:`expand` turns the list into what the model is made of:

- a ``motor`` entry with motor keys (flow rate, displacement, stall torque, efficiencies:
  :class:`drillstring.case.MotorKeys`) is also a downhole motor: ``Expansion.motor``, the case's ``[motor]``,
  its rotor station at the motor's bottom (the string below turns with the rotor, :mod:`drillstring.forces.motor`);
- every component but a zero-length stabilizer becomes one section (a hollow circular tube), in order, named
  after the component (``name``, else its type: ``"drill pipe"``, ``"drill collar"``, ...);
- every stabilizer becomes a lateral spring (``stiffness``) at the middle of its length, or, with no length, at
  the joint between its neighbours; its blade diameter is checked against the borehole (at most its diameter)
  but does not enter the model, whose stabilizers are springs without clearance (model §2);
- the section's stiffness (EA, EI, GJ, shear) is that of the tube of the given diameters; its mass per length
  is, in this order: ``weight_per_length`` when given together with ``inner_diameter`` (the pipe's nominal
  linear mass); else the tube's, ρ π (D_o² − D_i²)/4, where ``weight_per_length`` given without
  ``inner_diameter`` sets the bore, D_i = sqrt(D_o² − 4 w / (π ρ)) (the plain tube of that mass);
- tool joints (drill pipe, heavy-weight pipe) are *smeared*: the extra steel of a joint, ρ (A_tj − A) ℓ_tj over
  every ``spacing`` of pipe (a joint of pipe, 30 ft by default), is spread along the pipe as added mass per
  length; the joints' stiffness and their larger outer diameter are not modelled (the wall contact sees the
  pipe body's diameter);
- a mass per length other than the tube's is carried by a material of its own, the component's material with
  the density m / A (name ``"<material> (<section name>)"``), so the weight, the inertia (translation and
  rotation) and the imbalance follow the smeared mass, every other property the base material; its
  ``solid_density`` is the base material's, so the mud displaced (buoyancy) is the steel's volume m / ρ,
  tool joints included.

A string written so builds exactly the model of the same string written as sections: the built-in case
``reference_components`` is ``reference`` written as components. Everything here is in SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

__all__ = ["TYPES", "ComponentProblem", "Expansion", "expand"]

#: Component type -> default section name.
TYPES: dict[str, str] = {
    "drill_pipe": "drill pipe",
    "heavy_weight": "heavy-weight drill pipe",
    "collar": "drill collar",
    "mwd": "MWD",
    "motor": "motor",
    "stabilizer": "stabilizer",
    "bit": "bit",
}
#: The keys of a powered motor entry (:class:`drillstring.case.MotorKeys`): given any, the motor entry is also a
#: downhole motor whose rotor turns the string below it (``Expansion.motor``); without, a plain section.
MOTOR_KEYS = ("flow_rate", "displacement", "speed_per_flow", "stall_torque", "max_differential_pressure",
              "volumetric_efficiency", "mechanical_efficiency")
#: Types that may have tool joints.
JOINTED = ("drill_pipe", "heavy_weight")


class ComponentProblem(ValueError):
    """Problems of a component list: ``(location relative to the case, value, message)`` triples."""

    def __init__(self, problems: list[tuple[tuple[str | int, ...], Any, str]]) -> None:
        self.problems = problems
        super().__init__("; ".join(f"{loc}: {message}" for loc, _, message in problems))


@dataclass(frozen=True)
class Expansion:
    """The model's pieces made from a component list: sections, stabilizers and the materials they add
    (plain dictionaries of SI numbers, as a case file writes them)."""

    sections: list[dict[str, Any]]
    stabilizers: list[dict[str, Any]]
    materials: dict[str, dict[str, float]]
    #: the ``[motor]`` table of a powered motor entry (its keys and ``position``, the bottom of the motor:
    #: the string below turns with the rotor), None when there is none
    motor: dict[str, Any] | None = None


def _tube_area(outer: float, inner: float) -> float:
    return math.pi * (outer**2 - inner**2) / 4.0


def expand(components: list[Any], materials: Mapping[str, Any], borehole_diameter: float | None) -> Expansion:
    """Sections, stabilizers and added materials of ``components`` (validated
    :class:`drillstring.case.Component` objects, top to bit); ``materials`` maps a material name to an object
    with ``young_modulus``, ``density`` and ``poisson_ratio`` [SI]. Raises :class:`ComponentProblem` listing
    what cannot be built (an unknown material, a weight per length heavier than a solid bar, a blade diameter
    above the borehole's, a body or tool joint as wide as the hole, a stabilizer of no length at the top of
    the string)."""
    sections: list[dict[str, Any]] = []
    stabilizers: list[dict[str, Any]] = []
    added: dict[str, dict[str, float]] = {}
    problems: list[tuple[tuple[str | int, ...], Any, str]] = []
    motor: dict[str, Any] | None = None
    x = 0.0
    bit = next((i for i, c in enumerate(components) if c.type == "bit"), None)
    if bit is not None and bit != len(components) - 1:
        problems.append((("components", bit, "type"), "bit", "the bit must be the last component"))
    for i, c in enumerate(components):
        where = ("components", i)
        name = c.name or TYPES[c.type]
        if c.type == "stabilizer":
            if c.blade_diameter is not None and borehole_diameter is not None and c.blade_diameter > borehole_diameter:
                problems.append((where + ("blade_diameter",), c.blade_diameter,
                                 f"must be at most the borehole diameter ({borehole_diameter:g} m)"))
            if c.length == 0.0:
                if x == 0.0:
                    problems.append((where + ("length",), c.length,
                                     "a stabilizer of no length must come below another component"))
                stabilizers.append({"position": x, "stiffness": c.stiffness})
                continue
            stabilizers.append({"position": x + c.length / 2.0, "stiffness": c.stiffness})
        material = materials.get(c.material)
        if material is None:
            problems.append((where + ("material",), c.material,
                             f"unknown material; defined: {', '.join(materials) or 'none'}"))
            x += c.length
            continue
        inner = c.inner_diameter
        solid = material.density * _tube_area(c.outer_diameter, 0.0)
        if inner is None:  # the bore of the plain tube of this mass per length
            if c.weight_per_length >= solid:
                problems.append((where + ("weight_per_length",), c.weight_per_length,
                                 f"must be less than a solid bar of outer_diameter {c.outer_diameter:g} m "
                                 f"({solid:.6g} kg/m)"))
                x += c.length
                continue
            inner = math.sqrt(c.outer_diameter**2 - 4.0 * c.weight_per_length / (math.pi * material.density))
            mass = None
        else:
            mass = c.weight_per_length
        area = _tube_area(c.outer_diameter, inner)
        joint = getattr(c, "tool_joint", None)
        if borehole_diameter is not None:  # the pipe body and its tool joints must pass in the hole
            if c.outer_diameter >= borehole_diameter:
                problems.append((where + ("outer_diameter",), c.outer_diameter,
                                 f"must be less than the borehole diameter ({borehole_diameter:g} m)"))
            if joint is not None and joint.outer_diameter >= borehole_diameter:
                problems.append((where + ("tool_joint", "outer_diameter"), joint.outer_diameter,
                                 f"must be less than the borehole diameter ({borehole_diameter:g} m)"))
        if joint is not None:
            joint_inner = inner if joint.inner_diameter is None else joint.inner_diameter
            extra = material.density * (_tube_area(joint.outer_diameter, joint_inner) - area) * joint.length
            mass = (material.density * area if mass is None else mass) + extra / joint.spacing
        section: dict[str, Any] = {"name": name, "length": c.length, "outer_diameter": c.outer_diameter,
                                   "inner_diameter": inner, "material": c.material,
                                   "shear_factor": c.shear_factor}
        if c.eccentricity:
            section.update(eccentricity=c.eccentricity, eccentricity_angle=c.eccentricity_angle)
        if mass is not None and mass != material.density * area:
            smeared = f"{c.material} ({name})"
            if smeared in added or smeared in materials:
                smeared = f"{c.material} ({name}, component {i})"
            added[smeared] = {"young_modulus": material.young_modulus, "density": mass / area,
                              "poisson_ratio": material.poisson_ratio,
                              "solid_density": material.density if material.solid_density is None
                              else material.solid_density}
            section["material"] = smeared
        sections.append(section)
        x += c.length
        powered = [key for key in MOTOR_KEYS if key in c.model_fields_set]
        if c.type == "motor" and powered:
            if motor is not None:
                problems.append((where + ("type",), c.type, "at most one powered motor per string"))
            elif i == len(components) - 1:
                problems.append((where + ("type",), c.type, "a motor must have a component below it (the bit)"))
            motor = {key: getattr(c, key) for key in powered}
            motor["position"] = x
    if problems:
        raise ComponentProblem(problems)
    return Expansion(sections, stabilizers, added, motor)
