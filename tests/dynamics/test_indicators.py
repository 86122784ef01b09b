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
