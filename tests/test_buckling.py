"""Critical weight-on-bit against independent solutions: Euler/Engesser columns without gravity, the
heavy hanging column and the reference string by a compound-matrix shooting solution of the
column equation (tests/exact_solutions.py), and the sign of the lowest lateral eigenvalue."""

import math

import numpy as np
import pytest
from scipy import stats

from drillstring.buckling import (
    buckling_margin, buckling_probability, case_buckling_margin, critical_weight_on_bit,
)
from drillstring.case import load_case
from drillstring.fem.assembly import Stabilizer
from drillstring.fem.build import case_mesh
from drillstring.fem.fluid import fluid_coefficients
from drillstring.fem.mesh import build_mesh
from drillstring.modal import build_linear_system, case_linear_system
from drillstring.statics import case_static_state, solve_statics

from exact_solutions import engesser_buckling_load, heavy_column_critical_load

G = 9.81


def no_fluid(mesh):
    return [fluid_coefficients(s, 10.0, 0.0, 0.0, 0.0, 0.0) for s in mesh.sections]


def column_system(mesh, load_per_length, weight_on_bit=0.0, stabilizers=()):
    static = solve_statics(mesh, load_per_length, weight_on_bit)
    return build_linear_system(mesh, static, list(stabilizers), no_fluid(mesh))


def test_axial_force_is_affine_in_weight_on_bit(drill_pipe, drill_collar):
    """The premise of the direct eigen-solution: N(x; wob) = N(x; 0) − wob at every node."""
    mesh = build_mesh([1400.0, 200.0], [drill_pipe, drill_collar], 10.0)
    loads = [s.mass_per_length * G for s in mesh.sections]
    base = solve_statics(mesh, loads, 0.0).axial_force
    for wob in (1e3, 100e3, 800e3):
        np.testing.assert_allclose(solve_statics(mesh, loads, wob).axial_force, base - wob,
                                   rtol=0, atol=1e-9 * base[0])


@pytest.mark.parametrize("length", [10.0, 60.0])
def test_weightless_column_buckles_at_engesser_load(drill_pipe, length):
    """No gravity: N ≡ −wob, pinned–pinned, so wob_cr is Engesser's (shear-corrected Euler) load,
    approached from above at least at second order."""
    exact = engesser_buckling_load(length, drill_pipe.bending_stiffness, drill_pipe.shear_stiffness)
    errors = []
    for n_elements in (5, 10, 20):
        mesh = build_mesh([length], [drill_pipe], length / n_elements)
        critical = critical_weight_on_bit(column_system(mesh, [0.0]))
        assert critical >= exact * (1 - 1e-12)
        errors.append(critical / exact - 1)
    assert errors[-1] < 1e-4
    assert errors[0] / errors[1] > 3.5 and errors[1] / errors[2] > 3.5


@pytest.mark.parametrize("length", [200.0, 600.0])
def test_heavy_column_against_shooting_solution(drill_collar, length):
    """A uniform drill collar hanging from a pin at the top, pinned at the bit, under its own weight:
    the FE critical load converges to the shooting solution of (EI w'')'' − (N w')' = 0,
    N(x) = q (L − x) − wob. L = 200 m and 600 m are 9.3 and 28 times (EI/q)^{1/3}."""
    s = drill_collar
    q = s.mass_per_length * G
    exact = heavy_column_critical_load([(length, s.bending_stiffness, q, 0.0)],
                                       search_max=3.0 * (s.bending_stiffness * q**2) ** (1 / 3),
                                       n_grid=4)
    errors = []
    for element in (20.0, 10.0, 5.0):
        mesh = build_mesh([length], [s], element)
        errors.append(critical_weight_on_bit(column_system(mesh, [q])) / exact - 1)
    # FE (Timoshenko) is stiffer than the exact Euler–Bernoulli column by its discretisation error,
    # and softer by the shear flexibility, P/(k_s G A) ≈ 5e-5 here.
    assert errors[0] > 8 * errors[1] > 0
    assert abs(errors[2]) < 2e-5
    # Dimensionless load W/(q m), m = (EI/q)^{1/3} (Lubinski's unit): 1.890 and 1.653, decreasing
    # (slowly) with the length of the tension zone above; Lubinski's first-order value is 1.94.
    m = (s.bending_stiffness / q) ** (1 / 3)
    expected = {200.0: 1.8900, 600.0: 1.6531}[length]
    assert exact / (q * m) == pytest.approx(expected, abs=2e-4)


def test_reference_case_against_shooting_solution():
    """The whole reference string: drill pipe over drill collar, stabilizer spring at 1400 m,
    fluid centrifugal compression p = ρ_f A_i U_i² + χ ρ_f A_o U_o² per section, no buoyancy."""
    case = load_case("reference")
    rho, rho_f, e = 7850.0, 1200.0, 210e9
    flow = 1.5 * math.pi / 4 * 0.095**2
    segments = []
    for length, d_o, d_i in ((1400.0, 0.127, 0.095), (200.0, 0.2286, 0.0762)):
        a_o, a_i = math.pi / 4 * d_o**2, math.pi / 4 * d_i**2
        u_i, u_o = flow / a_i, flow / (math.pi / 4 * (0.3**2 - d_o**2))
        chi = (0.3**2 + d_o**2) / (0.3**2 - d_o**2)
        p = rho_f * a_i * u_i**2 + chi * rho_f * a_o * u_o**2
        segments.append((length, e * math.pi / 64 * (d_o**4 - d_i**4), rho * G * (a_o - a_i), p))
    exact = heavy_column_critical_load(segments, springs=((1400.0, 17.5e6),), search_max=3e5,
                                       n_grid=4)
    assert exact == pytest.approx(114.108e3, rel=1e-5)  # the shooting value itself, for the record
    default = case_buckling_margin(case).critical_weight_on_bit  # 10 m elements
    fine = critical_weight_on_bit(case_linear_system(case, case_static_state(case, mesh=case_mesh(case, 5.0))))
    assert default == pytest.approx(exact, rel=5e-4)
    assert fine == pytest.approx(exact, rel=1e-4)
    assert abs(fine - exact) < abs(default - exact)


def test_result_does_not_depend_on_the_state_it_is_computed_from():
    """Same wob_cr from a stable state, a buckled state (reference moved by a pull), dense or sparse."""
    case = load_case("reference")
    values = []
    for wob in (0.0, 100e3, 130e3, 600e3):
        system = case_linear_system(case, case_static_state(case, weight_on_bit=wob))
        values.append(critical_weight_on_bit(system))
    values.append(critical_weight_on_bit(system, dense_limit=0))
    np.testing.assert_allclose(values, values[0], rtol=1e-9)


def test_lowest_lateral_eigenvalue_sign_and_buoyancy():
    case = load_case("reference")
    margin = case_buckling_margin(case)
    assert margin.weight_on_bit == 100e3 and not margin.buckled
    assert margin.lowest_lateral_eigenvalue == pytest.approx((2 * math.pi * 0.0215) ** 2, rel=0.01)
    assert margin.margin == pytest.approx(margin.critical_weight_on_bit - 100e3)
    assert margin.critical_weight_on_hook == pytest.approx(case.weight - margin.critical_weight_on_bit,
                                                           rel=1e-12)
    critical = margin.critical_weight_on_bit
    for wob, buckled in ((critical - 500.0, False), (critical + 500.0, True), (130e3, True)):
        m = case_buckling_margin(case, case_static_state(case, weight_on_bit=wob))
        assert m.buckled is buckled
        assert m.critical_weight_on_bit == pytest.approx(critical, rel=1e-9)
    # The buckling mode is a bow of the lower collar: largest between the stabilizer and the bit.
    x = case_mesh(case).nodes
    lateral = margin.mode[6 * np.arange(len(x)) + 1]
    assert 1400.0 < x[np.argmax(np.abs(lateral))] < 1600.0
    # Buoyancy lightens the collar: q → q (1 − ρ_f/ρ), and wob_cr ≈ ∝ (EI q²)^{1/3}.
    buoyant = case.model_copy(update={"model": case.model.model_copy(update={"buoyancy": True})})
    ratio = case_buckling_margin(buoyant).critical_weight_on_bit / critical
    assert ratio == pytest.approx((1 - 1200 / 7850) ** (2 / 3), rel=0.02)


def test_stabilizer_raises_the_critical_load(drill_collar):
    mesh = build_mesh([400.0], [drill_collar], 10.0, [300.0])
    q = [drill_collar.mass_per_length * G]
    free = critical_weight_on_bit(column_system(mesh, q))
    held = critical_weight_on_bit(column_system(mesh, q, stabilizers=[Stabilizer(300.0, 17.5e6)]))
    assert held > 1.05 * free


def test_buckling_probability_normal_law():
    """P(wob > wob_cr) for a Normal weight-on-hook, also through the study's MaxEnt law."""
    from drillstring.stochastic.maxent import maximum_entropy, variance_constraints

    weight, critical, mean, sigma = 1.1634e6, 114.13e3, 1.0634e6, 5000.0
    expected = stats.norm.cdf((weight - critical - mean) / sigma)
    law = stats.norm(mean, sigma)
    assert buckling_probability(law, weight, critical) == pytest.approx(expected, rel=1e-12)
    assert buckling_probability(maximum_entropy((-math.inf, math.inf), variance_constraints(mean, sigma)),
                                weight, critical) == (
        pytest.approx(expected, rel=1e-3))
    assert 1 / 500 < expected < 1 / 300  # "about one realization in 500" (issue 10): 1 in 425
    assert buckling_probability(law, weight, math.inf) == 0.0
    with pytest.raises(ValueError, match="critical_weight_on_bit"):
        buckling_probability(law, weight, math.nan)


def test_case_margin_matches_system_margin():
    case = load_case("reference")
    static = case_static_state(case)
    a = case_buckling_margin(case, static)
    b = buckling_margin(case_linear_system(case, static))
    assert a.critical_weight_on_bit == b.critical_weight_on_bit
    assert a.lowest_lateral_eigenvalue == b.lowest_lateral_eigenvalue
