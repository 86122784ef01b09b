"""The hook load of a ramped start (drillstring.forces.hook_load): the compiled kernel against the ramp's
closed form; bad input refused."""

import numpy as np
import pytest

from drillstring.forces.hook_load import KERNEL_SIZE, HookLoadRamp, OnBottomStart, hook_load_change
from drillstring.forces.registry import HookContext, hook_load, hook_loads


def test_kernel_and_evaluate_at_are_the_ramp():
    """The kernel (and ``force``, the kernel over an array of times) against the ramp by hand: the hook holds
    back W at t = 0 (an upward force on the top: negative along +x), half of it halfway, nothing once the
    weight is on the bit."""
    ramp = HookLoadRamp(ramp_time=8.0, weight_on_bit=1.2e5, clearance=0.01)
    args = ramp.kernel_array()
    assert args.shape == (KERNEL_SIZE,) and ramp.active
    times = np.array([0.0, 1.0, 4.0, 7.999, 8.0, 20.0])
    by_hand = [-1.2e5, -1.05e5, -0.6e5, -15.0, 0.0, 0.0]
    np.testing.assert_allclose([hook_load_change(args, HookContext(t, 0.0)) for t in times], by_hand, atol=1e-6)
    np.testing.assert_allclose(ramp.force(times), by_hand, atol=1e-6)
    assert ramp.force(times.reshape(2, 3)).shape == (2, 3) and ramp.force(4.0).shape == ()


def test_no_ramp_is_no_force():
    ramp = HookLoadRamp()
    assert not ramp.active
    assert hook_load_change(ramp.kernel_array(), HookContext(0.0, 0.0)) == 0.0
    assert np.all(ramp.force([0.0, 3.0]) == 0.0)


@pytest.mark.parametrize("field, value", [("ramp_time", -1.0), ("weight_on_bit", float("nan")),
                                          ("clearance", -0.1)])
def test_bad_input_names_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        HookLoadRamp(**{field: value})


def test_the_starts_are_registered_hook_loads_named_by_the_case(reference_case):
    """``initial.start`` names a registered hook load; the on-bottom start adds nothing (code 0, no kernel), the
    ramp is built from its own keys (:class:`~drillstring.case.RampStartKeys`) and the static weight-on-bit."""
    from typing import get_args

    from drillstring.case import Initial, RampStartKeys

    package = tuple(n for n in hook_loads() if hook_load(n).__module__.startswith("drillstring."))  # tests add own
    assert package == tuple(sorted(get_args(Initial.model_fields["start"].annotation)))
    assert hook_load("on_bottom") is OnBottomStart and OnBottomStart.component_code == 0.0
    assert hook_load("ramp") is HookLoadRamp and HookLoadRamp.component_code > 0.0
    assert set(RampStartKeys.model_fields) <= set(Initial.model_fields)
    initial = reference_case.initial.model_copy(update={"start": "ramp", "weight_ramp_time": 6.0, "clearance": 0.02})
    ramp = hook_load("ramp").from_case(reference_case.model_copy(update={"initial": initial}), 1.5e5)
    assert ramp == HookLoadRamp(ramp_time=6.0, weight_on_bit=1.5e5, clearance=0.02)
    assert not OnBottomStart().active and OnBottomStart().kernel_array().size == 0
    np.testing.assert_array_equal(OnBottomStart().force(np.array([0.0, 1.0])), 0.0)
    with pytest.raises(ValueError, match="hook load 'lift'"):
        hook_load("lift")
