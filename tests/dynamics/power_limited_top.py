"""A top boundary the package does not have, written as a new contributor would: one module and its case table.

A drive whose torque follows a proportional speed controller, limited by the motor's power: ``τ_m = k (Ω − θ̇₀)``
while ``τ_m θ̇₀ ≤ P``, else ``τ_m = P / θ̇₀``. Stateless. Its case table: ``[top_drive] boundary =
"power_limited_test"`` and its keys in ``[top_drive.power_limited_test]`` (``power`` [W], ``gain`` [N·m·s/rad],
``inertia`` [kg·m²]). Nothing else in the package names it: the registry, the case and the stability analysis
ask it. Registered from outside the package, it runs through the NumPy reference engine.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from drillstring.case import MomentOfInertia, RotationalDamping
from drillstring.forces.registry import TopBoundary, TopContext, case_keys, register


class PowerLimitedKeys(BaseModel):
    """``[top_drive.power_limited_test]``."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    power: float = Field(gt=0, description="largest motor power P [W]")
    gain: RotationalDamping = Field(gt=0, description="proportional gain k [N*m*s/rad]")
    inertia: MomentOfInertia = Field(1000.0, gt=0, description="rotary inertia at the quill [kg*m^2]")


@njit(cache=False)
def power_limited_kernel(args, ctx, states, rates):
    """``[P, k, Ω]`` -> the motor torque [N·m]."""
    speed = ctx.quill_speed
    torque = args[1] * (args[2] - speed)
    if speed > 0.0 and torque * speed > args[0]:
        return args[0] / speed
    return torque


@register
@dataclass(frozen=True)
class PowerLimitedTop(TopBoundary):
    name: ClassVar[str] = "power_limited_test"
    kernel_size: ClassVar[int] = 3
    kernel: ClassVar = power_limited_kernel
    keys: ClassVar = PowerLimitedKeys

    set_point: float  # Ω [rad/s]
    power: float  # P [W]
    gain: float  # k [N·m·s/rad]
    inertia: float  # [kg·m²]

    @classmethod
    def from_case(cls, case, stick_slip_frequency=None):
        keys = case_keys(case.top_drive, cls)
        return cls(case.operation.top_speed, keys.power, keys.gain, keys.inertia)

    @property
    def top_inertia(self):
        return self.inertia

    def _limited(self, speed):
        return speed > 0.0 and self.gain * (self.set_point - speed) * speed > self.power

    def kernel_array(self):
        return np.array([self.power, self.gain, self.set_point])

    def evaluate_at(self, ctx: TopContext, states):
        speed = float(ctx.quill_speed)
        torque = self.power / speed if self._limited(speed) else self.gain * (self.set_point - speed)
        return torque, np.zeros(0)

    def jacobian_at(self, ctx: TopContext, states):
        speed = float(ctx.quill_speed)
        slope = -self.power / speed**2 if self._limited(speed) else -self.gain
        return np.array([[slope, 0.0]])

    def steady_speed(self, motor_torque):
        proportional = self.set_point - motor_torque / self.gain
        if motor_torque * proportional <= self.power:
            return proportional
        return self.power / motor_torque

    def describe(self):
        return {"top_boundary": self.name, "power": self.power, "gain": self.gain, "inertia": self.inertia}
