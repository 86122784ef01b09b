"""The stiff-term diagnosis of a collapsing run against the closed-form linearization of steady drilling."""

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import linearized_matrix, steady_drilling
from drillstring.dynamics.stiffness import BIT_ROCK, CONTACT, STABILITY_RADIUS, stiffness_diagnosis, stiffness_rates



@pytest.mark.parametrize("a2", [5.672e-8, 2.5e-8])
def test_bit_rock_rate_is_the_closed_form_jacobians(small_case, a2):
    """At steady drilling the finite-difference Jacobian's bit–rock part has the spectral radius of the
    closed-form coupling Φ_bᵀ ∂(f, t)/∂(u̇, θ̇) Φ_b of the stability analysis; the linear terms are ω_max and
    the damping's spectral radius; the bit–rock law's axial resistance 1/(a2 Z²) is the stiffest term."""
    case = small_case.model_copy(update={"bit_rock": small_case.bit_rock.model_copy(update={"a2": a2})})
    model = case_reduced_model(case)
    steady = steady_drilling(model)
    rates = stiffness_rates(model, 0.0, steady.state)
    n = model.size
    coupling = linearized_matrix(model, steady)[n:, n:] + model.damping
    axial_torsional = ~np.char.startswith(np.asarray(model.family), "lateral")
    exact = np.abs(np.linalg.eigvals(coupling[np.ix_(axial_torsional, axial_torsional)])).max()
    assert rates[BIT_ROCK] == pytest.approx(exact, rel=1e-5)
    assert rates[next(k for k in rates if k.startswith("modes"))] == pytest.approx(
        np.abs(model.angular_frequencies).max(), rel=1e-12)
    assert rates[CONTACT] < 1e-6 * exact  # centred: no contact
    assert next(iter(rates)) == BIT_ROCK
    line = stiffness_diagnosis(model, 0.0, steady.state)
    assert line.startswith(f"likely stiff term: {BIT_ROCK}, λ = ")
    allowed = float(line.split("stable steps ≲ ")[1].split(" s (next: ")[0])
    assert allowed == pytest.approx(STABILITY_RADIUS["dopri5"] / exact, rel=5e-3)  # printed to 3 digits
    assert f"(next: {list(rates)[1]}, λ = " in line


def test_top_drive_controller_named_with_its_closed_form_rate(small_case):
    """An absurd top drive (a 1e9 N·m·s/rad proportional gain on a 1e-3 kg·m² quill) is named, not the bit–rock
    law (issue 26): its rate is the gain over the modal inertia of the quill, k_p |φ_q|² (φ_q the quill's row
    of the modal shapes), the root of λ² − k_p|φ_q|² λ − k_i|φ_q|² = 0 for a negligible k_i."""
    from drillstring.dynamics.stiffness import TOP_DRIVE

    case = small_case.model_copy(update={"top_drive": {"controller": "pi", "inertia": 1e-3,
                                                       "proportional_gain": 1e9, "integral_gain": 1.0}})
    model = case_reduced_model(case)
    y = model.initial_state(1e-5, 0)
    rates = stiffness_rates(model, 0.0, y)
    assert next(iter(rates)) == TOP_DRIVE
    assert rates[TOP_DRIVE] == pytest.approx(1e9 * model.quill_shapes @ model.quill_shapes, rel=1e-6)
    assert rates[BIT_ROCK] < 1e-3 * rates[TOP_DRIVE]
    assert stiffness_diagnosis(model, 0.0, y).startswith(f"likely stiff term: {TOP_DRIVE}, λ = ")


def test_contact_named_when_the_string_presses_the_wall(small_case):
    """A string pressed into the wall (a lateral state beyond the radial gap): the contact is the stiffest
    term, and the bit–rock law's rate (from the law's own derivatives at the bit) is the one it has with the
    string centred, although the contact's friction torque loads the torsion (it was blamed on the bit–rock
    law, issue 26)."""
    model = case_reduced_model(small_case)
    centred = model.initial_state(0.0, 0)
    pressed = model.initial_state(3.0 * float(model.gap.min()) + 0.05, 0)
    at_rest, in_contact = stiffness_rates(model, 0.0, centred), stiffness_rates(model, 0.0, pressed)
    assert next(iter(in_contact)) == CONTACT
    assert in_contact[BIT_ROCK] == pytest.approx(at_rest[BIT_ROCK], rel=1e-6)
    assert at_rest[CONTACT] < 1e-3 * in_contact[CONTACT]


def test_bit_rock_rows_are_the_delayed_laws_own_partials():
    """The diagnosis differentiates a delayed law through its named context (issue 22's protocol): on
    ``aarsnes2019`` (Detournay), at a state where the wear flats' dashpot and the regularised stick are both
    active (u̇ = v_r/2, θ̇ = ω_r/2), the bit–rock rows equal the law's closed-form partials in the depth of cut,
    the axial velocity and the bit speed, carried along the bit's shapes."""
    from drillstring.case import load_case
    from drillstring.dynamics.delay import delayed_difference, start
    from drillstring.dynamics.stiffness import _bit_rock_rows

    model = case_reduced_model(load_case("aarsnes2019"))
    law, n = model.bit_rock, model.size
    steady = steady_drilling(model)
    position, angle = model.bit_position(0.0, steady.state)  # the helical bottom of steady drilling under it
    start(model.history, angle, position, steady.depth_of_cut / law.sector)
    axial_velocity, bit_speed = 0.5 * law.contact_velocity, 0.5 * law.friction_speed
    y = steady.state.copy()
    y[n:2 * n] = (axial_velocity * model.bit_u / (model.bit_u @ model.bit_u)
                  + (bit_speed - model.base_speed) * model.bit_t / (model.bit_t @ model.bit_t))
    position, angle = model.bit_position(0.0, y)
    depth = delayed_difference(model.history, angle, position)
    assert depth > 0.0
    partials = law.jacobian(depth, axial_velocity, bit_speed)  # columns d, u̇, ω
    shapes = np.column_stack([model.bit_u, model.bit_t])
    rows = _bit_rock_rows(model, 0.0, y)
    scale = np.abs(shapes @ partials[:, 1:] @ shapes.T).max()
    np.testing.assert_allclose(rows[:, n:2 * n], shapes @ partials[:, 1:] @ shapes.T, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(rows[:, :n], shapes @ partials[:, :1] @ model.bit_u[None, :], rtol=0,
                               atol=1e-6 * np.abs(shapes @ partials[:, :1] @ model.bit_u[None, :]).max())


def test_the_bit_landing_is_named_as_the_bit_rock_laws_jump_not_contact():
    """``aarsnes2019`` (no lateral modes) with the bit landing on its helical bottom (depth of cut 1e-10 m, at the
    rate of penetration of steady drilling): the wear flats' contact force aσl = 71.28 kN switches on at d = 0, a
    jump the finite differences see. It was named "borehole contact" in a case that has none (issue 37); now the
    bit–rock law's jump across the depth of cut, by aσl, and the contact is not a term of this model at all."""
    from drillstring.case import load_case
    from drillstring.dynamics.delay import delayed_difference, start
    from drillstring.dynamics.stiffness import BIT_ROCK_JUMP

    model = case_reduced_model(load_case("aarsnes2019"))
    law, n = model.bit_rock, model.size
    steady = steady_drilling(model)
    position, angle = model.bit_position(0.0, steady.state)
    start(model.history, angle, position, steady.depth_of_cut / law.sector)
    y = steady.state.copy()
    y[:n] -= (steady.depth_of_cut - 1e-10) * model.bit_u / (model.bit_u @ model.bit_u)  # lift it to d = 1e-10 m
    position, angle = model.bit_position(0.0, y)
    assert delayed_difference(model.history, angle, position) == pytest.approx(1e-10, rel=1e-3)
    rates = stiffness_rates(model, 0.0, y)
    assert CONTACT not in rates and next(iter(rates)) == BIT_ROCK_JUMP
    line = stiffness_diagnosis(model, 0.0, y)
    assert line.startswith(f"likely stiff term: {BIT_ROCK_JUMP}: its force on bit changes by ")
    jump = float(line.split("changes by ")[1].split(" kN")[0])
    assert jump == pytest.approx(law.contact_force / 1e3, rel=1e-3)  # aσl, in kN
    assert "across depth of cut = 1e-10 m (law 'detournay')" in line
