"""A validated description of a drilling case, loaded from TOML.

A *case* holds everything needed to build and run the model: the string's sections and materials, the
borehole, stabilizers, drilling fluid, bit-rock law, contact law, operating point, damping, model switches,
mesh, reduced-order model, time integration and initial state. It is a tree of immutable pydantic models
(``frozen=True``; unknown keys are refused). All values are stored in SI units.

Units at the edge
-----------------
Every physical field accepts either a plain number, taken in SI units, or a string ``"value unit"``, e.g.
``"100 rpm"``, ``"100 kN"``, ``"1400 m"``, ``"8.5 in"``, ``"10 ppg"``, ``"3000 psi"``, ``"17.5 MN/m"``, in any unit of
the field's dimension. The string is read by pint and converted to SI when the case is validated
(:mod:`drillstring.units`: writing rules, the oilfield units ppg, gpm and rev); a unit of the wrong dimension, or
an unknown unit, is refused naming the dimension expected. Two inputs are converted with the rest of the case:
``fluid.flow_rate`` (a volume flow, e.g. ``"600 gpm"``) gives ``fluid.inlet_velocity`` through the bore of the
top section, and a ``[[components]]`` list (:mod:`drillstring.components`) gives the sections and stabilizers.

Errors
------
Every invalid case raises :class:`CaseError` (a ``ValueError``); its message lists every problem found, one per
line, as ``<dotted.field.path> = <value>: <what is allowed>``, e.g.
``sections[1].inner_diameter = 0.3: must be less than outer_diameter (0.2286 m)``. This holds for
:func:`load_case`, :func:`case_from_dict` and for constructing any of the models directly in Python.
Cross-field rules (which need the whole case) are checked only once every field is individually valid.

Entry points: :func:`load_case`, :func:`case_from_dict`, :func:`builtin_cases`, :meth:`Case.to_toml`.

This module imports nothing from the rest of ``drillstring`` but :mod:`drillstring.derived` (pure functions
of numbers shared with the finite-element model: mesh layout, mode-family sizes, axial loads),
:mod:`drillstring.units` (reading units) and :mod:`drillstring.components` (strings from components).
"""

from __future__ import annotations

import math
import numbers
import os
import stat
import tomllib
import typing
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, Mapping

import tomli_w
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, model_validator

from drillstring.derived import (
    axial_load_per_length,
    element_counts,
    fluid_skin_friction,
    mesh_breaks,
    mode_family_sizes,
    string_axial_load,
)
from drillstring.components import MOTOR_KEYS
from drillstring.constants import STANDARD_GRAVITY
from drillstring.units import (
    ACCELERATION,
    ANGLE,
    ANGULAR_SPEED,
    AXIAL_DAMPING,
    DENSITY,
    DIMENSIONLESS,
    DIMENSIONS,
    FORCE,
    FORCE_ANGLE,
    LENGTH,
    LENGTH_PER_ANGLE,
    LINEAR_DAMPING,
    MASS_PER_LENGTH,
    MOMENT_OF_INERTIA,
    MOTOR_DISPLACEMENT,
    MOTOR_SPEED_PER_FLOW,
    PENETRATION_PER_FORCE,
    PRESSURE,
    ROTATIONAL_DAMPING,
    ROTATIONAL_STIFFNESS,
    STIFFNESS,
    STIFFNESS_PER_LENGTH,
    TIME,
    TORQUE,
    VELOCITY,
    VOLUME_FLOW,
    Dimension,
    quantity_text,
    to_si,
)

__all__ = [
    "DIMENSIONS",
    "MAX_ELEMENTS",
    "PHYSICAL_BOUNDS",
    "Acceleration",
    "Angle",
    "AngularSpeed",
    "AxialDamping",
    "ForceAngle",
    "LengthPerAngle",
    "LinearDamping",
    "PenetrationPerForce",
    "RotationalDamping",
    "BitRock",
    "TopDrive",
    "Borehole",
    "Bow",
    "Case",
    "CaseError",
    "Component",
    "Contact",
    "Damping",
    "Density",
    "Dimension",
    "Dimensionless",
    "Environment",
    "Fluid",
    "Force",
    "Initial",
    "Length",
    "MassPerLength",
    "Material",
    "Mesh",
    "Model",
    "Operation",
    "Pressure",
    "ReducedModel",
    "Section",
    "Simulation",
    "Stabilizer",
    "Stiffness",
    "StiffnessPerLength",
    "Time",
    "ToolJoint",
    "Torque",
    "Velocity",
    "VolumeFlow",
    "Well",
    "builtin_cases",
    "case_from_dict",
    "load_case",
    "to_si",
]


# ---------------------------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------------------------


class CaseError(ValueError):
    """An invalid case, or a case file that cannot be read.

    Attributes
    ----------
    problems:
        One line per problem, ``<dotted.field.path> = <value>: <what is allowed>`` (or a plain sentence for
        file-level problems such as a TOML syntax error).
    source:
        Where the case came from (a file name, ``"<dict>"``, ...).
    """

    def __init__(self, problems: list[str] | list[_Entry] | str, source: str = "<case>") -> None:
        if isinstance(problems, str):
            problems = [problems]
        self.entries: list[_Entry] = [((), None, p) if isinstance(p, str) else p for p in problems]
        self.problems: list[str] = [_format_entry(e) for e in self.entries]
        self.source: str = source
        n = len(self.problems)
        if n == 1:  # one problem, one line
            super().__init__(f"invalid case {source}: {self.problems[0]}")
            return
        head = f"invalid case {source}: {n} problems"
        super().__init__("\n".join([head, *(f"  {p}" for p in self.problems)]))

    def __reduce__(self) -> Any:  # picklable (worker processes)
        return (type(self), (self.entries, self.source))


#: One problem: (location, value as shown or None, what is allowed).
_Entry = tuple[tuple[str | int, ...], str | None, str]


def _format_entry(entry: _Entry) -> str:
    loc, value, message = entry
    if value is None:
        return f"{_loc_to_path(loc)}: {message}" if loc else message
    return f"{_loc_to_path(loc)} = {value}: {message}"


class _Problems(ValueError):
    """Cross-field problems raised from a model validator: ``(relative loc, value, message)`` triples.

    Pydantic wraps it in a ``value_error`` whose context keeps this object, so :class:`CaseError` can expand it
    into one line per problem with the full field path.
    """

    def __init__(self, problems: list[tuple[tuple[str | int, ...], Any, str]]) -> None:
        self.entries: list[_Entry] = [(tuple(loc), _fmt_value(v), m) for loc, v, m in problems]
        super().__init__("; ".join(_format_entry(e) for e in self.entries))


def _loc_to_path(loc: tuple[str | int, ...]) -> str:
    """``('sections', 1, 'inner_diameter')`` -> ``'sections[1].inner_diameter'``."""
    out = ""
    for item in loc:
        if isinstance(item, int):
            out += f"[{item}]"
        else:
            out += f".{item}" if out else str(item)
    return out or "<case>"


def _fmt_value(value: Any) -> str:
    if isinstance(value, bool):
        text = repr(value)
    elif isinstance(value, float):
        text = repr(float(f"{value:.12g}"))  # 0.30479999999999996 -> 0.3048
    elif isinstance(value, BaseModel):
        text = repr(value.model_dump())
    else:
        text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _fmt_limit(value: Any) -> str:
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**6:
        return str(value)  # an integer limit exactly (a seed's 2**64 - 1, not 1.84467e+19)
    return f"{value:g}" if isinstance(value, (int, float)) and not isinstance(value, bool) else repr(value)


def _unwrap(tp: Any) -> Any:
    """Strip ``Annotated[...]`` and ``Optional[...]`` from a type annotation."""
    while True:
        origin = typing.get_origin(tp)
        if origin is Annotated:
            tp = typing.get_args(tp)[0]
        elif origin is typing.Union:
            args = [a for a in typing.get_args(tp) if a is not type(None)]
            if len(args) != 1:
                return tp
            tp = args[0]
        else:
            return tp


def _model_at(root: type[BaseModel], loc: tuple[str | int, ...]) -> type[BaseModel] | None:
    """The model class found at ``loc`` below ``root`` (for listing allowed keys), or None."""
    tp: Any = root
    for item in loc:
        tp = _unwrap(tp)
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            if isinstance(item, str) and item in tp.model_fields:
                tp = tp.model_fields[item].annotation
                continue
            return None
        origin = typing.get_origin(tp)
        args = typing.get_args(tp)
        if origin in (list, tuple) and isinstance(item, int) and args:
            tp = args[0]
        elif origin is dict and len(args) == 2:
            tp = args[1]
        else:
            return None
    tp = _unwrap(tp)
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


_OPS = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}


_NOT_FOUND = object()


def _lookup(raw: Any, loc: tuple[str | int, ...]) -> Any:
    """The raw input value at ``loc`` (before unit conversion), or ``_NOT_FOUND``."""
    for item in loc:
        try:
            raw = raw[item]
        except (KeyError, IndexError, TypeError):
            return _NOT_FOUND
    return raw


def _entries_from_validation_error(exc: ValidationError, root: type[BaseModel], raw: Any = None) -> list[_Entry]:
    """Pydantic's errors as :data:`_Entry` triples, with paths relative to ``root``.

    ``raw`` is the input that was validated: where a constraint failed after unit conversion, the value is shown
    as the user wrote it, followed by its SI value.
    """
    out: list[_Entry] = []
    for err in exc.errors(include_url=False):
        loc = tuple(err["loc"])
        kind = err["type"]
        ctx = err.get("ctx") or {}
        inner = ctx.get("error")
        # Structured problems from a model validator, or from a nested model's __init__ (see _Base).
        if isinstance(inner, (_Problems, CaseError)):
            out.extend((loc + tuple(rel), value, message) for rel, value, message in inner.entries)
            continue
        if kind == "missing":
            out.append((loc, "(missing)", "required"))
            continue
        value = _fmt_value(err.get("input"))
        original = _lookup(raw, loc)
        if isinstance(original, str) and not isinstance(err.get("input"), str):
            value = f"{_fmt_value(original)} (= {value} SI)"
        elif isinstance(original, (int, float)) and not isinstance(original, bool):
            value = _fmt_value(original)  # as written: 0, not 0.0
        if kind == "extra_forbidden":
            parent = _model_at(root, loc[:-1])
            allowed = ", ".join(parent.model_fields) if parent is not None else "?"
            out.append((loc, value, f"unknown key; allowed keys here: {allowed}"))
        elif kind in _OPS:
            out.append((loc, value, f"must be {_OPS[kind]} {_fmt_limit(next(iter(ctx.values())))}"))
        elif kind == "string_too_long":
            out.append((loc, value, f"must be at most {ctx['max_length']:,} characters "
                                    f"(it has {len(err.get('input', '')):,})"))
        elif kind == "too_short" and "min_length" in ctx:
            n = ctx["min_length"]
            out.append((loc, value, f"must have at least {n} item{'s' if n != 1 else ''}"))
        elif isinstance(inner, Exception) and kind in ("value_error", "assertion_error"):
            out.append((loc, value, str(inner)))
        else:
            msg = str(err["msg"])
            if msg.startswith("Input should be "):
                msg = "must be " + msg[len("Input should be ") :]
            out.append((loc, value, msg))
    return out


# ---------------------------------------------------------------------------------------------------------
# Quantities with units
# ---------------------------------------------------------------------------------------------------------


# The dimensions and the conversion live in drillstring.units (pint); case.py names the field types.
_RPM = 2.0 * math.pi / 60.0  # rad/s per rpm


def _quantity(dim: Dimension) -> Any:
    def convert(value: Any) -> Any:
        return to_si(value, dim)

    convert.__name__ = f"to_si_{dim.name.replace(' ', '_')}"
    return Annotated[float, BeforeValidator(convert)]


Length = _quantity(LENGTH)  #: [m]
Force = _quantity(FORCE)  #: [N]
AngularSpeed = _quantity(ANGULAR_SPEED)  #: [rad/s]
Velocity = _quantity(VELOCITY)  #: [m/s]
Stiffness = _quantity(STIFFNESS)  #: [N/m]
StiffnessPerLength = _quantity(STIFFNESS_PER_LENGTH)  #: [N/m per m of string]
Pressure = _quantity(PRESSURE)  #: [Pa]
Density = _quantity(DENSITY)  #: [kg/m^3]
Time = _quantity(TIME)  #: [s]
Torque = _quantity(TORQUE)  #: [N*m]
Acceleration = _quantity(ACCELERATION)  #: [m/s^2]
Angle = _quantity(ANGLE)  #: [rad]
Dimensionless = _quantity(DIMENSIONLESS)  #: [-]
AxialDamping = _quantity(AXIAL_DAMPING)  #: [N*s/m]
RotationalDamping = _quantity(ROTATIONAL_DAMPING)  #: [N*m*s/rad]
LinearDamping = _quantity(LINEAR_DAMPING)  #: [N*s/m^2]
PenetrationPerForce = _quantity(PENETRATION_PER_FORCE)  #: [m/(N*s)]
LengthPerAngle = _quantity(LENGTH_PER_ANGLE)  #: [m/rad]
ForceAngle = _quantity(FORCE_ANGLE)  #: [N*rad]
MassPerLength = _quantity(MASS_PER_LENGTH)  #: [kg/m]
VolumeFlow = _quantity(VOLUME_FLOW)  #: [m^3/s]
MomentOfInertia = _quantity(MOMENT_OF_INERTIA)  #: [kg*m^2]
RotationalStiffness = _quantity(ROTATIONAL_STIFFNESS)  #: [N*m/rad]
MotorDisplacement = _quantity(MOTOR_DISPLACEMENT)  #: [m^3/rad]
MotorSpeedPerFlow = _quantity(MOTOR_SPEED_PER_FLOW)  #: [rad/m^3]


# ---------------------------------------------------------------------------------------------------------
# Models
# ---------------------------------------------------------------------------------------------------------


class _Base(BaseModel):
    """Immutable, refuses unknown keys; validation failures raise :class:`CaseError`, never a raw pydantic error.

    Because ``__init__`` is overridden, pydantic also calls it for nested models; the nested ``CaseError`` then
    reaches the parent as a ``value_error`` and :func:`_entries_from_validation_error` re-roots its entries.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    def __init__(self, /, **data: Any) -> None:
        try:
            super().__init__(**data)
        except ValidationError as exc:
            entries = _entries_from_validation_error(exc, type(self), data)
            raise CaseError(entries, source=f"<{type(self).__name__}>") from None

    def model_copy(self, *, update: Mapping[str, Any] | None = None, deep: bool = False) -> Any:
        """pydantic's copy, ``update`` (field name -> new value) checked for its *kind*: an unknown field, or a
        value that is not of the field's kind (``{"simulation": 5}``: a number where a table is expected),
        raises :class:`CaseError` naming the field; a mapping given for a table is validated into it. The
        *values* are not validated: the model copies values already checked, and tests build deliberately
        extreme models this way. :meth:`copy_with` is the validated path (every rule, cross-field too)."""
        if not update:
            return super().model_copy(deep=deep)
        if not isinstance(update, Mapping):
            raise TypeError(f"update = {update!r}: must be a mapping of field names to values")
        fields = type(self).model_fields
        checked = {}
        problems: list[_Entry] = []
        for name, value in update.items():
            if name not in fields:
                problems.append(((name,), _fmt_value(value), f"unknown key; allowed keys here: {', '.join(fields)}"))
                continue
            kind = _unwrap(fields[name].annotation)
            if value is None:
                if type(None) not in typing.get_args(fields[name].annotation):
                    problems.append(((name,), "None", "required: cannot be None"))
            elif isinstance(kind, type) and issubclass(kind, BaseModel):
                if isinstance(value, Mapping):
                    value = kind.model_validate(dict(value))
                elif not isinstance(value, kind):
                    problems.append(((name,), _fmt_value(value), f"must be a {kind.__name__} (or a table of its "
                                                                 f"keys), not {type(value).__name__}"))
            elif kind is float and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
                problems.append(((name,), _fmt_value(value), f"must be a number, not {type(value).__name__}"))
            elif typing.get_origin(kind) in (list, dict) and not isinstance(value, typing.get_origin(kind)):
                problems.append(((name,), _fmt_value(value), f"must be a {typing.get_origin(kind).__name__}, not "
                                                             f"{type(value).__name__}"))
            checked[name] = value
        if problems:
            raise CaseError(problems, source=f"<{type(self).__name__}.model_copy>")
        return super().model_copy(update=checked, deep=deep)

    def copy_with(self, update: Mapping[str, Any]) -> Any:
        """A copy with ``update`` (field name -> new value) validated like a new model: every field rule and
        cross-field rule applies, and a bad value raises :class:`CaseError` naming it."""
        if not isinstance(update, Mapping):
            raise TypeError(f"update = {update!r}: must be a mapping of field names to values")
        data = {name: getattr(self, name) for name in type(self).model_fields}
        data.update(update)
        return type(self).model_validate(data)

    @classmethod
    def model_validate(cls, obj: Any, *args: Any, **kwargs: Any) -> Any:  # type: ignore[override]
        try:
            return super().model_validate(obj, *args, **kwargs)
        except ValidationError as exc:
            entries = _entries_from_validation_error(exc, cls, obj)
            raise CaseError(entries, source=f"<{cls.__name__}>") from None


class Material(_Base):
    """Isotropic linear-elastic material."""

    young_modulus: Pressure = Field(gt=0, description="Young's modulus E [Pa]")
    density: Density = Field(gt=0, description="mass density rho [kg/m^3]")
    poisson_ratio: Dimensionless = Field(gt=0, lt=0.5, description="Poisson's ratio nu [-]")
    solid_density: Density | None = Field(
        None, gt=0, description="density of the solid itself when ``density`` smears extra parts (tool joints) "
        "over the section's area [kg/m^3]: the section's steel then occupies, and displaces, mass / solid_density "
        "per length; left out: ``density`` (the section is all solid)")

    @property
    def solid_fraction(self) -> float:
        """Volume of solid per volume of section [-]: ``density / solid_density`` (1 for a plain material; above 1
        when tool joints are smeared: their steel lies outside the pipe body's area)."""
        return 1.0 if self.solid_density is None else self.density / self.solid_density

    @property
    def shear_modulus(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)) [Pa]."""
        return self.young_modulus / (2.0 * (1.0 + self.poisson_ratio))


class ImbalanceKeys(_Base):
    """The case keys of a section's mass imbalance (the turning-load source ``"imbalance"``,
    :class:`~drillstring.forces.turning_loads.MassImbalance`), with their units and bounds."""

    eccentricity: Length = Field(
        0.0, ge=0, description="mass imbalance: offset e of the section's mass centre from its axis [m]; the "
        "centrifugal force rho A e (spin speed)^2 per metre turns with the string (0: none)")
    eccentricity_angle: Angle = Field(
        0.0, description="direction of the offset from y when the section's rotation is 0 [rad]")


class _SectionShape(_Base):
    name: str
    length: Length = Field(gt=0, description="length [m]")
    outer_diameter: Length = Field(gt=0, description="outer diameter D_o [m]")
    inner_diameter: Length = Field(ge=0, description="inner (bore) diameter D_i [m]; 0 for a solid section")
    material: str = Field("steel", description="key into Case.materials")
    shear_factor: Dimensionless = Field(6.0 / 7.0, gt=0, le=1, description="Timoshenko shear factor k_s [-]")


class Section(ImbalanceKeys, _SectionShape):
    """A hollow circular section of the string (drill pipe, drill collar, ...), listed from top to bit; its
    imbalance keys are :class:`ImbalanceKeys`."""

    @model_validator(mode="after")
    def _inner_less_than_outer(self) -> Section:
        if self.inner_diameter >= self.outer_diameter:
            raise _Problems(
                [
                    (
                        ("inner_diameter",),
                        self.inner_diameter,
                        f"must be less than outer_diameter ({self.outer_diameter:g} m)",
                    )
                ]
            )
        return self

    @property
    def outer_area(self) -> float:
        """pi D_o^2 / 4 [m^2]."""
        return math.pi * self.outer_diameter**2 / 4.0

    @property
    def inner_area(self) -> float:
        """pi D_i^2 / 4 [m^2] (the bore, where the mud flows down)."""
        return math.pi * self.inner_diameter**2 / 4.0

    @property
    def area(self) -> float:
        """Steel cross-section pi (D_o^2 - D_i^2) / 4 [m^2]."""
        return self.outer_area - self.inner_area


class Bow(_Base):
    """A stress-free bow of the string (a bent collar) turning with it: the unloaded shape is offset by
    ``amplitude sin²(π (x − start)/(end − start))`` between ``start`` and ``end`` (0 elsewhere; no kink), in
    the direction ``angle`` from y when the section's rotation is 0. ``amplitude = 0``: no bow."""

    amplitude: Length = Field(0.0, ge=0, description="largest offset of the unloaded shape [m]; 0: no bow")
    start: Length = Field(0.0, ge=0, description="upper end of the bow, from the top [m]")
    end: Length = Field(0.0, ge=0, description="lower end of the bow, from the top [m]; > start")
    angle: Angle = Field(0.0, description="direction of the bow from y at zero rotation [rad]")


class Borehole(_Base):
    """The (rigid, straight, vertical) borehole."""

    diameter: Length = Field(gt=0, description="borehole diameter D_ch [m]")


class Stabilizer(_Base):
    """A stabilizer: linear lateral springs on v and w at one point of the string."""

    position: Length = Field(description="x of the stabilizer, measured down from the top [m]; in (0, L]")
    stiffness: Stiffness = Field(gt=0, description="lateral stiffness k_stab [N/m]")


class Fluid(_Base):
    """Drilling fluid (mud): flows down the bore at ``inlet_velocity`` and up the annulus."""

    density: Density = Field(1200.0, ge=0, description="mud density rho_f [kg/m^3]")
    inlet_velocity: Velocity = Field(1.5, ge=0, description="flow speed U_i inside the string [m/s]")
    friction_coefficient: Dimensionless = Field(0.0125, ge=0, description="fluid friction coefficient C_f [-]")
    viscous_coefficient: LinearDamping = Field(0.0, ge=0, description="viscous damping k [N*s/m^2]")
    added_mass: bool = True
    coriolis: bool = True
    centrifugal: bool = True
    viscous_damping: bool = True
    axial_loads: bool = False


class TuckerWangKeys(_Base):
    """The case keys of the Tucker–Wang bit–rock law (``bit_rock.law = "tucker_wang"``,
    :mod:`drillstring.forces.bit_rock`), with their units and bounds."""

    a1: Velocity = Field(3.429e-3, ge=0, description="a1 [m/s]")
    a2: PenetrationPerForce = Field(5.672e-8, gt=0, description="a2 [m/(N*s)]")
    a3: LengthPerAngle = Field(1.374e-4, ge=0, description="a3 [m/rad]")
    a4: ForceAngle = Field(9.537e6, ge=0, description="a4 [N*rad]")
    a5: Torque = Field(1.475e3, ge=0, description="a5 [N*m]")
    regularization: AngularSpeed = Field(2.0, gt=0, description="e in Z = w / sqrt(w^2 + e^2) [rad/s]")
    stick_stiffening_limit: Dimensionless = Field(
        100.0, gt=1, description="largest ratio of the axial resistance 1/(a2 Z^2) to its value at the top speed;"
        " 1/Z^2 is frozen below the bit speed where it is reached (integrable stick) [-]"
    )


class DetournayKeys(_Base):
    """The case keys of the Detournay bit–rock law (``bit_rock.law = "detournay"``,
    :mod:`drillstring.forces.detournay`), with their units and bounds."""

    # -- law = "detournay" (Detournay & Defourny 1992; Richard, Germay & Detournay 2007) --------------------
    blades: int = Field(4, ge=1, le=100, description="detournay: number of blades n [-]")
    bit_radius: Length = Field(0.108, gt=0, description="detournay: bit radius a [m]")
    intrinsic_specific_energy: Pressure = Field(
        60e6, gt=0, description="detournay: intrinsic specific energy of the rock eps [Pa]")
    cutting_inclination: Dimensionless = Field(
        0.6, ge=0, description="detournay: inclination zeta of the cutting force, W_c = zeta T_c 2/a [-]")
    contact_stress: Pressure = Field(
        60e6, ge=0, description="detournay: contact stress sigma under the wear flats [Pa]")
    wear_flat_length: Length = Field(0.011, ge=0, description="detournay: wear-flat length l, W_f = a sigma l [m]")
    friction_coefficient: Dimensionless = Field(
        0.6, ge=0, description="detournay: friction coefficient mu of the wear flats on the rock [-]")
    bit_geometry: Dimensionless = Field(
        1.0, ge=0, description="detournay: bit geometry factor gamma, T_f = mu gamma a W_f / 2 [-]")
    contact_velocity: Velocity = Field(
        2.5e-4, gt=0, description="detournay: v_r, the wear-flat force ramps from 0 to a sigma l as the bit's "
        "axial velocity goes from 0 to v_r (a bit at rest creeps down at most v_r) [m/s]")
    friction_speed: AngularSpeed = Field(
        5e-3, gt=0, description="detournay: omega_r, the torque ramps from 0 to its full value as the bit "
        "speed goes from 0 to omega_r (a stuck bit turns at most omega_r) [rad/s]")


class _ComponentTables(_Base):
    """A kind's case table (``[bit_rock]``, ``[top_drive]``, ``[contact]``, ``[motor]``): besides its own keys,
    one sub-table per component, ``[bit_rock.<name>]``, holding that component's keys; the component reads and
    validates it itself (its ``keys`` model, :func:`drillstring.forces.registry.case_keys`), so a component
    added to the package or registered by a script needs no edit here, and two components may use the same
    key name."""

    model_config = ConfigDict(frozen=True, extra="allow")

    @model_validator(mode="after")
    def _tables_only(self) -> Any:
        wrong = [(name, value) for name, value in (self.model_extra or {}).items() if not isinstance(value, Mapping)]
        if wrong:
            name, value = wrong[0]
            raise _Problems([((name,), value, f"unknown key; allowed keys here: {', '.join(type(self).model_fields)}"
                                              f", or a component's table of keys ([...{name}])")])
        return self


class _BitRockLaw(_ComponentTables):
    law: str = Field("tucker_wang", min_length=1, description="bit-rock law: a registered law's name "
                     "(tucker_wang, off_bottom, detournay, or one added to the package or by a script)")


class BitRock(DetournayKeys, TuckerWangKeys, _BitRockLaw):
    """Bit-rock interaction law (docs/model.md, §5 and "Bit–rock law: Detournay"):

    - ``law = "tucker_wang"`` (the default): Tucker & Wang's law, coefficients ``a1`` .. ``a5`` and the
      regularisation ``e`` (``regularization``, ``stick_stiffening_limit``);
    - ``"off_bottom"``: the bit hangs free: no bit-rock force, weight-on-bit 0, the hook carries the whole
      string (``operation.weight_on_bit`` is then not used);
    - ``"detournay"``: the Detournay law of drag (PDC) bits, cutting plus wear-flat friction with the depth of
      cut set by the bit's own motion one blade passage earlier (:mod:`drillstring.forces.detournay`):
      ``blades`` n, ``bit_radius`` a, ``intrinsic_specific_energy`` ε, ``cutting_inclination`` ζ,
      ``contact_stress`` σ, ``wear_flat_length`` l, ``friction_coefficient`` μ, ``bit_geometry`` γ
      (``W = a ζ ε n d_n + a σ l``, ``T = ½ a² ε n d_n + ½ μ γ a · a σ l``), and the regularisations of its
      set-valued parts, ``contact_velocity`` v_r and ``friction_speed`` ω_r.

    Each law reads its own keys only; the others keep their defaults and are not used.
    A law's keys are its own model (:class:`TuckerWangKeys`, :class:`DetournayKeys`; the law declares it as
    its ``keys``, :mod:`drillstring.forces.registry`); the built-in laws' keys are written in this table itself,
    as case files always have; any other law's in its own sub-table, ``[bit_rock.<law>]``."""


class Contact(_ComponentTables):
    """String-borehole shocks and rubbing. The wall is a distributed stiffness: a length ℓ of string pressed
    δ into it is pushed back by ``shock_stiffness`` ℓ δ, whatever the mesh. ``law``: the registered contact law
    (``"penalty"``, whose keys are this table's; another law's keys in ``[contact.<law>]``)."""

    law: str = Field("penalty", min_length=1, description="contact law: a registered law's name")
    shock_stiffness: StiffnessPerLength = Field(
        1e8, ge=0, description="k_sh, per metre of string [N/m per m]")
    friction_coefficient: Dimensionless = Field(0.0005, ge=0, description="mu_sh [-]")
    tangential_friction: bool = False
    speed_regularization: AngularSpeed = Field(
        0.1, gt=0, description="regularises sign() of the spin speed in the friction torque [rad/s]"
    )


class Operation(_Base):
    """Operating point: what the driller controls."""

    top_speed: AngularSpeed = Field(
        100.0 * _RPM, gt=0, description="rotation speed imposed at the top [rad/s]"
    )
    weight_on_bit: Force = Field(1e5, gt=0, description="initial (static) weight-on-bit [N]")


class TopDrive(_ComponentTables):
    """The top boundary of the torsion (:mod:`drillstring.forces.top_drive`). ``controller =
    "imposed_speed"``: the top turns at ``operation.top_speed`` exactly (the reference study); ``"pi"``,
    ``"soft_torque"``, ``"z_torque"``: a top drive of rotary inertia ``inertia`` at the quill, driven by a
    motor whose torque, saturated at ``max_torque``, a controller sets from the quill speed (and the
    surface torque for ``z_torque``), with ``operation.top_speed`` as set point, reached after
    ``ramp_time`` from rest when that is > 0. ``pi`` needs both gains; the tuned controllers compute the
    gains left out (docs/model.md, "Top drive"). ``boundary``: the registered top boundary (``"top_drive"``,
    whose keys are this table's; another boundary drives the string, its keys in ``[top_drive.<boundary>]``)."""

    boundary: str = Field("top_drive", min_length=1, description="top boundary: a registered boundary's name")
    controller: Literal["imposed_speed", "pi", "soft_torque", "z_torque"] = Field(
        "imposed_speed", description="top boundary of the torsion")
    inertia: MomentOfInertia = Field(
        1000.0, gt=0, description="rotary inertia of motor, gearbox and quill at the quill J_td [kg*m^2]")
    proportional_gain: RotationalDamping | None = Field(
        None, ge=0, description="k_p of the speed controller [N*m*s/rad]; tuned when left out")
    integral_gain: RotationalStiffness | None = Field(
        None, ge=0, description="k_i of the speed controller [N*m/rad]; tuned when left out")
    max_torque: Torque = Field(60e3, gt=0, description="largest motor torque tau_max [N*m]")
    ramp_time: Time = Field(0.0, ge=0, description="set point ramped from 0 over this time [s]; 0: none")
    filter_frequency: AngularSpeed | None = Field(
        None, gt=0, description="z_torque: corner of the high-pass filter on the surface torque [rad/s];"
        " tuned when left out")

    @model_validator(mode="after")
    def _gains_given(self) -> TopDrive:
        if self.controller == "pi":
            missing = [k for k in ("proportional_gain", "integral_gain") if getattr(self, k) is None]
            if missing:
                raise _Problems([((missing[0],), None, 'must be given for controller = "pi" (in N*m*s/rad'
                                  ' and N*m/rad; "soft_torque" and "z_torque" tune their gains)')])
        return self


class Damping(_Base):
    """Structural damping: modal ratio on elastic modes, viscous coefficients on the rigid-body motions.

    ``basis = "free_free"``: xi, c1 and c2 are defined on the modes of the unconstrained string (axial and
    torsional families; the rigid modes get c1 and c2), then projected on the reduced basis;
    ``"constrained"``: xi on every mode of the reduced basis (torsional modes top-held), c2 unused.
    ``mass_proportional`` α [1/s] and ``stiffness_proportional`` β [s] add Rayleigh damping ``α M + β K`` of
    the string (``α`` alone: the distributed viscous damping ``k ρA u̇``, ``k ρJ θ̇`` of Aarsnes & van de Wouw's
    model, with ``k = α``), on top of the above. See :mod:`drillstring.damping`.
    """

    modal_damping_ratio: Dimensionless = Field(0.3, ge=0, lt=1, description="xi [-]")
    rigid_axial: AxialDamping = Field(0.05, ge=0, description="c1, rigid axial motion [N*s/m]")
    rigid_rotation: RotationalDamping = Field(0.05, ge=0, description="c2, rigid rotation [N*m*s/rad]")
    basis: Literal["free_free", "constrained"] = Field(
        "free_free", description="modes on which xi, c1, c2 are defined"
    )
    mass_proportional: float = Field(0.0, ge=0, le=1e6, description="Rayleigh alpha [1/s]: C += alpha M")
    stiffness_proportional: Time = Field(0.0, ge=0, le=1e3, description="Rayleigh beta [s]: C += beta K")


class Environment(_Base):
    gravity: Acceleration = Field(
        STANDARD_GRAVITY, ge=0, description="gravitational acceleration g [m/s^2]; standard gravity by default")


class Model(_Base):
    """Model switches."""

    gravity: bool = True
    buoyancy: bool = False
    nonlinear: Literal["bit_and_contact", "full"] = "bit_and_contact"


class Mesh(_Base):
    max_element_length: Length = Field(10.0, gt=0, description="largest finite element [m]")
    probes: list[Length] = Field(
        default_factory=lambda: [1560.0], description="x of the output probes, from the top [m]; in [0, L]"
    )


class ReducedModel(_Base):
    """Normal modes kept per family (lateral: per plane): ``lateral_modes`` at least, and every lateral mode
    whose frequency is below ``lateral_cutoff`` times the rotation frequency (all the family's modes at most);
    ``truncation_correction``: "static" (the default for new cases) appends to the axial and torsional families
    their residual-flexibility attachment modes at the bit (and the top with a top drive, and a downhole motor's
    torque pair: :func:`drillstring.rotor.released_torsional_modes`), "none" keeps the modes alone
    (:func:`drillstring.modal.compute_modes`; docs/model.md §8)."""

    axial_modes: int = Field(10, ge=0)
    torsional_modes: int = Field(10, ge=1, description="elastic torsional modes (a top drive adds the rigid rotation)")
    lateral_modes: int = Field(20, ge=0)
    lateral_cutoff: Dimensionless = Field(
        1.5, ge=0, description="keep every lateral mode below this multiple of the rotation frequency [-]")
    truncation_correction: Literal["none", "static"] = Field(
        "static", description="correction for the modes left out: 'static' appends to the axial and torsional "
        "families their residual-flexibility attachment modes at the bit (and the top with a top drive); "
        "'none', the modes alone")


class Simulation(_Base):
    """Time integration: adaptive Runge-Kutta, explicit or implicit-explicit (``method``)."""

    t_end: Time = Field(30.0, gt=0, description="end time [s]")
    output_step: Time = Field(0.01, gt=0, description="output sampling step [s]; <= t_end")
    rtol: Dimensionless = Field(1e-6, gt=0, lt=1)
    atol: Dimensionless = Field(1e-9, gt=0)
    max_steps: int = Field(2_000_000, gt=0, le=10**12)
    min_step: Time = Field(1e-12, gt=0, description="smallest step before giving up [s]")
    method: Literal["dopri5", "bs32", "ark43", "ark32"] = Field(
        "ark43", description="'dopri5' (Dormand-Prince 5(4)) or 'bs32' (Bogacki-Shampine 3(2)), explicit; 'ark43' "
        "(the default for new cases) or 'ark32' (Kennedy-Carpenter ARK4(3)6L, ARK3(2)4L): the linear modal part "
        "and the bit law implicit, so that the attachment modes of the default basis (truncation_correction = "
        "'static') do not set the step (docs/model.md §9)")

    @model_validator(mode="after")
    def _output_step_within_run(self) -> Simulation:
        if self.output_step > self.t_end:
            raise _Problems([(("output_step",), self.output_step, f"must be <= t_end ({self.t_end:g} s)")])
        return self


class RampStartKeys(_Base):
    """The case keys of the ramped start (``initial.start = "ramp"``, the hook load
    :class:`~drillstring.forces.hook_load.HookLoadRamp`), with their units and bounds."""

    clearance: Length = Field(0.005, ge=0, le=1.0, description="ramp: bit height above the rock at t = 0 [m]")
    weight_ramp_time: Time = Field(
        10.0, gt=0, le=1e4, description="ramp: time over which the weight on bit reaches its value [s]")


class _InitialState(_Base):
    lateral_perturbation: Length = Field(1e-4, ge=0, description="amplitude [m]; < smallest radial gap")
    seed: int = Field(0, ge=0, le=2**64 - 1)
    start: Literal["ramp", "on_bottom"] = Field("ramp", description="how the run starts")


class Initial(RampStartKeys, _InitialState):
    """Initial state and start. ``start`` names the hook load (:mod:`drillstring.forces.registry`):
    ``"ramp"`` (the default for new cases): the string turns off bottom,
    the bit ``clearance`` above the rock, the hook carrying the whole string; the hook load is then slacked off
    so that the weight on bit grows linearly from 0 to ``operation.weight_on_bit`` over ``weight_ramp_time``
    (:mod:`drillstring.forces.hook_load`; its keys :class:`RampStartKeys`). ``"on_bottom"`` (the reference
    study's start): the static state spinning at the top speed, the bit-rock law switched on at t = 0. Both add a
    seeded lateral perturbation."""


class CorrelationTable(_Base):
    """Correlation of uncertain normal parameters (the MaxEnt joint law is then the multivariate normal)."""

    parameters: list[str] = Field(min_length=2, description="paths of the correlated parameters")
    matrix: list[list[float]] = Field(description="their correlation matrix, one row per parameter")


class ModelUncertaintyTable(_Base):
    """Nonparametric model uncertainty: the dispersions δ of the random reduced mass, stiffness and damping
    matrices of Soize's SE+ ensemble (:mod:`drillstring.stochastic.random_matrices`), each in [0, 1) and
    below sqrt((n+1)/(n+5)) for every mode family of n modes (checked when a study uses them)."""

    mass_dispersion: float = Field(0.0, ge=0, lt=1, description="δ_M of the random reduced mass matrix [-]")
    stiffness_dispersion: float = Field(0.0, ge=0, lt=1, description="δ_K of the random reduced stiffness matrix [-]")
    damping_dispersion: float = Field(0.0, ge=0, lt=1, description="δ_D of the random reduced damping matrix [-]")


class UncertaintyTable(_Base):
    """Uncertain parameters for studies and sensitivity analyses (``drillstring study``, ``drillstring
    sensitivity``): case-parameter path -> law, as a spec string (``"uniform 1.2 1.8 m/s"``) or a table
    (``{law = "uniform", min = 1.2, max = 1.8, unit = "m/s"}``). The paths and laws are checked against the
    case when a study uses them (:mod:`drillstring.stochastic.uncertainty`); a single run ignores them."""

    parameters: dict[str, str | dict[str, str | float]] = Field(default_factory=dict)
    correlation: CorrelationTable | None = None
    model: ModelUncertaintyTable | None = Field(
        None, description="random reduced mass, stiffness and damping matrices of a study's realizations "
        "(:mod:`drillstring.stochastic.random_matrices`)")

    @model_validator(mode="after")
    def _something(self) -> UncertaintyTable:
        if not self.parameters and self.model is None:
            raise _Problems([(("parameters",), self.parameters, "give at least one uncertain parameter (or a "
                              "[uncertainty.model] table)")])
        return self


# ---------------------------------------------------------------------------------------------------------
# Strings from components (expanded into sections and stabilizers by drillstring.components)
# ---------------------------------------------------------------------------------------------------------


class _Missing:
    """A required field's value in a problem line."""

    def __repr__(self) -> str:
        return "(missing)"


_MISSING = _Missing()


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


# ---------------------------------------------------------------------------------------------------------
# The well path (deviated wells): survey, casing, friction factors. Read by drillstring.well.
# ---------------------------------------------------------------------------------------------------------


def _survey_entries(problems: list[tuple[int | None, Any, str]], key: str,
                    rows: Any = None) -> list[_Entry]:
    """Case-error entries ``well.<key>[row] = <row>: message`` of survey problems."""
    out: list[_Entry] = []
    for row, value, message in problems:
        loc: tuple[str | int, ...] = (key,) if row is None else (key, row)
        if value is _MISSING and rows is not None and row is not None and row < len(rows):
            value = rows[row]
        out.append((loc, None if value is _MISSING else _fmt_value(value), message))
    return out


class Well(_Base):
    """A deviated well (:mod:`drillstring.well`): its directional survey, casing and friction factors.

    The survey is given as ``survey = [[md, inc, az], ...]`` in ``survey_units`` (default m, deg, deg), or as
    ``survey_file`` (a CSV file, its path relative to the case file; units in its header), or, as ``to_toml``
    writes it, as the SI lists ``measured_depth`` [m], ``inclination`` [rad], ``azimuth`` [rad]
    (:mod:`drillstring.well.survey_input`). It starts at the surface and reaches at least the bit."""

    measured_depth: list[Length] = Field(description="survey stations' measured depths [m], from 0, increasing")
    inclination: list[Angle] = Field(description="inclination from the vertical at each station [rad], in [0, pi]")
    azimuth: list[Angle] = Field(description="azimuth from north at each station [rad]")
    casing_shoe: Length = Field(0.0, ge=0, description="measured depth of the casing shoe [m]; cased above")
    casing_inner_diameter: Length | None = Field(
        None, gt=0, description="casing bore [m] (buckling clearance in the cased hole); the borehole's by default")
    cased_hole_friction: Dimensionless = Field(0.25, ge=0, le=2, description="friction factor in the casing [-]")
    open_hole_friction: Dimensionless = Field(0.30, ge=0, le=2, description="friction factor in the open hole [-]")
    torque_on_bit: Torque = Field(0.0, ge=0, description="torque on bit when drilling [N*m]")
    inner_fluid_density: Density | None = Field(
        None, ge=0, description="mud density inside the string [kg/m^3]; fluid.density by default")
    tool_joints: dict[str, Length] = Field(
        default_factory=dict, description="tool-joint outer diameter by section name [m]: the torque arm")

    @staticmethod
    def _columns(data: dict[str, Any]) -> tuple[dict[str, Any], tuple[str, Any]]:
        """``data`` with ``survey`` or ``survey_file`` read into the SI lists; which key gave them."""
        from drillstring.well.survey_input import SurveyProblem, read_survey_csv, survey_from_rows

        given = [k for k in ("survey", "survey_file", "measured_depth") if k in data]
        if len(given) > 1:
            raise _Problems([((given[1],), _MISSING, f"give one of survey, survey_file or measured_depth/"
                                                       f"inclination/azimuth, not {' and '.join(given)}")])
        units = data.pop("survey_units", ["m", "deg", "deg"])
        if not (isinstance(units, list) and len(units) == 3 and all(isinstance(u, str) for u in units)):
            raise _Problems([(("survey_units",), units, 'must be three units, e.g. ["ft", "deg", "deg"]')])
        if "survey" in data:
            rows = data.pop("survey")
            if not isinstance(rows, list):
                raise _Problems([(("survey",), rows, "must be a list of [md, inc, az] rows")])
            try:
                columns = survey_from_rows(rows, units)
            except SurveyProblem as exc:
                raise CaseError(_survey_entries(exc.problems, "survey", rows)) from None
            origin: tuple[str, Any] = ("survey", rows)
        elif "survey_file" in data:
            path = data.pop("survey_file")
            try:
                columns = read_survey_csv(path, units)
            except SurveyProblem as exc:
                raise CaseError(_survey_entries(exc.problems, "survey_file")) from None
            except (TypeError, ValueError) as exc:
                raise _Problems([(("survey_file",), path, str(exc))]) from None
            origin = ("survey_file", None)
        else:
            return data, ("survey", None)
        Well._check(columns, *origin)
        data["measured_depth"], data["inclination"], data["azimuth"] = columns
        return data, origin

    @staticmethod
    def _check(columns: Any, key: str, raw: Any) -> None:
        """Raise a CaseError naming each bad row of the survey (:func:`survey_problems`)."""
        from drillstring.well.survey_input import survey_problems

        problems = survey_problems(*columns)
        if problems:
            values = raw if raw is not None else [
                [s, round(math.degrees(i), 9), round(math.degrees(a), 9)] for s, i, a in zip(*columns)]
            raise CaseError(_survey_entries([(r, _MISSING, m) for r, m in problems], key, values),
                            source="<Well>")

    def __init__(self, /, **data: Any) -> None:
        try:
            data, (key, raw) = self._columns(dict(data))
        except _Problems as exc:
            raise CaseError(exc.entries, source="<Well>") from None
        super().__init__(**data)
        if len({len(self.measured_depth), len(self.inclination), len(self.azimuth)}) != 1:
            raise CaseError([(("measured_depth",), None, "measured_depth, inclination and azimuth must have "
                                                           "the same length")], source="<Well>")
        if key == "survey" and raw is None:  # given as the SI lists
            self._check((self.measured_depth, self.inclination, self.azimuth), key, None)

    @classmethod
    def model_validate(cls, obj: Any, *args: Any, **kwargs: Any) -> Any:  # type: ignore[override]
        if isinstance(obj, Mapping):
            return cls(**dict(obj))
        return super().model_validate(obj, *args, **kwargs)

    @property
    def depth(self) -> float:
        """Measured depth of the last survey station [m]."""
        return self.measured_depth[-1]


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


def _well_problems(case: Any) -> list[tuple[tuple[str | int, ...], Any, str]]:
    """Cross-field rules of ``[well]``: the string fits in the well, the shoe is in it, tool joints name
    sections and are at most the hole's diameter."""
    well = case.well
    if well is None:
        return []
    problems: list[tuple[tuple[str | int, ...], Any, str]] = []
    last = len(well.measured_depth) - 1
    if case.length > well.depth * (1.0 + 1e-12):
        problems.append((("well", "survey", last), [well.depth, round(math.degrees(well.inclination[-1]), 9),
                                                    round(math.degrees(well.azimuth[-1]), 9)],
                         f"the last station ({well.depth:g} m) is above the bit: the string is "
                         f"{case.length:g} m long, longer than the well"))
    if well.casing_shoe > well.depth:
        problems.append((("well", "casing_shoe"), well.casing_shoe, f"must be within the well, <= {well.depth:g} m"))
    names = {s.name for s in case.sections}
    for name, diameter in well.tool_joints.items():
        if name not in names:
            problems.append((("well", "tool_joints", name), diameter,
                             f"unknown section; sections: {', '.join(sorted(names))}"))
        elif diameter >= case.borehole.diameter:
            problems.append((("well", "tool_joints", name), diameter,
                             f"must be less than the borehole diameter ({case.borehole.diameter:g} m)"))
    return problems


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


def _inlet_velocity_from_flow(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with ``fluid.flow_rate`` (a volume flow Q) replaced by ``fluid.inlet_velocity`` = Q / A_i, A_i
    the bore of the top section; left as it is when that bore cannot be read (reported elsewhere)."""
    fluid = dict(data["fluid"])
    flow = fluid.pop("flow_rate")
    where = ("fluid", "flow_rate")
    try:
        rate = to_si(flow, VOLUME_FLOW)
    except ValueError as exc:
        raise _Problems([(where, flow, str(exc))]) from None
    if "inlet_velocity" in fluid:
        raise _Problems([(where, flow, "give either fluid.flow_rate or fluid.inlet_velocity, not both")])
    try:
        bore = to_si(data["sections"][0]["inner_diameter"], LENGTH)
    except (KeyError, IndexError, TypeError, ValueError):
        return data
    if rate < 0.0 or bore <= 0.0:
        problem = "must be >= 0" if rate < 0.0 else "needs a bore: the top section's inner_diameter is 0"
        raise _Problems([(where, flow, problem)])
    fluid["inlet_velocity"] = rate / (math.pi * bore**2 / 4.0)
    data["fluid"] = fluid
    return data


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


def _depth(data: Any) -> int:
    """Nesting depth of tables and arrays in ``data`` (iterative: any depth is measured)."""
    deepest, stack = 0, [(data, 0)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, Mapping):
            children = node.values()
        elif isinstance(node, (list, tuple)):
            children = node
        else:
            continue
        deepest = max(deepest, level + 1)
        if deepest > MAX_CASE_DEPTH:
            return deepest
        stack.extend((child, level + 1) for child in children)
    return deepest


def _default_materials() -> dict[str, Material]:
    return {"steel": Material(young_modulus=210e9, density=7850.0, poisson_ratio=0.29)}


class Case(_Base):
    """A complete drilling case. Sections are ordered from the top (x = 0) to the bit (x = L)."""

    name: str = Field(max_length=MAX_NAME_LENGTH)
    description: str = Field("", max_length=MAX_DESCRIPTION_LENGTH)
    materials: dict[str, Material] = Field(default_factory=_default_materials)
    sections: list[Section] = Field(min_length=1)
    borehole: Borehole
    stabilizers: list[Stabilizer] = Field(default_factory=list)
    fluid: Fluid = Field(default_factory=Fluid)
    bit_rock: BitRock = Field(default_factory=BitRock)
    contact: Contact = Field(default_factory=Contact)
    operation: Operation = Field(default_factory=Operation)
    top_drive: TopDrive = Field(default_factory=TopDrive)
    damping: Damping = Field(default_factory=Damping)
    environment: Environment = Field(default_factory=Environment)
    model: Model = Field(default_factory=Model)
    mesh: Mesh = Field(default_factory=Mesh)
    reduced_model: ReducedModel = Field(default_factory=ReducedModel)
    simulation: Simulation = Field(default_factory=Simulation)
    initial: Initial = Field(default_factory=Initial)
    bow: Bow = Field(default_factory=Bow)
    uncertainty: UncertaintyTable | None = Field(
        None, description="optional [uncertainty] table: the laws of a study's random parameters")
    well: Well | None = Field(None, description="optional [well]: survey, casing, friction (drillstring.well)")
    motor: DownholeMotor | None = Field(
        None, description="optional [motor]: a downhole motor (drillstring.forces.motor), from [[components]]")

    # -- inputs converted with the whole case: components, flow rate -------------------------------------

    @model_validator(mode="before")
    @classmethod
    def _whole_case_inputs(cls, data: Any) -> Any:
        if not isinstance(data, Mapping):
            return data
        data = dict(data)
        if "components" in data:
            data = _from_components(data)
        if isinstance(data.get("fluid"), Mapping) and "flow_rate" in data["fluid"]:
            data = _inlet_velocity_from_flow(data)
        return data

    # -- derived quantities ------------------------------------------------------------------------------

    @property
    def top_driven(self) -> bool:
        """Whether a top boundary drives the string (the quill free, its first torsional mode the rigid rotation):
        the top drive under a controller, or any other registered boundary (``top_drive.boundary``)."""
        return self.top_drive.boundary != "top_drive" or self.top_drive.controller != "imposed_speed"

    @property
    def length(self) -> float:
        """Total string length L [m]."""
        return math.fsum(s.length for s in self.sections)

    @property
    def section_boundaries(self) -> tuple[float, ...]:
        """x of the lower end of each section, top to bit [m]; the last one is ``length``."""
        ends, x = [], 0.0
        for s in self.sections:
            x += s.length
            ends.append(x)
        return tuple(ends)

    def material_of(self, section: Section | int) -> Material:
        """The material of a section (given as a Section or as its index)."""
        if isinstance(section, int):
            section = self.sections[section]
        return self.materials[section.material]

    @property
    def flow_rate(self) -> float:
        """Mud volume flow Q = U_i A_i of the top section [m^3/s] (U_i the inlet velocity)."""
        return self.fluid.inlet_velocity * self.sections[0].inner_area

    @property
    def axial_load_per_length(self) -> tuple[float, ...]:
        """Distributed axial load q of each section [N/m], along +x (down): ``(rho A - rho_b A_s) g``, with
        ``A_s`` the section's solid area (tool joints' steel included: :attr:`Material.solid_fraction`),
        ``rho_b`` the mud density when ``model.buoyancy`` is on (else 0) and ``g`` 0 when ``model.gravity``
        is off, plus the mud's skin friction when ``fluid.axial_loads`` is on
        (:func:`drillstring.derived.axial_load_per_length`; the statics uses the same values)."""
        g = self.environment.gravity if self.model.gravity else 0.0
        buoyancy = self.fluid.density if self.model.buoyancy else 0.0
        loads = []
        for s in self.sections:
            friction = 0.0
            if self.fluid.axial_loads:
                friction = fluid_skin_friction(s.outer_diameter, s.inner_diameter, self.borehole.diameter,
                                               self.fluid.density, self.flow_rate,
                                               self.fluid.friction_coefficient)
            material = self.material_of(s)
            loads.append(axial_load_per_length(steel_density=material.density, area=s.area, gravity=g,
                                               buoyancy_density=buoyancy, skin_friction=friction,
                                               solid_area=material.solid_fraction * s.area))
        return tuple(loads)

    @property
    def weight(self) -> float:
        """Total distributed axial load on the string [N], ``sum q L`` over the sections
        (:attr:`axial_load_per_length`): its weight (buoyed when ``model.buoyancy`` is on, 0 when
        ``model.gravity`` is off) plus the mud's skin friction when ``fluid.axial_loads`` is on. The hook and
        the bit carry it together; it equals the static state's ``weight``."""
        return string_axial_load(self.axial_load_per_length, [s.length for s in self.sections])

    @property
    def weight_on_hook(self) -> float:
        """Static hook load, weight - weight_on_bit [N]; negative when the hook pushes (gravity off)."""
        return self.weight - self.operation.weight_on_bit

    @property
    def element_count(self) -> int:
        """Number of finite elements of the case's mesh (:func:`drillstring.derived.element_counts`)."""
        points = [st.position for st in self.stabilizers] + list(self.mesh.probes)
        breaks = mesh_breaks([s.length for s in self.sections], points)
        return sum(element_counts(breaks, self.mesh.max_element_length))

    def weight_on_bit_problem(self, weight_on_bit: float) -> str | None:
        """Why ``weight_on_bit`` [N] cannot be this case's (the rule of ``operation.weight_on_bit``, also
        applied to the API's overrides), or None: at most its :data:`PHYSICAL_BOUNDS` ceiling, and, with
        gravity on, less than the string's weight (the hook cannot push; with gravity off the string weighs
        nothing and the hook pushes)."""
        high = next(h for path, _, h, _ in PHYSICAL_BOUNDS if path == ("operation", "weight_on_bit"))
        if not weight_on_bit <= high:
            return f"must be within [0, {high:g}] N"
        w = self.weight
        if self.model.gravity and weight_on_bit >= w:
            shown = [quantity_text(f, "force", digits=6) for f in (weight_on_bit, w)]
            return f"must be less than the string's weight: weight_on_bit {shown[0]} >= weight {shown[1]}"
        return None

    # -- cross-field validation --------------------------------------------------------------------------

    @model_validator(mode="after")
    def _cross_field(self) -> Case:
        problems = _bound_problems(self)
        if problems:  # the rules below compute with these values
            raise _Problems(problems)
        defined = ", ".join(self.materials) or "none"
        for i, s in enumerate(self.sections):
            if s.material not in self.materials:
                problems.append(((("sections", i, "material")), s.material, f"unknown material; defined: {defined}"))
            if s.outer_diameter >= self.borehole.diameter:
                problems.append(
                    (
                        ("sections", i, "outer_diameter"),
                        s.outer_diameter,
                        f"must be less than the borehole diameter ({self.borehole.diameter:g} m)",
                    )
                )
        if self.bit_rock.law == "detournay" and self.bit_rock.bit_radius > self.borehole.diameter / 2.0:
            problems.append((("bit_rock", "bit_radius"), self.bit_rock.bit_radius,
                             f"must be at most the borehole radius ({self.borehole.diameter / 2.0:g} m): the bit "
                             f"cuts the hole"))
        L = self.length
        for i, st in enumerate(self.stabilizers):
            if not 0.0 < st.position <= L:
                problems.append(
                    (("stabilizers", i, "position"), st.position, f"must be within the string, 0 < x <= {L:g} m")
                )
        for i, p in enumerate(self.mesh.probes):
            if not 0.0 <= p <= L:
                problems.append((("mesh", "probes", i), p, f"must be within the string, 0 <= x <= {L:g} m"))
        if self.bow.amplitude > 0.0:
            if not self.bow.end <= L:
                problems.append((("bow", "end"), self.bow.end, f"must be within the string, <= {L:g} m"))
            if not self.bow.start < self.bow.end:
                problems.append((("bow", "start"), self.bow.start,
                                 f"must be less than bow.end ({self.bow.end:g} m)"))
        if problems:  # the rules below need valid materials and gaps
            raise _Problems(problems)
        problems.extend(self._offset_problems())
        problems.extend(_well_problems(self))
        problems.extend(_motor_problems(self))

        problems.extend(self._mesh_problems())

        wob_problem = self.weight_on_bit_problem(self.operation.weight_on_bit)
        if wob_problem:
            problems.append((("operation", "weight_on_bit"), self.operation.weight_on_bit, wob_problem))
        gaps = [(self.borehole.diameter - s.outer_diameter) / 2.0 for s in self.sections]
        i_min = min(range(len(gaps)), key=gaps.__getitem__)
        amp = self.initial.lateral_perturbation
        if amp >= gaps[i_min]:
            problems.append(
                (
                    ("initial", "lateral_perturbation"),
                    amp,
                    f"must be less than the smallest radial gap, {gaps[i_min]:.6g} m"
                    f" (section {self.sections[i_min].name!r})",
                )
            )
        if problems:
            raise _Problems(problems)
        return self

    @model_validator(mode="after")
    def _top_drive_model(self) -> Case:
        if self.top_driven and self.model.nonlinear == "full":
            raise _Problems([(("top_drive", "controller"), self.top_drive.controller,
                              'a top drive needs model.nonlinear = "bit_and_contact" (case 1 with a top drive '
                              'is not supported yet); use "imposed_speed" for case 1')])
        return self

    def _offset_problems(self) -> list[tuple[tuple[str | int, ...], Any, str]]:
        """A section's mass eccentricity and the bow must be less than the radial gap where they are: a
        larger offset puts the string's unloaded shape (bow) or its imbalance orbit (eccentricity) beyond the
        borehole wall, where the contact law would answer with absurd forces instead of a drilling run."""
        problems = []
        top = 0.0
        bowed = []
        for i, s in enumerate(self.sections):
            gap = (self.borehole.diameter - s.outer_diameter) / 2.0
            if s.eccentricity >= gap:
                problems.append((("sections", i, "eccentricity"), s.eccentricity,
                                 f"must be less than the section's radial gap ({gap:.6g} m)"))
            if self.bow.amplitude > 0.0 and top < self.bow.end and top + s.length > self.bow.start:
                bowed.append((gap, s.name))
            top += s.length
        if bowed and self.bow.amplitude >= min(bowed)[0]:
            gap, name = min(bowed)
            problems.append((("bow", "amplitude"), self.bow.amplitude,
                             f"must be less than the radial gap along the bow ({gap:.6g} m, section {name!r})"))
        return problems

    def _mesh_problems(self) -> list[tuple[tuple[str | int, ...], Any, str]]:
        """The case can be meshed (element length within the string, at most :data:`MAX_ELEMENTS`
        elements) and reduced (no family asks for more modes than the mesh has DOFs)."""
        length, h = self.length, self.mesh.max_element_length
        where = ("mesh", "max_element_length")
        if h > length:
            return [(where, h, f"must be at most the string length ({length:g} m)")]
        elements = self.element_count
        if elements > MAX_ELEMENTS:
            return [(where, h, f"gives {elements:,} elements, more than the {MAX_ELEMENTS:,} allowed "
                               f"(about max_element_length >= {length / MAX_ELEMENTS:.3g} m for this "
                               f"{length:g} m string)")]
        nodes = elements + 1
        top_free = self.top_driven
        sizes = mode_family_sizes(nodes, top_free)
        problems = []
        for key, family, rigid in (("axial_modes", "axial", 1), ("torsional_modes", "torsional", int(top_free)),
                                   ("lateral_modes", "lateral", 0)):
            requested = getattr(self.reduced_model, key)
            most = sizes[family] - rigid
            if requested > most:
                dofs = f"{sizes[family]} {family} DOFs" + (" per plane" if family == "lateral" else "")
                rigid_note = ", one of them the rigid mode" if rigid else ""
                problems.append((("reduced_model", key), requested,
                                 f"must be at most {most}: the mesh has {nodes} nodes, {dofs}{rigid_note}; "
                                 f"ask for fewer modes or lower mesh.max_element_length"))
        return problems

    # -- serialisation -----------------------------------------------------------------------------------

    def to_toml(self) -> str:
        """The case as TOML text, every value a plain SI number; ``load_case`` reads it back to an equal Case."""
        header = f"# drillstring case {self.name!r}; all numbers in SI units (m, N, Pa, kg/m3, s, rad/s).\n\n"
        return header + tomli_w.dumps(self.model_dump(mode="python", exclude_none=True))


# ---------------------------------------------------------------------------------------------------------
# Loading
# ---------------------------------------------------------------------------------------------------------


def _cases_dir() -> Any:
    return resources.files("drillstring").joinpath("cases")


def builtin_cases() -> list[str]:
    """Names of the built-in cases (``drillstring/cases/<name>.toml``), sorted."""
    folder = _cases_dir()
    try:
        entries = list(folder.iterdir())
    except (FileNotFoundError, NotADirectoryError):
        return []
    return sorted(e.name[: -len(".toml")] for e in entries if e.name.endswith(".toml") and e.is_file())


def case_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> Case:
    """Validate a (TOML-like) mapping into a :class:`Case`; raises :class:`CaseError` listing every problem."""
    if not isinstance(data, Mapping):
        raise CaseError(f"a case must be a table (mapping), got {type(data).__name__}", source=source)
    if _depth(data) > MAX_CASE_DEPTH:
        raise CaseError(f"tables and arrays nested more than {MAX_CASE_DEPTH} levels deep", source=source)
    try:
        return Case.model_validate(dict(data))
    except CaseError as exc:
        raise CaseError([_with_range(entry) for entry in exc.entries], source=source) from None


def _with_range(entry: _Entry) -> _Entry:
    """``entry`` with the field's plausible range (:data:`PHYSICAL_BOUNDS`) added when its value overflowed or
    underflowed while its unit was read (the range is otherwise checked after every field is read)."""
    loc, value, message = entry
    if not message.startswith(("overflows", "underflows")):
        return entry
    for path, low, high, unit in PHYSICAL_BOUNDS:
        if len(path) == len(loc) and all(p == "*" or p == item for p, item in zip(path, loc)):
            return loc, value, f"{message}; must be within [{low:g}, {high:g}] {unit}".rstrip()
    return entry


def _looks_like_path(source: str) -> bool:
    return source.endswith(".toml") or "/" in source or "\\" in source or Path(source).is_file()


def _read_case_file(path: Path, label: str) -> bytes:
    """The bytes of a case file: a regular file of at most :data:`MAX_CASE_FILE_BYTES` (a FIFO, a device
    such as /dev/zero or a folder is refused at once, without opening it)."""
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode):
            raise CaseError(f"case file {label} is not a regular file (a folder, FIFO, socket or device)",
                            source=label)
        if info.st_size > MAX_CASE_FILE_BYTES:
            raise CaseError(f"case file {label} has {info.st_size:,} bytes, more than the "
                            f"{MAX_CASE_FILE_BYTES:,} allowed", source=label)
        # Read no more than the bound even if the file grew since (or its size was not reported).
        with open(path, "rb", opener=lambda name, flags: os.open(name, flags | os.O_NONBLOCK)) as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):  # replaced since the check
                raise CaseError(f"case file {label} is not a regular file", source=label)
            raw = handle.read(MAX_CASE_FILE_BYTES + 1)
    except FileNotFoundError:
        raise CaseError(f"case file not found: {label}", source=label) from None
    except OSError as exc:
        raise CaseError(f"cannot read case file {label}: {exc.strerror or exc}", source=label) from None
    if len(raw) > MAX_CASE_FILE_BYTES:
        raise CaseError(f"case file {label} has more than the {MAX_CASE_FILE_BYTES:,} bytes allowed",
                        source=label)
    return raw


#: Longest key of a case file, dotted parts together [characters], and most parts of a dotted key (a case
#: needs 3: ``[uncertainty.correlation]``; tomllib's time grows with the square of the parts: 20,000 took 25 s).
MAX_KEY_LENGTH, MAX_KEY_PARTS = 400, MAX_CASE_DEPTH


def _toml_key_problem(text: str) -> str | None:
    """Why the keys of the TOML ``text`` are too long or too deeply dotted for a case, or None; a linear scan
    before ``tomllib`` parses it (the parser takes minutes, or runs out of memory, on a key of 100,000 parts).

    Each line's key (a ``[table]``/``[[array]]`` header, or what comes before ``=``) is scanned outside quotes
    and outside multi-line strings; a ``"."`` inside a quoted key is not a separator."""
    delimiter = None  # the closing quotes of the multi-line string the scan is in, if any
    for number, line in enumerate(text.splitlines(), start=1):
        if delimiter is not None:  # inside a multi-line string: find its end, keys start on a later line
            if line.count(delimiter) % 2 == 1:
                delimiter = None
            continue
        stripped = line.lstrip()
        if not stripped or stripped[0] == "#":
            continue
        header = stripped[0] == "["
        parts, length, quote = 1, 0, None
        i = (2 if stripped.startswith("[[") else 1) if header else 0
        while i < len(stripped):
            char = stripped[i]
            if quote is not None:
                if char == "\\" and quote == '"':
                    i += 1
                elif char == quote:
                    quote = None
            elif char in "\"'":
                quote = char
            elif char == "." :
                parts += 1
            elif (char == "]" and header) or (char == "=" and not header):
                break
            elif not (char.isascii() and (char.isalnum() or char in "_- \t")):
                break  # not a key (a value line of a multi-line array): nothing to check
            i += 1
            length += 1
            if length > MAX_KEY_LENGTH:
                return f"line {number}: a key longer than {MAX_KEY_LENGTH} characters"
            if parts > MAX_KEY_PARTS:
                return f"line {number}: a dotted key of more than {MAX_KEY_PARTS} parts"
        if not header:
            value = stripped[i + 1:]
            for opening in ('"""', "'''"):
                if value.count(opening) % 2 == 1:
                    delimiter = opening
                    break
    return None


def load_case(source: str | Path) -> Case:
    """Load a case: a built-in name (see :func:`builtin_cases`, e.g. ``"reference"``) or a path to a TOML file.

    A string is read as a path when it ends in ``.toml``, contains a path separator or names an existing
    file; otherwise as a built-in name. Raises :class:`CaseError` for a missing file, an unknown built-in name,
    a TOML syntax error or an invalid case.
    """
    folder: Any = None  # where a [well] survey_file is looked for
    if isinstance(source, Path) or _looks_like_path(str(source)):
        path = Path(source)
        label = str(path)
        raw = _read_case_file(path, label)
        folder = path.parent
    else:
        name = str(source)
        resource = _cases_dir().joinpath(f"{name}.toml")
        label = f"{name} (built-in)"
        if not resource.is_file():
            known = ", ".join(builtin_cases()) or "none"
            raise CaseError(
                f"unknown built-in case {name!r}; built-in cases: {known} (or give the path to a .toml file)",
                source=repr(name),
            )
        raw = resource.read_bytes()
        folder = _cases_dir()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CaseError(f"{label}: not UTF-8 text ({exc.reason} at byte {exc.start})", source=label) from None
    problem = _toml_key_problem(text)
    if problem:
        raise CaseError(f"{label}: {problem}", source=label)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"{label}: TOML syntax error: {exc}", source=label) from None
    except RecursionError:
        raise CaseError(f"{label}: tables and arrays nested more than {MAX_CASE_DEPTH} levels deep",
                        source=label) from None
    well = data.get("well")
    if isinstance(well, dict) and isinstance(well.get("survey_file"), str) and folder is not None:
        if not Path(well["survey_file"]).is_absolute():  # relative to the case file
            well["survey_file"] = str(folder.joinpath(well["survey_file"]))
    return case_from_dict(data, source=label)
