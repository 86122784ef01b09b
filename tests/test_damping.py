"""Damping defined on the free–free modes (SPEC §7): ξ, c1 and c2 recovered on the unconstrained bar and
rod, the first top-held torsional mode against the full unreduced system and a closed-form series,
the reduced model's blocks, and the earlier ("constrained") definition kept as an option."""

import math

import numpy as np
import pytest

from drillstring.damping import free_free_damping, projected_free_free_damping, reduced_structural_damping
from drillstring.dynamics.rom import case_reduced_model
from drillstring.fem.assembly import THETA_X, U, dof
from drillstring.fem.fluid import fluid_coefficients
from drillstring.fem.mesh import build_mesh
from drillstring.modal import build_linear_system, family_modes
from drillstring.statics import solve_statics

from exact_solutions import free_free_damping_on_first_fixed_free_mode

XI = 0.3
POISSON = 0.29
LENGTH = 1000.0  # m, uniform drill pipe


@pytest.fixture(scope="module")
def uniform_string():
    from drillstring.fem.sections import hollow_circle

    pipe = hollow_circle(0.127, 0.095, 210e9, 7850.0, POISSON, 6.0 / 7.0)
    mesh = build_mesh([LENGTH], [pipe], 10.0)
    static = solve_statics(mesh, [0.0], 0.0)
    fluid = [fluid_coefficients(s, 10.0, 0.0, 0.0, 0.0, 0.0) for s in mesh.sections]
    return pipe, mesh, build_linear_system(mesh, static, [], fluid)


def _family_matrices(system, kind):
    dofs = dof(np.arange(system.mesh.n_nodes), kind)
    return system.mass[dofs][:, dofs].toarray(), system.stiffness[dofs][:, dofs].toarray()


def _state_eigenvalues(m, c, k):
    """Eigenvalues of M q̈ + C q̇ + K q = 0 (first-order form), an independent check of C."""
    n = m.shape[0]
    a = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(m, k), -np.linalg.solve(m, c)]])
    return np.linalg.eigvals(a)


@pytest.mark.parametrize("kind, coefficient", [(U, 2.0e4), (THETA_X, 50.0)])
def test_free_free_bar_and_rod_recover_xi_and_rigid_coefficient(uniform_string, kind, coefficient):
    """Every elastic mode of the unconstrained uniform bar (axial) and rod (torsion) has the ratio ξ,
    the rigid motion decays at c/m with m the closed-form mass ρAL (or inertia ρI_pL), and the
    frequencies are the exact kπc/L of the free–free rod."""
    pipe, mesh, system = uniform_string
    m, k = _family_matrices(system, kind)
    damping = free_free_damping(m, k, XI, coefficient)
    c = damping.matrix
    np.testing.assert_allclose(c, c.T, atol=0)
    lam = _state_eigenvalues(m, c, k)
    oscillating = lam[lam.imag > 1e-9]
    oscillating = oscillating[np.argsort(np.abs(oscillating))]
    ratios = -oscillating.real / np.abs(oscillating)
    np.testing.assert_allclose(ratios, XI, rtol=1e-8)  # every elastic mode of the FE model
    if kind == U:
        rigid_mass, wave_speed = pipe.density * pipe.area * LENGTH, math.sqrt(pipe.young_modulus / pipe.density)
    else:
        shear_modulus = pipe.young_modulus / (2.0 * (1.0 + POISSON))
        rigid_mass = pipe.density * pipe.polar_moment * LENGTH
        wave_speed = math.sqrt(shear_modulus / pipe.density)
    assert damping.rigid_mass == pytest.approx(rigid_mass, rel=1e-12)
    real = np.sort(lam[np.abs(lam.imag) <= 1e-9].real)
    assert real[0] == pytest.approx(-coefficient / rigid_mass, rel=1e-8)  # rigid velocity decays at c/m
    assert abs(real[1]) < 1e-8  # rigid position: indifferent
    exact = np.arange(1, 5) * math.pi * wave_speed / LENGTH
    np.testing.assert_allclose(np.abs(oscillating[:4]), exact, rtol=2e-3)


def test_free_free_damping_refuses_a_constrained_family(uniform_string):
    _, _, system = uniform_string
    m, k = _family_matrices(system, THETA_X)
    with pytest.raises(ValueError, match="no rigid mode"):
        free_free_damping(m[1:, 1:], k[1:, 1:], XI, 1.0)


def _top_held_torsion(system, count):
    modes = family_modes(system, "torsional", count)
    reduced = reduced_structural_damping(
        system.mass, system.stiffness, modes.shapes, ["torsional"] * count, modes.angular_frequencies,
        damping_ratio=XI, rigid_axial=0.0, rigid_rotation=50.0, top_speed=10.0, definition="free_free",
    )
    return modes, reduced


def test_first_top_held_torsional_mode_against_full_system(uniform_string):
    """The ratio of the first top-held mode of the reduced model (10 modes, dense damping block)
    equals the complex eigenvalue of the full, unreduced FE system with the top held."""
    _, _, system = uniform_string
    m, k = _family_matrices(system, THETA_X)
    c = free_free_damping(m, k, XI, 50.0).matrix
    lam = _state_eigenvalues(m[1:, 1:], c[1:, 1:], k[1:, 1:])
    lam = lam[lam.imag > 0]
    first = lam[np.argmin(np.abs(lam))]
    full_ratio = -first.real / abs(first)

    modes, reduced = _top_held_torsion(system, 10)
    n = 10
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(modes.angular_frequencies**2), -reduced.matrix]])
    lam_r = np.linalg.eigvals(a)
    lam_r = lam_r[lam_r.imag > 0]
    first_r = lam_r[np.argmin(np.abs(lam_r))]
    assert -first_r.real / abs(first_r) == pytest.approx(full_ratio, rel=1e-3)
    assert 0.1 < full_ratio < 0.2  # far below ξ = 0.3: the mode is mostly a rigid rotation


def test_first_top_held_mode_projection_against_closed_form_series(uniform_string):
    """ψ₁ᵀCψ₁/(2ω₁) of the uniform rod equals Σ c_k a_k²/(2ω₁) over the exact free–free modes
    (a_k = ∫ρI_p ψ₁ φ_k, closed form in exact_solutions), converging with the mesh."""
    pipe, mesh, system = uniform_string
    modes, reduced = _top_held_torsion(system, 3)
    shear_modulus = pipe.young_modulus / (2.0 * (1.0 + POISSON))
    exact = free_free_damping_on_first_fixed_free_mode(
        XI, 50.0, pipe.density * pipe.polar_moment * LENGTH, math.sqrt(shear_modulus / pipe.density), LENGTH
    )
    fem = reduced.matrix[0, 0] / (2.0 * modes.angular_frequencies[0])
    assert fem == pytest.approx(exact, rel=5e-4)


def test_torsional_generalized_force_is_the_rigid_rotation_friction(uniform_string):
    """The imposed top speed Ω loads the top-held modes with −Ω Ψᵀ C 1 = −(c2 Ω / J) Ψᵀ M 1."""
    _, mesh, system = uniform_string
    modes, reduced = _top_held_torsion(system, 4)
    dofs = dof(np.arange(mesh.n_nodes), THETA_X)
    m = system.mass[dofs][:, dofs].toarray()
    inertia = m.sum()
    expected = -(50.0 * 10.0 / inertia) * (modes.shapes[dofs].T @ (m @ np.ones(len(dofs))))
    np.testing.assert_allclose(reduced.generalized_force, expected, rtol=1e-8, atol=1e-14)


def test_reduced_model_blocks(reference_case):
    """Free–free: the axial block is diagonal (the ROM's axial basis is free–free), 2ξω and c1/m; the
    torsional block is dense with a first-mode ratio ≈ 0.088; lateral modes keep 2ξ|ω|.
    Constrained: 2ξω on every elastic mode, c1/m on the rigid one, no generalised force."""
    model = case_reduced_model(reference_case)
    fluid = model.basis.T @ (model.system.fluid_damping @ model.basis)
    structural = model.damping - fluid
    labels = np.array(model.family)
    omega = model.angular_frequencies
    axial = np.isin(labels, ["rigid_axial", "axial"])
    block = structural[np.ix_(axial, axial)]
    string_mass = reference_case.weight / reference_case.environment.gravity
    expected = np.where(labels[axial] == "rigid_axial", reference_case.damping.rigid_axial / string_mass,
                        2 * XI * omega[axial])
    np.testing.assert_allclose(block, np.diag(expected), atol=1e-9 * expected.max())
    torsion = labels == "torsional"
    ratios = np.diag(structural)[torsion] / (2 * omega[torsion])
    assert 0.07 < ratios[0] < 0.1
    assert np.all(ratios < XI)
    lateral = np.char.startswith(labels, "lateral")
    np.testing.assert_allclose(np.diag(structural)[lateral], 2 * XI * np.abs(omega[lateral]), rtol=1e-12)
    assert np.all(model.generalized_force[~torsion] == 0) and np.all(model.generalized_force[torsion] != 0)

    constrained = reference_case.model_copy(
        update={"damping": reference_case.damping.model_copy(update={"basis": "constrained"})})
    old = case_reduced_model(constrained)
    old_structural = old.damping - fluid
    elastic = np.where(labels == "rigid_axial", reference_case.damping.rigid_axial / string_mass,
                       2 * XI * np.abs(omega))
    np.testing.assert_allclose(old_structural, np.diag(elastic), atol=1e-12)
    assert not old.generalized_force.any()


def test_unknown_damping_basis_is_refused(uniform_string):
    _, _, system = uniform_string
    modes = family_modes(system, "torsional", 2)
    with pytest.raises(ValueError, match="damping basis"):
        reduced_structural_damping(system.mass, system.stiffness, modes.shapes, ["torsional"] * 2,
                                   modes.angular_frequencies, damping_ratio=XI, rigid_axial=0.0,
                                   rigid_rotation=0.0, top_speed=1.0, definition="modal")


@pytest.mark.parametrize("kind, family, coefficient", [(U, "axial", 2.0e4), (THETA_X, "torsional", 50.0)])
def test_projection_without_modes_equals_the_dense_one(uniform_string, kind, family, coefficient):
    """The projection of long families (no mode and no C formed: the quadrature of eq. (2), forced here
    with dense_limit=0) equals the dense one built from every free–free mode, on the free–free axial
    basis (rigid mode included) and on the top-held torsional basis."""
    _, mesh, system = uniform_string
    dofs = dof(np.arange(mesh.n_nodes), kind)
    m, k = system.mass[dofs][:, dofs], system.stiffness[dofs][:, dofs]
    shapes = family_modes(system, family, 6).shapes[dofs]
    dense, dense_force = projected_free_free_damping(m, k, shapes, XI, coefficient)
    sparse, sparse_force = projected_free_free_damping(m, k, shapes, XI, coefficient, dense_limit=0)
    np.testing.assert_allclose(sparse, dense, rtol=0, atol=1e-11 * np.abs(dense).max())
    np.testing.assert_allclose(sparse_force, dense_force, rtol=0, atol=1e-10 * np.abs(dense_force).max())
    with pytest.raises(ValueError, match="no rigid mode"):
        projected_free_free_damping(m[1:, 1:], k[1:, 1:], shapes[1:], XI, coefficient, dense_limit=0)


def test_rayleigh_damping_on_the_modes_and_the_imposed_rotation(uniform_string):
    """Rayleigh damping α M + β K (issue 25): on the mass-normalised top-held torsional modes it is diagonal,
    α + β ω², i.e. the ratio ξ(ω) = α/(2ω) + βω/2 of each mode; it adds to the other definitions; with the top
    turned at Ω the mass-proportional part loads the modes with −Ω α Ψᵀ M 1 (the viscous torque α ρ I_p Ω per
    unit length of the rigidly turning string); α alone on a uniform rod, the first top-held mode decays
    at exactly α/2 (the damped wave equation ρ(ü + α u̇) = G u'': s² + α s + ω² = 0)."""
    _, mesh, system = uniform_string
    modes, _ = _top_held_torsion(system, 4)
    dofs = dof(np.arange(mesh.n_nodes), THETA_X)
    basis = np.zeros((mesh.n_dofs, 4))
    basis[dofs[1:]] = modes.shapes[dofs[1:]]
    omega = modes.angular_frequencies
    alpha, beta = 0.7, 2e-3
    common = dict(damping_ratio=0.0, rigid_axial=0.0, rigid_rotation=0.0, top_speed=10.0, definition="constrained")
    damped = reduced_structural_damping(system.mass, system.stiffness, basis, ["torsional"] * 4, omega,
                                        rayleigh=(alpha, beta), **common)
    np.testing.assert_allclose(damped.matrix, np.diag(alpha + beta * omega**2), rtol=1e-9, atol=1e-9)
    m = system.mass[dofs][:, dofs].toarray()
    expected = -10.0 * alpha * (modes.shapes[dofs].T @ (m @ np.ones(len(dofs))))
    np.testing.assert_allclose(damped.generalized_force, expected, rtol=1e-8, atol=1e-12)
    plus = reduced_structural_damping(system.mass, system.stiffness, basis, ["torsional"] * 4, omega,
                                      rayleigh=(alpha, beta), **{**common, "damping_ratio": XI})
    np.testing.assert_allclose(plus.matrix, damped.matrix + np.diag(2 * XI * omega), rtol=1e-9, atol=1e-9)
    viscous = reduced_structural_damping(system.mass, system.stiffness, basis, ["torsional"] * 4, omega,
                                         rayleigh=(alpha, 0.0), **common)
    lam = np.linalg.eigvals(np.block([[np.zeros((4, 4)), np.eye(4)], [-np.diag(omega**2), -viscous.matrix]]))
    np.testing.assert_allclose(lam.real, -alpha / 2, rtol=1e-9)
    with pytest.raises(ValueError, match="alpha .* and beta .* must be finite and >= 0"):
        reduced_structural_damping(system.mass, system.stiffness, basis, ["torsional"] * 4, omega,
                                   rayleigh=(-1.0, 0.0), **common)
