"""Sobol' indices from a Saltelli design: analytic functions against exact indices, the inverse-CDF mapping of
the design, convergence in N, failed runs, the result object and its JSON.

Tolerances: an estimate must lie within its 95 % bootstrap confidence interval, and the interval must be
narrow enough to tell the exact indices apart — half-width below half the smallest gap between the distinct
exact values of that output, so that the interval excludes every other parameter's exact index and a wrong
estimator, a swapped parameter or a wrong mapping of the design fails. N is chosen to meet that width.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from drillstring.case import load_case
from drillstring.stochastic.sensitivity import SobolResult, saltelli_design, sobol_analysis, sobol_indices
from drillstring.stochastic.uncertainty import uncertainty

A, B = 7.0, 0.1  # Ishigami constants
# Three parameters whose range allows [0, 2π]; the models shift them to X ~ U(−π, π).
PATHS = ("fluid.inlet_velocity", "bit_rock.a1", "damping.rigid_axial")


@pytest.fixture(scope="module")
def case():
    return load_case("reference")


@pytest.fixture(scope="module")
def uniform3(case):
    return uncertainty(case, {p: f"uniform 0 {2 * math.pi!r}" for p in PATHS})


def ishigami_exact():
    """Exact Sobol' indices of Y = sin X1 + a sin² X2 + b X3⁴ sin X1, X_i ~ U(−π, π) (Ishigami & Homma 1990)."""
    v1 = 0.5 * (1 + B * math.pi**4 / 5) ** 2
    v2 = A**2 / 8
    v13 = 8 * B**2 * math.pi**8 / 225
    v = v1 + v2 + v13
    return np.array([v1 / v, v2 / v, 0.0]), np.array([(v1 + v13) / v, v2 / v, v13 / v])


def analytic_model(values: np.ndarray) -> dict[str, np.ndarray]:
    x = values - math.pi
    return {
        "ishigami": np.sin(x[:, 0]) + A * np.sin(x[:, 1]) ** 2 + B * x[:, 2] ** 4 * np.sin(x[:, 0]),
        "linear": x[:, 0] + 2 * x[:, 1] + 3 * x[:, 2],
    }


@pytest.fixture(scope="module")
def ishigami(uniform3) -> SobolResult:
    return sobol_analysis(uniform3, analytic_model, 4096, seed=1, resamples=500)


def assert_within_ci(estimate, half_width, exact):
    distinct = np.unique(np.round(exact, 12))
    max_half_width = 0.5 * np.min(np.diff(distinct))
    assert np.all(half_width < max_half_width), (half_width, max_half_width)
    assert np.all(np.abs(estimate - exact) <= half_width), (estimate, exact, half_width)


def test_ishigami_against_exact_indices(ishigami):
    s1, st = ishigami_exact()
    o = ishigami.outputs.index("ishigami")
    assert_within_ci(ishigami.S1[o], ishigami.S1_conf[o], s1)  # half-widths < 0.064
    assert_within_ci(ishigami.ST[o], ishigami.ST_conf[o], st)  # half-widths < 0.058
    # X3 acts only through its interaction with X1: first order ~0, total clearly not
    assert ishigami.ST_interval[o, 2, 0] > 0.2 and ishigami.S1_interval[o, 2, 0] < 0 < ishigami.S1_interval[o, 2, 1]


def test_linear_output_of_the_same_runs(ishigami):
    exact = np.array([1.0, 4.0, 9.0]) / 14.0  # a_j² Var X_j / Σ, equal variances
    o = ishigami.outputs.index("linear")
    assert_within_ci(ishigami.S1[o], ishigami.S1_conf[o], exact)
    assert_within_ci(ishigami.ST[o], ishigami.ST_conf[o], exact)


def test_linear_model_with_non_uniform_laws(case):
    """Y = Σ w_j (X_j − μ_j)/σ_j with the declared μ, σ: S_j = S_Tj = w_j² / Σ w², whatever the laws —
    provided the design is mapped to each declared law (a uniform mapping would change the variances)."""
    declared = {
        "operation.top_speed": ("normal 100 5 rpm", 100 * math.pi / 30, 5 * math.pi / 30),
        "bit_rock.a2": ("gamma mean=5.7e-8 std=0.6e-8", 5.7e-8, 0.6e-8),
        "fluid.inlet_velocity": ("uniform 1.2 1.8 m/s", 1.5, 0.6 / math.sqrt(12)),
        "damping.modal_damping_ratio": ("maxent min=0.1 max=0.5 mean=0.25 std=0.08", 0.25, 0.08),
        "contact.friction_coefficient": ("exponential 0.002", 0.002, 0.002),
    }
    w = np.sqrt([1.0, 5.0, 9.0, 13.0, 22.0])  # exact indices 0.02, 0.10, 0.18, 0.26, 0.44
    mu = np.array([d[1] for d in declared.values()])
    sigma = np.array([d[2] for d in declared.values()])
    u = uncertainty(case, {p: d[0] for p, d in declared.items()})

    def model(values):
        return {"y": ((values - mu) / sigma) @ w}

    r = sobol_analysis(u, model, 4096, seed=3, resamples=500)
    exact = w**2 / np.sum(w**2)
    assert_within_ci(r.S1[0], r.S1_conf[0], exact)  # half-widths < 0.04
    assert_within_ci(r.ST[0], r.ST_conf[0], exact)


def test_design_maps_the_unit_hypercube_through_each_law(case):
    laws = {
        "operation.top_speed": ("normal 100 5 rpm", stats.norm(100 * math.pi / 30, 5 * math.pi / 30)),
        "bit_rock.a2": ("gamma mean=5.7e-8 std=0.6e-8", stats.gamma((5.7 / 0.6) ** 2, scale=0.36e-16 / 5.7e-8)),
        "fluid.inlet_velocity": ("uniform 1.2 1.8 m/s", stats.uniform(1.2, 0.6)),
        "contact.friction_coefficient": ("exponential 0.002", stats.expon(scale=0.002)),
    }
    u = uncertainty(case, {p: law for p, (law, _) in laws.items()})
    n, k = 1024, 4
    d = saltelli_design(u, n, seed=9)
    assert d.runs == n * (k + 2) and d.values.shape == d.unit.shape == (n * (k + 2), k)
    assert np.array_equal(d.values, u.from_unit(d.unit))
    blocks = d.values.reshape(n, k + 2, k)
    a, b = blocks[:, 0, :], blocks[:, -1, :]
    for j in range(k):  # A with column j from B
        ab = blocks[:, 1 + j, :]
        assert np.array_equal(ab[:, j], b[:, j])
        assert np.array_equal(np.delete(ab, j, axis=1), np.delete(a, j, axis=1))
    # each 1-D projection of N = 2^m scrambled Sobol' points has one point per interval [i/N, (i+1)/N), so the
    # empirical distribution of the mapped column is within 1/N of the declared law (Kolmogorov distance)
    for j, (_, ref) in enumerate(laws.values()):
        for column in (a[:, j], b[:, j]):
            assert stats.kstest(column, ref.cdf).statistic <= 1.0 / n + 1e-9
    # the design depends only on (uncertainty, N, seed)
    assert np.array_equal(saltelli_design(u, n, seed=9).unit, d.unit)
    assert not np.array_equal(saltelli_design(u, n, seed=10).unit, d.unit)


def test_convergence_levels_are_prefixes_of_the_design(uniform3, ishigami):
    assert ishigami.convergence_samples == (1024, 2048, 4096)
    assert np.array_equal(ishigami.S1_convergence[-1], ishigami.S1)
    assert np.array_equal(ishigami.ST_convergence[-1], ishigami.ST)
    half = sobol_analysis(uniform3, analytic_model, 2048, seed=1, resamples=500)
    # same design prefix, same estimator: equal to round-off (NumPy's SIMD sin differs by an ulp between
    # the vector body and the tail of an array, so the two model evaluations need not agree bit for bit)
    np.testing.assert_allclose(half.S1, ishigami.S1_convergence[1], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(half.ST, ishigami.ST_convergence[1], rtol=1e-12, atol=1e-14)
    change = ishigami.convergence_change("ishigami")
    assert change.shape == (2,)
    o = ishigami.outputs.index("ishigami")
    assert change[-1] <= max(ishigami.S1_conf[o].max(), ishigami.ST_conf[o].max())


def test_batches_give_the_same_result(uniform3):
    whole = sobol_analysis(uniform3, analytic_model, 64, seed=2, resamples=50)
    calls = []

    def counting(values):
        calls.append(len(values))
        return analytic_model(values)

    batched = sobol_analysis(uniform3, counting, 64, seed=2, resamples=50, batch_size=100)
    assert calls == [100, 100, 100, 20]
    assert np.array_equal(whole.S1, batched.S1) and np.array_equal(whole.ST_conf, batched.ST_conf)


def test_failed_runs_drop_their_base_samples(uniform3):
    design = saltelli_design(uniform3, 1024, seed=4)
    y = analytic_model(design.values)["linear"]
    broken = y.copy()
    broken[[7, 8, 5 * 100 + 2]] = np.nan  # runs 7 and 8 are in block 1, run 502 in block 100
    r = sobol_indices(design, {"linear": y, "broken": broken}, resamples=100)
    assert r.dropped == {"linear": 0, "broken": 2}
    exact = np.array([1.0, 4.0, 9.0]) / 14.0
    assert_within_ci(r.S1[1], r.S1_conf[1], exact)
    kept = np.delete(y.reshape(1024, 5), [1, 100], axis=0)
    # the estimate on the kept blocks is what the analysis of those blocks alone gives
    from SALib.analyze import sobol as salib

    ref = salib.analyze({"num_vars": 3, "names": list(PATHS), "bounds": [[0, 1]] * 3}, kept.reshape(-1),
                        calc_second_order=False, num_resamples=100, seed=1)
    assert np.allclose(r.S1[1], ref["S1"], rtol=1e-14, atol=1e-15)
    assert np.allclose(r.ST_conf[1], ref["ST_conf"], rtol=1e-14)


def test_constant_output_has_undefined_indices(uniform3):
    design = saltelli_design(uniform3, 8, seed=0)
    r = sobol_indices(design, {"constant": np.full(design.runs, 3.0)}, resamples=10)
    assert np.all(np.isnan(r.S1)) and np.all(np.isnan(r.ST_conf))
    data = json.loads(r.to_json())
    assert data["outputs"]["constant"]["S1"][PATHS[0]] is None


def test_result_to_json(ishigami, tmp_path):
    path = tmp_path / "sensitivity.json"
    text = ishigami.to_json(path)
    data = json.loads(path.read_text())
    assert data == json.loads(text)
    assert data["base_samples"] == 4096 and data["runs"] == 4096 * 5 and data["confidence_level"] == 0.95
    assert list(data["parameters"]) == list(PATHS)
    entry = data["outputs"]["ishigami"]
    for j, p in enumerate(PATHS):
        assert entry["S1"][p] == ishigami.S1[0, j]
        assert entry["ST_ci"][p] == [ishigami.ST[0, j] - ishigami.ST_conf[0, j], ishigami.ST[0, j] + ishigami.ST_conf[0, j]]
        assert entry["convergence"]["S1"][p][-1] == ishigami.S1[0, j]
    assert entry["convergence"]["base_samples"] == [1024, 2048, 4096]
    assert entry["dropped_base_samples"] == 0
    assert ishigami.indices("linear")["S1"]["bit_rock.a1"] == ishigami.S1[1, 1]
    with pytest.raises(KeyError, match="unknown output 'rop'"):
        ishigami.indices("rop")


@pytest.mark.parametrize("n, error, message", [
    (0, ValueError, "must be a power of 2 and >= 8"), (7, ValueError, "must be a power of 2 and >= 8"),
    (100, ValueError, "must be a power of 2 and >= 8"), (1000, ValueError, "must be a power of 2 and >= 8"),
    (2**19, ValueError, "524288: above the limit of 262144"),
    (4.0, TypeError, "must be an integer"), (True, TypeError, "must be an integer")])
def test_base_samples_must_be_a_power_of_two(uniform3, n, error, message):
    with pytest.raises(error, match=message):
        saltelli_design(uniform3, n)


def test_bad_inputs(case, uniform3):
    joint = uncertainty(case, {"operation.top_speed": "normal 100 5 rpm", "weight_on_hook": "normal 1063.4 5 kN"},
                        correlated=["operation.top_speed", "weight_on_hook"], correlation=[[1, 0.2], [0.2, 1]])
    with pytest.raises(ValueError, match="need independent parameters"):
        saltelli_design(joint, 64)
    design = saltelli_design(uniform3, 8)
    with pytest.raises(ValueError, match=r"shape \(10,\); it must be \(40,\)"):
        sobol_indices(design, {"y": np.zeros(10)})
    with pytest.raises(ValueError, match="confidence"):
        sobol_indices(design, {"y": np.zeros(40)}, confidence=95)
    with pytest.raises(TypeError, match="must return a non-empty mapping"):
        sobol_analysis(uniform3, lambda v: v[:, 0], 8)
    with pytest.raises(ValueError, match="returned 3 values of 'y' for a batch of 40 rows"):
        sobol_analysis(uniform3, lambda v: {"y": np.zeros(3)}, 8)


def test_too_small_a_sample_is_flagged(uniform3, ishigami):
    """N = 8 (allowed): the Ishigami indices have intervals wider than themselves, negative values or totals
    below first-order ones, and the notes say so; at N = 4096 (each index within ±0.064 of the exact one) there
    is no note for either output."""
    small = sobol_analysis(uniform3, analytic_model, 8, seed=1, resamples=200)
    notes = small.sample_notes("ishigami")
    assert notes and any("interval wider than the index" in n for n in notes)
    o = small.outputs.index("ishigami")
    flawed = (np.any(small.S1_conf[o] > np.maximum(np.abs(small.S1[o]), 0.05))
              or np.any(small.ST[o] < small.S1[o] - 0.05) or np.any(small.S1[o] < -0.05))
    assert flawed  # what the notes report is there
    assert small.to_dict()["outputs"]["ishigami"]["sample_notes"] == notes
    assert ishigami.sample_notes("ishigami") == [] and ishigami.sample_notes("linear") == []
