"""The Detournay bit–rock law in the reduced model (drillstring.forces.detournay, the bit's history of
drillstring.dynamics.delay): the compiled and NumPy paths agree, the bit really sticks and really bounces
in cases built to do so, and a start on the helical bottom of steady drilling carries the closed-form
weight."""

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model

RPM = np.pi / 30.0


def _with(case, **tables):
    update = {name: getattr(case, name).model_copy(update=fields) for name, fields in tables.items()}
    return case.model_copy(update=update)


@pytest.fixture(scope="module")
def detournay_case(torsional_case):
    """The coarse reference string (3 axial, 3 torsional modes) with the published PDC bit and rock."""
    return _with(torsional_case, bit_rock={"law": "detournay"}, initial={"start": "on_bottom"})


def _intervals(time, mask):
    """(start, end) times of the runs of True in ``mask``."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    return [(time[a], time[b - 1]) for a, b in zip(edges[::2], edges[1::2])]


def test_compiled_and_reference_paths_agree(detournay_case):
    model = case_reduced_model(detournay_case)
    options = dict(t_end=0.8, output_step=0.05, rtol=1e-9, atol=1e-12)
    compiled = simulate_model(model, **options)
    reference = simulate_model(model, engine="reference", **options)
    for name in ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit", "bit_depth"):
        a, b = compiled.observables[name], reference.observables[name]
        np.testing.assert_allclose(a, b, rtol=0, atol=2e-5 * np.abs(b).max(), err_msg=name)
    # the delay acts: 0.8 s at 100 rpm is more than five blade passages
    assert 0.8 > 5 * model.bit_rock.sector / model.top_speed


def test_the_start_on_the_steady_bottom_carries_the_weight(detournay_case):
    """Started on the helical bottom of steady drilling (its depth of cut per blade under the bit), the bit
    carries the closed-form cutting force at once: the rock's force at t = 0 is W_c of the static weight."""
    model = case_reduced_model(detournay_case)
    law = model.bit_rock
    run = simulate_model(model, t_end=0.01, output_step=0.01)
    cutting = model.weight_on_bit - law.contact_force  # W − aσl, the flats idle at rest
    assert run.observables["force_on_bit"][0] == pytest.approx(cutting, rel=1e-9)


def test_the_bit_sticks(detournay_case):
    """At 20 rpm the bit stops after the start: its speed stays within the regularisation ω_r for more than
    a second while the string winds up (the torque on bit rises) below the full torque the rock can resist
    (cutting at the frozen depth of cut plus the flats' friction), then it slips."""
    case = _with(detournay_case, operation={"top_speed": 20 * RPM})
    model = case_reduced_model(case)
    law = model.bit_rock
    run = simulate_model(model, t_end=4.0, output_step=0.005)
    t, o = run.time, run.observables
    stuck = np.abs(o["bit_speed"]) <= 2.0 * law.friction_speed
    start, end = max(_intervals(t, stuck), key=lambda iv: iv[1] - iv[0])
    assert end - start > 1.0 and end < t[-1]  # a stick phase that ends in a slip
    inside = (t >= start) & (t <= end)
    # the full resisting torque from the rock's force: flats W_f = aσl·clip(u̇/v_r, 0, 1), cutting the rest
    flats = law.contact_force * np.clip(o["rate_of_penetration"][inside] / law.contact_velocity, 0.0, 1.0)
    depth = (o["force_on_bit"][inside] - flats) / law.cutting_stiffness
    full = law.cutting_torque_rate * depth + law.friction_arm * flats
    torque = o["torque_on_bit"][inside]
    assert np.all(torque <= full * (1 + 1e-9))
    assert torque[-1] - torque[0] > 0.2 * torque[0]  # held by static friction while the string winds up
    assert np.max(o["bit_speed"][t > end + 0.2]) > 10 * law.friction_speed  # and then it slips


def test_the_bit_bounces(detournay_case):
    """Lowered onto the rock with a fast ramp, the bit lands, then leaves the rock again (the force on bit
    is exactly zero over an interval) and comes back: a bounce, not the approach."""
    case = _with(detournay_case, operation={"top_speed": 60 * RPM},
                 initial={"start": "ramp", "clearance": 0.02, "weight_ramp_time": 0.3})
    model = case_reduced_model(case)
    run = simulate_model(model, t_end=3.0, output_step=0.005)
    t, force = run.time, run.observables["force_on_bit"]
    off = _intervals(t, force <= 0.0)
    assert off[0][0] == 0.0  # off bottom at the start, the bit 20 mm above the rock
    bounces = [(a, b) for a, b in off[1:] if b < t[-1]]
    assert bounces, "no lift-off after the landing"
    a, b = bounces[0]
    assert b - a >= 0.02 and np.all(force[(t >= a) & (t <= b)] == 0.0)
    assert np.max(force[t > b]) > 0.0 and np.max(force[(t > off[0][1]) & (t < a)]) > model.weight_on_bit
