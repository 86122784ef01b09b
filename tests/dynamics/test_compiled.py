"""The compiled fast path against the reference path (NumPy RHS + generic integrator)."""

import numpy as np
import pytest

from drillstring.dynamics.rom import OBSERVABLE_COLUMN, case_reduced_model
from drillstring.dynamics.simulate import SimulationError, simulate_model

NAMES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit", "bit_depth",
         "nodes_in_contact", "contact_force")


@pytest.mark.parametrize("turning", [False, True])
def test_compiled_rhs_equals_reference_rhs_with_and_without_contact(coarse_case, turning):
    """With and without contact, and with loads turning with the string (an eccentric collar and a
    bowed pipe), at times where the turning loads point anywhere."""
    case = coarse_case
    if turning:
        sections = [s.model_copy(update={"eccentricity": e, "eccentricity_angle": a})
                    for s, e, a in zip(case.sections, (0.001, 0.005), (0.4, -2.0))]
        case = case.model_copy(update={"sections": sections, "bow": case.bow.model_copy(
            update={"amplitude": 0.003, "start": 300.0, "end": 900.0, "angle": 1.0})})
    rom = case_reduced_model(case, lateral_modes=5)
    assert len(rom.turning_loads) > 0 if turning else len(rom.turning_loads) == 0
    rng = np.random.default_rng(0)
    for t in (0.0, 0.37, 11.9):
        for scale in (1e-6, 30.0):  # centred, and far enough out that many nodes touch the wall
            y = rng.normal(size=2 * rom.size) * scale
            fast, slow = rom.rhs(t, y), rom.rhs_reference(t, y)
            np.testing.assert_allclose(fast, slow, rtol=1e-10, atol=1e-10 * np.abs(slow).max())
    assert rom.observe(0.0, y)[OBSERVABLE_COLUMN["nodes_in_contact"]] > 0  # the state really is in contact
    if turning:  # the turning loads move with t: the string at rest in the centre is pushed differently
        at_rest = np.zeros(2 * rom.size)
        assert np.abs(rom.rhs(0.0, at_rest) - rom.rhs(0.37, at_rest)).max() > 0.1 * np.abs(rom.rhs(0.0, at_rest)).max()


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
    """The compile monitor announces the first compilation of each kernel set in the process on one line,
    naming the set, and counts the time spent compiling (a cache load fires no compile event)."""
    from numba import njit
    from numba.core import event

    from drillstring.dynamics import compiled

    messages = []
    monkeypatch.setattr(compiled, "compile_notice", messages.append)
    monkeypatch.setattr(compiled, "_announced", set())

    def fresh(x):  # a new function each time: compiling it cannot hit any cache
        return x + 1.0

    for what, expected in (("the loop A", 1), ("the loop A", 1), ("the loop B", 2)):
        monitor = compiled._CompileMonitor(estimate=7, what=what)
        with event.install_listener("numba:compile", monitor):
            njit(cache=False)(fresh)(1.0)
        assert monitor.compiled and monitor.seconds > 0
        assert len(messages) == expected
    assert messages == [f"drillstring: compiling the simulation kernels for the loop {x} (first run of this kind "
                        "only, cached afterwards; up to about 7 s)..." for x in "AB"]
    monitor = compiled._CompileMonitor(estimate=7)
    with event.install_listener("numba:compile", monitor):
        pass
    assert not monitor.compiled and monitor.seconds == 0.0


def test_kernel_set_names_what_the_loop_is_compiled_for():
    """The announcement's kernel set is the key of the compiled loop: the types of the step's data and of the
    model's data are equal where the set's words are, and differ where they differ (aarsnes2019's ``ark43``
    with its delayed law is a set of its own: its first run compiles once more, legitimately)."""
    from numba import typeof

    from drillstring.case import load_case
    from drillstring.dynamics.compiled import kernel_set
    from drillstring.dynamics.runge_kutta import method_named
    from drillstring.dynamics.steps import step_data

    def coarse(name, method):
        case = load_case(name)
        case = case.model_copy(update={
            "mesh": case.mesh.model_copy(update={"max_element_length": 100.0}),
            "reduced_model": case.reduced_model.model_copy(update={
                "axial_modes": 2, "torsional_modes": 2, "lateral_modes": 2, "lateral_cutoff": 0.0})})
        model = case_reduced_model(case)
        tableau = method_named(method)
        return kernel_set(model, tableau), (typeof(step_data(tableau, model.state_size)), typeof(model.rhs_data))

    runs = [coarse(name, method) for name, method in
            (("aarsnes2019", "ark43"), ("aarsnes2019_paper", "ark43"), ("aarsnes2019", "dopri5"),
             ("reference", "ark43"), ("motor", "ark43"), ("reference", "dopri5"), ("stick_slip", "dopri5"))]
    assert runs[0][0] == "the implicit-explicit step (ark43) of the case 2 model with a delayed bit-rock law"
    assert runs[2][0] == "the explicit Runge-Kutta step (dopri5) of the case 2 model with a delayed bit-rock law"
    assert runs[3][0] == "the implicit-explicit step (ark43) of the case 2 model"
    for words, types in runs:
        for other_words, other_types in runs:
            assert (words == other_words) == (str(types) == str(other_types)), (words, other_words)


def test_fast_and_reference_paths_agree_within_integration_error_with_impacts(coarse_case):
    """A string thrown at the wall (lateral velocities along its seeded shape) hits it three times.
    Both paths count the same impacts (zones that appear, checked after every accepted step) as an
    rtol = 1e-10 solution; round-off and tolerance effects grow through impacts, so each path is
    compared with the tight-tolerance solution: the fast path's error must be of the size of the
    reference path's own error; the 2 % bound is only a sanity check."""
    rom = case_reduced_model(coarse_case, lateral_modes=6)
    n = rom.size
    y0 = rom.initial_state(0.01, 0)
    lateral = np.array([f.startswith("lateral") for f in rom.family])
    y0[n:][lateral] = 10.0 * y0[:n][lateral] / np.abs(y0[:n][lateral]).max()
    kwargs = dict(t_end=3.0, output_step=0.01, initial_state=y0)
    fast = simulate_model(rom, engine="compiled", rtol=1e-7, atol=1e-10, **kwargs)
    slow = simulate_model(rom, engine="reference", rtol=1e-7, atol=1e-10, **kwargs)
    truth = simulate_model(rom, engine="reference", rtol=1e-10, atol=1e-13, **kwargs)
    assert fast.impacts == slow.impacts == truth.impacts == 3
    assert fast.observables["contact_force"].max() > 0
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


def test_pausing_the_compiled_loop_changes_nothing(small_case, monkeypatch):
    """The loop returns to Python every few attempts when each call is given no time (so Ctrl-C is seen
    between calls); the step sequence and the outputs are bit-identical to the default run."""
    from drillstring.dynamics import compiled

    rom = case_reduced_model(small_case)
    calls = []
    default = simulate_model(rom, t_end=5.0, output_step=0.5, progress=calls.append)
    default_calls = len(calls)
    monkeypatch.setattr(compiled, "CALL_SECONDS", 0.0)  # 10 attempts per call
    monkeypatch.setattr(compiled, "FIRST_CALL_ATTEMPTS", 10)
    calls.clear()
    paused = simulate_model(rom, t_end=5.0, output_step=0.5, progress=calls.append)
    assert len(calls) > default_calls and len(calls) >= paused.stats["n_steps"] // 10
    np.testing.assert_array_equal(paused.observables["bit_speed"], default.observables["bit_speed"])
    assert paused.stats["n_steps"] == default.stats["n_steps"]


def test_step_size_collapse_stops_early_naming_the_stiff_term(small_case):
    """A stiff nonsense case (a 1e30 N/m stabilizer) stops after a few tens of thousands of attempts, not
    at max_steps, with t, h and the likely stiff term; the rows computed are kept."""
    from drillstring.dynamics.compiled import COLLAPSE_WINDOW

    stabilizer = small_case.stabilizers[0].model_copy(update={"stiffness": 1e30})
    rom = case_reduced_model(small_case.model_copy(update={"stabilizers": [stabilizer]}))
    result = simulate_model(rom, t_end=1.0, output_step=0.01, raise_on_failure=False)
    assert result.status == "failed"
    assert result.stats["n_steps"] < 3 * COLLAPSE_WINDOW
    assert "step size collapsed" in result.message and "likely stiff term: " in result.message
    assert f"(h = " in result.message and "\n" not in result.message
    assert len(result.time) >= 1 and np.all(np.isfinite(result.observables["bit_speed"]))
