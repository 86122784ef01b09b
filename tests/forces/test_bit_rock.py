"""Tests of the bit–rock law (SPEC §6, §9, §10)."""

import math

import numpy as np
import pytest

from drillstring.forces.bit_rock import (
    KERNEL_SIZE,
    STICK_SPEED_FLOOR_RATIO,
    BitRockParameters,
    bit_rock_force,
    bit_rock_force_floored,
    bit_rock_jacobian,
    case_bit_rock,
    evaluate_bit_rock,
    regularizer,
    steady_state,
    tucker_wang_kernel,
)
from drillstring.forces.off_bottom import OffBottom
from drillstring.forces.registry import bit_context

RPM = 2.0 * math.pi / 60.0
P = BitRockParameters.reference()
ARGS = tuple(P.as_array())


def test_as_array_order():
    np.testing.assert_array_equal(P.as_array(), [3.429e-3, 5.672e-8, 1.374e-4, 9.537e6, 1.475e3, 2.0])
    assert P.kernel_args()[-1] == pytest.approx(STICK_SPEED_FLOOR_RATIO * 2.0)


def test_invalid_parameters():
    with pytest.raises(ValueError):
        BitRockParameters(1.0, 0.0, 1.0, 1.0, 1.0, 2.0)
    with pytest.raises(ValueError):
        BitRockParameters(1.0, 1.0, 1.0, 1.0, 1.0, -1.0)


def test_reference_steady_state():
    rop, tob = steady_state(100e3, 100 * RPM, P)
    assert rop == pytest.approx(3.58e-3, rel=2e-3)
    assert tob == pytest.approx(4.59e3, rel=2e-3)


@pytest.mark.parametrize(
    "wob, rpm",
    [(100e3, 100.0), (60e3, 40.0), (150e3, 200.0), (80e3, 5.0), (120e3, -100.0)],
)
def test_force_law_at_steady_state(wob, rpm):
    omega = rpm * RPM
    rop, tob = steady_state(wob, omega, P)
    assert rop > 0.0
    f, t = bit_rock_force(rop, omega, *ARGS)
    assert f == pytest.approx(-wob, rel=1e-10)
    assert t == pytest.approx(-tob, rel=1e-10)


def test_steady_state_closed_form_by_hand():
    omega = 100 * RPM
    z = omega / math.sqrt(omega**2 + P.e**2)
    rop = z**2 * (P.a2 * 100e3 - P.a1) + z * P.a3 * omega
    tob = P.a4 * rop * z**2 / omega + P.a5 * z
    assert steady_state(100e3, omega, P) == pytest.approx((rop, tob), rel=1e-14)


def test_steady_state_no_penetration_clipped():
    # a2 wob < a1 and a slow bit: the raw formula is negative
    wob, omega = 10e3, 0.5
    raw_rop, _ = steady_state(wob, omega, P, allow_negative_rop=True)
    assert raw_rop < 0.0
    rop, tob = steady_state(wob, omega, P)
    assert rop == 0.0
    assert tob == pytest.approx(P.a5 * regularizer(omega, P.e), rel=1e-14)


def test_steady_state_zero_speed_and_arrays():
    assert steady_state(100e3, 0.0, P) == (0.0, 0.0)
    wob = np.array([60e3, 100e3, 150e3])
    rop, tob = steady_state(wob, 100 * RPM, P)
    for i in range(3):
        assert (rop[i], tob[i]) == pytest.approx(steady_state(wob[i], 100 * RPM, P), rel=1e-14)


def test_regularizer_limits_and_oddness():
    e = 2.0
    assert regularizer(0.0, e) == 0.0
    assert regularizer(0.0, 0.0) == 0.0
    assert regularizer(1e6, e) == pytest.approx(1.0, abs=1e-11)
    assert regularizer(-1e6, e) == pytest.approx(-1.0, abs=1e-11)
    assert regularizer(e, e) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-15)
    assert regularizer(1e-3, e) == pytest.approx(1e-3 / e, rel=1e-6)  # linear near 0, slope 1/e
    for s in (1e-8, 0.3, 2.0, 17.0, 1e300):
        z = regularizer(s, e)
        assert regularizer(-s, e) == -z
        assert abs(z) <= 1.0
    assert regularizer(5.0, 0.0) == 1.0


def test_law_matches_textbook_form_away_from_stick():
    for u in (-2e-3, 0.0, 3.5e-3):
        for w in (-15.0, -0.7, 0.05, 3.0, 10.0):
            z = w / math.sqrt(w * w + P.e**2)
            f_ref = -u / (P.a2 * z * z) + P.a3 * w / (P.a2 * z) - P.a1 / P.a2
            t_ref = -u * P.a4 * z * z / w - P.a5 * z
            f, t = bit_rock_force(u, w, *ARGS)
            assert f == pytest.approx(f_ref, rel=1e-12, abs=1e-6)
            assert t == pytest.approx(t_ref, rel=1e-12, abs=1e-9)


def test_stick_is_finite_and_defined():
    floor = STICK_SPEED_FLOOR_RATIO * P.e
    inv_z2_max = 1.0 + (P.e / floor) ** 2
    for u in (-1e-2, -1e-6, 0.0, 1e-6, 3.5e-3):
        f, t = bit_rock_force(u, 0.0, *ARGS)
        assert math.isfinite(f) and math.isfinite(t)
        assert f == pytest.approx(-u * inv_z2_max / P.a2 + P.a3 * P.e / P.a2 - P.a1 / P.a2, rel=1e-12)
        assert t == 0.0
    # a drilling bit that sticks is pushed back hard (penetration stops); a lifting one is pulled down
    assert bit_rock_force(1e-3, 0.0, *ARGS)[0] < -1e15
    assert bit_rock_force(-1e-3, 0.0, *ARGS)[0] > 1e15
    # continuous through the floor and through 0, no NaN/inf for tiny speeds
    for w in (1e-300, -1e-300, 5e-324, 1e-12, floor * (1 - 1e-12), floor, floor * (1 + 1e-12), 1e-4):
        f, t = bit_rock_force(1e-3, w, *ARGS)
        assert math.isfinite(f) and math.isfinite(t)
    f0 = bit_rock_force(1e-3, 0.0, *ARGS)[0]
    assert bit_rock_force(1e-3, 1e-300, *ARGS)[0] == pytest.approx(f0, rel=1e-14)
    below = bit_rock_force(1e-3, floor * (1 - 1e-9), *ARGS)[0]
    above = bit_rock_force(1e-3, floor * (1 + 1e-9), *ARGS)[0]
    assert below == pytest.approx(above, rel=1e-8)


def test_finite_for_extreme_inputs():
    for u, w in [(1.0, 1e200), (-1.0, -1e200), (1e-3, 1e-200), (0.0, 0.0), (1e3, 1e-10)]:
        f, t = bit_rock_force(u, w, *ARGS)
        assert math.isfinite(f) and math.isfinite(t)


def test_unregularised_and_zero_floor():
    args0 = ARGS[:5] + (0.0,)
    f, t = bit_rock_force(1e-3, 0.0, *args0)  # e = 0 at θ̇ = 0: Z = 0, 1/Z² = 1
    assert math.isfinite(f) and t == 0.0
    f, t = bit_rock_force(1e-3, 3.0, *args0)  # e = 0: Z = 1
    assert f == pytest.approx((-1e-3 + P.a3 * 3.0 - P.a1) / P.a2, rel=1e-14)
    assert t == pytest.approx(-1e-3 * P.a4 / 3.0 - P.a5, rel=1e-14)
    f, t = bit_rock_force_floored(1e-3, 0.0, *ARGS, 0.0)  # zero floor: falls back, still finite
    assert math.isfinite(f)
    f_big_floor = bit_rock_force_floored(1e-3, 0.0, *ARGS, 0.02)[0]
    assert f_big_floor == pytest.approx((-1e-3 * (1 + (P.e / 0.02) ** 2) + P.a3 * P.e - P.a1) / P.a2)


def test_negative_speed_symmetry():
    """Torque opposes the rotation; the law is symmetric under θ̇ -> −θ̇ as the formula says."""
    for u in (0.0, 1e-3, 4e-3):
        for w in (0.5, 2.0, 10.0):
            fp, tp = bit_rock_force(u, w, *ARGS)
            fm, tm = bit_rock_force(u, -w, *ARGS)
            assert fm == pytest.approx(fp, rel=1e-14)  # f is even in θ̇ (1/Z², θ̇/Z even)
            assert tm == pytest.approx(-tp, rel=1e-14)  # t is odd in θ̇
            if u >= 0.0:
                assert tp < 0.0 < tm  # opposes the rotation


def _law_as_written(u, w, params):
    """docs/model.md §5 by hand, away from stick (Z ≠ 0), with the unilateral contact: the force and torque on
    the string, ``(0, 0)`` where the law would pull the bit down. Independent of the kernels."""
    z = w / math.sqrt(w * w + params.e**2)
    f = -u / (params.a2 * z * z) + params.a3 * w / (params.a2 * z) - params.a1 / params.a2
    t = -u * params.a4 * z * z / w - params.a5 * z
    return (0.0, 0.0) if f > 0.0 else (f, t)


def test_kernel_and_evaluate_at_are_the_law_as_written_with_unilateral_contact():
    """The component's kernel (its numbers, the named context) and ``evaluate_at`` (the kernel applied
    elementwise) against the law written out by hand: the force where it pushes the bit up, nothing where
    the law would pull the bit down (it has left the rock)."""
    rng = np.random.default_rng(0)
    u = rng.normal(2e-3, 3e-3, size=(4, 5))
    w = rng.normal(5.0, 8.0, size=(4, 5))
    packed = P.kernel_array()
    f, t = P.evaluate_at(bit_context(u, w, time=1.0, position=0.1, angle=3.0, weight_on_bit=1e5))
    assert f.shape == t.shape == (4, 5)
    lifted = 0
    for idx in np.ndindex(u.shape):
        expected = _law_as_written(u[idx], w[idx], P)
        lifted += expected == (0.0, 0.0)
        assert (f[idx], t[idx]) == pytest.approx(expected, rel=1e-12, abs=1e-9)
        ctx = bit_context(u[idx], w[idx], time=1.0, weight_on_bit=1e5)
        assert tucker_wang_kernel(packed, ctx) == pytest.approx(expected, rel=1e-12, abs=1e-9)
    assert 0 < lifted < u.size  # both regimes are exercised
    fb, tb = evaluate_bit_rock(1e-3, np.array([0.5, 1.0, 10.0]), P)  # broadcasting, scalars to 0-d
    assert fb.shape == (3,) and tb[2] == pytest.approx(_law_as_written(1e-3, 10.0, P)[1], rel=1e-12)
    fs, ts = evaluate_bit_rock(1e-3, 10.0, P)
    assert fs.shape == () and float(fs) == pytest.approx(_law_as_written(1e-3, 10.0, P)[0], rel=1e-12)


def test_stick_floor_from_stiffening_limit():
    """Below θ̇_floor the axial resistance −∂f/∂u̇ = (1/Z²)/a2 stays at K times its value at Ω."""
    from drillstring.forces.bit_rock import stick_speed_floor_ratio

    omega, limit = 10.0, 100.0
    ratio = stick_speed_floor_ratio(P.e, omega, limit)
    params = BitRockParameters(P.a1, P.a2, P.a3, P.a4, P.a5, P.e, ratio)

    def resistance(w):
        f1, _ = evaluate_bit_rock(1e-3, w, params)
        f0, _ = evaluate_bit_rock(0.0, w, params)
        return -(float(f1) - float(f0)) / 1e-3

    at_top = resistance(omega)
    assert at_top == pytest.approx((1 + (P.e / omega) ** 2) / P.a2, rel=1e-9)
    for w in (0.0, 1e-9, 0.5 * params.stick_speed_floor):
        assert resistance(w) == pytest.approx(limit * at_top, rel=1e-9)
    assert resistance(2 * params.stick_speed_floor) < limit * at_top
    with pytest.raises(ValueError, match="must be > 1"):
        stick_speed_floor_ratio(P.e, omega, 1.0)


def test_bit_rock_jacobian_against_finite_differences():
    params = BitRockParameters.reference()
    for u, w in [(3.6e-3, 10.47), (1e-3, 1.5), (5e-3, 30.0), (2e-3, -4.0)]:
        jac = bit_rock_jacobian(u, w, params)
        np.testing.assert_array_equal(params.jacobian(u, w), jac)
        for j, (du, dw) in enumerate([(1e-9, 0.0), (0.0, 1e-6)]):
            plus = np.array(evaluate_bit_rock(u + du, w + dw, params), dtype=float)
            minus = np.array(evaluate_bit_rock(u - du, w - dw, params), dtype=float)
            fd = (plus - minus) / (2 * (du + dw))
            np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6, atol=1e-9 * np.abs(jac).max())


@pytest.mark.parametrize("law", ["tucker_wang", "off_bottom"])
def test_component_kernel_reads_its_numbers_and_the_named_context(law):
    """The compiled kernel reading its packed numbers and the named context gives the law as written (with a
    stick floor of 1e-3 e: at stick the floored form), zero off bottom; the Jacobian is zero off bottom."""
    params = (BitRockParameters(*P.as_array(), stick_speed_floor_ratio=1e-3) if law == "tucker_wang"
              else OffBottom())
    packed = params.kernel_array()
    assert packed.shape == (type(params).kernel_size,) and packed.dtype == np.float64
    assert params.name == law and params.on_bottom == (law == "tucker_wang")
    floor = 1e-3 * P.e
    for u, w in [(3.6e-3, 10.47), (0.0, 0.0), (1e-3, 1e-4), (-2e-3, -4.0)]:
        ctx = bit_context(u, w, time=1.0, position=0.1, angle=3.0, weight_on_bit=1e5)
        got = type(params).kernel(packed, ctx)
        assert got == tuple(float(v) for v in params.evaluate_at(ctx))
        if law == "off_bottom":
            assert got == (0.0, 0.0)
            np.testing.assert_array_equal(params.jacobian_at(ctx), np.zeros((2, 2)))
        elif abs(w) >= floor:
            assert got == pytest.approx(_law_as_written(u, w, P), rel=1e-12, abs=1e-9)
        else:  # below the floor 1/Z² is frozen at 1 + (e/θ̇_floor)², θ̇/Z = h, Z²/θ̇ = θ̇/h², Z = θ̇/h
            h = math.hypot(w, P.e)
            f = (-u * (1.0 + (P.e / floor) ** 2) + P.a3 * h - P.a1) / P.a2
            t = -u * P.a4 * w / h**2 - P.a5 * w / h
            assert got == pytest.approx((0.0, 0.0) if f > 0.0 else (f, t), rel=1e-12, abs=1e-9)
    assert KERNEL_SIZE == 7


def test_steady_drilling_balances_the_axial_load():
    """The law's steady state under an axial load W less a resistance c V: −f(V, Ω) = W − c V exactly, and
    with c = 0 the closed form of :func:`steady_state`."""
    omega = 100 * RPM
    for weight, resistance in ((1e5, 0.0), (1e5, 2e6), (8e4, 5e5)):
        steady = P.steady_drilling(omega, weight, resistance)
        force, torque = P.evaluate(steady.rate_of_penetration, omega)
        assert -float(force) == pytest.approx(weight - resistance * steady.rate_of_penetration, rel=1e-12)
        assert (steady.axial_force, steady.torque) == (float(force), float(torque))
    rop, tob = steady_state(1e5, omega, P)
    steady = P.steady_drilling(omega, 1e5, 0.0)
    assert steady.rate_of_penetration == pytest.approx(rop, rel=1e-12)
    assert -steady.torque == pytest.approx(tob, rel=1e-12)
    assert P.steady_drilling(omega, 0.0, 0.0) is None  # a2 W < a1 + ...: the bit would lift off
    assert OffBottom().steady_drilling(omega, 1e5, 0.0).rate_of_penetration == 0.0


def test_case_bit_rock_is_built_from_the_case(coarse_case):
    b = coarse_case.bit_rock
    params = case_bit_rock(coarse_case)
    assert (params.a1, params.a2, params.a3, params.a4, params.a5, params.e) == (b.a1, b.a2, b.a3, b.a4, b.a5,
                                                                                  b.regularization)
    assert params.name == b.law
    # 1 + (e/θ̇_floor)² = K (1 + (e/Ω)²), K the case's stiffening limit
    omega = coarse_case.operation.top_speed
    k = b.stick_stiffening_limit
    assert 1 + (b.regularization / params.stick_speed_floor) ** 2 == pytest.approx(
        k * (1 + (b.regularization / omega) ** 2), rel=1e-12)
