"""Along-string friction in a deviated well: the classical soft-string dynamic model along measured depth
(Aarsnes & van de Wouw 2019, §2; Johancsik, Friesen & Dawson 1984 for the statics).

At every node ``i`` that rests on the wall in the static state (the stiff string in the well,
:mod:`drillstring.well.stiff_string`), the wall presses the string with the static normal force ``N_i`` [N]
(the node's wall force, tributary length included) and resists the sliding of the contact point with a Coulomb
force of coefficient ``μ_i`` (the well's ``cased_hole_friction`` above the casing shoe, ``open_hole_friction``
below, as :func:`drillstring.well.torque_drag._friction`). The contact point at radius ``r_i`` (the pipe body,
or the tool joint where the case gives one: :func:`drillstring.well.torque_drag._section_table`) slides with
the axial velocity ``u̇_i`` along the string and the circumferential one ``r_i θ̇_i``; the friction acts against
that velocity, regularised by the speed ``v_reg``::

    v_i = sqrt(u̇_i² + (r_i θ̇_i)²),   s_i = sqrt(v_i² + v_reg²)
    g(v) = 1 + (k_s − 1) exp(−v / v_S)      (Stribeck: k_s μ at rest, μ sliding fast)
    f_i = −μ_i g(v_i) N_i u̇_i / s_i               axial force on the string [N]              (1)
    τ_i = −μ_i g(v_i) N_i r_i (r_i θ̇_i) / s_i     torque about the string's axis [N·m]      (2)

For ``v_reg → 0`` this is ``μ N`` along the sliding direction (the combined axial and circumferential
direction: a string rotating at ``Ω`` while moving axially at ``V`` takes the axial drag ``μ N V / sqrt(V² +
(rΩ)²)``, the soft-string model's reduction of drag by rotation); at ``|v| ≪ v_reg`` a viscous law of
coefficient ``k_s μ N / v_reg``. The static factor ``k_s`` (≥ 1; 1 by default: the kinetic coefficient alone)
raises the coefficient towards rest over the Stribeck speed ``v_S``: a friction that weakens with speed, the
mechanism of the string's own stick-slip. The friction's power ``f u̇ + τ θ̇ = −μ g N (u̇² + r² θ̇²)/s ≤ 0``:
it never feeds energy in.

The normal forces are the static ones, held fixed during the run (the dynamic lateral motion does not change
them; the lateral dynamics of the reduced model stays that of a straight string: docs/stiff_string.md).

SI units throughout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from drillstring.case import StringFrictionKeys
from drillstring.forces.registry import StringFriction, StringFrictionContext, case_keys, register

__all__ = ["CoulombStringFriction", "FrictionStations", "coulomb_string_friction_kernel"]


@njit(cache=True)
def coulomb_string_friction_kernel(args, ctx, force, torque):
    """Eqs. (1)-(2) at every station of ``ctx`` (:class:`~drillstring.forces.registry.StringFrictionContext`),
    ``args = [v_reg [m/s], k_s [-], v_S [m/s]]``: fills ``force`` [N] and ``torque`` [N·m] on the string."""
    v_reg2 = args[0] * args[0]
    excess = args[1] - 1.0
    for i in range(force.shape[0]):
        r = ctx.radius[i]
        axial = ctx.axial_velocity[i]
        circumferential = r * ctx.spin_speed[i]
        sliding2 = axial * axial + circumferential * circumferential
        scale = ctx.friction[i] * ctx.normal_force[i] / math.sqrt(sliding2 + v_reg2)
        if excess != 0.0:
            scale *= 1.0 + excess * math.exp(-math.sqrt(sliding2) / args[2])
        force[i] = -scale * axial
        torque[i] = -scale * r * circumferential


@register
@dataclass(frozen=True)
class CoulombStringFriction(StringFriction):
    """Kinetic Coulomb friction along the string, regularised (module docstring, eqs. (1)-(2)).

    Attributes:
        regularization_speed: v_reg [m/s] (> 0).
        static_factor: k_s [-] (≥ 1): the coefficient at rest over the kinetic one (1: kinetic only).
        stribeck_speed: v_S [m/s] (> 0): the sliding speed over which it decays to the kinetic one.
    """

    name: ClassVar[str] = "coulomb"
    kernel_size: ClassVar[int] = 3
    kernel: ClassVar = coulomb_string_friction_kernel
    keys: ClassVar = StringFrictionKeys

    regularization_speed: float = 0.01
    static_factor: float = 1.0
    stribeck_speed: float = 0.1

    def __post_init__(self) -> None:
        for field, low, unit, strict in (("regularization_speed", 0.0, "m/s", True), ("static_factor", 1.0, "", False),
                                         ("stribeck_speed", 0.0, "m/s", True)):
            v = getattr(self, field)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and (v > low if strict else v >= low)):
                raise ValueError(f"string_friction {field} = {v!r}{' ' + unit if unit else ''}: must be a finite "
                                 f"number {'>' if strict else '>='} {low:g}")

    @classmethod
    def from_case(cls, case) -> CoulombStringFriction:
        keys = case_keys(case.string_friction, cls)
        return cls(regularization_speed=float(keys.regularization_speed), static_factor=float(keys.static_factor),
                   stribeck_speed=float(keys.stribeck_speed))

    def kernel_array(self) -> np.ndarray:
        return np.array([self.regularization_speed, self.static_factor, self.stribeck_speed], dtype=np.float64)

    def jacobian_at(self, ctx: StringFrictionContext) -> np.ndarray:
        """(n, 2, 2): ∂(f, τ)/∂(u̇, θ̇x) of eqs. (1)-(2) per station, in closed form: with the sliding velocity
        ``p = (u̇, r θ̇)``, ``(f, τ/r) = −μ N h(v) p``, ``h = g(v)/s``, ``∂/∂p = −μ N (h I + p ⊗ h'(v) p/v)``
        (at ``v = 0`` the Stribeck term's direction is undefined: taken as 0)."""
        u = np.asarray(ctx.axial_velocity, dtype=float)
        r = np.broadcast_to(np.asarray(ctx.radius, dtype=float), u.shape)
        c = r * np.asarray(ctx.spin_speed, dtype=float)
        mu_n = np.asarray(ctx.friction, dtype=float) * np.asarray(ctx.normal_force, dtype=float)
        v = np.hypot(u, c)
        s = np.sqrt(v * v + self.regularization_speed**2)
        decay = (self.static_factor - 1.0) * np.exp(-v / self.stribeck_speed)
        g = 1.0 + decay
        h = g / s
        dh_dv = -decay / self.stribeck_speed / s - g * v / s**3
        radial = np.divide(dh_dv, v, out=np.zeros_like(v), where=v > 0.0)  # h'(v)/v
        a = np.empty(u.shape + (2, 2))
        a[..., 0, 0] = h + u * radial * u
        a[..., 0, 1] = u * radial * c
        a[..., 1, 0] = c * radial * u
        a[..., 1, 1] = h + c * radial * c
        out = np.empty(u.shape + (2, 2))
        out[..., 0, 0] = -mu_n * a[..., 0, 0]
        out[..., 0, 1] = -mu_n * a[..., 0, 1] * r
        out[..., 1, 0] = -mu_n * r * a[..., 1, 0]
        out[..., 1, 1] = -mu_n * r * r * a[..., 1, 1]
        return out


@dataclass(frozen=True)
class FrictionStations:
    """Where the along-string friction acts: the mesh nodes resting on the wall in the static state.

    Attributes:
        node: (m,) mesh node indices (int).
        normal_force: (m,) the wall's static normal force on each node N_i [N] (> 0).
        radius: (m,) contact radius r_i [m].
        friction: (m,) friction coefficient μ_i [-].
    """

    node: np.ndarray
    normal_force: np.ndarray
    radius: np.ndarray
    friction: np.ndarray

    def __post_init__(self) -> None:
        m = np.asarray(self.node).shape
        for name in ("normal_force", "radius", "friction"):
            values = np.asarray(getattr(self, name), dtype=float)
            if values.shape != m or not np.all(np.isfinite(values)) or np.any(values < 0.0):
                raise ValueError(f"friction stations {name}: must be {m[0] if m else 0} finite numbers >= 0, got "
                                 f"shape {values.shape}")

    def __len__(self) -> int:
        return int(np.asarray(self.node).shape[0])

    @classmethod
    def empty(cls) -> FrictionStations:
        return cls(np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), np.zeros(0))

    def rotating_torque(self) -> float:
        """Σ μ_i N_i r_i [N·m]: the surface torque of the string rotating steadily off bottom (v_reg → 0)."""
        return float(np.sum(self.friction * self.normal_force * self.radius))
