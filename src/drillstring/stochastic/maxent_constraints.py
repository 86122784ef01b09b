"""The available information of a Maximum-Entropy density: moment constraints and their checks.

A constraint ``E{g(X)} = m`` (eq. (2) of :mod:`drillstring.stochastic.maxent`) is a named function ``g`` and
its value ``m``; the helpers build the reserved ones (mean, second moment, mean of the logarithm) and
:func:`_validate_information` checks that a set of them is admissible on a support (Kapur 1989 §2.2).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

#: Reserved constraint names, used by the helpers and recognised by ``method="auto"``.
MEAN = "mean"
SECOND_MOMENT = "second_moment"
LOG_MEAN = "log_mean"
_RESERVED = (MEAN, SECOND_MOMENT, LOG_MEAN)


# ---------------------------------------------------------------------------------------------------------
# Constraints
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Constraint:
    """One moment constraint ``E{g(X)} = m`` of the available information, eq. (2).

    Attributes
    ----------
    function:
        ``g``, a vectorised callable ``ndarray -> ndarray`` of the same shape (units: those of ``value``).
        Module-level functions keep the constraint picklable (for process/Dask workers).
    value:
        ``m``, the prescribed mean value of ``g(X)`` (units of ``g``, e.g. N for a mean force, N² for a
        second moment of a force).
    name:
        A label. The names ``"mean"``, ``"second_moment"`` and ``"log_mean"`` are reserved for the helpers
        :func:`mean`, :func:`second_moment` and :func:`log_mean`: they are validated as such and used by
        ``maximum_entropy(method="auto")`` to recognise closed forms.
    """

    function: Callable[[np.ndarray], np.ndarray]
    value: float
    name: str

    def __post_init__(self) -> None:
        if not callable(self.function):
            raise TypeError(f"Constraint.function must be callable, got {type(self.function).__name__}")
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Constraint.name must be a non-empty string, got {self.name!r}")
        try:
            value = float(self.value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"constraint {self.name!r}: value must be a real number, got {self.value!r}") from exc
        if not math.isfinite(value):
            raise ValueError(f"constraint {self.name!r}: value = {value!r} must be finite")
        object.__setattr__(self, "value", value)

    def evaluate(self, x: np.ndarray) -> np.ndarray:
        """``g(x)`` as a float array of the shape of ``x`` (non-finite values are returned as such)."""
        x = np.asarray(x, dtype=float)
        with np.errstate(all="ignore"):
            out = np.asarray(self.function(x), dtype=float)
        if out.shape != x.shape:
            try:
                out = np.broadcast_to(out, x.shape).copy()
            except ValueError as exc:
                raise ValueError(
                    f"constraint {self.name!r}: function returned shape {out.shape} for input shape {x.shape}"
                ) from exc
        return out


def _identity(x: np.ndarray) -> np.ndarray:
    return np.asarray(x, dtype=float)


def _square(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return x * x


def _log(x: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(np.asarray(x, dtype=float))


def mean(m: float) -> Constraint:
    """Constraint ``E{X} = m`` (units of ``X``), named ``"mean"``."""
    return Constraint(_identity, m, MEAN)


def second_moment(m2: float) -> Constraint:
    """Constraint ``E{X²} = m2`` (units of ``X`` squared), named ``"second_moment"``."""
    return Constraint(_square, m2, SECOND_MOMENT)


def log_mean(m: float) -> Constraint:
    """Constraint ``E{ln X} = m`` (``X`` in its own unit, ``m`` dimensionless), named ``"log_mean"``.

    Only meaningful on a positive support; with ``E{X}`` it gives the Gamma law.
    """
    return Constraint(_log, m, LOG_MEAN)


def variance_constraints(mean: float, std: float) -> tuple[Constraint, Constraint]:
    """``E{X} = mean`` and ``E{X²} = mean² + std²``: a known mean and standard deviation ``std > 0``
    (both in units of ``X``)."""
    mean_value = float(mean)
    std_value = float(std)
    if not math.isfinite(mean_value):
        raise ValueError(f"mean = {mean!r} must be finite")
    if not (math.isfinite(std_value) and std_value > 0.0):
        raise ValueError(f"standard deviation std = {std!r} must be finite and > 0 (allowed range: (0, inf))")
    return (
        Constraint(_identity, mean_value, MEAN),
        Constraint(_square, mean_value * mean_value + std_value * std_value, SECOND_MOMENT),
    )


# ---------------------------------------------------------------------------------------------------------
# Validation of the information
# ---------------------------------------------------------------------------------------------------------


def _check_support(support: Sequence[float]) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in support)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"support must be a pair (a, b) of real numbers, got {support!r}") from exc
    if math.isnan(a) or math.isnan(b):
        raise ValueError(f"support = ({a}, {b}) contains NaN")
    if a == math.inf or b == -math.inf or not a < b:
        raise ValueError(f"support = ({a}, {b}) is empty: it needs a < b (a may be -inf, b may be +inf)")
    return a, b


def _named(constraints: Sequence[Constraint]) -> dict[str, float]:
    values: dict[str, float] = {}
    for c in constraints:
        if not isinstance(c, Constraint):
            raise TypeError(f"constraints must be Constraint objects, got {type(c).__name__}")
        if c.name in _RESERVED:
            if c.name in values:
                raise ValueError(f"constraint {c.name!r} is given twice")
            values[c.name] = c.value
    return values


def _validate_information(a: float, b: float, constraints: Sequence[Constraint]) -> dict[str, float]:
    """Check that the reserved-name information is possible on ``[a, b]``; return it by name."""
    named = _named(constraints)
    bounded = math.isfinite(a) and math.isfinite(b)
    m = named.get(MEAN)
    if m is not None and not a < m < b:
        raise ValueError(
            f"mean = {m!r} is outside the support: it must lie strictly inside ({a}, {b})"
        )
    m2 = named.get(SECOND_MOMENT)
    if m2 is not None:
        if m is not None:
            var = m2 - m * m
            if not var > 0.0:
                raise ValueError(
                    f"variance = second_moment - mean**2 = {var!r} (second_moment = {m2!r}, mean = {m!r}) "
                    f"must be > 0 (allowed range: (0, inf))"
                )
            if bounded:
                bound = (b - m) * (m - a)
                if not var < bound:
                    raise ValueError(
                        f"variance = {var!r} is too large for the support [{a}, {b}] with mean = {m!r}: "
                        f"allowed range (0, (b - mean)(mean - a)) = (0, {bound!r})"
                    )
        else:
            lo = 0.0 if a <= 0.0 <= b else min(a * a, b * b)
            hi = max(a * a, b * b)
            if not lo < m2 < hi:
                raise ValueError(
                    f"second_moment = {m2!r} is impossible on the support [{a}, {b}]: "
                    f"allowed range ({lo!r}, {hi!r})"
                )
    lm = named.get(LOG_MEAN)
    if lm is not None:
        if a < 0.0:
            raise ValueError(
                f"log_mean E{{ln X}} needs a positive support (a >= 0), got support = ({a}, {b})"
            )
        lo = math.log(a) if a > 0.0 else -math.inf
        hi = math.log(b) if math.isfinite(b) else math.inf
        if m is not None:
            hi = min(hi, math.log(m))
            if not lm < hi:
                raise ValueError(
                    f"log_mean E{{ln X}} = {lm!r} must be < ln(mean) = {math.log(m)!r} (Jensen's inequality; "
                    f"equality only for a constant X): allowed range ({lo!r}, {hi!r})"
                )
        if not lo < lm < hi:
            raise ValueError(f"log_mean E{{ln X}} = {lm!r} is outside the allowed range ({lo!r}, {hi!r})")
    return named

