"""Tests of the case-1 nonlinear forces f_se (strain energy) and f_ke (kinetic energy) (SPEC §6)."""

import numpy as np
import pytest
from numba import njit
from numba.core.runtime import _nrt_python, rtsys
from scipy.integrate import solve_ivp

from drillstring.fem.assembly import assemble_vector
from drillstring.fem.element import (
    BENDING_Y_DOFS,
    BENDING_Z_DOFS,
    PLANE_Z_SIGNS,
    TORSION_DOFS,
    axial_matrices,
    element_geometric_stiffness,
    element_mass,
    planar_shapes,
    shear_parameter,
)
from drillstring.fem.mesh import build_mesh
from drillstring.fem.sections import hollow_circle
from drillstring.forces.nonlinear import (  # noqa: I001
    _kinetic_energy_kernel,
    _kinetic_forces_kernel,
    _mass_coupling_kernel,
    _project_coupling_kernel,
    _strain_energy_forces_kernel,
    _strain_energy_kernel,
    element_kinetic_energy_nl,
    element_kinetic_force,
    element_rows,
    element_strain_energy,
    element_strain_energy_force,
    element_strain_energy_tangent,
    expand_mass_coupling,
    modal_mass_coupling,
    nonlinear_elements,
    project_mass_correction,
)

SECTION = hollow_circle(0.127, 0.095, 210e9, 7850.0, 0.29, 6.0 / 7.0)
COLLAR = hollow_circle(0.2286, 0.0762, 210e9, 7850.0, 0.29, 6.0 / 7.0)
L = 10.0
LATERAL = np.r_[BENDING_Y_DOFS, BENDING_Z_DOFS]
AXIAL = np.array([0, 6])


def random_state(rng, lateral=0.04, rotation=0.01, axial=1e-3, torsion=0.5):
    """A random element state with realistic magnitudes [m, rad]."""
    q = np.zeros(12)
    for node in (0, 6):
        q[node + 0] = axial * rng.standard_normal()
        q[node + 1] = lateral * rng.standard_normal()
        q[node + 2] = lateral * rng.standard_normal()
        q[node + 3] = torsion * rng.standard_normal()
        q[node + 4] = rotation * rng.standard_normal()
        q[node + 5] = rotation * rng.standard_normal()
    return q


def central_gradient(fun, x, h):
    g = np.zeros_like(x)
    for i in range(len(x)):
        e = np.zeros_like(x)
        e[i] = h[i] if np.ndim(h) else h
        g[i] = (fun(x + e) - fun(x - e)) / (2 * e[i])
    return g


def steps(q, rel=1e-6, floor=1e-9):
    return np.maximum(rel * np.abs(q), floor) + rel * np.max(np.abs(q))


def rel_err(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


# --- strain energy --------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(5))
def test_strain_force_is_minus_gradient_of_energy(seed):
    rng = np.random.default_rng(seed)
    q = random_state(rng)
    u_nl = lambda x: element_strain_energy(x, SECTION, L)  # noqa: E731
    fd = central_gradient(u_nl, q, steps(q, 1e-5))
    f = element_strain_energy_force(q, SECTION, L)
    assert rel_err(-fd, f) < 1e-6


@pytest.mark.parametrize("seed", range(5))
def test_strain_tangent_is_jacobian_of_force(seed):
    rng = np.random.default_rng(100 + seed)
    q = random_state(rng)
    h = steps(q, 1e-6)
    jac = np.empty((12, 12))
    for i in range(12):
        e = np.zeros(12)
        e[i] = h[i]
        jac[:, i] = -(element_strain_energy_force(q + e, SECTION, L) - element_strain_energy_force(q - e, SECTION, L))
        jac[:, i] /= 2 * h[i]
    k = element_strain_energy_tangent(q, SECTION, L)
    assert np.allclose(k, k.T, rtol=0, atol=1e-12 * np.abs(k).max())
    assert rel_err(jac, k) < 1e-6


def full_strain_energy(q, section, length, n_gauss=8):
    """½ ∫ EA (u' + ½(v'² + w'²))² dx computed independently (total displacements)."""
    s = planar_shapes(length, shear_parameter(section, length), n_gauss)
    du = (q[6] - q[0]) / length
    vp = s.slope @ q[BENDING_Y_DOFS]
    wp = s.slope @ (PLANE_Z_SIGNS * q[BENDING_Z_DOFS])
    eps = du + 0.5 * (vp**2 + wp**2)
    return 0.5 * section.axial_stiffness * s.weights @ eps**2


@pytest.mark.parametrize("tension", [-1.0e5, 2.5e5, 1.0e6])
def test_tangent_at_uniform_stretch_is_geometric_stiffness(tension):
    """∂²U_nl/∂q² at ū' = N/EA, v = w = 0 has the lateral block of [K_g(N)]: hence ū must be measured
    from the static state, otherwise [K_g] would be counted twice."""
    ea = SECTION.axial_stiffness
    q = np.zeros(12)
    q[6] = tension / ea * L
    k = element_strain_energy_tangent(q, SECTION, L)
    kg = element_geometric_stiffness(SECTION, L, tension, tension)
    lat = np.ix_(LATERAL, LATERAL)
    assert np.allclose(k[lat], kg[lat], rtol=1e-12, atol=1e-9 * np.abs(kg).max())
    # the full energy ½∫EAε² has the same lateral tangent there (by finite differences)
    h = 1e-6
    hess = np.empty((12, 12))
    for i in LATERAL:
        for j in LATERAL:
            ei = np.zeros(12)
            ej = np.zeros(12)
            ei[i] = h
            ej[j] = h
            f = lambda x: full_strain_energy(x, SECTION, L)  # noqa: E731
            hess[i, j] = (f(q + ei + ej) - f(q + ei - ej) - f(q - ei + ej) + f(q - ei - ej)) / (4 * h * h)
    assert rel_err(hess[lat], kg[lat]) < 1e-5


@pytest.mark.parametrize("seed", range(3))
def test_full_energy_decomposition(seed):
    """½∫EAε²(q_S + q̄) = const + linear + ½q̄ᵀ(K_axial + K_g)q̄ + U_nl(q̄) about a straight stretched state."""
    rng = np.random.default_rng(7 + seed)
    tension = 4.0e5
    q_s = np.zeros(12)
    q_s[6] = tension / SECTION.axial_stiffness * L
    qb = random_state(rng)
    k_lin = element_geometric_stiffness(SECTION, L, tension, tension)
    k_lin[np.ix_(AXIAL, AXIAL)] += axial_matrices(SECTION, L)[0]
    linear = tension * (qb[6] - qb[0])  # ∫ N ū' dx
    expected = (
        full_strain_energy(q_s, SECTION, L) + linear + 0.5 * qb @ k_lin @ qb + element_strain_energy(qb, SECTION, L)
    )
    assert full_strain_energy(q_s + qb, SECTION, L) == pytest.approx(expected, rel=1e-10)


def test_strain_force_zero_for_axial_torsion_and_translation():
    rng = np.random.default_rng(3)
    q = np.zeros(12)
    q[[0, 6]] = rng.standard_normal(2) * 1e-3  # pure axial
    q[[3, 9]] = rng.standard_normal(2)  # torsion
    assert np.all(element_strain_energy_force(q, SECTION, L) == 0.0)
    t = np.zeros(12)
    t[[0, 6]] = 0.3
    t[[1, 7]] = 0.02
    t[[2, 8]] = -0.03  # rigid translation
    f = element_strain_energy_force(t, SECTION, L)
    assert np.max(np.abs(f)) < 1e-12 * SECTION.axial_stiffness * 1e-6


def rigid_rotation(alpha, exact=False):
    """Rigid rotation by α about z (v = αx, θz = α) and by α/2 about y (w = −(α/2)x, θy = α/2)."""
    q = np.zeros(12)
    beta = 0.5 * alpha
    for node, x in ((0, 0.0), (6, L)):
        q[node + 1] = np.sin(alpha) * x if exact else alpha * x
        q[node + 5] = np.sin(alpha) if exact else alpha
        q[node + 2] = -beta * x
        q[node + 4] = beta
        if exact:
            q[node + 0] = (np.cos(alpha) - 1.0) * x
    return q


def test_small_rigid_rotation_gives_only_higher_order_forces():
    # linearised rigid rotation (u = 0, v = αx): no linear force; the axial DOFs get the O(α²) pull of the
    # geometric shortening ½EA v'² (a true rigid rotation cancels it with u = x(cos α − 1), see below) and
    # the lateral DOFs an O(α³) force: ratios 4 and 8 when α doubles
    f1 = element_strain_energy_force(rigid_rotation(1e-3), SECTION, L)
    f2 = element_strain_energy_force(rigid_rotation(2e-3), SECTION, L)
    atol = 1e-12 * np.abs(f2).max()
    assert np.allclose(f2[AXIAL], 4 * f1[AXIAL], rtol=1e-10, atol=atol)
    assert np.allclose(f2[LATERAL], 8 * f1[LATERAL], rtol=1e-10, atol=atol)
    assert np.allclose(f1[AXIAL], np.array([0.5, -0.5]) * SECTION.axial_stiffness * 1.25e-6, rtol=1e-10)
    # with the exact rigid rotation of the v-plane (u = x(cos α − 1), v = x sin α) the strain measure is
    # ε = cos α − 1 + ½ sin²α = O(α⁴), so the full energy gradient (axial stiffness force − f_se, no
    # prestress) is O(α⁴) on the axial DOFs and O(α⁵) on the lateral ones
    q1 = rigid_rotation(1e-2, exact=True)
    q1[[2, 4, 8, 10]] = 0.0
    q2 = rigid_rotation(2e-2, exact=True)
    q2[[2, 4, 8, 10]] = 0.0
    ka = np.zeros((12, 12))
    ka[np.ix_(AXIAL, AXIAL)] = axial_matrices(SECTION, L)[0]
    g1 = ka @ q1 - element_strain_energy_force(q1, SECTION, L)
    g2 = ka @ q2 - element_strain_energy_force(q2, SECTION, L)
    assert np.max(np.abs(g2[AXIAL])) / np.max(np.abs(g1[AXIAL])) == pytest.approx(16.0, rel=2e-3)
    assert np.max(np.abs(g2[LATERAL])) / np.max(np.abs(g1[LATERAL])) == pytest.approx(32.0, rel=2e-3)
    eps = np.cos(1e-2) - 1 + 0.5 * np.sin(1e-2) ** 2
    assert g1[6] == pytest.approx(SECTION.axial_stiffness * eps, rel=1e-6)
    # relative to the linear axial force of u = x(cos α − 1) alone it is ~α²/4
    assert np.max(np.abs(g1)) < 0.3e-4 * np.max(np.abs(ka @ q1))


def test_strain_force_scaling_cubic_and_quadratic():
    rng = np.random.default_rng(11)
    lateral = random_state(rng, axial=0.0, torsion=0.0)
    f = lambda s, q: element_strain_energy_force(s * q, SECTION, L)  # noqa: E731
    # lateral-only states: cubic lateral forces, quadratic axial pull (½ EA (v'² + w'²) on u)
    f1 = f(1.0, lateral)
    atol = 1e-13 * np.abs(f1).max()
    for s in (0.5, 2.0, -3.0):
        fs = f(s, lateral)
        assert np.allclose(fs[LATERAL], s**3 * f1[LATERAL], rtol=1e-12, atol=atol * abs(s) ** 3)
        assert np.allclose(fs[AXIAL], s**2 * f1[AXIAL], rtol=1e-12, atol=atol * s**2)
    assert np.abs(f1[LATERAL]).max() > 0 and np.abs(f1[AXIAL]).max() > 0
    mixed = random_state(rng)
    # f(s q) = s² A + s³ B exactly: identify A, B at s = 1, 2 and check elsewhere
    f1, f2 = f(1.0, mixed), f(2.0, mixed)
    b = (f2 - 4 * f1) / 4.0
    a = f1 - b
    for s in (0.3, -1.7, 5.0):
        assert np.allclose(f(s, mixed), s**2 * a + s**3 * b, rtol=0, atol=1e-11 * np.abs(f(s, mixed)).max())
    # both parts present; the quadratic part is f from ū'·v' coupling: −[½ s Bu + ū' h]
    assert np.abs(a).max() > 0 and np.abs(b).max() > 0
    assert np.abs(a[AXIAL]).max() > 0  # lateral slopes pull the axial DOFs (quadratic)


def test_large_amplitude_limits_finite_and_smooth():
    """Forces are polynomials of the state: finite, smooth, up to the gap (0.04 m) and 0.1 rad."""
    rng = np.random.default_rng(5)
    q = random_state(rng, lateral=0.04, rotation=0.1, axial=0.01, torsion=3.0)
    qd = random_state(rng, lateral=0.5, rotation=1.0, axial=0.1, torsion=10.0)
    qd[[3, 9]] += 10.5
    amplitudes = np.linspace(-1.0, 1.0, 9)
    fs = np.array([element_strain_energy_force(s * q, SECTION, L) for s in amplitudes])
    fk = np.array([element_kinetic_force(s * q, qd, SECTION, L)[1] @ qd for s in amplitudes])
    assert np.all(np.isfinite(fs)) and np.all(np.isfinite(fk))
    # a cubic through 4 amplitudes reproduces the rest (no hidden non-smooth terms)
    coef = np.polynomial.polynomial.polyfit(amplitudes, fs, 3)
    assert np.allclose(np.polynomial.polynomial.polyval(amplitudes, coef).T, fs, atol=1e-9 * np.abs(fs).max())
    # total element mass stays positive definite at θy = ±0.1 rad (|θy| < 1/√2 is sufficient)
    for sign in (-1.0, 1.0):
        qq = np.zeros(12)
        qq[[4, 10]] = sign * 0.1
        qq[[2, 8]] = sign * 0.01
        m = element_mass(SECTION, L) + element_kinetic_force(qq, qd, SECTION, L)[1]
        assert np.linalg.eigvalsh(m).min() > 0


# --- kinetic energy -------------------------------------------------------------------------------


def trajectory(rng):
    """q(t) polynomial in t (degree 3), with a spin of 10.5 rad/s in θx."""
    c = np.stack([random_state(rng, lateral=0.02, rotation=0.05, torsion=0.5) for _ in range(4)])
    c[1] *= 5.0
    c[1, [3, 9]] += 10.5

    def q(t):
        return c[0] + c[1] * t + c[2] * t**2 + c[3] * t**3

    def qd(t):
        return c[1] + 2 * c[2] * t + 3 * c[3] * t**2

    def qdd(t):
        return 2 * c[2] + 6 * c[3] * t

    return q, qd, qdd


@pytest.mark.parametrize("seed", range(5))
def test_kinetic_force_satisfies_lagrange_equations(seed):
    rng = np.random.default_rng(200 + seed)
    q, qd, qdd = trajectory(rng)
    t0 = 0.37
    T = lambda x, xd: element_kinetic_energy_nl(x, xd, SECTION, L)  # noqa: E731

    def p(t):  # ∂T/∂q̇ at the trajectory
        return central_gradient(lambda xd: T(q(t), xd), qd(t), 1e-3)

    dt = 1e-3
    dp_dt = (-p(t0 + 2 * dt) + 8 * p(t0 + dt) - 8 * p(t0 - dt) + p(t0 - 2 * dt)) / (12 * dt)
    dT_dq = central_gradient(lambda x: T(x, qd(t0)), q(t0), 1e-4)
    expected = -(dp_dt - dT_dq)
    f_vel, m_nl = element_kinetic_force(q(t0), qd(t0), SECTION, L)
    assert np.array_equal(m_nl, m_nl.T)
    assert rel_err(f_vel - m_nl @ qdd(t0), expected) < 1e-6
    # T_nl = ½ q̇ᵀ M_nl(q) q̇
    assert 0.5 * qd(t0) @ m_nl @ qd(t0) == pytest.approx(T(q(t0), qd(t0)), rel=1e-12)


def test_mass_correction_structure():
    rng = np.random.default_rng(9)
    q = random_state(rng)
    qd = random_state(rng)
    _, m = element_kinetic_force(q, qd, SECTION, L)
    mask = np.zeros((12, 12), bool)
    mask[np.ix_(TORSION_DOFS, BENDING_Y_DOFS)] = True
    mask |= mask.T
    assert np.all(m[~mask] == 0.0) and np.abs(m[mask]).max() > 0
    # linear in q, independent of q̇
    _, m2 = element_kinetic_force(2.0 * q, -qd, SECTION, L)
    assert np.allclose(m2, 2.0 * m, rtol=1e-13, atol=0)
    # zero for θy = 0
    q0 = q.copy()
    q0[BENDING_Z_DOFS] = 0.0
    assert np.all(element_kinetic_force(q0, qd, SECTION, L)[1] == 0.0)


def test_gyroscopic_terms_do_no_work():
    """With θ̇x = Ω uniform plus bending rates, f_vel on the bending DOFs is −Ω G q̇_b with G skew, so the
    power q̇_bᵀ f_vel,b vanishes (for any θy: f_vel does not depend on q); the only power of f_vel is in
    the torsion DOFs, ∫ρI_p θ̇x θ̇y θ̇z, exchanging energy between spin and whirl."""
    rng = np.random.default_rng(21)
    omega = 10.47
    qd = random_state(rng, lateral=0.3, rotation=0.05, axial=0.1, torsion=0.0)
    qd[[3, 9]] = omega
    bending = np.r_[BENDING_Y_DOFS, BENDING_Z_DOFS]
    f1, _ = element_kinetic_force(random_state(rng), qd, SECTION, L)
    f2, _ = element_kinetic_force(np.zeros(12), qd, SECTION, L)
    assert np.array_equal(f1, f2)
    scale = np.abs(f1[bending]).max() * np.abs(qd[bending]).max()
    assert abs(qd[bending] @ f1[bending]) < 1e-12 * scale
    # bending part linear in Ω
    qd2 = qd.copy()
    qd2[[3, 9]] = 2 * omega
    assert np.allclose(element_kinetic_force(np.zeros(12), qd2, SECTION, L)[0][bending], 2 * f1[bending], rtol=1e-13)
    # total power equals ∫ρI_p θ̇x θ̇y θ̇z dx (independent quadrature)
    s = planar_shapes(L, shear_parameter(SECTION, L), 6)
    tzd = s.rotation @ qd[BENDING_Y_DOFS]
    tyd = -s.rotation @ (PLANE_Z_SIGNS * qd[BENDING_Z_DOFS])
    power = SECTION.density * SECTION.polar_moment * s.weights @ (omega * tyd * tzd)
    assert qd @ f1 == pytest.approx(power, rel=1e-12)


def test_linearised_kinetic_forces_are_the_gyroscopic_matrix():
    """At θ̇x = Ω with small bending rates, f_vel is linear in q̇ and must be −Ω G q̇, G the element's
    gyroscopic matrix (fem.element.element_gyroscopic, checked against the Campbell diagram of a
    spinning shaft and the rate of the spin angular momentum)."""
    from drillstring.fem.element import element_gyroscopic

    rng = np.random.default_rng(31)
    omega = 10.47
    qd = np.zeros(12)
    bending = np.r_[BENDING_Y_DOFS, BENDING_Z_DOFS]
    qd[bending] = rng.normal(size=8) * 1e-3
    qd[[3, 9]] = omega
    f_vel, _ = element_kinetic_force(np.zeros(12), qd, SECTION, L)
    expected = -omega * element_gyroscopic(SECTION, L) @ qd
    np.testing.assert_allclose(f_vel[bending], expected[bending], rtol=1e-10, atol=1e-14)


def test_kinetic_energy_conserved_for_free_element():
    """Lagrange's equations (M + M_nl(q)) q̈ = f_vel(q̇) conserve E = ½q̇ᵀMq̇ + T_nl (no stiffness)."""
    rng = np.random.default_rng(4)
    m_lin = element_mass(SECTION, L)
    q0 = random_state(rng, lateral=0.01, rotation=0.05, torsion=0.1)
    qd0 = random_state(rng, lateral=0.05, rotation=0.5, axial=0.01, torsion=1.0)
    qd0[[3, 9]] += 10.5

    def rhs(t, y):
        q, qd = y[:12], y[12:]
        f, m = element_kinetic_force(q, qd, SECTION, L)
        return np.r_[qd, np.linalg.solve(m_lin + m, f)]

    def energy(y):
        q, qd = y[:12], y[12:]
        return 0.5 * qd @ m_lin @ qd + element_kinetic_energy_nl(q, qd, SECTION, L)

    sol = solve_ivp(rhs, (0.0, 2.0), np.r_[q0, qd0], method="DOP853", rtol=1e-11, atol=1e-12, dense_output=True)
    e = np.array([energy(sol.sol(t)) for t in np.linspace(0.0, 2.0, 21)])
    assert np.ptp(e) < 1e-8 * e[0]
    # and the nonlinear coupling actually moved energy around: T_nl changed
    t_nl = [element_kinetic_energy_nl(sol.sol(t)[:12], sol.sol(t)[12:], SECTION, L) for t in (0.0, 2.0)]
    assert abs(t_nl[1] - t_nl[0]) > 1e-6 * e[0]


# --- global evaluators ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def mesh():
    return build_mesh([30.0, 12.0], [SECTION, COLLAR], 10.0)


@pytest.fixture(scope="module")
def nl(mesh):
    return nonlinear_elements(mesh)


def global_state(rng, mesh):
    q = np.concatenate([random_state(rng)[:6] for _ in range(mesh.n_nodes)])
    qd = np.concatenate([random_state(rng, lateral=0.5, rotation=0.2, torsion=2.0)[:6] for _ in range(mesh.n_nodes)])
    qd[3::6] += 10.5
    return q, qd


def test_global_equals_sum_of_elements(mesh, nl):
    rng = np.random.default_rng(31)
    q, qd = global_state(rng, mesh)
    pairs = list(zip(mesh.element_sections(), mesh.element_lengths))
    dofs = [slice(6 * e, 6 * e + 12) for e in range(mesh.n_elements)]
    f_ref = assemble_vector(mesh.n_dofs, (element_strain_energy_force(q[d], s, h) for d, (s, h) in zip(dofs, pairs)))
    f = np.full(mesh.n_dofs, np.nan)
    assert nl.strain_energy_forces(q, f) is f
    assert rel_err(f, f_ref) < 1e-12
    u_ref = sum(element_strain_energy(q[d], s, h) for d, (s, h) in zip(dofs, pairs))
    assert nl.strain_energy(q) == pytest.approx(u_ref, rel=1e-12)

    results = [element_kinetic_force(q[d], qd[d], s, h) for d, (s, h) in zip(dofs, pairs)]
    fk_ref = assemble_vector(mesh.n_dofs, (r[0] for r in results))
    fk = np.full(mesh.n_dofs, np.nan)
    coupling = nl.kinetic_forces(q, qd, fk)
    assert rel_err(fk, fk_ref) < 1e-12
    blocks = expand_mass_coupling(coupling)
    assert rel_err(blocks, np.stack([r[1] for r in results])) < 1e-12
    assert np.allclose(nl.mass_coupling(q, np.empty_like(coupling)), coupling, rtol=1e-13, atol=0)
    t_ref = sum(element_kinetic_energy_nl(q[d], qd[d], s, h) for d, (s, h) in zip(dofs, pairs))
    assert nl.kinetic_energy_nl(q, qd) == pytest.approx(t_ref, rel=1e-12)
    m_global = nl.mass_correction_matrix(q)
    assert 0.5 * qd @ (m_global @ qd) == pytest.approx(t_ref, rel=1e-12)


def test_global_force_is_minus_gradient(mesh, nl):
    rng = np.random.default_rng(41)
    q, _ = global_state(rng, mesh)
    f = np.empty(mesh.n_dofs)
    nl.strain_energy_forces(q, f)
    fd = central_gradient(nl.strain_energy, q, steps(q, 1e-5))
    assert rel_err(-fd, f) < 1e-6


def test_projection_of_mass_correction(mesh, nl):
    rng = np.random.default_rng(51)
    q, qd = global_state(rng, mesh)
    n = 7
    phi = rng.standard_normal((mesh.n_dofs, n))
    phi_e = element_rows(phi)
    assert phi_e.shape == (mesh.n_elements, 12, n)
    coupling = nl.kinetic_forces(q, qd, np.empty(mesh.n_dofs))
    reference = phi.T @ (nl.mass_correction_matrix(q) @ phi)
    compact = project_mass_correction(coupling, phi_e)
    generic = project_mass_correction(expand_mass_coupling(coupling), phi_e)
    assert rel_err(compact, reference) < 1e-12
    assert rel_err(generic, reference) < 1e-12
    # family modes (each on its own DOFs): Φᵀ M_nl(Φη) Φ is zero but for the torsion × lateral-y block
    # Σ_k η_z,k T_k and its transpose
    families = {kind: np.zeros((mesh.n_dofs, 3)) for kind in ("u", "tx", "y", "z")}
    for kind, offsets in (("u", [0]), ("tx", [3]), ("y", [1, 5]), ("z", [2, 4])):
        for offset in offsets:
            families[kind][offset::6] = rng.standard_normal((mesh.n_nodes, 3))
    basis = np.hstack([families[k] for k in ("u", "tx", "y", "z")])
    tensor = modal_mass_coupling(nl, families["tx"], families["y"], families["z"])
    assert tensor.shape == (3, 3, 3)
    eta = rng.standard_normal(12)
    full = basis.T @ (nl.mass_correction_matrix(basis @ eta) @ basis)
    block = np.einsum("k,kij->ij", eta[9:], tensor)
    expected = np.zeros((12, 12))
    expected[3:6, 6:9] = block
    expected[6:9, 3:6] = block.T
    assert rel_err(full, expected) < 1e-12 and np.abs(block).max() > 0


@njit
def _drive_kernels(n_calls, q, qd, nl_arrays, phi_e, f, fk, coupling, out, work):
    inv_length, xi, weights, slope, rotation, ea, rho_ip = nl_arrays
    total = 0.0
    for _ in range(n_calls):
        _strain_energy_forces_kernel(q, inv_length, weights, slope, ea, f)
        _kinetic_forces_kernel(q, qd, xi, weights, rotation, rho_ip, fk, coupling)
        _mass_coupling_kernel(q, xi, weights, rotation, rho_ip, coupling)
        _project_coupling_kernel(coupling, phi_e, out, work)
        total += _strain_energy_kernel(q, inv_length, weights, slope, ea)
        total += _kinetic_energy_kernel(q, qd, xi, weights, rotation, rho_ip)
    return total


def test_global_kernels_do_not_allocate(mesh, nl):
    """The Numba kernels allocate nothing per call: the NRT allocation count of a compiled loop does not
    grow with the number of calls (only the constant boxing of the arguments remains)."""
    rng = np.random.default_rng(61)
    q, qd = global_state(rng, mesh)
    n = 5
    phi_e = element_rows(rng.standard_normal((mesh.n_dofs, n)))
    arrays = (nl.inv_length, nl.xi, nl.weights, nl.slope, nl.rotation, nl.axial_stiffness, nl.polar_inertia)
    buffers = (
        np.empty(mesh.n_dofs),
        np.empty(mesh.n_dofs),
        np.empty((mesh.n_elements, 2, 4)),
        np.empty((n, n)),
        np.empty((2, n)),
    )
    _drive_kernels(1, q, qd, arrays, phi_e, *buffers)  # compile
    was_enabled = _nrt_python.memsys_stats_enabled()
    _nrt_python.memsys_enable_stats()
    try:
        counts = []
        for n_calls in (1, 50):
            before = rtsys.get_allocation_stats()
            _drive_kernels(n_calls, q, qd, arrays, phi_e, *buffers)
            after = rtsys.get_allocation_stats()
            counts.append(after.alloc - before.alloc)
    finally:
        if not was_enabled:
            _nrt_python.memsys_disable_stats()
    assert counts[0] == counts[1]


def test_nonlinear_elements_rejects_too_few_gauss_points(mesh):
    with pytest.raises(ValueError):
        nonlinear_elements(mesh, n_gauss=4)
