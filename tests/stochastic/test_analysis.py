"""Study statistics and summary from a synthetic study with known dispersions."""

import numpy as np
import pytest
import xarray as xr

from drillstring.dynamics.indicators import CYCLE_METRICS
from drillstring.stochastic.analysis import TIME_CONVERGENCE_THRESHOLD, study_statistics, study_summary
from drillstring.stochastic.montecarlo import STUDY_OBSERVABLES
from drillstring.stochastic.runs import REALIZATION_METRICS
from drillstring.stochastic.store import DONE


def synthetic_raw(n_s=400, seed=1, top_speed=1.0):
    """Each observable is (1 + a_j) s(t) with a_j ~ N(0, 0.05²) and s(t) = 1 − e^{−t}: the dispersion is
    std(a)/mean(1 + a) at every t > 0, except for ROP, whose spread also grows linearly in time. Each
    realization's top speed is ``top_speed`` (a number or one per realization), its bit area 0.1 m², its
    growth rate a_j; the cycle metrics the workers store are left NaN (no ``metrics_transient``: the
    statistics recompute them from the histories)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 30.0 + 1e-9, 0.05)
    a = rng.normal(0.0, 0.05, n_s)
    shape = 1.0 - np.exp(-t)
    data = {}
    for name in STUDY_OBSERVABLES:
        values = (1.0 + a[:, None]) * shape[None, :]
        if name == "rate_of_penetration":
            values = values + a[:, None] * (t[None, :] / 30.0) * shape[None, :]
        data[name] = (("realization", "time"), values)
        data[f"nominal_{name}"] = (("time",), shape)
    data["radial_displacement"] = (("realization", "time", "probe"), np.full((n_s, len(t), 1), 1e-4))
    data["nominal_radial_displacement"] = (("time", "probe"), np.full((len(t), 1), 1e-4))
    data["status"] = (("realization",), np.full(n_s, DONE))
    data["weight_on_hook"] = (("realization",), 1e6 + 5e3 * a / 0.05)
    data["weight_on_bit"] = (("realization",), 1e5 - 5e3 * a / 0.05)
    data["input_values"] = (("realization", "parameter"), (1e6 + 5e3 * a / 0.05)[:, None])
    for name in REALIZATION_METRICS:
        data[name] = (("realization",), np.full(n_s, np.nan))
        data[f"nominal_{name}"] = (("one",), [np.nan])
    data["top_speed"] = (("realization",), np.broadcast_to(np.asarray(top_speed, dtype=float), (n_s,)).copy())
    data["bit_area"] = (("realization",), np.full(n_s, 0.1))
    data["growth_rate"] = (("realization",), a.copy())
    data["nominal_top_speed"], data["nominal_bit_area"] = (("one",), [1.0]), (("one",), [0.1])
    data["nominal_growth_rate"] = (("one",), [0.0125])
    raw = xr.Dataset(data, coords={"time": t, "x": ("probe", [1560.0])})
    raw.attrs.update({"settings": {"sigma": 5e3, "seed": 0}, "weight_on_hook_mean": 1e6, "weight": 1.1e6,
                      "case": "[operation]\ntop_speed = 1.0\n", "parameters": ["weight_on_hook"],
                      "laws": ["normal 1000000 5000"], "parameter_units": ["N"], "parameter_mean": [1e6],
                      "parameter_std": [5e3]})
    return raw, a


def test_whole_record_and_steady_window():
    raw, a = synthetic_raw()
    summary = study_summary(study_statistics(raw), t_transient=10.0)
    expected = a.std(ddof=1) / abs(np.mean(1.0 + a))
    torque = summary["observables"]["torque_on_bit"]
    assert torque["dispersion_time_mean"] == pytest.approx(expected, rel=1e-9)
    whole = torque["whole_record"]
    assert whole["t_start"] == pytest.approx(0.15)  # 1 − e^{−t} ≥ 0.1 from t = 0.105 s: the next output
    assert whole["dispersion_time_mean"] == pytest.approx(expected, rel=1e-9)
    assert whole["ratio_time_mean"]["weight_on_hook"] == pytest.approx(expected / 5e-3, rel=1e-9)
    rop = summary["observables"]["rate_of_penetration"]
    # spread (1 + t/30) a: the dispersion grows in time, its maximum at the end of the record
    assert rop["whole_record"]["time_of_max"] == pytest.approx(30.0)
    at_end = 2 * a.std(ddof=1) / abs(np.mean(1.0 + 2 * a))  # (1 + 2a)(1 − e^{−30})
    assert rop["whole_record"]["dispersion_max"] == pytest.approx(at_end, rel=1e-9)
    assert rop["whole_record"]["dispersion_time_mean"] < rop["dispersion_time_mean"]


def test_cycle_metrics_per_realization_and_their_distributions():
    """After 10 s the bit speed (1 + a_j)(1 − e^{−t}) runs from (1 + a_j)(1 − e^{−10}) to (1 + a_j)(1 − e^{−30}):
    the extremes have the dispersion std(a)/mean(1 + a) of the draws, the stick-slip index
    (e^{−10} − e^{−30})/(2 m) (m the time mean of 1 − e^{−t}) is the same for every draw, and the bit never
    drops below 10 % of the top speed (1 rad/s); Teale's MSE from the time means."""
    raw, a = synthetic_raw(n_s=50)
    stats = study_statistics(raw, t_transient=10.0)
    t = raw.time.values
    shape = 1.0 - np.exp(-t[t >= 10.0])
    np.testing.assert_allclose(stats["realization_bit_speed_min"].values, (1 + a) * (1 - np.exp(-10.0)), rtol=1e-12)
    np.testing.assert_allclose(stats["realization_bit_speed_max"].values, (1 + a) * (1 - np.exp(-30.0)), rtol=1e-12)
    index = (np.exp(-10.0) - np.exp(-30.0)) / (2 * shape.mean())
    np.testing.assert_allclose(stats["realization_stick_slip_index"].values, index, rtol=1e-9)
    assert not stats["realization_stick_time_fraction"].values.any()
    assert np.isnan(stats["realization_period"].values).all()  # a monotonic record: no oscillation, no period
    tob = (1 + a) * shape.mean()
    rop = tob + a * np.mean(t[t >= 10.0] / 30.0 * shape)
    np.testing.assert_allclose(stats["realization_mechanical_specific_energy"].values, tob / 0.1 + 1.0 * tob / (0.1 * rop),
                               rtol=1e-12)
    np.testing.assert_allclose(stats["realization_bit_speed_oscillation"].values,
                               (1 + a) * (np.exp(-10.0) - np.exp(-30.0)) / 2.0, rtol=1e-9)
    summary = study_summary(stats, t_transient=10.0)["realizations"]
    assert set(CYCLE_METRICS) <= set(summary)
    top = summary["bit_speed_max"]
    assert top["n"] == 50 and top["mean"] == pytest.approx((1 + a.mean()) * (1 - np.exp(-30.0)), rel=1e-12)
    assert top["dispersion"] == pytest.approx(a.std(ddof=1) / (1 + a.mean()), rel=1e-9)
    for q in (2.5, 50.0, 97.5):
        assert top[f"q{q:g}"] == pytest.approx(np.quantile((1 + a) * (1 - np.exp(-30.0)), q / 100), rel=1e-12)
    assert summary["stick_slip_index"]["std"] == pytest.approx(0.0, abs=1e-12)
    assert summary["period"]["n"] == 0 and summary["period"]["mean"] is None
    assert summary["stick_slip_realizations"] == 0 and summary["t_transient"] == 10.0


def test_cycle_metrics_use_each_realizations_top_speed():
    """Half the draws turn at 20 rad/s: their bit speed (about 1 rad/s) is below 10 % of it all the time
    (stick time fraction 1, oscillation (max − min)/(2·20)); the others, at 1 rad/s, never stick."""
    n_s = 40
    top = np.where(np.arange(n_s) % 2 == 0, 20.0, 1.0)
    raw, a = synthetic_raw(n_s=n_s, top_speed=top)
    stats = study_statistics(raw, t_transient=10.0)
    np.testing.assert_array_equal(stats["realization_stick_time_fraction"].values, (top == 20.0).astype(float))
    swing = (1 + a) * (np.exp(-10.0) - np.exp(-30.0))
    np.testing.assert_allclose(stats["realization_bit_speed_oscillation"].values, swing / (2 * top), rtol=1e-9)
    assert study_summary(stats, t_transient=10.0)["realizations"]["stick_slip_realizations"] == n_s // 2


def test_stored_metrics_are_used_for_their_window_and_recomputed_for_another():
    raw, a = synthetic_raw(n_s=10)
    raw["period"] = ("realization", np.arange(10.0))
    raw["nominal_period"] = ("one", [4.0])
    raw.attrs["metrics_transient"] = 10.0
    stats = study_statistics(raw, t_transient=10.0)
    np.testing.assert_array_equal(stats["realization_period"].values, np.arange(10.0))  # as the workers stored them
    assert stats["realization_period"].attrs["nominal"] == 4.0
    assert np.isnan(stats["realization_bit_speed_max"].values).all()
    stats = study_statistics(raw, t_transient=5.0)  # another window: recomputed from the histories
    np.testing.assert_allclose(stats["realization_bit_speed_min"].values, (1 + a) * (1 - np.exp(-5.0)), rtol=1e-12)
    assert np.isnan(stats["realization_period"].values).all()


def test_stability_of_the_draws():
    raw, a = synthetic_raw(n_s=60)
    boundary = {"weight_on_bit": 96e3}
    section = study_summary(study_statistics(raw, t_transient=10.0), t_transient=10.0, boundary=boundary)["stability"]
    assert section["unstable_fraction"] == pytest.approx(np.mean(a > 0))
    assert section["unstable_realizations"] == int(np.sum(a > 0)) and section["realizations_with_growth_rate"] == 60
    assert section["growth_rate"]["mean"] == pytest.approx(a.mean())
    assert section["nominal_growth_rate"] == 0.0125 and section["boundary"] == boundary
    assert section["by_family"] == {}  # a store written before the families were told apart
    raw["torsional_growth_rate"] = ("realization", a - 0.02)  # per family, as the workers now store them
    raw["nominal_torsional_growth_rate"] = ("one", [-0.0075])
    raw["lateral_growth_rate"] = ("realization", np.full(60, np.nan))
    raw["nominal_lateral_growth_rate"] = ("one", [np.nan])
    section = study_summary(study_statistics(raw, t_transient=10.0), t_transient=10.0)["stability"]
    torsion = section["by_family"]["torsional"]
    assert torsion["unstable_realizations"] == int(np.sum(a > 0.02)) and torsion["realizations_with_roots"] == 60
    assert torsion["growth_rate"]["mean"] == pytest.approx(a.mean() - 0.02)
    assert torsion["nominal_growth_rate"] == -0.0075
    assert section["by_family"]["lateral"]["realizations_with_roots"] == 0 and "axial" not in section["by_family"]


def test_time_convergence_over_growing_windows():
    """The ROP's dispersion grows in time, std(a)(1 + t/30)/mean(1 + a(1 + t/30)), so its maximum over a
    record from 10 s to T is that value at T and keeps changing; the torque's is constant and converged."""
    raw, a = synthetic_raw(n_s=200)
    section = study_summary(study_statistics(raw, t_transient=10.0), t_transient=10.0)["time_convergence"]
    assert section["window"] == 10.0 and section["threshold"] == TIME_CONVERGENCE_THRESHOLD
    assert section["t_start"] == 10.0
    rop = section["observables"]["rate_of_penetration"]
    assert [w["t_end"] for w in rop["windows"]] == pytest.approx([20.0, 30.0])
    for window in rop["windows"]:
        factor = 1 + window["t_end"] / 30.0
        expected = factor * a.std(ddof=1) / abs(np.mean(1 + factor * a))
        assert window["dispersion_max"] == pytest.approx(expected, rel=1e-9)
        assert window["time_of_max"] == pytest.approx(window["t_end"])
    last, before = rop["windows"][-1]["dispersion_max"], rop["windows"][-2]["dispersion_max"]
    assert rop["change"]["dispersion_max"] == pytest.approx(abs(last - before) / last, rel=1e-12)
    assert rop["change"]["dispersion_max"] > TIME_CONVERGENCE_THRESHOLD
    torque = section["observables"]["torque_on_bit"]
    assert torque["change"]["dispersion_max"] == pytest.approx(0.0, abs=1e-9)
    assert torque["change"]["dispersion_time_mean"] == pytest.approx(0.0, abs=1e-9)
    assert "rate_of_penetration" in section["warning"] and "torque_on_bit" not in section["warning"]
    assert "maximum" in section["warning"]
    assert "t_end" in section["warning"]
    short = study_summary(study_statistics(raw, t_transient=25.0), t_transient=25.0)["time_convergence"]
    assert [w["t_end"] for w in short["observables"]["torque_on_bit"]["windows"]] == [30.0]
    assert short["warning"] is None  # one record: nothing to compare
