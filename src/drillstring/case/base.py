"""The building blocks of the case's tables: the field types with units (``Length``, ``Force``, ...: a number
in SI units or a ``"value unit"`` string read by :mod:`drillstring.units`) and the base model of every table
(immutable, unknown keys refused, every failure a :class:`~drillstring.case.CaseError`).
"""

from __future__ import annotations

import math
import numbers
import typing
from typing import Annotated, Any, Mapping

from pydantic import BaseModel, BeforeValidator, ConfigDict, ValidationError

from drillstring.case.errors import CaseError, _Entry, _entries_from_validation_error, _fmt_value, _unwrap
from drillstring.units import (
    ACCELERATION,
    ANGLE,
    ANGULAR_SPEED,
    AXIAL_DAMPING,
    DENSITY,
    DIMENSIONLESS,
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
    to_si,
)

# ---------------------------------------------------------------------------------------------------------
# Quantities with units
# ---------------------------------------------------------------------------------------------------------


# The dimensions and the conversion live in drillstring.units (pint); this module names the field types.
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
