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
    assert_equal_models(parametric.model(case), case_reduced_model(case))


def assert_equal_models(found, exact):
    """The parametric model ``found`` equals the rebuilt ``exact``: to round-off in its axial and torsional parts,
    to RITZ_TOLERANCE in its lateral modes and damping (module docstring)."""
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
    assert found.top_speed == exact.top_speed and found.base_speed == exact.base_speed
    assert found.top_drive == exact.top_drive


# The reference Sobol' design's laws (benchmarks/bench_sensitivity.py): weight-on-bit 70-130 kN, inlet velocity
# 1-2 m/s, top speed 60-140 rpm.
RPM = 2.0 * np.pi / 60.0
DESIGN = ((70e3, 130e3), (1.0, 2.0))


@pytest.fixture(scope="module")
def design_model(reference):
    return ParametricReducedModel(reference, *DESIGN[0], flow=DESIGN[1], speed=True)


def realized_row(case, weight_on_bit, inlet_velocity, top_speed):
    return with_parameters(case, {"operation.weight_on_bit": weight_on_bit, "fluid.inlet_velocity": inlet_velocity,
                                  "operation.top_speed": top_speed})


@pytest.mark.parametrize("row", [(83e3, 1.13, 70 * RPM), (121e3, 1.91, 133 * RPM), (100e3, 2.0, 60 * RPM),
                                 (70e3, 1.0, 140 * RPM)])
def test_inlet_velocity_and_top_speed_equal_the_rebuild(reference, design_model, row):
    """With the inlet velocity and the top speed parameters too (the Sobol' design's three controls), the model at
    rows across the design's box equals the rebuild, its generalised force scaled with the imposed speed. The
    fluid damping moves by ~1e-1 of itself across the flow's range and the generalised force by 2.3x across the
    speed's: a model that kept the nominal fluid matrices or force fails the damping or force check."""
    assert_equal_models(design_model.model(realized_row(reference, *row)),
                        case_reduced_model(realized_row(reference, *row)))


def test_the_fluid_matrices_move_with_the_inlet_velocity(reference, design_model):
    """The fluid damping and stiffness do change across the flow's range (so the test above checks the form):
    the damping's largest entry by more than 10 %, and the affine form equals a fresh assembly to round-off."""
    low, high = (design_model.system_at(100e3, u) for u in DESIGN[1])
    change = abs(high.fluid_damping - low.fluid_damping).max() / abs(low.fluid_damping).max()
    assert change > 0.1
    exact = case_reduced_model(realized_row(reference, 100e3, 1.7, reference.operation.top_speed)).system
    found = design_model.system_at(100e3, 1.7)
    for name in ("fluid_damping", "fluid_stiffness", "fluid_mass"):
        a, b = getattr(found, name), getattr(exact, name)
        assert abs(a - b).max() <= 1e-12 * abs(b).max(), name
    assert design_model.ritz_error <= RITZ_TOLERANCE


def test_short_simulation_at_another_flow_and_speed_equals_the_rebuild(reference, design_model):
    """2 s at a row off every snapshot, with another top speed (the spin, its damping torque and the bit's speed
    follow it): the drilling observables equal the rebuilt model's to 1e-6 of their range."""
    found, _, options = same_short_run(design_model, realized_row(reference, 108.7e3, 1.23, 117 * RPM))
    # and the speed did reach the run: the bit turns faster than at the case's 100 rpm
    slower = simulate_model(design_model.model(realized_row(reference, 108.7e3, 1.23, reference.operation.top_speed)),
                            **options)
    ratio = np.mean(found.observables["bit_speed"]) / np.mean(slower.observables["bit_speed"])
    assert ratio > 1.1


def test_a_flow_or_speed_not_covered_is_refused(reference, parametric):
    """The weight-on-bit model refuses another inlet velocity or top speed (it holds them at the case's); a flow
    range is refused where the mud's skin friction moves the statics."""
    w0 = reference.operation.weight_on_bit
    with pytest.raises(NotCovered, match="inlet_velocity"):
        parametric.model(realized_row(reference, w0, 1.6, reference.operation.top_speed))
    with pytest.raises(NotCovered, match="top_speed"):
        parametric.model(realized_row(reference, w0, reference.fluid.inlet_velocity, 90 * RPM))
    loaded = reference.model_copy(update={"fluid": reference.fluid.model_copy(update={"axial_loads": True})})
    with pytest.raises(NotCovered, match="axial_loads"):
        ParametricReducedModel(loaded, w0 - SPREAD, w0 + SPREAD, flow=(1.0, 2.0))
    with pytest.raises(ValueError, match="inlet velocity range"):
        ParametricReducedModel(reference, w0 - SPREAD, w0 + SPREAD, flow=(1.6, 2.0))


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
    found, exact, _ = same_short_run(parametric, realized(reference, 108.7e3))
    np.testing.assert_allclose(found.radial_displacement, exact.radial_displacement, rtol=0,
                               atol=1e-6 * np.abs(exact.radial_displacement).max())


def same_short_run(parametric, case):
    """2 s of ``case`` on the parametric model and on the rebuilt one, their drilling observables checked equal to
    1e-6 of their range; returns both results and the simulation's options."""
    options = dict(t_end=2.0, output_step=0.01, method=case.simulation.method, rtol=case.simulation.rtol,
                   atol=case.simulation.atol, lateral_perturbation=case.initial.lateral_perturbation,
                   seed=case.initial.seed)
    found = simulate_model(parametric.model(case), **options)
    exact = simulate_model(case_reduced_model(case), **options)
    for name in ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit"):
        a, b = found.observables[name], exact.observables[name]
        assert np.abs(a - b).max() <= 1e-6 * (np.abs(b).max() + 1e-30), name
    return found, exact, options


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
