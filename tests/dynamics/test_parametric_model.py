"""The parametric reduced model (dynamics/reduced/parametric.py) against the rebuilt model at the same
weight-on-bit: the independent computation is :func:`case_reduced_model` on the realized case (statics, linear
system and modes solved from scratch).

Tolerances: the statics are a linear problem, so the affine form equals a fresh solve to round-off (1e-12 of the
largest axial force); the axial and torsional families do not depend on the weight-on-bit, so their frequencies,
shapes and damping blocks equal the rebuild's to round-off (1e-12 relative); the lateral modes are Ritz
approximations on snapshots of the exact ones, which the build checks at the midpoints between snapshots to
RITZ_TOLERANCE (1e-7, relative eigenvalue and shape error); they are checked here at other points (quarter points
and off-grid weights), with the same bound. Dropping the geometric stiffness's change (the mutation of a model that
keeps the nominal lateral modes) gives lateral frequencies off by about 1e-3 at ±25 kN: every check below fails.
"""

from __future__ import annotations

import numpy as np
import pytest

from drillstring.case import load_case
from drillstring.dynamics.reduced.parametric import RITZ_TOLERANCE, NotCovered, ParametricReducedModel
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
from drillstring.statics import case_static_state
from drillstring.stochastic.parameters import with_parameters

SPREAD = 30e3  # the range: the reference weight-on-bit ± 30 kN (± 6 σ of the reference study's 5 kN)


@pytest.fixture(scope="module")
def reference():
    return load_case("reference")


@pytest.fixture(scope="module")
def parametric(reference):
    w0 = reference.operation.weight_on_bit
    return ParametricReducedModel(reference, w0 - SPREAD, w0 + SPREAD)


def realized(case, weight_on_bit):
    return with_parameters(case, {"operation.weight_on_bit": weight_on_bit})


def aligned(a, b):
    """``a``'s columns with the signs of ``b``'s (a mode's sign is a convention)."""
    return a * np.sign(np.einsum("ij,ij->j", a, b))


def test_statics_affine_in_the_weight_on_bit(reference, parametric):
    for w in (71e3, 88e3, 100e3, 117.5e3, 129e3):
        exact = case_static_state(reference, w)
        found = parametric.static_at(w)
        scale = np.abs(exact.axial_force).max()
        assert np.abs(found.axial_force - exact.axial_force).max() <= 1e-12 * scale
        assert np.abs(found.displacement - exact.displacement).max() <= 1e-12 * np.abs(exact.displacement).max()
        assert abs(found.weight_on_hook - exact.weight_on_hook) <= 1e-12 * scale


@pytest.mark.parametrize("weight_on_bit", [77.5e3, 92.5e3, 103e3, 122.5e3])
def test_reduced_matrices_equal_the_rebuild(reference, parametric, weight_on_bit):
    case = realized(reference, weight_on_bit)
    found = parametric.model(case)
    exact = case_reduced_model(case)
    assert found.family == exact.family
    lateral = np.isin(np.array(exact.family), ("lateral_y", "lateral_z"))
    fixed = ~lateral
    # axial and torsional: independent of the weight-on-bit, equal to round-off
    np.testing.assert_allclose(found.angular_frequencies[fixed], exact.angular_frequencies[fixed], rtol=1e-12)
    np.testing.assert_allclose(found.basis[:, fixed], exact.basis[:, fixed], rtol=0,
                               atol=1e-12 * np.abs(exact.basis).max())
    # lateral: Ritz approximations within the build's checked tolerance (from above in exact arithmetic; the
    # rebuild's own dense eigensolver rounds at ~1e-10 of the smallest values, so the bound is not tested)
    ritz, modes = found.omega2[lateral], exact.omega2[lateral]
    assert np.abs(ritz / modes - 1).max() <= RITZ_TOLERANCE
    signs = np.sign(np.einsum("ij,ij->j", found.basis, exact.basis))
    assert np.abs(found.basis * signs - exact.basis).max() <= RITZ_TOLERANCE * np.abs(exact.basis).max()
    # the reduced damping (structural + fluid), with the basis's signs, and the constant generalised force
    damping = found.damping * np.outer(signs, signs)
    scale = np.abs(exact.damping).max()
    assert np.abs(damping - exact.damping).max() <= RITZ_TOLERANCE * scale
    assert np.abs(damping[np.ix_(fixed, fixed)] - exact.damping[np.ix_(fixed, fixed)]).max() <= 1e-12 * scale
    np.testing.assert_allclose(found.generalized_force * signs, exact.generalized_force, rtol=0,
                               atol=1e-12 * np.abs(exact.generalized_force).max())
    assert found.weight_on_bit == exact.weight_on_bit
    assert found.lowest_lateral_eigenvalue == pytest.approx(exact.lowest_lateral_eigenvalue, rel=RITZ_TOLERANCE)


def test_eigenfrequencies_move_with_the_prestress(reference, parametric):
    """The lateral frequencies do move across the range (so the checks above test the parametric form, not a
    constant model): the first one by more than 100x the tolerance between the range's ends."""
    w0 = reference.operation.weight_on_bit
    low, high = (parametric.model(realized(reference, w)).angular_frequencies for w in (w0 - SPREAD, w0 + SPREAD))
    lateral = np.isin(np.array(parametric.nominal.family), ("lateral_y",))
    change = np.abs(high[lateral] / low[lateral] - 1).max()
    assert change > 100 * RITZ_TOLERANCE
    assert parametric.ritz_error <= RITZ_TOLERANCE


def test_short_simulation_equals_the_rebuild(reference, parametric):
    """2 s of the reference study's run at a weight-on-bit between snapshots: the drilling observables of the
    parametric model equal the rebuilt model's to 1e-6 of their range (the models differ by ~1e-9)."""
    case = realized(reference, 108.7e3)
    options = dict(t_end=2.0, output_step=0.01, method=case.simulation.method, rtol=case.simulation.rtol,
                   atol=case.simulation.atol, lateral_perturbation=case.initial.lateral_perturbation,
                   seed=case.initial.seed)
    found = simulate_model(parametric.model(case), **options)
    exact = simulate_model(case_reduced_model(case), **options)
    for name in ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit"):
        a, b = found.observables[name], exact.observables[name]
        assert np.abs(a - b).max() <= 1e-6 * (np.abs(b).max() + 1e-30), name
    np.testing.assert_allclose(found.radial_displacement, exact.radial_displacement, rtol=0,
                               atol=1e-6 * np.abs(exact.radial_displacement).max())


def test_outside_the_range_is_refused(reference, parametric):
    w0 = reference.operation.weight_on_bit
    with pytest.raises(NotCovered, match="outside the parametric model's range"):
        parametric.model(realized(reference, w0 + SPREAD + 1.0))


def test_cases_outside_the_form_are_refused(reference):
    w0 = reference.operation.weight_on_bit
    with pytest.raises(ValueError, match="range"):
        ParametricReducedModel(reference, w0 + 1.0, w0 + 2.0)
    motor = load_case("motor")
    with pytest.raises(NotCovered, match="motor"):
        ParametricReducedModel(motor, 0.5 * motor.operation.weight_on_bit, 1.5 * motor.operation.weight_on_bit)
    deviated = load_case("deviated")  # its statics are the stiff string's along the path, not the vertical ones
    with pytest.raises(NotCovered, match=r"\[well\]"):
        ParametricReducedModel(deviated, 0.5 * deviated.operation.weight_on_bit, 1.5 * deviated.operation.weight_on_bit)


def test_lateral_cutoff_count_follows_the_rebuild():
    """The contact case keeps every lateral mode below 1.5x the rotation frequency: their count changes with the
    weight-on-bit (82 or 83 per plane across ±20 %) and the parametric model keeps the rebuild's count, with its
    frequencies within the tolerance."""
    contact = load_case("contact")
    w0 = contact.operation.weight_on_bit
    parametric = ParametricReducedModel(contact, 0.8 * w0, 1.2 * w0)
    sizes = set()
    for w in (0.85 * w0, 1.13 * w0):
        case = realized(contact, w)
        found, exact = parametric.model(case), case_reduced_model(case)
        assert found.family == exact.family
        assert len(found.generalized_force) == len(found.family)
        moving = exact.omega2 != 0.0
        assert np.abs(found.omega2[moving] / exact.omega2[moving] - 1).max() <= RITZ_TOLERANCE
        sizes.add(len(found.family))
    assert len(sizes) == 2  # the count did change across the range
