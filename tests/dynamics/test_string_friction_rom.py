"""The along-string friction in the reduced model (drillstring.forces.string_friction through
drillstring.dynamics.reduced): the compiled right-hand side against the NumPy reference, the rigid-body torque
balance of a string rotating steadily (the soft-string rotating-off-bottom torque sum mu N r), the friction's
power, the vertical limit (no normal force: bit-identical outputs) and a deviated case built on its well's
statics."""

import dataclasses

import numpy as np
import pytest

from drillstring.case import StringFriction, load_case
from drillstring.dynamics.reduced.build import case_friction_stations
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
from drillstring.dynamics.stability import linearized_matrix, steady_drilling
from drillstring.fem.dofs import THETA_X, U, dof
from drillstring.forces.registry import StringFrictionContext
from drillstring.forces.string_friction import CoulombStringFriction, FrictionStations
from drillstring.well.stiff_string import case_stiff_string
from drillstring.well.torque_drag import case_torque_drag

COULOMB = StringFriction.model_validate({"law": "coulomb"})


def _coarse_reference(**damping):
    """The reference case off bottom on a coarse mesh, every torsional mode kept (the static twist exact)."""
    case = load_case("reference")
    case = case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 150.0}),
        "bit_rock": case.bit_rock.model_copy(update={"law": "off_bottom"}),
        "damping": case.damping.model_copy(update=damping),
        "reduced_model": case.reduced_model.model_copy(update={"lateral_cutoff": 0.0, "lateral_modes": 4,
                                                               "axial_modes": 4, "torsional_modes": 1})})
    n_nodes = case_reduced_model(case, lateral_modes=0, axial_modes=0).static.mesh.n_nodes
    return case, n_nodes


@pytest.fixture(scope="module")
def coarse():
    case, n_nodes = _coarse_reference(rigid_rotation=0.0)
    model = case_reduced_model(case, torsional_modes=n_nodes - 1)
    nodes = np.array([2, 5, 7, n_nodes - 2], dtype=np.int64)
    stations = FrictionStations(nodes, np.array([3e3, 1.5e3, 8e3, 2e3]), np.array([0.08, 0.08, 0.1, 0.12]),
                                np.array([0.2, 0.3, 0.3, 0.25]))
    law = CoulombStringFriction(0.01)
    return model, dataclasses.replace(model, string_friction=law, friction_stations=stations)


def _random_state(model, seed=0):
    rng = np.random.default_rng(seed)
    y = model.initial_state(1e-4, 0)
    n = model.size
    y[:n] += 1e-3 * rng.standard_normal(n)
    y[n:2 * n] += 0.3 * rng.standard_normal(n)
    return y


def test_compiled_right_hand_side_matches_the_reference(coarse):
    _, model = coarse
    y = _random_state(model)
    a, b = model.rhs(0.3, y), model.rhs_reference(0.3, y)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())


def _nodal(model, y):
    """The friction's nodal forces and torques from the law's formula written here, and the stations' velocities."""
    n = model.size
    eta_dot = y[n:2 * n]
    fs = model.friction_stations
    phi = model.basis
    u_dot = phi[dof(fs.node, U)] @ eta_dot
    spin = model.base_speed + phi[dof(fs.node, THETA_X)] @ eta_dot
    s = np.sqrt(u_dot**2 + (fs.radius * spin) ** 2 + 0.01**2)
    force = -fs.friction * fs.normal_force * u_dot / s
    torque = -fs.friction * fs.normal_force * fs.radius**2 * spin / s
    return force, torque, u_dot, spin


def test_friction_generalised_force_is_the_projection_written_here(coarse):
    """Φᵀ of the nodal forces, computed here from the basis and the law's formula (mass-normalised modes: the
    acceleration difference is the generalised force)."""
    plain, model = coarse
    n = model.size
    fs = model.friction_stations
    phi = model.basis
    for seed in range(1, 8):
        y = _random_state(model, seed)
        force, torque, u_dot, spin = _nodal(model, y)
        expected = phi[dof(fs.node, U)].T @ force + phi[dof(fs.node, THETA_X)].T @ torque
        difference = model.rhs(0.2, y)[n:2 * n] - plain.rhs(0.2, y)[n:2 * n]
        np.testing.assert_allclose(difference, expected, rtol=1e-10, atol=1e-10 * np.abs(expected).max())
        # its power is never positive: the modal power is relative to the frame turning at Ω (the top's speed),
        # the friction's own adds Ω Σ τ_i
        power = force @ u_dot + torque @ spin
        assert power < 0.0
        assert difference @ y[n:2 * n] + model.base_speed * torque.sum() == pytest.approx(power, rel=1e-9)


def test_steady_rotation_takes_the_soft_string_torque(coarse):
    """A string turning steadily at the top speed Ω with the wall pressing it: the surface torque is Σ μ N r
    (times Ω r / sqrt((Ω r)² + v_reg²), the regularisation), the twist the static one under the friction
    torques; the right-hand side is at rest there and a run stays there."""
    _, model = coarse
    assert np.max(np.abs(model.generalized_force)) < 1e-9  # no damping of the imposed rotation (c2 = 0): rounding
    fs = model.friction_stations
    omega = model.top_speed
    slide = fs.radius * omega
    torque = -fs.friction * fs.normal_force * fs.radius * slide / np.sqrt(slide**2 + 0.01**2)
    n = model.size
    t0, t1 = model.blocks[2], model.blocks[3]
    y = np.zeros(model.state_size)
    generalised = model.phi_tx[fs.node, t0:t1].T @ torque
    y[t0:t1] = (generalised + model.generalized_force[t0:t1]) / model.omega2[t0:t1]
    assert np.max(np.abs(model.rhs(0.0, y)[n:2 * n])) < 1e-9 * np.max(np.abs(generalised))
    observed = model.observe(0.0, y)[model.observable_names.index("surface_torque")]
    assert observed == pytest.approx(-torque.sum(), rel=1e-9)
    assert -torque.sum() == pytest.approx(fs.rotating_torque(), rel=1e-4)  # v_reg / (r Ω) ~ 1e-2
    # the run's own start is that twist (the friction not switched on at t = 0), and it stays there
    start = model.initial_state(0.0, 0)
    np.testing.assert_allclose(start[:n], y[:n], rtol=0.0, atol=1e-9 * np.abs(y).max())  # y holds g: 3e-11 rounding
    assert not np.any(start[n:])
    result = simulate_model(model, t_end=1.0, output_step=0.1, lateral_perturbation=0.0)
    np.testing.assert_allclose(result.observables["surface_torque"], -torque.sum(), rtol=1e-6)


def test_vertical_limit_no_normal_force_is_bit_identical():
    """The friction law named in a case without [well]: no station, code 0, the same outputs bit for bit."""
    case, _ = _coarse_reference()
    plain = case_reduced_model(case)
    with_law = case_reduced_model(case.model_copy(update={"string_friction": COULOMB}))
    assert len(with_law.friction_stations) == 0 and with_law.active_friction is None
    y = _random_state(plain)
    assert np.array_equal(plain.rhs(0.1, y), with_law.rhs(0.1, y))
    a = simulate_model(plain, t_end=0.5, output_step=0.05)
    b = simulate_model(with_law, t_end=0.5, output_step=0.05)
    for name in a.observables:
        assert np.array_equal(a.observables[name], b.observables[name]), name


def test_deviated_case_builds_on_its_well_statics():
    """The deviated case (a coarse mesh): the prestress is the stiff string's axial force along measured depth,
    the friction acts at its nodes on the wall, and Σ μ N r is the soft string's rotating torque within the
    stiff string's difference (bending, its normal forces at the nodes: below 1 % on the case's mesh)."""
    case = load_case("deviated")
    case = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": 60.0}),
                                   "bit_rock": case.bit_rock.model_copy(update={"law": "off_bottom"})})
    model = case_reduced_model(case, axial_modes=2, torsional_modes=4, lateral_modes=2)
    state = case_stiff_string(case)
    np.testing.assert_array_equal(model.static.axial_force, state.axial_force)
    assert model.weight_on_bit == 0.0
    fs = model.friction_stations
    np.testing.assert_array_equal(fs.node, np.nonzero(state.in_contact)[0])
    np.testing.assert_array_equal(fs.normal_force, state.side_force[fs.node])
    shoe = case.well.casing_shoe
    np.testing.assert_array_equal(fs.friction, np.where(state.mesh.nodes[fs.node] < shoe, 0.2, 0.3))
    # on the case's own 10 m mesh (the 60 m one's stiff string presses harder: 19.3 against 18.1 kN·m)
    fine = load_case("deviated")
    fine = fine.model_copy(update={"bit_rock": fine.bit_rock.model_copy(update={"law": "off_bottom"})})
    stations = case_friction_stations(fine, case_stiff_string(fine))
    soft = case_torque_drag(fine)["rotating_off_bottom"].torque[0]
    assert stations.rotating_torque() == pytest.approx(soft, rel=0.01)
    # the vertical statics differs: the well's is not the vertical one
    vertical = case_reduced_model(case.model_copy(update={"well": None}), axial_modes=2, torsional_modes=4,
                                  lateral_modes=2)
    assert len(vertical.friction_stations) == 0
    assert abs(vertical.static.weight_on_hook - model.static.weight_on_hook) > 1e4


def test_projected_jacobian_of_the_compiled_friction(coarse):
    """∂(η̈)/∂(η̇) of the compiled right-hand side's friction part (central differences, with the model without
    friction subtracted) is the law's closed-form Jacobian projected here, ``Σ Φ_aᵀ J_ab Φ_b`` over (u, θx), with
    a static factor and a Stribeck decay as well."""
    plain, model = coarse
    model = dataclasses.replace(model, string_friction=CoulombStringFriction(0.01, 1.5, 0.1))
    n = model.size
    y = _random_state(model, 11)
    y[n:2 * n] *= 0.1
    fs = model.friction_stations
    phi_u, phi_t = model.basis[dof(fs.node, U)], model.basis[dof(fs.node, THETA_X)]
    jac = model.string_friction.jacobian_at(StringFrictionContext(
        phi_u @ y[n:2 * n], model.base_speed + phi_t @ y[n:2 * n], fs.normal_force, fs.radius, fs.friction))
    rows = (phi_u, phi_t)
    expected = sum(rows[a].T @ (jac[:, a, b][:, None] * rows[b]) for a in range(2) for b in range(2))
    numeric = np.empty((n, n))
    for k in range(n):
        step = 1e-7
        up, down = y.copy(), y.copy()
        up[n + k] += step
        down[n + k] -= step
        numeric[:, k] = ((model.rhs(0.0, up) - plain.rhs(0.0, up)) - (model.rhs(0.0, down) - plain.rhs(0.0, down))
                         )[n:2 * n] / (2 * step)
    # the differences' rounding: a few ulps of the accelerations over the step
    rounding = 8 * np.finfo(float).eps * np.abs(model.rhs(0.0, y)[n:2 * n]).max() / 1e-7
    np.testing.assert_allclose(numeric, expected, rtol=1e-5, atol=rounding)
    assert rounding < 1e-2 * np.abs(expected).max()


@pytest.mark.parametrize("law", ["off_bottom", "tucker_wang"])
def test_stability_analysis_includes_the_friction(law):
    """The stability analysis's steady state is an equilibrium of the right-hand side with the friction (off
    bottom exactly; drilling to the friction's nonlinearity in the rate of penetration, (V/rΩ)² ~ 1e-5), and its
    state matrix is the central differences of the compiled right-hand side there (a deviated case, coarse mesh,
    a Stribeck factor to make the friction's Jacobian matter)."""
    case = load_case("deviated")
    case = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": 60.0}),
                                   "bit_rock": case.bit_rock.model_copy(update={"law": law})})
    model = case_reduced_model(case, axial_modes=2, torsional_modes=4, lateral_modes=2)
    model = dataclasses.replace(model, string_friction=CoulombStringFriction(0.01, 1.5, 0.5))
    n = model.size
    after = 1e3  # [s]: after the case's start (its hook-load ramp), the steady state's regime
    steady = steady_drilling(model)
    y = np.asarray(steady.state, dtype=float)
    load = np.abs(model.friction_load(y[n:2 * n])).max()
    residual = np.abs(model.rhs(after, y)[n:2 * n]).max()
    assert residual < (1e-9 if law == "off_bottom" else 1e-4) * load
    a = linearized_matrix(model, steady)
    numeric = np.empty_like(a)
    for k in range(y.size):
        step = 1e-6 * max(abs(y[k]), 1.0)  # the differences' rounding ~ eps |ω² η| / step stays below 1e-7
        up, down = y.copy(), y.copy()
        up[k] += step
        down[k] -= step
        numeric[:, k] = (model.rhs(after, up) - model.rhs(after, down)) / (2 * step)
    scale = np.abs(a[n:2 * n]).max()
    np.testing.assert_allclose(numeric[n:2 * n], a[n:2 * n], rtol=1e-5, atol=1e-7 * scale)
    # and the friction is in it: its Jacobian is not negligible there
    assert np.abs(model.friction_jacobian(y[n:2 * n])).max() > 1e-4 * scale
