"""Drilling indicators of one run on synthetic records with known answers."""

import numpy as np
import pytest

from drillstring.dynamics.indicators import STICK_SPEED_RATIO, drilling_indicators, transient_end


def test_sinusoidal_bit_speed():
    t = np.linspace(0.0, 30.0, 3001)
    omega = 10.0
    speed = omega * (1.0 + 0.7 * np.sin(2 * np.pi * 0.25 * t))
    rop = 3e-3 + 1e-3 * np.sin(2 * np.pi * 0.25 * t)
    out = drilling_indicators(t, rop, speed, omega, 10.0)
    assert out["bit_speed_oscillation"] == pytest.approx(0.7, rel=1e-6)
    assert out["stick_time_fraction"] == 0.0 and out["stick_slip"] is False
    assert out["mean_rate_of_penetration"] == pytest.approx(3e-3, rel=1e-3)  # 5 whole periods after 10 s
    assert out["bit_speed_min"] == pytest.approx(3.0, rel=1e-6)


def test_stick_time_fraction_counts_samples_below_the_threshold():
    t = np.arange(0.0, 20.0, 0.01)
    omega = 10.0
    speed = np.full_like(t, omega)
    stuck = (t >= 12.0) & (t < 15.0)  # 3 s of the 10 s after the transient
    speed[stuck] = 0.5 * STICK_SPEED_RATIO * omega
    out = drilling_indicators(t, np.full_like(t, 1e-3), speed, omega, 10.0)
    assert out["stick_time_fraction"] == pytest.approx(0.3, abs=1e-9)
    assert out["stick_slip"] is True
    assert out["bit_speed_oscillation"] == pytest.approx((1 - 0.05) / 2)


def test_transient_and_failed_runs():
    assert transient_end(30.0) == 10.0 and transient_end(6.0) == 3.0
    t = np.arange(0.0, 4.0, 0.01)  # a run that stopped before the transient ended: use what there is
    out = drilling_indicators(t, np.ones_like(t), np.full_like(t, np.nan), 10.0, 10.0)
    assert out["mean_rate_of_penetration"] == 1.0 and out["bit_speed_oscillation"] is None


def test_cycle_metrics_of_a_sine_bit_speed():
    """Bit speed Ω(1 + 0.7 sin 2πt/4): after 10 s (5 whole periods) min 0.3Ω, max 1.7Ω, mean Ω, so the
    stick-slip index is 0.7, the period 4 s; ROP, TOB and FOB means are their constant parts."""
    from drillstring.dynamics.indicators import CYCLE_METRICS, cycle_metrics, mechanical_specific_energy

    t = np.arange(0.0, 30.0 + 1e-9, 0.001)
    omega, area = 10.0, 0.05
    phase = 2 * np.pi * t / 4.0
    obs = {"bit_speed": omega * (1.0 + 0.7 * np.sin(phase)), "rate_of_penetration": 3e-3 + 1e-3 * np.sin(phase),
           "torque_on_bit": 5e3 + 2e3 * np.cos(phase), "force_on_bit": np.full_like(t, 1e5)}
    out = cycle_metrics(t, obs, omega, area, 10.0)
    assert set(out) == set(CYCLE_METRICS)
    assert out["bit_speed_min"] == pytest.approx(0.3 * omega, rel=1e-9)
    assert out["bit_speed_max"] == pytest.approx(1.7 * omega, rel=1e-9)
    assert out["stick_slip_index"] == pytest.approx(0.7, rel=1e-4)
    assert out["period"] == pytest.approx(4.0, rel=1e-6)
    assert out["mean_rate_of_penetration"] == pytest.approx(3e-3, rel=1e-4)
    assert out["mean_torque_on_bit"] == pytest.approx(5e3, rel=1e-4)
    assert out["mean_force_on_bit"] == 1e5
    assert out["stick_time_fraction"] == 0.0
    expected = 1e5 / area + omega * 5e3 / (area * 3e-3)  # Teale with the time means
    assert out["mechanical_specific_energy"] == pytest.approx(expected, rel=1e-3)
    assert out["mechanical_specific_energy"] == pytest.approx(mechanical_specific_energy(
        1e5, out["mean_torque_on_bit"], omega, out["mean_rate_of_penetration"], area), rel=1e-14)


def test_cycle_metrics_of_a_stick_slip_cycle():
    """Bit speed max(0, Ω(1 + 1.5 sin 2πt/3.3)): stuck (below 0.1Ω) while sin < −0.6, a fraction
    (π − 2 asin 0.6)/(2π) of each cycle; min 0, max 2.5Ω; period 3.3 s."""
    from drillstring.dynamics.indicators import cycle_metrics

    t = np.arange(0.0, 10.0 + 100 * 3.3 + 1e-9, 0.001)
    omega = 10.0
    speed = np.maximum(0.0, omega * (1.0 + 1.5 * np.sin(2 * np.pi * (t - 10.0) / 3.3)))
    obs = {"bit_speed": speed, "rate_of_penetration": np.full_like(t, 1e-3), "torque_on_bit": np.ones_like(t),
           "force_on_bit": np.ones_like(t)}
    out = cycle_metrics(t, obs, omega, 0.05, 10.0)
    # counted on samples: one sample (0.001 s) per 3.3 s cycle of resolution
    assert out["stick_time_fraction"] == pytest.approx((np.pi - 2 * np.arcsin(0.6)) / (2 * np.pi), abs=0.001 / 3.3)
    assert out["bit_speed_min"] == 0.0 and out["bit_speed_max"] == pytest.approx(2.5 * omega, rel=1e-6)
    assert out["period"] == pytest.approx(3.3, rel=1e-6)
    assert out["stick_slip_index"] == pytest.approx(2.5 * omega / (2 * np.mean(speed[t >= 10.0])), rel=1e-12)


def test_period_of_steady_and_of_noisy_records():
    from drillstring.dynamics.indicators import oscillation_period

    t = np.arange(0.0, 20.0, 0.01)
    assert np.isnan(oscillation_period(t, np.full_like(t, 3.0)))  # steady drilling: no period
    assert np.isnan(oscillation_period(t, np.sin(2 * np.pi * t / 30.0)))  # under one cycle: one crossing
    ripple = np.sin(2 * np.pi * t / 2.0) + 0.05 * np.sin(2 * np.pi * t / 0.05)  # fast ripple on the level
    assert oscillation_period(t, ripple) == pytest.approx(2.0, rel=1e-2)
