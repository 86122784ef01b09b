"""Study statistics and summary from a synthetic study with known dispersions."""

import numpy as np
import pytest
import xarray as xr

from drillstring.stochastic.analysis import study_statistics, study_summary
from drillstring.stochastic.montecarlo import STUDY_OBSERVABLES
from drillstring.stochastic.store import DONE


def synthetic_raw(n_s=400, seed=1):
    """Each observable is (1 + a_j) s(t) with a_j ~ N(0, 0.05²) and s(t) = 1 − e^{−t}: the dispersion is
    std(a)/mean(1 + a) at every t > 0, except for ROP, whose spread also grows linearly in time."""
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


def test_vibration_indicators_per_realization():
    """The bit speed (1 + a_j)(1 − e^{−t}) swings by (1 + a_j)(e^{−10} − e^{−30}) after 10 s and never
    drops below 10 % of the top speed (1 rad/s) unless a_j < −0.9."""
    raw, a = synthetic_raw(n_s=50)
    stats = study_statistics(raw, t_transient=10.0)
    expected = (1.0 + a) * (np.exp(-10.0) - np.exp(-30.0)) / 2.0
    np.testing.assert_allclose(stats["bit_speed_oscillation"].values, expected, rtol=1e-6)
    assert not stats["stick_time_fraction"].values.any()
    summary = study_summary(stats, t_transient=10.0)["indicators"]
    assert summary["stick_slip_realizations"] == 0
    assert summary["bit_speed_oscillation"]["max"] == pytest.approx(expected.max(), rel=1e-6)
