"""Case 1 (full nonlinear model) in the reduced-order model: compiled vs reference right-hand side,
and conservation of the Jacobi integral of the undamped, unforced system over many periods."""

import dataclasses

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model, reduced_model
from drillstring.dynamics.runge_kutta import integrate
from drillstring.fem.assembly import THETA_X, dof
from drillstring.fem.build import section_fluid_coefficients, stabilizers
from drillstring.forces.bit_rock import BitRockParameters
from drillstring.forces.contact import ContactParameters
from drillstring.modal import build_linear_system
from drillstring.statics import case_static_state


@pytest.fixture(scope="module")
def short_case():
    """60 m of pipe over 20 m of collars on 5 m elements: centimetre lateral motion over metres-long
    waves gives slopes ~1e-2, where the nonlinear energies are a visible part of the total."""
    from drillstring.case import load_case

    case = load_case("reference")
    sections = [case.sections[0].model_copy(update={"length": 60.0}),
                case.sections[1].model_copy(update={"length": 20.0})]
    return case.model_copy(update={
        "sections": sections,
        "stabilizers": [case.stabilizers[0].model_copy(update={"position": 60.0})],
        "mesh": case.mesh.model_copy(update={"max_element_length": 5.0, "probes": [70.0]}),
        "operation": case.operation.model_copy(update={"weight_on_bit": 20e3}),
    })


def large_state(rom, rng, lateral=0.03, other=1e-4):
    """Lateral displacements of a few cm (with velocities), small axial and torsional motion."""
    n = rom.size
    labels = np.array(rom.family)
    lateral_modes = np.char.startswith(labels, "lateral")
    y = np.zeros(2 * n)
    for part in (slice(0, n), slice(n, 2 * n)):
        values = rng.normal(size=n)
        values[lateral_modes] *= lateral / np.abs(rom.phi_v[:, lateral_modes[: n]]).max(initial=1e-12)
        values[~lateral_modes] *= other * 100
        y[part] = values
    return y


def test_compiled_full_rhs_equals_reference(short_case):
    rom = case_reduced_model(short_case, axial_modes=3, torsional_modes=3, lateral_modes=5,
                             nonlinear="full")
    case2 = case_reduced_model(short_case, axial_modes=3, torsional_modes=3, lateral_modes=5)
    y = large_state(rom, np.random.default_rng(4))
    fast, slow = rom.rhs(0.0, y), rom.rhs_reference(0.0, y)
    np.testing.assert_allclose(fast, slow, rtol=1e-9, atol=1e-9 * np.abs(slow).max())
    # ... and the nonlinear forces really contribute at this amplitude.
    difference = np.abs(fast - case2.rhs(0.0, y)).max()
    assert difference > 1e-3 * np.abs(fast[rom.size:]).max()


def test_generalized_force_goes_through_the_nonlinear_mass(short_case):
    """Case 1 solves (I + Φᵀ M_nl(Φη) Φ) η̈ = … + g: at η = 0 the mass is I and g adds to η̈ as is;
    elsewhere compiled and reference right-hand sides still agree with g."""
    rom = case_reduced_model(short_case, axial_modes=3, torsional_modes=3, lateral_modes=5,
                             nonlinear="full")
    force = np.random.default_rng(8).normal(size=rom.size)
    forced = dataclasses.replace(rom, generalized_force=rom.generalized_force + force)
    y = large_state(rom, np.random.default_rng(9))
    at_rest_shape = y.copy()
    at_rest_shape[: rom.size] = 0.0
    difference = forced.rhs(0.0, at_rest_shape) - rom.rhs(0.0, at_rest_shape)
    np.testing.assert_allclose(difference[rom.size:], force, rtol=1e-9, atol=1e-9)
    fast, slow = forced.rhs(0.0, y), forced.rhs_reference(0.0, y)
    np.testing.assert_allclose(fast, slow, rtol=1e-9, atol=1e-9 * np.abs(slow).max())
    shifted = forced.rhs(0.0, y) - rom.rhs(0.0, y)
    assert np.abs(shifted[rom.size:] - force).max() > 1e-6 * np.abs(force).max()  # M_nl ≠ 0 here


def conservative_full_model(case, top_speed):
    static = dataclasses.replace(case_static_state(case), weight_on_bit=0.0)
    fluid_case = case.model_copy(update={"fluid": case.fluid.model_copy(
        update={"coriolis": False, "viscous_damping": False})})
    system = build_linear_system(static.mesh, static, stabilizers(case),
                                 section_fluid_coefficients(fluid_case, static.mesh))
    return reduced_model(
        static, system, axial_modes=3, torsional_modes=3, lateral_modes=4, modal_damping_ratio=0.0,
        rigid_axial_damping=0.0, top_speed=top_speed,
        bit_rock=BitRockParameters(0.0, 1e40, 0.0, 0.0, 0.0, 2.0),
        contact=ContactParameters(0.0, 0.0, 0.1, False), borehole_diameter=case.borehole.diameter,
        nonlinear="full",
    )


def jacobi_integral(rom, y):
    """h = ½η̇ᵀη̇ + ½Σω²η² + U_nl(Φη) + T_nl(Φη, Φη̇) with the spin Ω left out of T_nl: the
    imposed rotation makes the Lagrangian autonomous, so h is conserved (terms linear in the
    relative velocities, the gyroscopic ones, do not enter h)."""
    n = rom.size
    q = rom.basis @ y[:n]
    qd = rom.basis @ y[n:]
    return (rom.energy(y) + rom.elements.strain_energy(q)
            + rom.elements.kinetic_energy_nl(q, qd))


def test_full_model_conserves_its_jacobi_integral(short_case):
    rom = conservative_full_model(short_case, top_speed=10.0)
    rng = np.random.default_rng(1)
    y0 = large_state(rom, rng)
    y0[0] = 0.0
    q = rom.basis @ y0[: rom.size]
    # Nonlinear energies are a visible part of the total.
    assert abs(rom.elements.strain_energy(q)) > 1e-3 * rom.energy(y0)
    periods = 2 * np.pi / np.sort(rom.angular_frequencies[rom.angular_frequencies > 0])
    t_end = 5 * periods[len(periods) // 2]  # 5 periods of the median mode, ~150 of the fastest
    sol = integrate(rom.rhs, (0.0, t_end), y0, output_step=t_end / 40, rtol=1e-9, atol=1e-12,
                    observe=lambda t, y: np.array([jacobi_integral(rom, y), rom.energy(y)]))
    h = sol.y[:, 0]
    drift = np.abs(h / h[0] - 1).max()
    assert drift < 1e-5, drift  # measured 2e-6 at rtol 1e-9 (2e-7 at rtol 1e-10)
    # The linear energy alone is NOT conserved: energy flows through the nonlinear terms.
    linear = sol.y[:, 1]
    assert np.abs(linear / linear[0] - 1).max() > 100 * drift


def test_case_switch_comes_from_the_case(coarse_case):
    full = coarse_case.model_copy(update={"model": coarse_case.model.model_copy(
        update={"nonlinear": "full"})})
    assert case_reduced_model(full, lateral_modes=2).nonlinear == "full"
    assert case_reduced_model(coarse_case, lateral_modes=2).nonlinear == "bit_and_contact"
    with pytest.raises(ValueError, match="nonlinear"):
        case_reduced_model(coarse_case, lateral_modes=2, nonlinear="everything")


def test_cholesky_solve_of_the_nonlinear_mass():
    """The compiled solve of (I + Φᵀ M_nl Φ) η̈ = …: equal to LAPACK's on a positive definite matrix; NaN
    (a rejected step for the integrator) when the matrix is not positive definite."""
    from drillstring.dynamics.rom import _cholesky_solve

    rng = np.random.default_rng(1)
    n = 30
    m = rng.normal(size=(n, n)) * 0.3
    a = np.eye(n) + m @ m.T
    b = rng.normal(size=n)
    x = np.zeros(n)
    _cholesky_solve(a.copy(), b, x)
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-12, atol=1e-12)
    indefinite = np.eye(n)
    indefinite[3, 3] = -1.0
    _cholesky_solve(indefinite, b, x)
    assert np.all(np.isnan(x))
