"""The tables of a string given by components (``[[components]]``, expanded into sections and stabilizers by
:mod:`drillstring.components`) and of a downhole motor (``[motor]``), with the motor's cross-field rule.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, Literal, Mapping

from pydantic import Field, model_validator

from drillstring.case.base import (
    Angle,
    Dimensionless,
    Length,
    MassPerLength,
    MotorDisplacement,
    MotorSpeedPerFlow,
    Pressure,
    Stiffness,
    Torque,
    Velocity,
    VolumeFlow,
    _Base,
    _RPM,
)
from drillstring.case.errors import _MISSING, CaseError, _Entry, _Problems
from drillstring.case.tables import Material, _ComponentTables, _default_materials
from drillstring.components import MOTOR_KEYS
from drillstring.units import LENGTH, to_si


class ToolJoint(_Base):
    """The tool joints of a drill pipe or heavy-weight pipe, smeared as added mass along it
    (:mod:`drillstring.components`)."""

    outer_diameter: Length = Field(gt=0, description="tool-joint outer diameter [m]")
    inner_diameter: Length | None = Field(
        None, ge=0, description="tool-joint bore [m]; the pipe's by default")
    length: Length = Field(gt=0, description="length of one tool joint (box and pin together) [m]")
    spacing: Length = Field(9.144, gt=0, description="pipe length per tool joint [m]; 30 ft (range 2) by default")

    @model_validator(mode="after")
    def _consistent(self) -> ToolJoint:
        if self.inner_diameter is not None and self.inner_diameter >= self.outer_diameter:
            raise _Problems([(("inner_diameter",), self.inner_diameter,
                              f"must be less than outer_diameter ({self.outer_diameter:g} m)")])
        if self.length >= self.spacing:
            raise _Problems([(("length",), self.length, f"must be less than spacing ({self.spacing:g} m)")])
        return self


class MotorKeys(_Base):
    """The keys of a downhole positive-displacement (Moineau) motor (:mod:`drillstring.forces.motor`): on the
    ``motor`` entry of ``[[components]]`` or in a ``[motor]`` table (which adds ``position``). The motor's law
    needs its displacement, given as ``displacement`` (volume per revolution, e.g. ``"1.2 gal/rev"``) or
    ``speed_per_flow`` (revolutions per volume, ``"0.83 rev/gal"``), and its stall torque, given as
    ``stall_torque`` (``"9000 ft*lbf"``) or ``max_differential_pressure`` (the pressure drop across the power
    section at stall, ``"900 psi"``). ``flow_rate``: the mud flow through the power section (default: the case's
    pumped flow, ``fluid.flow_rate``; less when a rotor nozzle bypasses part of it)."""

    flow_rate: VolumeFlow | None = Field(
        None, gt=0, description="mud flow through the power section Q [m^3/s]; default the case's flow rate")
    displacement: MotorDisplacement | None = Field(
        None, gt=0, description="volume per radian of the rotor V/(2 pi) [m^3/rad] ('1.2 gal/rev')")
    speed_per_flow: MotorSpeedPerFlow | None = Field(
        None, gt=0, description="rotor turn per volume 2 pi/V [rad/m^3] ('0.83 rev/gal'): the displacement's inverse")
    stall_torque: Torque | None = Field(None, gt=0, description="rotor torque at stall T_s [N*m]")
    max_differential_pressure: Pressure | None = Field(
        None, gt=0, description="differential pressure at stall dp_s [Pa]: T_s = eta_m V dp_s / (2 pi)")
    volumetric_efficiency: Dimensionless = Field(
        1.0, gt=0, le=1, description="eta_v [-]: no-load speed 2 pi eta_v Q / V")
    mechanical_efficiency: Dimensionless = Field(
        1.0, gt=0, le=1, description="eta_m [-]: torque eta_m V dp / (2 pi)")

    #: the keys that make a powered motor (without any of them a ``motor`` component is a plain section)
    LAW_KEYS: ClassVar[tuple[str, ...]] = MOTOR_KEYS

    #: Physical range of each key [SI]: (low, high, unit, what the range spans). Positive-displacement motors run
    #: from 1 11/16 in (about 0.03 gal/rev) to 11 1/4 in (about 15 gal/rev), at 10 to 3000 gpm, their
    #: efficiencies 0.5-0.95 new (a worn one lower); the ranges leave a margin and keep the law's steps finite.
    RANGES: ClassVar[dict[str, tuple[float, float, str, str]]] = {
        "flow_rate": (1e-4, 1.0, "m3/s", "1.6 to 15,900 gpm"),
        "displacement": (1e-6, 0.1, "m3/rad", "0.0017 to 166 gal/rev"),
        "speed_per_flow": (10.0, 1e6, "rad/m3", "0.006 to 600 rev/gal"),
        "stall_torque": (1.0, 1e6, "N*m", "0.74 to 738,000 ft*lbf"),
        "max_differential_pressure": (1e4, 1e9, "Pa", "1.5 to 145,000 psi"),
        "volumetric_efficiency": (0.1, 1.0, "", "10 to 100 %"),
        "mechanical_efficiency": (0.1, 1.0, "", "10 to 100 %"),
    }

    def motor_problems(self) -> list[tuple[tuple[str | int, ...], Any, str]]:
        """Problems of the motor's keys: each within its physical range (:attr:`RANGES`), and taken together
        (one of each pair given)."""
        problems: list[tuple[tuple[str | int, ...], Any, str]] = []
        for key, (low, high, unit, span) in self.RANGES.items():
            value = getattr(self, key)
            if value is not None and not low <= value <= high:
                problems.append(((key,), value, f"must be within [{low:g}, {high:g}] {unit}".rstrip()
                                 + f" ({span}: a downhole motor's range)"))
        for first, second in (("displacement", "speed_per_flow"), ("stall_torque", "max_differential_pressure")):
            a, b = getattr(self, first), getattr(self, second)
            if a is None and b is None:
                problems.append(((first,), _MISSING, f"give {first} or {second}"))
            elif a is not None and b is not None:
                problems.append(((second,), b, f"give either {first} or {second}, not both"))
        return problems


class DownholeMotor(MotorKeys, _ComponentTables):
    """``[motor]``: a downhole motor whose rotor turns the string below ``position`` relative to the string
    above (the ``motor`` entry of ``[[components]]`` writes it, ``position`` at the bottom of the motor).
    ``law``: the registered motor (``"positive_displacement"``, whose keys are this table's; another motor's
    keys in ``[motor.<law>]``)."""

    position: Length = Field(gt=0, description="x of the rotor station from the top [m] (a mesh node)")
    law: str = Field("positive_displacement", min_length=1, description="downhole motor: a registered motor's name")

    @model_validator(mode="after")
    def _complete(self) -> DownholeMotor:
        problems = self.motor_problems() if self.law == "positive_displacement" else []
        if problems:
            raise _Problems(problems)
        return self


class Component(MotorKeys):
    """One component of the string, listed from the top to the bit in ``[[components]]``
    (:mod:`drillstring.components` says how it becomes sections and stabilizers)."""

    type: Literal["drill_pipe", "heavy_weight", "collar", "mwd", "motor", "stabilizer", "bit"]
    name: str | None = Field(None, description="section name; by default from the type ('drill pipe', ...)")
    length: Length = Field(0.0, ge=0, description="length [m]; > 0 except for a stabilizer (0: a point)")
    outer_diameter: Length | None = Field(None, gt=0, description="outer diameter D_o [m]")
    inner_diameter: Length | None = Field(None, ge=0, description="inner (bore) diameter D_i [m]")
    weight_per_length: MassPerLength | None = Field(
        None, gt=0, description="nominal mass per length, e.g. '19.5 lb/ft' [kg/m]: with inner_diameter, the "
        "section's linear mass; without it, sets the bore of the plain tube of that mass")
    material: str = Field("steel", description="key into Case.materials")
    shear_factor: Dimensionless = Field(6.0 / 7.0, gt=0, le=1, description="Timoshenko shear factor k_s [-]")
    eccentricity: Length = Field(0.0, ge=0, description="mass-centre offset e [m] (see Section)")
    eccentricity_angle: Angle = Field(0.0, description="direction of the offset [rad] (see Section)")
    tool_joint: ToolJoint | None = Field(None, description="drill pipe and heavy-weight pipe only")
    stiffness: Stiffness | None = Field(None, gt=0, description="stabilizer only: lateral stiffness [N/m]")
    blade_diameter: Length | None = Field(
        None, gt=0, description="stabilizer only: blade (gauge) diameter [m], at most the borehole's")

    @model_validator(mode="after")
    def _fields_of_type(self) -> Component:
        problems: list[tuple[tuple[str | int, ...], Any, str]] = []
        stabilizer = self.type == "stabilizer"
        for key in ("stiffness", "blade_diameter"):
            if not stabilizer and getattr(self, key) is not None:
                problems.append(((key,), getattr(self, key), f"only for a stabilizer, not a {self.type}"))
        if stabilizer and self.stiffness is None:
            problems.append((("stiffness",), _MISSING, "required for a stabilizer"))
        powered = [key for key in MotorKeys.LAW_KEYS if key in self.model_fields_set]
        if self.type != "motor":
            problems += [((key,), getattr(self, key), f"only for a motor, not a {self.type}") for key in powered]
        elif powered:
            problems += self.motor_problems()
        if self.tool_joint is not None and self.type not in ("drill_pipe", "heavy_weight"):
            problems.append((("tool_joint",), self.tool_joint, "only for drill_pipe and heavy_weight"))
        tube = not stabilizer or self.length > 0.0
        if not stabilizer and self.length == 0.0:
            problems.append((("length",), self.length, f"must be > 0 for a {self.type}"))
        if tube:
            if self.outer_diameter is None:
                problems.append((("outer_diameter",), _MISSING, "required"))
            if self.inner_diameter is None and self.weight_per_length is None:
                problems.append((("inner_diameter",), _MISSING, "give inner_diameter or weight_per_length"))
            if (self.outer_diameter is not None and self.inner_diameter is not None
                    and self.inner_diameter >= self.outer_diameter):
                problems.append((("inner_diameter",), self.inner_diameter,
                                 f"must be less than outer_diameter ({self.outer_diameter:g} m)"))
            if (stabilizer and self.blade_diameter is not None and self.outer_diameter is not None
                    and self.blade_diameter < self.outer_diameter):
                problems.append((("blade_diameter",), self.blade_diameter,
                                 f"must be at least the body's outer_diameter ({self.outer_diameter:g} m)"))
            if (self.tool_joint is not None and self.outer_diameter is not None
                    and self.tool_joint.outer_diameter < self.outer_diameter):
                problems.append((("tool_joint", "outer_diameter"), self.tool_joint.outer_diameter,
                                 f"must be at least the pipe's outer_diameter ({self.outer_diameter:g} m)"))
        if problems:
            raise _Problems(problems)
        return self



#: No-load speed of a downhole motor, 2 pi eta_v Q / V [rpm]: its allowed range (motors turn the bit at
#: 50-1000 rpm; below 1 rpm the rotor's damping T_s/omega_0 makes the motor a stiff lock, no longer a motor).
MOTOR_SPEED_RANGE = (1.0, 5000.0)


def _motor_problems(case: Any) -> list[tuple[tuple[str | int, ...], Any, str]]:
    """The motor's no-load speed from its keys and the flow it gets (the case's pumped flow by default) within
    :data:`MOTOR_SPEED_RANGE` (docs/model.md §6, "Downhole motor", eq. (1))."""
    motor = case.motor
    if motor is None:
        return []
    flow = case.flow_rate if motor.flow_rate is None else motor.flow_rate
    per_radian = motor.displacement if motor.displacement is not None else 1.0 / motor.speed_per_flow
    rpm = motor.volumetric_efficiency * flow / per_radian / _RPM
    low, high = MOTOR_SPEED_RANGE
    if low <= rpm <= high:
        return []
    key, value = (("motor", "flow_rate"), motor.flow_rate) if motor.flow_rate is not None else \
        (("fluid", "flow_rate"), flow)
    return [(key, value, f"gives the motor a no-load speed 2 pi eta_v Q / V of {rpm:.3g} rpm (Q {flow:.4g} m3/s, "
                         f"V {2 * math.pi * per_radian:.4g} m3/rev, eta_v {motor.volumetric_efficiency:g}): must be "
                         f"within [{low:g}, {high:g}] rpm")]


def _from_components(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with its ``components`` list replaced by the sections, stabilizers and materials they make
    (:func:`drillstring.components.expand`); raises :class:`CaseError` naming the component fields at fault."""
    from drillstring.components import ComponentProblem, expand

    raw = data.pop("components")
    if "sections" in data:
        raise _Problems([(("components",), "[...]", "give either [[components]] or [[sections]], not both")])
    if not isinstance(raw, list) or not raw:
        raise _Problems([(("components",), raw, "must be a non-empty list of tables")])
    entries: list[_Entry] = []
    components = []
    for i, item in enumerate(raw):
        try:
            components.append(Component.model_validate(item))
        except CaseError as exc:
            entries.extend((("components", i) + loc, value, message) for loc, value, message in exc.entries)
    raw_materials = data.get("materials")
    materials = _default_materials() if raw_materials is None else {}
    for name, raw_material in (raw_materials.items() if isinstance(raw_materials, Mapping) else ()):
        try:
            materials[name] = Material.model_validate(raw_material)
        except CaseError as exc:  # needed for the expansion: reported here
            entries.extend((("materials", name) + loc, value, message) for loc, value, message in exc.entries)
    try:
        borehole = to_si(data["borehole"]["diameter"], LENGTH)
    except (KeyError, TypeError, ValueError):
        borehole = None
    if entries:
        raise CaseError(entries)
    try:
        expansion = expand(components, materials, borehole)
    except ComponentProblem as exc:
        raise _Problems(exc.problems) from None
    data["sections"] = expansion.sections
    if expansion.motor is not None:
        if "motor" in data:
            raise _Problems([(("motor",), "{...}", "give the motor on its [[components]] entry or as [motor], "
                                                  "not both")])
        data["motor"] = expansion.motor
    data["stabilizers"] = list(data.get("stabilizers", [])) + expansion.stabilizers
    if expansion.materials:
        data["materials"] = {**(raw_materials if raw_materials is not None else
                                {n: m.model_dump() for n, m in materials.items()}), **expansion.materials}
    return data


class StringFrictionKeys(_Base):
    """The keys of the along-string Coulomb friction (:mod:`drillstring.forces.string_friction`), in
    ``[string_friction.coulomb]``. The friction factors are the well's (``well.cased_hole_friction`` above the
    casing shoe, ``well.open_hole_friction`` below), the normal forces the stiff string's in the well."""

    regularization_speed: Velocity = Field(
        0.01, gt=0, description="v_reg [m/s]: the friction is mu N v / sqrt(v^2 + v_reg^2) along the contact point's "
                                "sliding velocity v (axial and circumferential)")
    static_factor: Dimensionless = Field(
        1.0, ge=1, le=5, description="k_s [-]: the friction coefficient at rest over the kinetic one (1: kinetic only)")
    stribeck_speed: Velocity = Field(
        0.1, gt=0, description="v_S [m/s]: the sliding speed over which the coefficient decays from k_s mu to mu")


class StringFriction(_ComponentTables):
    """Along-string friction in the dynamics of a deviated well (docs/stiff_string.md): ``law`` names a registered
    friction law (``"coulomb"``; ``"none"``: no friction, the default), its keys in ``[string_friction.<law>]``.
    It acts only in a case with ``[well]``, whose stiff-string statics gives the normal forces."""

    law: str = Field("none", min_length=1, description="along-string friction law: 'none' or a registered law's name")
