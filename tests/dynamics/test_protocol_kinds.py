"""The component protocol holds for every kind (issue 33): stable codes, each component's keys in its own case
table, its states, its Jacobian at an operating point (``jacobian_at``) and its steady state, for top boundaries
and motors as for bit laws. Each test here failed on b1c1e75."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
from power_limited_top import PowerLimitedTop

from drillstring.case import TopDrive
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import linearized_matrix, stability, steady_drilling
from drillstring.forces.registry import (
    BitLaw,
    TopBoundary,
    TopContext,
    _REGISTRY,
    bit_law,
    bit_laws,
    pack,
    register,
)


def _package_codes(kind_names):
    return {name: bit_law(name).component_code for name in kind_names}


def test_adding_a_law_shifts_no_code():
    """A law added to the package (here a class claiming a module of ``drillstring.forces``, whose name sorts
    first) leaves every other code as it was: on b1c1e75 codes were ranks among the sorted names, so the
    Detournay law took the off-bottom law's code, and a cached dispatch ran the off-bottom law for it."""
    names = [n for n in bit_laws() if bit_law(n).component_code > 0]
    before = _package_codes(names)
    aardvark = type("Aardvark", (BitLaw,), {"name": "aardvark", "kernel_size": 0, "kernel": None,
                                            "__module__": "drillstring.forces.aardvark"})
    try:
        register(aardvark)
        assert aardvark.component_code > 0.0 and aardvark.component_code not in before.values()
        assert _package_codes(names) == before
    finally:
        _REGISTRY["bit_law"].pop("aardvark", None)


def _fd_matrix(model, y, relative_step=1e-7):
    """Central differences of the NumPy reference right-hand side at ``y``."""
    fd = np.zeros((len(y), len(y)))
    for k in range(len(y)):
        step = relative_step * max(1.0, abs(y[k]))
        d = np.zeros_like(y)
        d[k] = step
        fd[:, k] = (model.rhs_reference(0.0, y + d) - model.rhs_reference(0.0, y - d)) / (2 * step)
    return fd


def _power_limited_case(case, power):
    """The case with the power-limited top boundary: one key naming it and its own table."""
    top = TopDrive.model_validate({"boundary": "power_limited_test",
                                   "power_limited_test": {"power": power, "gain": 3e3, "inertia": 800.0}})
    return case.model_copy(update={"top_drive": top})


def test_a_power_limited_top_is_one_module_and_its_case_table(torsional_case):
    """The test-only module ``power_limited_top.py`` and a case table: the case names the boundary
    (``top_drive.boundary``, no such key on b1c1e75) and its keys sit in its own table, converted by its own keys
    model; the model and the stability analysis take it from there."""
    model = case_reduced_model(_power_limited_case(torsional_case, 5e5))
    assert model.top_drive == PowerLimitedTop(torsional_case.operation.top_speed, 5e5, 3e3, 800.0)
    assert model.top_drive.drives and model.state_size == 2 * model.size
    assert stability(model).top_drive == model.top_drive.describe()


@pytest.fixture(scope="module")
def limited(torsional_case):
    """A model whose power-limited top runs on its power limit in steady drilling (P = 0.6 τ Ω of the unlimited
    steady state)."""
    omega = torsional_case.operation.top_speed
    unlimited = case_reduced_model(torsional_case, top_drive=PowerLimitedTop(omega, 1e12, 3e3, 800.0))
    free = steady_drilling(unlimited)
    load = unlimited.top_drive.evaluate_at(TopContext(0.0, free.bit_speed, 0.0), ())[0]
    model = case_reduced_model(torsional_case, top_drive=PowerLimitedTop(omega, 0.6 * load * free.bit_speed, 3e3,
                                                                          800.0))
    return model, free


def test_a_top_boundary_is_linearised_at_its_steady_state(limited):
    """The stability analysis linearises the boundary at the steady speed (``jacobian_at``: −P/ω² on the power
    limit), which matches finite differences of the right-hand side. On b1c1e75 ``jacobian()`` had no operating
    point (the proportional branch's −k): a false growing root, +0.015 1/s instead of −0.062 1/s."""
    model, free = limited
    steady = steady_drilling(model)
    assert steady.bit_speed < 0.9 * free.bit_speed and model.top_drive._limited(steady.bit_speed)
    a = linearized_matrix(model, steady)
    np.testing.assert_allclose(a, _fd_matrix(model, steady.state), atol=1e-7 * np.abs(a).max())


def test_the_stability_table_prints_another_top_boundary(limited, monkeypatch):
    """``drillstring stability`` with another top boundary prints its summary (on b1c1e75 the table read the top
    drive's ``tuned`` and raised KeyError)."""
    from typer.testing import CliRunner

    import drillstring.api
    from drillstring.cli import app

    model, _ = limited
    monkeypatch.setattr(drillstring.api, "stability", lambda case, **options: stability(model))
    done = CliRunner().invoke(app, ["stability", "reference"], env={"COLUMNS": "160"})
    assert done.exit_code == 0, done.output
    assert "power_limited_test" in done.output and "gain" in done.output


@dataclass(frozen=True)
class LaggedDrive(TopBoundary):
    """A top boundary with one state and no integral gain: the motor torque s lags the proportional demand,
    ``ṡ = (k (Ω − θ̇₀) − s) / T``, ``τ_m = s``."""

    name: ClassVar[str] = "lagged_drive_test"
    kernel_size: ClassVar[int] = 0

    set_point: float
    gain: float
    lag: float
    inertia: float = 800.0

    @property
    def n_states(self):
        return 1

    @property
    def top_inertia(self):
        return self.inertia

    def evaluate_at(self, ctx, states):
        return float(states[0]), np.array([(self.gain * (self.set_point - ctx.quill_speed) - states[0]) / self.lag])

    def jacobian_at(self, ctx, states):
        return np.array([[0.0, 0.0, 1.0], [-self.gain / self.lag, 0.0, -1.0 / self.lag]])

    def steady_states(self, motor_torque, surface_torque):
        return np.array([motor_torque])

    def steady_speed(self, motor_torque):
        return self.set_point - motor_torque / self.gain


register(LaggedDrive)


def test_a_top_boundary_with_a_state_and_no_integral_gain(torsional_case):
    """``stability`` asks the boundary, never its fields: on b1c1e75 it read ``integral_gain`` of any boundary
    with states (AttributeError). Its steady state is an equilibrium and its linearisation matches finite
    differences."""
    model = case_reduced_model(torsional_case, top_drive=LaggedDrive(torsional_case.operation.top_speed, 3e3, 0.05))
    steady = steady_drilling(model)
    n = model.size
    assert np.abs(model.rhs_reference(0.0, steady.state)[2 * n:]).max() < 1e-6 * abs(steady.state[2 * n])
    a = linearized_matrix(model, steady)
    # a larger step: the state's rate (k (Ω − θ̇₀) − s) / T cancels two torques of 10 kN·m
    np.testing.assert_allclose(a, _fd_matrix(model, steady.state, 1e-5), atol=1e-7 * np.abs(a).max())
    assert stability(model).leading.growth_rate < 0.0


def test_pack_checks_the_top_boundarys_size(limited):
    """``pack()`` checks every declared size, the top boundary's too (not on b1c1e75)."""
    model, _ = limited

    class Short(PowerLimitedTop):
        kernel_size: ClassVar[int] = 4

    top = Short(1.0, 1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="top boundary 'power_limited_test': kernel_array\\(\\) has 3 numbers, "
                                         "kernel_size says 4"):
        pack(model.bit_rock, top, model.hook_load, np.zeros(4), 2 * model.size)


def test_component_tables_in_the_case():
    """A case names its top boundary (``top_drive.boundary``) and holds a component's keys in its own table;
    the old flat form of the built-in keys still loads; a plain unknown key is refused, naming it."""
    from drillstring.case import BitRock, CaseError, Contact

    top = TopDrive.model_validate({"boundary": "power_limited_test",
                                   "power_limited_test": {"power": 5e5, "gain": "3000 N*m*s/rad"}})
    assert top.boundary == "power_limited_test" and top.model_extra["power_limited_test"]["power"] == 5e5
    assert TopDrive.model_validate({"controller": "pi", "proportional_gain": 1.0, "integral_gain": 2.0}).boundary \
        == "top_drive"
    # two laws may use one key name: each in its own table (a1 is Tucker-Wang's too)
    rock = BitRock.model_validate({"law": "other_law", "a1": 1e-3, "other_law": {"a1": 7.0}})
    assert rock.a1 == 1e-3 and rock.model_extra["other_law"] == {"a1": 7.0}
    assert Contact.model_validate({}).law == "penalty"
    with pytest.raises(CaseError, match="frobnicate"):
        TopDrive.model_validate({"frobnicate": 1.0})


def test_a_compiled_motor_with_states_writes_their_rates(tmp_path):
    """The compiled dispatch hands a downhole motor its states and the rates to write (on b1c1e75 a motor with
    states left its rates unwritten: 4.65e-310 from the compiled kernels). Run in a fresh process and kernel
    cache: the motor claims a module of the package, which the cache of this session must not see."""
    script = textwrap.dedent("""
        import json, sys
        from dataclasses import dataclass
        from typing import ClassVar
        import numpy as np
        from numba import njit
        from drillstring.forces.registry import (HEADER, MOTOR, MOTOR_CODE, MOTOR_STATES, Motor, MotorContext,
                                                 motor_torque, register)

        @njit
        def lag_kernel(args, ctx, states, rates):
            rates[0] = (args[0] * ctx.relative_speed - states[0]) / args[1]
            return states[0]

        @dataclass(frozen=True)
        class LaggedMotor(Motor):
            name: ClassVar[str] = "lagged_motor_test"
            kernel_size: ClassVar[int] = 2
            kernel: ClassVar = lag_kernel

        LaggedMotor.__module__ = "drillstring.forces.lagged_motor_test"
        register(LaggedMotor)

        @njit
        def rhs(laws, speed, y, out):
            return motor_torque(laws, MotorContext(0.0, speed), y, out)

        laws = np.zeros(len(HEADER) + 2)
        laws[MOTOR_CODE] = LaggedMotor.component_code
        laws[MOTOR] = len(HEADER)
        laws[MOTOR_STATES] = 3
        laws[len(HEADER):] = [-40.0, 0.5]
        y = np.array([0.0, 0.0, 0.0, 100.0])
        out = np.full(4, np.nan)
        torque = rhs(laws, 2.0, y, out)
        print(json.dumps([torque, out[3]]))
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    torque, rate = json.loads(done.stdout.strip().splitlines()[-1])
    assert torque == 100.0 and rate == pytest.approx((-40.0 * 2.0 - 100.0) / 0.5)
