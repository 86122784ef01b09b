"""The downhole positive-displacement (Moineau) mud motor: a rotor between two sections of the string.

The mud pumped down the string through the motor's power section turns its rotor relative to its stator (the
housing, part of the string above); the rotor turns the string below (drive shaft, bit). A motor of
displacement ``V`` [m³ per revolution] (``v = V/2π`` per radian) passing the flow ``Q`` [m³/s] with the
differential pressure ``Δp`` [Pa] across it gives, ideally, the rotor speed ``Q/v`` and the torque ``v Δp``
(the hydraulic power ``Q Δp`` turned into the mechanical power ``T ω``). With the volumetric efficiency ``η_v``
(the mud that slips past the seal lines without turning the rotor) and the mechanical efficiency ``η_m``
(friction in the power section) these are the relations of the positive-displacement motor in Samuel & Miska,
"Analytical study of the performance of positive displacement motor (PDM): modeling for incompressible
fluid", SPE 39026 (1997), and R. Samuel, *Downhole Drilling Tools: Theory and Practice for Engineers and
Students*, Gulf Publishing (2007), chapter on positive displacement motors::

    no-load speed   ω₀ = η_v Q / v = 2π η_v Q / V,
    torque          T  = η_m v Δp = η_m V Δp / (2π).                                               (1)

The slip past the seal lines grows with the differential pressure, so the rotor slows down as the load
grows; the motor's performance sheets draw that droop as a straight line of speed against differential
pressure, from the no-load speed at ``Δp = 0`` to stall at the maximum differential pressure ``Δp_s``. Here
that line is the motor's law, written as the torque the rotor gives at its speed ``ω_m`` relative to the
stator::

    T(ω_m) = T_s (1 − ω_m / ω₀),     T_s = η_m v Δp_s  (the stall torque),
    Δp(T)  = T / (η_m v).                                                                          (2)

``T(ω_m)`` is the linear no-load-speed / stall-torque model: ``T = 0`` at the no-load speed, ``T_s`` at stall;
it is used as written outside ``[0, ω₀]`` too (a rotor turned backwards gives more than the stall torque, one
overrun beyond the no-load speed brakes), a choice of this model, not a property taken from the sources.
Its slope ``dT/dω_m = −T_s/ω₀`` is a viscous damper across the rotor: the motor damps the torsional motion
of the string below it.

In the reduced model (:mod:`drillstring.dynamics.rom`) the motor is a component
(:mod:`drillstring.forces.registry`, registered as ``"positive_displacement"``): ``+T`` on the rotor side
of the rotor station and ``−T`` on the stator side, through the mode shapes of the torsional family in which
:mod:`drillstring.rotor` released the rotor's rotation; ``ω_m`` is the rotor's speed less the stator's.
The bit's speed is then the string's speed above the motor plus ``ω_m``. SI units throughout.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from drillstring.case import DownholeMotor
from drillstring.forces.registry import Motor, MotorContext, case_keys, register
from drillstring.forces.registry import motor as registered_motor

__all__ = ["PositiveDisplacementMotor", "case_motor", "positive_displacement_kernel", "positive_displacement_slope"]


@njit(cache=True)
def positive_displacement_kernel(args, ctx, states, rates):
    """Eq. (2): the rotor's torque [N·m] at its speed ``ctx.relative_speed`` ω_m [rad/s] relative to the stator
    (:class:`~drillstring.forces.registry.MotorContext`); ``args`` = [T_s (stall torque, N·m), ω₀ (no-load
    speed, rad/s)]; no states (``states``, ``rates`` empty)."""
    return args[0] * (1.0 - ctx.relative_speed / args[1])


@njit(cache=True)
def positive_displacement_slope(args, ctx, states):
    """The motor's compiled Jacobian (its ``jacobian_kernel``, the one its ``jacobian_at`` and the compiled
    stiff part call): ``dT/dω_m = −T_s/ω₀`` [N·m·s/rad] of eq. (2), the same at every speed (the law is
    linear); ``args`` as :func:`positive_displacement_kernel`'s."""
    return -args[0] / args[1]


@register
@dataclass(frozen=True)
class PositiveDisplacementMotor(Motor):
    """A positive-displacement motor (module docstring), SI: ``position`` [m] of the rotor station from the top,
    ``flow_rate`` Q [m³/s], ``displacement`` v [m³/rad] (V/2π), ``stall_torque`` T_s [N·m],
    ``volumetric_efficiency`` η_v, ``mechanical_efficiency`` η_m [-]."""

    name: ClassVar[str] = "positive_displacement"
    kernel_size: ClassVar[int] = 2
    kernel: ClassVar = positive_displacement_kernel
    jacobian_kernel: ClassVar = positive_displacement_slope
    keys: ClassVar = DownholeMotor

    position: float
    flow_rate: float
    displacement: float
    stall_torque: float
    volumetric_efficiency: float = 1.0
    mechanical_efficiency: float = 1.0

    def __post_init__(self) -> None:
        for field, low, high in (("position", 0.0, np.inf), ("flow_rate", 0.0, np.inf),
                                 ("displacement", 0.0, np.inf), ("stall_torque", 0.0, np.inf),
                                 ("volumetric_efficiency", 0.0, 1.0), ("mechanical_efficiency", 0.0, 1.0)):
            value = getattr(self, field)
            if not (isinstance(value, (int, float, np.floating)) and low < value <= high and np.isfinite(value)):
                raise ValueError(f"motor {field} = {value!r}: must be a finite number in ({low:g}, {high:g}]")

    @classmethod
    def from_case(cls, case) -> PositiveDisplacementMotor | None:
        """The case's ``[motor]`` (None without): its flow rate by default the case's pumped flow
        (``fluid.flow_rate``), its displacement from ``speed_per_flow`` when given so, its stall torque from
        ``max_differential_pressure`` by eq. (2) when given so."""
        if case.motor is None or case.motor.law != cls.name:
            return None
        m = case_keys(case.motor, cls)
        flow = case.flow_rate if m.flow_rate is None else m.flow_rate
        if not flow > 0.0:
            raise ValueError(f"motor.flow_rate: the case pumps no mud (fluid flow rate {flow:g} m3/s): give "
                             f"fluid.flow_rate or motor.flow_rate > 0")
        displacement = m.displacement if m.displacement is not None else 1.0 / m.speed_per_flow
        stall = (m.stall_torque if m.stall_torque is not None
                 else m.mechanical_efficiency * displacement * m.max_differential_pressure)
        return cls(position=float(m.position), flow_rate=float(flow), displacement=float(displacement),
                   stall_torque=float(stall), volumetric_efficiency=float(m.volumetric_efficiency),
                   mechanical_efficiency=float(m.mechanical_efficiency))

    @property
    def no_load_speed(self) -> float:
        """ω₀ = η_v Q / v [rad/s], eq. (1)."""
        return self.volumetric_efficiency * self.flow_rate / self.displacement

    @property
    def max_differential_pressure(self) -> float:
        """Δp_s = T_s / (η_m v) [Pa], the differential pressure at stall."""
        return self.differential_pressure(self.stall_torque)

    def kernel_array(self) -> np.ndarray:
        return np.array([self.stall_torque, self.no_load_speed])

    def evaluate(self, relative_speed):
        """Eq. (2): the torque [N·m] at ``relative_speed`` ω_m [rad/s] (array-like; scalars in, 0-d arrays out),
        :func:`positive_displacement_kernel` (the law's one implementation) applied elementwise."""
        speeds = np.asarray(relative_speed, dtype=float)
        args, none = self.kernel_array(), np.zeros(0)
        torque = [positive_displacement_kernel(args, MotorContext(0.0, float(w)), none, none) for w in speeds.flat]
        return np.array(torque, dtype=float).reshape(speeds.shape)

    def evaluate_at(self, ctx: MotorContext, states) -> tuple[float, np.ndarray]:
        """The kernel at ``ctx`` (:meth:`evaluate`): ``(T [N·m], no rates)``."""
        return self.evaluate(ctx.relative_speed), np.zeros(0)

    # jacobian_at(ctx, states) is inherited: [[dT/dω_m]] of positive_displacement_slope, its compiled Jacobian

    def speed_at(self, torque):
        """The rotor's speed ω_m [rad/s] relative to the stator at which it gives ``torque`` [N·m] (eq. (2)
        inverted)."""
        return self.no_load_speed * (1.0 - np.asarray(torque, dtype=float) / self.stall_torque)

    def differential_pressure(self, torque):
        """Δp = T / (η_m v) [Pa] across the power section for the rotor torque ``torque`` [N·m], eq. (2)."""
        return np.asarray(torque, dtype=float) / (self.mechanical_efficiency * self.displacement)

    def describe(self) -> dict:
        return {"motor": self.name, "position": self.position, "flow_rate": self.flow_rate,
                "displacement": self.displacement, "stall_torque": self.stall_torque,
                "no_load_speed": self.no_load_speed, "max_differential_pressure": self.max_differential_pressure,
                "volumetric_efficiency": self.volumetric_efficiency,
                "mechanical_efficiency": self.mechanical_efficiency}


def case_motor(case) -> Motor | None:
    """The downhole motor of a :class:`~drillstring.case.Case` (its ``[motor]``; the registered motor that
    ``motor.law`` names), None without one."""
    if case.motor is None:
        return None
    return registered_motor(case.motor.law, "motor.law").from_case(case)
