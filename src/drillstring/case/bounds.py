"""The limits of a case: the plausible physical range of the values whose extremes break the computation
(:data:`PHYSICAL_BOUNDS`), the largest mesh, and the size of what is read (names, files, nesting).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from pydantic import BaseModel


#: Most finite elements a case may have (a mesh finer than this is refused at validation; 10 000 elements is
#: 0.16 m for the 1600 m reference string, 1 m for a 10 km string, whose sparse set-up takes about 450 MiB).
MAX_ELEMENTS = 10_000


#: Plausible physical ranges [SI] of the values whose extremes overflow, underflow or make the integration
#: degenerate (a product of a length and a modulus beyond 1.8e308, a division by a subnormal a2 or atol):
#: path (``*``: every item of a list or table), lowest, highest, SI unit. Checked before any other rule.
PHYSICAL_BOUNDS: tuple[tuple[tuple[str, ...], float, float, str], ...] = (
    (("materials", "*", "young_modulus"), 1e6, 1e13, "Pa"),
    (("materials", "*", "density"), 1.0, 1e5, "kg/m3"),
    (("sections", "*", "length"), 1e-3, 1e5, "m"),
    (("sections", "*", "outer_diameter"), 1e-3, 10.0, "m"),
    (("sections", "*", "inner_diameter"), 0.0, 10.0, "m"),
    (("borehole", "diameter"), 1e-3, 10.0, "m"),
    (("stabilizers", "*", "stiffness"), 0.0, 1e15, "N/m"),
    (("fluid", "density"), 0.0, 1e5, "kg/m3"),
    (("fluid", "inlet_velocity"), 0.0, 1e3, "m/s"),
    (("fluid", "friction_coefficient"), 0.0, 10.0, ""),
    (("fluid", "viscous_coefficient"), 0.0, 1e9, "N*s/m2"),
    (("bit_rock", "a1"), 0.0, 10.0, "m/s"),
    (("bit_rock", "a2"), 1e-15, 1e-3, "m/(N*s)"),
    (("bit_rock", "a3"), 0.0, 1.0, "m/rad"),
    (("bit_rock", "a4"), 0.0, 1e12, "N*rad"),
    (("bit_rock", "a5"), 0.0, 1e9, "N*m"),
    (("bit_rock", "regularization"), 1e-6, 1e3, "rad/s"),
    (("bit_rock", "stick_stiffening_limit"), 1.0, 1e6, ""),
    (("bit_rock", "bit_radius"), 1e-3, 10.0, "m"),
    # Detournay: rocks from chalk to granite have eps of 10-400 MPa and zeta of 0.4-1 (Detournay, Richard &
    # Shepherd 2008); zeta -> 0 or eps -> 0 makes the depth of cut per turn (W - a sigma l)/(a zeta eps n)
    # unbounded (a steady ROP of 4.7e9 m/h at zeta = 0).
    (("bit_rock", "intrinsic_specific_energy"), 1e6, 1e12, "Pa"),
    (("bit_rock", "cutting_inclination"), 0.1, 10.0, ""),
    (("bit_rock", "contact_stress"), 0.0, 1e12, "Pa"),
    (("bit_rock", "wear_flat_length"), 0.0, 10.0, "m"),
    (("bit_rock", "friction_coefficient"), 0.0, 10.0, ""),
    (("bit_rock", "bit_geometry"), 0.0, 10.0, ""),
    (("bit_rock", "contact_velocity"), 1e-9, 1e3, "m/s"),
    (("bit_rock", "friction_speed"), 1e-9, 1e3, "rad/s"),
    (("contact", "shock_stiffness"), 0.0, 1e15, "N/m2"),
    (("contact", "friction_coefficient"), 0.0, 10.0, ""),
    (("contact", "speed_regularization"), 1e-6, 1e3, "rad/s"),
    (("operation", "top_speed"), 1e-3, 1e3, "rad/s"),  # 0.01 rpm at least (1/Z² of the bit law grows as 1/speed²)
    (("operation", "weight_on_bit"), 0.0, 1e9, "N"),
    (("damping", "rigid_axial"), 0.0, 1e12, "N*s/m"),
    (("damping", "rigid_rotation"), 0.0, 1e12, "N*m*s/rad"),
    (("environment", "gravity"), 0.0, 100.0, "m/s2"),
    (("well", "casing_shoe"), 0.0, 1e5, "m"),
    (("well", "casing_inner_diameter"), 1e-3, 10.0, "m"),
    (("well", "torque_on_bit"), 0.0, 1e6, "N*m"),  # top drives deliver up to about 150 kN*m
    (("well", "inner_fluid_density"), 0.0, 1e5, "kg/m3"),
    (("well", "tool_joints", "*"), 1e-3, 10.0, "m"),
    (("sections", "*", "eccentricity_angle"), -1e4, 1e4, "rad"),
    (("bow", "angle"), -1e4, 1e4, "rad"),
    (("top_drive", "inertia"), 1e-3, 1e9, "kg*m2"),
    (("top_drive", "proportional_gain"), 0.0, 1e12, "N*m*s/rad"),
    (("top_drive", "integral_gain"), 0.0, 1e12, "N*m/rad"),
    (("top_drive", "max_torque"), 1.0, 1e9, "N*m"),
    (("top_drive", "ramp_time"), 0.0, 1e5, "s"),
    (("top_drive", "filter_frequency"), 1e-6, 1e6, "rad/s"),
    (("simulation", "t_end"), 1e-9, 1e7, "s"),
    (("simulation", "rtol"), 1e-14, 1.0, ""),
    (("simulation", "atol"), 1e-20, 1e3, ""),
    (("simulation", "min_step"), 1e-20, 1.0, "s"),
)


def _bound_problems(case: BaseModel) -> list[tuple[tuple[str | int, ...], Any, str]]:
    """Every value of ``case`` outside its :data:`PHYSICAL_BOUNDS` range, as cross-field problems."""
    problems: list[tuple[tuple[str | int, ...], Any, str]] = []

    def visit(node: Any, rest: tuple[str, ...], loc: tuple[str | int, ...], low: float, high: float,
              unit: str) -> None:
        if node is None:  # an optional table or key left out
            return
        if not rest:
            if isinstance(node, float) and not low <= node <= high:
                overflow = " (it overflows to infinity)" if math.isinf(node) else ""
                problems.append((loc, node, f"must be within [{low:g}, {high:g}] {unit}".rstrip() + overflow))
            return
        key, rest = rest[0], rest[1:]
        if key != "*":
            visit(getattr(node, key), rest, loc + (key,), low, high, unit)
        elif isinstance(node, Mapping):
            for name, item in node.items():
                visit(item, rest, loc + (name,), low, high, unit)
        else:
            for i, item in enumerate(node):
                visit(item, rest, loc + (i,), low, high, unit)

    for path, low, high, unit in PHYSICAL_BOUNDS:
        visit(case, path, (), low, high, unit)
    return problems


#: Longest case name and description [characters] (they are titles and table cells, not documents).
MAX_NAME_LENGTH, MAX_DESCRIPTION_LENGTH = 200, 2000
#: Largest case file read [bytes]: the annotated reference case is 14 kB.
MAX_CASE_FILE_BYTES = 1_000_000
#: Deepest nesting of tables and arrays in a case (the format needs 4: uncertainty.correlation.matrix rows).
MAX_CASE_DEPTH = 16
