"""The top drive (drillstring.forces.top_drive) as the torsion's top boundary of the reduced model:
closed-loop eigenvalues against the exact distributed rod, the imposed speed recovered at high gains, the
reflection coefficient of a torsional pulse, off bottom, and the component's pieces against each other."""

import math

import numpy as np
import pytest

from drillstring.case import case_from_dict
from drillstring.derived import mode_family_sizes
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.runge_kutta import integrate
from drillstring.dynamics.simulate import simulate_model
from drillstring.dynamics.stability import linearized_matrix, stability, steady_drilling
from drillstring.fem.dofs import THETA_X, dof
from drillstring.forces.registry import TopContext
from drillstring.forces.top_drive import (
    TopDriveParameters,
    reflection_coefficient,
    soft_torque_gains,
    top_drive_jacobian,
    top_drive_kernel,
    top_drive_law,
)
from drillstring.modal import family_dofs, top_inertia_matrix
from tests.exact_solutions import torsional_rod_top_drive_roots


def _with(case, **tables):
    """``case`` with some tables' fields replaced: ``_with(case, top_drive={...}, damping={...})``."""
    update = {name: getattr(case, name).model_copy(update=fields) for name, fields in tables.items()}
    return case.model_copy(update=update)


def _linear_torsion(case, **tables):
    """Off bottom, damping and fluid off: the torsion alone is linear."""
    return _with(case, bit_rock={"law": "off_bottom"}, fluid={"density": 0.0, "inlet_velocity": 0.0},
                 damping={"modal_damping_ratio": 0.0, "rigid_axial": 0.0, "rigid_rotation": 0.0}, **tables)


def _material(case):
    steel = case.materials["steel"]
    return steel.shear_modulus, steel.density


def test_closed_loop_eigenvalues_match_the_exact_rod_with_a_pi_top_drive(reference_case):
    """The reference string off bottom, undamped, turned by a PI top drive: the eigenvalues of the linearised
    reduced model (controller state included) against the roots of the exact characteristic equation of the
    distributed two-section rod with the top drive as boundary condition (0.5 % in frequency asked; 1e-3 held)."""
    drive = {"controller": "pi", "inertia": 500.0, "proportional_gain": 2000.0, "integral_gain": 5000.0}
    case = _linear_torsion(reference_case, top_drive=drive,
                           reduced_model={"axial_modes": 1, "torsional_modes": 12, "lateral_modes": 0,
                                          "lateral_cutoff": 0.0})
    result = stability(case_reduced_model(case))
    fe = sorted((m for m in result.modes if m.family == "torsional" and m.frequency > 0.0),
                key=lambda m: m.frequency)
    g, rho = _material(case)
    polar = [math.pi * (s.outer_diameter**4 - s.inner_diameter**4) / 32 for s in case.sections]
    exact = torsional_rod_top_drive_roots(
        (case.sections[0].length, case.sections[1].length), tuple(p * math.sqrt(g * rho) for p in polar),
        math.sqrt(g / rho), (drive["inertia"], drive["proportional_gain"], drive["integral_gain"]), 3.0)
    assert len(exact) >= 3
    for root, mode in zip(exact, fe):
        assert mode.frequency == pytest.approx(root.imag / (2 * math.pi), rel=1e-3)  # 0.5 % asked; 1e-4 found
        # the damping the controller gives each mode, to the same accuracy relative to |λ|
        assert abs(mode.growth_rate - root.real) < 1e-3 * abs(root)
    # the top drive damps the modes: a held top (r = -1) would leave them undamped
    assert all(root.real < -1e-3 for root in exact[:3])


def test_high_gain_pi_reproduces_the_imposed_speed_limit_cycle(torsional_case):
    """The torsional limit cycle (stick-slip-like, 28.7-171.3 rpm on this basis) with a stiff PI top drive:
    bit-speed extremes within 1 % of the imposed speed's."""
    stiff = _with(torsional_case, top_drive={"controller": "pi", "proportional_gain": 1e5, "integral_gain": 3e6})
    ranges = []
    for case in (torsional_case, stiff):
        run = simulate_model(case_reduced_model(case), t_end=60.0, output_step=0.01, lateral_perturbation=0.0)
        speed = run.observables["bit_speed"][run.time > 30.0]
        ranges.append((speed.min(), speed.max()))
    (low, high), (low_pi, high_pi) = ranges
    assert low < 0.4 * 100 * math.pi / 30  # a strong limit cycle, not a decayed one
    assert low_pi == pytest.approx(low, rel=1e-2)
    assert high_pi == pytest.approx(high, rel=1e-2)


def _pipe_case(drive):
    """A uniform 2000 m drill pipe on a 5 m mesh, torsion only, off bottom, undamped, turning at 10 rad/s."""
    return case_from_dict({
        "name": "pipe",
        "sections": [{"name": "pipe", "length": 2000.0, "outer_diameter": 0.127, "inner_diameter": 0.095,
                      "material": "steel"}],
        "borehole": {"diameter": 0.3},
        "bit_rock": {"law": "off_bottom"},
        "fluid": {"density": 0.0, "inlet_velocity": 0.0},
        "damping": {"modal_damping_ratio": 0.0, "rigid_axial": 0.0, "rigid_rotation": 0.0},
        "operation": {"top_speed": 10.0},
        "model": {"gravity": False},
        "mesh": {"max_element_length": 5.0, "probes": [0.0]},
        "reduced_model": {"axial_modes": 0, "torsional_modes": 40, "lateral_modes": 0, "lateral_cutoff": 0.0},
        "top_drive": drive,
    })


def test_reflection_of_a_torsional_pulse_at_the_top_drive():
    """A Gaussian torsional pulse travels up the pipe; at x_m the up- and down-going waves are separated
    (``up = (θ̇ + T/Z_p)/2``, ``down = (θ̇ − T/Z_p)/2``, ``T = G I_p θ'``); the down-going wave is the up-going
    one reflected at the top: ``DOWN(ω) = r(iω) e^{−2iωx_m/c} UP(ω)`` with the closed form
    ``r = (Z_p − Z_td)/(Z_p + Z_td)``, ``Z_td = iωJ + k_p + k_i/(iω)``."""
    drive = {"controller": "pi", "inertia": 5.0, "proportional_gain": 300.0, "integral_gain": 2000.0}
    case = _pipe_case(drive)
    model = case_reduced_model(case)
    mesh = model.static.mesh
    g, rho = _material(case)
    c = math.sqrt(g / rho)
    section = case.sections[0]
    polar = math.pi * (section.outer_diameter**4 - section.inner_diameter**4) / 32
    z_p = polar * math.sqrt(g * rho)
    # initial state: steady rotation at Ω plus an up-going pulse θ = F(x + ct) centred at x0
    x = mesh.nodes
    x0, width, amplitude = 1300.0, 100.0, 1e-3
    theta = amplitude * np.exp(-0.5 * ((x - x0) / width) ** 2)
    theta_rate = c * np.gradient(theta, x)  # θ̇ = c θ' for an up-going wave
    q, qd = np.zeros(mesh.n_dofs), np.zeros(mesh.n_dofs)
    q[dof(np.arange(mesh.n_nodes), THETA_X)] = theta
    qd[dof(np.arange(mesh.n_nodes), THETA_X)] = theta_rate
    mass = model.system.mass + top_inertia_matrix(mesh, drive["inertia"])
    n = model.size
    y0 = model.initial_state(0.0, 0)
    y0[:n] += model.basis.T @ (mass @ q)
    y0[n:2 * n] += model.basis.T @ (mass @ qd)
    m = mesh.node_index(600.0)
    x_m = mesh.nodes[m]
    h = mesh.nodes[m + 1] - mesh.nodes[m - 1]
    rows = model.basis[dof(np.array([m - 1, m, m + 1]), THETA_X)]

    def observe(t, y):
        angle = rows @ y[:n]
        return np.array([rows[1] @ y[n:2 * n] - case.operation.top_speed, g * polar * (angle[2] - angle[0]) / h])

    dt = 1e-3
    run = integrate(model.rhs, (0.0, 2.0), y0, output_step=dt, rtol=1e-9, atol=1e-12, observe=observe)
    speed, torque = np.asarray(run.y).T
    up, down = 0.5 * (speed + torque / z_p), 0.5 * (speed - torque / z_p)
    assert np.abs(up).max() > 0.5 * amplitude * c / width  # the pulse went past x_m
    size = 8 * len(up)
    omega = 2 * math.pi * np.fft.rfftfreq(size, dt)
    params = TopDriveParameters("pi", 10.0, inertia=5.0, proportional_gain=300.0, integral_gain=2000.0,
                                max_torque=1e9)
    r = np.empty(len(omega), dtype=complex)
    r[0] = -1.0  # integral action: the top holds its mean speed
    r[1:] = reflection_coefficient(omega[1:], params, z_p)
    predicted = np.fft.irfft(r * np.exp(-2j * omega * x_m / c) * np.fft.rfft(up, size), size)[:len(up)]
    error = np.linalg.norm(down - predicted) / np.linalg.norm(down)
    assert error < 0.02
    # the closed form matters: an imposed speed's r = -1 does not describe the measured reflection
    held = np.fft.irfft(-np.exp(-2j * omega * x_m / c) * np.fft.rfft(up, size), size)[:len(up)]
    assert np.linalg.norm(down - held) / np.linalg.norm(down) > 0.3


# --- the component's pieces --------------------------------------------------------------------------------

_CONTROLLERS = [
    TopDriveParameters("pi", 10.0, inertia=800.0, proportional_gain=2e3, integral_gain=5e3, max_torque=4e4,
                       ramp_time=5.0),
    TopDriveParameters("soft_torque", 10.0, inertia=800.0, proportional_gain=443.0, integral_gain=1.7e3,
                       max_torque=4e4, pipe_impedance=443.0, stick_slip_frequency=1.45),
    TopDriveParameters("z_torque", 10.0, inertia=800.0, proportional_gain=4430.0, integral_gain=6e3,
                       max_torque=4e4, pipe_impedance=443.0, filter_frequency=0.29),
]


def _controller_by_hand(params, t, quill_speed, surface_torque, integral, filtered):
    """Eq. (1) of :mod:`drillstring.forces.top_drive` and the z_torque feedback written out, independently of
    the compiled law: ``(τ_m, ż, ẋ)``."""
    reference = params.set_point * (min(t / params.ramp_time, 1.0) if params.ramp_time > 0 else 1.0)
    d_filtered = 0.0
    if params.controller == "z_torque":
        reference -= (surface_torque - filtered) / params.pipe_impedance
        d_filtered = params.filter_frequency * (surface_torque - filtered)
    error = reference - quill_speed
    raw = params.proportional_gain * error + params.integral_gain * integral
    torque = float(np.clip(raw, -params.max_torque, params.max_torque))
    saturated = torque != raw and np.sign(error) == np.sign(raw)  # conditional integration
    return torque, 0.0 if saturated else error, d_filtered


@pytest.mark.parametrize("params", _CONTROLLERS, ids=lambda p: p.controller)
def test_compiled_law_is_the_controller_as_written_and_its_jacobian(params):
    """The compiled law (which the kernel and ``evaluate_at`` both call) against eq. (1) written out by hand,
    through the ramp, both saturations and the z_torque feedback; its Jacobian against central differences."""
    rng = np.random.default_rng(3)
    saturated = 0
    windup = 2.0 * params.max_torque / params.integral_gain  # an integral state beyond either saturation
    points = [rng.uniform([0, 0, -1e4, -20, -1e4], [10, 20, 2e4, 20, 2e4]) for _ in range(50)]
    points += [(6.0, 9.0, 1e3, windup, 0.0), (6.0, 11.0, 1e3, -windup, 0.0), (6.0, 11.0, 1e3, windup, 0.0)]
    for t, speed, torque, integral, filtered in points:
        compiled = top_drive_law(params.kernel_args(), t, speed, torque, integral, filtered)
        expected = _controller_by_hand(params, t, speed, torque, integral, filtered)
        np.testing.assert_allclose(compiled, expected, rtol=1e-13, atol=1e-9)
        saturated += abs(compiled[0]) == params.max_torque
        assert abs(compiled[0]) <= params.max_torque
    assert 3 <= saturated < len(points)
    # the Jacobian against central differences, unsaturated, after the ramp
    point = np.array([9.5, 5e3, 1.0, 4.9e3])
    jac = top_drive_jacobian(params)
    m = params.n_states
    np.testing.assert_array_equal(params.jacobian(), jac[:1 + m, :2 + m])  # the states it owns only
    assert not jac[1 + m:].any() and not jac[:, 2 + m:].any()
    # the component's kernel (named context, its own states at an offset) against its NumPy reference
    for t, speed, torque, integral, filtered in ((2.0, 8.0, 3e3, 1.0, 2e3), (9.0, 12.0, -1e3, -4.0, 5e2)):
        states = np.array([7.0, integral, filtered, 7.0])
        rates = np.full(4, -1.0)
        ctx = TopContext(t, speed, torque)
        motor = top_drive_kernel(params.kernel_array(), ctx, states[1:], rates[1:])
        expected, expected_rates = params.evaluate_at(ctx, states[1:1 + m])
        assert motor == pytest.approx(expected, rel=1e-14)
        np.testing.assert_allclose(rates[1:1 + m], expected_rates, rtol=1e-14)
        assert rates[0] == -1.0 and (rates[1 + m:] == -1.0).all()  # nothing outside its own states
    for k in range(4):
        step = np.zeros(4)
        step[k] = 1e-4 * max(1.0, abs(point[k]))
        plus = top_drive_law(params.kernel_args(), 20.0, *(point + step))
        minus = top_drive_law(params.kernel_args(), 20.0, *(point - step))
        assert np.allclose((np.array(plus) - np.array(minus)) / (2 * step[k]), jac[:, k], rtol=1e-7, atol=1e-9)


def test_saturation_stops_the_integral_in_the_saturating_direction():
    params = _CONTROLLERS[0]
    torque, d_integral, _ = top_drive_law(params.kernel_args(), 10.0, 0.0, 0.0, 100.0, 0.0)
    assert torque == params.max_torque and d_integral == 0.0
    torque, d_integral, _ = top_drive_law(params.kernel_args(), 10.0, 30.0, 0.0, 100.0, 0.0)
    assert d_integral == pytest.approx(10.0 - 30.0)  # unwinding is allowed


def test_soft_torque_absorbs_waves_at_the_stick_slip_frequency():
    z_p, j, w_s = 443.0, 1000.0, 1.45
    k_p, k_i = soft_torque_gains(j, z_p, w_s)
    params = TopDriveParameters("soft_torque", 10.0, inertia=j, proportional_gain=k_p, integral_gain=k_i,
                                max_torque=1e5, pipe_impedance=z_p)
    assert abs(reflection_coefficient(w_s, params, z_p)) < 1e-12
    assert abs(reflection_coefficient(3 * w_s, params, z_p)) > 0.5
    stiff = TopDriveParameters("pi", 10.0, inertia=j, proportional_gain=1e7, integral_gain=1e8, max_torque=1e5)
    assert reflection_coefficient(w_s, stiff, z_p) == pytest.approx(-1.0, abs=1e-3)


@pytest.mark.parametrize("controller", ["pi", "soft_torque", "z_torque"])
def test_compiled_rhs_matches_the_numpy_reference_and_steady_drilling_is_an_equilibrium(torsional_case,
                                                                                         controller):
    drive = {"controller": controller}
    if controller == "pi":
        drive.update(proportional_gain=5e3, integral_gain=2e4)
    model = case_reduced_model(_with(torsional_case, top_drive=drive))
    steady = steady_drilling(model)
    y = steady.state
    assert y.shape == (model.state_size,)
    rate = model.rhs(3.0, y)
    n = model.size
    assert np.allclose(model.rhs_reference(3.0, y), rate, rtol=1e-12, atol=1e-9)
    # every derivative vanishes but the rigid positions' (the depth drilled, the angle turned)
    moving = np.zeros(model.state_size, dtype=bool)
    moving[[int(model.blocks[0]), model.rigid_rotation_column]] = True
    scale = np.abs(model.omega2) @ np.abs(y[:n]) / n + 1.0
    assert np.abs(rate[~moving]).max() < 1e-9 * scale
    assert rate[model.rigid_rotation_column] * model.quill_shapes[model.rigid_rotation_column] == \
        pytest.approx(torsional_case.operation.top_speed, rel=1e-12)
    # the linearisation against central differences of the compiled right-hand side
    a = linearized_matrix(model, steady)
    rng = np.random.default_rng(0)
    direction = rng.standard_normal(model.state_size) * np.maximum(np.abs(y), 1e-3)
    eps = 1e-6
    numeric = (model.rhs(3.0, y + eps * direction) - model.rhs(3.0, y - eps * direction)) / (2 * eps)
    assert np.allclose(numeric, a @ direction, rtol=1e-5, atol=1e-6 * np.abs(a @ direction).max())


def test_off_bottom_has_no_bit_force_and_rotates_without_penetration(torsional_case):
    case = _with(torsional_case, bit_rock={"law": "off_bottom"})
    model = case_reduced_model(case)
    assert model.weight_on_bit == 0.0
    steady = steady_drilling(model)
    assert steady.rate_of_penetration == 0.0 and steady.torque_on_bit == 0.0
    run = simulate_model(model, t_end=5.0, output_step=0.05, lateral_perturbation=0.0)
    assert np.all(run.observables["torque_on_bit"] == 0.0) and np.all(run.observables["force_on_bit"] == 0.0)
    # nothing drives the torsion but the rigid-rotation friction c2 Ω (0.5 N·m): the bit turns at the top speed
    assert np.allclose(run.observables["bit_speed"], case.operation.top_speed, rtol=1e-4)
    assert np.abs(run.observables["surface_torque"]).max() < 2.0


def test_tuned_gains_are_reported_and_the_family_sizes_agree(reference_case):
    case = _with(reference_case, top_drive={"controller": "soft_torque"},
                 reduced_model={"axial_modes": 1, "torsional_modes": 3, "lateral_modes": 0, "lateral_cutoff": 0.0})
    model = case_reduced_model(case)
    described = model.top_drive.describe()
    assert described["tuned"] == ["integral_gain", "proportional_gain"]
    assert described["proportional_gain"] == pytest.approx(443.45, rel=1e-4)  # Z_p of the reference pipe
    # ω_s: the first torsional frequency with the top held (0.2313 Hz, SPEC §10, within the fluid's effect)
    assert described["stick_slip_frequency"] / (2 * math.pi) == pytest.approx(0.2313, rel=5e-3)
    assert described["integral_gain"] == pytest.approx(1000.0 * described["stick_slip_frequency"] ** 2)
    mesh = model.static.mesh
    for top_free in (False, True):
        sizes = mode_family_sizes(mesh.n_nodes, top_free)
        assert len(family_dofs(mesh, "torsional", top_free)) == sizes["torsional"]
    # the free torsional family: the rigid rotation first, then the elastic modes
    t0 = model.rigid_rotation_column
    assert model.angular_frequencies[t0] == 0.0 and np.all(model.angular_frequencies[t0 + 1:t0 + 4] > 0)


def test_controller_parameters_vary_like_any_numeric_case_field(reference_case):
    from drillstring.case import load_case
    from drillstring.stochastic.parameters import ParameterError, parameter_value, with_parameters

    stick = load_case("stick_slip")
    assert parameter_value(stick, "top_drive.proportional_gain") == 3e4
    varied = with_parameters(stick, {"top_drive.proportional_gain": 5e3,
                                     "top_drive.inertia": "800 kg*m2"})
    assert varied.top_drive.proportional_gain == 5e3 and varied.top_drive.inertia == 800.0
    with pytest.raises(ParameterError, match=r"top_drive.proportional_gain is not set"):
        parameter_value(reference_case, "top_drive.proportional_gain")


def test_cli_stability_reports_the_closed_loop_and_the_tuned_gains(tmp_path):
    """``drillstring stability`` on a case file with a soft_torque top drive: the gains it tuned, in the table
    and the JSON."""
    import json

    from typer.testing import CliRunner

    from drillstring.case import load_case
    from drillstring.cli import app

    case = load_case("stick_slip")
    case = _with(case, top_drive={"controller": "soft_torque", "proportional_gain": None, "integral_gain": None},
                 mesh={"max_element_length": 100.0},
                 reduced_model={"axial_modes": 2, "torsional_modes": 3, "lateral_modes": 0})
    path = tmp_path / "soft.toml"
    path.write_text(case.to_toml())
    runner = CliRunner()
    table = runner.invoke(app, ["stability", str(path)], env={"COLUMNS": "200", "FORCE_COLOR": None})
    assert table.exit_code == 0, table.stdout
    assert "top drive: soft_torque" in table.stdout and "proportional gain (tuned)" in table.stdout
    result = runner.invoke(app, ["stability", str(path), "--json"])
    payload = json.loads(result.stdout)
    assert payload["top_drive"]["controller"] == "soft_torque"
    assert payload["top_drive"]["tuned"] == ["integral_gain", "proportional_gain"]
    assert payload["top_drive"]["proportional_gain"] == pytest.approx(payload["top_drive"]["pipe_impedance"])
