"""The hook load during a realistic start: the bit lowered to the rock and the weight-on-bit ramped up.

The reduced model is written about the static state in which the rock carries the weight-on-bit ``W``
and the hook the rest of the string's weight (docs/model.md §6). In the reference start the bit sits on that
state from t = 0 and the bit–rock law is switched on at once. The **realistic start** (a case option,
``initial.start = "ramp"``) instead begins as a driller does: the string turning off bottom, the hook
carrying the whole string (the bit carries nothing), then the hook load slacked off linearly so that the
weight transferred to the bit grows from 0 to ``W`` over ``ramp_time``::

    hook load = static hook load + W (1 − min(t / ramp_time, 1))

i.e. relative to the static state an extra upward force ``W (1 − r(t))`` at the top, ``r = min(t/T, 1)``.
The string, free axially, moves down under the growing imbalance until the bit meets the rock
(:attr:`HookLoadRamp.clearance` below it at t = 0), then the rock takes the weight as it is transferred.
After ``ramp_time`` the hook load is the static one.

Two components of the protocol (:class:`~drillstring.forces.registry.HookLoad`, :mod:`drillstring.forces.registry`),
named by the case's ``initial.start``: :class:`OnBottomStart` (``"on_bottom"``, the reference start: no extra
force, code 0, nothing in the kernels) and :class:`HookLoadRamp` (``"ramp"``: its keys
:class:`~drillstring.case.RampStartKeys`, the numbers :meth:`HookLoadRamp.kernel_array` the compiled kernel
:func:`hook_load_change` reads, which :meth:`HookLoadRamp.evaluate_at` applies over an array of times). A ramp
time of 0 is the reference start (no extra force). The load is a prescribed function of time: no Jacobian on the state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from typing import ClassVar

from numba import njit

from drillstring.case import RampStartKeys
from drillstring.forces.registry import HookContext, HookLoad, register

__all__ = ["HookLoadRamp", "KERNEL_SIZE", "OnBottomStart", "hook_load_change"]

#: Entries of :meth:`HookLoadRamp.kernel_array`: ``[ramp_time, weight_on_bit]``.
KERNEL_SIZE = 2


@njit(cache=True)
def hook_load_change(args, ctx):
    """The extra axial force [N] on the string's top along +x (down) at time ``ctx.time`` [s]
    (:class:`~drillstring.forces.registry.HookContext`) for the numbers ``args`` of
    :meth:`HookLoadRamp.kernel_array`: ``−W (1 − min(t/T, 1))`` (the hook holds back the weight not yet
    transferred to the bit); 0 when ``T = 0``."""
    t = ctx.time
    ramp_time = args[0]
    if ramp_time <= 0.0 or t >= ramp_time:
        return 0.0
    return -args[1] * (1.0 - t / ramp_time)


@register
@dataclass(frozen=True)
class OnBottomStart(HookLoad):
    """The reference start (``initial.start = "on_bottom"``): the bit on the static state from t = 0, the hook
    load the static one throughout (no extra force; the kernels add nothing)."""

    name: ClassVar[str] = "on_bottom"
    adds: ClassVar[bool] = False

    @classmethod
    def from_case(cls, case, weight_on_bit: float) -> "OnBottomStart":
        return cls()


@register
@dataclass(frozen=True)
class HookLoadRamp(HookLoad):
    """The realistic start (module docstring; ``initial.start = "ramp"``): ``weight_on_bit`` W [N] transferred
    to the bit over ``ramp_time`` [s] (0: the reference start, nothing transferred, W on the bit from t = 0), the
    bit ``clearance`` [m] above the rock at t = 0."""

    name: ClassVar[str] = "ramp"
    kernel_size: ClassVar[int] = KERNEL_SIZE
    kernel: ClassVar = hook_load_change
    keys: ClassVar = RampStartKeys

    ramp_time: float = 0.0
    weight_on_bit: float = 0.0
    clearance: float = 0.0

    def __post_init__(self) -> None:
        for name in ("ramp_time", "weight_on_bit", "clearance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} = {value!r}: must be finite and >= 0")

    @classmethod
    def from_case(cls, case, weight_on_bit: float) -> "HookLoadRamp":
        """The case's ramp (``initial.weight_ramp_time``, ``initial.clearance``) of ``weight_on_bit`` [N]."""
        i = case.initial
        return cls(ramp_time=i.weight_ramp_time, weight_on_bit=float(weight_on_bit), clearance=i.clearance)

    @property
    def active(self) -> bool:
        """True for a ramped start."""
        return self.ramp_time > 0.0

    def kernel_array(self) -> np.ndarray:
        """``[ramp_time, W]`` (float64), what :func:`hook_load_change` reads."""
        return np.array([self.ramp_time, self.weight_on_bit], dtype=np.float64)

    def evaluate_at(self, ctx: HookContext):
        """The extra axial force on the top [N] along +x (down) at time(s) ``ctx.time`` [s] (array-like):
        ``−W (1 − min(t/T, 1))``, 0 without a ramp; :func:`hook_load_change` (the load's one implementation)
        applied elementwise."""
        t = np.asarray(ctx.time, dtype=float)
        args = self.kernel_array()
        force = [hook_load_change(args, HookContext(float(time), float(ctx.weight_on_bit))) for time in t.flat]
        return np.array(force, dtype=float).reshape(t.shape)
