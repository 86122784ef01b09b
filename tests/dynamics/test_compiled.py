"""The compiled fast path against the reference path (NumPy RHS + generic integrator)."""

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import SimulationError, simulate_model

NAMES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit", "bit_depth",
         "nodes_in_contact")


def test_compiled_rhs_equals_reference_rhs_with_and_without_contact(coarse_case):
    rom = case_reduced_model(coarse_case, lateral_modes=5)
    rng = np.random.default_rng(0)
    for scale in (1e-6, 30.0):  # centred, and far enough out that many nodes touch the wall
        y = rng.normal(size=2 * rom.size) * scale
        fast, slow = rom.rhs(0.0, y), rom.rhs_reference(0.0, y)
        np.testing.assert_allclose(fast, slow, rtol=1e-10, atol=1e-10 * np.abs(slow).max())
    assert rom.observe(0.0, y)[5] > 0  # the second state really is in contact


@pytest.mark.parametrize("method", ["dopri5", "bs32"])
def test_fast_and_reference_paths_agree_without_contact(coarse_case, method):
    """Same method, same controller functions, same dense output: the same steps and, but for
    round-off, the same outputs."""
    rom = case_reduced_model(coarse_case, lateral_modes=6)
    kwargs = dict(t_end=3.0 if method == "dopri5" else 1.0, output_step=0.01, rtol=1e-7, atol=1e-10,
                  lateral_perturbation=1e-4, method=method)
    fast = simulate_model(rom, engine="compiled", **kwargs)
    slow = simulate_model(rom, engine="reference", **kwargs)
    np.testing.assert_array_equal(fast.time, slow.time)
    for name in NAMES[:4]:
        a, b = fast.observables[name], slow.observables[name]
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), name
    assert fast.stats["n_accepted"] == slow.stats["n_accepted"]
    assert fast.stats["n_rejected"] == slow.stats["n_rejected"]
    assert fast.stats["n_rhs"] == slow.stats["n_rhs"]


def test_first_compilation_is_announced_once_and_timed(monkeypatch):
    """The compile monitor announces the first compilation of the process on one line and counts
    the time spent compiling (a cache load fires no compile event)."""
    from numba import njit
    from numba.core import event

    from drillstring.dynamics import compiled

    messages = []
    monkeypatch.setattr(compiled, "compile_notice", messages.append)
    monkeypatch.setattr(compiled, "_announced", False)

    def fresh(x):  # a new function each time: compiling it cannot hit any cache
        return x + 1.0

    for expected in (1, 1):
        monitor = compiled._CompileMonitor(estimate=7)
        with event.install_listener("numba:compile", monitor):
            njit(cache=False)(fresh)(1.0)
        assert monitor.compiled and monitor.seconds > 0
        assert len(messages) == expected
    assert messages == ["drillstring: compiling the simulation kernels (first run only, about 7 s)..."]
    monitor = compiled._CompileMonitor(estimate=7)
    with event.install_listener("numba:compile", monitor):
        pass
    assert not monitor.compiled and monitor.seconds == 0.0


def test_fast_and_reference_paths_agree_within_integration_error_with_impacts(coarse_case):
    """With impacts, round-off and tolerance effects grow (the radial displacement of both paths
    differs from an rtol = 1e-10 solution by ~0.5 % at rtol = 1e-7), so compare each path with the
    tight-tolerance solution: the fast path's error must be of the size of the reference path's
    own error; the 2 % bound is only a sanity check."""
    rom = case_reduced_model(coarse_case, lateral_modes=6)
    kwargs = dict(t_end=3.0, output_step=0.01, lateral_perturbation=0.07)
    fast = simulate_model(rom, engine="compiled", rtol=1e-7, atol=1e-10, **kwargs)
    slow = simulate_model(rom, engine="reference", rtol=1e-7, atol=1e-10, **kwargs)
    truth = simulate_model(rom, engine="reference", rtol=1e-10, atol=1e-13, **kwargs)
    assert fast.impacts > 0 and fast.impacts == slow.impacts
    pairs = [(fast.observables[n], slow.observables[n], truth.observables[n]) for n in NAMES[:4]]
    pairs.append((fast.radial_displacement, slow.radial_displacement, truth.radial_displacement))
    for a, b, c in pairs:
        scale = np.max(np.abs(c))
        fast_error, slow_error = np.max(np.abs(a - c)), np.max(np.abs(b - c))
        assert fast_error <= 2e-2 * scale
        assert fast_error <= 3.0 * slow_error + 1e-12 * scale


def test_compiled_failure_message_and_partial_outputs(coarse_case):
    rom = case_reduced_model(coarse_case, lateral_modes=2)
    with pytest.raises(SimulationError, match=r"failed at t = [0-9.e-]+ s .*maximum number of steps"):
        simulate_model(rom, t_end=5.0, output_step=0.01, max_steps=40)
    partial = simulate_model(rom, t_end=5.0, output_step=0.01, max_steps=40, raise_on_failure=False)
    assert partial.status == "failed" and 0 < len(partial.time) < 501
    assert np.all(np.isfinite(partial.observables["bit_speed"]))
    with pytest.raises(ValueError, match="engine"):
        simulate_model(rom, t_end=1.0, output_step=0.1, engine="fortran")
