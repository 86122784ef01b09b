"""Characteristic roots of linear delay systems: the scalar equation against the Lambert W closed form,
the stability boundary of ``x' = −b x(t − τ)``, a delayed oscillator against roots found independently
(Newton on its scalar characteristic function from a grid, counted by the argument principle), and the
builder of the modal delay matrices against 1-DOF and 2-DOF characteristic equations derived by hand."""

import math

import numpy as np
import pytest
from scipy.linalg import block_diag
from scipy.special import lambertw

from drillstring.dynamics.delay_stability import (
    append_states,
    characteristic_roots,
    chebyshev_differentiation,
    chebyshev_generator,
    delayed_factors,
    second_order_delay_matrices,
)


def delta_det(A0, A1, tau, s):
    return np.linalg.det(s * np.eye(A0.shape[0]) - A0 - A1 * np.exp(-s * tau))


@pytest.mark.parametrize("a, b, tau", [(-1.0, -2.0, 1.0), (0.5, -1.0, 0.7), (-2.0, 0.5, 2.0),
                                       (0.3, 0.4, 1.5), (-1.0, -0.2, 1.0)])
def test_scalar_roots_match_lambert_w(a, b, tau):
    """x' = a x + b x(t − τ): s_k = a + W_k(b τ e^{−aτ})/τ; the principal branch is the rightmost root."""
    result = characteristic_roots([[a]], [[b]], tau)
    exact = [a + complex(lambertw(b * tau * math.exp(-a * tau), k)) / tau for k in range(-3, 4)]
    rightmost = exact[3]
    assert abs(result.leading - rightmost) <= 1e-10 * abs(rightmost) or abs(
        result.leading - rightmost.conjugate()) <= 1e-10 * abs(rightmost)
    assert max(e.real for e in exact) == pytest.approx(rightmost.real)
    for s in exact:
        assert np.min(np.abs(result.roots - s)) <= 1e-10 * abs(s)
    assert result.stable == (rightmost.real < 0)
    assert result.leading_change <= 1e-8
    assert np.all(result.residuals <= 1e-10)
    # the conjugate pairs are both listed, sorted by real part
    assert np.all(np.diff(result.roots.real) <= 1e-12)


@pytest.mark.parametrize("b_tau, stable", [(0.3, True), (1.5, True), (1.55, True), (1.6, False), (3.0, False)])
def test_stability_boundary_of_pure_delay(b_tau, stable):
    """x' = −b x(t − τ) is stable iff bτ < π/2; at the boundary the roots cross at ±iπ/(2τ)."""
    tau = 0.5
    result = characteristic_roots([[0.0]], [[-b_tau / tau]], tau)
    assert result.stable is stable
    if b_tau > 1 / math.e:  # complex leading pair; on the boundary its frequency is 1/(4τ) Hz
        assert abs(result.frequency - 1 / (4 * tau)) < 0.5 * abs(b_tau - math.pi / 2) / tau + 1e-12


def test_pure_delay_on_the_boundary():
    tau = 0.5
    result = characteristic_roots([[0.0]], [[-math.pi / 2 / tau]], tau)
    assert abs(result.leading - 1j * math.pi / (2 * tau)) < 1e-12


def oscillator(omega, zeta, k, tau):
    """s² + 2ζω s + ω² + k(1 − e^{−sτ}) = 0 in the state [u, u']."""
    A0 = np.array([[0.0, 1.0], [-omega**2 - k, -2 * zeta * omega]])
    A1 = np.array([[0.0, 0.0], [k, 0.0]])
    p = lambda s: s**2 + 2 * zeta * omega * s + omega**2 + k * (1 - np.exp(-s * tau))  # noqa: E731
    dp = lambda s: 2 * s + 2 * zeta * omega + k * tau * np.exp(-s * tau)  # noqa: E731
    return A0, A1, p, dp


def independent_roots(p, dp, re_min, re_max, im_max, n=60):
    """Newton on the scalar p from a grid of starting points, roots kept in the box."""
    s = (np.linspace(re_min, re_max, n)[:, None] + 1j * np.linspace(0, im_max, n)[None, :]).ravel()
    for _ in range(100):
        with np.errstate(all="ignore"):
            s = s - p(s) / dp(s)
    ok = np.isfinite(s) & (np.abs(p(s)) < 1e-9 * (1 + np.abs(s) ** 2))
    s = s[ok & (s.real > re_min) & (s.real < re_max) & (s.imag >= 0) & (s.imag < im_max)]
    roots = []
    for z in s[np.argsort(-s.real)]:
        if all(abs(z - r) > 1e-7 * (1 + abs(z)) for r in roots):
            roots.append(z)
    return np.array(roots)


def argument_principle_count(p, dp, re_min, re_max, im_max, n=20000):
    """Zeros of p in the rectangle [re_min, re_max] × [−im_max, im_max]: (1/2πi) ∮ p'/p ds."""
    corners = [re_min - 1j * im_max, re_max - 1j * im_max, re_max + 1j * im_max, re_min + 1j * im_max]
    total = 0j
    for z0, z1 in zip(corners, corners[1:] + corners[:1]):
        t = np.linspace(0, 1, n)
        z = z0 + (z1 - z0) * t
        total += np.trapezoid(dp(z) / p(z), z)
    return round((total / (2j * math.pi)).real)


@pytest.mark.parametrize("k, unstable_pairs", [(0.5, 0), (3.0, 1), (80.0, 2)])
def test_delayed_oscillator_against_independent_roots(k, unstable_pairs):
    """Every root in the box −8 < Re s < 3, |Im s| < 40 found by Newton on the scalar characteristic
    function from a 60×60 grid (the box's count checked by the argument principle) is found, to 1e-10
    relative; the count in the right half-plane agrees with the argument principle."""
    omega, zeta, tau = 2 * math.pi, 0.02, 0.8
    A0, A1, p, dp = oscillator(omega, zeta, k, tau)
    re_min, re_max, im_max = -8.0, 3.0, 40.0
    # the box reaches |s| τ ≈ 33: M = 48 resolves it (the default M only covers Re s ≥ 0)
    result = characteristic_roots(A0, A1, tau, M=48)
    assert result.resolved
    reference = independent_roots(p, dp, re_min, re_max, im_max)
    n_box = argument_principle_count(p, dp, re_min, re_max, im_max)
    assert n_box == 2 * np.sum(reference.imag > 1e-9) + np.sum(reference.imag <= 1e-9) >= 5
    in_box = (result.roots.real > re_min) & (np.abs(result.roots.imag) < im_max)
    assert int(np.sum(in_box)) == n_box
    for z in reference:
        assert np.min(np.abs(result.roots - z)) <= 1e-10 * abs(z)
    n_right = argument_principle_count(p, dp, 0.0, 5.0, 60.0)
    assert n_right == 2 * unstable_pairs == int(np.sum(result.roots.real > 0))
    assert result.stable == (unstable_pairs == 0)


def test_one_dof_builder_against_hand_equation():
    """m u'' + c u' + k_c (u(t) − u(t − τ)) = 0 as modal equations (η = √m u, b_u = 1/√m, f_d = −k_c):
    A0, A1 built by hand; det Δ(s) = (m s² + c s + k_c(1 − e^{−sτ}))/m; s = 0 reported as neutral."""
    m, c, k_c, tau = 250.0, 40.0, 3.0e4, 0.5
    A0, A1 = second_order_delay_matrices([[0.0]], [[c / m]], [1 / math.sqrt(m)], [0.0], f_du=0.0,
                                         f_dtheta=0.0, f_d=-k_c, t_du=0.0, t_dtheta=0.0, t_d=0.0,
                                         rate_of_penetration=0.01, bit_speed=3.0)
    np.testing.assert_allclose(A0, [[0, 1], [-k_c / m, -c / m]], rtol=1e-14)
    np.testing.assert_allclose(A1, [[0, 0], [k_c / m, 0]], rtol=1e-14)
    for s in (0.3 + 2j, -1 + 7j, 4.0):
        assert delta_det(A0, A1, tau, s) == pytest.approx((m * s**2 + c * s + k_c * (1 - np.exp(-s * tau))) / m,
                                                          rel=1e-12)
    result = characteristic_roots(A0, A1, tau)
    assert len(result.neutral) == 1 and abs(result.neutral[0]) < 1e-10
    assert np.all(np.abs(result.roots) > 1e-3)
    h = lambda s: m * s**2 + c * s + k_c * (1 - np.exp(-s * tau))  # noqa: E731
    for s in result.roots[:10]:
        assert abs(h(s)) <= 1e-9 * (m * abs(s) ** 2 + c * abs(s) + 2 * k_c)
    # the leading root (unstable here: the regenerative stiffness against little damping) against the
    # scalar equation's roots found independently
    reference = independent_roots(h, lambda s: 2 * m * s + c + k_c * tau * np.exp(-s * tau), -2.0, 2.0, 40.0)
    reference = reference[np.abs(reference) > 1e-6]
    assert result.leading.real == pytest.approx(reference[0].real, rel=1e-9) and not result.stable


def two_dof_hand_det(s, p, tau):
    """Axial u (mass m, stiffness k_a, damping c_a) and torsional θ (inertia I, k_t, c_t), physical
    coordinates, δd = (1 − e^{−sτ})(δu − (V/Ω) δθ)."""
    E, r = np.exp(-s * tau), p["V"] / p["Omega"]
    a11 = p["m"] * s**2 + (p["c_a"] - p["f_du"]) * s + p["k_a"] - p["f_d"] * (1 - E)
    a12 = -p["f_dtheta"] * s + p["f_d"] * r * (1 - E)
    a21 = -p["t_du"] * s - p["t_d"] * (1 - E)
    a22 = p["I"] * s**2 + (p["c_t"] - p["t_dtheta"]) * s + p["k_t"] + p["t_d"] * r * (1 - E)
    return a11 * a22 - a12 * a21


TWO_DOF = dict(m=3000.0, c_a=2.0e3, k_a=5.0e5, I=40.0, c_t=30.0, k_t=900.0, f_du=-1.0e4, f_dtheta=-50.0,
               f_d=-6.0e6, t_du=-300.0, t_dtheta=-15.0, t_d=-1.2e5, V=30 / 3600, Omega=math.pi)


def two_dof_matrices(p):
    K = np.diag([p["k_a"] / p["m"], p["k_t"] / p["I"]])
    C = np.diag([p["c_a"] / p["m"], p["c_t"] / p["I"]])
    return second_order_delay_matrices(
        K, C, [1 / math.sqrt(p["m"]), 0.0], [0.0, 1 / math.sqrt(p["I"])], f_du=p["f_du"],
        f_dtheta=p["f_dtheta"], f_d=p["f_d"], t_du=p["t_du"], t_dtheta=p["t_dtheta"], t_d=p["t_d"],
        rate_of_penetration=p["V"], bit_speed=p["Omega"])


def test_two_dof_builder_against_hand_matrices_and_determinant():
    p, tau = TWO_DOF, math.pi / 2 / TWO_DOF["Omega"]
    A0, A1 = two_dof_matrices(p)
    m, I, r = p["m"], p["I"], p["V"] / p["Omega"]
    sm, si = math.sqrt(m), math.sqrt(I)
    hand0 = np.zeros((4, 4))
    hand0[0, 2] = hand0[1, 3] = 1
    hand0[2] = [(-p["k_a"] + p["f_d"]) / m, -p["f_d"] * r / (sm * si), (-p["c_a"] + p["f_du"]) / m,
                p["f_dtheta"] / (sm * si)]
    hand0[3] = [p["t_d"] / (sm * si), (-p["k_t"] - p["t_d"] * r) / I, p["t_du"] / (sm * si),
                (-p["c_t"] + p["t_dtheta"]) / I]
    hand1 = np.zeros((4, 4))
    hand1[2, :2] = [-p["f_d"] / m, p["f_d"] * r / (sm * si)]
    hand1[3, :2] = [-p["t_d"] / (sm * si), p["t_d"] * r / I]
    np.testing.assert_allclose(A0, hand0, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(A1, hand1, rtol=1e-13, atol=1e-13)
    for s in (0.4 + 3j, -2 + 20j, 1.5):
        assert delta_det(A0, A1, tau, s) == pytest.approx(two_dof_hand_det(s, p, tau) / (m * I), rel=1e-11)
    result = characteristic_roots(A0, A1, tau)
    scale = lambda s: (m * abs(s) ** 2 + 1e7) * (I * abs(s) ** 2 + 1e6)  # noqa: E731
    for s in result.roots[:12]:
        assert abs(two_dof_hand_det(s, p, tau)) <= 1e-8 * scale(s)
    # without the V/Ω term the roots move: the term is in the matrices
    q = dict(p, V=0.0)
    assert abs(characteristic_roots(*two_dof_matrices(q), tau).leading - result.leading) > 1e-6


def test_rigid_two_dof_has_two_neutral_roots():
    """Rigid axial translation and rigid rotation leave δd unchanged: s = 0 twice, both neutral."""
    p = dict(TWO_DOF, k_a=0.0, k_t=0.0)
    tau = math.pi / 2 / p["Omega"]
    result = characteristic_roots(*two_dof_matrices(p), tau)
    assert len(result.neutral) == 2
    assert np.all(np.abs(result.roots) > 1e-4)


def test_append_states_adds_an_integral_controller():
    """A pure-delay equation x' = −b x(t − τ) with an added state z' = x, x' gets −k z: the bordered
    matrices give s² + b s e^{−sτ} + k = 0."""
    b, k, tau = 0.8, 0.3, 0.6
    A0, A1 = append_states([[0.0]], [[-b]], [[-k]], [[1.0]], [[0.0]])
    result = characteristic_roots(A0, A1, tau)
    for s in result.roots[:6]:
        assert abs(s**2 + b * s * np.exp(-s * tau) + k) <= 1e-10 * (1 + abs(s) ** 2)


def test_chebyshev_generator_differentiates_polynomials_exactly():
    """Block rows j ≥ 1 apply d/dθ on the nodes θ_j = (τ/2)(cos(jπ/M) − 1) to the delayed signal
    w = Vᵀx, with w(θ_0) = Vᵀx(0): exact for a cubic."""
    tau, M = 0.7, 6
    G = chebyshev_generator(np.zeros((1, 1)), np.array([[-2.0]]), tau, M)
    theta, _ = chebyshev_differentiation(tau, M)
    U, V = delayed_factors(np.array([[-2.0]]))
    assert (U @ V.T).item() == pytest.approx(-2.0)
    f, df = (theta + 0.3) ** 3, 3 * (theta + 0.3) ** 2
    z = np.concatenate([[f[0]], V.item() * f[1:]])
    np.testing.assert_allclose(G[1:] @ z, V.item() * df[1:], atol=1e-12)
    np.testing.assert_allclose(G[0], np.r_[0.0, np.zeros(M - 1), U.item()])


def test_low_rank_generator_against_full_collocation_matrix():
    """For the rank-one delay of a bit law the N + M generator has the eigenvalues of the N(M+1) matrix
    [A0, 0, …, A1; D_{≥1,·} ⊗ I_N] built here, less N − 1 copies of the eigenvalues of D_{≥1,≥1}."""
    p, tau, M = TWO_DOF, math.pi / 2 / TWO_DOF["Omega"], 12
    A0, A1 = two_dof_matrices(p)
    N = A0.shape[0]
    _, D = chebyshev_differentiation(tau, M)
    full = np.zeros((N * (M + 1), N * (M + 1)))
    full[:N, :N], full[:N, N * M:] = A0, A1
    full[N:] = np.kron(D[1:], np.eye(N))
    small = chebyshev_generator(A0, A1, tau, M)
    assert small.shape == (N + M, N + M)
    lam_full = np.linalg.eigvals(full)
    lam_small = np.linalg.eigvals(small)
    spurious = np.linalg.eigvals(D[1:, 1:])
    expected = list(lam_small) + list(spurious) * (N - 1)
    assert len(expected) == lam_full.size
    for z in lam_small:
        assert np.min(np.abs(lam_full - z)) <= 1e-6 * max(abs(z), 1)
    for z in spurious:  # N − 1 copies each in the full matrix
        assert np.sum(np.abs(lam_full - z) <= 1e-3 * abs(z)) >= N - 1


@pytest.mark.parametrize("bad, message", [
    (dict(tau=0.0), "tau"), (dict(A1=np.zeros((2, 2))), "A0 and A1"), (dict(M=1), "M = 1")])
def test_bad_input(bad, message):
    args = dict(A0=np.zeros((1, 1)), A1=np.ones((1, 1)), tau=1.0) | bad
    with pytest.raises(ValueError, match=message):
        characteristic_roots(args.pop("A0"), args.pop("A1"), **args)


@pytest.mark.parametrize("seed", [0, 2])
def test_default_degree_covers_the_right_half_plane(seed):
    """N = 8, full-rank A1 with ‖A1‖ = 40 1/s, τ = 0.5 s: the rightmost root lies at |s|τ ≈ 30–40, missed
    with M = 8 (seed 0) or M = 16 (seed 2). The default M = ⌈τR⌉ finds the rightmost root of a reference
    with M = 100; every root in the right half-plane has |s| ≤ R (R: balanced norm bound)."""
    rng = np.random.default_rng(seed)
    N, tau = 8, 0.5
    Q = np.linalg.qr(rng.standard_normal((N, N)))[0]
    blocks = [np.array([[-a, w], [-w, -a]]) for a, w in zip(rng.uniform(0.1, 5, N // 2), rng.uniform(0, 100, N // 2))]
    A0 = Q @ block_diag(*blocks) @ Q.T
    A1 = rng.standard_normal((N, N))
    A1 *= 40 / np.linalg.norm(A1, 2)
    reference = characteristic_roots(A0, A1, tau, M=100, verify=False)
    assert reference.resolved
    right = reference.roots[reference.roots.real >= 0]
    assert right.size >= 4 and np.max(np.abs(right)) <= reference.radius
    result = characteristic_roots(A0, A1, tau)
    assert result.resolved and result.leading_change <= 1e-8
    assert abs(result.leading - reference.leading) <= 1e-10 * abs(reference.leading)
    assert int(np.sum(result.roots.real >= 0)) == right.size
    missed_at = {0: 8, 2: 16}[seed]
    coarse = characteristic_roots(A0, A1, tau, M=missed_at, verify=False)
    assert coarse.leading.real < reference.leading.real - 0.1


def test_a_small_genuine_root_is_not_neutral():
    """m u'' + c u' + k u + k_c(u − u(t − τ)) = 0 with a stiff regenerative term (‖A0‖ ≈ 1e6 1/s²) and a
    weak spring: the slow root s ≈ −k/(c + k_c τ) ≈ −1e-3 1/s is a root, not an invariance (k = 0: neutral)."""
    m, c, k, k_c, tau = 1.0, 10.0, 10.0, 1e6, 0.01
    h = lambda s: m * s**2 + c * s + k + k_c * (1 - np.exp(-s * tau))  # noqa: E731
    A0 = np.array([[0.0, 1.0], [-(k + k_c) / m, -c / m]])
    A1 = np.array([[0.0, 0.0], [k_c / m, 0.0]])
    result = characteristic_roots(A0, A1, tau)
    slow = result.roots[np.argmin(np.abs(result.roots))]
    assert result.neutral.size == 0
    assert slow.imag == 0 and slow.real == pytest.approx(-k / (c + k_c * tau), rel=1e-2)
    assert abs(h(slow)) <= 1e-12 * k_c * abs(slow) * tau
    A0[1, 0] = -k_c / m
    assert characteristic_roots(A0, A1, tau).neutral.size == 1


def test_double_roots_keep_their_multiplicity():
    """Two identical uncoupled scalar equations: every Lambert W root twice, none more often."""
    a, b, tau = -1.0, -2.0, 1.0
    result = characteristic_roots(a * np.eye(2), b * np.eye(2), tau)
    for k in range(-2, 3):
        s = a + complex(lambertw(b * tau * math.exp(-a * tau), k)) / tau
        assert int(np.sum(np.abs(result.roots - s) <= 1e-9 * abs(s))) == 2
