"""Element matrices: symmetry, definiteness, rigid-body modes, closed forms."""

import numpy as np
import pytest

from drillstring.fem import element as el


@pytest.fixture(params=[0.5, 10.0])
def length(request):
    return request.param


def test_symmetry_and_definiteness(drill_collar, length):
    k = el.element_stiffness(drill_collar, length)
    m = el.element_mass(drill_collar, length)
    np.testing.assert_allclose(k, k.T, rtol=0, atol=1e-9 * np.abs(k).max())
    np.testing.assert_allclose(m, m.T, rtol=0, atol=1e-12 * np.abs(m).max())
    assert np.linalg.eigvalsh(m).min() > 0
    eig_k = np.linalg.eigvalsh(k)
    assert eig_k.min() > -1e-9 * eig_k.max()


def rigid_body_modes(length):
    """Six rigid motions of a free element: 3 translations, 3 small rotations (θ about x, y, z)."""
    modes = []
    for k in range(3):
        r = np.zeros(12)
        r[[k, 6 + k]] = 1.0
        modes.append(r)
    r = np.zeros(12)  # rotation about x
    r[[3, 9]] = 1.0
    modes.append(r)
    r = np.zeros(12)  # rotation about y: w = −x θy
    r[[4, 10]] = 1.0
    r[8] = -length
    modes.append(r)
    r = np.zeros(12)  # rotation about z: v = x θz
    r[[5, 11]] = 1.0
    r[7] = length
    modes.append(r)
    return np.array(modes).T


def test_free_element_has_exactly_six_rigid_body_modes(drill_pipe, length):
    k = el.element_stiffness(drill_pipe, length)
    rigid = rigid_body_modes(length)
    scale = np.abs(k).max()
    np.testing.assert_allclose(k @ rigid, 0.0, atol=1e-9 * scale * max(1, length))
    eig = np.linalg.eigvalsh(k)
    assert np.sum(np.abs(eig) < 1e-9 * eig.max()) == 6


def test_bending_stiffness_equals_closed_form_timoshenko(drill_collar, length):
    """Przemieniecki's Timoshenko stiffness (Theory of Matrix Structural Analysis, 1968, §5.6)."""
    ei = drill_collar.bending_stiffness
    phi = el.shear_parameter(drill_collar, length)
    L = length
    expected = (
        ei
        / (L**3 * (1 + phi))
        * np.array(
            [
                [12, 6 * L, -12, 6 * L],
                [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
                [-12, -6 * L, 12, -6 * L],
                [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2],
            ]
        )
    )
    np.testing.assert_allclose(el.bending_stiffness(drill_collar, L), expected, rtol=1e-10,
                               atol=1e-10 * np.abs(expected).max())


def test_euler_bernoulli_limit_of_mass(drill_pipe):
    """For Φ -> 0 and no rotary inertia the translational mass is the classic cubic-Hermite one."""
    L = 50.0  # slender: Φ ~ 1e-5
    s = el.planar_shapes(L, 0.0)
    m = drill_pipe.mass_per_length * np.einsum("g,gi,gj->ij", s.weights, s.displacement,
                                                s.displacement)
    expected = drill_pipe.mass_per_length * L / 420 * np.array(
        [[156, 22 * L, 54, -13 * L], [22 * L, 4 * L**2, 13 * L, -3 * L**2],
         [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L**2, -22 * L, 4 * L**2]]
    )
    np.testing.assert_allclose(m, expected, rtol=1e-12, atol=1e-9)


def test_mass_matrix_carries_total_mass_and_inertias(drill_collar, length):
    m = el.element_mass(drill_collar, length)
    rigid = rigid_body_modes(length)
    mass = drill_collar.mass_per_length * length
    for k in range(3):  # translations carry the element mass
        assert rigid[:, k] @ m @ rigid[:, k] == pytest.approx(mass, rel=1e-12)
    # Rotation about x: polar inertia ρ I_p L.
    assert rigid[:, 3] @ m @ rigid[:, 3] == pytest.approx(
        drill_collar.density * drill_collar.polar_moment * length, rel=1e-12
    )
    # Rigid rotation about z through the top node: ρA L³/3 + ρ I L.
    expected = mass * length**2 / 3 + drill_collar.density * drill_collar.second_moment * length
    assert rigid[:, 5] @ m @ rigid[:, 5] == pytest.approx(expected, rel=1e-12)
    assert rigid[:, 4] @ m @ rigid[:, 4] == pytest.approx(expected, rel=1e-12)


def test_shape_functions_are_nodal_and_interdependent(drill_collar):
    L = 2.0
    phi = el.shear_parameter(drill_collar, L)
    s = el.planar_shapes(L, phi, n_gauss=6)
    # The shear strain v' − ψ of each shape is constant along the element (Friedman–Kosmatka).
    gamma = s.slope - s.rotation
    np.testing.assert_allclose(gamma, np.broadcast_to(gamma[0], gamma.shape), atol=1e-12)
    # Homogeneous moment equilibrium EI ψ'' + k_s G A (v' − ψ) = 0, with ψ'' constant.
    curvature_slope = (s.curvature[-1] - s.curvature[0]) / ((s.xi[-1] - s.xi[0]) * L)
    np.testing.assert_allclose(
        drill_collar.bending_stiffness * curvature_slope, -drill_collar.shear_stiffness * gamma[0],
        rtol=1e-9, atol=1e-9,
    )


def test_geometric_stiffness_rigid_rotation_energy(drill_pipe):
    """Rigid rotation θ under constant N: qᵀ K_g q = N L θ²; rigid translation: 0."""
    L, n, theta = 7.0, 3.0e5, 0.01
    kg = el.bending_geometric_stiffness(drill_pipe, L, n, n)
    q = np.array([0.0, theta, L * theta, theta])
    assert q @ kg @ q == pytest.approx(n * L * theta**2, rel=1e-12)
    np.testing.assert_allclose(kg @ np.array([1.0, 0, 1.0, 0]), 0.0, atol=1e-6)
    np.testing.assert_allclose(kg, kg.T, atol=1e-9)
    # Linear in N: mean of the end forces gives the same energy for a rigid rotation.
    kg_lin = el.bending_geometric_stiffness(drill_pipe, L, 0.0, 2 * n)
    assert q @ kg_lin @ q == pytest.approx(n * L * theta**2, rel=1e-12)


def test_planes_are_consistent_under_rotation_about_axis(drill_pipe):
    """Rotating the lateral frame by 90° about x maps (v, θz) to (w, −θy): energies must agree."""
    k = el.element_stiffness(drill_pipe, 3.0)
    rng = np.random.default_rng(1)
    q = rng.normal(size=12)
    r = q.copy()
    for node in (0, 6):  # v -> w, w -> −v, θy -> θz, θz -> −θy
        v, w, ty, tz = q[node + 1], q[node + 2], q[node + 4], q[node + 5]
        r[node + 1], r[node + 2], r[node + 4], r[node + 5] = -w, v, -tz, ty
    assert r @ k @ r == pytest.approx(q @ k @ q, rel=1e-12)


def test_gravity_load_sums_to_weight():
    f = el.element_gravity_load(43.8, 10.0, 9.81)
    assert f.sum() == pytest.approx(43.8 * 10.0 * 9.81)
    assert f[0] == f[6]


# --- gyroscopic matrix ----------------------------------------------------------------------------------


def _rigid_rotation_rates(length, about):
    """Element velocities of a rigid rotation at unit rate about y or z through the first node."""
    qd = np.zeros(12)
    for node, x in ((0, 0.0), (1, length)):
        if about == "z":  # θz = ∂v/∂x: v̇ = x, θ̇z = 1
            qd[6 * node + 1], qd[6 * node + 5] = x, 1.0
        else:  # θy = −∂w/∂x: ẇ = −x, θ̇y = 1
            qd[6 * node + 2], qd[6 * node + 4] = -x, 1.0
    return qd


def test_gyroscopic_matrix_is_skew_and_couples_only_the_bending_planes(drill_collar, length):
    g = el.element_gyroscopic(drill_collar, length)
    np.testing.assert_array_equal(g, -g.T)
    rng = np.random.default_rng(0)
    for _ in range(5):
        qd = rng.normal(size=12)
        assert abs(qd @ g @ qd) < 1e-14 * np.abs(g).max()  # gyroscopic forces do no work
    nonzero = np.zeros((12, 12), dtype=bool)
    nonzero[np.ix_(el.BENDING_Y_DOFS, el.BENDING_Z_DOFS)] = True
    nonzero[np.ix_(el.BENDING_Z_DOFS, el.BENDING_Y_DOFS)] = True
    assert np.all(g[~nonzero] == 0.0) and np.abs(g[nonzero]).max() > 0
    # a rigid lateral translation (v̇, ẇ uniform, no rotation rate) excites no gyroscopic force
    translation = np.zeros(12)
    translation[[1, 7]], translation[[2, 8]] = 0.3, -0.7
    np.testing.assert_allclose(g @ translation, 0.0, atol=1e-15 * np.abs(g).max())


def test_gyroscopic_moment_is_the_rate_of_spin_angular_momentum(drill_collar, length):
    """Tilting a spinning element rigidly about y at rate α̇ turns its spin angular momentum
    H = ρI_p L Ω n, n = (1, θz, −θy), so dH/dt = −ρI_p L Ω α̇ ẑ: the moment resultant about z of
    Ω G q̇ (its virtual power on a unit rigid rotation about z) must equal it, and symmetrically
    +ρI_p L Ω β̇ ŷ for a tilt about z. Also: the spin axis follows a torque (precession)."""
    g = el.element_gyroscopic(drill_collar, length)
    rho_ip_l = drill_collar.density * drill_collar.polar_moment * length
    about_y, about_z = _rigid_rotation_rates(length, "y"), _rigid_rotation_rates(length, "z")
    assert about_z @ g @ about_y == pytest.approx(-rho_ip_l, rel=1e-12)
    assert about_y @ g @ about_z == pytest.approx(rho_ip_l, rel=1e-12)
    np.testing.assert_allclose(g @ about_y @ about_y, 0.0, atol=1e-15 * rho_ip_l)
