"""Scalar outputs of one run: Teale's MSE and the summaries of a run with known histories."""

import math

import numpy as np
import pytest

from drillstring.case import load_case
from drillstring.dynamics.simulate import SimulationResult
from drillstring.dynamics.indicators import bit_area, mechanical_specific_energy
from drillstring.stochastic.runs import RUN_OUTPUTS, result_outputs


def test_mechanical_specific_energy_is_teale():
    """MSE = WOB/A + 2πN·T/(A·ROP) with N in rev/s: 100 kN, 10 kN·m, 120 rpm (2 rev/s), 10 m/h on a
    0.3 m bit: 1.4147 MPa + 2π·2·1e4/(0.0707·0.002778) = 1.4147 MPa + 640.0 MPa."""
    area = math.pi * 0.3**2 / 4
    rop = 10.0 / 3600.0
    expected = 1e5 / area + 2 * math.pi * 2.0 * 1e4 / (area * rop)
    assert mechanical_specific_energy(1e5, 1e4, 4 * math.pi, rop, area) == pytest.approx(expected, rel=1e-14)
    assert expected / 1e6 == pytest.approx(641.41, abs=0.01)
    assert math.isnan(mechanical_specific_energy(1e5, 1e4, 4 * math.pi, 0.0, area))
    assert math.isnan(mechanical_specific_energy(math.nan, 1e4, 4 * math.pi, rop, area))
    assert bit_area(load_case("reference")) == pytest.approx(area)


def test_outputs_of_a_run_with_known_histories():
    """ROP 2 + sin t, bit speed Ω (1 + 0.95 sin t), TOB 3, FOB 4 + cos t over 0..40 s; after 10 s."""
    case = load_case("reference")
    omega = case.operation.top_speed
    t = np.linspace(0.0, 40.0, 40001)
    steady = t >= 10.0
    obs = {"rate_of_penetration": 2 + np.sin(t), "bit_speed": omega * (1 + 0.95 * np.sin(t)),
           "torque_on_bit": np.full_like(t, 3.0), "force_on_bit": 4 + np.cos(t)}
    radial = np.stack([1e-3 * (t / 40.0), np.zeros_like(t)], axis=1)
    lateral = np.stack([radial, np.zeros_like(radial)], axis=2)  # (v, w) at the probes: w = 0
    result = SimulationResult(time=t, observables=obs, radial_displacement=radial, lateral_displacement=lateral,
                              probe_positions=np.array([1500.0, 1560.0]), probe_gaps=np.array([0.1, 0.1]),
                              impacts=7, status="success", message="")
    out = result_outputs(result, case, 10.0)
    assert set(out) == set(RUN_OUTPUTS)
    assert out["mean_rate_of_penetration"] == pytest.approx(np.mean(obs["rate_of_penetration"][steady]))
    assert out["std_rate_of_penetration"] == pytest.approx(np.std(np.sin(t[steady])))
    assert out["std_torque_on_bit"] == 0.0 and out["mean_torque_on_bit"] == 3.0
    assert out["mean_force_on_bit"] == pytest.approx(np.mean(4 + np.cos(t[steady])))
    assert out["bit_speed_oscillation"] == pytest.approx(0.95, rel=1e-6)
    below = np.mean(1 + 0.95 * np.sin(t[steady]) < 0.1)  # stuck below 10 % of the top speed
    assert out["stick_time_fraction"] == pytest.approx(below) and below > 0
    assert out["max_radial_displacement"] == pytest.approx(1e-3) and out["impacts"] == 7.0
    # Teale's MSE from the exact time means over 10..40 s: FOB 4 + (sin 40 − sin 10)/30, ROP 2 + (cos 10 −
    # cos 40)/30, TOB 3, at the top speed Ω, on the 0.3 m bit (area π 0.3²/4); the run's means are those of
    # 30,001 samples, within 3e-6 of the integrals
    fob = 4 + (math.sin(40.0) - math.sin(10.0)) / 30
    rop = 2 + (math.cos(10.0) - math.cos(40.0)) / 30
    area = math.pi * 0.3**2 / 4
    assert out["mechanical_specific_energy"] == pytest.approx(fob / area + 3.0 * omega / (area * rop), rel=1e-5)
