"""Tests of the Monte Carlo statistics (SPEC §8), :mod:`drillstring.stochastic.statistics`, on known answers."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from drillstring.stochastic.statistics import (
    dispersion,
    dispersion_summary,
    mean_square_convergence,
    quantile_envelope,
    realization_statistics,
)

# ---------------------------------------------------------------------------------------------------------
# conv(n)
# ---------------------------------------------------------------------------------------------------------


def test_mean_square_convergence_scalar_closed_form():
    # U_j(t) = a_j sin t on [0, π]: ∫ U_j² dt = a_j² π/2, so conv(n) = (π/2) mean(a_1..a_n ²).
    # sin² = (1 − cos 2t)/2 and the trapezoid rule is exact for cos 2t over its full period.
    rng = np.random.default_rng(0)
    a = rng.normal(1.0, 0.3, size=50)
    t = np.linspace(0.0, math.pi, 401)
    u = a[:, None] * np.sin(t)[None, :]
    conv = mean_square_convergence(u, t)
    expected = 0.5 * math.pi * np.cumsum(a**2) / np.arange(1, a.size + 1)
    assert conv.shape == (50,)
    np.testing.assert_allclose(conv, expected, rtol=1e-12)


def test_mean_square_convergence_vector_observable():
    # U_j = (a_j sin t, b_j cos t): ||U_j||² integrates to (a_j² + b_j²) π/2 on [0, π]
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=20), rng.normal(size=20)
    t = np.linspace(0.0, math.pi, 257)
    u = np.stack([a[:, None] * np.sin(t), b[:, None] * np.cos(t)], axis=-1)
    assert u.shape == (20, 257, 2)
    conv = mean_square_convergence(u, t)
    expected = 0.5 * math.pi * np.cumsum(a**2 + b**2) / np.arange(1, 21)
    np.testing.assert_allclose(conv, expected, rtol=1e-12)
    # non-uniform time grid, linear observable U = c t on [0, 2]: ∫ c² t² dt = 8c²/3 (trapezoid: O(h²))
    t = np.sort(np.concatenate([[0.0, 2.0], np.random.default_rng(2).uniform(0, 2, 4000)]))
    c = np.array([1.0, 2.0])
    conv = mean_square_convergence(c[:, None] * t[None, :], t)
    np.testing.assert_allclose(conv, [8 / 3, (8 / 3) * (1 + 4) / 2], rtol=1e-5)


@pytest.mark.parametrize(
    ("samples", "time", "match"),
    [
        (np.array([[1.0, 2.0], [np.nan, 1.0]]), np.array([0.0, 1.0]), r"NaN \(1 realization"),
        (np.array([[1.0, np.inf]]), np.array([0.0, 1.0]), "inf"),
        (np.ones((2, 3)), np.array([0.0, 1.0]), "time must have shape"),
        (np.ones((2, 3)), np.array([0.0, 2.0, 1.0]), "strictly increasing"),
        (np.ones(3), np.array([0.0, 1.0, 2.0]), "shape"),
    ],
)
def test_mean_square_convergence_refuses_bad_input(samples, time, match):
    with pytest.raises(ValueError, match=match):
        mean_square_convergence(samples, time)


# ---------------------------------------------------------------------------------------------------------
# Quantile envelope
# ---------------------------------------------------------------------------------------------------------


def test_envelope_of_large_normal_sample_matches_exact_quantiles():
    n = 200_000
    sigmas = np.array([1.0, 5000.0, 0.01])
    means = np.array([0.0, 1.0634e6, -3.0])
    rng = np.random.default_rng(42)
    x = means + sigmas * rng.standard_normal((n, 3))
    lower, upper = quantile_envelope(x, 0.95)
    z = stats.norm.ppf(0.975)  # 1.959964
    # sampling standard error of a sample q-quantile: sqrt(q(1 − q)/n) / f(x_q)
    se = math.sqrt(0.025 * 0.975 / n) / stats.norm.pdf(z) * sigmas
    assert np.all(np.abs(lower - (means - z * sigmas)) < 5 * se)
    assert np.all(np.abs(upper - (means + z * sigmas)) < 5 * se)
    # same along another axis
    lo_t, up_t = quantile_envelope(x.T, 0.95, axis=1)
    np.testing.assert_array_equal(lo_t, lower)
    np.testing.assert_array_equal(up_t, upper)


def test_envelope_exact_on_uniform_grid():
    # sample 0, 1, ..., 999 (shuffled). "linear" (Hyndman–Fan 7): position (n − 1) q -> 24.975 and 974.025.
    x = np.random.default_rng(3).permutation(np.arange(1000.0))
    lower, upper = quantile_envelope(x, 0.95)
    assert lower == pytest.approx(24.975, abs=1e-9)
    assert upper == pytest.approx(974.025, abs=1e-9)
    lower, upper = quantile_envelope(x, 0.90)
    assert lower == pytest.approx(49.95, abs=1e-9)
    assert upper == pytest.approx(949.05, abs=1e-9)
    # "inverted_cdf" (smallest x with F_n(x) >= q) on 0..998: F_n(k) = (k + 1)/999 -> 24 and 974.
    # (On 0..999, q·n = 25 sits exactly on a jump, where 1 − 0.95 = 0.05000000000000004 in binary decides.)
    y = np.random.default_rng(4).permutation(np.arange(999.0))
    lower, upper = quantile_envelope(y, 0.95, method="inverted_cdf")
    assert (lower, upper) == (24.0, 974.0)
    lower, upper = quantile_envelope(y, 0.95)  # linear: (n − 1) q = 24.95 and 973.05
    assert (lower, upper) == (pytest.approx(24.95, abs=1e-9), pytest.approx(973.05, abs=1e-9))


def test_envelope_validation():
    with pytest.raises(ValueError, match="level"):
        quantile_envelope(np.arange(10.0), 1.5)
    with pytest.raises(ValueError, match="NaN"):
        quantile_envelope(np.array([1.0, np.nan, 2.0]))


# ---------------------------------------------------------------------------------------------------------
# Dispersion
# ---------------------------------------------------------------------------------------------------------


def _standardised(n, seed):
    z = np.random.default_rng(seed).standard_normal(n)
    z -= z.mean()
    return z / z.std(ddof=1)  # sample mean 0, sample std (ddof = 1) 1


def test_dispersion_known_mean_and_std():
    z = _standardised(101, 4)
    x = np.column_stack([5.0 + 0.2 * z, -2.0 + 0.5 * z, 1.0634e6 + 5000.0 * z])
    np.testing.assert_allclose(dispersion(x), [0.2 / 5.0, 0.5 / 2.0, 5000.0 / 1.0634e6], rtol=1e-12)
    np.testing.assert_allclose(dispersion(x.T, axis=1), dispersion(x), rtol=1e-15)
    # ddof = 0: std scaled by sqrt((n − 1)/n)
    np.testing.assert_allclose(dispersion(x, ddof=0), dispersion(x) * math.sqrt(100 / 101), rtol=1e-12)
    assert dispersion(5.0 + 0.2 * z) == pytest.approx(0.04, rel=1e-12)


def test_dispersion_zero_mean_is_nan_without_warnings():
    z = _standardised(11, 5)
    x = np.column_stack([z, 3.0 + z, np.zeros(11)])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = dispersion(x)
    assert np.isnan(d[0]) or abs(d[0]) > 1e10  # mean is 0 up to rounding: undefined or huge
    assert d[1] == pytest.approx(1 / 3, rel=1e-12)
    assert np.isnan(d[2])  # 0/0
    exact_zero = np.array([[-1.0, 2.0], [1.0, 2.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = dispersion(exact_zero)
    assert np.isnan(d[0]) and d[1] == 0.0


def test_dispersion_validation():
    with pytest.raises(ValueError, match="NaN"):
        dispersion(np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match="realizations"):
        dispersion(np.array([[1.0, 2.0]]))  # one realization with ddof = 1


# ---------------------------------------------------------------------------------------------------------
# xarray wrappers
# ---------------------------------------------------------------------------------------------------------


def _study(n_s=200, seed=6):
    rng = np.random.default_rng(seed)
    time = np.linspace(0.0, 10.0, 41)
    node = np.array([0.0, 800.0, 1600.0])
    woh = 1.0634e6 + 5000.0 * rng.standard_normal(n_s)
    rop = (woh / 1.0634e6)[:, None] ** 8 * (1.0 + 0.1 * np.sin(time))[None, :] * 0.01
    disp = (woh[:, None, None] - 1.0634e6) * 1e-9 * np.cos(time)[None, :, None] * node[None, None, :]
    ds = xr.Dataset(
        {
            "rate_of_penetration": (("realization", "time"), rop, {"units": "m/s", "long_name": "rate of penetration"}),
            "radial_displacement": (("realization", "time", "node"), disp, {"units": "m"}),
            "mesh_size": ((), 10.0, {"units": "m"}),
        },
        coords={
            "realization": np.arange(n_s),
            "time": ("time", time, {"units": "s"}),
            "node": node,
            "weight_on_hook": ("realization", woh, {"units": "N"}),
        },
        attrs={"case": "reference"},
    )
    return ds


def test_realization_statistics_dataset():
    ds = _study()
    st = realization_statistics(ds, level=0.95)
    expected_vars = {
        f"{v}_{s}"
        for v in ("rate_of_penetration", "radial_displacement")
        for s in ("mean", "std", "lower", "upper", "dispersion")
    }
    assert set(st.data_vars) == expected_vars  # mesh_size has no realization dim: left out
    assert "realization" not in st.dims
    assert "weight_on_hook" not in st.coords  # coordinate along the realizations is dropped
    np.testing.assert_array_equal(st["time"].values, ds["time"].values)
    assert st["time"].attrs["units"] == "s"
    assert st["rate_of_penetration_mean"].dims == ("time",)
    assert st["radial_displacement_upper"].dims == ("time", "node")
    # values equal the NumPy core definitions
    rop = ds["rate_of_penetration"].values
    np.testing.assert_allclose(st["rate_of_penetration_mean"], rop.mean(axis=0), rtol=1e-14)
    np.testing.assert_allclose(st["rate_of_penetration_std"], rop.std(axis=0, ddof=1), rtol=1e-12)
    lo, up = quantile_envelope(rop, 0.95)
    np.testing.assert_array_equal(st["rate_of_penetration_lower"], lo)
    np.testing.assert_array_equal(st["rate_of_penetration_upper"], up)
    np.testing.assert_allclose(st["rate_of_penetration_dispersion"], dispersion(rop), rtol=1e-12)
    rd = ds["radial_displacement"].transpose("realization", "time", "node").values
    lo, up = quantile_envelope(rd, 0.95)
    np.testing.assert_array_equal(st["radial_displacement_lower"].transpose("time", "node"), lo)
    # node 0 has identically zero displacement: dispersion NaN, not an error
    assert np.all(np.isnan(st["radial_displacement_dispersion"].sel(node=0.0)))
    # attributes
    assert st["rate_of_penetration_mean"].attrs["units"] == "m/s"
    assert st["rate_of_penetration_lower"].attrs["units"] == "m/s"
    assert st["rate_of_penetration_lower"].attrs["quantile"] == pytest.approx(0.025)
    assert st["rate_of_penetration_upper"].attrs["quantile"] == pytest.approx(0.975)
    assert st["rate_of_penetration_std"].attrs["long_name"] == "std of rate of penetration"
    assert st["rate_of_penetration_dispersion"].attrs["units"] == "1"
    assert st["radial_displacement_std"].attrs["units"] == "m"
    assert st.attrs["n_realizations"] == 200 and st.attrs["level"] == 0.95
    assert st.attrs["quantile_method"] == "linear"


def test_realization_statistics_dataarray_and_other_dim_name():
    rng = np.random.default_rng(7)
    da = xr.DataArray(
        rng.normal(3.0, 0.3, size=(4, 500)),
        dims=("time", "sample"),
        coords={"time": [0.0, 1.0, 2.0, 3.0]},
        name="bit_speed",
        attrs={"units": "rad/s"},
    )
    st = realization_statistics(da, dim="sample", level=0.9)
    assert set(st.data_vars) == {f"bit_speed_{s}" for s in ("mean", "std", "lower", "upper", "dispersion")}
    lo, up = quantile_envelope(da.values, 0.9, axis=1)
    np.testing.assert_array_equal(st["bit_speed_lower"], lo)
    np.testing.assert_array_equal(st["bit_speed_upper"], up)
    assert st["bit_speed_mean"].attrs["units"] == "rad/s"
    unnamed = realization_statistics(da.rename(None), dim="sample")
    assert "data_mean" in unnamed
    # lazily loaded (dask) data give the same result
    st_dask = realization_statistics(da.chunk({"time": 2}), dim="sample", level=0.9).compute()
    xr.testing.assert_allclose(st, st_dask)


def test_realization_statistics_refuses_nan_and_missing_dim():
    ds = _study(n_s=10)
    bad = ds.copy(deep=True)
    bad["rate_of_penetration"][3, 5] = np.nan
    with pytest.raises(ValueError, match=r"NaN in 1 realization"):
        realization_statistics(bad)
    # after dropping the failed realization it works
    st = realization_statistics(bad.dropna("realization", how="any"))
    assert st.attrs["n_realizations"] == 9
    with pytest.raises(ValueError, match="dimension 'sample' not found"):
        realization_statistics(ds, dim="sample")


def _stats_with_dispersion(time, delta, name="rate_of_penetration"):
    return xr.Dataset(
        {f"{name}_dispersion": ("time", np.asarray(delta, dtype=float), {"units": "1"})},
        coords={"time": ("time", np.asarray(time, dtype=float), {"units": "s"})},
    )


def test_dispersion_summary_after_transient():
    # transient (t < 1 s) with a large dispersion, then δ(t) = 0.02 + 0.01 sin(2π t) on [1, 3]:
    # the trapezoid time-mean over whole periods is 0.02 exactly, the maximum 0.03 at t = 1.25 s and 2.25 s
    t = np.linspace(0.0, 3.0, 301)
    delta = np.where(t < 1.0, 0.5, 0.02 + 0.01 * np.sin(2 * math.pi * t))
    st = _stats_with_dispersion(t, delta)
    st["bit_speed_dispersion"] = ("time", np.where(t < 1.0, 1.0, 0.004 + 0.0 * t))
    out = dispersion_summary(
        st,
        ["rate_of_penetration", "bit_speed"],
        t_transient=1.0,
        input_dispersion={"weight_on_hook": 0.005, "weight_on_bit": 0.01},
    )
    rop = out["rate_of_penetration"]
    assert rop["dispersion_time_mean"] == pytest.approx(0.02, abs=1e-14)
    assert rop["dispersion_max"] == pytest.approx(0.03, rel=1e-12)
    assert rop["time_of_max"] == pytest.approx(1.25)
    assert rop["t_start"] == pytest.approx(1.0) and rop["t_end"] == 3.0 and rop["n_times"] == 201
    assert rop["ratio_time_mean"] == pytest.approx({"weight_on_hook": 4.0, "weight_on_bit": 2.0})
    assert rop["ratio_max"] == pytest.approx({"weight_on_hook": 6.0, "weight_on_bit": 3.0})
    bs = out["bit_speed"]
    assert bs["dispersion_time_mean"] == pytest.approx(0.004, rel=1e-12)
    assert bs["ratio_max"]["weight_on_hook"] == pytest.approx(0.8)
    # without the cut the transient dominates
    assert dispersion_summary(st, "bit_speed", t_transient=0.0)["bit_speed"]["dispersion_max"] == 1.0
    # plain JSON
    text = json.dumps(out, allow_nan=False)
    assert json.loads(text) == out
    assert all(type(v) in (float, int, dict) for v in rop.values())


def test_dispersion_summary_time_average_on_non_uniform_grid_and_undefined_points():
    # δ = 0.01 t on a non-uniform grid over [1, 3]: time average 0.02 (the sample mean would differ)
    t = np.array([0.0, 1.0, 1.1, 1.2, 2.9, 3.0])
    delta = 0.01 * t
    st = _stats_with_dispersion(t, delta)
    out = dispersion_summary(st, ["rate_of_penetration"], t_transient=1.0)["rate_of_penetration"]
    assert out["dispersion_time_mean"] == pytest.approx(0.02, rel=1e-12)
    assert out["ratio_time_mean"] == {} and out["ratio_max"] == {}
    delta[3] = np.nan  # mean exactly 0 at one time
    out = dispersion_summary(_stats_with_dispersion(t, delta), ["rate_of_penetration"], t_transient=1.0)
    assert out["rate_of_penetration"]["n_undefined"] == 1
    assert out["rate_of_penetration"]["dispersion_max"] == pytest.approx(0.03)


def test_dispersion_summary_validation():
    st = _stats_with_dispersion([0.0, 1.0, 2.0], [0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="no output time >= t_transient"):
        dispersion_summary(st, ["rate_of_penetration"], t_transient=5.0)
    with pytest.raises(ValueError, match=r"no dispersion for 'torque_on_bit'.*available: \['rate_of_penetration'\]"):
        dispersion_summary(st, ["torque_on_bit"], t_transient=0.0)
    with pytest.raises(ValueError, match="input dispersion 'weight_on_hook'"):
        dispersion_summary(st, ["rate_of_penetration"], t_transient=0.0, input_dispersion={"weight_on_hook": 0.0})
    two_d = xr.Dataset(
        {"x_dispersion": (("time", "node"), np.ones((3, 2)))}, coords={"time": [0.0, 1.0, 2.0], "node": [0, 1]}
    )
    with pytest.raises(ValueError, match="select the others first"):
        dispersion_summary(two_d, ["x"], t_transient=0.0)
    # end to end: statistics of a study, then the summary, one entry per variable
    summary = dispersion_summary(
        realization_statistics(_study()),
        ["rate_of_penetration"],
        t_transient=2.0,
        input_dispersion={"weight_on_hook": 5000.0 / 1.0634e6},
    )
    # ROP ∝ WOH⁸ here, so the dispersion is amplified about 8 times
    assert summary["rate_of_penetration"]["ratio_time_mean"]["weight_on_hook"] == pytest.approx(8.0, rel=0.15)


def test_record_start_after_the_mean_leaves_zero():
    from drillstring.stochastic.statistics import record_start

    t = np.arange(0.0, 20.0, 0.01)
    mean = np.minimum(t / 2.0, 1.0)  # ramps from 0 to 1 over 2 s, then steady
    start = record_start(t, mean, 10.0)
    assert start == pytest.approx(0.2)  # first time with |mean| >= 0.1 of its steady value
    assert record_start(t, np.ones_like(t), 10.0) == 0.0  # never near 0: the record starts at t = 0
    dipped = mean.copy()
    dipped[(t > 5.0) & (t < 5.5)] = 0.0  # a late dip before the transient ends moves the start after it
    assert record_start(t, dipped, 10.0) == pytest.approx(5.5)
    mean_nan = mean.copy()
    mean_nan[0] = np.nan
    assert record_start(t, mean_nan, 10.0) == pytest.approx(0.2)
