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

Layout: :mod:`~drillstring.case.errors` (:class:`CaseError` and its problem lines),
:mod:`~drillstring.case.base` (the field types with units, the base model), :mod:`~drillstring.case.tables`
(the string, hole, fluid, laws, operation and run settings), :mod:`~drillstring.case.component_tables`
(``[[components]]`` and ``[motor]``), :mod:`~drillstring.case.well_table` and
:mod:`~drillstring.case.survey_input` (``[well]`` and its survey), :mod:`~drillstring.case.bounds`
(:data:`PHYSICAL_BOUNDS` and the size limits), :mod:`~drillstring.case.drilling_case` (:class:`Case` and its
cross-field rules) and :mod:`~drillstring.case.loading` (files and mappings); every public name is
importable from ``drillstring.case``.

This package imports nothing from the rest of ``drillstring`` but :mod:`drillstring.derived` (pure functions
of numbers shared with the finite-element model: mesh layout, mode-family sizes, axial loads),
:mod:`drillstring.units` (reading units), :mod:`drillstring.components` (strings from components),
:mod:`drillstring.constants` and :mod:`drillstring.files` (reading survey files within bounds).
"""

from drillstring.case import base as _base
from drillstring.case import bounds as _bounds
from drillstring.case.bounds import (  # noqa: F401  (re-exported: the case's public names)
    MAX_CASE_DEPTH,
    MAX_CASE_FILE_BYTES,
    MAX_DESCRIPTION_LENGTH,
    MAX_NAME_LENGTH,
)
from drillstring.case.component_tables import (  # noqa: F401  (re-exported: the case's public names)
    MOTOR_SPEED_RANGE,
    Component,
    DownholeMotor,
    StringFriction,
    StringFrictionKeys,
    MotorKeys,
    ToolJoint,
)
from drillstring.case.drilling_case import Case  # noqa: F401
from drillstring.case.errors import CaseError  # noqa: F401
from drillstring.case.loading import (  # noqa: F401  (re-exported: the case's public names)
    MAX_KEY_LENGTH,
    MAX_KEY_PARTS,
    builtin_cases,
    case_from_dict,
    load_case,
)
from drillstring.case.tables import (  # noqa: F401  (re-exported: the case's public names)
    BitRock,
    Borehole,
    Bow,
    Contact,
    CorrelationTable,
    Damping,
    DetournayKeys,
    Environment,
    Fluid,
    ImbalanceKeys,
    Initial,
    Material,
    Mesh,
    Model,
    ModelUncertaintyTable,
    Operation,
    RampStartKeys,
    ReducedModel,
    Section,
    Simulation,
    Stabilizer,
    TopDrive,
    TuckerWangKeys,
    UncertaintyTable,
)
from drillstring.case.well_table import Well  # noqa: F401
from drillstring.components import MOTOR_KEYS  # noqa: F401
from drillstring.constants import STANDARD_GRAVITY  # noqa: F401
from drillstring.units import (  # noqa: F401  (re-exported: the case's public names)
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

# The field types with units and the limits, re-exported here with their doc comments (the API reference
# documents the package's names from this file's comments).
Length = _base.Length  #: [m]
Force = _base.Force  #: [N]
AngularSpeed = _base.AngularSpeed  #: [rad/s]
Velocity = _base.Velocity  #: [m/s]
Stiffness = _base.Stiffness  #: [N/m]
StiffnessPerLength = _base.StiffnessPerLength  #: [N/m per m of string]
Pressure = _base.Pressure  #: [Pa]
Density = _base.Density  #: [kg/m^3]
Time = _base.Time  #: [s]
Torque = _base.Torque  #: [N*m]
Acceleration = _base.Acceleration  #: [m/s^2]
Angle = _base.Angle  #: [rad]
Dimensionless = _base.Dimensionless  #: [-]
AxialDamping = _base.AxialDamping  #: [N*s/m]
RotationalDamping = _base.RotationalDamping  #: [N*m*s/rad]
LinearDamping = _base.LinearDamping  #: [N*s/m^2]
PenetrationPerForce = _base.PenetrationPerForce  #: [m/(N*s)]
LengthPerAngle = _base.LengthPerAngle  #: [m/rad]
ForceAngle = _base.ForceAngle  #: [N*rad]
MassPerLength = _base.MassPerLength  #: [kg/m]
VolumeFlow = _base.VolumeFlow  #: [m^3/s]
MomentOfInertia = _base.MomentOfInertia  #: [kg*m^2]
RotationalStiffness = _base.RotationalStiffness  #: [N*m/rad]
MotorDisplacement = _base.MotorDisplacement  #: [m^3/rad]
MotorSpeedPerFlow = _base.MotorSpeedPerFlow  #: [rad/m^3]

#: Most finite elements a case may have (a mesh finer than this is refused at validation; 10 000 elements is
#: 0.16 m for the 1600 m reference string, 1 m for a 10 km string, whose sparse set-up takes about 450 MiB).
MAX_ELEMENTS = _bounds.MAX_ELEMENTS
#: Plausible physical ranges [SI] of the values whose extremes overflow, underflow or make the integration
#: degenerate (a product of a length and a modulus beyond 1.8e308, a division by a subnormal a2 or atol):
#: path (``*``: every item of a list or table), lowest, highest, SI unit. Checked before any other rule.
PHYSICAL_BOUNDS: tuple[tuple[tuple[str, ...], float, float, str], ...] = _bounds.PHYSICAL_BOUNDS

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
    "StringFriction",
    "StringFrictionKeys",
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
