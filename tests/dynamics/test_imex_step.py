"""The implicit–explicit step (drillstring.dynamics.steps.imex_ark): order of convergence on problems with
known solutions (its NumPy reference, a partial Jacobian so that both parts of the pair act), a stiff linear
problem whose stiff mode the explicit method cannot step over, the compiled stiff part against the bit law's
closed-form partials, and the compiled step against DOPRI5 on the reduced model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from drillstring.dynamics.additive_rk import ARK3_2_4L, ARK4_3_6L
from drillstring.dynamics.rom import case_reduced_model, stiff_part
from drillstring.dynamics.runge_kutta import DORMAND_PRINCE_54, RungeKuttaStepper, integrate, method_named
from drillstring.dynamics.simulate import simulate_model


class SplitProblem:
    """``rhs(t, y)`` with the part of its Jacobian the IMEX step takes implicitly (``stiff_jacobian``)."""

    def __init__(self, rhs, jacobian):
        self.rhs, self.stiff_jacobian, self.calls = rhs, jacobian, 0

    def __call__(self, t, y):
        self.calls += 1
        return self.rhs(t, y)


STIFF = -1e4  # [1/s]


def stiff_linear() -> tuple[SplitProblem, np.ndarray, callable]:
    """A stiff mode slaved to a slow oscillator, with a nonlinear slow part: y1' = λ (y1 − c) − s, c' = −s,
    s' = c, q' = y1² (exact: y1 = c = cos t, s = sin t, q = t/2 + sin 2t / 4), λ = STIFF; the linear part is
    taken implicitly (as the reduced model's modal part), the square explicitly."""
    linear = np.array([[STIFF, -STIFF, -1.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0] * 4])
    problem = SplitProblem(lambda t, y: linear @ y + np.array([0.0, 0.0, 0.0, y[0] ** 2]),
                           lambda t, y: linear)
    return problem, np.array([1.0, 1.0, 0.0, 0.0]), \
        lambda t: np.array([math.cos(t), math.cos(t), math.sin(t), t / 2 + math.sin(2 * t) / 4])


def fixed_steps(problem, y0, tableau, h: float, t_end: float) -> np.ndarray:
    stepper = RungeKuttaStepper(problem, 0.0, y0, tableau, None, h, t_bound=t_end)
    with np.errstate(all="ignore"):
        while not stepper.finished:
            stepper.step()
            if not np.all(np.isfinite(stepper.y)) or np.abs(stepper.y).max() > 1e12:
                return np.full_like(stepper.y, np.inf)
    return stepper.y


@pytest.mark.parametrize("tab", [ARK3_2_4L, ARK4_3_6L], ids=lambda t: t.name)
def test_order_of_convergence_with_both_parts_active(tab):
    """Fixed steps on y' = 1 + y² (exact tan t) with the exact Jacobian 2y taken implicitly and the rest
    explicit, and on the oscillator y'' = −y − 0.5 y' with only the damping implicit: the global error falls
    as h^order (the coupling conditions hold, else the observed order would drop)."""
    tangent = SplitProblem(lambda t, y: 1.0 + y * y, lambda t, y: np.array([[2.0 * y[0]]]))
    damped = SplitProblem(lambda t, y: np.array([y[1], -y[0] - 0.5 * y[1]]),
                          lambda t, y: np.array([[0.0, 0.0], [0.0, -0.5]]))
    omega = math.sqrt(1.0 - 0.0625)
    exact_damped = np.exp(-0.25 * 2.0) * np.array(
        [math.cos(omega * 2.0) + 0.25 / omega * math.sin(omega * 2.0),
         -(1.0 / omega) * math.sin(omega * 2.0)])
    for problem, y0, t_end, exact in ((tangent, np.array([0.0]), 1.2, np.array([math.tan(1.2)])),
                                      (damped, np.array([1.0, 0.0]), 2.0, exact_damped)):
        errors = [np.abs(fixed_steps(problem, y0, tab, t_end / m, t_end) - exact).max() for m in (40, 80)]
        observed = math.log2(errors[0] / errors[1])
        assert observed == pytest.approx(tab.order, abs=0.35), (problem, errors)


def test_stiff_mode_the_explicit_method_cannot_step_over():
    """On a stiff linear mode slaved to a slow one (λ = −1e4) fixed steps of 0.01 s (hλ = −100) blow DOPRI5 up, while
    both IMEX pairs stay on the solution; adaptively, DOPRI5's steps are bounded by its stability
    (|hλ| ≲ 3.3: thousands of steps over 1 s) and the IMEX pair's by accuracy (tens)."""
    problem, y0, exact = stiff_linear()
    assert not np.all(np.isfinite(fixed_steps(problem, y0, DORMAND_PRINCE_54, 0.01, 1.0)))
    for tab in (ARK3_2_4L, ARK4_3_6L):
        assert np.abs(fixed_steps(problem, y0, tab, 0.01, 1.0) - exact(1.0)).max() < 1e-5
    explicit = integrate(problem, (0.0, 1.0), y0, tableau="dopri5", rtol=1e-6, atol=1e-9, t_out=[1.0])
    implicit = integrate(problem, (0.0, 1.0), y0, tableau="ark43", rtol=1e-6, atol=1e-9, t_out=[1.0])
    assert explicit.stats["n_accepted"] > 2500
    assert implicit.stats["n_accepted"] < 60
    assert np.abs(implicit.y[-1] - exact(1.0)).max() < 1e-5


def test_methods_by_name():
    assert method_named("ark43") is ARK4_3_6L and method_named("ark32") is ARK3_2_4L
    with pytest.raises(ValueError, match="unknown tableau 'ark5'.*ark43"):
        method_named("ark5")


@njit(cache=True)
def _stiff_part(data, t, y, shapes, partials):
    return stiff_part(data, t, y, shapes, partials, np.empty(y.shape[0]))


def test_compiled_stiff_part_is_the_laws_closed_form_jacobian(small_case):
    """The compiled stiff part (the Tucker–Wang law's compiled Jacobian) equals the law's closed-form partials
    in u̇ and θ̇ (``jacobian_at``, the same function called from Python) at a drilling state, and carries them
    along the bit's own shapes; the law reads no position (last column 0); it returns the model's ω² and
    damping."""
    from drillstring.forces.registry import bit_context

    model = case_reduced_model(small_case)
    n = model.size
    y = model.initial_state(0.0, 0)
    y[n:2 * n] += 1e-3 * model.bit_u / (model.bit_u @ model.bit_u)  # drilling at 1 mm/s
    shapes, partials = np.zeros((2, len(y))), np.zeros((2, 3))
    omega2, damping_t, blocks = _stiff_part(model.rhs_data, 0.0, y, shapes, partials)
    np.testing.assert_array_equal(omega2, model.omega2)
    np.testing.assert_array_equal(damping_t, model.damping.T)
    np.testing.assert_array_equal(shapes[0, :n], model.bit_u)
    np.testing.assert_array_equal(shapes[1, :n], model.bit_t)
    position, angle = model.bit_position(0.0, y)
    ctx = bit_context(model.bit_u @ y[n:2 * n], model.base_speed + model.bit_t @ y[n:2 * n], 0.0, time=0.0,
                      position=position, angle=angle, weight_on_bit=model.weight_on_bit)
    closed = np.asarray(model.bit_rock.jacobian_at(ctx), dtype=float)
    np.testing.assert_allclose(partials[:, :2], closed, rtol=1e-12, atol=0.0)
    assert np.all(closed != 0.0)
    np.testing.assert_array_equal(partials[:, 2], 0.0)


def test_compiled_stiff_part_of_a_delayed_law_moves_the_depth_of_cut_with_the_position(torsional_case):
    """The Detournay law (delayed): the stiff part's partials in u̇ and θ̇ are ``jacobian_at`` and its position
    column the depth partials ``depth_partials`` (the depth of cut ``u − u(θ − 2π/n)`` moves with the position
    at a fixed angle), at the context the stiffness diagnosis builds from the model's history."""
    from drillstring.dynamics.stiffness import _bit_context_at

    case = torsional_case.model_copy(update={
        "bit_rock": torsional_case.bit_rock.model_copy(update={"law": "detournay"}),
        "initial": torsional_case.initial.model_copy(update={"start": "on_bottom"})})
    model = case_reduced_model(case)
    n = model.size
    y = model.initial_state(0.0, 0)
    y[n:2 * n] += 1e-4 * model.bit_u / (model.bit_u @ model.bit_u)  # advancing below v_r: f_u ≠ 0
    y[:n] += 1e-3 * model.bit_u / (model.bit_u @ model.bit_u)  # 1 mm below the model's (flat) prehistory
    shapes, partials = np.zeros((2, len(y))), np.zeros((2, 3))
    _stiff_part(model.rhs_data, 0.0, y, shapes, partials)
    ctx = _bit_context_at(model, 0.0, y)
    assert ctx.depth_of_cut > 0.0
    law = model.bit_rock
    np.testing.assert_allclose(partials[:, :2], law.jacobian_at(ctx), rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(partials[:, 2], law.depth_partials(ctx), rtol=1e-12, atol=0.0)
    assert partials[0, 2] == -law.cutting_stiffness and partials[0, 0] < 0.0


def test_compiled_imex_agrees_with_dopri5_on_the_reduced_model(small_case):
    """A drilling run of the small reference string: the compiled IMEX steps (the bit law implicit) and
    DOPRI5 at tight tolerance give the same observables within the tolerance; one Jacobian per accepted
    step (a rejected step reuses its state's)."""
    model = case_reduced_model(small_case)
    kwargs = dict(t_end=1.0, output_step=0.01, rtol=1e-8, atol=1e-11, lateral_perturbation=1e-4, seed=0)
    explicit = simulate_model(model, method="dopri5", **kwargs)
    for name in ("ark43", "ark32"):
        implicit = simulate_model(model, method=name, **kwargs)
        assert implicit.stats["n_jacobians"] == implicit.stats["n_steps"]
        for key in ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit"):
            x, ref = implicit.observables[key], explicit.observables[key]
            assert np.abs(x - ref).max() <= 1e-5 * np.abs(ref).max(), (name, key)


def dense_jacobian(model, data, omega2, damping_t, blocks) -> np.ndarray:
    """The ``J`` the step solves with, dense: the kinematics, −Ω² and the damping (a block whole where the step
    factored it, else its diagonal), and the bit law's rows from the step's shapes and partials."""
    n, size = model.size, model.state_size
    jac = np.zeros((size, size))
    jac[:n, n:2 * n] = np.eye(n)
    jac[n:2 * n, :n] = -np.diag(omega2)
    damping = damping_t.T
    for b, (start, end) in enumerate(blocks):
        part = damping[start:end, start:end]
        jac[n + start:n + end, n + start:n + end] = -(part if data.dense_blocks[b] else np.diag(np.diag(part)))
    shapes = data.shapes[:, :n]
    jac[n:2 * n, n:2 * n] += shapes[:2].T @ data.partials[:2, :2] @ shapes[:2]
    jac[n:2 * n, :n] += shapes[:2].T @ data.partials[:2, 2:3] @ shapes[:1]
    jac[n:2 * n, n:2 * n] += data.partials[2, 0] * np.outer(shapes[2], shapes[2])  # a downhole motor's
    return jac


@pytest.mark.parametrize("h", [1e-4, 1e-2])
def test_stage_solve_is_the_inverse_of_i_minus_h_gamma_j(small_case, h):
    """The step's block LU and Woodbury solve give z with (I − hγJ) z = r for the dense J it stands for (the
    bit law's low-rank part with a made-up position partial, so that all three columns act)."""
    from drillstring.dynamics.steps import imex_ark

    model = case_reduced_model(small_case)
    n = model.size
    y = model.initial_state(0.0, 0)
    y[n:2 * n] += 1e-3 * model.bit_u / (model.bit_u @ model.bit_u)
    data = imex_ark.allocate(ARK4_3_6L, model.state_size)
    omega2, damping_t, blocks = _stiff_part(model.rhs_data, 0.0, y, data.shapes, data.partials)
    data.partials[0, 2] = -1e7  # a cutting stiffness [N/m]
    assert imex_ark._factor(data, h, omega2, damping_t, blocks)
    r = np.random.default_rng(0).standard_normal(model.state_size)
    z = np.zeros_like(r)
    imex_ark._solve(data, h, omega2, blocks, r, z)
    jac = dense_jacobian(model, data, omega2, damping_t, blocks)
    residual = (np.eye(len(r)) - h * ARK4_3_6L.gamma * jac) @ z - r
    assert np.abs(residual).max() < 1e-9 * np.abs(r).max()
    assert data.dense_blocks[:len(blocks)].any() == (h == 1e-2)


def _small_motor_case():
    """The built-in motor case on a 50 m mesh with a small basis (as tests/dynamics/test_motor.py)."""
    from drillstring.case import load_case

    case = load_case("motor")
    return case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={"axial_modes": 3, "torsional_modes": 4,
                                                               "lateral_modes": 2})})


@pytest.fixture(scope="module")
def motor_model():
    return case_reduced_model(_small_motor_case())


def test_stage_solve_with_a_downhole_motor(motor_model):
    """With a downhole motor the stiff part carries its torque slope across the rotor: the rotor's relative
    row (``motor_shapes``) and dT/dω_m equal to the law's closed form −T_s/ω₀; the Woodbury solve with this
    fourth low-rank term still inverts I − hγJ (the motor's term in the dense J), at a short and a long step."""
    from drillstring.dynamics.steps import imex_ark

    model = motor_model
    n = model.size
    y = model.initial_state(0.0, 0)
    data = imex_ark.allocate(ARK4_3_6L, model.state_size)
    omega2, damping_t, blocks = _stiff_part(model.rhs_data, 0.0, y, data.shapes, data.partials)
    np.testing.assert_array_equal(data.shapes[2, :n], model.motor_shapes)
    assert np.abs(model.motor_shapes).max() > 0.0
    slope = model.motor.jacobian()
    assert data.partials[2, 0] == pytest.approx(slope, rel=1e-8) and slope < 0.0
    np.testing.assert_array_equal(data.partials[2, 1:], 0.0)
    rate = slope * (model.motor_shapes @ model.motor_shapes)  # the motor's rate on its own mode [1/s]
    r = np.random.default_rng(1).standard_normal(model.state_size)
    for h in (1e-4, 10.0 / abs(rate)):
        assert imex_ark._factor(data, h, omega2, damping_t, blocks)
        z = np.zeros_like(r)
        imex_ark._solve(data, h, omega2, blocks, r, z)
        jac = dense_jacobian(model, data, omega2, damping_t, blocks)
        residual = (np.eye(len(r)) - h * ARK4_3_6L.gamma * jac) @ z - r
        assert np.abs(residual).max() < 1e-9 * np.abs(r).max(), h
        # without the motor's term the same z is not the solution once hγ|rate| is not small
        partial = data.partials[2, 0]
        data.partials[2, 0] = 0.0
        off = (np.eye(len(r)) - h * ARK4_3_6L.gamma * dense_jacobian(model, data, omega2, damping_t, blocks)) @ z - r
        data.partials[2, 0] = partial
        if h > 1e-3:
            assert np.abs(off).max() > 1e-3 * np.abs(r).max()


def test_compiled_imex_agrees_with_dopri5_with_a_downhole_motor(motor_model):
    """A drilling run of the small motor string: ARK4(3)6L (the motor's slope implicit) and DOPRI5 at tight
    tolerance give the same bit speed, motor speed and torque within the tolerance."""
    kwargs = dict(t_end=0.5, output_step=0.01, rtol=1e-8, atol=1e-11, lateral_perturbation=1e-4, seed=0)
    explicit = simulate_model(motor_model, method="dopri5", **kwargs)
    implicit = simulate_model(motor_model, method="ark43", **kwargs)
    for key in ("bit_speed", "motor_speed", "motor_torque", "torque_on_bit", "rate_of_penetration"):
        x, ref = implicit.observables[key], explicit.observables[key]
        assert np.abs(x - ref).max() <= 1e-5 * np.abs(ref).max(), key
