"""The reduced model of a deviated case against a full finite-element time integration, no modal reduction
(issue 34, "Must show"; the integrator: tests/dynamics/full_fe_reference.py, written apart from the reduced
model's code).

The ``deviated`` case on a coarse mesh (50 m elements, 65 nodes), started on bottom (the bit–rock law switched on at
t = 0 with the string turning at 120 rpm and twisted by the wall's friction: over the first second the bit slows
from 12.6 to 2.8 rad/s, the force on bit goes from the law's 29.6 kN at rest axially to 79.5 kN, the surface torque
from 18.8 to 21.3 kN·m), its along-string Coulomb friction at the 54 nodes on the wall. With every axial and
torsional mode of the mesh the reduced model solves the same equations as the full integration, so their difference
over 1 s is the two integrators' (measured: 2.5e-11 for the surface torque, 4e-10 for the bit speed, 1.1e-7 for the
force on bit, of each signal's largest value, the reduced model's implicit-explicit steps at rtol 1e-7 against Radau
at rtol 1e-8: the full integration differs from itself at rtol 1e-10 by 1.1e-9 at most); the bound is 2e-6. Two
wrong reduced models exceed it: the highest torsional mode left out (a truncation: 1.3e-4 in the bit speed), and the
friction stations moved one node up (a wrong projection of the nodal friction: 2.5e-5 in the surface torque, 5.6e-4
in the force on bit). No lateral DOF on either side: the straight string's lateral modes touch the axial and
torsional ones only through the wall's contact, and in this record no node reaches the wall
(benchmarks/full_fe_convergence.py: with the case's lateral modes and perturbation, 0 nodes in contact).
"""

import dataclasses

import numpy as np
import pytest
from full_fe_reference import full_fe_model, integrate

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
from drillstring.forces.string_friction import FrictionStations

#: The record [s], its output step [s] and the bound on the relative differences.
T_END, OUTPUT_STEP, BOUND = 1.0, 0.01, 2e-6
COMPARED = ("bit_speed", "surface_torque", "force_on_bit")


def _case():
    case = load_case("deviated")
    return case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
                                   "initial": case.initial.model_copy(update={"start": "on_bottom"})})


@pytest.fixture(scope="module")
def full():
    case = _case()
    model = full_fe_model(case)
    return case, model, integrate(model, T_END, OUTPUT_STEP, rtol=1e-8)


def _differences(model, reference) -> dict[str, float]:
    """The largest difference of each compared signal over the record, relative to the full integration's largest
    value."""
    run = simulate_model(model, t_end=T_END, output_step=OUTPUT_STEP, rtol=1e-7, atol=1e-12, method="ark43",
                         lateral_perturbation=0.0)
    assert np.allclose(run.time, reference.times, rtol=0.0, atol=1e-12)
    return {name: float(np.max(np.abs(run.observables[name] - reference.observables[name]))
                        / np.max(np.abs(reference.observables[name]))) for name in COMPARED}


def _all_modes(case, full_model, **override):
    n_nodes = full_model.bit_axial + 1
    modes = {"axial_modes": n_nodes - 1, "torsional_modes": n_nodes - 1} | override
    return case_reduced_model(case, lateral_modes=0, **modes)


def test_every_mode_agrees_with_the_full_integration(full):
    case, full_model, reference = full
    model = _all_modes(case, full_model)
    assert model.size == 2 * (full_model.bit_axial + 1) - 1  # every axial (rigid included) and torsional DOF
    assert len(model.friction_stations) == len(full_model.stations) > 40
    # the record has dynamics to compare: the bit slows down, the force on bit builds up
    speed = reference.observables["bit_speed"]
    assert speed[0] == pytest.approx(full_model.top_speed) and speed[-1] < 0.5 * speed[0]
    assert np.ptp(reference.observables["force_on_bit"]) > 1e4
    assert np.ptp(reference.observables["surface_torque"]) > 1e3
    differences = _differences(model, reference)
    assert max(differences.values()) < BOUND, differences


def test_the_check_fails_without_the_highest_torsional_mode(full):
    case, full_model, reference = full
    model = _all_modes(case, full_model, torsional_modes=full_model.bit_axial - 1)
    differences = _differences(model, reference)
    # the highest torsional mode lives at the bit (the short stabilizer element): the bit speed leaves the bound
    # (measured 1.3e-4), the surface torque hardly feels it (9.6e-7)
    assert differences["bit_speed"] > 20 * BOUND and differences["force_on_bit"] > BOUND, differences


def test_the_check_fails_with_the_friction_stations_moved(full):
    """The stations one node up (none onto the top's held rotation): the nodal friction projected on the wrong
    shapes. The friction is spread along the string, so a shift by one node changes the surface torque little
    (measured 2.5e-5), the bit speed by 1.6e-4 and the force on bit by 5.6e-4; every signal leaves the bound."""
    case, full_model, reference = full
    model = _all_modes(case, full_model)
    fs = model.friction_stations
    moved = FrictionStations(np.maximum(fs.node - 1, 1), fs.normal_force, fs.radius,
                             fs.friction)
    differences = _differences(dataclasses.replace(model, friction_stations=moved), reference)
    assert min(differences.values()) > 5 * BOUND and differences["force_on_bit"] > 50 * BOUND, differences


def test_the_reference_refuses_what_it_does_not_integrate():
    """The ramped start (the case as written) and a case without [well]: a clear refusal, not a wrong reference."""
    with pytest.raises(ValueError, match="initial.start = 'ramp'"):
        full_fe_model(load_case("deviated"))
    with pytest.raises(ValueError, match="no \\[well\\]"):
        full_fe_model(load_case("reference"))


def _few_modes(case, correction: str, monkeypatch=None):
    """5 axial + 5 torsional modes with ``truncation_correction = correction``; ``monkeypatch``: the friction's
    load patterns left out (the bit's and top's attachment modes only)."""
    if monkeypatch is not None:
        monkeypatch.setattr("drillstring.dynamics.reduced.build.friction_load_patterns", lambda *args: None)
    case = case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
        update={"truncation_correction": correction})})
    return case_reduced_model(case, axial_modes=5, torsional_modes=5, lateral_modes=0)


def test_the_friction_patterns_carry_the_steady_twist(full, monkeypatch):
    """With the friction's two load patterns in the basis (``truncation_correction = "static"``, one attachment
    column in each of the axial and torsional families) the steady twist under the friction spread over 54 stations
    is exact on 5 + 5 modes: the surface torque at t = 0 equals the full integration's to 2.2e-9 (the bit's and
    top's attachment modes alone: 3.9e-2; no correction: 4.2e-2)."""
    case, full_model, reference = full
    start = reference.observables["surface_torque"][0]

    def error(model):
        twist = model.basis @ model.friction_twist()
        return abs(full_model.surface_torque_row @ twist[full_model.dofs] - start) / abs(start)

    corrected = _few_modes(case, "static")
    assert error(corrected) < 1e-7
    assert error(_few_modes(case, "none")) > 3e-2
    bit_and_top = _few_modes(case, "static", monkeypatch)
    assert error(bit_and_top) > 3e-2
    assert corrected.family.count("axial") == bit_and_top.family.count("axial") + 1
    assert corrected.family.count("torsional") == bit_and_top.family.count("torsional") + 1


def test_the_friction_patterns_shrink_the_truncation_error_of_a_record(full, monkeypatch):
    """Over the 1 s record on 5 + 5 modes, the surface torque's largest difference from the full integration with
    the friction's patterns in the basis is 9.1e-3 of its largest value, against 3.5e-2 with the bit's and top's
    attachment modes alone (bit speed 7.88e-2 against 7.92e-2, force on bit 1.40e-2 against 1.45e-2: the
    bit's transient, which the patterns are not for)."""
    case, _, reference = full
    corrected = _differences(_few_modes(case, "static"), reference)
    bit_and_top = _differences(_few_modes(case, "static", monkeypatch), reference)
    assert corrected["surface_torque"] < 0.5 * bit_and_top["surface_torque"], (corrected, bit_and_top)
    assert all(corrected[name] <= bit_and_top[name] for name in COMPARED), (corrected, bit_and_top)
