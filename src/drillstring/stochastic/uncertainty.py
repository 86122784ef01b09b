"""Uncertain case parameters: laws built by the Maximum Entropy Principle from declared information.

Any numeric case parameter (by its path, :mod:`drillstring.stochastic.parameters`, including the derived
``weight_on_hook``) may be declared uncertain. What the user declares is *information* — a support, a mean,
a standard deviation or a log-mean — and the law is the Maximum-Entropy density under that information
(:func:`~drillstring.stochastic.maxent.maximum_entropy`; Jaynes 1957, Kapur 1989, Soize 2017 ch. 5). The law
names below are shorthands for the classical information sets, whose MaxEnt laws are known in closed form;
``maxent`` states the information directly and covers every other set through the numerical dual.

Spec syntax
-----------
One string, usable as a case-file value and on the command line::

    SPEC := LAW ARG* [UNIT]        ARG := NUMBER | KEY=NUMBER        KEY := min | max | mean | std | log_mean

    "uniform 1.2 1.8 m/s"          "normal 100 5 rpm"              "exponential 2 mm"
    "gamma mean=5.7e-8 std=0.6e-8" "gamma mean=5.7e-8 log_mean=-16.7"
    "maxent min=1.2 max=1.8 mean=1.4 m/s"    "maxent min=1.2 max=1.8 mean=1.4 std=0.1 m/s"

Positional numbers fill the law's keys in order (table below); ``key=value`` gives any allowed key. One unit,
last, applies to every number (``min``, ``max``, ``mean``, ``std`` scale with it; ``log_mean = E{ln(X/unit)}``
shifts by ``ln`` of the unit's SI factor). The unit must be of the parameter's dimension (the units of case
files, :data:`drillstring.case.DIMENSIONS`); without a unit the numbers are SI. The same information may be
given as a table, e.g. in TOML ``{law = "uniform", min = 1.2, max = 1.8, unit = "m/s"}``.

=================  ===============  ==============================  ========================================
law                positional       information (support; moments)  Maximum-Entropy law
=================  ===============  ==============================  ========================================
``uniform``        ``min max``      ``[min, max]``; none            uniform
``normal``         ``mean std``     ``ℝ``; ``E{X}``, ``E{X²}``      normal ``N(mean, std²)``
``exponential``    ``mean``         ``[min, ∞)`` (``min`` key,      exponential shifted to ``min``
                                    default 0); ``E{X}``
``gamma``          ``mean std``     ``(0, ∞)``; ``E{X}``,           gamma, shape ``k`` from
                                    ``E{ln X}``                     ``ln k − ψ(k) = ln E{X} − E{ln X}``
``maxent``         (keys only)      ``[min, max]`` (defaults        closed form when the set is one of the
                                    ``−∞``, ``+∞``) and any of      above, else the numerical dual: bounded
                                    ``mean``, ``std``,              + mean -> truncated exponential; bounded
                                    ``log_mean``                    (or ``[0, ∞)``) + mean + std ->
                                                                    truncated normal
=================  ===============  ==============================  ========================================

Which information gives the gamma law: on ``(0, ∞)`` the MaxEnt law under a mean and a *log-mean* is the
gamma law. ``gamma mean=M std=S`` declares the same information with the log-mean chosen so that the law has
standard deviation ``S``: ``E{ln X} = ψ(k) + ln θ`` with ``k = (M/S)²``, ``θ = S²/M`` — i.e. the gamma law of
mean ``M`` and standard deviation ``S``. A mean and a standard deviation *alone* on ``(0, ∞)``
(``maxent min=0 mean=M std=S``) give another law, the normal truncated to ``[0, ∞)`` (which exists only for
``S < M``).

A law must respect the parameter's range (:class:`~drillstring.stochastic.parameters.Bounds`: the field's own
range within its plausible range, ``drillstring.case.PHYSICAL_BOUNDS``): a law whose probability outside the
range exceeds :data:`OUT_OF_RANGE_TOLERANCE` is refused (e.g. a normal top speed whose standard deviation is
comparable with its mean); use a law on a bounded or positive support instead. The case itself must accept
the law's quantiles at that tolerance (its cross-field rules: a collar diameter below the borehole's), all
checked when the law is declared, before any realization.
Integer settings cannot carry a continuous law.

Joint laws
----------
Parameters are independent unless a correlation matrix is declared for a subset of *normal* parameters:
the MaxEnt density on ``ℝⁿ`` under a mean vector ``μ`` and a covariance matrix ``C`` is the multivariate
normal ``N(μ, C)`` (Kapur 1989; Soize 2017 ch. 5), here with ``C = D R D``, ``D = diag(std)`` and ``R`` the
declared correlation matrix (symmetric, unit diagonal, positive definite). Correlating laws other than the
normal is refused: their MaxEnt joint law under a covariance is no longer of a known form, and a copula would
not be a MaxEnt law. In a table::

    [uncertainty.parameters]
    "operation.top_speed" = "normal 100 5 rpm"
    weight_on_hook = "normal 1063.4 5 kN"
    [uncertainty.correlation]
    parameters = ["operation.top_speed", "weight_on_hook"]
    matrix = [[1.0, -0.3], [-0.3, 1.0]]

Sampling
--------
All draws are the image of points of the unit hypercube ``(0, 1)^k`` (:meth:`Uncertainty.from_unit`):
independent parameters by their inverse distribution functions ``x_j = F_j⁻¹(u_j)``; a correlated normal
group by ``x = μ + D L Φ⁻¹(u)`` with ``L`` the Cholesky factor of ``R``. Monte Carlo realization ``i`` of a
study seeded ``s`` takes ``u = rng.random(k)`` from its own stream
:func:`~drillstring.stochastic.maxent.realization_generator` ``(s, i)`` (:meth:`Uncertainty.draw`), so a
realization's values depend only on ``(s, i)`` and the declaration: not on workers, order or resumption.
The Sobol' sampler (:mod:`drillstring.stochastic.sensitivity`) maps its Saltelli design through the same
function. ``u`` is clipped to ``[2⁻⁵³, 1 − 2⁻⁵³]`` so that infinite ends are never returned.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import linalg, stats

from drillstring.case import Case
from drillstring.stochastic.maxent import (
    realization_generator,
)
from drillstring.stochastic.parameters import CaseParameter, ParameterError, case_parameter, with_parameters

__all__ = [
    "LAWS",
    "OUT_OF_RANGE_TOLERANCE",
    "ParameterLaw",
    "UncertainParameter",
    "Uncertainty",
    "correlation_table",
    "declared_uncertainty",
    "input_attributes",
    "parse_law",
    "split_assignment",
    "split_correlation",
    "uncertainty",
]

from drillstring.stochastic.laws import (
    LAWS,
    OUT_OF_RANGE_TOLERANCE,
    UNIT_INTERVAL_MARGIN,
    ParameterLaw,
    parse_law,
)

# ---------------------------------------------------------------------------------------------------------
# Uncertain parameters of a case
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class UncertainParameter:
    """A case parameter and its law."""

    parameter: CaseParameter
    law: ParameterLaw

    @property
    def path(self) -> str:
        return self.parameter.path


def _check_range(parameter: CaseParameter, law: ParameterLaw, spec_text: str,
                 tolerance: float = OUT_OF_RANGE_TOLERANCE) -> None:
    bounds = parameter.bounds
    density = law.density
    below = float(density.cdf(bounds.lower)) if math.isfinite(bounds.lower) else 0.0
    above = 1.0 - float(density.cdf(bounds.upper)) if math.isfinite(bounds.upper) else 0.0
    outside = below + above
    if outside > tolerance:
        unit = f" {parameter.unit}" if parameter.unit else ""
        raise ParameterError(
            f"{parameter.path} = {spec_text!r}: the law puts probability {outside:.3g} outside the allowed range "
            f"({bounds.describe()}{unit}); allowed: at most {tolerance:g}, e.g. a law whose support lies "
            "inside the range (uniform, gamma, exponential, maxent min=... max=...)"
        )


#: Case parameters that cannot be random, and why: every run of a study or sensitivity design is kept on
#: the run's one time grid and probe positions (its settings, not the drawn case), so a drawn value would be
#: recorded but have no effect.
NOT_DRAWN = {
    "simulation.t_end": "every run of a study keeps the study's one time grid (give t_end, --t-end, instead)",
    "simulation.output_step": "every run of a study keeps the study's one time grid (give output_step instead)",
    "mesh.probes": "the runs' displacements are stored at the case's probe positions",
}


def _bind(case: Case, path: str, spec: str | Mapping[str, Any],
          tolerance: float = OUT_OF_RANGE_TOLERANCE) -> UncertainParameter:
    parameter = case_parameter(case, path)
    text = spec if isinstance(spec, str) else repr(dict(spec)) if isinstance(spec, Mapping) else repr(spec)
    fixed = next((why for name, why in NOT_DRAWN.items()
                  if parameter.path == name or parameter.path.startswith(name + "[")), None)
    if fixed is not None:
        raise ParameterError(f"{parameter.path} = {text!r}: cannot be random: {fixed}")
    if parameter.integer:
        raise ParameterError(
            f"{parameter.path} = {text!r}: an integer setting cannot carry a continuous law"
        )
    try:
        law = parse_law(spec, parameter.dimension)
    except ValueError as exc:
        raise ParameterError(f"{parameter.path} = {text!r}: {exc}".replace("\n", " ")) from None
    _check_range(parameter, law, text, tolerance)
    _check_case_at_extremes(case, parameter, law, text, tolerance)
    return UncertainParameter(parameter, law)


def _check_case_at_extremes(case: Case, parameter: CaseParameter, law: ParameterLaw, spec_text: str,
                            tolerance: float) -> None:
    """Refuse, before any realization, a law whose draws the *case* refuses more often than ``tolerance``:
    the case is validated with the parameter at the law's ``tolerance`` and ``1 − tolerance`` quantiles
    (every other value nominal), so that the cross-field rules count too (a collar diameter reaching the
    borehole's, a lateral perturbation reaching the gap), not only the field's own range."""
    if tolerance >= 0.5:
        return
    for q in (tolerance, 1.0 - tolerance):
        value = float(law.density.ppf(q))
        if not math.isfinite(value):
            continue
        try:
            with_parameters(case, {parameter.path: value})
        except ParameterError as error:
            unit = f" {parameter.unit}" if parameter.unit else ""
            reason = str(error).split(": ", 1)[-1]
            raise ParameterError(
                f"{parameter.path} = {spec_text!r}: the case refuses the law's {q:.6g} quantile, {value:.6g}{unit} "
                f"({reason}); allowed: a law whose draws the case accepts but for a share of at most "
                f"{tolerance:g}") from None


class Uncertainty:
    """The declared uncertain parameters of a case and their joint law (see the module docstring).

    Build it with :func:`uncertainty` or :meth:`from_mapping`. ``parameters`` keeps the declaration order,
    which is the column order of every value array ``(n, k)`` (SI units) and of the unit hypercube.
    """

    def __init__(
        self,
        parameters: Sequence[UncertainParameter],
        correlated: Sequence[str] = (),
        correlation: Any = None,
    ) -> None:
        self.parameters: tuple[UncertainParameter, ...] = tuple(parameters)
        if not self.parameters:
            raise ParameterError("no uncertain parameter declared")
        paths = [p.path for p in self.parameters]
        if len(set(paths)) != len(paths):
            twice = sorted({p for p in paths if paths.count(p) > 1})
            raise ParameterError(f"parameter {', '.join(twice)} is declared twice")
        self.paths: tuple[str, ...] = tuple(paths)
        self.correlated: tuple[str, ...] = tuple(correlated)
        self.correlation: np.ndarray | None = None
        self._group: np.ndarray = np.zeros(0, dtype=int)
        self._cholesky: np.ndarray | None = None
        if self.correlated or correlation is not None:
            self._set_correlation(list(self.correlated), correlation)

    # -- construction ------------------------------------------------------------------------------------

    def _set_correlation(self, names: list[str], matrix: Any) -> None:
        index = {p: j for j, p in enumerate(self.paths)}
        resolved = []
        for name in names:
            key = name.strip() if isinstance(name, str) else name
            if key not in index:
                raise ParameterError(
                    f"correlation.parameters: {name!r} is not a declared uncertain parameter; "
                    f"declared: {', '.join(self.paths)}"
                )
            resolved.append(key)
        if len(set(resolved)) != len(resolved):
            raise ParameterError(f"correlation.parameters = {names!r}: a parameter is listed twice")
        if len(resolved) < 2:
            raise ParameterError(f"correlation.parameters = {names!r}: a correlation needs at least 2 parameters")
        for name in resolved:
            law = self.parameters[index[name]].law
            if law.law != "normal":
                raise ParameterError(
                    f"correlation.parameters: {name} has law {law.to_spec()!r}; only normal parameters can be "
                    "correlated (the MaxEnt law under a mean vector and a covariance is the multivariate normal)"
                )
        try:
            r = np.array(matrix, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(f"correlation.matrix = {matrix!r} must be a square table of numbers") from None
        n = len(resolved)
        if r.shape != (n, n):
            raise ParameterError(
                f"correlation.matrix has shape {r.shape}; it must be {n} x {n} (one row per parameter)"
            )
        if not np.all(np.isfinite(r)):
            raise ParameterError("correlation.matrix must hold finite numbers")
        if not np.allclose(r, r.T, rtol=0.0, atol=1e-12):
            i, j = np.unravel_index(np.argmax(np.abs(r - r.T)), r.shape)
            raise ParameterError(
                f"correlation.matrix[{i}][{j}] = {r[i, j]:g} differs from [{j}][{i}] = {r[j, i]:g}: "
                "it must be symmetric"
            )
        if not np.allclose(np.diag(r), 1.0, rtol=0.0, atol=1e-12):
            i = int(np.argmax(np.abs(np.diag(r) - 1.0)))
            raise ParameterError(f"correlation.matrix[{i}][{i}] = {r[i, i]:g}: the diagonal must be 1")
        if np.any(np.abs(r) > 1.0):
            i, j = np.unravel_index(np.argmax(np.abs(r)), r.shape)
            raise ParameterError(f"correlation.matrix[{i}][{j}] = {r[i, j]:g} must be in [-1, 1]")
        r = 0.5 * (r + r.T)
        smallest = float(np.linalg.eigvalsh(r)[0])
        if not smallest > 1e-12:
            raise ParameterError(
                f"correlation.matrix must be positive definite (smallest eigenvalue {smallest:.3g}): a singular "
                "correlation leaves no density, drop a parameter that is a combination of others"
            )
        self.correlated = tuple(resolved)
        self.correlation = r
        self._group = np.array([index[p] for p in resolved], dtype=int)
        self._cholesky = linalg.cholesky(r, lower=True)

    @classmethod
    def from_mapping(cls, case: Case, mapping: Mapping[str, Any], *,
                     tolerance: float = OUT_OF_RANGE_TOLERANCE) -> Uncertainty:
        """From the table form ``{"parameters": {path: spec}, "correlation": {"parameters": [...],
        "matrix": [[...]]}}`` (the ``[uncertainty]`` table of the module docstring)."""
        if not isinstance(mapping, Mapping):
            raise ParameterError(f"uncertainty must be a table, got {type(mapping).__name__}")
        unknown = [k for k in mapping if k not in ("parameters", "correlation")]
        if unknown:
            raise ParameterError(f"uncertainty.{unknown[0]}: unknown key; allowed keys here: parameters, correlation")
        parameters = mapping.get("parameters")
        if not isinstance(parameters, Mapping) or not parameters:
            raise ParameterError("uncertainty.parameters must be a non-empty table path = law")
        correlation = mapping.get("correlation")
        if correlation is None:
            return uncertainty(case, parameters, tolerance=tolerance)
        if not isinstance(correlation, Mapping) or set(correlation) != {"parameters", "matrix"}:
            raise ParameterError("uncertainty.correlation must be a table with exactly the keys parameters and matrix")
        return uncertainty(case, parameters, correlated=correlation["parameters"], correlation=correlation["matrix"],
                           tolerance=tolerance)

    def to_mapping(self) -> dict[str, Any]:
        """The table form (declared units); :meth:`from_mapping` reads it back to an equal Uncertainty."""
        out: dict[str, Any] = {"parameters": {p.path: p.law.to_spec() for p in self.parameters}}
        if self.correlation is not None:
            out["correlation"] = {"parameters": list(self.correlated), "matrix": self.correlation.tolist()}
        return out

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Uncertainty):
            return NotImplemented
        same_corr = (self.correlation is None and other.correlation is None) or (
            self.correlation is not None
            and other.correlation is not None
            and self.correlated == other.correlated
            and np.array_equal(self.correlation, other.correlation)
        )
        return self.paths == other.paths and [p.law for p in self.parameters] == [
            p.law for p in other.parameters
        ] and same_corr

    def __repr__(self) -> str:
        laws = ", ".join(f"{p.path}={p.law.to_spec()!r}" for p in self.parameters)
        corr = f", correlated={list(self.correlated)}" if self.correlation is not None else ""
        return f"Uncertainty({laws}{corr})"

    # -- properties --------------------------------------------------------------------------------------

    @property
    def size(self) -> int:
        """Number of uncertain parameters ``k``."""
        return len(self.parameters)

    @property
    def independent(self) -> bool:
        """True when no correlation is declared."""
        return self.correlation is None

    @property
    def units(self) -> tuple[str, ...]:
        """SI unit of each parameter (``""``: dimensionless)."""
        return tuple(p.parameter.unit for p in self.parameters)

    def mean(self) -> np.ndarray:
        """Mean of each parameter [SI], shape ``(k,)``."""
        return np.array([p.law.density.mean() for p in self.parameters])

    def std(self) -> np.ndarray:
        """Standard deviation of each parameter [SI], shape ``(k,)``."""
        return np.array([p.law.density.std() for p in self.parameters])

    def covariance(self) -> np.ndarray:
        """Covariance matrix of the parameters [SI products], shape ``(k, k)``."""
        s = self.std()
        c = np.diag(s * s)
        if self.correlation is not None:
            g = self._group
            c[np.ix_(g, g)] = self.correlation * np.outer(s[g], s[g])
        return c

    # -- sampling ------------------------------------------------------------------------------------------

    def from_unit(self, u: Any) -> np.ndarray:
        """Map points ``u`` of the unit hypercube, shape ``(n, k)`` (or ``(k,)``), to parameter values [SI]
        of the same shape (inverse distribution functions; the correlated group through ``μ + D L Φ⁻¹(u)``)."""
        u = np.asarray(u, dtype=float)
        single = u.ndim == 1
        u2 = np.atleast_2d(u)
        if u2.ndim != 2 or u2.shape[1] != self.size:
            raise ValueError(f"unit-hypercube points must have shape (n, {self.size}), got {u.shape}")
        if np.any(~np.isfinite(u2)) or np.any((u2 < 0.0) | (u2 > 1.0)):
            raise ValueError("unit-hypercube points must lie in [0, 1]")
        u2 = np.clip(u2, UNIT_INTERVAL_MARGIN, 1.0 - UNIT_INTERVAL_MARGIN)
        x = np.empty_like(u2)
        grouped = set(self._group.tolist())
        for j, p in enumerate(self.parameters):
            if j not in grouped:
                x[:, j] = p.law.density.ppf(u2[:, j])
        if self._cholesky is not None:
            g = self._group
            z = stats.norm.ppf(u2[:, g]) @ self._cholesky.T
            means = np.array([self.parameters[j].law.density.mean() for j in g])
            stds = np.array([self.parameters[j].law.density.std() for j in g])
            x[:, g] = means + z * stds
        return x[0] if single else x

    def draw(self, seed: int, indices: Sequence[int] | np.ndarray) -> np.ndarray:
        """The values [SI] of realizations ``indices`` of a study seeded ``seed``, shape ``(len(indices), k)``:
        realization ``i`` maps ``realization_generator(seed, i).random(k)`` through :meth:`from_unit`."""
        idx = list(indices)
        u = np.empty((len(idx), self.size))
        for n, i in enumerate(idx):
            u[n] = realization_generator(seed, i).random(self.size)
        return self.from_unit(u)

    def values(self, row: Sequence[float]) -> dict[str, float]:
        """``{path: value}`` of one row of values [SI]."""
        row = np.asarray(row, dtype=float)
        if row.shape != (self.size,):
            raise ValueError(f"a row of values must have shape ({self.size},), got {row.shape}")
        return {p: float(v) for p, v in zip(self.paths, row)}

    def apply(self, case: Case, row: Sequence[float]) -> Case:
        """``case`` with the parameters set to one row of values [SI] (a new validated Case; raises
        :class:`~drillstring.stochastic.parameters.ParameterError` if a value breaks a case rule, e.g. a
        drawn weight-on-hook above the weight)."""
        return with_parameters(case, self.values(row))


def uncertainty(
    case: Case,
    laws: Mapping[str, str | Mapping[str, Any]],
    *,
    correlated: Sequence[str] = (),
    correlation: Any = None,
    tolerance: float = OUT_OF_RANGE_TOLERANCE,
) -> Uncertainty:
    """Declare uncertain parameters of ``case``: ``laws`` maps parameter paths to law specs (strings or tables);
    ``correlation`` is the correlation matrix of the normal parameters listed in ``correlated``.

    Raises :class:`~drillstring.stochastic.parameters.ParameterError` (one line) for an unknown path, a bad
    spec, a law that puts a probability above ``tolerance`` outside the parameter's range (default
    :data:`OUT_OF_RANGE_TOLERANCE`; a Monte Carlo study accepts up to 1e-3, recording such draws as failed
    realizations; 1 accepts any law) or an invalid correlation.
    """
    if not isinstance(laws, Mapping):
        raise ParameterError(f"laws must be a mapping path -> law, got {type(laws).__name__}")
    if (correlation is None) != (not correlated):
        raise ParameterError("give both the correlated parameters and their correlation matrix, or neither")
    parameters = [_bind(case, path, spec, tolerance) for path, spec in laws.items()]
    return Uncertainty(parameters, correlated, correlation)


def split_assignment(text: str) -> tuple[str, str]:
    """``"fluid.inlet_velocity=uniform 1.2 1.8 m/s"`` -> ``("fluid.inlet_velocity", "uniform 1.2 1.8 m/s")``
    (a command-line ``--param`` value; quotes around the law are removed)."""
    path, sep, spec = text.partition("=")
    path, spec = path.strip(), spec.strip()
    if len(spec) >= 2 and spec[0] == spec[-1] and spec[0] in "'\"":
        spec = spec[1:-1].strip()
    if not sep or not path or not spec:
        raise ParameterError(
            f"{text!r} is not PATH=LAW, e.g. fluid.inlet_velocity=\"{LAWS['uniform'].example}\""
        )
    return path, spec


def split_correlation(text: str) -> tuple[str, str, float]:
    """``"operation.top_speed,weight_on_hook=-0.3"`` -> ``("operation.top_speed", "weight_on_hook", -0.3)``
    (a command-line ``--correlation`` value: two parameter paths and their correlation coefficient)."""
    pair, sep, value = text.partition("=")
    a, comma, b = pair.partition(",")
    a, b = a.strip(), b.strip()
    try:
        r = float(value)
    except ValueError:
        r = math.nan
    if not sep or not comma or not a or not b or not math.isfinite(r):
        raise ParameterError(f"{text!r} is not PATH1,PATH2=R, e.g. operation.top_speed,weight_on_hook=-0.3")
    return a, b, r


def correlation_table(pairs: Sequence[tuple[str, str, float]]) -> dict[str, Any]:
    """The table form ``{"parameters": [...], "matrix": [[...]]}`` of pairwise correlation coefficients
    (unit diagonal; pairs not given are uncorrelated). A pair given twice is refused."""
    names: list[str] = []
    for a, b, _ in pairs:
        for name in (a, b):
            if name not in names:
                names.append(name)
    n = len(names)
    matrix = np.eye(n)
    seen: set[frozenset[str]] = set()
    for a, b, r in pairs:
        key = frozenset((a, b))
        if a == b:
            raise ParameterError(f"correlation {a},{b}: a parameter with itself (the diagonal is 1)")
        if key in seen:
            raise ParameterError(f"correlation {a},{b}: given twice")
        seen.add(key)
        i, j = names.index(a), names.index(b)
        matrix[i, j] = matrix[j, i] = r
    return {"parameters": names, "matrix": matrix.tolist()}


def declared_uncertainty(
    case: Case,
    laws: Mapping[str, str | Mapping[str, Any]] | None = None,
    correlation: Mapping[str, Any] | None = None,
    *,
    first: Mapping[str, str | Mapping[str, Any]] | None = None,
    tolerance: float = OUT_OF_RANGE_TOLERANCE,
) -> Uncertainty | None:
    """The uncertain parameters of a study of ``case``: ``laws`` (path -> law) with ``correlation`` (the
    table form ``{"parameters": [...], "matrix": [[...]]}``) when ``laws`` is given, otherwise the case's
    ``[uncertainty]`` table; the laws of ``first`` (e.g. the weight-on-hook law of a ``sigma``) come
    before them. None when nothing is declared at all.

    Raises :class:`~drillstring.stochastic.parameters.ParameterError` (one line; prefixed with
    ``[uncertainty] of the case:`` when the problem is in the case's table), also for a parameter
    declared twice."""
    source = ""
    if laws is None and case.uncertainty is not None:
        table = case.uncertainty
        laws = dict(table.parameters)
        if table.correlation is not None and correlation is None:
            correlation = {"parameters": list(table.correlation.parameters), "matrix": table.correlation.matrix}
        source = "[uncertainty] of the case: "
    declared: dict[str, Any] = dict(first or {})
    try:
        for path, spec in (laws or {}).items():
            key = path.strip() if isinstance(path, str) else path
            if key in declared:
                raise ParameterError(f"{key} is declared twice")
            declared[key] = spec
        if not declared:
            if correlation is not None:
                raise ParameterError("a correlation is declared without any uncertain parameter")
            return None
        if correlation is None:
            return uncertainty(case, declared, tolerance=tolerance)
        if not isinstance(correlation, Mapping) or set(correlation) != {"parameters", "matrix"}:
            raise ParameterError("a correlation must be a table with exactly the keys parameters and matrix")
        return uncertainty(case, declared, correlated=list(correlation["parameters"]),
                           correlation=correlation["matrix"], tolerance=tolerance)
    except ParameterError as error:
        raise ParameterError(f"{source}{error}") from None


def input_attributes(law: Uncertainty) -> dict[str, Any]:
    """The declared laws as plain attributes of a store or Dataset (lists, one entry per parameter, SI):
    ``parameters`` (paths), ``laws`` (canonical specs), ``parameter_units``, ``parameter_mean``,
    ``parameter_std``, and ``correlated`` / ``correlation`` (empty when independent)."""
    return {
        "parameters": list(law.paths),
        "laws": [p.law.to_spec() for p in law.parameters],
        "parameter_units": list(law.units),
        "parameter_mean": [float(v) for v in law.mean()],
        "parameter_std": [float(v) for v in law.std()],
        "correlated": list(law.correlated) if law.correlation is not None else [],
        "correlation": law.correlation.tolist() if law.correlation is not None else [],
    }
