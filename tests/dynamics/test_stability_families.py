"""Per-family roots of the linearised model (issue 25, items 1 and 2): energy shares, the leading root of each
family against the same model without the lateral family (which the bit–rock law does not couple at the
centred state), and the proportional controller's steady speed on the branch of the set point."""

import math

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import (
    MIXED_SHARE,
    SET_POINT_TOLERANCE,
    STABILITY_FAMILIES,
    _steady_load,
    boundary_steady_speed,
    stability,
    steady_drilling,
)
from drillstring.dynamics.rom import rigid_axial_column
from drillstring.stochastic.runs import coexisting_cycles, stability_outputs, stored_outputs

RPM = math.pi / 30.0


def _matched_top(case, lateral_modes: int, *, weight_on_bit: float, rpm: float, integral_gain: float = 1.0):
    """The reference string (coarse mesh, small basis) under a matched top: PI with k_p = Z_p = 443.4
    N*m*s/rad, k_i ≈ 0 and a light top drive (10 kg*m2)."""
    return case.model_copy(update={
        "reduced_model": case.reduced_model.model_copy(
            update={"axial_modes": 4, "torsional_modes": 6, "lateral_modes": lateral_modes, "lateral_cutoff": 0.0}),
        "operation": case.operation.model_copy(update={"weight_on_bit": weight_on_bit, "top_speed": rpm * RPM}),
        "top_drive": case.top_drive.model_copy(update={"controller": "pi", "inertia": 10.0,
                                                       "proportional_gain": 443.4, "integral_gain": integral_gain}),
    })


def test_shares_and_leading_root_per_family_above_buckling(coarse_case):
    """At 150 kN (above the reference string's buckling load, 114 kN) and 100 rpm with a matched top, the
    overall leading root is the lateral divergence (real, growing), while every torsional and axial root
    decays. The leading root of each of those families equals the leading root of the same model without
    lateral modes (an independent computation: the lateral family is not coupled at the centred state)."""
    with_lateral = stability(case_reduced_model(_matched_top(coarse_case, 4, weight_on_bit=150e3, rpm=100.0)))
    without = stability(case_reduced_model(_matched_top(coarse_case, 0, weight_on_bit=150e3, rpm=100.0)))
    for mode in with_lateral.modes:
        assert sum(mode.shares.values()) == pytest.approx(1.0, abs=1e-12)
        assert mode.family == max(mode.shares, key=mode.shares.get)
        assert mode.mixed == (max(mode.shares.values()) < MIXED_SHARE)
    leading = with_lateral.leading
    assert leading.family == "lateral" and leading.growth_rate > 0.0 and leading.frequency < 1e-9
    assert leading.shares["lateral"] > 0.999
    assert not with_lateral.stable
    by_family = with_lateral.leading_by_family
    assert set(by_family) == set(STABILITY_FAMILIES)
    assert with_lateral.family_stable("torsional") and with_lateral.family_stable("axial")
    assert with_lateral.family_stable("lateral") is False
    reference = without.leading_by_family
    assert reference["lateral"] is None and without.family_stable("lateral") is None
    for family in ("torsional", "axial"):
        assert by_family[family].growth_rate < 0.0
        assert by_family[family].growth_rate == pytest.approx(reference[family].growth_rate, rel=1e-6, abs=1e-9)
        assert by_family[family].frequency == pytest.approx(reference[family].frequency, rel=1e-6, abs=1e-9)
    payload = with_lateral.to_dict()
    assert payload["leading_by_family"]["torsional"]["stable"] is True
    assert payload["leading_by_family"]["lateral"]["growth_rate"] == leading.growth_rate
    assert {tuple(m["shares"]) for m in payload["modes"]} == {STABILITY_FAMILIES}
    outputs, note = stability_outputs(case_reduced_model(_matched_top(coarse_case, 4, weight_on_bit=150e3,
                                                                      rpm=100.0)))
    assert note == ""
    assert outputs["growth_rate"] == leading.growth_rate > 0 > outputs["torsional_growth_rate"]
    assert outputs["torsional_growth_rate"] == by_family["torsional"].growth_rate
    assert outputs["leading_family"] == 2.0 and outputs["leading_share"] > 0.999
    assert outputs["steady_bit_speed"] == pytest.approx(100.0 * RPM, rel=1e-12)


def test_coexisting_cycles_and_old_stores():
    """The derived flag: stable torsion and axial roots (NaN: the family is absent) with a run in stick-slip
    (the bit stuck part of the time, not all of it);
    NaN where both growth rates or the stick time are unknown. A store written before an output existed reads
    it as NaN."""
    values = {"torsional_growth_rate": np.array([-0.1, -0.1, 0.2, np.nan, -0.1, np.nan, -0.1]),
              "axial_growth_rate": np.array([-1.0, -1.0, -1.0, -1.0, 0.3, np.nan, -1.0]),
              "stick_time_fraction": np.array([0.3, 0.0, 0.3, 0.2, 0.2, 0.2, 1.0])}  # 1: a stalled bit, no cycle
    np.testing.assert_array_equal(coexisting_cycles(values), [1.0, 0.0, 0.0, 1.0, 0.0, np.nan, 0.0])
    group = {"a": np.arange(4.0)}
    read = stored_outputs(group, {"a": ["point"]}, ("a", "b"), (2, 2))
    np.testing.assert_array_equal(read["a"], [[0, 1], [2, 3]])
    assert np.isnan(read["b"]).all() and read["b"].shape == (2, 2)


@pytest.fixture(scope="module")
def drooping(reference_case):
    """The reference string under a PI top drive without integral action (k_p = 3000 N*m*s/rad), asked for
    60 rpm at 200 kN, on a coarse basis. The earlier fixed-point iteration ω ← Ω − τ_m(ω)/k_p does not
    converge here (|dτ_m/dω| > k_p on this velocity-weakening load) and returned 35.9 rpm, not a steady state."""
    stick = reference_case.model_copy(update={
        "mesh": reference_case.mesh.model_copy(update={"max_element_length": 40.0}),
        "reduced_model": reference_case.reduced_model.model_copy(
            update={"axial_modes": 3, "torsional_modes": 4, "lateral_modes": 0, "lateral_cutoff": 0.0}),
        "operation": reference_case.operation.model_copy(update={"weight_on_bit": 200e3, "top_speed": 60 * RPM}),
        "top_drive": reference_case.top_drive.model_copy(update={"controller": "pi", "inertia": 1000.0,
                                                                 "proportional_gain": 3e3, "integral_gain": 0.0}),
    })
    return case_reduced_model(stick)


def test_integral_gain_zero_stays_on_the_set_points_branch(drooping):
    """integral_gain = 0: the steady speed solves ω = Ω − τ_m(ω)/k_p, is the root nearest the set point (no
    root between it and Ω on a fine scan: the branch asked for, never another one), is an equilibrium of the
    model, and the state's note names the speed and the weight on bit found in one line."""
    model = drooping
    steady = steady_drilling(model)
    omega, set_point, k_p = steady.bit_speed, model.top_drive.set_point, model.top_drive.proportional_gain
    r = rigid_axial_column(model)
    motor = lambda w: _steady_load(model, w, r)[3]  # noqa: E731
    assert 0.0 < omega < set_point
    assert omega - set_point + motor(omega) / k_p == pytest.approx(0.0, abs=1e-9 * set_point)
    scan = np.linspace(omega, set_point, 2001)[1:]
    assert np.all(scan - set_point + np.array([motor(w) for w in scan]) / k_p > 0.0)
    rhs = model.rhs(0.0, steady.state)
    n = model.size
    assert np.abs(rhs[n:2 * n]).max() < 1e-9 * np.abs(model.omega2 * steady.state[:n]).max()
    assert "\n" not in steady.note
    assert f"{omega / RPM:.4g} rpm" in steady.note and "200 kN" in steady.note and "set point 60 rpm" in steady.note
    assert steady.to_dict()["note"] == steady.note
    result = stability(model)  # the integral state, on which nothing depends, is left out: no root at 0
    assert all(abs(m.growth_rate) > 1e-9 or m.frequency > 0 for m in result.modes)
    _, note = stability_outputs(model)
    assert note == steady.note


def test_proportional_speed_takes_the_branch_of_the_set_point():
    """A load with two steady branches (velocity weakening): ω − Ω + τ(ω)/k_p has roots at 2 and 8 rad/s in
    (0, Ω = 10]; the one nearest the set point, 8, is returned; a load the gain cannot carry is refused."""
    k_p, set_point = 1.0, 10.0

    def proportional(gain):
        return lambda torque: set_point - torque / gain

    motor = lambda w: set_point - w + (w - 2.0) * (w - 8.0) * 0.1  # noqa: E731
    assert boundary_steady_speed(motor, proportional(k_p), set_point) == pytest.approx(8.0, rel=1e-12)
    with pytest.raises(ValueError, match="cannot carry the load torque 20 N\\*m"):
        boundary_steady_speed(lambda w: 20.0, proportional(k_p), set_point)
    speed = boundary_steady_speed(lambda w: 1e-6, proportional(1e4), set_point)
    assert abs(speed - set_point) < SET_POINT_TOLERANCE * set_point


def test_stick_slip_coexists_with_stable_steady_drilling():
    """``stick_slip`` with SoftTorque retuned to the loaded string's frequency (k_p = Z_p = 443.4 N*m*s/rad,
    k_i = J_td ω² = 419 N*m/rad at 0.103 Hz): every root of steady drilling decays, yet the 90 s run from the
    case's start lands on a stick-slip cycle (the bit stuck about 45 % of the time after 30 s): the map's
    ``coexisting_cycles`` flag is 1 there."""
    from drillstring.case import load_case
    from drillstring.stochastic.runs import run_outputs

    case = load_case("stick_slip")
    case = case.model_copy(update={"top_drive": case.top_drive.model_copy(
        update={"controller": "soft_torque", "proportional_gain": 443.4, "integral_gain": 419.0})})
    outcome = run_outputs(case, 0, t_end=90.0, output_step=0.05, t_transient=30.0, with_stability=True)
    values = outcome.values
    assert outcome.status == 1, outcome.message
    assert values["growth_rate"] < 0 and values["torsional_growth_rate"] < 0 and values["axial_growth_rate"] < 0
    assert values["stick_time_fraction"] > 0.3
    assert coexisting_cycles({k: np.array([v]) for k, v in values.items()})[0] == 1.0
