"""Tests of the Maximum-Entropy construction (SPEC §8), :mod:`drillstring.stochastic.maxent`.

References are independent of the module: closed forms come from :mod:`scipy.stats` directly, and the
non-standard cases are checked against a direct (primal) maximisation of the entropy of a discretised density
under the constraints with ``scipy.optimize.minimize(method="SLSQP")``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, special, stats

from drillstring.stochastic import maxent as me
from drillstring.stochastic.maxent import (
    Constraint,
    log_mean,
    maximum_entropy,
    mean,
    realization_generator,
    second_moment,
    variance_constraints,
)

INF = math.inf
WOH_MEAN = 1.0634e6  # N, reference case weight-on-hook (SPEC §10)


def _fourth(x):
    return x**4


def _log_squared(x):
    return np.log(x) ** 2


def _gamma_information(k: float, theta: float) -> list[Constraint]:
    # E{X} = kθ, E{ln X} = ψ(k) + ln θ
    return [mean(k * theta), log_mean(float(special.digamma(k)) + math.log(theta))]


# (id, support, constraints, scipy reference, closed-form kind, multipliers [λ0, λ1, ...] of eq. (3))
CLOSED_FORMS = [
    (
        "normal",
        (-INF, INF),
        list(variance_constraints(2.0, 0.5)),
        stats.norm(2.0, 0.5),
        "normal",
        [0.5 * math.log(2 * math.pi * 0.25) + 4.0 / 0.5, -2.0 / 0.25, 1.0 / 0.5],
    ),
    (
        "normal-woh",
        (-INF, INF),
        list(variance_constraints(WOH_MEAN, 5000.0)),
        stats.norm(WOH_MEAN, 5000.0),
        "normal",
        [
            0.5 * math.log(2 * math.pi * 5000.0**2) + WOH_MEAN**2 / (2 * 5000.0**2),
            -WOH_MEAN / 5000.0**2,
            1.0 / (2 * 5000.0**2),
        ],
    ),
    ("uniform", (-1.0, 3.0), [], stats.uniform(-1.0, 4.0), "uniform", [math.log(4.0)]),
    ("exponential", (0.0, INF), [mean(2.5)], stats.expon(scale=2.5), "exponential", [math.log(2.5), 1 / 2.5]),
    (
        "exponential-shifted",
        (1.0, INF),
        [mean(2.5)],
        stats.expon(loc=1.0, scale=1.5),
        "exponential",
        [math.log(1.5) - 1.0 / 1.5, 1 / 1.5],
    ),
    (
        "gamma-2.5",
        (0.0, INF),
        _gamma_information(2.5, 1.7),
        stats.gamma(2.5, scale=1.7),
        "gamma",
        [math.lgamma(2.5) + 2.5 * math.log(1.7), 1 / 1.7, -1.5],
    ),
    (
        "gamma-0.6-singular",
        (0.0, INF),
        _gamma_information(0.6, 3.0),
        stats.gamma(0.6, scale=3.0),
        "gamma",
        [math.lgamma(0.6) + 0.6 * math.log(3.0), 1 / 3.0, 0.4],
    ),
]


def _close(actual, expected, rel):
    np.testing.assert_allclose(actual, expected, rtol=rel, atol=0.0)


@pytest.mark.parametrize(
    ("support", "constraints", "ref", "kind", "multipliers"),
    [c[1:] for c in CLOSED_FORMS],
    ids=[c[0] for c in CLOSED_FORMS],
)
def test_numerical_dual_recovers_closed_form(support, constraints, ref, kind, multipliers):
    law = maximum_entropy(support, constraints, method="numerical")
    assert law.kind == "numerical"
    assert law.frozen is None
    x = ref.ppf([0.001, 0.02, 0.2, 0.5, 0.8, 0.98, 0.999])
    _close(law.pdf(x), ref.pdf(x), 1e-6)
    _close(law.logpdf(x), ref.logpdf(x), 1e-6)
    _close(law.mean(), ref.mean(), 1e-6)
    _close(law.var(), ref.var(), 1e-6)
    _close(law.std(), ref.std(), 1e-6)
    _close(law.entropy(), ref.entropy(), 1e-6)
    np.testing.assert_allclose(law.cdf(x), ref.cdf(x), rtol=1e-8, atol=1e-10)
    q = np.array([0.01, 0.25, 0.5, 0.75, 0.99])
    np.testing.assert_allclose(law.ppf(q), ref.ppf(q), rtol=1e-8, atol=1e-8 * ref.std())
    # the information is reproduced to 1e-8 relative (quadrature of the converged rule)
    for c in constraints:
        _close(law.expect(c.function), c.value, 1e-8)
    # Lagrange multipliers of eq. (3) match the closed form
    lam = law.lagrange_multipliers
    assert lam.shape == (len(constraints) + 1,)
    np.testing.assert_allclose(lam, multipliers, rtol=1e-6, atol=1e-9)
    # outside the support the density vanishes
    a, b = support
    if math.isfinite(a):
        assert law.pdf(a - 1.0) == 0.0 and law.cdf(a - 1.0) == 0.0
    if math.isfinite(b):
        assert law.pdf(b + 1.0) == 0.0 and law.cdf(b + 1.0) == 1.0


@pytest.mark.parametrize(
    ("support", "constraints", "ref", "kind", "multipliers"),
    [c[1:] for c in CLOSED_FORMS],
    ids=[c[0] for c in CLOSED_FORMS],
)
def test_auto_dispatches_to_closed_form(support, constraints, ref, kind, multipliers):
    law = maximum_entropy(support, constraints)
    assert law.kind == kind
    assert law.support == (float(support[0]), float(support[1]))
    x = ref.ppf([0.01, 0.3, 0.5, 0.9])
    _close(law.pdf(x), ref.pdf(x), 1e-12)
    _close(law.mean(), ref.mean(), 1e-12)
    _close(law.var(), ref.var(), 1e-10)
    _close(law.entropy(), ref.entropy(), 1e-12)
    np.testing.assert_allclose(law.lagrange_multipliers, multipliers, rtol=1e-10, atol=1e-15)
    assert law.frozen is not None
    assert law.frozen.dist.name == ref.dist.name
    # the multipliers reproduce the density through eq. (3): ln p = −λ0 − Σ λ_k g_k
    lam = law.lagrange_multipliers
    logp = -lam[0] - sum(lk * c.function(x) for lk, c in zip(lam[1:], constraints))
    _close(logp, ref.logpdf(x), 1e-9)


def test_auto_falls_back_to_numerical_when_no_closed_form():
    assert maximum_entropy((0.0, 1.0), [mean(0.3)]).kind == "numerical"  # truncated exponential
    assert maximum_entropy((-INF, INF), [*variance_constraints(0.0, 1.0), Constraint(_fourth, 2.5, "m4")]).kind == (
        "numerical"
    )
    # same names but a support that is not the closed form's
    assert maximum_entropy((0.0, INF), list(variance_constraints(3.0, 1.0))).kind == "numerical"
    with pytest.raises(ValueError, match="method"):
        maximum_entropy((0.0, 1.0), [], method="newton")


def test_gamma_shape_equation():
    for k in (0.05, 0.6, 1.0, 2.5, 30.0, 1e5):
        d = math.log(k) - float(special.digamma(k)) if k < 1e3 else 1 / (2 * k) + 1 / (12 * k * k)
        k_found = me.gamma_shape(1.0, -d)  # ln(1) − E{ln X} = d
        _close(k_found, k, 1e-9)


def test_truncated_normal_and_lognormal_are_recovered():
    """Two further laws with known form: [a, ∞) with mean and variance (variance < (mean − a)²) is a truncated
    Normal; (0, ∞) with E{ln X} and E{ln² X} is a lognormal."""
    # upper end at 40 sd rather than inf (scipy's truncnorm entropy is NaN with inf)
    tn = stats.truncnorm((2.0 - 2.5) / 0.8, 40.0, loc=2.5, scale=0.8)
    law = maximum_entropy((2.0, INF), [mean(tn.mean()), second_moment(tn.var() + tn.mean() ** 2)])
    x = tn.ppf([0.01, 0.2, 0.5, 0.9, 0.999])
    _close(law.pdf(x), tn.pdf(x), 1e-7)
    _close(law.entropy(), tn.entropy(), 1e-8)

    ln = stats.lognorm(0.5, scale=math.exp(0.2))
    law = maximum_entropy((0.0, INF), [log_mean(0.2), Constraint(_log_squared, 0.2**2 + 0.5**2, "log_second")])
    x = ln.ppf([0.01, 0.2, 0.5, 0.9, 0.999])
    _close(law.pdf(x), ln.pdf(x), 1e-7)
    _close(law.mean(), ln.mean(), 1e-8)
    _close(law.entropy(), ln.entropy(), 1e-8)


# ---------------------------------------------------------------------------------------------------------
# Non-standard information against a direct maximisation of the entropy
# ---------------------------------------------------------------------------------------------------------


def _primal_maxent(lower, upper, n, functions, values):
    """Maximise −Σ p_i ln p_i Δ over a midpoint grid (density values p_i ≥ 0) under Σ p_i Δ = 1 and
    Σ p_i g_k(x_i) Δ = m_k, by SLSQP from the uniform density. Returns grid, density and entropy."""
    dx = (upper - lower) / n
    x = lower + dx * (np.arange(n) + 0.5)
    G = np.vstack([np.ones(n)] + [f(x) for f in functions]) * dx
    target = np.concatenate([[1.0], values])

    def neg_entropy(p):
        return float(np.sum(p * np.log(p)) * dx)

    def neg_entropy_grad(p):
        return (np.log(p) + 1.0) * dx

    res = optimize.minimize(
        neg_entropy,
        np.full(n, 1.0 / (upper - lower)),
        jac=neg_entropy_grad,
        method="SLSQP",
        bounds=[(1e-12, None)] * n,
        constraints=[{"type": "eq", "fun": lambda p: G @ p - target, "jac": lambda p: G}],
        options={"maxiter": 1000, "ftol": 1e-12},
    )
    # judge the optimum by its feasibility (SLSQP may stop on its LSQ-subproblem limit at the optimum)
    assert res.status in (0, 3), res.message
    assert np.max(np.abs(G @ res.x - target)) < 1e-8, res.message
    return x, res.x, -res.fun


@pytest.mark.parametrize(
    ("support", "constraints", "grid", "n"),
    [
        ((0.0, 1.0), [mean(0.3), second_moment(0.15)], (0.0, 1.0), 80),
        (
            (-INF, INF),
            [*variance_constraints(0.0, 1.0), Constraint(_fourth, 2.5, "fourth_moment")],
            (-6.0, 6.0),
            60,
        ),
    ],
    ids=["bounded-mean-second-moment", "real-line-fourth-moment"],
)
def test_non_standard_case_against_direct_entropy_maximisation(support, constraints, grid, n):
    law = maximum_entropy(support, constraints)
    assert law.kind == "numerical"
    functions, values = [c.function for c in constraints], [c.value for c in constraints]
    x, p, entropy = _primal_maxent(grid[0], grid[1], n, functions, values)
    assert law.entropy() == pytest.approx(entropy, abs=1e-3)
    for c in constraints:
        assert law.expect(c.function) == pytest.approx(c.value, rel=1e-10, abs=1e-12)
        dx = x[1] - x[0]
        assert float(np.sum(p * c.function(x)) * dx) == pytest.approx(c.value, abs=1e-6)
    assert law.mean() == pytest.approx(float(np.sum(p * x) / np.sum(p)), abs=1e-3)
    # the densities agree where the grid density is resolved
    mask = p > 1e-3 * p.max()
    np.testing.assert_allclose(law.pdf(x[mask]), p[mask], rtol=5e-3, atol=1e-3 * p.max())
    # and the dual solution beats (or equals) the discrete optimum's entropy up to discretisation error
    assert law.entropy() >= entropy - 1e-3


def test_numerical_density_distribution_function_and_sampling():
    law = maximum_entropy((0.0, 1.0), [mean(0.3), second_moment(0.15)])
    q = np.array([1e-12, 1e-6, 0.025, 0.5, 0.975, 1 - 1e-9])
    np.testing.assert_allclose(law.cdf(law.ppf(q)), q, rtol=1e-9, atol=1e-15)
    assert law.ppf(0.0) == 0.0 and law.ppf(1.0) == 1.0
    assert np.isnan(law.ppf(1.5))
    # cdf is the integral of pdf (independent quadrature)
    from scipy import integrate

    for xv in (0.05, 0.3, 0.8):
        val, _ = integrate.quad(law.pdf, 0.0, xv, epsabs=1e-13, epsrel=1e-12)
        assert law.cdf(xv) == pytest.approx(val, rel=1e-9, abs=1e-13)
    # inverse-CDF sampling: moments within 5 standard errors and a Kolmogorov–Smirnov test
    rng = np.random.default_rng(12345)
    n = 20000
    s = law.ppf(rng.random(n))  # the studies' draw: the inverse distribution function of uniform draws
    assert s.shape == (n,)
    assert np.all((s > 0.0) & (s < 1.0))
    assert abs(s.mean() - 0.3) < 5 * law.std() / math.sqrt(n)
    assert stats.kstest(s, law.cdf).pvalue > 1e-3


# ---------------------------------------------------------------------------------------------------------
# The Normal law (support ℝ, known mean and standard deviation: the weight-on-hook's law of the studies)
# ---------------------------------------------------------------------------------------------------------


def test_normal_law_from_mean_and_standard_deviation():
    law = maximum_entropy((-INF, INF), variance_constraints(WOH_MEAN, 5000.0))
    assert law.kind == "normal"
    assert law.support == (-INF, INF)
    assert law.mean() == pytest.approx(WOH_MEAN, rel=1e-14)
    assert law.std() == pytest.approx(5000.0, rel=1e-9)
    assert law.frozen.dist.name == "norm"
    x = WOH_MEAN + 5000.0 * np.array([-3.0, -1.0, 0.0, 0.5, 2.0])
    _close(law.pdf(x), stats.norm(WOH_MEAN, 5000.0).pdf(x), 1e-9)


@pytest.mark.parametrize("sigma", [1000.0, 3000.0, 5000.0])
def test_normal_law_matches_numerical_dual_for_study_sigmas(sigma):
    closed = maximum_entropy((-INF, INF), variance_constraints(WOH_MEAN, sigma))
    numerical = maximum_entropy((-INF, INF), variance_constraints(WOH_MEAN, sigma), method="numerical")
    x = WOH_MEAN + sigma * np.array([-3.0, -1.0, 0.0, 2.0])
    _close(numerical.pdf(x), closed.pdf(x), 1e-6)
    _close(numerical.std(), sigma, 1e-8)
    _close(numerical.lagrange_multipliers, closed.lagrange_multipliers, 1e-6)


# ---------------------------------------------------------------------------------------------------------
# Reproducible streams
# ---------------------------------------------------------------------------------------------------------


def test_realization_generator_depends_only_on_seed_and_index():
    a = realization_generator(2024, 7).standard_normal(3)
    b = realization_generator(2024, 7).standard_normal(3)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, realization_generator(2024, 8).standard_normal(3))
    assert not np.array_equal(a, realization_generator(2025, 7).standard_normal(3))
    # identical to NumPy's spawned child streams
    child = np.random.SeedSequence(2024).spawn(8)[7]
    np.testing.assert_array_equal(a, np.random.Generator(np.random.PCG64(child)).standard_normal(3))
    with pytest.raises(ValueError, match="index"):
        realization_generator(1, -1)
    with pytest.raises(TypeError):
        realization_generator(1, 1.5)


def test_closed_form_and_numerical_normal_draws_are_statistically_equivalent():
    closed = maximum_entropy((-INF, INF), variance_constraints(WOH_MEAN, 3000.0))
    numerical = maximum_entropy((-INF, INF), variance_constraints(WOH_MEAN, 3000.0), method="numerical")
    draws = numerical.ppf(np.random.default_rng(99).random(5000))
    assert stats.kstest(draws, closed.cdf).pvalue > 1e-3


# ---------------------------------------------------------------------------------------------------------
# Impossible information
# ---------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("support", "constraints", "match"),
    [
        ((1.0, 1.0), [], r"support = \(1\.0, 1\.0\) is empty"),
        ((2.0, 1.0), [], "empty"),
        ((INF, INF), [], "empty"),
        ((0.0, 1.0), [mean(1.5)], r"mean = 1\.5 is outside the support.*\(0\.0, 1\.0\)"),
        ((0.0, INF), [mean(-2.0)], "mean = -2.0 is outside the support"),
        ((-INF, INF), [mean(1.0), second_moment(0.5)], r"variance = .*-0\.5.* must be > 0"),
        ((-INF, INF), [mean(1.0), second_moment(1.0)], r"variance = .*0\.0.* must be > 0"),
        ((0.0, 1.0), [mean(0.5), second_moment(0.6)], r"variance = .*too large.*\(0, 0\.25\)"),
        ((0.0, INF), [mean(2.0), log_mean(math.log(2.0))], r"log_mean E\{ln X\} = .* must be < ln\(mean\)"),
        ((0.0, INF), [mean(2.0), log_mean(1.0)], "Jensen"),
        ((-1.0, INF), [log_mean(0.0)], r"positive support \(a >= 0\)"),
        ((-INF, INF), [mean(1.0)], "does not define a normalisable"),
        ((0.0, INF), [], "does not define a normalisable"),
        ((-INF, INF), [*variance_constraints(0.0, 1.0), Constraint(_fourth, 4.0, "m4")], "normalisable"),
        ((0.0, 1.0), [mean(0.3), mean(0.4)], "given twice"),
        ((0.0, INF), [second_moment(1.0), Constraint(np.square, 1.0, "again")], "linearly dependent"),
    ],
)
def test_impossible_information_is_refused(support, constraints, match):
    with pytest.raises(ValueError, match=match):
        maximum_entropy(support, constraints)


def test_constraint_helpers_and_validation():
    m, m2 = variance_constraints(3.0, 2.0)
    assert (m.name, m.value, m2.name, m2.value) == ("mean", 3.0, "second_moment", 13.0)
    assert log_mean(0.5).name == "log_mean"
    x = np.array([1.0, 2.0])
    np.testing.assert_array_equal(m2.function(x), x**2)
    with pytest.raises(ValueError, match=r"std = 0\.0 must be finite and > 0"):
        variance_constraints(1.0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        Constraint(np.sin, math.inf, "bad")
    with pytest.raises(TypeError):
        Constraint(3.0, 1.0, "not callable")  # type: ignore[arg-type]
    with pytest.raises(AttributeError):
        m.value = 2.0  # frozen
