"""The bit off bottom: no bit–rock force, registered as the bit–rock law ``"off_bottom"`` (docs/extending.md).

The bit hangs free above the rock: the rock exerts neither force nor torque on it, the weight-on-bit is 0 and
the hook carries the whole string. Its steady state is rotation without penetration (rate of penetration 0)
and its Jacobian is zero. A component of :mod:`drillstring.forces.registry` with no numbers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from drillstring.forces.registry import BitContext, BitLaw, BitSteadyState, register

__all__ = ["OffBottom", "off_bottom_jacobian", "off_bottom_kernel"]


@njit(cache=True)
def off_bottom_kernel(args, ctx):
    """No force, no torque: ``(0.0, 0.0)`` whatever the context."""
    return 0.0, 0.0


@njit(cache=True)
def off_bottom_jacobian(args, ctx):
    """Its compiled Jacobian (``jacobian_kernel``): six zeros, ``(f_u, f_θ, f_d, t_u, t_θ, t_d)``."""
    return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@register
@dataclass(frozen=True)
class OffBottom(BitLaw):
    """The bit off bottom (module docstring); no parameters."""

    name: ClassVar[str] = "off_bottom"
    kernel_size: ClassVar[int] = 0
    kernel: ClassVar = off_bottom_kernel
    jacobian_kernel: ClassVar = off_bottom_jacobian
    on_bottom: ClassVar[bool] = False

    @classmethod
    def from_case(cls, case) -> "OffBottom":
        return cls()

    def kernel_array(self) -> np.ndarray:
        return np.zeros(0)

    def evaluate_at(self, ctx: BitContext):
        """Zeros shaped as the context's broadcast fields."""
        shape = np.broadcast(np.asarray(ctx.axial_velocity), np.asarray(ctx.bit_speed)).shape
        return np.zeros(shape), np.zeros(shape)

    def steady_drilling(self, bit_speed: float, axial_load: float, resistance: float) -> BitSteadyState:
        """Rotation without penetration: rate of penetration 0, no force, no torque."""
        return BitSteadyState(0.0, 0.0, 0.0)
