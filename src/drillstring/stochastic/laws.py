"""One uncertain parameter's law from its declared information: the spec syntax (``"normal 100 5 rpm"``,
``{law = "uniform", min = 1.2, max = 1.8}``) read into a support and moment constraints, and the
Maximum-Entropy density under them (see :mod:`drillstring.stochastic.uncertainty` for the syntax and the
table of laws).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from scipy import special

from drillstring.case import Dimension, to_si
from drillstring.stochastic.maxent import (
    Constraint,
    MaxEntDensity,
    log_mean,
    maximum_entropy,
    mean,
    variance_constraints,
)

__all__ = ["LAWS", "OUT_OF_RANGE_TOLERANCE", "ParameterLaw", "parse_law"]

#: Largest probability a law may put outside its parameter's range.
OUT_OF_RANGE_TOLERANCE = 1e-6

#: Smallest point, and distance of the largest from 1, of the unit interval that a law maps (its quantiles).
UNIT_INTERVAL_MARGIN = 2.0**-53  # smallest / (1 − largest) point of the unit interval that is mapped


@dataclass(frozen=True)
class _Form:
    positional: tuple[str, ...]
    keys: frozenset[str]
    canonical_positional: bool  # write the positional form in to_spec
    example: str


#: The laws of the spec syntax: positional keys, allowed keys (see the module docstring).
LAWS: dict[str, _Form] = {
    "uniform": _Form(("min", "max"), frozenset({"min", "max"}), True, "uniform 1.2 1.8 m/s"),
    "normal": _Form(("mean", "std"), frozenset({"mean", "std"}), True, "normal 100 5 rpm"),
    "exponential": _Form(("mean",), frozenset({"mean", "min"}), True, "exponential 2 mm"),
    "gamma": _Form(
        ("mean", "std"), frozenset({"mean", "std", "log_mean"}), False, "gamma mean=5.7e-8 std=0.6e-8"
    ),
    "maxent": _Form(
        (), frozenset({"min", "max", "mean", "std", "log_mean"}), False, "maxent min=1.2 max=1.8 mean=1.4 m/s"
    ),
}
_KEY_ORDER = ("min", "max", "mean", "std", "log_mean")
_NUMBER = re.compile(r"^[+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|inf|infinity)$", re.IGNORECASE)


def _fmt(x: float) -> str:
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


# ---------------------------------------------------------------------------------------------------------
# One law
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ParameterLaw:
    """A law as declared (in the declared unit) and the Maximum-Entropy density it defines (in SI).

    Attributes
    ----------
    law:
        ``"uniform"``, ``"normal"``, ``"exponential"``, ``"gamma"`` or ``"maxent"``.
    declared:
        The declared numbers ``(key, value)`` in the declared unit, in the order min, max, mean, std, log_mean.
    unit:
        The declared unit (``""``: SI).
    support:
        ``(a, b)`` in SI, ends possibly infinite.
    constraints:
        The moment constraints in SI (``mean``, ``second_moment``, ``log_mean``).
    density:
        The :class:`~drillstring.stochastic.maxent.MaxEntDensity` (SI); ``density.kind`` names the law found.
    """

    law: str
    declared: tuple[tuple[str, float], ...]
    unit: str
    support: tuple[float, float] = field(compare=False)
    constraints: tuple[Constraint, ...] = field(compare=False, repr=False)
    density: MaxEntDensity = field(compare=False, repr=False)

    @property
    def value(self) -> dict[str, float]:
        """The declared numbers by key (declared unit)."""
        return dict(self.declared)

    def to_spec(self) -> str:
        """The canonical spec string; :func:`parse_law` reads it back to an equal law."""
        form = LAWS[self.law]
        values = self.value
        words = [self.law]
        if form.canonical_positional:
            words += [_fmt(values[k]) for k in form.positional]
            words += [f"{k}={_fmt(v)}" for k, v in self.declared if k not in form.positional]
        else:
            words += [f"{k}={_fmt(v)}" for k, v in self.declared]
        if self.unit:
            words.append(self.unit)
        return " ".join(words)

    def to_mapping(self) -> dict[str, Any]:
        """The table form ``{"law": ..., key: value, ..., "unit": ...}`` (declared unit)."""
        out: dict[str, Any] = {"law": self.law, **self.value}
        if self.unit:
            out["unit"] = self.unit
        return out

    def __str__(self) -> str:
        return self.to_spec()


def _tokens(spec: str) -> tuple[str, list[str]]:
    text = re.sub(r"\s*=\s*", "=", spec.strip())
    words = text.split()
    if not words:
        raise ValueError(f"empty law; write LAW NUMBERS [UNIT], e.g. {LAWS['uniform'].example!r}")
    return words[0].lower(), words[1:]


def _read_spec(spec: str) -> tuple[str, list[tuple[str | None, float]], str]:
    """``(law, [(key or None for positional, number)], unit)`` from a spec string."""
    law, words = _tokens(spec)
    args: list[tuple[str | None, float]] = []
    unit_words: list[str] = []
    for word in words:
        key, _, number = word.rpartition("=") if "=" in word else (None, "", word)
        if _NUMBER.match(number) and not unit_words:
            if key is not None and not key:
                raise ValueError(f"'{word}' has no key before '='")
            args.append((key, float(number)))
        elif _NUMBER.match(number):
            raise ValueError(f"'{word}' comes after the unit '{' '.join(unit_words)}': write the unit once, last")
        elif key is not None:
            raise ValueError(f"'{word}': the value of {key} must be a number (the unit goes once, at the end)")
        else:
            unit_words.append(word)
    return law, args, " ".join(unit_words)


def _read_mapping(spec: Mapping[str, Any]) -> tuple[str, list[tuple[str | None, float]], str]:
    if "law" not in spec:
        raise ValueError(f"a law table needs a 'law' key ({', '.join(LAWS)}), got keys {', '.join(spec) or 'none'}")
    law = str(spec["law"]).lower()
    unit = spec.get("unit", "")
    if not isinstance(unit, str):
        raise ValueError(f"unit = {unit!r} must be a string")
    args: list[tuple[str | None, float]] = []
    for key, value in spec.items():
        if key in ("law", "unit"):
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{key} = {value!r} must be a number (the unit goes in the 'unit' key)")
        args.append((str(key), float(value)))
    return law, args, unit


def _assign(law: str, args: list[tuple[str | None, float]]) -> dict[str, float]:
    if law not in LAWS:
        raise ValueError(f"unknown law {law!r}; laws: {', '.join(LAWS)}")
    form = LAWS[law]
    values: dict[str, float] = {}
    positional = [v for k, v in args if k is None]
    if len(positional) > len(form.positional):
        expected = " ".join(form.positional) if form.positional else "no positional numbers (use key=value)"
        raise ValueError(f"{law} takes {expected}, got {len(positional)} numbers")
    for key, v in zip(form.positional, positional):
        values[key] = v
    for key, v in args:
        if key is None:
            continue
        if key not in form.keys:
            allowed = ", ".join(k for k in _KEY_ORDER if k in form.keys)
            raise ValueError(f"{law} has no key {key!r}; its keys: {allowed}")
        if key in values:
            raise ValueError(f"{key} is given twice")
        values[key] = v
    return values


def _information(law: str, v: dict[str, float]) -> tuple[tuple[float, float], tuple[Constraint, ...]]:
    """Support and constraints (declared unit, log_mean still in it) of a law's declared numbers."""

    def need(*keys: str) -> None:
        missing = [k for k in keys if k not in v]
        if missing:
            raise ValueError(
                f"{law} needs {' and '.join(keys)} (missing {', '.join(missing)}), e.g. {LAWS[law].example!r}"
            )

    for key, x in v.items():
        if key in ("min", "max"):
            if math.isnan(x):
                raise ValueError(f"{key} = nan must be a number")
        elif not math.isfinite(x):
            raise ValueError(f"{key} = {x!r} must be finite")
    if "std" in v and not v["std"] > 0.0:
        raise ValueError(f"std = {_fmt(v['std'])} must be > 0")
    lo, hi = v.get("min", -math.inf), v.get("max", math.inf)
    if law == "exponential" and "min" not in v:
        lo = 0.0
    if not lo < hi:
        raise ValueError(f"min = {_fmt(lo)} must be less than max = {_fmt(hi)}")
    if "mean" in v and not lo < v["mean"] < hi and law not in ("normal", "gamma"):
        raise ValueError(f"mean = {_fmt(v['mean'])} must lie strictly between min = {_fmt(lo)} and max = {_fmt(hi)}")
    if law == "uniform":
        need("min", "max")
        if not (math.isfinite(v["min"]) and math.isfinite(v["max"])):
            raise ValueError("uniform needs finite min and max")
        return (v["min"], v["max"]), ()
    if law == "normal":
        need("mean", "std")
        return (-math.inf, math.inf), variance_constraints(v["mean"], v["std"])
    if law == "exponential":
        need("mean")
        lo = v.get("min", 0.0)
        if not math.isfinite(lo):
            raise ValueError(f"min = {lo!r} must be finite for an exponential law")
        return (lo, math.inf), (mean(v["mean"]),)
    if law == "gamma":
        need("mean")
        if ("std" in v) == ("log_mean" in v):
            raise ValueError(
                "gamma needs mean and exactly one of std and log_mean, e.g. 'gamma mean=5.7e-8 std=0.6e-8'"
            )
        m = v["mean"]
        if not m > 0.0:
            raise ValueError(f"mean = {_fmt(m)} must be > 0 for a gamma law (support (0, inf))")
        if "std" in v:
            k = (m / v["std"]) ** 2
            lm = float(special.digamma(k)) + math.log(v["std"] ** 2 / m)
        else:
            lm = v["log_mean"]
        return (0.0, math.inf), (mean(m), log_mean(lm))
    # maxent: the information as declared
    support = (v.get("min", -math.inf), v.get("max", math.inf))
    constraints: list[Constraint] = []
    if "std" in v:
        need("mean")
        constraints += variance_constraints(v["mean"], v["std"])
    elif "mean" in v:
        constraints.append(mean(v["mean"]))
    if "log_mean" in v:
        constraints.append(log_mean(v["log_mean"]))
    return support, tuple(constraints)


def _to_si_information(
    support: tuple[float, float], constraints: tuple[Constraint, ...], unit: str, dimension: Dimension
) -> tuple[tuple[float, float], tuple[Constraint, ...]]:
    factor = to_si(f"1 {unit}", dimension) if unit else 1.0
    if factor == 1.0:
        return support, constraints
    a, b = (x * factor for x in support)
    out = []
    for c in constraints:
        if c.name == "mean":
            out.append(Constraint(c.function, c.value * factor, c.name))
        elif c.name == "second_moment":
            out.append(Constraint(c.function, c.value * factor * factor, c.name))
        elif c.name == "log_mean":
            out.append(Constraint(c.function, c.value + math.log(factor), c.name))
        else:  # pragma: no cover - only reserved constraints are built here
            raise AssertionError(c.name)
    return (a, b), tuple(out)


def parse_law(spec: str | Mapping[str, Any], dimension: Dimension) -> ParameterLaw:
    """Parse a law spec (string or table, see the module docstring) for a quantity of ``dimension``.

    Raises ``ValueError`` with a one-line explanation (the problem and what is allowed). Use
    :meth:`Uncertainty` / :func:`uncertainty` to bind a law to a case parameter with its range checked.
    """
    if isinstance(spec, str):
        law, args, unit = _read_spec(spec)
    elif isinstance(spec, Mapping):
        law, args, unit = _read_mapping(spec)
    else:
        raise ValueError(f"a law must be a string such as {LAWS['uniform'].example!r} or a table, got {spec!r}")
    values = _assign(law, args)
    if unit:
        to_si(f"1 {unit}", dimension)  # the unit's own error names the allowed units
    support, constraints = _information(law, values)
    support, constraints = _to_si_information(support, constraints, unit, dimension)
    density = maximum_entropy(support, constraints)
    declared = tuple((k, values[k]) for k in _KEY_ORDER if k in values)
    return ParameterLaw(law, declared, unit, density.support, constraints, density)


