"""A downhole motor in the reduced model: the released torsion (drillstring.rotor) against the spectra of the two
strings it separates, the compiled right-hand side against the NumPy reference, steady drilling against the
closed form, the linearisation against finite differences."""

import math

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import brentq

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import linearized_matrix, stability, steady_drilling
from drillstring.fem.assembly import THETA_X, dof
from drillstring.fem.element import torsion_matrices
from drillstring.modal import case_linear_system
from drillstring.rotor import released_system, released_torsional_modes, rotor_node
from drillstring.statics import case_static_state


def _case(controller="imposed_speed", law=None, undamped_rigid=False):
    """The built-in motor case on a 50 m mesh with a small basis; ``undamped_rigid``: c1 = c2 = 0 (no
    resistance to the rigid motions, so steady drilling has the closed form)."""
    case = load_case("motor")
    update = {
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={"axial_modes": 4, "torsional_modes": 6,
                                                               "lateral_modes": 4}),
        "top_drive": case.top_drive.model_copy(update={"controller": controller}),
    }
    if law is not None:
        update["bit_rock"] = case.bit_rock.model_copy(update={"law": law})
    if undamped_rigid:
        update["damping"] = case.damping.model_copy(update={"rigid_axial": 0.0, "rigid_rotation": 0.0})
    return case.model_copy(update=update)


@pytest.fixture(scope="module")
def model():
    return case_reduced_model(_case())


def test_the_released_torsion_is_the_two_strings_it_separates():
    """Released at the rotor station, the string held at the top has the spectrum of the string above the
    station (held at the top, free below) together with that of the string below it (free at both ends: its
    rigid rotation at 0), each assembled here from its elements' torsion matrices."""
    case = _case()
    static = case_static_state(case)
    system = case_linear_system(case, static)
    mesh = static.mesh
    node = rotor_node(mesh, case.motor.position)
    release = released_torsional_modes(released_system(system, node), node, 30)
    sections, lengths = mesh.element_sections(), mesh.element_lengths

    def assembled(elements):
        size = len(elements) + 1
        k, m = np.zeros((size, size)), np.zeros((size, size))
        for i, e in enumerate(elements):
            ke, me = torsion_matrices(sections[e], float(lengths[e]))
            k[i:i + 2, i:i + 2] += ke
            m[i:i + 2, i:i + 2] += me
        return k, m

    k_up, m_up = assembled(range(node))
    k_low, m_low = assembled(range(node, mesh.n_elements))
    upper = sla.eigh(k_up[1:, 1:], m_up[1:, 1:], eigvals_only=True)  # held at the top
    lower = sla.eigh(k_low, m_low, eigvals_only=True)  # free-free
    expected = np.sort(np.concatenate([upper, lower]))[:30]
    found = release.family.eigenvalues
    np.testing.assert_allclose(found[1:], expected[1:], rtol=1e-9)
    assert found[0] == 0.0 and abs(expected[0]) < 1e-6 * expected[1]
    # the rigid motion is the lower string turning: 1 on the rotor side and below the station, 0 above
    rigid = release.family.shapes[:, 0]
    theta = rigid[dof(np.arange(mesh.n_nodes), THETA_X)]
    assert np.all(theta[:node + 1] == 0.0) and np.allclose(theta[node + 1:], release.rotor[0])
    assert release.relative @ release.lower_rotation == pytest.approx(1.0, rel=1e-12)


def test_tying_the_rotor_back_gives_the_string_without_motor():
    """q_dup = T q with θ_r tied to θ_k again (the rotor side's row and column added to node k's) is the
    mesh's own system, to round-off."""
    case = _case()
    static = case_static_state(case)
    system = case_linear_system(case, static)
    node = rotor_node(static.mesh, case.motor.position)
    released = released_system(system, node)
    n = system.mesh.n_dofs
    tie = np.zeros((n + 1, n))
    tie[np.arange(n), np.arange(n)] = 1.0
    tie[n, dof(node, THETA_X)] = 1.0
    for matrix in ("mass", "stiffness"):
        tied = tie.T @ getattr(released, matrix).toarray() @ tie
        original = getattr(system, matrix).toarray()
        assert np.abs(tied - original).max() <= 1e-12 * np.abs(original).max(), matrix
    assert not np.allclose(released.stiffness.toarray()[:n, :n], system.stiffness.toarray())
    # the rotor side couples to itself and to the θx of the node below the station only
    assert sorted(released.stiffness[n].indices) == [int(dof(node + 1, THETA_X)), n]


def test_compiled_right_hand_side_and_observations_with_a_motor(model):
    rng = np.random.default_rng(4)
    n = model.size
    y = model.initial_state(0.0, 0) + 1e-3 * rng.standard_normal(model.state_size)
    compiled, reference = model.rhs(0.3, y), model.rhs_reference(0.3, y)
    np.testing.assert_allclose(compiled, reference, rtol=1e-10, atol=1e-12 * np.abs(reference).max())
    out = dict(zip(model.observable_names, model.observe(0.3, y)))
    speed = model.motor_shapes @ y[n:2 * n]
    assert out["motor_speed"] == pytest.approx(speed, rel=1e-12)
    assert out["motor_torque"] == pytest.approx(float(model.motor.evaluate(speed)), rel=1e-12)


def _tucker_wang_torque_on_bit(law, bit_speed, weight):
    """TOB of the Tucker–Wang law (SPEC §6) in steady drilling without rigid axial resistance, written out:
    ROP = Z²(a2 W − a1) + Z a3 Ω, TOB = a4 Z² ROP / Ω + a5 Z, Z = Ω / sqrt(Ω² + e²)."""
    z = bit_speed / math.hypot(bit_speed, law.e)
    rop = z * z * (law.a2 * weight - law.a1) + z * law.a3 * bit_speed
    return law.a4 * z * z * rop / bit_speed + law.a5 * z, rop


@pytest.mark.parametrize("controller", ["imposed_speed", "pi", "soft_torque"])
def test_steady_drilling_with_a_motor_is_the_closed_form(controller):
    """Without resistance to the rigid motions the motor's torque at its speed is the bit's torque at the bit's
    speed: T_s (1 − ω_m/ω₀) = TOB(Ω + ω_m), a scalar equation solved here with the Tucker–Wang law written out;
    the differential pressure T/(η_m v); the state an equilibrium of the compiled right-hand side."""
    model = case_reduced_model(_case(controller, undamped_rigid=True))
    steady = steady_drilling(model)
    law, m, omega = model.bit_rock, model.motor, model.top_speed
    weight = model.weight_on_bit

    def balance(w):
        return m.stall_torque * (1 - w / m.no_load_speed) - _tucker_wang_torque_on_bit(law, omega + w, weight)[0]

    w_m = brentq(balance, 0.0, m.no_load_speed, xtol=1e-14)
    tob, rop = _tucker_wang_torque_on_bit(law, omega + w_m, weight)
    assert steady.motor["motor_speed"] == pytest.approx(w_m, rel=1e-9)
    assert steady.bit_speed == pytest.approx(omega + w_m, rel=1e-12)
    assert steady.motor["string_speed"] == pytest.approx(omega, rel=1e-12)
    assert steady.torque_on_bit == pytest.approx(tob, rel=1e-9)
    assert steady.motor["motor_torque"] == pytest.approx(tob, rel=1e-9)
    assert steady.rate_of_penetration == pytest.approx(rop, rel=1e-9)
    assert steady.motor["differential_pressure"] == pytest.approx(
        tob / (m.mechanical_efficiency * m.displacement), rel=1e-9)
    n = model.size
    rate = model.rhs(0.0, steady.state)
    assert np.abs(rate[n:2 * n]).max() < 1e-9 * np.abs(model.omega2 * steady.state[:n]).max()
    observed = dict(zip(model.observable_names, model.observe(0.0, steady.state)))
    assert observed["motor_speed"] == pytest.approx(w_m, rel=1e-9)
    assert observed["bit_speed"] == pytest.approx(omega + w_m, rel=1e-9)
    assert observed["quill_speed"] == pytest.approx(omega, rel=1e-12)


def test_off_bottom_the_motor_turns_at_its_no_load_speed():
    model = case_reduced_model(_case(law="off_bottom", undamped_rigid=True))
    steady = steady_drilling(model)
    assert steady.motor["motor_speed"] == pytest.approx(model.motor.no_load_speed, rel=1e-10)
    assert steady.bit_speed == pytest.approx(model.top_speed + model.motor.no_load_speed, rel=1e-10)
    assert abs(steady.motor["motor_torque"]) < 1e-9 * model.motor.stall_torque


@pytest.mark.parametrize("controller", ["imposed_speed", "pi", "soft_torque"])
def test_the_linearisation_is_the_right_hand_sides_jacobian(controller):
    """The state matrix about steady drilling (bit law, top drive and motor Jacobians) against central
    differences of the NumPy right-hand side."""
    model = case_reduced_model(_case(controller))
    steady = steady_drilling(model)
    a = linearized_matrix(model, steady)
    y0 = steady.state
    fd = np.zeros_like(a)
    for j in range(model.state_size):
        step = 1e-6 * max(1.0, abs(y0[j]))
        up, down = y0.copy(), y0.copy()
        up[j] += step
        down[j] -= step
        fd[:, j] = (model.rhs_reference(0.0, up) - model.rhs_reference(0.0, down)) / (2 * step)
    n = model.size
    scale = np.abs(a[n:]).max()
    assert np.abs(fd[n:] - a[n:]).max() < 1e-6 * scale
    # the motor's part alone is what the motor adds: dT/dω_m on the relative-rotation row
    assert model.motor.jacobian() * model.motor_shapes @ model.motor_shapes != 0.0


def test_the_stability_of_a_motor_case_leaves_out_only_the_rigid_angles():
    model = case_reduced_model(_case("pi"))
    result = stability(model)
    rigid = sum(1 for f, w2 in zip(model.family, model.omega2) if f != "lateral_y" and f != "lateral_z" and w2 == 0)
    # every root is informative: none at 0 (the rigid angles, rigid axial, rotation and the rotor's, are left out)
    assert rigid == 3
    assert min(abs(complex(m.growth_rate, 2 * math.pi * m.frequency)) for m in result.modes) > 1e-6
    assert result.steady_state.to_dict()["motor_speed"] > 0


def test_the_stiff_term_diagnosis_names_the_motor(model):
    """The motor's slope across the rotor, on the small inertia below it, is a rate of its own
    (|dT/dω_m| |φ_r − φ_k|², the damper's), not counted as contact."""
    from drillstring.dynamics.stiffness import CONTACT, MOTOR, stiffness_rates

    steady = steady_drilling(model)
    rates = stiffness_rates(model, 0.0, steady.state)
    expected = abs(model.motor.jacobian()) * float(model.motor_shapes @ model.motor_shapes)
    assert rates[MOTOR] == pytest.approx(expected, rel=1e-9)
    assert rates[CONTACT] < 1e-3 * rates[MOTOR]


def test_a_run_outputs_the_motor_and_a_run_without_one_does_not():
    from drillstring.api import simulate

    case = _case()
    data = simulate(case, t_end=0.05, output_step=0.01)
    motor = case_reduced_model(case).motor
    np.testing.assert_allclose(data["differential_pressure"].values,
                               data["motor_torque"].values / (motor.mechanical_efficiency * motor.displacement),
                               rtol=1e-12)
    assert data["motor_speed"].attrs["units"] == "rad/s" and data["differential_pressure"].attrs["units"] == "Pa"
    # started with the rotor at rest relative to the housing: the motor gives its stall torque at t = 0
    assert data["motor_torque"].values[0] == pytest.approx(motor.stall_torque, rel=1e-6)
    plain = simulate(load_case("reference"), t_end=0.02, output_step=0.01)
    assert not {"motor_speed", "motor_torque", "differential_pressure"} & set(plain.data_vars)
