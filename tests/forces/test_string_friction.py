"""The along-string Coulomb friction (drillstring.forces.string_friction): its kernel against the law written
here by hand (eqs. (1)-(2)), its sign, its regularisation limit, the combined axial + circumferential direction,
its power, its Jacobian against finite differences, its registration and case keys."""

import math

import numpy as np
import pytest

from drillstring.case import CaseError, StringFriction, load_case
from drillstring.forces.registry import (
    STRING_FRICTION,
    STRING_FRICTION_CODE,
    StringFrictionContext,
    pack,
    registry_table,
    string_friction,
)
from drillstring.forces.string_friction import CoulombStringFriction, FrictionStations


def _by_hand(u_dot, spin, normal, radius, mu, v_reg, static_factor=1.0, stribeck=0.1):
    """Eqs. (1)-(2), one station at a time: the friction force mu N along -(sliding velocity), the sliding
    velocity of the contact point (u_dot, r spin), magnitude scaled by |v| / sqrt(|v|^2 + v_reg^2), the
    coefficient raised to static_factor mu at rest, decaying over the Stribeck speed."""
    force, torque = [], []
    for u, w, n, r, m in zip(u_dot, spin, normal, radius, mu):
        v = math.hypot(u, r * w)
        if v == 0.0:
            force.append(0.0)
            torque.append(0.0)
            continue
        coefficient = m * (1.0 + (static_factor - 1.0) * math.exp(-v / stribeck))
        magnitude = coefficient * n * v / math.sqrt(v * v + v_reg * v_reg)
        force.append(-magnitude * u / v)
        torque.append(-magnitude * (r * w / v) * r)
    return np.array(force), np.array(torque)


def _context(rng, n=200):
    return StringFrictionContext(rng.normal(0.0, 0.5, n), rng.normal(0.0, 15.0, n), rng.uniform(0.0, 5e3, n),
                                 rng.uniform(0.05, 0.1, n), rng.uniform(0.1, 0.4, n))


def test_kernel_matches_the_law_written_by_hand():
    rng = np.random.default_rng(1)
    ctx = _context(rng)
    for v_reg, k, v_s in ((1e-3, 1.0, 0.1), (0.01, 1.0, 0.1), (0.3, 1.0, 0.1), (0.01, 1.5, 0.2), (1e-3, 2.0, 0.05)):
        force, torque = CoulombStringFriction(v_reg, k, v_s).evaluate_at(ctx)
        f_ref, t_ref = _by_hand(*ctx, v_reg, k, v_s)
        np.testing.assert_allclose(force, f_ref, rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(torque, t_ref, rtol=1e-13, atol=1e-12)


def test_stribeck_factor_limits():
    """k_s mu at rest (|v| >> v_reg but << v_S), mu sliding fast (|v| >> v_S); k_s = 1: the kinetic law bit for bit."""
    normal, radius, mu = 1000.0, 0.08, 0.25
    law = CoulombStringFriction(1e-7, 1.6, 0.2)
    slow, _ = law.evaluate_at(StringFrictionContext([1e-4], [0.0], [normal], [radius], [mu]))
    fast, _ = law.evaluate_at(StringFrictionContext([20.0], [0.0], [normal], [radius], [mu]))
    assert slow[0] == pytest.approx(-1.6 * mu * normal, rel=1e-3)
    assert fast[0] == pytest.approx(-mu * normal, rel=1e-12)
    ctx = _context(np.random.default_rng(5))
    a, b = CoulombStringFriction(0.01).evaluate_at(ctx), CoulombStringFriction(0.01, 1.0, 0.02).evaluate_at(ctx)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


def test_sign_direction_and_regularisation_limit():
    law = CoulombStringFriction(1e-9)
    normal, radius, mu = 1000.0, 0.08, 0.25
    # pure rotation: no axial force, torque -mu N r against the spin (either way)
    for spin in (12.0, -12.0):
        force, torque = law.evaluate_at(StringFrictionContext([0.0], [spin], [normal], [radius], [mu]))
        assert force[0] == 0.0
        assert torque[0] == pytest.approx(-math.copysign(mu * normal * radius, spin), rel=1e-12)
    # pure axial sliding down (u_dot > 0): the force points up, magnitude mu N
    force, torque = law.evaluate_at(StringFrictionContext([0.3], [0.0], [normal], [radius], [mu]))
    assert force[0] == pytest.approx(-mu * normal, rel=1e-12) and torque[0] == 0.0
    # combined: (f, tau / r) is -mu N times the unit sliding direction (soft-string drag reduction by rotation)
    u, w = 0.01, 12.0
    force, torque = law.evaluate_at(StringFrictionContext([u], [w], [normal], [radius], [mu]))
    v = math.hypot(u, radius * w)
    assert force[0] == pytest.approx(-mu * normal * u / v, rel=1e-9)
    assert torque[0] / radius == pytest.approx(-mu * normal * radius * w / v, rel=1e-9)
    assert math.hypot(force[0], torque[0] / radius) == pytest.approx(mu * normal, rel=1e-9)
    # regularised: viscous below v_reg (slope mu N / v_reg), the full mu N well above it
    soft = CoulombStringFriction(0.1)
    force, _ = soft.evaluate_at(StringFrictionContext([1e-5], [0.0], [normal], [radius], [mu]))
    assert force[0] == pytest.approx(-mu * normal * 1e-5 / 0.1, rel=1e-6)
    force, _ = soft.evaluate_at(StringFrictionContext([100.0], [0.0], [normal], [radius], [mu]))
    assert force[0] == pytest.approx(-mu * normal / math.sqrt(1.0 + 1e-6), rel=1e-12)


def test_power_is_never_positive():
    rng = np.random.default_rng(2)
    ctx = _context(rng, 2000)
    for law in (CoulombStringFriction(0.01), CoulombStringFriction(0.01, 2.0, 0.1)):
        force, torque = law.evaluate_at(ctx)
        power = force * ctx.axial_velocity + torque * ctx.spin_speed
        assert np.all(power <= 0.0)
        assert np.all(power[ctx.normal_force > 0] < 0.0)


def test_jacobian_against_finite_differences():
    rng = np.random.default_rng(3)
    ctx = _context(rng, 50)
    for law in (CoulombStringFriction(0.05), CoulombStringFriction(0.05, 1.8, 0.3)):
        jac = law.jacobian_at(ctx)
        for column, field in enumerate(("axial_velocity", "spin_speed")):
            base = np.asarray(getattr(ctx, field))
            step = 1e-6 * np.maximum(np.abs(base), 1e-2)
            up = law.evaluate_at(ctx._replace(**{field: base + step}))
            down = law.evaluate_at(ctx._replace(**{field: base - step}))
            for row in range(2):
                np.testing.assert_allclose(jac[:, row, column], (up[row] - down[row]) / (2 * step), rtol=1e-5,
                                           atol=1e-6 * np.abs(jac).max())


def test_registered_packed_and_off_by_default():
    assert "coulomb" in registry_table()["string_friction"]
    assert string_friction("coulomb") is CoulombStringFriction
    with pytest.raises(ValueError, match="string friction 'dry'|registered"):
        string_friction("dry", "string_friction.law")
    case = load_case("reference")
    assert case.string_friction.law == "none"
    from drillstring.forces.registry import bit_law, hook_load, top_boundary
    from drillstring.forces.top_drive import TopDriveParameters

    bit = bit_law("off_bottom")()
    top = TopDriveParameters("imposed_speed", 10.0)
    hook = hook_load("on_bottom")()
    laws, _ = pack(bit, top, hook, np.zeros(4), 4)
    assert laws[STRING_FRICTION_CODE] == 0.0
    laws, layout = pack(bit, top, hook, np.zeros(4), 4, friction=CoulombStringFriction(0.02))
    assert laws[STRING_FRICTION_CODE] == CoulombStringFriction.component_code > 0.0
    start = int(laws[STRING_FRICTION])
    assert list(laws[start:start + 3]) == [0.02, 1.0, 0.1] and layout.numbers["string_friction"] == start


def test_case_keys_and_bad_input():
    case = load_case("deviated")
    assert case.string_friction.law == "coulomb"
    assert CoulombStringFriction.from_case(case).regularization_speed == pytest.approx(0.01)
    table = StringFriction.model_validate({"law": "coulomb", "coulomb": {"regularization_speed": "5 cm/s"}})
    assert CoulombStringFriction.from_case(case.model_copy(update={"string_friction": table})) \
        .regularization_speed == pytest.approx(0.05)
    with pytest.raises((CaseError, ValueError), match="regularization_speed"):
        CoulombStringFriction.from_case(case.model_copy(update={"string_friction": StringFriction.model_validate(
            {"law": "coulomb", "coulomb": {"regularization_speed": 0.0}})}))
    with pytest.raises(ValueError, match="regularization_speed = -1"):
        CoulombStringFriction(-1.0)
    with pytest.raises(ValueError, match="static_factor = 0.5"):
        CoulombStringFriction(0.01, 0.5)
    with pytest.raises(ValueError, match="stribeck_speed = 0"):
        CoulombStringFriction(0.01, 1.5, 0.0)
    with pytest.raises((CaseError, ValueError), match="static_factor"):
        StringFriction.model_validate({"law": "coulomb", "coulomb": {"static_factor": 0.9}}) and \
            CoulombStringFriction.from_case(case.model_copy(update={"string_friction": StringFriction.model_validate(
                {"law": "coulomb", "coulomb": {"static_factor": 0.9}})}))
    with pytest.raises(ValueError, match="normal_force"):
        FrictionStations(np.array([1, 2]), np.array([1.0, -1.0]), np.ones(2), np.ones(2))
    stations = FrictionStations(np.array([1, 2]), np.array([100.0, 200.0]), np.array([0.1, 0.05]),
                                np.array([0.2, 0.3]))
    assert stations.rotating_torque() == pytest.approx(0.2 * 100 * 0.1 + 0.3 * 200 * 0.05)
