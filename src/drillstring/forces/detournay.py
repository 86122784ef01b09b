"""The Detournay bit–rock law for drag (PDC) bits: cutting plus wear-flat friction with a regenerative
depth of cut (Detournay & Defourny 1992; Richard, Germay & Detournay 2004, 2007).

A bit of radius ``a`` [m] with ``n`` identical blades, each followed by a wear flat of length ``l`` [m],
drills rock of intrinsic specific energy ``ε`` [Pa] with a cutting-force inclination ``ζ`` [-]; the flats
press on the rock with the contact stress ``σ`` [Pa] and rub on it with the friction coefficient ``μ`` [-];
``γ`` [-] is the bit geometry factor of the friction torque. With ``d_n`` [m] the depth of cut per blade
(``d = n d_n`` per revolution) the rock exerts on the bit (Richard, Germay & Detournay, J. Sound Vib. 305,
2007, eqs. 4–7)::

    W_c = a ζ ε n d_n,          T_c = ½ a² ε n d_n                   (cutting)
    W_f = a σ l,                T_f = ½ μ γ a W_f                     (wear-flat contact, while advancing)

**Convention.** ``T_f = ½ μ γ a W_f``: with it every steady state in contact lies on the line
``E = E₀ + μ γ S`` (``E = 2T/(a² d)`` the specific energy, ``S = W/(a d)`` the drilling strength,
``E₀ = (1 − μγζ) ε``; Detournay, Richard & Shepherd 2008). Authors who write ``γ μ a W_f`` use a ``γ``
twice ours.

**Depth of cut.** ``d_n(t) = u(t) − u(t − t_n)``, ``θ(t) − θ(t − t_n) = 2π/n``: the bit's axial position
now minus where it was when it had turned one blade sector less (the hole bottom the previous blade
left). The reduced model computes it from its history (:mod:`drillstring.dynamics.delay`) and passes it to
the kernel; this module knows nothing of time.

**Set-valued parts, regularised (decision).** When the bit does not advance (``u̇ = 0``) the flats carry
any force in ``[0, aσl]``; when it does not turn, the torque is any value up to its full value. The kernel
replaces the two set-valued maps by saturations of slopes ``1/v_r`` and ``1/ω_r``::

    W_f = a σ l · clip(u̇ / v_r, 0, 1),       T = (T_c + T_f) · clip(ω / ω_r, −1, 1)

so a bit at rest holds its weight by creeping down at most ``v_r`` and holds a torque below its full value
by turning at most ``ω_r``: it sticks to within ``ω_r`` (default 5e-3 rad/s, 0.05 rpm) and bears weight
to within ``v_r`` (default 2.5e-4 m/s, 0.9 m/h). The slopes are stiff (``aσl/v_r`` is a dashpot of 2.9e8
N·s/m for the published bit) and an explicit integrator resolves them with steps of about 1e-4 s while the
bit sticks or rests; the defaults are the largest values whose metrics agree with those of regularisations
5 times smaller (docs/verification.md: on the published case the stick time fraction is the most sensitive,
0.51 at twice these values, 0.38–0.40 at these and below).
In steady drilling
(``u̇ > v_r``, ``ω > ω_r``) neither saturation is active, so they change neither the steady state nor its
linearisation. **Bit bounce**: ``d_n ≤ 0`` (the bit above the bottom the last blade left) means no contact
at all: no cutting, no flat contact, no torque.

Forces are returned on the string along / about ``+x`` (down; with the top's rotation), like the other
bit–rock laws (:mod:`drillstring.forces.bit_rock`): ``(−W, −T)`` while drilling.

The component (:mod:`drillstring.forces.registry`), registered as ``"detournay"``: :class:`DetournayParameters`
(built from the case by :meth:`DetournayParameters.from_case`), its kernel :func:`detournay_kernel` (reading
the depth of cut of the named context), its Jacobian (:func:`detournay_jacobian`, compiled, which its
``jacobian_at`` and ``depth_partials`` call from Python) and steady drilling in closed form. The law is written
once, in :func:`detournay_force`; :meth:`DetournayParameters.evaluate` (and ``evaluate_at``) apply it
elementwise, and the tests check it against the steady state, the saturations and the friction line above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from typing import ClassVar

import numpy as np
from numba import njit

from drillstring.case import DetournayKeys
from drillstring.forces.registry import BitContext, BitLaw, BitSteadyState, register

__all__ = [
    "DetournayParameters",
    "DetournaySteadyState",
    "KERNEL_SIZE",
    "detournay_force",
    "detournay_force_array",
    "detournay_jacobian",
    "detournay_kernel",
    "detournay_partials",
]

#: Numbers of :meth:`DetournayParameters.kernel_array`: ``[a ζ ε n, ½ a² ε n, a σ l, ½ μ γ a, v_r, ω_r, 2π/n]``.
KERNEL_SIZE = 7


@dataclass(frozen=True)
class DetournaySteadyState:
    """Steady drilling of the Detournay law at a rate of penetration and bit speed (SI units)."""

    rate_of_penetration: float  # V [m/s]
    bit_speed: float  # Ω [rad/s]
    depth_per_revolution: float  # d = 2π V / Ω [m]
    depth_per_blade: float  # d_n = d / n [m]
    delay: float  # t_n = 2π / (n Ω) [s]
    cutting_force: float  # W_c [N]
    contact_force: float  # W_f [N]
    weight_on_bit: float  # W = W_c + W_f [N]
    cutting_torque: float  # T_c [N·m]
    friction_torque: float  # T_f [N·m]
    torque_on_bit: float  # T = T_c + T_f [N·m]


@register
@dataclass(frozen=True)
class DetournayParameters(BitLaw):
    """The bit and the rock of the Detournay law (module docstring; SI units), registered as ``"detournay"``.

    Attributes: ``blades`` n [-], ``radius`` a [m], ``intrinsic_specific_energy`` ε [Pa],
    ``cutting_inclination`` ζ [-], ``contact_stress`` σ [Pa], ``wear_flat_length`` l [m],
    ``friction_coefficient`` μ [-], ``geometry`` γ [-], ``contact_velocity`` v_r [m/s] and
    ``friction_speed`` ω_r [rad/s] (the regularisations of the set-valued parts).
    """

    name: ClassVar[str] = "detournay"
    kernel_size: ClassVar[int] = KERNEL_SIZE
    keys: ClassVar = DetournayKeys
    delayed: ClassVar[bool] = True

    blades: int
    radius: float
    intrinsic_specific_energy: float
    cutting_inclination: float
    contact_stress: float
    wear_flat_length: float
    friction_coefficient: float
    geometry: float = 1.0
    contact_velocity: float = 2.5e-4
    friction_speed: float = 5e-3

    def __post_init__(self) -> None:
        if int(self.blades) != self.blades or self.blades < 1:
            raise ValueError(f"blades = {self.blades!r}: must be a whole number >= 1")
        for name in ("radius", "intrinsic_specific_energy", "contact_velocity", "friction_speed"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} = {value!r}: must be finite and > 0")
        for name in ("cutting_inclination", "contact_stress", "wear_flat_length", "friction_coefficient",
                     "geometry"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} = {value!r}: must be finite and >= 0")

    @classmethod
    def from_case(cls, case) -> "DetournayParameters":
        """The bit and rock of a :class:`~drillstring.case.Case` (``[bit_rock]``, law = "detournay")."""
        b = case.bit_rock
        return cls(blades=b.blades, radius=b.bit_radius, intrinsic_specific_energy=b.intrinsic_specific_energy,
                   cutting_inclination=b.cutting_inclination, contact_stress=b.contact_stress,
                   wear_flat_length=b.wear_flat_length, friction_coefficient=b.friction_coefficient,
                   geometry=b.bit_geometry, contact_velocity=b.contact_velocity, friction_speed=b.friction_speed)

    # -- the protocol (drillstring.forces.registry) -------------------------------------------------------
    def evaluate_at(self, ctx: BitContext):
        """:meth:`evaluate` (the kernel, elementwise) at the context's depth of cut, axial velocity and bit speed."""
        return self.evaluate(ctx.depth_of_cut, ctx.axial_velocity, ctx.bit_speed)

    # jacobian_at(ctx) and depth_partials(ctx) are inherited: detournay_jacobian, the law's compiled Jacobian

    def steady_depth_of_cut(self, rate_of_penetration: float, bit_speed: float) -> float:
        """The depth of cut per blade [m] of steady drilling at ``rate_of_penetration`` V [m/s] and
        ``bit_speed`` Ω [rad/s]: ``V · 2π/(nΩ)`` (the advance over one blade passage)."""
        return rate_of_penetration * self.sector / bit_speed

    def start_depth_of_cut(self, weight_on_bit: float, bit_speed: float) -> float:
        """The depth of cut [m] per blade of steady drilling under ``weight_on_bit`` [N] at ``bit_speed``
        [rad/s] (:meth:`rate_of_penetration`; 0 when the flats carry the whole weight)."""
        return self.steady_depth_of_cut(self.rate_of_penetration(weight_on_bit, bit_speed), bit_speed)

    def steady_drilling(self, bit_speed: float, axial_load: float, resistance: float) -> BitSteadyState | None:
        """Steady drilling at Ω = ``bit_speed`` [rad/s] under ``axial_load`` W [N] less ``resistance`` c
        [N·s/m] times V, in closed form with the flats in contact: ``−f = aσl + a ζ ε n · V (2π/(nΩ))``
        (:meth:`axial_force_affine`), so ``V = (W − aσl) / (a ζ ε n 2π/(nΩ) + c)``. None when V ≤ 0."""
        f0, f1 = self.axial_force_affine(bit_speed)
        rop = (axial_load + f0) / (resistance - f1)
        if not rop > 0.0:
            return None
        depth = self.steady_depth_of_cut(rop, bit_speed)
        force, torque = self.evaluate(depth, rop, bit_speed)
        return BitSteadyState(float(rop), float(force), float(torque), float(depth))

    # -- the law's constants ---------------------------------------------------------------------------
    @property
    def sector(self) -> float:
        """``2π/n`` [rad]: the angle between blades, the lag of the depth of cut."""
        return 2.0 * math.pi / self.blades

    @property
    def cutting_stiffness(self) -> float:
        """``a ζ ε n`` [N/m]: cutting force per metre of depth of cut per blade."""
        return self.radius * self.cutting_inclination * self.intrinsic_specific_energy * self.blades

    @property
    def cutting_torque_rate(self) -> float:
        """``½ a² ε n`` [N·m/m]: cutting torque per metre of depth of cut per blade."""
        return 0.5 * self.radius**2 * self.intrinsic_specific_energy * self.blades

    @property
    def contact_force(self) -> float:
        """``a σ l`` [N]: the wear flats' contact force while the bit advances."""
        return self.radius * self.contact_stress * self.wear_flat_length

    @property
    def friction_arm(self) -> float:
        """``½ μ γ a`` [m]: friction torque per newton of contact force."""
        return 0.5 * self.friction_coefficient * self.geometry * self.radius

    @property
    def baseline_specific_energy(self) -> float:
        """``E₀ = (1 − μγζ) ε`` [Pa], where the friction line ``E = E₀ + μγS`` meets ``S = 0``."""
        return (1.0 - self.friction_coefficient * self.geometry * self.cutting_inclination) * \
            self.intrinsic_specific_energy

    def kernel_array(self) -> np.ndarray:
        """The numbers :func:`detournay_force` reads (:data:`KERNEL_SIZE` entries, float64)."""
        return np.array([self.cutting_stiffness, self.cutting_torque_rate, self.contact_force,
                         self.friction_arm, self.contact_velocity, self.friction_speed, self.sector],
                        dtype=np.float64)

    def cutting_force(self, depth_of_cut):
        """``W_c = a ζ ε n d_n`` [N] for the depth of cut per blade ``d_n`` [m] (array-like), 0 off the rock
        (``d_n ≤ 0``): the cutting part of the force on bit; the rest is the wear flats' contact."""
        d = np.asarray(depth_of_cut, dtype=np.float64)
        return np.where(d > 0.0, self.cutting_stiffness * np.maximum(d, 0.0), 0.0)

    # -- the law over arrays and its Jacobian ---------------------------------------------------------------
    def evaluate(self, depth_of_cut, bit_axial_velocity, bit_speed):
        """:func:`detournay_force` (the law's one implementation) applied elementwise: ``(axial_force [N],
        torque [N·m])`` on the string for the depth of cut per blade ``d_n`` [m], the bit's axial velocity u̇
        [m/s] and spin speed ω [rad/s], array-likes broadcast together (scalars in, 0-d arrays out);
        ``(0, 0)`` where ``d_n ≤ 0``."""
        d, u, w = np.broadcast_arrays(np.asarray(depth_of_cut, dtype=np.float64),
                                      np.asarray(bit_axial_velocity, dtype=np.float64),
                                      np.asarray(bit_speed, dtype=np.float64))
        force = np.empty(d.size)
        torque = np.empty(d.size)
        detournay_force_array(self.kernel_array(), np.ascontiguousarray(d).reshape(-1),
                              np.ascontiguousarray(u).reshape(-1), np.ascontiguousarray(w).reshape(-1), force,
                              torque)
        return force.reshape(d.shape), torque.reshape(d.shape)

    def jacobian(self, depth_of_cut: float, bit_axial_velocity: float, bit_speed: float) -> np.ndarray:
        """``[[f_d, f_u, f_ω], [t_d, t_u, t_ω]]``: partial derivatives of the force f [N] and torque t [N·m]
        of :func:`detournay_force` with respect to the depth of cut per blade ``d_n`` [m], the bit's axial
        velocity u̇ [m/s] and spin speed ω [rad/s], in closed form. With ``s_u = clip(u̇/v_r, 0, 1)`` and
        ``s_ω = clip(ω/ω_r, −1, 1)``, ``f = −(a ζ ε n d_n + aσl s_u)``, ``t = −(½a²εn d_n + ½μγa aσl s_u) s_ω``::

            f_d = −a ζ ε n,       f_u = −aσl s_u',                       f_ω = 0,
            t_d = −½ a² ε n s_ω,  t_u = −½ μ γ a aσl s_u' s_ω,           t_ω = −(½a²εn d_n + ½μγa aσl s_u) s_ω',

        ``s_u' = 1/v_r`` for ``0 < u̇ < v_r`` (0 outside), ``s_ω' = 1/ω_r`` for ``|ω| < ω_r`` (0 outside).
        Valid away from the kinks ``u̇ ∈ {0, v_r}``, ``|ω| = ω_r`` and ``d_n = 0``; zero for ``d_n ≤ 0``
        (off the rock). The law's one Jacobian, :func:`detournay_partials` (compiled), called from Python."""
        f_d, f_u, f_w, t_d, t_u, t_w = detournay_partials(self.kernel_array(), float(depth_of_cut),
                                                          float(bit_axial_velocity), float(bit_speed))
        return np.array([[f_d, f_u, f_w], [t_d, t_u, t_w]])

    # -- steady drilling, closed form --------------------------------------------------------------------
    def steady_state(self, rate_of_penetration: float, bit_speed: float) -> DetournaySteadyState:
        """Steady drilling at ``rate_of_penetration`` V [m/s] (> 0) and ``bit_speed`` Ω [rad/s] (> 0):
        ``d = 2πV/Ω``, ``t_n = 2π/(nΩ)``, then the forces of the module docstring (flats in contact)."""
        if not (rate_of_penetration > 0.0 and bit_speed > 0.0):
            raise ValueError(f"steady drilling needs rate_of_penetration > 0 and bit_speed > 0, got "
                             f"{rate_of_penetration!r} m/s and {bit_speed!r} rad/s")
        depth = 2.0 * math.pi * rate_of_penetration / bit_speed
        depth_blade = depth / self.blades
        cutting_force = self.cutting_stiffness * depth_blade
        cutting_torque = self.cutting_torque_rate * depth_blade
        friction_torque = self.friction_arm * self.contact_force
        return DetournaySteadyState(
            rate_of_penetration=float(rate_of_penetration), bit_speed=float(bit_speed),
            depth_per_revolution=depth, depth_per_blade=depth_blade, delay=self.sector / bit_speed,
            cutting_force=cutting_force, contact_force=self.contact_force,
            weight_on_bit=cutting_force + self.contact_force, cutting_torque=cutting_torque,
            friction_torque=friction_torque, torque_on_bit=cutting_torque + friction_torque,
        )

    def rate_of_penetration(self, weight_on_bit: float, bit_speed: float) -> float:
        """Steady rate of penetration [m/s] under ``weight_on_bit`` W [N] at ``bit_speed`` Ω [rad/s]:
        ``V = (W − aσl) Ω / (2π a ζ ε)``; 0 when ``W ≤ aσl`` (the flats carry the whole weight, nothing
        is cut: the bit does not advance)."""
        excess = weight_on_bit - self.contact_force
        if excess <= 0.0 or self.cutting_stiffness == 0.0:
            return 0.0
        return excess / self.cutting_stiffness * self.blades * bit_speed / (2.0 * math.pi)

    def axial_force_affine(self, bit_speed: float) -> tuple[float, float]:
        """``(f0 [N], f1 [N·s/m])`` with the steady axial force on the string ``f = f0 + f1 V`` at bit
        speed Ω [rad/s] while drilling: ``f0 = −aσl``, ``f1 = −a ζ ε n · 2π/(nΩ)``."""
        return -self.contact_force, -self.cutting_stiffness * self.sector / bit_speed

    def specific_energy(self, state: DetournaySteadyState) -> float:
        """``E = 2T/(a² d)`` [Pa] of a steady state (``d`` per revolution)."""
        return 2.0 * state.torque_on_bit / (self.radius**2 * state.depth_per_revolution)

    def drilling_strength(self, state: DetournaySteadyState) -> float:
        """``S = W/(a d)`` [Pa] of a steady state (``d`` per revolution)."""
        return state.weight_on_bit / (self.radius * state.depth_per_revolution)


@njit(cache=True)
def detournay_force(args, depth_of_cut, bit_axial_velocity, bit_speed):
    """The Detournay law's ``(axial_force [N], torque [N·m])`` on the string (module docstring) for the
    numbers ``args`` of :meth:`DetournayParameters.kernel_array`, the depth of cut per blade
    ``depth_of_cut`` d_n [m], the bit's axial velocity u̇ [m/s] (> 0 drilling) and spin speed ω [rad/s].
    ``(0, 0)`` when ``d_n ≤ 0`` (the bit is off the rock)."""
    if not depth_of_cut > 0.0:
        return 0.0, 0.0
    advance = bit_axial_velocity / args[4]
    advance = min(max(advance, 0.0), 1.0)
    turn = bit_speed / args[5]
    turn = min(max(turn, -1.0), 1.0)
    contact = args[2] * advance
    weight = args[0] * depth_of_cut + contact
    torque = (args[1] * depth_of_cut + args[3] * contact) * turn
    return -weight, -torque


@njit(cache=True)
def detournay_kernel(args, ctx):
    """The component's compiled kernel: :func:`detournay_force` at the context's depth of cut, axial velocity
    and bit speed (:class:`~drillstring.forces.registry.BitContext`)."""
    return detournay_force(args, ctx.depth_of_cut, ctx.axial_velocity, ctx.bit_speed)


DetournayParameters.kernel = detournay_kernel


@njit(cache=True)
def detournay_partials(args, depth_of_cut, bit_axial_velocity, bit_speed):
    """``(f_d, f_u, f_ω, t_d, t_u, t_ω)``: the partials of :func:`detournay_force` in the depth of cut per blade
    [m], the axial velocity [m/s] and the spin speed [rad/s], in closed form (:meth:`DetournayParameters.jacobian`);
    zeros off the rock (``d_n ≤ 0``)."""
    if not depth_of_cut > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    v_r, w_r = args[4], args[5]
    advance = min(max(bit_axial_velocity / v_r, 0.0), 1.0)
    turn = min(max(bit_speed / w_r, -1.0), 1.0)
    advance_slope = 1.0 / v_r if 0.0 < bit_axial_velocity < v_r else 0.0
    turn_slope = 1.0 / w_r if abs(bit_speed) < w_r else 0.0
    full_torque = args[1] * depth_of_cut + args[3] * (args[2] * advance)
    return (-args[0], -args[2] * advance_slope, 0.0,
            -args[1] * turn, -args[3] * args[2] * advance_slope * turn, -full_torque * turn_slope)


@njit(cache=True)
def detournay_jacobian(args, ctx):
    """The component's compiled Jacobian (its ``jacobian_kernel``, the one its ``jacobian_at``, its
    ``depth_partials`` and the compiled stiff part call): ``(f_u, f_ω, f_d, t_u, t_ω, t_d)`` of
    :func:`detournay_partials` at the context's depth of cut, axial velocity and bit speed."""
    f_d, f_u, f_w, t_d, t_u, t_w = detournay_partials(args, ctx.depth_of_cut, ctx.axial_velocity, ctx.bit_speed)
    return f_u, f_w, f_d, t_u, t_w, t_d


DetournayParameters.jacobian_kernel = detournay_jacobian


@njit(cache=True)
def detournay_force_array(args, depth_of_cut, bit_axial_velocity, bit_speed, axial_force, torque):
    """Loop of :func:`detournay_force` over 1-D arrays; fills ``axial_force`` [N] and ``torque`` [N·m] in place."""
    for i in range(depth_of_cut.shape[0]):
        axial_force[i], torque[i] = detournay_force(args, depth_of_cut[i], bit_axial_velocity[i], bit_speed[i])
