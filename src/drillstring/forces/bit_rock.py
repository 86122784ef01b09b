"""Bit–rock interaction law (docs/model.md §5, ``f_br``).

The law couples the axial and torsional motion of the bit node. It is the model of Tucker & Wang
(R. W. Tucker, C. Wang, "An integrated model for drill-string dynamics", J. Sound Vib. 224(1), 1999;
"Torsional vibration control and Cosserat dynamics of a drill-rig assembly", Meccanica 38, 2003) in the
regularised form used by Ritto, Soize & Sampaio (T. G. Ritto, C. Soize, R. Sampaio, "Non-linear dynamics
of a drill-string with uncertain model of the bit–rock interaction", Int. J. Non-Linear Mech. 44, 2009),
written exactly as in docs/model.md §5::

    f_xbit = − u̇_bit / (a2 Z²) + a3 θ̇_bit / (a2 Z) − a1/a2            [N]
    t_xbit = − u̇_bit a4 Z² / θ̇_bit − a5 Z                              [N·m]
    Z(θ̇) = θ̇ / sqrt(θ̇² + e²)                                          [-]

Sign conventions (docs/model.md §1, §5): ``x`` points down, ``u̇_bit > 0`` is drilling (the bit moves down into the
rock), ``θ̇_bit > 0`` turns with the top. ``f_xbit`` and ``t_xbit`` are the force and torque exerted **on the
string** at the bit node, along / about ``+x``: in steady drilling ``f_xbit = −wob < 0`` (the rock pushes
the bit up) and ``t_xbit = −TOB`` opposes the rotation.

Numerically safe evaluation
---------------------------
The kernels never form ``Z`` and then divide by it. With ``h = hypot(θ̇, e) = sqrt(θ̇² + e²)`` (computed
without overflow) they use the exact identities::

    Z = θ̇ / h,      Z²/θ̇ = θ̇ / (θ̇² + e²) = Z / h,      θ̇/Z = h,      1/Z² = 1 + (e/θ̇)².

All are finite at ``θ̇ = 0`` except ``1/Z²``, which grows like ``e²/θ̇²``: the law stiffens without bound as
the bit sticks (``θ̇ -> 0``). Physically, a bit that does not turn cannot cut, so the law drives ``u̇_bit``
to zero with an axial "viscous" coefficient ``1/(a2 Z²)`` that becomes infinite.

**Stick handling (decision).** The exact law is kept for ``|θ̇| ≥ θ̇_floor``. Below it, ``1/Z²`` is evaluated
with ``|θ̇|`` replaced by ``θ̇_floor`` (``1/Z² = 1 + (e/θ̇_floor)²``), so the force is finite and continuous
for every finite input, including ``θ̇ = 0`` exactly. ``θ̇_floor = STICK_SPEED_FLOOR_RATIO · e`` by default
(``1e-6 · e``, i.e. 2 µrad/s for the reference ``e = 2 rad/s``), giving at most ``1/Z² ≈ 1e12``: at
``θ̇ = 0`` the axial force is ``−u̇ (1 + 1e12)/a2 + a3 e/a2 − a1/a2``, a very stiff finite reaction that
stops penetration — the stick limit of the law, not a NaN. The other terms use their exact limits
(``θ̇/Z -> e``, ``Z -> 0``, ``Z²/θ̇ -> 0``), so at stick the bit–rock torque is zero (the regularised law
has no static friction at the bit). Callers that prefer a larger floor (an explicit integrator resolves
the axial time scale ``m a2 Z²``, which collapses at stick) use :func:`bit_rock_force_floored` or
``BitRockParameters.stick_speed_floor_ratio``.

If ``e = 0`` (unregularised law, ``Z = sgn θ̇``) the kernels return ``Z = 0`` and ``1/Z² = 1`` at ``θ̇ = 0``.

The component (docs/extending.md)
---------------------------------
The law is one component of the reduced model (:mod:`drillstring.forces.registry`), registered as
``"tucker_wang"``: :class:`BitRockParameters` is its parameters (built from the case in one place,
:meth:`BitRockParameters.from_case`), the numbers its compiled kernel reads
(:meth:`BitRockParameters.kernel_array`, :data:`KERNEL_SIZE` entries), the compiled kernel
:func:`tucker_wang_kernel` (reading the named context :class:`~drillstring.forces.registry.BitContext`),
its Jacobian :func:`tucker_wang_jacobian` (compiled; :func:`bit_rock_jacobian` calls it from Python) and its
steady drilling (:meth:`BitRockParameters.steady_drilling`,
closed form). The law is written once, in the kernel: :func:`evaluate_bit_rock` (the component's
``evaluate_at``, which the NumPy reference engine calls) applies that kernel elementwise; it is no
independent reference. The tests check the kernel against the law as written above, the steady state's
closed form (:func:`steady_state`) and finite differences of the Jacobian (docs/extending.md). The other
laws are components of their own: :mod:`drillstring.forces.off_bottom` and :mod:`drillstring.forces.detournay`.

**Unilateral contact.** The rock pushes the bit, never pulls it: when the law gives an axial force on the
string pointing down (``f > 0``: it does so when the bit moves up faster than ``a3 h − a1`` over ``1/Z²``,
about 1.9 mm/s at the reference point), the bit has left the rock and the component returns no force and no
torque. The time the force on bit is zero is the bit's bounce.
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from drillstring.case import TuckerWangKeys
from drillstring.forces.registry import BitContext, BitLaw, BitSteadyState, register

__all__ = [
    "KERNEL_SIZE",
    "STICK_SPEED_FLOOR_RATIO",
    "BitRockParameters",
    "regularizer",
    "bit_rock_force",
    "bit_rock_force_floored",
    "bit_rock_law_array",
    "bit_rock_jacobian",
    "case_bit_rock",
    "tucker_wang_jacobian",
    "tucker_wang_kernel",
    "evaluate_bit_rock",
    "steady_state",
    "stick_speed_floor_ratio",
]

#: Entries of :meth:`BitRockParameters.kernel_array`: ``[a1, a2, a3, a4, a5, e, θ̇_floor]``.
KERNEL_SIZE = 7

#: Default ratio ``θ̇_floor / e`` below which ``1/Z²`` is frozen (see module docstring).
STICK_SPEED_FLOOR_RATIO = 1.0e-6


@register
@dataclass(frozen=True)
class BitRockParameters(BitLaw):
    """The Tucker–Wang bit–rock law, registered as ``"tucker_wang"`` (docs/model.md §5, values for the reference case
    in §12).

    Attributes
    ----------
    a1 : float
        [m/s] ROP offset; the bit penetrates only if ``a2 · wob > a1`` (at high speed).
    a2 : float
        [m/(N·s)] ROP per unit weight-on-bit.
    a3 : float
        [m/rad] ROP per unit bit rotation speed (depth of cut per radian).
    a4 : float
        [N·rad] torque-on-bit per unit depth of cut per radian (``a4 · ROP/θ̇``).
    a5 : float
        [N·m] frictional (constant) part of the torque-on-bit.
    e : float
        [rad/s] regularisation speed of ``Z(θ̇) = θ̇/sqrt(θ̇² + e²)`` (Ritto, Soize & Sampaio 2009).
    stick_speed_floor_ratio : float
        [-] ``θ̇_floor / e``: below ``|θ̇| = θ̇_floor`` the term ``1/Z²`` is frozen so that the law stays
        finite at stick (module docstring). Not part of :meth:`as_array`.
    """

    name: ClassVar[str] = "tucker_wang"
    kernel_size: ClassVar[int] = KERNEL_SIZE
    keys: ClassVar = TuckerWangKeys

    a1: float
    a2: float
    a3: float
    a4: float
    a5: float
    e: float
    stick_speed_floor_ratio: float = STICK_SPEED_FLOOR_RATIO

    def __post_init__(self) -> None:
        for name in ("a1", "a2", "a3", "a4", "a5", "e", "stick_speed_floor_ratio"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
        if self.a2 <= 0.0:
            raise ValueError(f"a2 must be > 0 (it divides the law), got {self.a2!r}")
        if self.e < 0.0:
            raise ValueError(f"e must be >= 0, got {self.e!r}")
        if self.stick_speed_floor_ratio < 0.0:
            raise ValueError("stick_speed_floor_ratio must be >= 0")

    @classmethod
    def reference(cls) -> "BitRockParameters":
        """Reference-case coefficients (docs/model.md §12)."""
        return cls(a1=3.429e-3, a2=5.672e-8, a3=1.374e-4, a4=9.537e6, a5=1.475e3, e=2.0)

    @classmethod
    def from_case(cls, case) -> "BitRockParameters":
        """The law of a :class:`~drillstring.case.Case` (``[bit_rock]``: ``a1`` .. ``a5``, ``regularization``)
        with the stick floor from ``stick_stiffening_limit`` at the case's top speed
        (:func:`stick_speed_floor_ratio`)."""
        b = case.bit_rock
        return cls(b.a1, b.a2, b.a3, b.a4, b.a5, b.regularization,
                   stick_speed_floor_ratio(b.regularization, case.operation.top_speed, b.stick_stiffening_limit))

    @property
    def stick_speed_floor(self) -> float:
        """[rad/s] ``θ̇_floor = stick_speed_floor_ratio · e``."""
        return self.stick_speed_floor_ratio * self.e

    def as_array(self) -> np.ndarray:
        """``[a1, a2, a3, a4, a5, e]`` as float64, the argument order of :func:`bit_rock_force`."""
        return np.array(astuple(self)[:6], dtype=np.float64)

    def kernel_args(self) -> tuple[float, ...]:
        """``(a1, a2, a3, a4, a5, e, θ̇_floor)``, the trailing arguments of :func:`bit_rock_force_floored`."""
        return (self.a1, self.a2, self.a3, self.a4, self.a5, self.e, self.stick_speed_floor)

    def kernel_array(self) -> np.ndarray:
        """The numbers :func:`tucker_wang_kernel` reads, float64: ``[a1, a2, a3, a4, a5, e, θ̇_floor]``."""
        return np.array(self.kernel_args(), dtype=np.float64)

    # -- the protocol (drillstring.forces.registry) -------------------------------------------------------
    def evaluate_at(self, ctx: BitContext):
        """The kernel at array-valued contexts: :func:`evaluate_bit_rock` at the context's axial velocity and
        bit speed (the law's one implementation, applied elementwise)."""
        return evaluate_bit_rock(ctx.axial_velocity, ctx.bit_speed, self)

    def steady_drilling(self, bit_speed: float, axial_load: float, resistance: float) -> BitSteadyState | None:
        """Steady drilling at Ω = ``bit_speed`` [rad/s] under ``axial_load`` W [N] less ``resistance`` c
        [N·s/m] times V, in closed form: the law is affine in u̇ at a fixed θ̇, ``f = (−u̇/Z² + a3 h − a1)/a2``
        (``1/Z²`` at the floored speed), so ``V = (W + (a3 h − a1)/a2) / (1/(a2 Z²) + c)`` (with ``c = 0``
        :func:`steady_state`'s ``Z² (a2 W − a1) + Z a3 Ω``). None when V ≤ 0 (the bit would lift off)."""
        omega = float(bit_speed)
        h = math.hypot(omega, self.e)
        speed = max(abs(omega), self.stick_speed_floor)
        inv_z2 = 1.0 + (self.e / speed) ** 2 if speed > 0.0 else 1.0
        offset = (self.a3 * h - self.a1) / self.a2  # f at u̇ = 0 [N]
        rop = (axial_load + offset) / (inv_z2 / self.a2 + resistance)
        if not rop > 0.0:
            return None
        force, torque = self.evaluate(rop, omega)
        return BitSteadyState(float(rop), float(force), float(torque))

    # -- the law in its historical arguments ---------------------------------------------------------------
    def evaluate(self, bit_axial_velocity, bit_speed, depth_of_cut=0.0):
        """:func:`evaluate_bit_rock` of this law: ``(axial_force [N], torque [N·m])`` on the string."""
        return evaluate_bit_rock(bit_axial_velocity, bit_speed, self)

    def steady_forces(self, rate_of_penetration: float, bit_speed: float) -> tuple[float, float]:
        """``(axial_force [N], torque [N·m])`` on the string in steady drilling at ``rate_of_penetration`` V
        [m/s] and ``bit_speed`` Ω [rad/s]: the law at ``u̇ = V``, ``θ̇ = Ω``."""
        force, torque = self.evaluate(rate_of_penetration, bit_speed)
        return float(force), float(torque)

    def jacobian(self, bit_axial_velocity: float, bit_speed: float, depth_of_cut: float = 0.0) -> np.ndarray:
        """:func:`bit_rock_jacobian` of this law."""
        return bit_rock_jacobian(bit_axial_velocity, bit_speed, self)


def stick_speed_floor_ratio(regularization: float, top_speed: float, stiffening_limit: float) -> float:
    """``θ̇_floor / e`` such that the law's axial resistance ``1/(a2 Z²)`` never exceeds
    ``stiffening_limit`` times its value at the top speed Ω [-].

    ``1/Z² = 1 + (e/θ̇)²`` grows without bound as the bit sticks; an explicit integrator must resolve the
    axial time scale it sets (∝ Z²), so the step size would collapse at every stick. Freezing ``1/Z²``
    below ``θ̇_floor`` with ``1 + (e/θ̇_floor)² = K (1 + (e/Ω)²)``, ``K = stiffening_limit``, bounds the
    step-size reduction at stick to about ``K`` while the bit still behaves as blocked axially (its
    resistance is then ``K`` times the drilling value, itself ≈ 12 times the axial impedance of the
    reference drill collar). Measured on a sticking case (docs/verification.md): mean ROP, TOB and the
    stick time fraction change by < 2e-4 between K = 100 and K = 10⁴, at 4 times fewer steps.

    Args: ``regularization`` e [rad/s], ``top_speed`` Ω [rad/s] (> 0), ``stiffening_limit`` K (> 1).
    """
    if not stiffening_limit > 1.0:
        raise ValueError(f"stick stiffening limit = {stiffening_limit!r}: must be > 1")
    if not top_speed > 0.0:
        raise ValueError(f"top_speed = {top_speed!r} rad/s: must be > 0")
    if regularization == 0.0:
        return 0.0
    q_max = stiffening_limit * (1.0 + (regularization / top_speed) ** 2)
    return 1.0 / math.sqrt(q_max - 1.0)


# --------------------------------------------------------------------------------------------------------
# numba kernels (plain floats)
# --------------------------------------------------------------------------------------------------------


@njit(cache=True)
def regularizer(bit_speed, e):
    """``Z = θ̇ / sqrt(θ̇² + e²)`` [-], odd in ``θ̇``, ``|Z| < 1``, ``Z -> ±1`` for ``|θ̇| >> e``.

    ``bit_speed`` θ̇ [rad/s], ``e`` [rad/s]. Evaluated with ``hypot`` (no overflow); ``Z(0) = 0`` also
    when ``e = 0``. Ritto, Soize & Sampaio (2009); docs/model.md §5.
    """
    h = math.hypot(bit_speed, e)
    if h == 0.0:
        return 0.0
    return bit_speed / h


@njit(cache=True)
def bit_rock_force_floored(bit_axial_velocity, bit_speed, a1, a2, a3, a4, a5, e, speed_floor):
    """Bit–rock force and torque on the string, with an explicit stick floor ``speed_floor`` [rad/s].

    Same as :func:`bit_rock_force` (docs/model.md §5, Tucker & Wang 1999/2003, Ritto et al. 2009) except that
    ``1/Z²`` uses ``max(|θ̇|, speed_floor)``. Returns ``(axial_force [N], torque [N·m])``.
    """
    h = math.hypot(bit_speed, e)
    if h == 0.0:
        z = 0.0
        z2_over_speed = 0.0
    else:
        z = bit_speed / h
        z2_over_speed = z / h  # = θ̇ / (θ̇² + e²) = Z²/θ̇
    s = max(abs(bit_speed), speed_floor)
    if s == 0.0:
        if e == 0.0:
            inv_z2 = 1.0
        else:  # zero floor requested at θ̇ = 0: fall back on the default floor
            ratio = 1.0 / STICK_SPEED_FLOOR_RATIO
            inv_z2 = 1.0 + ratio * ratio
    else:
        q = e / s
        inv_z2 = 1.0 + q * q  # = 1/Z² = (θ̇² + e²)/θ̇²
    axial_force = (-bit_axial_velocity * inv_z2 + a3 * h - a1) / a2  # a3 θ̇/(a2 Z) = a3 h / a2
    torque = -bit_axial_velocity * a4 * z2_over_speed - a5 * z
    return axial_force, torque


@njit(cache=True)
def bit_rock_force(bit_axial_velocity, bit_speed, a1, a2, a3, a4, a5, e):
    """Bit–rock axial force [N] and torque [N·m] exerted on the string (docs/model.md §5).

    ``f = −u̇/(a2 Z²) + a3 θ̇/(a2 Z) − a1/a2``, ``t = −u̇ a4 Z²/θ̇ − a5 Z``, ``Z = θ̇/sqrt(θ̇² + e²)``
    (Tucker & Wang 1999, 2003; regularised by Ritto, Soize & Sampaio 2009).

    Parameters: ``bit_axial_velocity`` u̇_bit [m/s] (> 0 drilling, x down), ``bit_speed`` θ̇_bit [rad/s]
    (> 0 with the top), ``a1`` [m/s], ``a2`` [m/(N·s)], ``a3`` [m/rad], ``a4`` [N·rad], ``a5`` [N·m],
    ``e`` [rad/s]. Forces are along / about ``+x``. Finite for all finite inputs: below
    ``|θ̇| = STICK_SPEED_FLOOR_RATIO · e`` the stiffening term ``1/Z²`` is frozen (module docstring).
    """
    return bit_rock_force_floored(
        bit_axial_velocity, bit_speed, a1, a2, a3, a4, a5, e, STICK_SPEED_FLOOR_RATIO * e
    )


@njit(cache=True)
def tucker_wang_kernel(args, ctx):
    """The component's compiled kernel: bit–rock ``(axial_force [N], torque [N·m])`` on the string at the
    context ``ctx`` (:class:`~drillstring.forces.registry.BitContext`: its axial velocity and bit speed) for
    the numbers ``args`` of :meth:`BitRockParameters.kernel_array`; ``(0, 0)`` whenever the law would pull the
    bit down (unilateral contact, module docstring)."""
    force, torque = bit_rock_force_floored(ctx.axial_velocity, ctx.bit_speed, args[0], args[1], args[2], args[3],
                                           args[4], args[5], args[6])
    if force > 0.0:  # the rock would pull the bit: it has left the rock
        return 0.0, 0.0
    return force, torque


BitRockParameters.kernel = tucker_wang_kernel


@njit(cache=True)
def tucker_wang_jacobian(args, ctx):
    """The component's compiled Jacobian (its ``jacobian_kernel``, the one :func:`bit_rock_jacobian`, the
    component's ``jacobian_at`` and the compiled stiff part call): ``(f_u, f_θ, f_d, t_u, t_θ, t_d)``, the
    partials of :func:`tucker_wang_kernel` in u̇ [m/s], θ̇ [rad/s] and the depth of cut (none: 0) at ``ctx``
    for the numbers ``args`` of :meth:`BitRockParameters.kernel_array`, in closed form (:func:`bit_rock_jacobian`).
    Zero where the kernel gives no force (unilateral contact); at ``θ̇ = 0`` with no floor, the kernel's own
    limits (``1/Z²`` frozen, ``Z²/θ̇ = 0``)."""
    u, w = ctx.axial_velocity, ctx.bit_speed
    a2, a3, a4, a5, e, floor = args[1], args[2], args[3], args[4], args[5], args[6]
    force, _ = bit_rock_force_floored(u, w, args[0], a2, a3, a4, a5, e, floor)
    if force >= 0.0:  # the kernel gives (0, 0): the bit has left the rock
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    speed = max(abs(w), floor)
    if speed > 0.0:
        q = e / speed
        inv_z2 = 1.0 + q * q
    elif e == 0.0:
        inv_z2 = 1.0
    else:  # as bit_rock_force_floored at θ̇ = 0 with a zero floor
        ratio = 1.0 / STICK_SPEED_FLOOR_RATIO
        inv_z2 = 1.0 + ratio * ratio
    h2 = w * w + e * e
    h = math.sqrt(h2)
    f_u = -inv_z2 / a2
    f_theta = 0.0 if (abs(w) < floor or w == 0.0) else 2.0 * e * e * u / (a2 * w**3)  # 1/Z² frozen: none
    t_u = 0.0
    t_theta = 0.0
    if h > 0.0:
        f_theta += a3 * w / (a2 * h)
        t_u = -a4 * w / h2
        t_theta = -a4 * u * (e * e - w * w) / (h2 * h2) - a5 * e * e / (h2 * h)
    return f_u, f_theta, 0.0, t_u, t_theta, 0.0


BitRockParameters.jacobian_kernel = tucker_wang_jacobian


@njit(cache=True)
def bit_rock_law_array(args, bit_axial_velocity, bit_speed, axial_force, torque):
    """Loop of :func:`tucker_wang_kernel` over 1-D arrays; fills ``axial_force``/``torque`` in place."""
    for i in range(bit_axial_velocity.shape[0]):
        ctx = BitContext(0.0, 0.0, 0.0, bit_axial_velocity[i], bit_speed[i], 0.0, 0.0)
        axial_force[i], torque[i] = tucker_wang_kernel(args, ctx)


# --------------------------------------------------------------------------------------------------------
# Python wrappers
# --------------------------------------------------------------------------------------------------------


def evaluate_bit_rock(bit_axial_velocity, bit_speed, params: BitRockParameters):
    """Vectorised Tucker–Wang law: ``(axial_force [N], torque [N·m])`` on the string, broadcast over inputs.

    ``bit_axial_velocity`` [m/s] and ``bit_speed`` [rad/s] are array-likes (broadcast together). Scalars in,
    0-d arrays out. The component's kernel :func:`tucker_wang_kernel` (the law, its stick handling,
    unilateral contact) applied elementwise: the law's one implementation, not an independent reference.
    """
    u, w = np.broadcast_arrays(np.asarray(bit_axial_velocity, dtype=np.float64),
                               np.asarray(bit_speed, dtype=np.float64))
    shape = u.shape
    force = np.empty(u.size)
    torque = np.empty(u.size)
    bit_rock_law_array(params.kernel_array(), np.ascontiguousarray(u).reshape(-1),
                       np.ascontiguousarray(w).reshape(-1), force, torque)
    return force.reshape(shape), torque.reshape(shape)


def steady_state(weight_on_bit, bit_speed, params: BitRockParameters, allow_negative_rop: bool = False):
    """Steady drilling state of the bit–rock law: ``(rate_of_penetration [m/s], torque_on_bit [N·m])``.

    Closed forms from docs/model.md §5 (Tucker & Wang 1999/2003 with the regularisation of Ritto et al. 2009),
    obtained by setting ``f_xbit = −wob`` and solving for ``u̇_bit``::

        ROP = Z² (a2 · wob − a1) + Z a3 ω,        TOB = a4 · ROP · Z²/ω + a5 Z,     Z = Z(ω)

    ``weight_on_bit`` wob [N] (> 0 pushes the bit down), ``bit_speed`` ω [rad/s]; array-likes broadcast.
    ``TOB`` is the resisting torque magnitude for ``ω > 0``; the torque on the string is ``−TOB`` (odd in
    ``ω``: for ``ω < 0`` TOB is negative, still opposing the rotation).

    If the formula gives ``ROP < 0`` (``a2 · wob < a1`` and the speed term ``Z a3 ω`` too small), the law
    would pull the bit up out of the rock; physically the bit does not penetrate. By default the ROP is then
    clipped to 0 and ``TOB = a5 Z`` (friction only); in that case ``f_xbit(0, ω) ≠ −wob`` (the bit is not in
    the drilling regime of the law). ``allow_negative_rop=True`` returns the raw formula.

    At ``ω = 0``: ``Z = 0`` so ``ROP = 0`` and ``TOB = 0`` (``Z²/ω -> 0``). Scalars in, floats out.
    """
    wob = np.asarray(weight_on_bit, dtype=np.float64)
    omega = np.asarray(bit_speed, dtype=np.float64)
    h = np.hypot(omega, params.e)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where(h > 0.0, omega / np.where(h > 0.0, h, 1.0), 0.0)
        z2_over_omega = np.where(h > 0.0, z / np.where(h > 0.0, h, 1.0), 0.0)
    rop = z * z * (params.a2 * wob - params.a1) + z * params.a3 * omega
    if not allow_negative_rop:
        rop = np.maximum(rop, 0.0)
    tob = params.a4 * rop * z2_over_omega + params.a5 * z
    if rop.ndim == 0:
        return float(rop), float(tob)
    return rop, tob


def bit_rock_jacobian(bit_axial_velocity: float, bit_speed: float, params: BitRockParameters) -> np.ndarray:
    """``[[f_u, f_θ], [t_u, t_θ]]``: partial derivatives of the bit–rock force f [N] and torque t [N·m]
    on the string (docs/model.md §5) with respect to ``u̇_bit`` [m/s] and ``θ̇_bit`` [rad/s], in closed form.

    With ``h = √(θ̇² + e²)``: ``f = −u̇ (1 + e²/θ̇²)/a2 + (a3 h − a1)/a2``, ``t = −a4 u̇ θ̇/h² − a5 θ̇/h``::

        f_u = −(1 + e²/θ̇²)/a2,      f_θ = 2 e² u̇/(a2 θ̇³) + a3 θ̇/(a2 h),
        t_u = −a4 θ̇/h²,              t_θ = −a4 u̇ (e² − θ̇²)/h⁴ − a5 e²/h³.

    Valid above the stick floor (where ``1/Z²`` is frozen, ``f_θ`` loses its first term). Zero where the law
    would pull the bit (unilateral contact). The law's one Jacobian, :func:`tucker_wang_jacobian` (compiled),
    called from Python.
    """
    values = tucker_wang_jacobian(params.kernel_array(),
                                  BitContext(0.0, 0.0, 0.0, float(bit_axial_velocity), float(bit_speed), 0.0, 0.0))
    return np.array([[values[0], values[1]], [values[3], values[4]]])


def case_bit_rock(case) -> BitLaw:
    """The bit–rock law of a :class:`~drillstring.case.Case`: the registered law named by ``bit_rock.law``
    (:func:`~drillstring.forces.registry.bit_law`), built from the case by its own ``from_case``."""
    from drillstring.forces.registry import bit_law

    return bit_law(case.bit_rock.law, "bit_rock.law").from_case(case)
