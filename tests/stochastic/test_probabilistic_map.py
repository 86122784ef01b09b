"""Probabilistic operating maps: the probability of a buckled string at every point against its closed form
from the weight-on-bit law, the per-point statistics, the random streams, resume and refusals."""

import math

import numpy as np
import pytest
from scipy import stats

from drillstring.buckling import case_buckling_margin
from drillstring.stochastic import execution
from drillstring.stochastic import probabilistic_map as pm
from drillstring.stochastic.maxent import realization_generator
from drillstring.stochastic.operating_map import MapSettings
from drillstring.stochastic.store import DONE, StoreError

RPM = math.pi / 30.0
SIGMA = 5e3


def _settings(critical, samples=40, seed=3, t_end=1.0, **extra):
    grid = MapSettings((100 * RPM,), (critical - 6e3, critical, critical + 4e3), t_end=t_end, output_step=0.05)
    return pm.SampledMapSettings(grid, samples=samples, seed=seed, **({"sigma": SIGMA} | extra))


@pytest.fixture(scope="module")
def buckling_map(small_case, tmp_path_factory):
    critical = case_buckling_margin(small_case).critical_weight_on_bit
    settings = _settings(critical)
    path = tmp_path_factory.mktemp("pmap") / "map.zarr"
    run = pm.run_sampled_map(small_case, settings, path, execution.Engine(workers=1))
    return critical, settings, pm.sampled_map_dataset(run.store.path)


def test_buckling_probability_against_the_closed_form(buckling_map):
    """wob = weight − woh with woh Normal around each point's hook load: wob ~ N(wob_point, σ), so a draw is
    buckled iff wob > wob_cr and P = Φ((wob_point − wob_cr)/σ). Each realization's flag (lowest lateral
    eigenvalue < 0, from the realized model) equals the closed-form event, and P̂ is within 4 binomial
    standard errors (+ 1/n) of P at every point."""
    critical, settings, ds = buckling_map
    assert int(ds.attrs["n_done"]) == settings.realizations
    n = settings.samples
    for j, wob in enumerate(ds.weight_on_bit.values):
        realized = ds.realized_weight_on_bit.values[0, j]
        buckled = ds.lowest_lateral_eigenvalue.values[0, j] < 0
        clear = np.abs(realized - critical) > 1.0  # draws within 1 N of the critical load: either flag
        np.testing.assert_array_equal(buckled[clear], (realized > critical)[clear])
        exact = stats.norm.cdf((wob - critical) / SIGMA)
        estimate = float(ds.buckling_probability.values[0, j])
        assert abs(estimate - exact) <= 4 * math.sqrt(exact * (1 - exact) / n) + 1.0 / n, (wob, estimate, exact)
        assert float(ds.buckling_probability_standard_error.values[0, j]) == pytest.approx(
            math.sqrt(estimate * (1 - estimate) / n))
    p = ds.buckling_probability.values[0]
    assert p[0] < p[1] < p[2]  # 6 kN below, at, 4 kN above the critical load: Φ(-1.2), 1/2, Φ(0.8)


def test_draws_are_one_stream_per_realization_common_to_the_points(buckling_map):
    """Realization s of every point draws the weight-on-hook woh_point + σ Φ⁻¹(u_s), u_s the first number of
    stream (seed, s), so its weight-on-bit is wob_point − σ Φ⁻¹(u_s)."""
    critical, settings, ds = buckling_map
    u = np.array([realization_generator(settings.seed, s).random(1)[0] for s in range(settings.samples)])
    z = stats.norm.ppf(u)
    for j, wob in enumerate(ds.weight_on_bit.values):
        np.testing.assert_allclose(ds.realized_weight_on_bit.values[0, j], wob - SIGMA * z, rtol=1e-9)


def test_per_point_statistics_from_the_realizations(buckling_map):
    """Every probability is the share of its event among the point's finished realizations; the quantiles are
    those of the realizations' values."""
    _, settings, ds = buckling_map
    done = ds.status.values == DONE
    for name, (output, event, _) in pm.PROBABILITIES.items():
        values = ds[output].values
        with np.errstate(invalid="ignore"):  # NaN (no steady drilling): not an event
            expected = (event(values) & done).sum(axis=2) / done.sum(axis=2)
        np.testing.assert_allclose(ds[name].values, expected, err_msg=name)
    for output, name in pm.QUANTILE_OUTPUTS.items():
        for j in range(ds.sizes["weight_on_bit"]):
            np.testing.assert_allclose(ds[name].values[0, j], np.quantile(ds[output].values[0, j], pm.QUANTILES))
    summary = pm.sampled_map_summary(ds)
    assert summary["probabilities"]["buckling_probability"]["values"][0] == pytest.approx(
        list(ds.buckling_probability.values[0]))


def test_an_interrupted_map_resumes_to_the_same_map_and_a_deterministic_store_is_refused(torsional_case, tmp_path):
    grid = MapSettings((8.0, 12.0), (6e4,), t_end=2.0, output_step=0.05)
    settings = pm.SampledMapSettings(grid, samples=3, seed=1, sigma=4e3)
    whole = pm.run_sampled_map(torsional_case, settings, tmp_path / "whole.zarr", execution.Engine(workers=1))
    assert whole.completed == 6

    def interrupt_after_two(done, failed, total):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(execution.Interrupted, match="map interrupted after 2 of 6 realizations.*resume"):
        pm.run_sampled_map(torsional_case, settings, tmp_path / "cut.zarr",
                           execution.Engine(workers=1, progress=interrupt_after_two))
    resumed = pm.run_sampled_map(torsional_case, settings, tmp_path / "cut.zarr", execution.Engine(workers=1))
    assert resumed.completed == 6 and resumed.computed == 4
    a, b = pm.sampled_map_dataset(tmp_path / "whole.zarr"), pm.sampled_map_dataset(tmp_path / "cut.zarr")
    for name in (*pm.SAMPLE_OUTPUTS, "input_values", *pm.PROBABILITIES, *pm.QUANTILE_OUTPUTS.values()):
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    other = pm.SampledMapSettings(grid, samples=3, seed=2, sigma=4e3)
    with pytest.raises(ValueError, match="holds a different probabilistic map"):
        pm.run_sampled_map(torsional_case, other, tmp_path / "cut.zarr", execution.Engine(workers=1))
    from drillstring.stochastic import operating_map as om

    om.run_map(torsional_case, grid, tmp_path / "deterministic.zarr", execution.Engine(workers=1))
    with pytest.raises(StoreError, match="it is a map store"):
        pm.sampled_map_dataset(tmp_path / "deterministic.zarr")


@pytest.mark.parametrize("extra, message", [
    ({"samples": 1}, "samples = 1"),
    ({"laws": (("weight_on_hook", "normal 1e6 1e3"),)}, "weight_on_hook: cannot carry a law on a map"),
    ({"laws": (("operation.weight_on_bit", "uniform 5e4 7e4"),)}, "operation.weight_on_bit: cannot carry"),
    ({"sigma": None}, "no random parameter"),
    ({"samples": 40_000}, "above the limit of 100000"),
])
def test_bad_settings_are_refused_in_one_line(extra, message):
    grid = MapSettings((8.0, 12.0), (6e4, 7e4), t_end=2.0, output_step=0.05)
    with pytest.raises(ValueError, match=message) as error:
        pm.SampledMapSettings(grid, **({"samples": 4, "sigma": 4e3} | extra))
    assert "\n" not in str(error.value)


def test_a_sigma_that_puts_a_point_out_of_range_is_refused_naming_the_point(torsional_case):
    """At 10 kN on the bit, σ = 5 kN puts wob < 0 with probability Φ(−2) = 0.023 > 1e-3."""
    grid = MapSettings((8.0,), (1e4, 1e5), t_end=2.0, output_step=0.05)
    with pytest.raises(ValueError, match=r"at the point 76.39 rpm, 10 kN.*probability 0.0228"):
        pm.check_sampled_map(torsional_case, pm.SampledMapSettings(grid, samples=4, sigma=5e3))
