"""The components' compiled Jacobians (issue 33, item 2): the dispatch the IMEX step's stiff part calls
(:func:`~drillstring.forces.registry.bit_law_jacobian`, :func:`~drillstring.forces.registry.motor_slope`) equals,
for every registered bit law and downhole motor, the component's Python ``jacobian_at`` / ``depth_partials`` (the
same compiled function called from Python: equal to round-off) and, independently, central differences of the
compiled law itself (:func:`~drillstring.forces.registry.bit_law_force`, :func:`~drillstring.forces.registry.
motor_torque`) at random states away from the laws' kinks. A law that declares no Jacobian is differenced, in
Python and in the compiled dispatch alike."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numba import njit

from drillstring.forces.bit_rock import BitRockParameters, tucker_wang_jacobian
from drillstring.forces.detournay import DetournayParameters
from drillstring.forces.motor import PositiveDisplacementMotor
from drillstring.forces.off_bottom import OffBottom
from drillstring.forces.registry import (
    BIT_LAW,
    BIT_LAW_CODE,
    HEADER,
    MOTOR,
    MOTOR_CODE,
    MOTOR_STATES,
    BitContext,
    MotorContext,
    bit_context,
    bit_law,
    bit_law_force,
    bit_law_jacobian,
    bit_laws,
    motor,
    motor_slope,
    motor_torque,
    motors,
)

#: One instance of every registered bit law (the Detournay law with the published bit of Aarsnes & van de
#: Wouw 2019) and a random state drawn away from its kinks: (u̇ [m/s], θ̇ [rad/s], d [m]).
LAWS = {
    "tucker_wang": BitRockParameters.reference(),
    "detournay": DetournayParameters(blades=4, radius=0.108, intrinsic_specific_energy=60e6,
                                     cutting_inclination=0.6, contact_stress=60e6, wear_flat_length=0.011,
                                     friction_coefficient=0.6),
    "off_bottom": OffBottom(),
}
MOTORS = {"positive_displacement": PositiveDisplacementMotor(position=800.0, flow_rate=0.03, displacement=2e-3,
                                                             stall_torque=8e3, volumetric_efficiency=0.9,
                                                             mechanical_efficiency=0.8)}


def _state(name: str, rng: np.random.Generator) -> tuple[float, float, float]:
    if name == "detournay":  # off the kinks u̇ ∈ {0, v_r}, |θ̇| = ω_r (v_r = 2.5e-4 m/s, ω_r = 5e-3 rad/s)
        u = rng.choice([rng.uniform(2e-5, 2.3e-4), rng.uniform(3e-4, 3e-3), rng.uniform(-1e-3, -2e-5)])
        w = rng.choice([rng.uniform(-4e-3, 4e-3), rng.uniform(6e-3, 20.0), rng.uniform(-20.0, -6e-3)])
        return float(u), float(w), float(rng.uniform(1e-4, 3e-3))
    # the Tucker–Wang law in contact (f < 0 checked below), above its stick floor
    return float(rng.uniform(-1e-3, 4e-3)), float(rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 25.0)), 0.0


def _bit_laws_array(law) -> np.ndarray:
    laws = np.zeros(BIT_LAW + type(law).kernel_size)
    laws[BIT_LAW_CODE] = type(law).component_code
    laws[BIT_LAW:] = law.kernel_array()
    return laws


@njit
def _compiled_jacobian(laws, u, w, d):
    return bit_law_jacobian(laws, BitContext(0.3, 0.01, 2.0, u, w, d, 1e5))


@njit
def _compiled_force(laws, u, w, d):
    return bit_law_force(laws, BitContext(0.3, 0.01, 2.0, u, w, d, 1e5))


def _context(u, w, d):
    return bit_context(u, w, d, time=0.3, position=0.01, angle=2.0, weight_on_bit=1e5)


def _central_differences(laws, point) -> np.ndarray:
    """(2, 3): the compiled law's force and torque differenced in u̇, θ̇ and d (steps 1e-6 of the value, at least
    of 1e-3 m/s, 1 rad/s, 1e-3 m)."""
    out = np.zeros((2, 3))
    for k, scale in enumerate((1e-3, 1.0, 1e-3)):
        step = 1e-6 * max(abs(point[k]), scale)
        up, down = np.array(point), np.array(point)
        up[k] += step
        down[k] -= step
        out[:, k] = (np.array(_compiled_force(laws, *up)) - np.array(_compiled_force(laws, *down))) / (2.0 * step)
    return out


def test_every_registered_bit_law_and_motor_is_checked():
    """The package's laws and motors (other tests register their own, named ``*_test``, in the same process)."""
    assert set(LAWS) == {name for name in bit_laws() if bit_law(name).__module__.startswith("drillstring.")}
    assert set(MOTORS) == {name for name in motors() if motor(name).__module__.startswith("drillstring.")}


@pytest.mark.parametrize("name", sorted(LAWS))
def test_compiled_bit_law_jacobian_is_the_laws_jacobian_at_and_its_differences(name):
    """At 40 random states: the compiled dispatch equals ``jacobian_at`` and ``depth_partials`` to 1e-12, and central
    differences of the compiled law to 1e-6 of each row's largest partial."""
    law = LAWS[name]
    laws = _bit_laws_array(law)
    rng = np.random.default_rng(33)
    checked = 0
    while checked < 40:
        point = _state(name, rng)
        if name == "tucker_wang" and not law.evaluate(point[0], point[1])[0] < -1e-3 * law.a1 / law.a2:
            continue  # near or past lift-off (the unilateral kink)
        compiled = np.array(_compiled_jacobian(laws, *point)).reshape(2, 3)
        ctx = _context(*point)
        python = np.column_stack([law.jacobian_at(ctx), law.depth_partials(ctx)])
        np.testing.assert_allclose(compiled, python, rtol=1e-12, atol=0.0, err_msg=f"{name} at {point}")
        differenced = _central_differences(laws, point)
        scale = np.abs(compiled).max(axis=1, keepdims=True)
        assert np.all(np.abs(differenced - compiled) <= 1e-6 * np.maximum(np.abs(compiled), scale) + 1e-300), \
            (name, point, compiled, differenced)
        checked += 1
    if name != "off_bottom":  # the check could fail: the partials are not all zero
        assert np.abs(compiled).max() > 0.0


def test_the_tucker_wang_jacobian_at_stick_and_off_the_rock():
    """At the stick floor, at θ̇ = 0 and past lift-off the compiled Jacobian is the kernel's own limits: 1/Z²
    frozen (no f_θ from it), the torque's partials those of Z²/θ̇ = 0 at θ̇ = 0, zeros where there is no force."""
    law = BitRockParameters.reference()
    laws = _bit_laws_array(law)
    f_u, f_w, f_d, t_u, t_w, t_d = _compiled_jacobian(laws, 1e-3, 0.0, 0.0)
    assert f_u == pytest.approx(-(1.0 + (law.e / law.stick_speed_floor) ** 2) / law.a2, rel=1e-12)
    assert (f_w, f_d, t_u, t_d) == (0.0, 0.0, 0.0, 0.0)
    assert t_w == pytest.approx(-law.a4 * 1e-3 / law.e**2 - law.a5 / law.e, rel=1e-12)
    assert _compiled_jacobian(laws, -1.0, 10.0, 0.0) == (0.0,) * 6  # the bit moves up fast: off the rock
    no_floor = dataclasses.replace(law, stick_speed_floor_ratio=0.0)
    assert np.all(np.isfinite(_compiled_jacobian(_bit_laws_array(no_floor), 1e-3, 0.0, 0.0)))


def _motor_laws_array(motor) -> np.ndarray:
    laws = np.zeros(len(HEADER) + type(motor).kernel_size)
    laws[MOTOR_CODE] = type(motor).component_code
    laws[MOTOR] = len(HEADER)
    laws[MOTOR_STATES] = 0
    laws[len(HEADER):] = motor.kernel_array()
    return laws


@njit
def _compiled_slope(laws, speed, y, out):
    return motor_slope(laws, MotorContext(0.2, speed), y, out)


@njit
def _compiled_torque(laws, speed, y, out):
    return motor_torque(laws, MotorContext(0.2, speed), y, out)


@pytest.mark.parametrize("name", sorted(MOTORS))
def test_compiled_motor_slope_is_the_motors_jacobian_at_and_its_difference(name):
    motor = MOTORS[name]
    laws = _motor_laws_array(motor)
    y, out = np.zeros(motor.n_states), np.zeros(motor.n_states)
    for speed in np.random.default_rng(7).uniform(-50.0, 80.0, 20):
        compiled = _compiled_slope(laws, speed, y, out)
        python = motor.jacobian_at(MotorContext(0.2, speed), motor.steady_states(speed))[0, 0]
        assert compiled == pytest.approx(python, rel=1e-12, abs=0.0)
        step = 1e-6 * max(abs(speed), 1.0)
        differenced = (_compiled_torque(laws, speed + step, y, out) - _compiled_torque(laws, speed - step, y, out)) \
            / (2.0 * step)
        assert differenced == pytest.approx(compiled, rel=1e-6)
        assert compiled != 0.0


class _DifferencedTuckerWang(BitRockParameters):
    """The Tucker–Wang law declaring no Jacobian (not registered)."""

    jacobian_kernel = None


class _DifferencedMotor(PositiveDisplacementMotor):
    jacobian_kernel = None


def test_a_law_without_a_jacobian_is_differenced_in_python_and_in_the_compiled_dispatch():
    """A bit law and a motor that declare no ``jacobian_kernel``: their Python ``jacobian_at`` and the function
    the registry compiles into its dispatch for them (:func:`~drillstring.forces.protocol.differenced_bit_jacobian`
    of the kernel, inlined) both give the closed form to 1e-6."""
    from drillstring.forces.registry import (
        _bit_law_jacobian_member,
        _motor_slope_member,
        inlined,
    )

    law = _DifferencedTuckerWang(*dataclasses.astuple(BitRockParameters.reference()))
    ctx = _context(2e-3, 9.0, 0.0)
    closed = np.array(tucker_wang_jacobian(law.kernel_array(), BitContext(*map(float, ctx)))).reshape(2, 3)
    np.testing.assert_allclose(law.partials_at(ctx), closed, rtol=1e-6, atol=1e-6 * np.abs(closed).max())

    function, arguments = _bit_law_jacobian_member(_DifferencedTuckerWang)
    assert arguments == f"laws[{BIT_LAW}:], ctx"
    function = inlined(function)  # as the dispatch compiles it
    compiled = njit(lambda args, ctx: function(args, ctx))(law.kernel_array(), BitContext(*map(float, ctx)))
    np.testing.assert_allclose(np.array(compiled).reshape(2, 3), law.partials_at(ctx), rtol=1e-12, atol=0.0)

    motor = _DifferencedMotor(*dataclasses.astuple(MOTORS["positive_displacement"]))
    slope, arguments = _motor_slope_member(_DifferencedMotor)
    slope = inlined(slope)
    assert arguments.endswith(f"out[int(laws[{MOTOR_STATES}]):]")  # the scratch takes the states' rates
    expected = -motor.stall_torque / motor.no_load_speed
    assert motor.jacobian(4.0) == pytest.approx(expected, rel=1e-6)
    none = np.zeros(0)
    compiled = njit(lambda args, ctx, y, out: slope(args, ctx, y, out))(motor.kernel_array(), MotorContext(0.0, 4.0),
                                                                         none, none)
    assert compiled == pytest.approx(motor.jacobian(4.0), rel=1e-12)
