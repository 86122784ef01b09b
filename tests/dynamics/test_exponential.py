"""The exponential Runge–Kutta step (drillstring.dynamics.steps.exponential, drillstring.dynamics.exponential_rk):
the φ functions against their closed forms and series, the pair's stiff order conditions, the order of
convergence measured on a stiff linear and a nonlinear problem with known solutions (the NumPy reference step),
exactness for a purely linear problem at any step, the compiled step against the reference on the reduced
model, and a run of the compiled loop against DOPRI5."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from drillstring.dynamics.exponential_rk import ERK32, ExponentialTableau, phi_functions
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.runge_kutta import method_named
from drillstring.dynamics.simulate import simulate_model
from drillstring.dynamics.steps import exponential, step_data

POINTS = [1e-12, 1e-6 - 2e-6j, 0.3 + 0.2j, -0.999, 0.999j, 1.0, -1.001, 2.5 - 4j, -60.0, -300 + 700j, 8.0]


def closed_forms(z: complex) -> np.ndarray:
    """φ_0, φ_1, φ_2 from e^z in extended precision where cancellation would bite: the series summed exactly
    in Python's floats term by term (math.fsum) for |z| < 2, the closed forms above."""
    if abs(z) < 2.0:
        return np.array([sum(z ** j / math.factorial(j + k) for j in range(80)) for k in range(3)])
    e = complex(np.exp(z))
    return np.array([e, (e - 1.0) / z, (e - 1.0 - z) / z ** 2])


@pytest.mark.parametrize("z", POINTS)
def test_phi_functions_against_closed_forms_and_series(z):
    want = closed_forms(complex(z))
    got = phi_functions(np.array([z]), 3)[:, 0]
    compiled = np.zeros(3, dtype=complex)
    exponential._phi_row(complex(z), compiled)
    np.testing.assert_allclose(got, want, rtol=2e-15, atol=0.0)
    np.testing.assert_allclose(compiled, want, rtol=2e-15, atol=0.0)


def test_phi_recurrence_and_values_at_zero():
    z = np.array([0.0, 1e-3, 0.9, 1.1, -40.0 + 3.0j])
    phi = phi_functions(z, 4)
    np.testing.assert_allclose(phi[:, 0], [1.0, 1.0, 1.0 / 2.0, 1.0 / 6.0])  # φ_k(0) = 1/k!
    for k in range(1, 4):  # φ_{k−1}(z) = z φ_k(z) + 1/(k − 1)!
        np.testing.assert_allclose(phi[k - 1], z * phi[k] + 1.0 / math.factorial(k - 1), rtol=1e-14, atol=1e-15)


def _psi2(tableau: ExponentialTableau, z: complex) -> np.ndarray:
    """ψ_{2,i}(z) = Σ_k a_ik(z) c_k − c_i² φ_2(c_i z) (HO 2005)."""
    a, _, _ = tableau.coefficients(z)
    return np.array([a[i] @ tableau.c - tableau.c[i] ** 2 * phi_functions(tableau.c[i] * z, 3)[2]
                     for i in range(tableau.n_stages)])


@pytest.mark.parametrize("z", [0.0, -0.5, -3.0 + 2.0j, -80.0, 0.7j, -1e4 + 5e3j])
def test_stiff_order_conditions_of_erk32(z):
    """HO 2005 Table 5.1, at scalar z (the conditions hold as functions of z; the one with J by its parts)."""
    tab = ERK32
    a, b, b_hat = tab.coefficients(z)
    phi = [phi_functions(z, 4)[k] for k in range(4)]
    c = tab.c
    for i in range(tab.n_stages):  # internal: Σ_j a_ij = c_i φ_1(c_i z)
        assert a[i].sum() == pytest.approx(c[i] * phi_functions(c[i] * z, 2)[1], rel=1e-13, abs=1e-15)
    assert b.sum() == pytest.approx(phi[1], rel=1e-13)  # order 1
    assert b @ c == pytest.approx(phi[2], rel=1e-13)  # order 2
    # order 3: Σ b_i J ψ_{2,i} = 0 for every J: each b_i with a nonzero weight has ψ_{2,i} ≡ 0
    psi = _psi2(tab, z)
    for i in range(tab.n_stages):
        assert abs(b[i]) < 1e-14 or abs(psi[i]) < 1e-13 * max(1.0, abs(phi[1]))
    # the embedded solution meets orders 1 and 2
    assert b_hat.sum() == pytest.approx(phi[1], rel=1e-13)
    assert b_hat @ c == pytest.approx(phi[2], rel=1e-13)


def test_third_order_condition_holds_in_its_weakened_form_only():
    """Σ b_i(0) c_i² = 1/3 (HO 2005 (4.16), what order 3 needs); the strong form Σ b_i c_i²/2 = φ_3 does not
    hold off z = 0, and the embedded weights fail even the weak one (their order is 2)."""
    _, b0, b_hat0 = ERK32.coefficients(0.0)
    assert b0 @ ERK32.c ** 2 == pytest.approx(1.0 / 3.0, rel=1e-14)
    assert abs(b_hat0 @ ERK32.c ** 2 - 1.0 / 3.0) > 0.05
    z = -2.0
    _, b, _ = ERK32.coefficients(z)
    assert abs(b @ ERK32.c ** 2 / 2 - phi_functions(z, 4)[3]) > 1e-3


def test_tableau_validation():
    with pytest.raises(ValueError, match="explicit"):
        ExponentialTableau(name="bad", c=ERK32.c, alpha=ERK32.alpha.copy() + np.eye(3)[:, :, None] * 0.1,
                           beta=ERK32.beta, beta_hat=ERK32.beta_hat, order=3, error_order=2)
    beta = ERK32.beta.copy()
    beta[0, 1] = 0.9
    with pytest.raises(ValueError, match="consistency"):
        ExponentialTableau(name="bad", c=ERK32.c, alpha=ERK32.alpha, beta=beta, beta_hat=ERK32.beta_hat,
                           order=3, error_order=2)
    assert method_named("erk32") is ERK32


# --- convergence on problems with known solutions (the NumPy reference step) ---------------------------------

OMEGA, ZETA = 400.0, 0.05  # a stiff lightly damped oscillator (|λ| = 400 1/s) and a slow one
LINEAR = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0], [-OMEGA ** 2, 0.0, -2 * ZETA * OMEGA, 0.0],
                   [0.0, -1.0, 0.0, -0.1]])


def forced_linear():
    """y' = L y + g(t), g = [0, 0, cos 3t, 0]: the exact solution from the homogeneous part (expm) and the
    particular one Re[(3i − L)⁻¹ e_3 e^{3it}], an independent computation."""
    forcing = np.array([0.0, 0.0, 1.0, 0.0])
    particular = np.linalg.solve(3j * np.eye(4) - LINEAR, forcing)
    y0 = np.array([1e-3, 1.0, 0.0, 0.5])

    def exact(t):
        yp0 = particular.real
        return expm(LINEAR * t) @ (y0 - yp0) + (particular * np.exp(3j * t)).real

    return (lambda t, y: LINEAR @ y + forcing * math.cos(3 * t)), y0, exact


def manufactured_nonlinear():
    """y' = L y + N(t, y), N = w∘sin(y − u) + e_3 (y_2² − u_2²) + u' − L u (non-stiff: |w| ≤ 20, the slow
    coordinate driving the stiff oscillator through its square): the exact solution u(t) =
    [1e-3 sin 5t, cos t, 5e-3 cos 5t, −sin t]."""
    def u(t):
        return np.array([1e-3 * math.sin(5 * t), math.cos(t), 5e-3 * math.cos(5 * t), -math.sin(t)])

    def du(t):
        return np.array([5e-3 * math.cos(5 * t), -math.sin(t), -25e-3 * math.sin(5 * t), -math.cos(t)])

    def rhs(t, y):
        square = np.array([0.0, 0.0, y[1] ** 2 - u(t)[1] ** 2, 0.0])
        return LINEAR @ y + np.sin(y - u(t)) * np.array([0.0, 1.0, 20.0, 1.0]) + square + du(t) - LINEAR @ u(t)

    return rhs, u(0.0), u


def fixed_steps(rhs, y0, h, t_end, matrix=LINEAR):
    y, t = np.array(y0, dtype=float), 0.0
    for _ in range(int(round(t_end / h))):
        y, _ = exponential.reference_step(ERK32, matrix, rhs, t, h, y, rhs(t, y))
        t += h
    return y


@pytest.mark.parametrize("problem", [forced_linear, manufactured_nonlinear])
def test_order_of_convergence_across_the_stiff_range(problem):
    """The global error at t = 1 falls as h³ with h·|λ_stiff| from 12.5 down to 1.6: order 3 where the step is
    far beyond the stiff mode's period (an explicit method is unstable at the larger steps)."""
    rhs, y0, exact = problem()
    steps = [1 / 32, 1 / 64, 1 / 128, 1 / 256]
    errors = [np.abs(fixed_steps(rhs, y0, h, 1.0) - exact(1.0)).max() for h in steps]
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert observed.mean() == pytest.approx(3.0, abs=0.35), errors


def test_linear_part_alone_is_exact_at_any_step():
    """N = 0: every step is e^{hA} y, to round-off, at steps far beyond the stiff period."""
    y0 = np.array([1e-3, 1.0, 0.2, 0.5])
    for h in (1e-4, 0.05, 1.0, 7.0):
        y_new, err = exponential.reference_step(ERK32, LINEAR, lambda t, y: LINEAR @ y, 0.0, h, y0, LINEAR @ y0)
        np.testing.assert_allclose(y_new, expm(LINEAR * h) @ y0, rtol=0.0, atol=1e-13)
        assert np.abs(err).max() < 1e-13


def test_error_estimate_is_third_order_locally():
    """The embedded estimate h Σ (b − b̂) N_i is O(h³) (the controller's q = 2) where h|λ| is small."""
    rhs, y0, exact = manufactured_nonlinear()
    local = [np.abs(exponential.reference_step(ERK32, LINEAR, rhs, 0.0, h, y0, rhs(0.0, y0))[1]).max()
             for h in (2e-4, 1e-4)]
    assert math.log2(local[0] / local[1]) == pytest.approx(3.0, abs=0.3)


# --- the compiled step on the reduced model ---------------------------------------------------------------------

def dense_linear_part(eigen, n_state: int) -> np.ndarray:
    """The step's A, dense, from its eigen data: Re(V Λ W) block by block, zero on the free states."""
    a = np.zeros((n_state, n_state))
    n = eigen.n_modal
    for b, (first, k, e0, e1) in enumerate(eigen.blocks):
        ne = e1 - e0
        off = eigen.offsets[b]
        v = (eigen.v_re[off:off + 2 * k * ne] + 1j * eigen.v_im[off:off + 2 * k * ne]).reshape(2 * k, ne)
        w = (eigen.w_re[off:off + 2 * k * ne] + 1j * eigen.w_im[off:off + 2 * k * ne]).reshape(ne, 2 * k)
        modes = list(eigen.modes[first:first + k])
        index = modes + [n + i for i in modes]
        a[np.ix_(index, index)] = (v @ np.diag(eigen.lam[e0:e1]) @ w).real
    return a


def test_linear_part_is_the_models_modal_part(small_case):
    """A = [[0, I], [−Ω², −D]] on every mode it holds (D whole on a fast small block, its diagonal on a slow
    one), zero on the rigid axial mode (left out) and the other states."""
    model = case_reduced_model(small_case)
    data = model.kernel_data()
    n_state = model.state_size
    step = step_data(ERK32, n_state, data.rhs)
    eigen = step.eigen
    a = dense_linear_part(eigen, n_state)
    n = model.size
    held = sorted(eigen.modes)
    assert 0 not in held and list(eigen.free[:2]) == [0, n]  # the rigid axial translation
    for i in held:
        assert a[i, n + i] == pytest.approx(1.0, abs=1e-12)
        assert a[n + i, i] == pytest.approx(-model.omega2[i], rel=1e-9, abs=1e-9)
    np.testing.assert_allclose(np.diag(a[n:2 * n, n:2 * n])[held], -np.diag(model.damping)[held], rtol=1e-9,
                               atol=1e-12)


def test_compiled_step_is_the_reference_step(small_case):
    """One compiled attempt on the reduced model from a perturbed state equals the NumPy reference step with
    the same A (to rounding), at a short and a long step."""
    model = case_reduced_model(small_case)
    data = model.kernel_data()
    n_state = model.state_size
    y = model.initial_state(1e-3, 1)
    y[model.size:2 * model.size] += 1e-3 * np.random.default_rng(0).standard_normal(model.size)
    step = step_data(ERK32, n_state, data.rhs)
    a = dense_linear_part(step.eigen, n_state)

    def rhs(t, x):
        out = np.zeros(n_state)
        exponential.evaluate_rhs(data.rhs, t, x, out)
        return out

    for h in (1e-4, 5e-3):
        f = rhs(0.0, y)
        y_new, err = np.zeros(n_state), np.zeros(n_state)
        evaluations, finite = exponential.attempt(step, data.rhs, 0.0, h, y, f, y_new, err)
        assert finite and evaluations == 3
        want, want_err = exponential.reference_step(ERK32, a, rhs, 0.0, h, y, f)
        scale = np.abs(y_new - y).max()
        assert np.abs(y_new - want).max() < 1e-9 * scale
        assert np.abs(err - want_err).max() < 1e-6 * np.abs(want_err).max()
        np.testing.assert_allclose(step.f_new, rhs(h, y_new), rtol=0, atol=1e-12 * np.abs(step.f_new).max())


def test_compiled_erk32_agrees_with_dopri5_on_the_reduced_model(small_case):
    """A drilling run of the small reference string: erk32 and DOPRI5 at a tight tolerance give the same
    observables within the tolerance."""
    model = case_reduced_model(small_case)
    kwargs = dict(t_end=1.0, output_step=0.01, rtol=1e-8, atol=1e-11, lateral_perturbation=1e-4, seed=0)
    explicit = simulate_model(model, method="dopri5", **kwargs)
    result = simulate_model(model, method="erk32", **kwargs)
    assert result.stats["n_rhs"] <= 3 * result.stats["n_steps"] + 2
    for key in ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit"):
        x, ref = result.observables[key], explicit.observables[key]
        assert np.abs(x - ref).max() <= 1e-5 * np.abs(ref).max(), key


def test_bit_law_linearisation_is_the_laws_jacobian(small_case):
    """The measured alternative's law part of A (off by default): the compiled partials as modal damping and
    stiffness equal the NumPy Jacobian rows of the law (drillstring.dynamics.stiffness, the law's closed form)."""
    from drillstring.dynamics.stiffness import _bit_rock_rows

    model = case_reduced_model(small_case)
    data = model.kernel_data()
    y = model.initial_state(1e-3, 1)
    n = model.size
    stiffness, damping = exponential.bit_law_linearisation(data.rhs, 0.0, y)
    rows = _bit_rock_rows(model, 0.0, y)
    scale = np.abs(rows[:, n:2 * n]).max()
    assert scale > 0.0
    np.testing.assert_allclose(-damping, rows[:, n:2 * n], rtol=0.0, atol=1e-6 * scale)
    np.testing.assert_allclose(-stiffness, rows[:, :n], rtol=0.0, atol=1e-6 * scale)
