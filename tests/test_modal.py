"""Modes against exact solutions (SPEC §10): the two-section bar in axial and torsional motion,
uniform Timoshenko beams, Euler (Engesser) buckling through K_g, fluid added mass."""

import math

import numpy as np
import pytest

from drillstring.fem.assembly import Stabilizer
from drillstring.fem.fluid import fluid_coefficients
from drillstring.fem.mesh import build_mesh
from drillstring.fem.sections import hollow_circle
from drillstring.modal import (
    build_linear_system, compute_modes, family_coupling, family_modes,
)
from drillstring.statics import solve_statics

from exact_solutions import (
    engesser_buckling_load, timoshenko_pinned_frequencies, two_section_rod_frequencies,
)

G = 9.81
DEFAULT_ELEMENT = 10.0  # m, the default mesh of the reference case
TOL = 0.005  # 0.5 % (issue #2)


def no_fluid(mesh):
    return [fluid_coefficients(s, 10.0, 0.0, 0.0, 0.0, 0.0) for s in mesh.sections]


def unloaded_system(mesh, stabilizers=(), fluid=None):
    static = solve_statics(mesh, [0.0] * len(mesh.sections), 0.0)
    return build_linear_system(mesh, static, list(stabilizers), fluid or no_fluid(mesh))


@pytest.fixture
def reference_bar(drill_pipe, drill_collar):
    mesh = build_mesh([1400.0, 200.0], [drill_pipe, drill_collar], DEFAULT_ELEMENT, [1560.0])
    return mesh, unloaded_system(mesh)


def test_axial_free_free_against_two_section_bar(reference_bar, drill_pipe, drill_collar):
    mesh, system = reference_bar
    c = math.sqrt(drill_pipe.young_modulus / drill_pipe.density)
    exact = two_section_rod_frequencies((1400.0, 200.0), (drill_pipe.area, drill_collar.area), c,
                                        "free", 5)
    np.testing.assert_allclose(exact, [0.0, 1.2006, 2.8767, 4.6601, exact[4]], atol=5e-5)  # SPEC
    fem = family_modes(system, "axial", 5).frequencies
    assert fem[0] == 0.0  # rigid axial mode
    np.testing.assert_allclose(fem[1:], exact[1:], rtol=TOL)


def test_axial_top_fixed_against_two_section_bar(reference_bar, drill_pipe, drill_collar):
    """SPEC §10 also quotes the hook-held bar (0.518, 2.012 Hz): remove the top axial DOF."""
    mesh, system = reference_bar
    c = math.sqrt(drill_pipe.young_modulus / drill_pipe.density)
    exact = two_section_rod_frequencies((1400.0, 200.0), (drill_pipe.area, drill_collar.area), c,
                                        "fixed", 4)
    np.testing.assert_allclose(exact[:2], [0.518, 2.012], atol=6e-4)
    import scipy.linalg as sla
    dofs = np.arange(1, mesh.n_nodes) * 6
    k = system.stiffness[dofs][:, dofs].toarray()
    m = system.mass[dofs][:, dofs].toarray()
    fem = np.sqrt(sla.eigh(k, m, eigvals_only=True, subset_by_index=[0, 3])) / (2 * math.pi)
    np.testing.assert_allclose(fem, exact, rtol=TOL)


def test_torsion_top_fixed_against_two_section_bar(reference_bar, drill_pipe, drill_collar):
    mesh, system = reference_bar
    c = math.sqrt(drill_pipe.shear_modulus / drill_pipe.density)
    exact = two_section_rod_frequencies(
        (1400.0, 200.0), (drill_pipe.polar_moment, drill_collar.polar_moment), c, "fixed", 4
    )
    np.testing.assert_allclose(exact[:3], [0.2313, 1.1978, 2.3191], atol=5e-5)  # SPEC §10
    fem = family_modes(system, "torsional", 4).frequencies
    np.testing.assert_allclose(fem, exact, rtol=TOL)


@pytest.mark.parametrize("length, shear_effect", [(2.0, (0.75, 0.85)), (40.0, (0.998, 1.0))])
def test_uniform_timoshenko_pinned_pinned(drill_collar, length, shear_effect):
    """Thick (L/D ≈ 9: shear and rotary inertia matter) and slender (L/D ≈ 175) pipes; ``shear_effect``
    bounds the 4th frequency over its Euler–Bernoulli value (0.807 and 0.9993 exactly)."""
    s = drill_collar
    exact = timoshenko_pinned_frequencies(4, length, s.bending_stiffness, s.mass_per_length,
                                          s.density * s.second_moment, s.shear_stiffness)
    errors = []
    for n_elements in (16, 32):
        system = unloaded_system(build_mesh([length], [drill_collar], length / n_elements))
        for family in ("lateral_y", "lateral_z"):
            fem = family_modes(system, family, 4).frequencies
            assert np.all(fem >= exact * (1 - 1e-9))  # consistent mass: upper bounds
        errors.append(np.abs(fem / exact - 1))
    np.testing.assert_allclose(fem, exact, rtol=TOL)
    # At least second-order mesh convergence of the 4th mode (fourth order in the slender limit).
    assert errors[0][3] / errors[1][3] > 3.5
    # Shear and rotary inertia lower the thick pipe's 4th frequency well below Euler–Bernoulli (the
    # elements capture it, not only the closed form); the slender pipe's stays within 0.2 % of it.
    euler = (4 * math.pi / length) ** 2 * math.sqrt(s.bending_stiffness / s.mass_per_length) / (2 * math.pi)
    low, high = shear_effect
    assert low < exact[3] / euler < high
    assert low < fem[3] / euler < high


@pytest.mark.parametrize("length", [10.0, 60.0])
def test_buckling_load_through_geometric_stiffness(drill_pipe, length):
    """Smallest P with det(K + K_g(N = −P)) = 0 for a pinned–pinned column equals Engesser's load."""
    import scipy.linalg as sla

    mesh = build_mesh([length], [drill_pipe], length / 20)
    system = unloaded_system(mesh)
    from drillstring.fem.assembly import geometric_stiffness
    from drillstring.modal import family_dofs

    dofs = family_dofs(mesh, "lateral_y")
    k = system.elastic_stiffness[dofs][:, dofs].toarray()
    kg_unit = geometric_stiffness(mesh, np.ones(mesh.n_nodes))[dofs][:, dofs].toarray()  # N = +1
    p_cr = sla.eigh(k, kg_unit, eigvals_only=True, subset_by_index=[0, 0])[0]
    s = drill_pipe
    assert p_cr == pytest.approx(engesser_buckling_load(length, s.bending_stiffness,
                                                         s.shear_stiffness), rel=TOL)


def test_tension_raises_and_compression_lowers_lateral_frequencies(drill_pipe):
    mesh = build_mesh([60.0], [drill_pipe], 3.0)
    base = family_modes(unloaded_system(mesh), "lateral_y", 1).frequencies[0]
    fluid = no_fluid(mesh)
    static = solve_statics(mesh, [0.0], 0.0)
    import dataclasses
    for n, cmp in ((5e4, np.greater), (-5e3, np.less)):
        pre = dataclasses.replace(static, axial_force=np.full(mesh.n_nodes, n))
        f = family_modes(build_linear_system(mesh, pre, [], fluid), "lateral_y", 1).frequencies[0]
        assert cmp(f, base)
        # Pinned string-beam: ω² = ω₀² (1 + N/P_E) for the first mode (EB limit, slender pipe).
        p_e = math.pi**2 * drill_pipe.bending_stiffness / 60.0**2
        assert (f / base) ** 2 == pytest.approx(1 + n / p_e, rel=3e-3)  # observed: 1e-5, 1.2e-3


def test_added_mass_lowers_frequencies_by_mass_ratio(drill_pipe):
    length = 60.0
    mesh = build_mesh([length], [drill_pipe], length / 16)
    dry = family_modes(unloaded_system(mesh), "lateral_y", 4).frequencies
    fluid = [fluid_coefficients(s, 0.3, 1200.0, 0.0, 0.0, 0.0) for s in mesh.sections]
    wet = family_modes(unloaded_system(mesh, fluid=fluid), "lateral_y", 4).frequencies
    s = drill_pipe
    m, m_f = s.mass_per_length, fluid[0].added_mass
    # Exact Timoshenko ratio, and the slender-beam limit sqrt(m / (m + m_f)).
    exact = timoshenko_pinned_frequencies(4, length, s.bending_stiffness, m,
                                          s.density * s.second_moment, s.shear_stiffness, m_f)
    np.testing.assert_allclose(wet, exact, rtol=TOL)
    np.testing.assert_allclose(wet / dry, math.sqrt(m / (m + m_f)), rtol=TOL)


def test_families_are_uncoupled_and_planes_degenerate(drill_pipe, drill_collar):
    mesh = build_mesh([1400.0, 200.0], [drill_pipe, drill_collar], 20.0, [1560.0])
    static = solve_statics(mesh, [s.mass_per_length * G for s in mesh.sections], 100e3)
    fluid = [fluid_coefficients(s, 0.3, 1200.0, 1.5 * drill_pipe.inner_area, 0.0125, 0.0)
             for s in mesh.sections]
    system = build_linear_system(mesh, static, [Stabilizer(1400.0, 17.5e6)], fluid)
    assert family_coupling(system) == 0.0
    modes = compute_modes(system, axial=3, torsional=3, lateral=6)
    np.testing.assert_allclose(modes.lateral_y.frequencies, modes.lateral_z.frequencies, rtol=1e-9)
    for fam in (modes.axial, modes.torsional, modes.lateral_y):
        gram = fam.shapes.T @ (system.mass @ fam.shapes)
        np.testing.assert_allclose(gram, np.eye(gram.shape[0]), atol=1e-8)
        assert np.all(np.diff(fam.frequencies) > 0)


# --- buckled strings: signed eigenvalues and growing linear modal response (issue 10) -----------------


def _reference_system(weight_on_bit):
    from drillstring.case import load_case
    from drillstring.modal import case_linear_system
    from drillstring.statics import case_static_state

    case = load_case("reference")
    return case_linear_system(case, case_static_state(case, weight_on_bit=weight_on_bit))


@pytest.mark.parametrize("wob", [100e3, 130e3, 300e3])
@pytest.mark.parametrize("dense_limit", [2500, 10])
def test_buckled_string_has_signed_negative_eigenvalues(wob, dense_limit, monkeypatch):
    """Above the critical load the lowest lateral ω² are negative, reported signed (ω < 0), equal to
    a direct dense solve, on the dense and the sparse (eigsh) paths; and by Sylvester's law of
    inertia their number is the number of buckling loads below wob (generalized problem
    K(0) φ = λ G φ, G the geometric stiffness of a unit tension)."""
    import scipy.linalg as sla

    from drillstring import modal
    from drillstring.fem.assembly import geometric_stiffness
    from drillstring.modal import family_dofs

    system = _reference_system(wob)
    dofs = family_dofs(system.mesh, "lateral_y")
    k = system.stiffness[dofs][:, dofs].toarray()
    exact = sla.eigh(k, system.mass[dofs][:, dofs].toarray(), eigvals_only=True)[:6]
    monkeypatch.setattr(modal, "DENSE_LIMIT", dense_limit)
    family = family_modes(system, "lateral_y", 6)
    np.testing.assert_allclose(family.eigenvalues, exact, rtol=1e-8, atol=1e-10)
    assert np.array_equal(np.sign(family.angular_frequencies), np.sign(exact))
    g = geometric_stiffness(system.mesh, np.ones(system.mesh.n_nodes))[dofs][:, dofs].toarray()
    mu = sla.eigh(g, k + wob * g, eigvals_only=True)  # K(0) = K(wob) + wob G
    loads = 1.0 / mu[mu > 1e-12]
    assert np.sum(loads < wob) == np.sum(exact < 0) == {100e3: 0, 130e3: 1, 300e3: 2}[wob]


def test_sparse_path_finds_strongly_unstable_modes(monkeypatch):
    from drillstring import modal

    """At 600 kN the reference string has three modes with ω² from −4.8 to −1.6 rad²/s²: the sparse path
    (shift-invert Lanczos) must shift below them all, not at −1 where it would return the three
    eigenvalues nearest −1."""
    system = _reference_system(600e3)
    dense = family_modes(system, "lateral_y", 5).eigenvalues
    assert np.sum(dense < -1.0) == 3
    monkeypatch.setattr(modal, "DENSE_LIMIT", 10)
    np.testing.assert_allclose(family_modes(system, "lateral_y", 5).eigenvalues, dense, rtol=1e-8)


@pytest.mark.parametrize("wob", [100e3, 600e3])
def test_count_below_is_the_number_of_eigenvalues_below_the_shift(wob):
    """Sylvester's inertia of K − σM (used to place the sparse solver's shift) against dense eigenvalues."""
    import scipy.linalg as sla

    from drillstring.modal import count_below, family_dofs

    system = _reference_system(wob)
    dofs = family_dofs(system.mesh, "lateral_y")
    k, m = system.stiffness[dofs][:, dofs], system.mass[dofs][:, dofs]
    exact = sla.eigh(k.toarray(), m.toarray(), eigvals_only=True)
    for sigma in (-10.0, -3.0, -1.0, -0.5, 0.0, 0.3, 5.0):
        assert count_below(k, m, sigma) == np.sum(exact < sigma)


def test_linear_modal_equations_grow_when_buckled():
    """The reduced linear lateral equations η̈ + (2ξ|ω| + ΦᵀC_fΦ) η̇ + ω² η = 0 (the reduced model's
    linear part, ξ = 0.3): above the critical load the state matrix has one real positive eigenvalue,
    |ω₁|(sqrt(1 + ξ²) − ξ) up to the small fluid damping, and a response started on the unstable
    mode grows at that rate; below it every solution decays."""
    import scipy.linalg as sla
    from scipy.integrate import solve_ivp

    xi = 0.3
    rates = {}
    for wob in (100e3, 130e3):
        system = _reference_system(wob)
        family = family_modes(system, "lateral_y", 8)
        omega2, phi = family.eigenvalues, family.shapes
        damping = phi.T @ (system.fluid_damping @ phi) + np.diag(2 * xi * np.abs(family.angular_frequencies))
        n = len(omega2)
        state = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(omega2), -damping]])
        eigenvalues = sla.eigvals(state)
        rates[wob] = eigenvalues.real.max()
        if wob == 100e3:
            assert rates[wob] < 0
            continue
        w1 = abs(family.angular_frequencies[0])
        assert omega2[0] < 0 and np.sum(eigenvalues.real > 0) == 1
        assert rates[wob] == pytest.approx(w1 * (math.sqrt(1 + xi**2) - xi), rel=0.05)
        y0 = np.zeros(2 * n)
        y0[0] = 1e-4
        t_end = 5.0 / rates[wob]
        sol = solve_ivp(lambda t, y: state @ y, (0.0, t_end), y0, rtol=1e-8, atol=1e-14)
        growth = sol.y[0, -1] / sol.y[0, 0]
        # after the fast decaying transient, the unstable mode dominates: η ∝ exp(λ t)
        assert growth > 50
        assert math.log(growth) == pytest.approx(rates[wob] * t_end, abs=1.0)



def test_the_dense_fallback_refuses_what_would_not_fit_before_allocating():
    """All 20,000 modes of a 20,000-DOF family would need a dense eigenproblem of 8.9 GiB: refused with that
    size (three n × n arrays), above the 2 GiB allowed, before anything is allocated."""
    import scipy.sparse as sp

    from drillstring import modal

    n = 20_000
    identity = sp.identity(n, format="csr")
    with pytest.raises(ValueError, match=r"20,000-DOF family .* would need 8\.9 GiB dense, more than the 2 GiB"):
        modal._eigen(identity, identity, n)
