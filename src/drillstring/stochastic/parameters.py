"""Numeric case parameters addressed by their case-file path: read one, or set several into a new Case.

A *parameter path* names one number of a :class:`~drillstring.case.Case` as it is written in a case file:
table and key joined by dots, list items by ``[index]`` (from 0), dictionary keys by name, e.g.

    operation.top_speed            fluid.inlet_velocity          bit_rock.a2
    sections[1].outer_diameter     damping.modal_damping_ratio   materials.steel.young_modulus
    mesh.probes[0]                 stabilizers[0].stiffness      materials["high strength"].density

A dictionary key that is not a plain identifier is written in quotes inside brackets. Besides the fields of the
case there is one *derived* parameter, the pseudo-path ``weight_on_hook`` (static hook load, ``weight −
weight_on_bit`` [N], :attr:`Case.weight_on_hook`): setting it sets ``operation.weight_on_bit = weight −
weight_on_hook``, with the weight of the case *after* every other parameter of the same call is set (so a
denser steel and a weight-on-hook can be drawn together).

Values are given as in case files: a plain number in SI units or a ``"value unit"`` string of the field's
dimension (``"120 rpm"``, ``"1.4 m/s"``, ``"120 kN"``). Setting goes through the case's own validation
(:func:`~drillstring.case.case_from_dict` on the case's data with the new values), so units, ranges and the
cross-field rules (``weight_on_bit < weight``, ``outer_diameter < borehole diameter``, ...) are checked exactly
as in a case file, and the result is a new, validated, frozen Case (about 0.1 ms).

Errors
------
Every problem raises :class:`ParameterError` (a ``ValueError``) whose message is one line naming the path,
the value and what is allowed, e.g.

    operation.top_speed = '-5 rpm' (= -0.523598775598 SI): must be > 0
    unknown case parameter 'operation.top_sped': operation has no field 'top_sped'; numeric fields
    there: top_speed, weight_on_bit
    fluid.coriolis is not a numeric parameter (a true/false switch)

What is numeric
---------------
Every ``float`` field of the case (all physical quantities and dimensionless coefficients; each has a
:class:`~drillstring.case.Dimension`) and every ``int`` field (mode counts, ``initial.seed``,
``simulation.max_steps``; :attr:`CaseParameter.integer` is true). Booleans, names and choices
(``model.nonlinear``) are not. :func:`numeric_parameter_paths` lists them all for a case.

This module imports only :mod:`drillstring.case`.
"""

from __future__ import annotations

import difflib
import math
import re
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import annotated_types
from pydantic import BaseModel, BeforeValidator

from drillstring.case import (
    DIMENSIONLESS,
    DIMENSIONS,
    PHYSICAL_BOUNDS,
    Case,
    CaseError,
    Dimension,
    case_from_dict,
    to_si,
)

__all__ = [
    "WEIGHT_ON_HOOK",
    "Bounds",
    "CaseParameter",
    "ParameterError",
    "case_parameter",
    "numeric_parameter_paths",
    "parameter_value",
    "si_unit",
    "with_parameters",
]

#: The derived pseudo-path: weight − weight_on_bit [N].
WEIGHT_ON_HOOK = "weight_on_hook"
_WEIGHT_ON_BIT = "operation.weight_on_bit"
#: The case's [uncertainty] table: laws, not parameters.
_UNCERTAINTY = "uncertainty"

_FORCE = next(d for d in DIMENSIONS if d.name == "force")


class ParameterError(ValueError):
    """A parameter path that names no numeric case parameter, or a value it cannot take (one-line message)."""


# ---------------------------------------------------------------------------------------------------------
# Field ranges
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Bounds:
    """The range a parameter's own field allows, in SI units (cross-field rules are checked when set).

    ``lower``/``upper`` may be infinite; ``*_closed`` says whether the end itself is allowed.
    """

    lower: float = -math.inf
    upper: float = math.inf
    lower_closed: bool = False
    upper_closed: bool = False

    def contains(self, x: float) -> bool:
        """Whether ``x`` (SI) is allowed."""
        above = x >= self.lower if self.lower_closed else x > self.lower
        below = x <= self.upper if self.upper_closed else x < self.upper
        return bool(above and below)

    def describe(self) -> str:
        """``"> 0"``, ``">= 0 and < 1"``, ``"in (0, 1.16e+06)"``-style text, or ``"any number"``."""
        parts = []
        if math.isfinite(self.lower):
            parts.append(f"{'>=' if self.lower_closed else '>'} {self.lower:g}")
        if math.isfinite(self.upper):
            parts.append(f"{'<=' if self.upper_closed else '<'} {self.upper:g}")
        return " and ".join(parts) if parts else "any number"


def _bounds_from_metadata(metadata: typing.Iterable[Any]) -> Bounds:
    lower, upper, lower_closed, upper_closed = -math.inf, math.inf, False, False
    for item in metadata:
        if isinstance(item, annotated_types.Gt):
            lower, lower_closed = float(item.gt), False
        elif isinstance(item, annotated_types.Ge):
            lower, lower_closed = float(item.ge), True
        elif isinstance(item, annotated_types.Lt):
            upper, upper_closed = float(item.lt), False
        elif isinstance(item, annotated_types.Le):
            upper, upper_closed = float(item.le), True
    return Bounds(lower, upper, lower_closed, upper_closed)


# ---------------------------------------------------------------------------------------------------------
# The parameter
# ---------------------------------------------------------------------------------------------------------


def si_unit(dimension: Dimension) -> str:
    """The SI unit of ``dimension`` as written in case files (``"rad/s"``, ``"N"``); ``""`` when
    dimensionless."""
    return dimension.si


@dataclass(frozen=True)
class CaseParameter:
    """One numeric parameter of a case, resolved from its path (see the module docstring).

    Attributes
    ----------
    path:
        The canonical path, e.g. ``"sections[1].outer_diameter"`` or ``"weight_on_hook"``.
    location:
        The keys from the case root to the field, e.g. ``("sections", 1, "outer_diameter")``; ``()`` for
        ``weight_on_hook``.
    dimension:
        The field's :class:`~drillstring.case.Dimension` (units accepted for its values).
    integer:
        True for integer settings (mode counts, seeds, step counts).
    bounds:
        The range the field itself allows [SI]; for ``weight_on_hook``, ``(0, weight)`` of the case it was
        resolved on (gravity on) or ``(-inf, 0)`` (gravity off, the weight is 0).
    description:
        The field's description from the case model (units in brackets), or ``""``.
    """

    path: str
    location: tuple[str | int, ...]
    dimension: Dimension
    integer: bool
    bounds: Bounds
    description: str = ""

    @property
    def unit(self) -> str:
        """The SI unit the values are stored in (``""`` when dimensionless)."""
        return si_unit(self.dimension)

    @property
    def derived(self) -> bool:
        """True for ``weight_on_hook``, which is computed, not stored."""
        return self.location == ()

    def value(self, case: Case) -> float:
        """The parameter's value in ``case`` [SI]."""
        if self.derived:
            return float(case.weight_on_hook)
        node: Any = case
        for item in self.location:
            node = getattr(node, item) if isinstance(item, str) and isinstance(node, BaseModel) else node[item]
        if node is None:  # an optional field left out (e.g. a gain the controller tunes)
            raise ParameterError(f"{self.path} is not set in case {case.name!r} (left out: computed when the "
                                 f"model is built); give it in the case to vary it around a value")
        return float(node)

    def to_si(self, value: Any) -> float:
        """``value`` (a number in SI or a ``"value unit"`` string of the field's dimension) as an SI float.

        Raises :class:`ParameterError` naming the path and the allowed units. The range is not checked here
        (see :meth:`Bounds.contains` and :func:`with_parameters`).
        """
        try:
            return to_si(value, self.dimension)
        except ValueError as exc:
            raise ParameterError(f"{self.path} = {value!r}: {exc}") from None


# ---------------------------------------------------------------------------------------------------------
# Path parsing and resolution
# ---------------------------------------------------------------------------------------------------------

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_\-]*")
_INDEX = re.compile(r"\[\s*(-?\d+)\s*\]")
_QUOTED = re.compile(r"\[\s*(?:\"([^\"]*)\"|'([^']*)')\s*\]")


def _parse_path(path: str) -> tuple[str | int, ...]:
    """``'sections[1].outer_diameter'`` -> ``('sections', 1, 'outer_diameter')``; bracketed quoted names
    are keys (strings), bracketed integers are list indices."""
    if not isinstance(path, str):
        raise ParameterError(f"a parameter path must be a string, got {path!r}")
    text = path.strip()
    items: list[str | int] = []
    pos = 0
    while pos < len(text):
        if items and text[pos] == ".":
            pos += 1
            m = _NAME.match(text, pos)
            if m is None:
                break
            items.append(m.group(0))
            pos = m.end()
            continue
        if not items:
            m = _NAME.match(text, pos)
            if m is not None:
                items.append(m.group(0))
                pos = m.end()
                continue
        m = _INDEX.match(text, pos)
        if m is not None and items:
            items.append(int(m.group(1)))
            pos = m.end()
            continue
        m = _QUOTED.match(text, pos)
        if m is not None and items:
            items.append(m.group(1) if m.group(1) is not None else m.group(2))
            pos = m.end()
            continue
        break
    if pos != len(text) or not items:
        raise ParameterError(
            f"parameter path {path!r} is not of the form table.key, table[index].key or table.key[index] "
            "(e.g. operation.top_speed, sections[1].outer_diameter)"
        )
    return tuple(items)


def _format_path(location: tuple[str | int, ...]) -> str:
    out = ""
    for item in location:
        if isinstance(item, int):
            out += f"[{item}]"
        elif not out:
            out = item
        elif _NAME.fullmatch(item):
            out += f".{item}"
        else:
            out += f'["{item}"]'
    return out


def _unwrap(annotation: Any) -> tuple[Any, list[Any]]:
    """Strip ``Annotated``/``Optional``; return the bare type and the collected metadata."""
    metadata: list[Any] = []
    while True:
        origin = typing.get_origin(annotation)
        if origin is typing.Annotated:
            args = typing.get_args(annotation)
            annotation, metadata = args[0], [*metadata, *args[1:]]
        elif origin is typing.Union:
            args = [a for a in typing.get_args(annotation) if a is not type(None)]
            if len(args) != 1:
                return annotation, metadata
            annotation = args[0]
        else:
            return annotation, metadata


def _dimension_of(metadata: typing.Iterable[Any]) -> Dimension:
    """The dimension of a quantity field: drillstring.case.base names each unit converter ``to_si_<dimension name>``."""
    for item in metadata:
        if isinstance(item, BeforeValidator):
            name = getattr(item.func, "__name__", "")
            for dim in DIMENSIONS:
                if name == f"to_si_{dim.name.replace(' ', '_')}":
                    return dim
    return DIMENSIONLESS


def _kind_name(tp: Any) -> str:
    if tp is bool:
        return "a true/false switch"
    if tp is str:
        return "a name"
    if typing.get_origin(tp) is typing.Literal:
        choices = ", ".join(repr(a) for a in typing.get_args(tp))
        return f"a choice among {choices}"
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return "a table"
    if typing.get_origin(tp) in (list, tuple):
        return "a list; give an index, e.g. [0]"
    if typing.get_origin(tp) is dict:
        return "a table of named entries; give a name"
    return f"of type {getattr(tp, '__name__', tp)}"


def _numeric_fields(model: type[BaseModel]) -> list[str]:
    out = []
    for name, info in model.model_fields.items():
        tp, _ = _unwrap(info.annotation)
        if tp in (float, int):
            out.append(name)
    return out


def _unknown(path: str, where: str, item: Any, choices: typing.Iterable[str], kind: str, kinds: str) -> ParameterError:
    choices = list(choices)
    close = difflib.get_close_matches(str(item), choices, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    listed = ", ".join(choices) or "none"
    return ParameterError(
        f"unknown case parameter {path!r}: {where} has no {kind} {item!r}{hint}; {kinds} there: {listed}"
    )


def case_parameter(case: Case, path: str) -> CaseParameter:
    """Resolve ``path`` on ``case`` (see the module docstring).

    Raises :class:`ParameterError` for a malformed or unknown path, an index out of range, or a field that is
    not numeric.
    """
    text = path.strip() if isinstance(path, str) else path
    if text == WEIGHT_ON_HOOK:
        w = case.weight
        bounds = Bounds(0.0, w) if case.model.gravity else Bounds(-math.inf, 0.0)
        return CaseParameter(
            WEIGHT_ON_HOOK, (), _FORCE, False, bounds, "static hook load, weight - weight_on_bit [N]"
        )
    location = _parse_path(text)
    if location[0] == _UNCERTAINTY:
        raise ParameterError(f"{text} is not a numeric parameter (the [uncertainty] table declares the laws of "
                             "a study's parameters; it is not a parameter itself)")
    node: Any = case
    tp: Any = type(case)
    metadata: list[Any] = []
    description = ""
    for depth, item in enumerate(location):
        where = _format_path(location[:depth]) or "the case"
        if isinstance(node, BaseModel):
            fields = type(node).model_fields
            if not isinstance(item, str) or item not in fields:
                numeric = [n for n in fields if n in _numeric_fields(type(node))]
                tables = [n for n in fields if n not in numeric]
                listed = numeric if numeric else tables
                kind = "numeric field" if numeric else "field"
                raise _unknown(text, where, item, listed, kind, kind + "s")
            info = fields[item]
            tp, metadata = _unwrap(info.annotation)
            metadata = [*metadata, *info.metadata]
            description = info.description or ""
            node = getattr(node, item)
        elif isinstance(node, list):
            if not isinstance(item, int):
                raise ParameterError(
                    f"unknown case parameter {text!r}: {where} is a list; give an index in [0, {len(node) - 1}]"
                )
            if not 0 <= item < len(node):
                raise ParameterError(
                    f"unknown case parameter {text!r}: {where} has {len(node)} item{'s' if len(node) != 1 else ''}, "
                    f"index {item} is not in [0, {len(node) - 1}]"
                )
            tp, metadata = _unwrap(typing.get_args(tp)[0])
            description = ""
            node = node[item]
        elif isinstance(node, dict):
            if not isinstance(item, str) or item not in node:
                raise _unknown(text, where, item, node, "entry", "entries")
            tp, metadata = _unwrap(typing.get_args(tp)[1])
            description = ""
            node = node[item]
        else:
            raise ParameterError(
                f"unknown case parameter {text!r}: {where} is a number and has no {_format_path((item,))!r}"
            )
    canonical = _format_path(location)
    if tp is bool or tp not in (float, int):
        raise ParameterError(f"{canonical} is not a numeric parameter ({_kind_name(tp)})")
    integer = tp is int
    dimension = DIMENSIONLESS if integer else _dimension_of(metadata)
    bounds = _bounds_from_metadata(metadata)
    if location == ("operation", "weight_on_bit") and case.model.gravity:  # the hook cannot push
        bounds = _intersection(bounds, Bounds(0.0, case.weight))
    return CaseParameter(canonical, location, dimension, integer, _intersection(bounds, _physical(location)),
                         description)


def _physical(location: tuple) -> Bounds:
    """The plausible range of the field at ``location`` (:data:`drillstring.case.PHYSICAL_BOUNDS`, where the
    case is refused), or no bound: a law is checked against it before any realization runs."""
    for path, low, high, _ in PHYSICAL_BOUNDS:
        if len(path) == len(location) and all(p == "*" or p == item for p, item in zip(path, location)):
            return Bounds(low, high, True, True)
    return Bounds()


def _intersection(a: Bounds, b: Bounds) -> Bounds:
    """The values both ``a`` and ``b`` allow."""
    if b.lower > a.lower or (b.lower == a.lower and not b.lower_closed):
        lower, lower_closed = b.lower, b.lower_closed
    else:
        lower, lower_closed = a.lower, a.lower_closed
    if b.upper < a.upper or (b.upper == a.upper and not b.upper_closed):
        upper, upper_closed = b.upper, b.upper_closed
    else:
        upper, upper_closed = a.upper, a.upper_closed
    return Bounds(lower, upper, lower_closed, upper_closed)


def parameter_value(case: Case, path: str) -> float:
    """The value of the parameter at ``path`` in ``case`` [SI]."""
    return case_parameter(case, path).value(case)


def numeric_parameter_paths(case: Case, *, integers: bool = True) -> list[str]:
    """Every numeric parameter path of ``case`` (in case-file order), plus ``weight_on_hook`` after
    ``operation.weight_on_bit``; ``integers=False`` leaves out the integer settings; optional fields left
    out (None) are not listed."""
    out: list[str] = []

    def walk(node: Any, location: tuple[str | int, ...]) -> None:
        if isinstance(node, BaseModel):
            for name, info in type(node).model_fields.items():
                if location == () and name == _UNCERTAINTY:
                    continue
                tp, _ = _unwrap(info.annotation)
                value = getattr(node, name)
                if value is None:  # an optional field left out (a gain the controller tunes)
                    continue
                if tp is float or (tp is int and integers):
                    out.append(_format_path((*location, name)))
                    if (*location, name) == ("operation", "weight_on_bit"):
                        out.append(WEIGHT_ON_HOOK)
                elif isinstance(value, (BaseModel, list, dict)):
                    walk(value, (*location, name))
        elif isinstance(node, list):
            for i, value in enumerate(node):
                if isinstance(value, float):
                    out.append(_format_path((*location, i)))
                else:
                    walk(value, (*location, i))
        elif isinstance(node, dict):
            for key, value in node.items():
                walk(value, (*location, key))

    walk(case, ())
    return out


# ---------------------------------------------------------------------------------------------------------
# Setting
# ---------------------------------------------------------------------------------------------------------


def _set_in(data: Any, location: tuple[str | int, ...], value: Any) -> None:
    for item in location[:-1]:
        data = data[item]
    data[location[-1]] = value


def _case_error_line(exc: CaseError) -> str:
    return "; ".join(exc.problems)


def _shown(value: Any, si: float, unit: str) -> str:
    if isinstance(value, str):
        return f"{value!r} (= {si:.6g} {unit})".rstrip()
    return f"{value!r}"


def with_parameters(case: Case, values: Mapping[str, Any]) -> Case:
    """A new validated Case: ``case`` with each parameter ``path -> value`` of ``values`` set.

    ``value`` is a number in SI units or a ``"value unit"`` string, as in case files. Ordinary paths are set
    first and validated together with the whole case; ``weight_on_hook`` is then converted with the weight
    of that new case, ``weight_on_bit = weight − weight_on_hook``. Two spellings of one path, or
    ``weight_on_hook`` together with ``operation.weight_on_bit``, are refused.

    Raises :class:`ParameterError` (one line: the path, the value as given, what is allowed).
    """
    if not isinstance(values, Mapping):
        raise ParameterError(f"parameter values must be a mapping path -> value, got {type(values).__name__}")
    resolved: dict[str, tuple[CaseParameter, Any]] = {}
    for path, value in values.items():
        parameter = case_parameter(case, path)
        if parameter.path in resolved:
            raise ParameterError(f"{parameter.path} is given twice ({path!r})")
        if isinstance(value, bool) or not isinstance(value, (int, float, str)) and not hasattr(value, "__float__"):
            raise ParameterError(
                f"{parameter.path} = {value!r}: must be a number or a \"value unit\" string"
                + (f" (allowed units: {parameter.dimension.allowed})" if parameter.dimension.units else "")
            )
        resolved[parameter.path] = (parameter, value)
    if WEIGHT_ON_HOOK in resolved and _WEIGHT_ON_BIT in resolved:
        raise ParameterError(
            f"{WEIGHT_ON_HOOK} and {_WEIGHT_ON_BIT} cannot both be set: weight_on_hook = weight - weight_on_bit"
        )
    data = case.model_dump(mode="python")
    ordinary = {p: pv for p, pv in resolved.items() if p != WEIGHT_ON_HOOK}
    for parameter, value in ordinary.values():
        if not isinstance(value, (int, float, str)):
            value = float(value)  # numpy scalars
        _set_in(data, parameter.location, value)
    try:
        new = case_from_dict(data, source="<parameters>") if ordinary else case
    except CaseError as exc:
        raise ParameterError(_case_error_line(exc)) from None
    if WEIGHT_ON_HOOK in resolved:
        parameter, value = resolved[WEIGHT_ON_HOOK]
        woh = parameter.to_si(value)
        w = new.weight
        allowed = Bounds(0.0, w) if new.model.gravity else Bounds(-math.inf, 0.0)
        if not allowed.contains(woh):
            rule = (
                f"in (0, {w:.6g}) N (the string's weight {w:.6g} N minus a weight_on_bit in (0, weight))"
                if new.model.gravity
                else "< 0 N (gravity is off: the string weighs nothing and the hook pushes weight_on_bit > 0)"
            )
            raise ParameterError(f"{WEIGHT_ON_HOOK} = {_shown(value, woh, 'N')}: must be {rule}")
        data = new.model_dump(mode="python")
        data["operation"]["weight_on_bit"] = w - woh
        try:
            new = case_from_dict(data, source="<parameters>")
        except CaseError as exc:  # pragma: no cover - the range check above covers the weight rule
            raise ParameterError(f"{WEIGHT_ON_HOOK} = {_shown(value, woh, 'N')}: {_case_error_line(exc)}") from None
    return new
