"""The ramped start (initial.start = "ramp", drillstring.forces.hook_load) in the reduced model: the string
hangs off bottom in equilibrium at t = 0, the bit its clearance above the rock, and the weight is
transferred to the bit over the ramp time."""

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model


def _with(case, **tables):
    update = {name: getattr(case, name).model_copy(update=fields) for name, fields in tables.items()}
    return case.model_copy(update=update)


@pytest.fixture(scope="module")
def ramped(torsional_case):
    return _with(torsional_case, initial={"start": "ramp", "clearance": 0.004, "weight_ramp_time": 3.0})


def test_the_string_starts_off_bottom_in_equilibrium(ramped):
    model = case_reduced_model(ramped)
    y0 = model.initial_state(0.0, 0)
    n = model.size
    position, _ = model.bit_position(0.0, y0)
    assert position == pytest.approx(-0.004, abs=1e-12)  # the clearance above the rock (its static position)
    # the hook holds the weight the bit no longer carries: apart from the bit-rock law (here the Tucker-Wang
    # law, which has no bottom position and pushes at rest), nothing accelerates the axial modes at t = 0
    a0, a1 = model.blocks[:2]
    law, _ = model.bit_rock.evaluate(0.0, model.top_speed)
    acceleration = model.rhs(0.0, y0)[n + a0:n + a1] - model.bit_u[a0:a1] * float(law)
    scale = model.weight_on_bit * np.abs(model.bit_u[a0:a1]).max()
    assert np.abs(acceleration).max() < 1e-9 * scale
    # once the ramp is over the hook no longer holds the weight back: the same state accelerates
    held = model.rhs(3.5, y0)[n + a0:n + a1] - model.bit_u[a0:a1] * float(law)
    assert np.abs(held).max() > 0.1 * scale


def test_the_weight_reaches_the_bit_over_the_ramp(ramped):
    model = case_reduced_model(ramped)
    run = simulate_model(model, t_end=6.0, output_step=0.01)
    fob = run.observables["force_on_bit"]
    late = run.time >= 5.0
    assert np.mean(fob[late]) == pytest.approx(model.weight_on_bit, rel=0.01)
    early = run.time <= 0.5
    assert np.max(fob[early]) < 0.5 * model.weight_on_bit  # no impulsive start: the weight comes in gradually
