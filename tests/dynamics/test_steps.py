"""The step kinds of the compiled loop (drillstring.dynamics.steps): the loop runs a step kind defined here,
outside the package, chosen by the type of its data."""

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pytest
from numba import njit

from drillstring.dynamics.rom import case_reduced_model, evaluate_rhs
from drillstring.dynamics.runge_kutta import DORMAND_PRINCE_54
from drillstring.dynamics.simulate import simulate_model
from drillstring.dynamics.steps import StepKind, kind_of, register, step_data
from drillstring.dynamics.steps.explicit_rk import ExplicitRungeKuttaStep


@dataclass(frozen=True)
class HeunEuler:
    """Heun's method (order 2) with the explicit Euler step (order 1) as its error estimate, written as a
    step kind of its own (not as a Butcher tableau); linear interpolation between the ends of a step."""

    name: str = "heun_euler"


class HeunEulerStep(NamedTuple):
    order: float  # of the error estimate (Euler): 1
    dense: np.ndarray  # (2, 1): y(t + θh) = y + h θ (k1 + k2)/2
    k2: np.ndarray  # (n,) the second stage of the step being attempted
    dense_stages: np.ndarray  # (2, n) k1, k2 of the last accepted step


def heun_euler_data(method: HeunEuler, n: int) -> HeunEulerStep:
    return HeunEulerStep(order=1.0, dense=np.array([[0.5], [0.5]]), k2=np.zeros(n), dense_stages=np.zeros((2, n)))


@njit
def heun_euler_attempt(data, rhs_data, t, h, y, f, y_new, err):
    n = y.shape[0]
    for j in range(n):
        y_new[j] = y[j] + h * f[j]  # Euler's predictor, the argument of the second stage
    evaluate_rhs(rhs_data, t + h, y_new, data.k2)
    for j in range(n):
        if not math.isfinite(data.k2[j]):
            return 1, False
    for j in range(n):
        y_new[j] = y[j] + 0.5 * h * (f[j] + data.k2[j])
        err[j] = 0.5 * h * (data.k2[j] - f[j])
    return 1, True


@njit
def heun_euler_accept(data, y, f):
    for j in range(y.shape[0]):
        data.dense_stages[0, j] = f[j]
        data.dense_stages[1, j] = data.k2[j]
    return False  # f at the new state is not known: the loop evaluates it


KIND = register(StepKind(method=HeunEuler, data=HeunEulerStep, allocate=heun_euler_data,
                         attempt=heun_euler_attempt, accept=heun_euler_accept))


def test_the_loop_runs_a_step_kind_defined_outside_the_package(small_case):
    """A Heun–Euler 2(1) step defined in this file runs through the compiled loop (its controller, dense output
    and observations): the right-hand-side count is its own (2 to start, 1 per attempt, 1 more per accepted
    step; Dormand–Prince takes 6 per attempt), and its outputs agree with Dormand–Prince 5(4) at the same
    tolerance within the accuracy of a 2nd-order method with linear interpolation."""
    assert kind_of(HeunEuler()) is KIND and not KIND.cacheable  # outside the package: not cached on disk
    assert type(step_data(HeunEuler(), 4)) is HeunEulerStep
    rom = case_reduced_model(small_case)
    kwargs = dict(t_end=0.5, output_step=0.01, rtol=1e-6, atol=1e-9)
    heun = simulate_model(rom, method=HeunEuler(), **kwargs)
    dopri = simulate_model(rom, method="dopri5", **kwargs)
    stats = heun.stats
    assert stats["n_rhs"] == 2 + stats["n_steps"] + stats["n_accepted"]
    assert dopri.stats["n_rhs"] == 2 + 6 * dopri.stats["n_steps"]
    assert stats["n_accepted"] > 3 * dopri.stats["n_accepted"]  # a 2nd-order method takes more steps
    np.testing.assert_array_equal(heun.time, dopri.time)
    for name in ("bit_speed", "rate_of_penetration", "torque_on_bit"):
        a, b = heun.observables[name], dopri.observables[name]
        scale = np.max(np.abs(b))
        assert np.max(np.abs(a - b)) <= 1e-3 * scale, name
        assert np.max(np.abs(a - b)) > 0.0, name  # really another method


def test_step_kinds_are_chosen_by_type_and_an_unknown_method_is_refused(small_case):
    assert type(step_data(DORMAND_PRINCE_54, 3)) is ExplicitRungeKuttaStep
    rom = case_reduced_model(small_case)
    with pytest.raises(TypeError, match="no step kind is registered for str"):
        kind_of("dopri5")
    with pytest.raises(TypeError, match="no step kind is registered for object"):
        simulate_model(rom, t_end=0.1, output_step=0.01, method=object())
    with pytest.raises(TypeError, match="lacks the fields"):
        StepKind(method=HeunEuler, data=NamedTuple("Bare", [("order", float)]), allocate=heun_euler_data,
                 attempt=heun_euler_attempt, accept=heun_euler_accept)
