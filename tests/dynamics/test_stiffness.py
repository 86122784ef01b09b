"""The stiff-term diagnosis of a collapsing run against the closed-form linearization of steady drilling."""

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import linearized_matrix, steady_drilling
from drillstring.dynamics.stiffness import STABILITY_RADIUS, stiffness_diagnosis, stiffness_rates

BIT_ROCK = "bit–rock law (the nonlinear axial and torsional forces)"


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
    assert rates["borehole contact (the nonlinear lateral forces)"] < 1e-6 * exact  # centred: no contact
    assert next(iter(rates)) == BIT_ROCK
    line = stiffness_diagnosis(model, 0.0, steady.state)
    assert line.startswith(f"likely stiff term: {BIT_ROCK}, λ = ")
    allowed = float(line.split("stable steps ≲ ")[1].split(" s (next: ")[0])
    assert allowed == pytest.approx(STABILITY_RADIUS["dopri5"] / exact, rel=5e-3)  # printed to 3 digits
    assert f"(next: {list(rates)[1]}, λ = " in line
