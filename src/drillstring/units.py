"""Physical units at the edge: ``"value unit"`` strings read into SI, and the unit systems of output.

Reading
-------
A physical value of a case (or of a command-line option) is a plain number in SI units or a string
``"value unit"``. The unit is read by `pint <https://pint.readthedocs.io>`_ (its default registry: SI, US
customary and imperial units with every SI prefix), so any unit of the right dimension is accepted: ``"8.5 in"``,
``"30 klbf"``, ``"10 ppg"``, ``"3000 psi"``, ``"15 kft*lbf"``, ``"60 ft/h"``, ``"2 deg"``, ``"600 gpm"``,
``"19.5 lb/ft"``. Beyond pint's own names, three oilfield abbreviations are defined (:data:`OILFIELD_UNITS`):

- ``ppg``: pound (mass) per US gallon, the mud weight, 119.826427 kg/m³;
- ``gpm``: US gallon per minute, the flow rate, 6.30901964e-5 m³/s;
- ``rev``: a revolution, 2π rad (``rev/min``, ``rev/s``).

Writing rules: units are case-sensitive (``mm`` is not ``Mm``); ``*``, ``·``, ``.`` and a space denote a product;
``^`` or ``**`` a power, and a digit right after a unit's name is its power (``m2``, ``kg/m3``, ``m/s2``).
One number, then one unit: pint evaluates a unit as an arithmetic expression, so the unit is tokenised
first (:func:`check_unit_text`) and a number inside it (a digit group: ``"1 200 m"`` would read 200 m), a
comma (a decimal comma: ``"22,5 klbf"`` would read 5 klbf times 22), a power above 4, a power of a power
(``"kN*9**9**9"``: pint would compute 9**387420489), more than 8 unit names, parentheses deeper than 2, a
unit over 40 characters or a value over 80 are refused before pint sees them. A value that overflows or
underflows in SI (``"1e308 kg*km2"``), or an integer beyond a float (``10**400``), is refused too.

Angles are kept apart from plain numbers: pint treats the radian as dimensionless, but a unit is accepted here
only when its power of angle matches the field's (``"N*m*s/rad"`` for a rotational damping, not ``"N*m*s"``;
an angle in ``rad`` or ``deg``, not ``m/m``). One exception: an angular speed may be given as a frequency
(``Hz``, ``1/min``), read as revolutions per unit time (``1 Hz`` = 2π rad/s), as ``rpm`` is.

A value of the wrong dimension, or an unknown unit, raises ``ValueError`` with one line naming the dimension
expected and, where it is another known dimension, the one given (:func:`to_si`). Pint is imported on the first
unit read (about 0.3 s), never for plain numbers.

Output
------
Tables, figures and reports speak one of two unit systems (:data:`UNIT_SYSTEMS`, :func:`display_unit`): ``si``
(kN, m, m/h, kN·m, rpm, mm, kg/m³, MPa) or ``field`` (klbf, ft, ft/h, kft·lbf, rpm, in, ppg, psi). The command
line's ``--units`` option picks it; without the option, the environment variable ``DRILLSTRING_UNITS``
(:data:`UNITS_ENVIRONMENT`), else ``si``. JSON output is always SI.

This module imports nothing from the rest of ``drillstring``.
"""

from __future__ import annotations

import functools
import math
import os
import re
import sys
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, Literal

__all__ = [
    "DIMENSIONS",
    "OILFIELD_UNITS",
    "UNITS_ENVIRONMENT",
    "UNIT_SYSTEMS",
    "DisplayUnit",
    "Dimension",
    "display_unit",
    "registry",
    "to_si",
    "unit_factor",
    "unit_system",
]

#: Oilfield units missing from pint's default registry, as pint definitions.
OILFIELD_UNITS: tuple[str, ...] = (
    "rev = revolution",
    "ppg = pound / gallon",  # pound-mass per US gallon
    "gpm = gallon / minute",  # US gallon per minute
)


#: Optional libraries pint imports when they are installed, to support their arrays (unused here: only
#: unit strings are read). Hidden while pint is imported, unless already loaded: Dask alone costs about
#: 0.3 s of start-up, and the light commands load neither (tests/test_cli.py).
_PINT_OPTIONAL = ("dask", "scipy", "uncertainties", "babel")


@functools.cache
def registry() -> Any:
    """The unit registry (pint's default definitions plus :data:`OILFIELD_UNITS`), built on first use."""
    import sys

    hidden = [name for name in _PINT_OPTIONAL if name not in sys.modules]
    for name in hidden:
        sys.modules[name] = None  # type: ignore[assignment]  # `import name` raises ImportError
    try:
        import pint
    finally:
        for name in hidden:
            if sys.modules.get(name, 0) is None:
                del sys.modules[name]

    ureg = pint.UnitRegistry()
    for definition in OILFIELD_UNITS:
        ureg.define(definition)
    return ureg


# ---------------------------------------------------------------------------------------------------------
# Dimensions
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Dimension:
    """A physical dimension of a case field.

    Attributes
    ----------
    name:
        What the field is (``"length"``, ``"angular speed"``), for messages.
    si:
        Its SI unit as written in case files (``"rad/s"``); ``""``: a plain number, no unit accepted.
    examples:
        Common units of the dimension, shown in messages (any other unit of the dimension is accepted too).
    also:
        Other units whose values are read as the same SI number (the shock stiffness per metre of string
        may be written in ``N/m``, as the reference data do).
    cyclic:
        True for an angular speed: a frequency (``Hz``) is read as revolutions per unit time.
    """

    name: str
    si: str
    examples: tuple[str, ...] = ()
    also: tuple[str, ...] = ()
    cyclic: bool = False

    @property
    def units(self) -> tuple[str, ...]:
        """The SI unit and the examples; empty for a plain number."""
        return (self.si, *self.examples) if self.si else ()

    @property
    def allowed(self) -> str:
        if not self.si:
            return "none (a plain number)"
        return f"{', '.join(self.units + self.also)} or any other {self.name} unit"


LENGTH = Dimension("length", "m", ("cm", "mm", "km", "in", "ft"))
FORCE = Dimension("force", "N", ("kN", "MN", "lbf", "klbf"))
ANGULAR_SPEED = Dimension("angular speed", "rad/s", ("rpm", "rev/min", "rev/s", "Hz"), cyclic=True)
VELOCITY = Dimension("velocity", "m/s", ("m/h", "ft/s", "ft/h"))
STIFFNESS = Dimension("stiffness", "N/m", ("kN/m", "MN/m", "lbf/in"))
PRESSURE = Dimension("pressure", "Pa", ("kPa", "MPa", "GPa", "psi", "ksi"))
# A stiffness per metre of string [N/m per m = N/m²]. "N/m" is accepted too, read per metre, because the
# reference data write the shock stiffness so ("1e8 N/m" for the shocks, per meter of string).
STIFFNESS_PER_LENGTH = Dimension("stiffness per length", "N/m2", ("kN/m2", "MN/m2"), also=("N/m",))
DENSITY = Dimension("density", "kg/m3", ("g/cm3", "ppg", "lb/ft3"))
TIME = Dimension("time", "s", ("ms", "min", "h"))
TORQUE = Dimension("torque", "N*m", ("kN*m", "ft*lbf", "kft*lbf"))
ACCELERATION = Dimension("acceleration", "m/s2", ("ft/s2",))
ANGLE = Dimension("angle", "rad", ("deg",))
MASS_PER_LENGTH = Dimension("mass per length", "kg/m", ("lb/ft",))
VOLUME_FLOW = Dimension("volume flow", "m3/s", ("L/min", "gpm", "bbl/min"))
DIMENSIONLESS = Dimension("dimensionless number", "")
# Coefficients that only ever appear in SI; any consistent unit is still accepted.
AXIAL_DAMPING = Dimension("axial damping coefficient", "N*s/m")
ROTATIONAL_DAMPING = Dimension("rotational damping coefficient", "N*m*s/rad")
LINEAR_DAMPING = Dimension("damping per unit length", "N*s/m2")
PENETRATION_PER_FORCE = Dimension("bit-rock coefficient a2", "m/(N*s)")
LENGTH_PER_ANGLE = Dimension("length per angle", "m/rad")
FORCE_ANGLE = Dimension("force times angle", "N*rad")
MOMENT_OF_INERTIA = Dimension("moment of inertia", "kg*m2")
ROTATIONAL_STIFFNESS = Dimension("rotational stiffness", "N*m/rad", ("kN*m/rad",))
# A positive-displacement motor's displacement: the volume of mud that turns the rotor by one radian ("1 gal/rev"
# = 6.02e-4 m3/rad), or its inverse, the rotor's turn per volume ("0.3 rev/gal"); "rev" is 2 pi rad.
MOTOR_DISPLACEMENT = Dimension("motor displacement (volume per revolution)", "m3/rad", ("L/rev", "gal/rev"))
MOTOR_SPEED_PER_FLOW = Dimension("motor speed per flow (revolutions per volume)", "rad/m3", ("rev/L", "rev/gal"))

#: Every dimension, for error messages naming the dimension a misplaced unit belongs to (the first one whose
#: SI unit matches: a pressure before a stiffness per length, a stiffness before a stiffness per length).
DIMENSIONS: tuple[Dimension, ...] = (
    LENGTH, FORCE, ANGULAR_SPEED, VELOCITY, STIFFNESS, PRESSURE, STIFFNESS_PER_LENGTH, DENSITY, TIME, TORQUE,
    ACCELERATION, ANGLE, MASS_PER_LENGTH, VOLUME_FLOW, DIMENSIONLESS, AXIAL_DAMPING, ROTATIONAL_DAMPING,
    LINEAR_DAMPING, PENETRATION_PER_FORCE, LENGTH_PER_ANGLE, FORCE_ANGLE, MOMENT_OF_INERTIA, ROTATIONAL_STIFFNESS,
    MOTOR_DISPLACEMENT, MOTOR_SPEED_PER_FLOW,
)  # fmt: skip


# ---------------------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------------------

_QUANTITY = re.compile(r"^\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*$")
_PRODUCT_DOT = re.compile(r"(?<=[A-Za-z0-9)])\.(?=[A-Za-z(])")  # "N.m" -> "N*m" (not "1.5")
_POWER_DIGITS = re.compile(r"(?<=[A-Za-z])(\d+)")  # "m3" -> "m**3"
_Root = tuple[float, tuple[tuple[str, float], ...]]  # SI factor and root units (radian kept as a base unit)


def _normalise_unit(unit: str) -> str:
    unit = unit.replace("·", "*").replace("⋅", "*").replace("²", "2").replace("³", "3").replace("^", "**")
    return _POWER_DIGITS.sub(r"**\1", _PRODUCT_DOT.sub("*", unit.strip()))


#: Longest unit accepted [characters] (``"N*m*s/rad"`` has 9; ``"m/(N*s)"`` 7).
MAX_UNIT_LENGTH = 40
#: Most unit names in one unit, and the largest power of one (``kg/m3``: 2 names, power 3).
MAX_UNIT_NAMES, MAX_UNIT_POWER = 8, 4
#: Deepest parentheses in a unit.
MAX_UNIT_PARENTHESES = 2

_UNIT_TOKEN = re.compile(r"\s*(?:(?P<name>[^\W\d]+|°)|(?P<power>\*\*)|(?P<op>[*/()])|(?P<number>\d+(?:\.\d+)?))")


def check_unit_text(unit: str) -> None:
    """Refuse, before pint sees it, a unit that is not a short product of unit names and small powers.

    pint evaluates a unit string as an arithmetic expression: ``"kN*9**9**9"`` asks for 9**387420489 (minutes
    of work), ``"200 m"`` after a digit group (``"1 200 m"``) multiplies the value by 200, ``",5 klbf"`` after a
    decimal comma (``"22,5 klbf"``) by 5. Here a unit is tokenised first: unit names, ``*``, ``/``,
    parentheses (at most :data:`MAX_UNIT_PARENTHESES` deep) and powers ``**n`` of a name or a parenthesis,
    ``|n|`` <= :data:`MAX_UNIT_POWER` (a plain ``1`` is allowed only as ``1/...``), at most
    :data:`MAX_UNIT_NAMES` names and :data:`MAX_UNIT_LENGTH` characters. Raises ``ValueError`` (one line)
    for anything else: a number in the unit, a comma, an exponent tower, an over-long unit.
    """
    if len(unit) > MAX_UNIT_LENGTH:
        raise ValueError(f"unit of {len(unit):,} characters; at most {MAX_UNIT_LENGTH} are allowed")
    if "," in unit:
        raise ValueError("a comma is not allowed in a value (write the decimal point as '.', and no digit "
                         "group separator: '22.5 klbf', '1200 m')")
    text = _normalise_unit(unit)
    names = depth = 0
    previous = ""  # kind of the previous token: "", name, close, power, op, number
    position = 0
    while position < len(text):
        token = _UNIT_TOKEN.match(text, position)
        if token is None or token.end() == position:
            if text[position:].strip() == "":
                break
            raise ValueError(f"character {text[position]!r} is not allowed in a unit")
        position = token.end()
        kind = token.lastgroup
        value = token.group(kind)
        if kind == "name":
            names += 1
            if names > MAX_UNIT_NAMES:
                raise ValueError(f"more than {MAX_UNIT_NAMES} unit names in one unit")
            previous = "name"
        elif kind == "power":
            if previous not in ("name", "close"):
                raise ValueError("'**' or '^' must follow a unit name or a parenthesis")
            sign = re.compile(r"\s*[-+]?\s*(\d+(?:\.\d+)?)").match(text, position)
            if sign is None:
                raise ValueError("a power must be a number: 'm**2', 'm^-1', 'm2'")
            if float(sign.group(1)) > MAX_UNIT_POWER:
                raise ValueError(f"power {sign.group(1)} in a unit; at most {MAX_UNIT_POWER} is allowed")
            position = sign.end()
            previous = "power"
        elif kind == "number":
            rest = text[position:].lstrip()
            if not (value == "1" and previous == "" and rest.startswith("/")):
                raise ValueError(f"a number ({value}) inside the unit: write one number then its unit (no digit "
                                 "groups: '1200 m', not '1 200 m')")
            previous = "number"
        else:  # * / ( )
            if value == "(":
                depth += 1
                if depth > MAX_UNIT_PARENTHESES:
                    raise ValueError(f"parentheses nested more than {MAX_UNIT_PARENTHESES} deep in a unit")
            elif value == ")":
                depth -= 1
                if depth < 0:
                    raise ValueError("unbalanced parentheses in the unit")
                previous = "close"
                continue
            previous = "op"
        if previous == "power" and _UNIT_TOKEN.match(text, position) and text[position:].lstrip().startswith("**"):
            raise ValueError("a power of a power (exponent tower) is not allowed in a unit")
    if depth:
        raise ValueError("unbalanced parentheses in the unit")


@functools.lru_cache(maxsize=512)
def _root(unit: str) -> _Root:
    """``unit`` in root units: (factor, sorted (root unit, power) pairs); raises ValueError if unknown."""
    ureg = registry()
    check_unit_text(unit)  # raises ValueError with its own message (not caught below)
    try:
        quantity = ureg.parse_expression(_normalise_unit(unit))
        if not isinstance(quantity, ureg.Quantity):  # a bare number
            return float(quantity), ()
        root = quantity.to_root_units()
    except Exception:  # pint raises UndefinedUnitError, DefinitionSyntaxError, offset-unit and tokenizer errors
        raise ValueError(unit) from None
    powers = tuple(sorted((str(name), float(power)) for name, power in root._units.items()))
    return float(root.magnitude), powers


def _dimension_named(powers: tuple[tuple[str, float], ...]) -> Dimension | None:
    """The first of :data:`DIMENSIONS` whose SI unit has these root units."""
    return next((d for d in DIMENSIONS if d.si and _root(d.si)[1] == powers), None)


def _ratio(unit: str, dim: Dimension) -> float | None:
    """The SI value of 1 ``unit`` as a ``dim`` value, or None when its dimension is another one."""
    factor, powers = _root(unit)
    for target in (dim.si, *dim.also):
        target_factor, target_powers = _root(target)
        if powers == target_powers:
            return factor / target_factor
    if dim.cyclic:  # a frequency, read as revolutions per unit time
        target_factor, target_powers = _root(dim.si)
        if tuple(p for p in target_powers if p[0] != "radian") == powers:
            return 2.0 * math.pi * factor / target_factor
    return None


def unit_factor(unit: str, dim: Dimension) -> float:
    """The SI value of 1 ``unit`` of dimension ``dim`` (``unit_factor("ft", LENGTH)`` = 0.3048); raises
    ``ValueError`` with a one-line explanation when ``unit`` is unknown or of another dimension."""
    if not isinstance(dim, Dimension):
        raise TypeError(f"dim = {dim!r}: must be a drillstring.units.Dimension (e.g. units.LENGTH), not "
                        f"{type(dim).__name__}")
    if not isinstance(unit, str):
        raise TypeError(f"unit = {unit!r}: must be a string, not {type(unit).__name__}")
    shown = unit if len(unit) <= 40 else unit[:37] + "..."
    if not dim.si:
        raise ValueError(f"a plain number without unit is expected ({dim.name}), got unit '{shown}'")
    try:
        check_unit_text(unit)
    except ValueError as error:
        raise ValueError(f"unit '{shown}': {error}") from None
    try:
        ratio = _ratio(unit, dim)
    except ValueError:
        raise ValueError(f"unknown unit '{unit}', not a {dim.name} unit; allowed units: {dim.allowed}") from None
    if ratio is not None:
        return ratio
    other = _dimension_named(_root(unit)[1])
    if other is not None and other.si:
        raise ValueError(f"unit '{unit}' is a {other.name} unit, not a {dim.name} unit; allowed units: "
                         f"{dim.allowed}")
    dimensionality = registry().parse_expression(_normalise_unit(unit))
    shown = getattr(dimensionality, "dimensionality", "dimensionless")
    raise ValueError(f"unit '{unit}' is of dimension {shown}, not a {dim.name} unit; allowed units: {dim.allowed}")


def to_si(value: Any, dim: Dimension) -> float:
    """Convert a plain number (taken as SI) or a ``"value unit"`` string of dimension ``dim`` to an SI float.

    Raises ``ValueError`` with a one-line explanation (the dimension expected, the allowed units) when the
    value cannot be converted.
    """
    if not isinstance(dim, Dimension):
        raise TypeError(f"dim = {dim!r}: must be a drillstring.units.Dimension (e.g. units.LENGTH), not "
                        f"{type(dim).__name__}")
    if isinstance(value, bool):
        raise ValueError(f"expected a number, got a boolean; allowed units: {dim.allowed}")
    if isinstance(value, (int, float)):
        try:
            number, unit = float(value), ""
        except OverflowError:  # an integer beyond 1.8e308
            raise ValueError(f"{_digits(value)}: too large (the largest number is about 1.8e308)") from None
    elif isinstance(value, str):
        if len(value) > MAX_VALUE_LENGTH:
            raise ValueError(f"a value of {len(value):,} characters; at most {MAX_VALUE_LENGTH} are allowed")
        match = _QUANTITY.match(value)
        if match is None:
            hint = f'a number or a "value unit" string (allowed units: {dim.allowed})'
            raise ValueError(f"not {hint if dim.si else 'a plain number'}")
        number, unit = float(match.group(1)), match.group(2)
    else:
        try:  # numpy scalars and the like
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"expected a number, got {type(value).__name__}") from None
        unit = ""
    if not math.isfinite(number):
        raise ValueError("must be a finite number")
    if not unit:
        return number
    si = number * unit_factor(unit, dim)
    if not math.isfinite(si):
        raise ValueError(f"overflows to infinity in SI units ({dim.si}); the largest number is about 1.8e308")
    if si == 0.0 and number != 0.0 or 0.0 < abs(si) < sys.float_info.min:
        raise ValueError(f"underflows to {si:g} in SI units ({dim.si}); the smallest number is about 2.2e-308")
    return si


#: Longest ``"value unit"`` string accepted [characters].
MAX_VALUE_LENGTH = 80


def _digits(value: int) -> str:
    """A huge integer shown short: its number of digits."""
    text = str(value) if abs(value) < 10**40 else f"an integer of {len(str(abs(value))):,} digits"
    return text


# ---------------------------------------------------------------------------------------------------------
# Output unit systems
# ---------------------------------------------------------------------------------------------------------

#: The unit systems of tables, figures and reports.
UNIT_SYSTEMS: tuple[str, ...] = ("si", "field")
#: The environment variable that keeps a user's unit system (``si`` or ``field``).
UNITS_ENVIRONMENT = "DRILLSTRING_UNITS"

UnitSystem = Literal["si", "field"]

#: Output quantity kind -> (dimension, SI-system unit, field-system unit), units as pint reads them.
_DISPLAY: dict[str, tuple[Dimension, str, str]] = {
    "force": (FORCE, "kN", "klbf"),
    "length": (LENGTH, "m", "ft"),
    "diameter": (LENGTH, "mm", "in"),
    "small_length": (LENGTH, "mm", "in"),
    "rate_of_penetration": (VELOCITY, "m/h", "ft/h"),
    "torque": (TORQUE, "kN*m", "kft*lbf"),
    "angular_speed": (ANGULAR_SPEED, "rpm", "rpm"),
    "density": (DENSITY, "kg/m3", "ppg"),
    "pressure": (PRESSURE, "MPa", "psi"),
    "stiffness": (STIFFNESS, "MN/m", "klbf/in"),
    "flow": (VOLUME_FLOW, "L/min", "gpm"),
    "mass_per_length": (MASS_PER_LENGTH, "kg/m", "lb/ft"),
}
#: How a display unit is printed (pint spelling -> label).
_LABELS = {"kN*m": "kN·m", "kft*lbf": "kft·lbf", "kg/m3": "kg/m³"}


@dataclass(frozen=True)
class DisplayUnit:
    """A unit of output: its label and the number of them in one SI unit (``value_si * scale``)."""

    label: str
    scale: float

    def __call__(self, value_si: float) -> float:
        """``value_si`` [SI] in this unit."""
        return value_si * self.scale


def unit_system(choice: str | None = None, name: str = "--units") -> UnitSystem:
    """The unit system of output: ``choice`` when given, else ``$DRILLSTRING_UNITS``, else ``"si"``.

    Raises ``ValueError`` (one line, naming where the value came from: ``name`` for ``choice``) for anything
    but ``si`` or ``field``.
    """
    source = name
    if choice is not None and not isinstance(choice, str):
        raise TypeError(f"{name} = {choice!r}: must be a string, one of {', '.join(UNIT_SYSTEMS)}")
    if choice is None:
        choice, source = os.environ.get(UNITS_ENVIRONMENT, "").strip() or "si", UNITS_ENVIRONMENT
    text = choice.strip().lower()
    if text not in UNIT_SYSTEMS:
        raise ValueError(f"{source} = {choice!r}: must be one of {', '.join(UNIT_SYSTEMS)}")
    return text  # type: ignore[return-value]


def display_unit(kind: str, system: str | None = None) -> DisplayUnit:
    """The unit in which ``system`` (``"si"``, ``"field"``; None: :func:`unit_system`'s default) shows a
    quantity of ``kind`` (``"force"``, ``"length"``, ``"diameter"``, ``"small_length"``,
    ``"rate_of_penetration"``, ``"torque"``, ``"angular_speed"``, ``"density"``, ``"pressure"``, ``"stiffness"``,
    ``"flow"``, ``"mass_per_length"``)."""
    if kind not in _DISPLAY:
        raise ValueError(f"kind = {kind!r}: must be one of {', '.join(_DISPLAY)}")
    return _display_unit(kind, unit_system(system, name="system"))


@functools.lru_cache(maxsize=64)
def _display_unit(kind: str, system: str) -> DisplayUnit:
    dim, si_unit, field_unit = _DISPLAY[kind]
    unit = field_unit if system == "field" else si_unit
    return DisplayUnit(_LABELS.get(unit, unit), 1.0 / unit_factor(unit, dim))


def display_unit_of(si_unit: str, system: str | None = None) -> DisplayUnit:
    """The unit in which ``system`` shows a quantity whose SI unit is ``si_unit`` (as case files write it:
    ``"N"``, ``"m"``, ``"rad/s"``): that of the first output kind of its dimension (:func:`display_unit`;
    a length in m or ft, a velocity in m/h or ft/h); a unit of no output kind (a coefficient) as it is, and
    ``""`` (a plain number) as a plain number."""
    for kind, (dim, _, _) in _DISPLAY.items():
        if dim.si == si_unit:
            return display_unit(kind, system)
    return DisplayUnit(si_unit, 1.0)


def significant(value: float, digits: int = 4) -> str:
    """``value`` with ``digits`` significant digits and thousands separators, without an exponent from 0.001
    to a million (``59,860``, ``0.09439``, ``26.39``), with one outside it (``1.234e-05``)."""
    if value == 0.0 or not math.isfinite(value) or not 1e-3 <= abs(value) < 1e6:
        return format(value, f".{digits}g")
    return format(value, f",.{max(0, digits - 1 - math.floor(math.log10(abs(value))))}f")


#: The unit system of the messages (errors, notes) of the running command: set by the command line's
#: ``--units`` (:func:`message_units`), else :func:`unit_system`'s default.
_MESSAGE_UNITS: ContextVar[str | None] = ContextVar("drillstring_message_units", default=None)


def message_units(system: str | None):
    """Make ``system`` the unit system of :func:`quantity_text` in this context; returns the token that
    ``_MESSAGE_UNITS.reset`` takes to undo it."""
    return _MESSAGE_UNITS.set(system)


def reset_message_units(token) -> None:
    """Undo :func:`message_units` (back to the default where the token belongs to another context)."""
    try:
        _MESSAGE_UNITS.reset(token)
    except ValueError:
        _MESSAGE_UNITS.set(None)


def quantity_text(value_si: float, kind: str, system: str | None = None, digits: int = 4) -> str:
    """``value_si`` [SI] of the output kind ``kind`` as a message shows it, with ``digits`` significant digits
    (``g`` format), in the unit system ``system`` (None: the running command's ``--units``, else
    ``$DRILLSTRING_UNITS``, else si; an unusable ``$DRILLSTRING_UNITS`` is refused elsewhere and reads si
    here): ``"26.39 klbf"``, ``"117.4 kN"``."""
    try:
        unit = display_unit(kind, system or _MESSAGE_UNITS.get())
    except ValueError:
        unit = display_unit(kind, "si")
    return f"{unit(value_si):.{digits}g} {unit.label}"
