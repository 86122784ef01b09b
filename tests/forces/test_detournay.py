"""Tests of the Detournay bit–rock law (drillstring.forces.detournay): the closed-form steady state of the
published data set, the friction line E = E₀ + μγS, the compiled kernel (contact, saturations, bounce),
its closed-form Jacobian and the kernel applied over arrays."""

import math

import numpy as np
import pytest

from drillstring.forces.detournay import KERNEL_SIZE, DetournayParameters, detournay_force

RPM = 2.0 * math.pi / 60.0
M_PER_H = 1.0 / 3600.0

#: Aarsnes & van de Wouw, J. Sound Vib. 444 (2019): bit and rock.
PUBLISHED = dict(blades=4, radius=0.108, intrinsic_specific_energy=60e6, cutting_inclination=0.6,
                 contact_stress=60e6, wear_flat_length=0.011, friction_coefficient=0.6, geometry=1.0)
LAW = DetournayParameters(**PUBLISHED)


def _random_parameters(rng) -> DetournayParameters:
    return DetournayParameters(
        blades=int(rng.integers(1, 9)), radius=rng.uniform(0.05, 0.2),
        intrinsic_specific_energy=rng.uniform(10e6, 300e6), cutting_inclination=rng.uniform(0.3, 1.0),
        contact_stress=rng.uniform(10e6, 300e6), wear_flat_length=rng.uniform(0.5e-3, 20e-3),
        friction_coefficient=rng.uniform(0.2, 1.0), geometry=rng.uniform(0.5, 1.5),
        contact_velocity=10.0 ** rng.uniform(-6, -4), friction_speed=10.0 ** rng.uniform(-4, -2))


def _random_steady_states(seed: int, count: int):
    """``(law, V, Ω, steady state)`` of random bits and rocks at random operating points (1–100 m/h,
    20–200 rpm)."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        law = _random_parameters(rng)
        rop, omega = rng.uniform(1.0, 100.0) * M_PER_H, rng.uniform(20.0, 200.0) * RPM
        yield law, rop, omega, law.steady_state(rop, omega)


def _kernel(law: DetournayParameters, depth, velocity, speed):
    return detournay_force(law.kernel_array(), float(depth), float(velocity), float(speed))


# ------------------------------------------------------------------------------- the published steady state


def test_published_steady_state_at_30_rpm_and_30_m_per_h():
    """Depth of cut 16.7 mm/rev (4.17 mm/blade), delay 0.5 s, W_c 64.8 kN, W_f 71.3 kN, W 136.1 kN,
    T_c 5.83 kN·m: the stated (rounded) values and the paper's formulas, derived here from the raw numbers."""
    a, eps, zeta, sigma, l, mu, gamma, n = 0.108, 60e6, 0.6, 60e6, 0.011, 0.6, 1.0, 4
    omega, rop = 30.0 * 2.0 * math.pi / 60.0, 30.0 / 3600.0
    # Independent derivation: one revolution takes 2π/Ω = 2 s, in which the bit advances 30 m/h · 2 s.
    depth = rop * (2.0 * math.pi / omega)
    depth_blade = depth / n
    delay = (2.0 * math.pi / n) / omega
    w_c = a * zeta * eps * depth  # n blades, each cutting d_n: a ζ ε n d_n = a ζ ε d
    w_f = a * sigma * l
    t_c = 0.5 * a**2 * eps * depth
    t_f = 0.5 * mu * gamma * a * w_f

    s = LAW.steady_state(rop, omega)
    # The rounded values, to their last digit.
    assert s.depth_per_revolution * 1e3 == pytest.approx(16.7, abs=0.05)
    assert s.depth_per_blade * 1e3 == pytest.approx(4.17, abs=0.005)
    assert s.delay == pytest.approx(0.5, abs=5e-13)
    assert s.cutting_force / 1e3 == pytest.approx(64.8, abs=0.05)
    assert s.contact_force / 1e3 == pytest.approx(71.3, abs=0.05)
    assert s.weight_on_bit / 1e3 == pytest.approx(136.1, abs=0.05)
    assert s.cutting_torque / 1e3 == pytest.approx(5.83, abs=0.005)
    # The formulas, to round-off.
    for got, want in ((s.depth_per_revolution, depth), (s.depth_per_blade, depth_blade), (s.delay, delay),
                      (s.cutting_force, w_c), (s.contact_force, w_f), (s.weight_on_bit, w_c + w_f),
                      (s.cutting_torque, t_c), (s.friction_torque, t_f), (s.torque_on_bit, t_c + t_f)):
        assert got == pytest.approx(want, rel=1e-12)
    assert (s.rate_of_penetration, s.bit_speed) == (rop, omega)
    # The exact values the rounded ones come from: 1/60 m per revolution, 64.8 kN, 71.28 kN, 5.832 kN·m.
    assert s.depth_per_revolution == pytest.approx(1.0 / 60.0, rel=1e-12)
    assert s.weight_on_bit == pytest.approx(136_080.0, rel=1e-12)
    assert s.cutting_torque == pytest.approx(5_832.0, rel=1e-12)
    assert s.friction_torque == pytest.approx(2_309.472, rel=1e-12)


def test_published_law_constants():
    assert LAW.cutting_stiffness == pytest.approx(0.108 * 0.6 * 60e6 * 4, rel=1e-15)
    assert LAW.cutting_torque_rate == pytest.approx(0.5 * 0.108**2 * 60e6 * 4, rel=1e-15)
    assert LAW.contact_force == pytest.approx(71_280.0, rel=1e-15)
    assert LAW.friction_arm == pytest.approx(0.5 * 0.6 * 0.108, rel=1e-15)
    assert LAW.baseline_specific_energy == pytest.approx(0.64 * 60e6, rel=1e-15)
    assert LAW.sector == pytest.approx(math.pi / 2.0, rel=1e-15)
    assert LAW.kernel_array().shape == (KERNEL_SIZE,)


# -------------------------------------------------------------------------------- the E–S friction line


def test_every_steady_state_in_contact_lies_on_the_friction_line():
    """E = E₀ + μγS with E = 2T/(a²d), S = W/(ad), E₀ = (1 − μγζ)ε, over random bits, rocks and
    operating points; the cutting point (no flats) would lie at (ζε, ε), off the line when σl > 0."""
    for law, _, _, s in _random_steady_states(17, 300):
        a, d = law.radius, s.depth_per_revolution
        energy, strength = 2.0 * s.torque_on_bit / (a * a * d), s.weight_on_bit / (a * d)
        assert law.specific_energy(s) == pytest.approx(energy, rel=1e-13)
        assert law.drilling_strength(s) == pytest.approx(strength, rel=1e-13)
        e0 = (1.0 - law.friction_coefficient * law.geometry * law.cutting_inclination) * \
            law.intrinsic_specific_energy
        line = e0 + law.friction_coefficient * law.geometry * strength
        assert energy == pytest.approx(line, rel=1e-12)
        # the flats move the point along the line, away from the pure-cutting point (S, E) = (ζε, ε)
        assert strength > law.cutting_inclination * law.intrinsic_specific_energy


def test_rate_of_penetration_inverts_the_steady_state():
    for law, rop, omega, s in _random_steady_states(1992, 200):
        assert law.rate_of_penetration(s.weight_on_bit, omega) == pytest.approx(rop, rel=1e-12)
        f0, f1 = law.axial_force_affine(omega)
        assert f0 + f1 * rop == pytest.approx(-s.weight_on_bit, rel=1e-12)


def test_no_penetration_while_the_flats_carry_the_weight():
    """W ≤ aσl: nothing is cut (the contact force alone balances the weight), V = 0; just above it V > 0."""
    w_f = LAW.contact_force
    for weight in (0.0, 1.0, 0.5 * w_f, w_f):
        assert LAW.rate_of_penetration(weight, 30.0 * RPM) == 0.0
    assert LAW.rate_of_penetration(w_f * (1 + 1e-9), 30.0 * RPM) > 0.0
    blunt = DetournayParameters(**{**PUBLISHED, "cutting_inclination": 0.0})
    assert blunt.rate_of_penetration(2.0 * w_f, 30.0 * RPM) == 0.0  # no cutting force: no finite V


# ----------------------------------------------------------------------------------------------- the kernel


def test_kernel_is_minus_the_steady_state_while_drilling():
    for law, rop, omega, s in _random_steady_states(2004, 100):
        assert rop > law.contact_velocity and omega > law.friction_speed  # outside both saturations
        force, torque = _kernel(law, s.depth_per_blade, rop, omega)
        assert force == pytest.approx(-s.weight_on_bit, rel=1e-13)
        assert torque == pytest.approx(-s.torque_on_bit, rel=1e-13)
    s = LAW.steady_state(30.0 * M_PER_H, 30.0 * RPM)
    force, torque = _kernel(LAW, s.depth_per_blade, s.rate_of_penetration, s.bit_speed)
    assert (force, torque) == pytest.approx((-136_080.0, -(5_832.0 + 2_309.472)), rel=1e-12)


@pytest.mark.parametrize("depth", [0.0, -0.0, -1e-12, -4e-3, -np.inf, np.nan])
@pytest.mark.parametrize("velocity", [-0.1, 0.0, 5e-6, 1e-2])
@pytest.mark.parametrize("speed", [-3.0, 0.0, 3.0])
def test_no_force_off_the_rock(depth, velocity, speed):
    """Bit bounce: d_n ≤ 0 (the bit above the bottom the previous blade left) means no contact at all."""
    assert _kernel(LAW, depth, velocity, speed) == (0.0, 0.0)
    force, torque = LAW.evaluate(depth, velocity, speed)
    assert float(force) == 0.0 and float(torque) == 0.0
    np.testing.assert_array_equal(LAW.jacobian(depth, velocity, speed), np.zeros((2, 3)))


def test_contact_force_saturates_in_the_axial_velocity():
    """The flats' force: 0 while the bit moves up or rests, a ramp of slope aσl/v_r below v_r, aσl above;
    the cutting force does not depend on u̇."""
    law, depth, omega = LAW, 2e-3, 30.0 * RPM
    v_r, cut, w_f = law.contact_velocity, law.cutting_stiffness * depth, law.contact_force
    for velocity in (-1.0, -1e-3, -v_r, -1e-12, 0.0):
        assert _kernel(law, depth, velocity, omega)[0] == pytest.approx(-cut, rel=1e-15)
    for fraction in (1e-3, 0.25, 0.5, 0.9, 1.0 - 1e-9):
        assert _kernel(law, depth, fraction * v_r, omega)[0] == pytest.approx(-(cut + fraction * w_f), rel=1e-13)
    for velocity in (v_r, 1.0000001 * v_r, 2 * v_r, 1e-2, 10.0):
        assert _kernel(law, depth, velocity, omega)[0] == pytest.approx(-(cut + w_f), rel=1e-15)
    # the torque carries the friction of the flats in the same proportion
    full = law.cutting_torque_rate * depth
    assert _kernel(law, depth, -1.0, omega)[1] == pytest.approx(-full, rel=1e-15)
    assert _kernel(law, depth, 0.5 * v_r, omega)[1] == pytest.approx(-(full + 0.5 * law.friction_arm * w_f),
                                                                     rel=1e-13)
    velocities = np.linspace(-3 * v_r, 3 * v_r, 601)
    forces = np.array([_kernel(law, depth, v, omega)[0] for v in velocities])
    assert np.all(np.diff(forces) <= 0.0)  # monotone: the faster the bit advances, the more the rock pushes


def test_torque_saturates_in_the_bit_speed():
    """Odd in ω, linear below ω_r, the full value above: |t| never exceeds it (a bit at rest holds any
    torque below its full value by turning at most ω_r)."""
    law, depth, velocity = LAW, 3e-3, 1e-3
    w_r = law.friction_speed
    full = law.cutting_torque_rate * depth + law.friction_arm * law.contact_force
    speeds = np.concatenate([np.linspace(-5 * w_r, 5 * w_r, 1001), [-10.0, -1.0, 1.0, 10.0]])
    torques = np.array([_kernel(law, depth, velocity, w)[1] for w in speeds])
    mirrored = np.array([_kernel(law, depth, velocity, -w)[1] for w in speeds])
    np.testing.assert_array_equal(torques, -mirrored)
    assert np.all(np.abs(torques) <= full * (1 + 1e-15))
    assert _kernel(law, depth, velocity, 0.0)[1] == 0.0
    inside = np.abs(speeds) < w_r
    np.testing.assert_allclose(torques[inside], -full * speeds[inside] / w_r, rtol=1e-13, atol=1e-12 * full)
    np.testing.assert_allclose(torques[~inside], -full * np.sign(speeds[~inside]), rtol=1e-15)
    assert np.all(np.diff(torques[:1001]) <= 0.0)
    # the axial force does not depend on ω
    forces = {_kernel(law, depth, velocity, w)[0] for w in speeds}
    assert len(forces) == 1


# ------------------------------------------------------------------ Jacobian and the law over arrays


def _regime_points(law, rng, count):
    """Random states in every regime of the two saturations, away from their kinks."""
    v_r, w_r = law.contact_velocity, law.friction_speed
    velocity_bands = [(-5.0 * v_r, -0.05 * v_r), (0.05 * v_r, 0.95 * v_r), (1.05 * v_r, 1e4 * v_r)]
    speed_bands = [(-20.0, -1.05 * w_r), (-0.95 * w_r, 0.95 * w_r), (1.05 * w_r, 20.0)]
    for i in range(count):
        vb, sb = velocity_bands[i % 3], speed_bands[(i // 3) % 3]
        yield rng.uniform(1e-4, 1e-2), rng.uniform(*vb), rng.uniform(*sb)


def test_jacobian_matches_central_differences_of_the_kernel():
    rng = np.random.default_rng(2007)
    checked = 0
    for _ in range(20):
        law = _random_parameters(rng)
        v_r, w_r = law.contact_velocity, law.friction_speed
        for depth, velocity, speed in _regime_points(law, rng, 27):
            jac = law.jacobian(depth, velocity, speed)
            steps = (1e-6 * depth, 1e-3 * v_r, 1e-3 * w_r)
            state = [depth, velocity, speed]
            numeric = np.empty((2, 3))
            for j, h in enumerate(steps):
                up, down = list(state), list(state)
                up[j] += h
                down[j] -= h
                numeric[:, j] = (np.array(_kernel(law, *up)) - np.array(_kernel(law, *down))) / (2.0 * h)
            scale = np.abs(numeric).max(axis=1, keepdims=True)
            np.testing.assert_allclose(jac, numeric, rtol=1e-6, atol=1e-8 * float(scale.max()))
            checked += 1
    assert checked == 540


def test_jacobian_entries_in_each_regime():
    """The closed form itself: slopes 1/v_r and 1/ω_r inside the ramps, 0 outside; f_ω = 0 everywhere."""
    law, depth = LAW, 4e-3
    v_r, w_r = law.contact_velocity, law.friction_speed
    drilling = law.jacobian(depth, 1e-2, 3.0)
    np.testing.assert_allclose(drilling, [[-law.cutting_stiffness, 0.0, 0.0],
                                          [-law.cutting_torque_rate, 0.0, 0.0]], rtol=1e-15)
    creeping = law.jacobian(depth, 0.5 * v_r, 3.0)
    assert creeping[0, 1] == pytest.approx(-law.contact_force / v_r, rel=1e-15)
    assert creeping[1, 1] == pytest.approx(-law.friction_arm * law.contact_force / v_r, rel=1e-15)
    stuck = law.jacobian(depth, 1e-2, 0.0)
    full = law.cutting_torque_rate * depth + law.friction_arm * law.contact_force
    assert stuck[1, 2] == pytest.approx(-full / w_r, rel=1e-15)
    assert stuck[1, 0] == 0.0 and stuck[0, 2] == 0.0
    backwards = law.jacobian(depth, 1e-2, -3.0)
    assert backwards[1, 0] == pytest.approx(law.cutting_torque_rate, rel=1e-15)


def test_evaluate_applies_the_kernel_elementwise_and_broadcasts():
    """``evaluate`` is the kernel applied elementwise (the law's one implementation, checked against the closed
    forms above): the same numbers, broadcast over the inputs, 0-d arrays for scalars."""
    rng = np.random.default_rng(4)
    law = _random_parameters(rng)
    v_r, w_r = law.contact_velocity, law.friction_speed
    depth = rng.uniform(-2e-3, 1e-2, size=(40, 1, 1))
    velocity = rng.uniform(-2 * v_r, 2 * v_r, size=(1, 30, 1))
    speed = rng.uniform(-2 * w_r, 2 * w_r, size=(1, 1, 20))
    force, torque = law.evaluate(depth, velocity, speed)
    assert force.shape == torque.shape == (40, 30, 20)
    d, u, w = np.broadcast_arrays(depth, velocity, speed)
    expected = np.array([_kernel(law, *x) for x in zip(d.ravel(), u.ravel(), w.ravel())])
    np.testing.assert_array_equal(force.ravel(), expected[:, 0])
    np.testing.assert_array_equal(torque.ravel(), expected[:, 1])
    assert np.count_nonzero(force == 0.0) == np.count_nonzero(d <= 0.0)
    scalar = law.evaluate(2e-3, 1.0, 3.0)
    assert scalar[0].shape == () and float(scalar[0]) == _kernel(law, 2e-3, 1.0, 3.0)[0]


# ------------------------------------------------------------------------------------------------ bad input


@pytest.mark.parametrize(("field", "value"), [
    ("blades", 0), ("blades", 2.5), ("radius", 0.0), ("radius", math.nan),
    ("intrinsic_specific_energy", -1.0), ("intrinsic_specific_energy", math.inf),
    ("cutting_inclination", -0.1), ("contact_stress", -1.0), ("wear_flat_length", math.nan),
    ("friction_coefficient", -0.5), ("geometry", -1.0), ("contact_velocity", 0.0), ("friction_speed", -1e-3),
])
def test_bad_parameters_name_the_field(field, value):
    with pytest.raises(ValueError) as info:
        DetournayParameters(**{**PUBLISHED, field: value})
    message = str(info.value)
    assert message.startswith(f"{field} = ") and "must be" in message and "\n" not in message


@pytest.mark.parametrize(("rop", "omega"), [(0.0, 3.0), (-1e-3, 3.0), (1e-3, 0.0), (1e-3, -3.0)])
def test_steady_state_needs_advance_and_rotation(rop, omega):
    with pytest.raises(ValueError, match="rate_of_penetration > 0 and bit_speed > 0"):
        LAW.steady_state(rop, omega)
