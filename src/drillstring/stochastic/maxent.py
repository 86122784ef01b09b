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
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from scipy import optimize, special, stats

from drillstring.stochastic.maxent_constraints import (
    LOG_MEAN,
    MEAN,
    SECOND_MOMENT,
    Constraint,
    _RESERVED,
    _check_support,
    _identity,
    _validate_information,
    log_mean,
    mean,
    second_moment,
    variance_constraints,
)
from drillstring.stochastic.maxent_dual import (
    _FAR,
    _FAR_STEPS,
    _H_START,
    _LEVEL_TOL,
    _MAX_LEVELS,
    _NOISE_TOL,
    _Basis,
    _Map,
    _NumericalSolution,
    _Rule,
    _dual_terms,
    _location_scale,
    _newton,
    _raise_if_escaping,
)

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
