"""Uncertain parameters: each declared information set's MaxEnt law against its closed form, spec parsing
round trips, errors, joint normal laws, and reproducible inverse-CDF sampling.

The references are independent of the module: scipy.stats laws, and for the truncated laws the parameters of
the closed form solved here with scipy.optimize from the declared moments.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, special, stats

from drillstring.case import load_case
from drillstring.stochastic.maxent import realization_generator
from drillstring.stochastic.parameters import ParameterError
from drillstring.stochastic.uncertainty import (
    OUT_OF_RANGE_TOLERANCE,
    Uncertainty,
    parse_law,
    split_assignment,
    uncertainty,
)

RPM = 2.0 * math.pi / 60.0


@pytest.fixture(scope="module")
def case():
    return load_case("reference")


def _truncated_exponential(a: float, b: float, m: float) -> tuple[float, stats.rv_continuous]:
    """p(x) ∝ exp(−λ x) on [a, b] with mean m: λ solved from the closed-form mean."""
    L = b - a

    def mean_error(lam: float) -> float:
        if abs(lam) < 1e-12:
            return a + L / 2 - m
        return a + 1.0 / lam - L / math.expm1(lam * L) - m

    lam = optimize.brentq(mean_error, -50 / L, 50 / L, xtol=1e-14)
    assert lam > 0  # a mean below the middle of [a, b]
    return lam, stats.truncexpon(b=lam * L, loc=a, scale=1.0 / lam)


def _truncated_normal(a: float, b: float, m: float, s: float) -> stats.rv_continuous:
    """The normal truncated to [a, b] whose mean and std are m and s: parent (μ, σ) solved here."""

    def law(p):
        mu, sigma = p[0], math.exp(p[1])
        return stats.truncnorm((a - mu) / sigma, (b - mu) / sigma, loc=mu, scale=sigma)

    def error(p):
        d = law(p)
        return [d.mean() - m, d.std() - s]

    sol = optimize.root(error, [m, math.log(s)], tol=1e-14)
    assert max(abs(e) for e in error(sol.x)) < 1e-12 * m
    return law(sol.x)


def _gamma_from_mean_std(m: float, s: float):
    return stats.gamma((m / s) ** 2, scale=s * s / m)


# (parameter path, spec, kind found, reference law in SI)
LAWS = [
    ("fluid.inlet_velocity", "uniform 1.2 1.8 m/s", "uniform", stats.uniform(1.2, 0.6)),
    ("fluid.inlet_velocity", "uniform 72 108 m/min", "uniform", stats.uniform(1.2, 0.6)),
    ("operation.top_speed", "normal 100 5 rpm", "normal", stats.norm(100 * RPM, 5 * RPM)),
    ("weight_on_hook", "normal 1063.4 5 kN", "normal", stats.norm(1.0634e6, 5e3)),
    ("contact.friction_coefficient", "exponential 0.002", "exponential", stats.expon(scale=0.002)),
    ("bit_rock.a1", "exponential 12 min=3 m/h", "exponential", stats.expon(loc=3 / 3600, scale=9 / 3600)),
    ("bit_rock.a2", "gamma mean=5.7e-8 std=0.6e-8", "gamma", _gamma_from_mean_std(5.7e-8, 0.6e-8)),
    ("bit_rock.a2", "gamma 5.7e-8 0.6e-8", "gamma", _gamma_from_mean_std(5.7e-8, 0.6e-8)),
    (
        "bit_rock.a2",
        f"gamma mean=5e-8 log_mean={float(special.digamma(2.5)) + math.log(2e-8)!r}",
        "gamma",
        stats.gamma(2.5, scale=2e-8),
    ),
    (  # a log-mean declared in kN: E{ln(X/kN)}
        "operation.weight_on_bit",
        f"gamma mean=100 log_mean={float(special.digamma(40.0)) + math.log(2.5)!r} kN",
        "gamma",
        stats.gamma(40.0, scale=2.5e3),
    ),
    ("fluid.inlet_velocity", "maxent min=1.2 max=1.8 m/s", "uniform", stats.uniform(1.2, 0.6)),
    ("operation.top_speed", "maxent mean=100 std=5 rpm", "normal", stats.norm(100 * RPM, 5 * RPM)),
    ("contact.friction_coefficient", "maxent min=0 mean=0.002", "exponential", stats.expon(scale=0.002)),
    ("fluid.inlet_velocity", "maxent min=1.2 max=1.8 mean=1.4 m/s", "numerical",
     _truncated_exponential(1.2, 1.8, 1.4)[1]),
    ("damping.modal_damping_ratio", "maxent min=0.1 max=0.5 mean=0.25 std=0.08", "numerical",
     _truncated_normal(0.1, 0.5, 0.25, 0.08)),
    ("fluid.inlet_velocity", "maxent min=0 mean=1.5 std=0.9 m/s", "numerical",
     _truncated_normal(0.0, math.inf, 1.5, 0.9)),
]


@pytest.mark.parametrize(("path", "spec", "kind", "reference"), LAWS, ids=[f"{p}={s}" for p, s, _, _ in LAWS])
def test_law_of_each_information_set_matches_its_closed_form(case, path, spec, kind, reference):
    u = uncertainty(case, {path: spec})
    density = u.parameters[0].law.density
    assert density.kind == kind
    assert density.mean() == pytest.approx(reference.mean(), rel=1e-9)
    assert density.std() == pytest.approx(reference.std(), rel=1e-8)
    q = np.linspace(0.005, 0.995, 41)
    x = reference.ppf(q)
    assert np.allclose(density.pdf(x), reference.pdf(x), rtol=1e-7, atol=0)
    assert np.allclose(density.cdf(x), q, rtol=0, atol=1e-9)
    assert np.allclose(density.ppf(q), x, rtol=1e-8, atol=0)


def test_truncated_exponential_multiplier(case):
    lam, _ = _truncated_exponential(1.2, 1.8, 1.4)
    law = uncertainty(case, {"fluid.inlet_velocity": "maxent min=1.2 max=1.8 mean=1.4 m/s"}).parameters[0].law
    # p(x) = exp(−λ0 − λ1 x): λ1 is the decay rate
    assert law.density.lagrange_multipliers[1] == pytest.approx(lam, rel=1e-8)


def test_declared_moments_are_reproduced(case):
    u = uncertainty(case, {
        "operation.top_speed": "normal 100 5 rpm",
        "bit_rock.a2": "gamma mean=5.7e-8 std=0.6e-8",
        "damping.modal_damping_ratio": "maxent min=0.1 max=0.5 mean=0.25 std=0.08",
        "fluid.inlet_velocity": "uniform 1.2 1.8 m/s",
    })
    assert np.allclose(u.mean(), [100 * RPM, 5.7e-8, 0.25, 1.5], rtol=1e-10)
    assert np.allclose(u.std(), [5 * RPM, 0.6e-8, 0.08, 0.6 / math.sqrt(12)], rtol=1e-8)
    assert u.units == ("rad/s", "m/(N*s)", "", "m/s")


# ---------------------------------------------------------------------------------------------- parsing


@pytest.mark.parametrize(
    "spec",
    [
        "uniform 1.2 1.8 m/s",
        "normal 100 5 rpm",
        "exponential 12 min=3 m/h",
        "gamma mean=5.7e-8 std=0.6e-8",
        "gamma mean=5e-8 log_mean=-16.9",
        "maxent min=1.2 max=1.8 mean=1.4 std=0.1 m/s",
        "maxent min=0 mean=1.5 std=0.9 ft/s",
        "normal 0.1 2.5e-3 zorks/h",
    ],
)
def test_spec_round_trips(spec):
    from drillstring.case import DIMENSIONS

    velocity = next(d for d in DIMENSIONS if d.name == "velocity")
    dim = velocity if any(u in spec for u in ("m/s", "m/h", "ft/s")) else None
    if "rpm" in spec:
        dim = next(d for d in DIMENSIONS if d.name == "angular speed")
    if dim is None:
        dim = next(d for d in DIMENSIONS if d.name == "dimensionless number")
    if "zorks/h" in spec:
        with pytest.raises(ValueError, match="unknown unit 'zorks/h'"):
            parse_law(spec, velocity)
        return
    law = parse_law(spec, dim)
    again = parse_law(law.to_spec(), dim)
    assert again == law and again.to_spec() == law.to_spec()
    assert parse_law(law.to_mapping(), dim) == law
    assert again.support == law.support
    assert [c.value for c in again.constraints] == [c.value for c in law.constraints]


def test_spec_spelling_variants_give_the_same_law(case):
    dim = _dim("angular speed")
    ref = parse_law("normal 100 5 rpm", dim)
    for spec in ("normal mean=100 std=5 rpm", "Normal  100  std = 5  rpm", "normal std=5 mean=100 rev/min",
                 {"law": "normal", "mean": 100, "std": 5, "unit": "rpm"}):
        law = parse_law(spec, dim)
        assert law.density.mean() == ref.density.mean() and law.density.std() == pytest.approx(ref.density.std())
    assert parse_law("gamma 5.7e-8 0.6e-8", _dim("dimensionless number")).to_spec() == "gamma mean=5.7e-08 std=6e-09"
    assert parse_law("normal 100 5", dim).unit == "" and parse_law("normal 100 5", dim).density.mean() == 100.0


def _dim(name):
    from drillstring.case import DIMENSIONS

    return next(d for d in DIMENSIONS if d.name == name)


@pytest.mark.parametrize(
    ("path", "spec", "fragments"),
    [
        ("operation.top_speed", "normal 100 rpm", ["normal needs mean and std (missing std)", "e.g. 'normal 100 5 rpm'"]),
        ("operation.top_speed", "normal 100 5 kN", ["'normal 100 5 kN'", "force unit", "allowed units: rad/s, rpm"]),
        ("operation.top_speed", "weibull 1 2", ["unknown law 'weibull'", "uniform, normal, exponential, gamma, maxent"]),
        ("operation.top_speed", "uniform 1 2 rpm 3", ["'3' comes after the unit 'rpm'"]),
        ("operation.top_speed", "uniform 1 2 3 rpm", ["uniform takes min max, got 3 numbers"]),
        ("operation.top_speed", "uniform 2 1 rpm", ["min = 2 must be less than max = 1"]),
        ("operation.top_speed", "normal 100 -5 rpm", ["std = -5 must be > 0"]),
        ("operation.top_speed", "normal mean=100 sd=5 rpm", ["normal has no key 'sd'; its keys: mean, std"]),
        ("operation.top_speed", "normal 100 mean=5 rpm", ["mean is given twice"]),
        ("operation.top_speed", "normal 100 std=fast rpm", ["the value of std must be a number"]),
        ("operation.top_speed", "", ["empty law"]),
        ("bit_rock.a2", "gamma mean=5 std=1 log_mean=1", ["exactly one of std and log_mean"]),
        ("bit_rock.a2", "gamma mean=5e-8 log_mean=-10", ["Jensen"]),
        ("fluid.inlet_velocity", "exponential 1 min=2", ["mean = 1 must lie strictly between min = 2 and max = inf"]),
        ("fluid.inlet_velocity", "maxent min=1 max=2 mean=3", ["mean = 3 must lie strictly between"]),
        ("fluid.inlet_velocity", "maxent min=1 max=2 mean=1.5 std=0.9", ["variance", "too large"]),
        ("fluid.inlet_velocity", "maxent mean=1.5", ["does not define a normalisable"]),
        ("fluid.inlet_velocity", "maxent min=0 mean=1 std=1.5", ["does not define a normalisable"]),
        ("fluid.inlet_velocity", "maxent std=1", ["maxent needs mean"]),
        ("damping.modal_damping_ratio", "uniform 0.1 0.5 rpm", ["a plain number without unit is expected"]),
        ("damping.modal_damping_ratio", "uniform 0.5 1.2", ["probability 0.286 outside the allowed range (>= 0 and < 1)"]),
        ("operation.top_speed", "normal 100 60 rpm", ["probability 0.0478 outside the allowed range (>= 0.001 and <= 1000 rad/s)"]),
        ("reduced_model.axial_modes", "uniform 1 5", ["integer setting cannot carry a continuous law"]),
        ("operation.top_sped", "uniform 1 5", ["unknown case parameter 'operation.top_sped'"]),
    ],
)
def test_bad_laws_give_one_clear_line(case, path, spec, fragments):
    with pytest.raises(ParameterError) as info:
        uncertainty(case, {path: spec})
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path} = {spec!r}") or "unknown case parameter" in message, message
    for fragment in fragments:
        assert fragment in message, message


def test_out_of_range_tolerance_boundary(case):
    # a normal top speed 4.7 standard deviations above zero: P(X <= 0) = Φ(−4.7) ≈ 1.3e-6 > 1e-6, refused;
    # at 4.8 (7.9e-7) accepted
    assert stats.norm.cdf(-4.7) > OUT_OF_RANGE_TOLERANCE > stats.norm.cdf(-4.8)
    with pytest.raises(ParameterError, match="outside the allowed range"):
        uncertainty(case, {"operation.top_speed": "normal 47 10 rpm"})
    uncertainty(case, {"operation.top_speed": "normal 48 10 rpm"})


def test_mapping_round_trip_and_table_errors(case):
    table = {
        "parameters": {"operation.top_speed": "normal 100 5 rpm", "weight_on_hook": "normal 1063.4 5 kN",
                       "fluid.inlet_velocity": {"law": "uniform", "min": 1.2, "max": 1.8, "unit": "m/s"}},
        "correlation": {"parameters": ["weight_on_hook", "operation.top_speed"], "matrix": [[1, -0.3], [-0.3, 1]]},
    }
    u = Uncertainty.from_mapping(case, table)
    assert u.to_mapping()["parameters"]["fluid.inlet_velocity"] == "uniform 1.2 1.8 m/s"
    assert Uncertainty.from_mapping(case, u.to_mapping()) == u
    for bad, fragment in [
        ({"parameter": {}}, "uncertainty.parameter: unknown key"),
        ({"parameters": {}}, "non-empty table"),
        ({"parameters": {"operation.top_speed": "normal 100 5 rpm"}, "correlation": {"matrix": [[1]]}},
         "exactly the keys parameters and matrix"),
    ]:
        with pytest.raises(ParameterError, match=fragment):
            Uncertainty.from_mapping(case, bad)


def test_split_assignment():
    assert split_assignment('fluid.inlet_velocity="uniform 1.2 1.8 m/s"') == (
        "fluid.inlet_velocity", "uniform 1.2 1.8 m/s")
    assert split_assignment("bit_rock.a2=gamma mean=5.7e-8 std=0.6e-8") == ("bit_rock.a2", "gamma mean=5.7e-8 std=0.6e-8")
    with pytest.raises(ParameterError, match="is not PATH=LAW"):
        split_assignment("operation.top_speed")


# ---------------------------------------------------------------------------------------------- joint laws


@pytest.fixture(scope="module")
def joint(case):
    return uncertainty(
        case,
        {"operation.top_speed": "normal 100 5 rpm", "fluid.inlet_velocity": "uniform 1.2 1.8 m/s",
         "weight_on_hook": "normal 1063.4 5 kN", "bit_rock.a2": "normal 5.7e-8 0.5e-8"},
        correlated=["operation.top_speed", "weight_on_hook", "bit_rock.a2"],
        correlation=[[1.0, -0.4, 0.2], [-0.4, 1.0, 0.5], [0.2, 0.5, 1.0]],
    )


def test_correlated_normals_are_the_multivariate_normal(joint):
    assert not joint.independent
    s = np.array([5 * RPM, 0.6 / math.sqrt(12), 5e3, 0.5e-8])
    r = np.eye(4)
    r[np.ix_([0, 2, 3], [0, 2, 3])] = [[1.0, -0.4, 0.2], [-0.4, 1.0, 0.5], [0.2, 0.5, 1.0]]
    # the normal's variance comes back from E{X²} − E{X}²: ~1e-11 relative round-off for weight_on_hook
    assert np.allclose(joint.covariance(), r * np.outer(s, s), rtol=1e-10, atol=0)
    n = 200_000
    x = joint.from_unit(np.random.default_rng(5).random((n, 4)))
    corr = np.corrcoef(x, rowvar=False)
    # standard error of a sample correlation ≈ (1 − ρ²)/√n ≤ 2.3e-3: allow 5 of them
    assert np.allclose(corr, r, atol=5 / math.sqrt(n))
    assert np.allclose(x.mean(axis=0), [100 * RPM, 1.5, 1.0634e6, 5.7e-8], rtol=0, atol=5 * s / math.sqrt(n))
    # each correlated marginal is still its declared normal, the uniform is untouched (independent of the others)
    for j, ref in ((0, stats.norm(100 * RPM, 5 * RPM)), (2, stats.norm(1.0634e6, 5e3)), (1, stats.uniform(1.2, 0.6))):
        assert stats.kstest(x[:, j], ref.cdf).pvalue > 1e-3
    # the joint density is the MaxEnt one for mean and covariance: N(μ, C), whose whitened vector is N(0, I)
    g = [0, 2, 3]
    c = joint.covariance()[np.ix_(g, g)]
    w = np.linalg.solve(np.linalg.cholesky(c), (x[:, g] - [100 * RPM, 1.0634e6, 5.7e-8]).T)
    m2 = np.sum(w * w, axis=0)  # Mahalanobis distances: chi-squared with 3 degrees of freedom
    assert stats.kstest(m2, stats.chi2(3).cdf).pvalue > 1e-3


@pytest.mark.parametrize(
    ("correlated", "matrix", "fragment"),
    [
        (["operation.top_speed", "fluid.inlet_velocity"], [[1, 0.1], [0.1, 1]], "only normal parameters can be correlated"),
        (["operation.top_speed", "weight_on_hook"], [[1, 0.1], [0.2, 1]], "must be symmetric"),
        (["operation.top_speed", "weight_on_hook"], [[1, 0.1], [0.1, 0.9]], "the diagonal must be 1"),
        (["operation.top_speed", "weight_on_hook"], [[1, 1.5], [1.5, 1]], "must be in [-1, 1]"),
        (["operation.top_speed", "weight_on_hook"], [[1, 1], [1, 1]], "positive definite"),
        (["operation.top_speed", "weight_on_hook"], [[1, 0.1, 0], [0.1, 1, 0]], "must be 2 x 2"),
        (["operation.top_speed", "bit_rock.a1"], [[1, 0.1], [0.1, 1]], "'bit_rock.a1' is not a declared uncertain parameter"),
        (["operation.top_speed"], [[1]], "at least 2 parameters"),
        (["operation.top_speed", "weight_on_hook"], None, "give both"),
    ],
)
def test_bad_correlations(case, correlated, matrix, fragment):
    laws = {"operation.top_speed": "normal 100 5 rpm", "weight_on_hook": "normal 1063.4 5 kN",
            "fluid.inlet_velocity": "uniform 1.2 1.8 m/s"}
    with pytest.raises(ParameterError) as info:
        uncertainty(case, laws, correlated=correlated, correlation=matrix)
    assert fragment in str(info.value) and "\n" not in str(info.value)


# ---------------------------------------------------------------------------------------------- sampling


def test_draws_depend_only_on_seed_and_index(joint):
    all_rows = joint.draw(7, range(12))
    assert np.array_equal(joint.draw(7, [9, 3]), all_rows[[9, 3]])
    assert np.array_equal(all_rows[4], joint.from_unit(realization_generator(7, 4).random(4)))
    assert not np.array_equal(joint.draw(8, [4]), all_rows[[4]])


def test_draws_follow_the_declared_laws(case):
    refs = {
        "operation.top_speed": ("normal 100 5 rpm", stats.norm(100 * RPM, 5 * RPM)),
        "bit_rock.a2": ("gamma mean=5.7e-8 std=0.6e-8", _gamma_from_mean_std(5.7e-8, 0.6e-8)),
        "damping.modal_damping_ratio": ("maxent min=0.1 max=0.5 mean=0.25 std=0.08", _truncated_normal(0.1, 0.5, 0.25, 0.08)),
        "fluid.inlet_velocity": ("maxent min=1.2 max=1.8 mean=1.4 m/s", _truncated_exponential(1.2, 1.8, 1.4)[1]),
    }
    u = uncertainty(case, {p: spec for p, (spec, _) in refs.items()})
    x = u.draw(3, range(3000))
    for j, (_, ref) in enumerate(refs.values()):
        assert stats.kstest(x[:, j], ref.cdf).pvalue > 1e-3
    # the unit-interval ends map inside the support (never an infinite end)
    ends = u.from_unit(np.array([[0.0] * 4, [1.0] * 4]))
    assert np.all(np.isfinite(ends))
    with pytest.raises(ValueError, match=r"shape \(n, 4\)"):
        u.from_unit(np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"lie in \[0, 1\]"):
        u.from_unit(np.full((1, 4), 1.5))


def test_apply_sets_a_row_on_the_case(case, joint):
    row = joint.draw(0, [1])[0]
    new = joint.apply(case, row)
    assert new.operation.top_speed == row[0] and new.fluid.inlet_velocity == row[1]
    assert new.weight_on_hook == pytest.approx(row[2], rel=1e-12) and new.bit_rock.a2 == row[3]
    bad = row.copy()
    bad[2] = 2e6
    with pytest.raises(ParameterError, match="weight_on_hook = 2000000.0: must be in"):
        joint.apply(case, bad)
