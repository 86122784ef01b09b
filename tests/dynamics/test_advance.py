"""State in, state out: advance() integrates a run from a state to a time and returns where it stands; every
array a run writes is its own, so a run can be continued, restarted from a modified state, interleaved with
another run of the same model, and leaves the model as it found it."""

import numpy as np
import pytest

from drillstring.dynamics.compiled import AdvanceResult, RunState, SolverSettings, advance
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import output_grid, simulate_model


def _with(case, **tables):
    update = {name: getattr(case, name).model_copy(update=fields) for name, fields in tables.items()}
    return case.model_copy(update=update)


@pytest.fixture(scope="module")
def detournay_model(torsional_case):
    """The Detournay law (a state-dependent delay: the bit's history is part of the run's state)."""
    return case_reduced_model(_with(torsional_case, bit_rock={"law": "detournay"}, initial={"start": "on_bottom"}))


@pytest.fixture(scope="module")
def contact_model(coarse_case):
    return case_reduced_model(coarse_case, lateral_modes=6)


def _thrown(model, seed=0):
    """A string thrown at the wall: lateral velocities along its seeded shape (it hits the wall)."""
    n = model.size
    y0 = model.initial_state(0.01, seed)
    lateral = np.array([f.startswith("lateral") for f in model.family])
    y0[n:][lateral] = 10.0 * y0[:n][lateral] / np.abs(y0[:n][lateral]).max()
    return y0


def _start(model, seed=0):
    """Thrown at the wall (with lateral modes), or with modal velocities 0.01·``seed`` (without)."""
    if model.lateral_columns.any():
        return RunState.start(model, _thrown(model, seed))
    y0 = model.initial_state(0.0, 0)
    y0[model.size:2 * model.size] += 0.01 * seed
    return RunState.start(model, y0)


def _joined(*parts: AdvanceResult):
    return np.concatenate([p.time for p in parts]), np.concatenate([p.outputs for p in parts])


def _arrays(value, seen=None):
    """Every NumPy array reachable from ``value`` through attributes, tuples, lists and dicts, by path."""
    seen = set() if seen is None else seen
    found = {}
    if id(value) in seen or isinstance(value, (str, bytes, int, float, bool, type(None))):
        return found
    seen.add(id(value))
    if isinstance(value, np.ndarray):
        return {"": value}
    if isinstance(value, dict):
        items = value.items()
    elif isinstance(value, (tuple, list)):
        items = enumerate(value)
    elif hasattr(value, "__dict__") and type(value).__module__.startswith("drillstring"):
        items = vars(value).items()
    else:
        return found
    for key, item in items:
        for path, array in _arrays(item, seen).items():
            found[f"{key}.{path}" if path else str(key)] = array
    return found


@pytest.mark.parametrize("model_name, method", [("detournay_model", "dopri5"), ("detournay_model", "ark43"),
                                                ("contact_model", "dopri5")])
def test_a_run_continued_from_its_state_repeats_one_run_bit_for_bit(model_name, method, request):
    """0 -> t_mid (stopping at the first step that reaches t_mid) then on to t1 from the returned state, the
    controller's state carried: the same steps, the same outputs, state, bit history and impacts, bit for
    bit, as one run 0 -> t1."""
    model = request.getfixturevalue(model_name)
    solver = SolverSettings(method, rtol=1e-7, atol=1e-10)
    start = _start(model)
    t1, grid = 3.0, output_grid(3.0, 0.01)
    one = advance(model, solver, start, t1, output_times=grid)
    first = advance(model, solver, start, 1.405, output_times=grid, land=False)
    assert first.state.t >= 1.405 and first.time[-1] <= first.state.t < grid[len(first.time)]
    rest = advance(model, solver, first.state, t1, output_times=grid[len(first.time):])
    assert one.success and first.success and rest.success
    time, outputs = _joined(first, rest)
    np.testing.assert_array_equal(time, one.time)
    np.testing.assert_array_equal(outputs, one.outputs)
    np.testing.assert_array_equal(rest.state.y, one.state.y)
    np.testing.assert_array_equal(rest.state.history, one.state.history)
    assert rest.state.t == one.state.t == t1
    assert first.stats["n_accepted"] + rest.stats["n_accepted"] == one.stats["n_accepted"]
    assert first.stats["impacts"] + rest.stats["impacts"] == one.stats["impacts"]
    if model is request.getfixturevalue("contact_model"):
        # stopped in contact (1.40-1.41 s): the contact carried across the stop is not a new impact
        assert first.state.in_contact.any() and rest.stats["impacts"] >= 1
    else:  # the history carried across the stop matters: the delay reaches back before t_mid
        assert not np.array_equal(rest.state.history, first.state.history)


def test_a_run_landing_on_an_intermediate_time_continues_within_the_tolerance(detournay_model):
    """Landing on t_mid (the state at t_mid exactly, what a filter updates) changes the steps after it: the
    continued run agrees with one run to the integration tolerance, not bit for bit."""
    model, solver = detournay_model, SolverSettings(rtol=1e-9, atol=1e-12)
    start, grid = _start(model), output_grid(1.0, 0.01)
    one = advance(model, solver, start, 1.0, output_times=grid)
    first = advance(model, solver, start, 0.505, output_times=grid)
    assert first.state.t == 0.505
    rest = advance(model, solver, first.state, 1.0, output_times=grid[len(first.time):])
    _, outputs = _joined(first, rest)
    difference = np.abs(outputs - one.outputs).max(axis=0) / np.maximum(np.abs(one.outputs).max(axis=0), 1e-300)
    assert difference.max() < 1e-6, difference
    assert not np.array_equal(outputs, one.outputs)


def test_a_restart_from_an_updated_state_starts_there(detournay_model):
    """A filter's update (a modified state at t_mid, the history and controller kept) is a run from that
    state: the same as a run whose start is that state with the same history."""
    model, solver = detournay_model, SolverSettings()
    first = advance(model, solver, _start(model), 0.5)
    y = first.state.y.copy()
    y[model.size:] *= 1.01  # a 1 % faster string
    updated = first.state.updated(y)
    assert updated.rate is None and updated.controller == first.state.controller
    restarted = advance(model, solver, updated, 1.0, output_times=[0.5, 0.75, 1.0])
    again = advance(model, solver, RunState(0.5, y, first.state.history, first.state.in_contact,
                                            first.state.controller), 1.0, output_times=[0.5, 0.75, 1.0])
    np.testing.assert_array_equal(restarted.outputs, again.outputs)
    unchanged = advance(model, solver, first.state, 1.0, output_times=[0.5, 0.75, 1.0])
    assert not np.allclose(restarted.outputs[1:], unchanged.outputs[1:])


@pytest.mark.parametrize("model_name", ["detournay_model", "contact_model"])
def test_two_runs_of_one_model_interleaved_equal_the_runs_alone(model_name, request):
    """Runs A and B of the same model object advanced in turns (A to 0.7 s, B to 0.7 s, A on, B on) give what
    each gives alone: no run reads what another wrote."""
    model = request.getfixturevalue(model_name)
    solver = SolverSettings(rtol=1e-7, atol=1e-10)
    starts = [_start(model, 0), _start(model, 1)]
    alone = [advance(model, solver, s, 1.2, output_times=output_grid(1.2, 0.05)) for s in starts]
    halves = [advance(model, solver, s, 0.7, land=False) for s in starts]
    ends = [advance(model, solver, h.state, 1.2) for h in halves]
    for run, end in zip(alone, ends):
        np.testing.assert_array_equal(end.state.y, run.state.y)
        np.testing.assert_array_equal(end.state.history, run.state.history)
    assert not np.array_equal(alone[0].state.y, alone[1].state.y)


@pytest.mark.parametrize("model_name", ["detournay_model", "contact_model"])
def test_a_run_leaves_the_model_unchanged(model_name, request):
    """Every array the model holds, its kernels' data included, is the same after a run (the bit's history,
    the contact work and the observation's scratch are the run's own)."""
    model = request.getfixturevalue(model_name)
    before = {path: array.copy() for path, array in _arrays(model).items()}
    run = simulate_model(model, t_end=1.5, output_step=0.01, initial_state=_start(model).y)
    assert run.success and (run.impacts > 0 or model.bit_rock.delayed)
    after = _arrays(model)
    assert sorted(after) == sorted(before)
    changed = [path for path, array in after.items() if not np.array_equal(array, before[path], equal_nan=True)]
    assert not changed, changed


def test_advance_refuses_bad_times(detournay_model):
    start = _start(detournay_model)
    with pytest.raises(ValueError, match="t1"):
        advance(detournay_model, SolverSettings(), start, -1.0)
    with pytest.raises(ValueError, match="output_times"):
        advance(detournay_model, SolverSettings(), RunState(0.5, start.y, start.history), 1.0, output_times=[0.0])
    with pytest.raises(ValueError, match="history"):
        advance(detournay_model, SolverSettings(), RunState(0.0, start.y, np.zeros(3)), 1.0)


def test_a_copy_of_the_model_reads_a_runs_history(detournay_model):
    """with_history: code that takes a model (the stiffness diagnosis of a failed run) reads the run's bit
    history through a shallow copy; the model itself keeps its own."""
    model = detournay_model
    run = advance(model, SolverSettings(), _start(model), 0.5)
    own = model.history.values.copy()
    other = model.with_history(run.state.history)
    t, y = run.state.t, run.state.y
    np.testing.assert_array_equal(other.rhs(t, y), model.rhs(t, y, run.state.history))
    assert not np.array_equal(other.rhs(t, y), model.rhs(t, y))  # the delay reads the history
    np.testing.assert_array_equal(model.history.values, own)
