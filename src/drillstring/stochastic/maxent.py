"""Maximum-Entropy probability densities from the available information (docs/model.md §11).

The Maximum Entropy Principle (E. T. Jaynes, "Information theory and statistical mechanics", Phys. Rev. 106,
1957; J. N. Kapur, *Maximum-Entropy Models in Science and Engineering*, Wiley, 1989; C. Soize,
*Uncertainty Quantification: An Accelerated Course with Advanced Applications in Computational
Engineering*, Springer, 2017, ch. 5) builds the probability density ``p`` of a real random variable ``X``
that maximises the (differential) Shannon entropy

    S(p) = − ∫ p(x) ln p(x) dx                                                       [nat]         (1)

under the *available information*: a support ``K = [a, b]`` (ends possibly infinite) and ``μ`` moment
constraints

    ∫_K p(x) dx = 1,        E{g_k(X)} = ∫_K g_k(x) p(x) dx = m_k,   k = 1..μ.                           (2)

With Lagrange multipliers ``λ0, λ = (λ1..λμ)`` the solution has the exponential form (Jaynes 1957;
Kapur 1989 §2.2; Soize 2017 eq. 5.22)

    p(x) = 1_K(x) exp(−λ0 − Σ_k λ_k g_k(x)),                                                             (3)
    λ0   = ln ∫_K exp(−Σ_k λ_k g_k(x)) dx,                                                               (4)

and ``λ`` is the unique minimiser of the convex *dual function* (Kapur 1989 §2.3; Soize 2017 §5.3.5)

    Γ(λ) = ln ∫_K exp(−Σ_k λ_k g_k(x)) dx + Σ_k λ_k m_k,                                                 (5)
    ∇Γ(λ)_k  = m_k − E_λ{g_k(X)},        ∇²Γ(λ)_kl = Cov_λ{g_k(X), g_l(X)},                              (6)

whose minimum value is the maximal entropy, ``S(p) = Γ(λ*) = λ0 + Σ_k λ_k m_k``. Its gradient vanishes
exactly when the moments (2) are reproduced.

Closed forms (``method="auto"``)
--------------------------------
Classical information sets give known laws (Kapur 1989 ch. 2; Soize 2017 §5.3.6), recognised from the
support and the constraint *names* of the helper functions below:

=====================================  ======================================  ====================
support                                constraints                             law (``kind``)
=====================================  ======================================  ====================
``[a, b]`` bounded                     none                                    ``"uniform"``
``[a, +∞)``                            ``mean``                                ``"exponential"``
``(−∞, +∞)``                           ``mean``, ``second_moment``             ``"normal"``
``(0, +∞)``                            ``mean``, ``log_mean``                  ``"gamma"``
=====================================  ======================================  ====================

The Gamma shape ``k`` solves ``ln k − ψ(k) = ln E{X} − E{ln X}`` (ψ the digamma function) and the scale
is ``θ = E{X}/k``. For these laws the object delegates to a frozen :mod:`scipy.stats` distribution and the
Lagrange multipliers of (3) are filled from the closed form, so that they compare with a numerical solution.
Every other information set, or ``method="numerical"``, is solved through the dual (5).

Numerical dual
--------------
* **Standardised variable.** The support is mapped to the real line with the double-exponential
  transformations of Takahasi & Mori (H. Takahasi, M. Mori, "Double exponential formulas for numerical
  integration", Publ. RIMS 9, 1974): with ``z = (π/2) sinh t``,

      bounded [a, b]:    x = (a + b)/2 + (b − a)/2 · tanh z         (tanh–sinh)
      [a, +∞):           x = a + s · exp z                          (exp–sinh)
      (−∞, b]:           x = b − s · exp z
      (−∞, +∞):          x = c + s · sinh z                         (sinh–sinh)

  where the location ``c`` and scale ``s`` standardise ``X`` (by default from the ``mean`` and
  ``second_moment`` constraints when present; the keyword options ``location``/``scale`` override them).
  The trapezoid rule in ``t`` with step ``h`` converges exponentially for analytic integrands, including
  integrable end-point singularities (e.g. a Gamma density of shape < 1) and infinite ends; the nodes are
  truncated where the mapped weight underflows, or at ``|x − c|/s = 1e12`` on infinite ends.
* **Well-conditioned basis.** The constraint functions are centred and orthonormalised (weighted QR)
  against a reference density on the standardised variable (uniform / exponential / Gaussian), i.e. the
  dual is solved in multipliers ``ν = R λ`` of an orthonormal basis ``h = (g − ḡ) R⁻¹``; this is a linear
  change of variable of (5) that leaves the density unchanged and makes the Hessian (6) ≈ identity.
* **Damped Newton** (Newton direction from (6), Armijo backtracking) on the *discrete* dual, which is a
  log-sum-exp of linear functions and hence convex for every step ``h``. It starts from the projection of
  the reference log-density on the basis and, on infinite ends, continues in the domain: it is solved on
  ``|x − c| ≤ D s`` for ``D = 8, 64, 1e3, 1e5, 1e8, 1e12`` in turn (warm starts), so that the first steps
  never meet the huge values of, e.g., ``x⁴`` far out. The step ``h`` is then halved until the solution at
  ``h`` reproduces the normalisation and the moments on the ``h/2`` nodes to ``1e-10`` (in the orthonormal
  units, i.e. relative to the standard deviation of ``g_k``), or until that disagreement stops decreasing
  below ``1e-7`` (the round-off floor of the constraint values), and the ``h/2`` rule is kept. The
  achieved agreement and moment residuals are in ``MaxEntDensity.diagnostics``.
* **Existence.** When the information admits no maximum-entropy density (e.g. only a mean on ℝ, nothing on
  ``[0, ∞)``, a kurtosis above 3 with moments up to order 4 on ℝ, a variance above ``(E{X} − a)²`` with mean
  and variance on ``[a, ∞)``), the solution of the truncated problem puts its mass at the truncation; more
  than ``1e-9`` of probability beyond ``1e6`` scales raises :class:`ValueError`. (A genuine density that
  heavy-tailed, in units of the scale, needs a ``scale=`` hint.)
* **Distribution function** of a numerical density: tabulated once (lazily) on a uniform grid in ``t``
  (4096 intervals, 10-point Gauss–Legendre per interval) and interpolated by a cubic Hermite polynomial
  using the density as derivative; ``ppf`` inverts the table by bisection on that polynomial, and
  :meth:`MaxEntDensity.sample` draws by inverse CDF.

Impossible information raises :class:`ValueError` naming the quantity, its value and the allowed range:
empty support, mean outside the support, variance ``E{X²} − E{X}² ≤ 0`` (or above the Bhatia–Davis bound
``(b − E{X})(E{X} − a)`` on a bounded support), ``E{ln X}`` on a support that reaches ``x ≤ 0``,
``E{ln X} ≥ ln E{X}`` (Jensen), information that leaves the density non-normalisable (mass escaping to
infinity) and linearly dependent constraints.

Reproducible Monte Carlo draws
------------------------------
:func:`realization_generator` gives realization ``i`` of a study with seed ``s`` its own PCG64 stream,
seeded by ``SeedSequence(s, spawn_key=(i,))`` (the stream NumPy's ``SeedSequence(s).spawn`` would hand to
child ``i``). A draw therefore depends only on ``(s, i)``: not on the number of workers, the order in which
realizations run, or whether a study is resumed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import linalg, optimize, special, stats

__all__ = [
    "Constraint",
    "MaxEntDensity",
    "mean",
    "second_moment",
    "variance_constraints",
    "log_mean",
    "maximum_entropy",
    "realization_generator",
    "gamma_shape",
]

#: Reserved constraint names, used by the helpers and recognised by ``method="auto"``.
MEAN = "mean"
SECOND_MOMENT = "second_moment"
LOG_MEAN = "log_mean"
_RESERVED = (MEAN, SECOND_MOMENT, LOG_MEAN)

# Numerical-dual settings (see the module docstring).
_H_START = 1.0 / 8.0  # first step of the trapezoid rule in the mapped variable t
_MAX_LEVELS = 8  # h down to 1/1024
_LEVEL_TOL = 1e-10  # agreement between the h and h/2 rules (normalisation and moments)
_NOISE_TOL = 1e-7  # accepted agreement / moment residual when round-off in the g_k limits it
_GRAD_TOL = 1e-12  # Newton stop: max |∇Γ| in orthonormal units
_MAX_NEWTON = 400
_FAR = 1e12  # truncation of infinite ends, in units of the scale s
_FAR_STEPS = (8.0, 64.0, 1e3, 1e5, 1e8, _FAR)  # domain continuation on infinite ends
_ESCAPE_DISTANCE = 1e6  # mass beyond this many scales counts as "escaping to infinity"
_ESCAPE_TOL = 1e-9
_TABLE_INTERVALS = 4096
_TABLE_GAUSS = 10
_TABLE_TAIL = 1e-17  # CDF table covers the mass between these tail probabilities


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


# ---------------------------------------------------------------------------------------------------------
# The density object
# ---------------------------------------------------------------------------------------------------------


class MaxEntDensity:
    """A Maximum-Entropy probability density on ``support`` (units of ``x`` are those of the constraints).

    Attributes
    ----------
    kind:
        ``"normal"``, ``"uniform"``, ``"exponential"``, ``"gamma"`` (closed forms) or ``"numerical"``.
    support:
        ``(a, b)``, floats, ends possibly infinite.
    constraints:
        The constraints it was built from, in the given order.
    lagrange_multipliers:
        ``[λ0, λ1, …, λμ]`` of eq. (3), ``λ_k`` in the order of ``constraints`` (``λ0`` is the log of the
        normalisation (4), in units of ``ln(1/[x])``). Filled for closed forms too.
    frozen:
        The frozen :mod:`scipy.stats` distribution for closed forms, ``None`` for numerical densities.
    diagnostics:
        For numerical densities: trapezoid step ``h``, number of nodes, Newton iterations, max moment
        residual (relative, per constraint) and the location/scale used; empty for closed forms.
    """

    def __init__(
        self,
        kind: str,
        support: tuple[float, float],
        constraints: Sequence[Constraint],
        lagrange_multipliers: np.ndarray,
        frozen: Any = None,
        numerical: _NumericalSolution | None = None,
        diagnostics: dict[str, Any] | None = None,
    ) -> None:
        self.kind = kind
        self.support = (float(support[0]), float(support[1]))
        self.constraints = tuple(constraints)
        self.lagrange_multipliers = np.asarray(lagrange_multipliers, dtype=float)
        self.frozen = frozen
        self._num = numerical
        self.diagnostics = dict(diagnostics or {})

    def __repr__(self) -> str:
        names = ", ".join(f"{c.name}={c.value:.6g}" for c in self.constraints)
        return f"MaxEntDensity(kind={self.kind!r}, support={self.support}, {names or 'no constraints'})"

    # -- densities -----------------------------------------------------------------------------------------
    def logpdf(self, x: Any) -> np.ndarray | float:
        """``ln p(x)`` [ln(1/unit of x)]; ``-inf`` outside the support."""
        if self.frozen is not None:
            return _scalar_or_array(self.frozen.logpdf(x))
        return _scalar_or_array(self._num.logpdf(np.asarray(x, dtype=float)))

    def pdf(self, x: Any) -> np.ndarray | float:
        """``p(x)`` of eq. (3) [1/unit of x]; 0 outside the support."""
        if self.frozen is not None:
            return _scalar_or_array(self.frozen.pdf(x))
        with np.errstate(over="ignore", under="ignore"):
            return _scalar_or_array(np.exp(self._num.logpdf(np.asarray(x, dtype=float))))

    def cdf(self, x: Any) -> np.ndarray | float:
        """``P(X ≤ x)`` (dimensionless)."""
        if self.frozen is not None:
            return _scalar_or_array(self.frozen.cdf(x))
        return _scalar_or_array(self._num.cdf(np.asarray(x, dtype=float)))

    def ppf(self, q: Any) -> np.ndarray | float:
        """Quantile function, inverse of :meth:`cdf` (units of ``x``); ``ppf(0) = a``, ``ppf(1) = b``, NaN
        outside ``[0, 1]``."""
        if self.frozen is not None:
            return _scalar_or_array(self.frozen.ppf(q))
        return _scalar_or_array(self._num.ppf(np.asarray(q, dtype=float), clip=False))

    # -- moments ---------------------------------------------------------------------------------------------
    def mean(self) -> float:
        """``E{X}`` (units of ``x``)."""
        if self.frozen is not None:
            return float(self.frozen.mean())
        return self._num.expect(_identity)

    def var(self) -> float:
        """``Var{X} = E{(X − E{X})²}`` (units of ``x`` squared)."""
        if self.frozen is not None:
            return float(self.frozen.var())
        m = self.mean()
        return self._num.expect(lambda x: (x - m) ** 2)

    def std(self) -> float:
        """Standard deviation (units of ``x``)."""
        return math.sqrt(self.var())

    def entropy(self) -> float:
        """Differential entropy (1) [nat]; depends on the unit of ``x`` (adds ``ln c`` when ``x`` is scaled by
        ``c``)."""
        if self.frozen is not None:
            return float(self.frozen.entropy())
        return self._num.entropy()

    def expect(self, function: Callable[[np.ndarray], np.ndarray]) -> float:
        """``E{f(X)}`` for a vectorised ``f`` (closed forms: ``scipy.stats`` ``expect``; numerical: the
        converged quadrature rule)."""
        if self.frozen is not None:
            return float(self.frozen.expect(lambda x: function(np.asarray(x, dtype=float))))
        return self._num.expect(function)



def _scalar_or_array(v: Any) -> np.ndarray | float:
    arr = np.asarray(v, dtype=float)
    return float(arr) if arr.ndim == 0 else arr


# ---------------------------------------------------------------------------------------------------------
# Double-exponential maps of the support (Takahasi & Mori 1974)
# ---------------------------------------------------------------------------------------------------------


class _Map:
    """``x(t)``, ``ln dx/dt`` and ``t(x)`` for one support, plus the reference log-density of the
    standardised variable used to orthonormalise the constraints."""

    def __init__(self, a: float, b: float, location: float, scale: float) -> None:
        self.a, self.b, self.c, self.s = a, b, location, scale
        fa, fb = math.isfinite(a), math.isfinite(b)
        if fa and fb:
            self.kind = "bounded"
        elif fa:
            self.kind = "lower"
        elif fb:
            self.kind = "upper"
        else:
            self.kind = "real"

    def t_range(self, far: float) -> tuple[float, float]:
        """Range of the mapped variable: where the weight underflows at a finite end (``|z| ≤ 350`` or
        ``e^z ≥ 1e-304``), and at ``far`` scales from the location on an infinite end."""
        k = math.pi / 2
        if self.kind == "bounded":
            return -math.asinh(350.0 / k), math.asinh(350.0 / k)
        if self.kind in ("lower", "upper"):
            return -math.asinh(700.0 / k), math.asinh(math.log(far) / k)
        tm = math.asinh(math.asinh(far) / k)
        return -tm, tm

    def nodes(self, h: float, far: float) -> np.ndarray:
        t0, t1 = self.t_range(far)
        return np.arange(math.ceil(t0 / h), math.floor(t1 / h) + 1, dtype=float) * h

    def x_logdxdt(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``x(t)``, ``ln dx/dt`` and the standardised distance ``d`` (for tail checks)."""
        z = (math.pi / 2) * np.sinh(t)
        log_cosh_t = np.abs(t) + np.log1p(np.exp(-2.0 * np.abs(t))) - math.log(2.0)
        base = math.log(math.pi / 2) + log_cosh_t
        if self.kind == "bounded":
            a, b = self.a, self.b
            az = np.abs(z)
            e = np.exp(-2.0 * az)
            frac = e / (1.0 + e)  # distance to the nearer end / (b − a)
            x = np.where(z < 0, a + (b - a) * frac, b - (b - a) * frac)
            # dx/dt = (b − a)/2 · sech² z · (π/2) cosh t,  sech² z = 4 e^{−2|z|} / (1 + e^{−2|z|})²
            logd = math.log((b - a) / 2) + math.log(4.0) - 2.0 * az - 2.0 * np.log1p(e) + base
            return x, logd, np.zeros_like(x)
        if self.kind in ("lower", "upper"):
            u = np.exp(z)
            x = self.a + self.s * u if self.kind == "lower" else self.b - self.s * u
            logd = math.log(self.s) + z + base
            return x, logd, u
        y = np.sinh(z)
        az = np.abs(z)
        log_cosh_z = az + np.log1p(np.exp(-2.0 * az)) - math.log(2.0)
        x = self.c + self.s * y
        logd = math.log(self.s) + log_cosh_z + base
        return x, logd, np.abs(y)

    def reference_logdensity(self, t: np.ndarray) -> np.ndarray:
        z = (math.pi / 2) * np.sinh(t)
        if self.kind == "bounded":
            return np.zeros_like(t)
        if self.kind in ("lower", "upper"):
            return -np.exp(z)
        return -0.5 * np.sinh(z) ** 2

    def t_of_x(self, x: np.ndarray) -> np.ndarray:
        """Inverse map; ``±inf`` at and beyond the ends of the support."""
        x = np.asarray(x, dtype=float)
        with np.errstate(all="ignore"):
            if self.kind == "bounded":
                z = 0.5 * (np.log(x - self.a) - np.log(self.b - x))
            elif self.kind == "lower":
                z = np.log((x - self.a) / self.s)
            elif self.kind == "upper":
                z = np.log((self.b - x) / self.s)
            else:
                z = np.arcsinh((x - self.c) / self.s)
            t = np.arcsinh(z / (math.pi / 2))
        if self.kind == "upper":
            t = -t  # keep t increasing with x
        t = np.where(x <= self.a, -np.inf, t)
        t = np.where(x >= self.b, np.inf, t)
        return t

    def x_of_t_increasing(self, t: np.ndarray) -> np.ndarray:
        """``x`` for a ``t`` that increases with ``x`` (the ``upper`` map runs backwards in its own t)."""
        if self.kind == "upper":
            return self.x_logdxdt(-t)[0]
        return self.x_logdxdt(t)[0]

    def logdxdt_increasing(self, t: np.ndarray) -> np.ndarray:
        if self.kind == "upper":
            return self.x_logdxdt(-t)[1]
        return self.x_logdxdt(t)[1]


# ---------------------------------------------------------------------------------------------------------
# Numerical solution of the dual
# ---------------------------------------------------------------------------------------------------------


class _Rule:
    """Quadrature nodes of one step ``h`` with the constraint values in the orthonormal basis."""

    def __init__(
        self, mapping: _Map, h: float, far: float, constraints: Sequence[Constraint], basis: _Basis | None
    ) -> None:
        t = mapping.nodes(h, far)
        x, logd, dist = mapping.x_logdxdt(t)
        logw = logd + math.log(h)
        G = np.column_stack([c.evaluate(x) for c in constraints]) if constraints else np.zeros((x.size, 0))
        keep = (x > mapping.a) & (x < mapping.b) & np.isfinite(logw) & np.all(np.isfinite(G), axis=1)
        self.h, self.far = h, far
        self.t, self.x, self.logw, self.dist, self.G = t[keep], x[keep], logw[keep], dist[keep], G[keep]
        self.ref = mapping.reference_logdensity(self.t)
        self.H = basis.transform(self.G) if basis is not None else None


class _Basis:
    """Centring ``ḡ`` and triangular factor ``R`` with ``h = (g − ḡ) R⁻¹`` orthonormal under the reference."""

    def __init__(self, rule: _Rule, names: Sequence[str]) -> None:
        K = rule.G.shape[1]
        self.K = K
        if K == 0:
            self.gbar = np.zeros(0)
            self.R = np.zeros((0, 0))
            return
        lq = rule.logw + rule.ref
        q = np.exp(lq - lq.max())
        q /= q.sum()
        self.gbar = q @ rule.G
        W = np.sqrt(q)[:, None] * (rule.G - self.gbar)
        R = linalg.qr(W, mode="r")[0][:K, :K]
        d = np.abs(np.diag(R))
        if K > 0 and (not np.all(np.isfinite(R)) or d.min() <= 1e-11 * max(d.max(), np.finfo(float).tiny)):
            raise ValueError(
                f"the constraint functions {list(names)} are linearly dependent (together with the constant) "
                "on the support: drop the redundant constraint"
            )
        signs = np.sign(np.diag(R))
        self.R = R * signs[:, None]

    def transform(self, G: np.ndarray) -> np.ndarray:
        if self.K == 0:
            return np.zeros((G.shape[0], 0))
        return linalg.solve_triangular(self.R, (G - self.gbar).T, trans="T", lower=False).T

    def lam(self, nu: np.ndarray) -> np.ndarray:
        if self.K == 0:
            return np.zeros(0)
        return linalg.solve_triangular(self.R, nu, lower=False)


def _dual_terms(nu: np.ndarray, rule: _Rule, target: np.ndarray, hessian: bool = True):
    """Discrete dual (5) in the orthonormal basis: value, gradient (6), Hessian (6), ln Z, node masses."""
    a = rule.logw - rule.H @ nu
    amax = float(a.max())
    e = np.exp(a - amax)
    Z = float(e.sum())
    lnZ = amax + math.log(Z)
    p = e / Z
    value = lnZ + float(nu @ target)
    Eh = p @ rule.H
    grad = target - Eh
    hess = None
    if hessian:
        mask = p > 0.0
        Hc = rule.H[mask] - Eh
        hess = (Hc * p[mask, None]).T @ Hc
    return value, grad, hess, lnZ, p


def _newton(nu: np.ndarray, rule: _Rule, target: np.ndarray) -> tuple[np.ndarray, int, float]:
    """Damped Newton on the convex discrete dual; returns ``ν``, iterations and the final max |∇Γ|."""
    K = nu.size
    if K == 0:
        return nu, 0, 0.0
    value, grad, hess, _, _ = _dual_terms(nu, rule, target)
    gnorm = float(np.max(np.abs(grad)))
    for it in range(1, _MAX_NEWTON + 1):
        if gnorm < _GRAD_TOL:
            return nu, it - 1, gnorm
        try:
            step = linalg.solve(hess + 1e-14 * np.eye(K) * max(1.0, np.trace(hess)), -grad, assume_a="pos")
        except (linalg.LinAlgError, ValueError):
            step = -grad
        slope = float(grad @ step)
        if not slope < 0.0:
            step, slope = -grad, -float(grad @ grad)
        alpha = 1.0
        accepted = False
        for _ in range(60):
            trial = nu + alpha * step
            tv, tg, th, _, _ = _dual_terms(trial, rule, target)
            if math.isfinite(tv) and tv <= value + 1e-4 * alpha * slope + 1e-15 * abs(value):
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            break  # no further decrease possible at machine precision
        nu, value, grad, hess = trial, tv, tg, th
        gnorm = float(np.max(np.abs(grad)))
        if np.max(np.abs(nu)) > 1e12:
            break
    return nu, _MAX_NEWTON, gnorm


@dataclass
class _NumericalSolution:
    mapping: _Map
    basis: _Basis
    rule: _Rule
    constraints: tuple[Constraint, ...]
    nu: np.ndarray
    lnZ: float
    p: np.ndarray
    _table: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def logpdf(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        flat = x.reshape(-1)
        out = np.full(flat.shape, -np.inf)
        a, b = self.mapping.a, self.mapping.b
        inside = (flat >= a) & (flat <= b) & ~np.isnan(flat) & np.isfinite(flat)
        if np.any(inside):
            xi = flat[inside]
            if self.constraints:
                G = np.column_stack([c.evaluate(xi) for c in self.constraints])
                with np.errstate(all="ignore"):
                    val = -self.lnZ - self.basis.transform(G) @ self.nu
            else:
                val = np.full(xi.shape, -self.lnZ)
            out[inside] = val
        out[np.isnan(flat)] = np.nan
        return out.reshape(x.shape)

    def expect(self, function: Callable[[np.ndarray], np.ndarray]) -> float:
        with np.errstate(all="ignore"):
            f = np.asarray(function(self.rule.x), dtype=float)
        return float(self.p @ np.broadcast_to(f, self.rule.x.shape))

    def entropy(self) -> float:
        # −∫ p ln p = ln Z + ν·E{h}  (eq. (5) at the optimum)
        if self.nu.size == 0:
            return float(self.lnZ)
        return float(self.lnZ + self.nu @ (self.p @ self.rule.H))

    # -- tabulated distribution function, in the increasing mapped variable t ------------------------------
    def _density_t(self, t: np.ndarray) -> np.ndarray:
        x = self.mapping.x_of_t_increasing(t)
        with np.errstate(all="ignore"):
            f = np.exp(self.logpdf(x) + self.mapping.logdxdt_increasing(t))
        return np.where(np.isfinite(f), f, 0.0)

    def table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self._table is None:
            t = self.rule.t if self.mapping.kind != "upper" else -self.rule.t
            order = np.argsort(t)
            t, p = t[order], self.p[order]
            cum = np.cumsum(p)
            h = self.rule.h
            i_lo = int(np.searchsorted(cum, _TABLE_TAIL))
            i_hi = int(np.searchsorted(cum, 1.0 - _TABLE_TAIL))
            t_lo = t[max(i_lo - 1, 0)] - h
            t_hi = t[min(i_hi + 1, t.size - 1)] + h
            knots = np.linspace(t_lo, t_hi, _TABLE_INTERVALS + 1)
            gx, gw = np.polynomial.legendre.leggauss(_TABLE_GAUSS)
            half = 0.5 * (knots[1:] - knots[:-1])
            mid = 0.5 * (knots[1:] + knots[:-1])
            tt = mid[:, None] + half[:, None] * gx[None, :]
            pieces = (self._density_t(tt.reshape(-1)).reshape(tt.shape) * gw).sum(axis=1) * half
            F = np.concatenate([[0.0], np.cumsum(pieces)])
            total = F[-1]
            F /= total
            dF = self._density_t(knots) / total
            self._table = (knots, F, dF)
        return self._table

    def _hermite(self, j: np.ndarray, t: np.ndarray) -> np.ndarray:
        knots, F, dF = self.table()
        t0, t1 = knots[j], knots[j + 1]
        dt = t1 - t0
        s = (t - t0) / dt
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h10 = s * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h11 = s * s * (s - 1)
        return h00 * F[j] + h10 * dt * dF[j] + h01 * F[j + 1] + h11 * dt * dF[j + 1]

    def cdf(self, x: np.ndarray) -> np.ndarray:
        knots, F, _ = self.table()
        x = np.asarray(x, dtype=float)
        t = self.mapping.t_of_x(x).reshape(-1)
        out = np.where(t <= knots[0], 0.0, 1.0)
        mid = (t > knots[0]) & (t < knots[-1])
        if np.any(mid):
            j = np.clip(np.searchsorted(knots, t[mid], side="right") - 1, 0, knots.size - 2)
            out[mid] = np.clip(self._hermite(j, t[mid]), 0.0, 1.0)
        out[np.isnan(x.reshape(-1))] = np.nan
        return out.reshape(x.shape)

    def ppf(self, q: np.ndarray, clip: bool) -> np.ndarray:
        knots, F, dF = self.table()
        q = np.asarray(q, dtype=float)
        flat = q.reshape(-1)
        out = np.full(flat.shape, np.nan)
        ok = (flat >= 0.0) & (flat <= 1.0)
        qq = np.clip(flat[ok], 0.0, 1.0)
        j = np.clip(np.searchsorted(F, qq, side="right") - 1, 0, knots.size - 2)
        # solve the cubic Hermite piece P(σ) = q on σ ∈ [0, 1] by Newton's method safeguarded by bisection
        t0, dt = knots[j], knots[j + 1] - knots[j]
        F0, F1 = F[j], F[j + 1]
        d0, d1 = dt * dF[j], dt * dF[j + 1]
        den = F1 - F0
        with np.errstate(all="ignore"):
            sig = np.clip(np.where(den > 0, (qq - F0) / den, 0.5), 0.0, 1.0)
        lo, hi = np.zeros_like(sig), np.ones_like(sig)
        for _ in range(60):
            s2 = sig * sig
            P = (1 + 2 * sig) * (1 - sig) ** 2 * F0 + sig * (1 - sig) ** 2 * d0 + s2 * (3 - 2 * sig) * F1
            P += s2 * (sig - 1) * d1 - qq
            dP = (6 * s2 - 6 * sig) * (F0 - F1) + (3 * s2 - 4 * sig + 1) * d0 + (3 * s2 - 2 * sig) * d1
            lo = np.where(P < 0, sig, lo)
            hi = np.where(P < 0, hi, sig)
            with np.errstate(all="ignore"):
                new = sig - P / dP
            bad = ~((new > lo) & (new < hi))
            new = np.where(bad, 0.5 * (lo + hi), new)
            done = np.max(np.abs(new - sig), initial=0.0) < 1e-15
            sig = new
            if done:
                break
        res = self.mapping.x_of_t_increasing(t0 + sig * dt)
        if not clip:
            res = np.where(qq <= 0.0, self.mapping.a, res)
            res = np.where(qq >= 1.0, self.mapping.b, res)
        out[ok] = res
        return out.reshape(q.shape)


def _raise_if_escaping(mapping: _Map, rule: _Rule, nu: np.ndarray, target: np.ndarray, names: list[str]) -> None:
    """Information that does not define a normalisable density pushes the mass to the truncated ends."""
    if mapping.kind == "bounded":
        return
    _, _, _, _, p = _dual_terms(nu, rule, target, hessian=False)
    escaped = float(p[rule.dist > min(_ESCAPE_DISTANCE, rule.far / 8.0)].sum())
    if escaped > _ESCAPE_TOL:
        a, b = mapping.a, mapping.b
        raise ValueError(
            f"the information {names} does not define a normalisable maximum-entropy density on the "
            f"support ({a}, {b}): probability {escaped:.3g} escapes to infinity "
            "(the supremum of the entropy is not attained: a constraint that controls the tails is missing, "
            "e.g. a second moment, or the moments are such that none exists, e.g. a kurtosis > 3 with "
            "moments up to order 4 on the real line)"
        )


def _location_scale(
    a: float, b: float, named: dict[str, float], location: float | None, scale: float | None
) -> tuple[float, float]:
    m = named.get(MEAN)
    m2 = named.get(SECOND_MOMENT)
    lm = named.get(LOG_MEAN)
    if math.isfinite(a) and math.isfinite(b):
        c, s = 0.5 * (a + b), 0.5 * (b - a)
    elif math.isfinite(a):
        c = a
        if m is not None:
            s = m - a
        elif m2 is not None and a == 0.0:
            s = math.sqrt(m2)
        elif lm is not None and a == 0.0:
            s = math.exp(lm)
        else:
            s = 1.0
    elif math.isfinite(b):
        c = b
        s = b - m if m is not None else (math.sqrt(m2) if m2 is not None and b == 0.0 else 1.0)
    else:
        c = m if m is not None else 0.0
        if m2 is not None:
            v = m2 - c * c
            s = math.sqrt(v) if v > 0 else math.sqrt(m2)
        else:
            s = 1.0
    if location is not None:
        c = float(location)
    if scale is not None:
        s = float(scale)
    if not (math.isfinite(c) and math.isfinite(s) and s > 0.0):
        raise ValueError(f"location = {c!r} and scale = {s!r} must be finite with scale > 0")
    return c, s


def _solve_numerical(
    a: float,
    b: float,
    constraints: tuple[Constraint, ...],
    named: dict[str, float],
    location: float | None,
    scale: float | None,
) -> MaxEntDensity:
    c, s = _location_scale(a, b, named, location, scale)
    mapping = _Map(a, b, c, s)
    names = [k.name for k in constraints]
    basis_rule = _Rule(mapping, _H_START / 4.0, _FAR_STEPS[0], constraints, None)
    basis = _Basis(basis_rule, names)
    m = np.array([k.value for k in constraints], dtype=float)
    target = basis.transform(m[None, :])[0] if constraints else np.zeros(0)

    h = _H_START
    # Domain continuation on infinite ends: solve on |x − c| ≤ D·s for growing D (warm starts), so that the
    # first Newton steps never see the huge constraint values far out; a decaying solution is unchanged by
    # the extension, a non-normalisable one runs to the truncation and is caught below.
    fars = _FAR_STEPS if mapping.kind != "bounded" else (_FAR,)
    rule = _Rule(mapping, h, fars[0], constraints, basis)
    # start from the projection of the reference log-density onto the basis (exact when it is in the span)
    if constraints:
        lq = rule.logw + rule.ref
        q = np.exp(lq - lq.max())
        q /= q.sum()
        nu = -(q * (rule.ref - q @ rule.ref)) @ rule.H
        if not np.all(np.isfinite(nu)):
            nu = np.zeros(len(constraints))
    else:
        nu = np.zeros(0)
    total_iterations = 0
    for previous, far in zip(fars[:-1], fars[1:]):
        nu, its, _ = _newton(nu, rule, target)
        total_iterations += its
        if previous > fars[0]:
            _, _, _, _, p = _dual_terms(nu, rule, target, hessian=False)
            if float(p[rule.dist > fars[fars.index(previous) - 1]].sum()) > 0.5:
                break  # mass runs to the truncation: caught by the escape check below
        rule = _Rule(mapping, h, far, constraints, basis)
    _raise_if_escaping(mapping, rule, nu, target, names)
    converged_levels = False
    previous = math.inf
    agreement = math.inf
    for _level in range(_MAX_LEVELS):
        nu, its, gnorm = _newton(nu, rule, target)
        total_iterations += its
        finer = _Rule(mapping, h / 2.0, _FAR, constraints, basis)
        _, g_f, _, lnZ_f, _ = _dual_terms(nu, finer, target, hessian=False)
        _, _, _, lnZ_c, _ = _dual_terms(nu, rule, target, hessian=False)
        agreement = max(
            abs(lnZ_f - lnZ_c) / max(1.0, abs(lnZ_c)), float(np.max(np.abs(g_f))) if g_f.size else 0.0
        )
        h /= 2.0
        rule = finer
        # converged; or the disagreement has reached the round-off floor of the constraint values (it stops
        # decreasing, e.g. E{X²} of a variable with a tiny coefficient of variation) at an acceptable level
        if agreement <= _LEVEL_TOL or (_level >= 2 and agreement > 0.5 * previous and agreement <= _NOISE_TOL):
            converged_levels = True
            break
        previous = agreement
    nu, its, gnorm = _newton(nu, rule, target)
    total_iterations += its
    _, grad, _, lnZ, p = _dual_terms(nu, rule, target, hessian=False)

    _raise_if_escaping(mapping, rule, nu, target, names)
    gmax = float(np.max(np.abs(grad))) if grad.size else 0.0
    if gmax > _NOISE_TOL:
        raise ValueError(
            f"the maximum-entropy dual did not converge for the information {names} on ({a}, {b}) "
            f"(max moment residual {gmax:.3g} in standardised units); the moments may be impossible on this "
            "support, or pass location=/scale= hints"
        )
    if not converged_levels:
        raise ValueError(
            f"the quadrature of the maximum-entropy density for the information {names} on ({a}, {b}) did not "
            f"converge (relative disagreement {agreement:.3g} between the finest two rules): the constraint values "
            "may carry too little precision (e.g. E{{X²}} of a variable whose coefficient of variation is near "
            "round-off), or pass location=/scale= hints that standardise the variable"
        )
    lam = basis.lam(nu)
    lam0 = lnZ - float(basis.gbar @ lam) if lam.size else lnZ
    sol = _NumericalSolution(mapping, basis, rule, constraints, nu, lnZ, p)
    residuals = {}
    for k, con in enumerate(constraints):
        achieved = float(p @ rule.G[:, k])
        spread = math.sqrt(max(float(p @ (rule.G[:, k] - achieved) ** 2), 0.0))
        residuals[con.name] = abs(achieved - con.value) / max(abs(con.value), spread, 1e-300)
    diagnostics = {
        "h": h,
        "nodes": int(rule.x.size),
        "newton_iterations": total_iterations,
        "max_gradient": gmax,
        "quadrature_agreement": agreement,
        "relative_moment_residuals": residuals,  # |E{g} − m| / max(|m|, std of g)
        "location": c,
        "scale": s,
    }
    return MaxEntDensity(
        "numerical", (a, b), constraints, np.concatenate([[lam0], lam]), numerical=sol, diagnostics=diagnostics
    )


# ---------------------------------------------------------------------------------------------------------
# Closed forms
# ---------------------------------------------------------------------------------------------------------


def _log_minus_digamma(k: float) -> float:
    """``ln k − ψ(k)`` without cancellation for large ``k`` (asymptotic series, Abramowitz & Stegun 6.3.18)."""
    if k >= 20.0:
        k2 = 1.0 / (k * k)
        return 1.0 / (2.0 * k) + k2 * (1.0 / 12 - k2 * (1.0 / 120 - k2 * (1.0 / 252 - k2 * (1.0 / 240 - k2 / 132))))
    return math.log(k) - float(special.digamma(k))


def gamma_shape(mean_value: float, log_mean_value: float) -> float:
    """Gamma shape ``k`` with ``ln k − ψ(k) = ln E{X} − E{ln X}`` (dimensionless; needs the right-hand side
    ``d > 0``). Uses ``1/(2k) < ln k − ψ(k) < 1/k``, so ``k ∈ (1/(2d), 1/d)``, and Brent's method."""
    d = math.log(mean_value) - log_mean_value
    if not d > 0.0:
        raise ValueError(f"ln(mean) - log_mean = {d!r} must be > 0 (Jensen's inequality)")
    lo, hi = 0.49 / d, 1.01 / d
    return float(optimize.brentq(lambda k: _log_minus_digamma(k) - d, lo, hi, xtol=1e-300, rtol=1e-15, maxiter=500))


def _closed_form(
    a: float, b: float, constraints: tuple[Constraint, ...], named: dict[str, float]
) -> MaxEntDensity | None:
    names = [c.name for c in constraints]
    if any(n not in _RESERVED for n in names) or len(set(names)) != len(names):
        return None
    keys = set(names)
    index = {n: i for i, n in enumerate(names)}
    lam = np.zeros(len(constraints))

    if math.isinf(a) and math.isinf(b) and keys == {MEAN, SECOND_MOMENT}:
        mu = named[MEAN]
        var = named[SECOND_MOMENT] - mu * mu
        sigma = math.sqrt(var)
        frozen = stats.norm(loc=mu, scale=sigma)
        # ln p = −[½ ln(2πσ²) + μ²/(2σ²)] + (μ/σ²) x − x²/(2σ²)
        lam0 = 0.5 * math.log(2 * math.pi * var) + mu * mu / (2 * var)
        lam[index[MEAN]] = -mu / var
        lam[index[SECOND_MOMENT]] = 1.0 / (2 * var)
        kind = "normal"
    elif math.isfinite(a) and math.isfinite(b) and not keys:
        frozen = stats.uniform(loc=a, scale=b - a)
        lam0 = math.log(b - a)
        kind = "uniform"
    elif math.isfinite(a) and math.isinf(b) and keys == {MEAN}:
        theta = named[MEAN] - a
        frozen = stats.expon(loc=a, scale=theta)
        # ln p = −ln θ − (x − a)/θ
        lam0 = math.log(theta) - a / theta
        lam[index[MEAN]] = 1.0 / theta
        kind = "exponential"
    elif a == 0.0 and math.isinf(b) and keys == {MEAN, LOG_MEAN}:
        k = gamma_shape(named[MEAN], named[LOG_MEAN])
        theta = named[MEAN] / k
        frozen = stats.gamma(k, scale=theta)
        # ln p = −[ln Γ(k) + k ln θ] + (k − 1) ln x − x/θ
        lam0 = float(special.gammaln(k)) + k * math.log(theta)
        lam[index[MEAN]] = 1.0 / theta
        lam[index[LOG_MEAN]] = 1.0 - k
        kind = "gamma"
    else:
        return None
    return MaxEntDensity(kind, (a, b), constraints, np.concatenate([[lam0], lam]), frozen=frozen)


# ---------------------------------------------------------------------------------------------------------
# Public constructors
# ---------------------------------------------------------------------------------------------------------


def maximum_entropy(
    support: tuple[float, float],
    constraints: Sequence[Constraint] = (),
    *,
    method: str = "auto",
    location: float | None = None,
    scale: float | None = None,
) -> MaxEntDensity:
    """The Maximum-Entropy density on ``support = (a, b)`` under ``E{g_k(X)} = m_k`` (eqs. (1)–(6)).

    Parameters
    ----------
    support:
        ``(a, b)`` with ``a < b``; ``-inf``/``+inf`` for infinite ends (units of ``x``).
    constraints:
        :class:`Constraint` objects, e.g. from :func:`mean`, :func:`second_moment`,
        :func:`variance_constraints`, :func:`log_mean`, or user-defined functions.
    method:
        ``"auto"`` (default): closed form when the support and constraint names match the table of the module
        docstring, numerical dual otherwise. ``"numerical"``: always the numerical dual.
    location, scale:
        Optional standardisation hints ``x = location + scale · y`` (units of ``x``) for the numerical dual on
        infinite supports; they change the conditioning, not the answer. Default from ``mean`` and
        ``second_moment`` when present.

    Raises
    ------
    ValueError
        Impossible information (see the module docstring), with the quantity, value and allowed range.
    """
    if method not in ("auto", "numerical"):
        raise ValueError(f"method = {method!r} must be 'auto' or 'numerical'")
    a, b = _check_support(support)
    constraints = tuple(constraints)
    named = _validate_information(a, b, constraints)
    if method == "auto":
        closed = _closed_form(a, b, constraints, named)
        if closed is not None:
            return closed
    return _solve_numerical(a, b, constraints, named, location, scale)


# ---------------------------------------------------------------------------------------------------------
# Reproducible random streams
# ---------------------------------------------------------------------------------------------------------


def _check_nonnegative_int(value: Any, what: str) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{what} must be an integer, got {value!r}")
    if value < 0:
        raise ValueError(f"{what} = {value} must be >= 0")
    return int(value)


def realization_generator(seed: int, index: int) -> np.random.Generator:
    """The independent random stream of realization ``index`` of a study seeded with ``seed``.

    ``Generator(PCG64(SeedSequence(seed, spawn_key=(index,))))``: identical to child ``index`` of
    ``SeedSequence(seed).spawn``; depends only on ``(seed, index)`` (both integers ≥ 0).
    """
    s = _check_nonnegative_int(seed, "seed")
    i = _check_nonnegative_int(index, "realization index")
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(s, spawn_key=(i,))))
