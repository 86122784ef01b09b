"""The top boundary of the torsion: imposed speed or a top drive under a speed controller (docs/model.md §6).

**Imposed speed** (the reference study): ``θx(0, t) = Ω t``. Seen from the string the top is infinitely
stiff; every torsional wave is reflected with ``r = −1``.

**Top drive.** The quill angle θ₀ is free; motor, gearbox and quill are one rotary inertia ``J_td`` at the
top node: ``J_td θ̈₀ = τ_m − T_s`` with ``T_s`` the torque the string takes from the quill. The motor
torque comes from a speed controller acting on the quill speed ``θ̇₀`` (Kyllingstad & Nessjøen, SPE 119660,
2009)::

    e = Ω_ref(t) − θ̇₀,   τ_m = sat(k_p e + k_i z),   ż = e,                                       (1)

saturated at ``±τ_max``; while saturated the integral stops growing in the saturating direction
(conditional integration, the usual anti-windup). ``Ω_ref`` is the set point ``Ω`` (``operation.top_speed``),
ramped linearly from 0 over ``ramp_time`` when that is > 0. Seen from the string, the linear top drive is
the impedance ``Z_td(iω) = iωJ_td + k_p + k_i/(iω)``; a torsional wave arriving from below is reflected with

    r(iω) = (Z_p − Z_td(iω)) / (Z_p + Z_td(iω)),     Z_p = I_p √(Gρ)                              (2)

the characteristic impedance of the pipe at the top (443 N·m·s/rad for the reference drill pipe).

Controllers (``top_drive.controller``):

- ``pi``: (1) with the gains given. High gains make ``Z_td`` large: the imposed speed again (``r → −1``).
- ``soft_torque`` (SoftTorque/SoftSpeed type; Kyllingstad & Nessjøen 2009): (1) tuned so that the top
  absorbs torsional waves at the stick-slip frequency ω_s: ``k_p = Z_p`` and ``k_i = J_td ω_s²``, so that
  inertia and integral action cancel at ω_s (``Z_td(iω_s) = Z_p``, ``r(iω_s) = 0``). ω_s is the first
  torsional natural frequency of the string with the top held and the bit free.
- ``z_torque`` (torque feedback, Z-Torque type; Dwars, SPE/IADC 173037, 2015): the speed reference is
  corrected by the high-passed surface torque, ``Ω_ref = Ω − HP[T_s]/Z_p``, ``HP[T] = T − x``,
  ``ẋ = ω_f (T − x)``, so that above the corner ω_f the quill moves as the top of an infinitely long pipe
  would (``θ̇₀ = −T_s/Z_p``: no reflection), and below it the mean speed still follows Ω. The inner speed
  loop is stiff: ``k_p = 10 Z_p``, ``k_i = k_p²/(4 J_td)`` (a critically damped quill) unless given;
  ``ω_f = ω_s / 5`` unless given.

The z_torque feedback reads ``T_s`` as the elastic torque of the top element, ``(K q)`` at the top's θx
(positive while the string is driven forward). The ``surface_torque`` observable of a top drive is instead
the torque consistent with the quill's equation of motion, ``T_s = τ_m − J_td θ̈₀`` (the motor torque less
the quill's inertial torque, ``θ̈₀`` from the model's right-hand side): read from a truncated modal basis the
elastic torque of the top element depends on ``J_td`` (its shapes do) — 0.08–4 kN·m at 100 kg·m² against
2.4–9.2 kN·m at 1000 kg·m² for the same quill and bit motion — while ``τ_m − J_td θ̈₀`` does not
(tests/dynamics/test_surface_torque.py).

The component (:mod:`drillstring.forces.registry`, registered as ``"top_drive"``; the imposed speed is the
top drive that does not drive, ``controller = "imposed_speed"``) declares its states: ``z`` (every
controller) and ``x`` (``z_torque`` only), integrated with the modal coordinates where the registry puts them
(:attr:`TopDriveParameters.n_states`). Its pieces: :class:`TopDriveParameters` (built from the case in one
place, :func:`case_top_drive`), the compiled kernel :func:`top_drive_kernel` (reading the named context
:class:`~drillstring.forces.registry.TopContext` and its own states) over the law :func:`top_drive_law` (written
once: :meth:`TopDriveParameters.evaluate_at` calls it from Python; the tests check it against eq. (1) by hand),
the Jacobian :func:`top_drive_jacobian` (used by the
closed-loop stability), the steady states :meth:`TopDriveParameters.steady_states` and the closed form (2),
:func:`reflection_coefficient`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from typing import ClassVar

import numpy as np
from numba import njit

from drillstring.case import TopDrive
from drillstring.forces.registry import TopBoundary, TopContext, register, top_boundary

#: The top boundaries, ``top_drive.controller`` in a case; code = index (the kernels read the code).
CONTROLLERS = ("imposed_speed", "pi", "soft_torque", "z_torque")
#: Entries of :meth:`TopDriveParameters.kernel_args`.
KERNEL_SIZE = 9
IMPOSED_SPEED, PI, SOFT_TORQUE, Z_TORQUE = range(4)
#: z_torque's inner speed loop: k_p = this × Z_p when not given.
Z_TORQUE_STIFFNESS = 10.0
#: z_torque's high-pass corner ω_f = ω_s / this when not given.
Z_TORQUE_FILTER_RATIO = 5.0


@register
@dataclass(frozen=True)
class TopDriveParameters(TopBoundary):
    """The top boundary (SI units), registered as ``"top_drive"``.

    Attributes:
        controller: one of :data:`CONTROLLERS`.
        set_point: Ω [rad/s], ``operation.top_speed``.
        inertia: J_td [kg·m²] (top drive only).
        proportional_gain: k_p [N·m·s/rad]; integral_gain: k_i [N·m/rad].
        max_torque: τ_max [N·m].
        ramp_time: [s], set point ramped from 0 over it when > 0.
        pipe_impedance: Z_p [N·m·s/rad] of the pipe at the top.
        filter_frequency: ω_f [rad/s] (z_torque).
        stick_slip_frequency: ω_s [rad/s] the tuning used (0 when not needed).
        tuned: names of the gains computed by the tuning rule rather than given.
    """

    name: ClassVar[str] = "top_drive"
    kernel_size: ClassVar[int] = KERNEL_SIZE
    keys: ClassVar = TopDrive

    controller: str
    set_point: float
    inertia: float = 0.0
    proportional_gain: float = 0.0
    integral_gain: float = 0.0
    max_torque: float = math.inf
    ramp_time: float = 0.0
    pipe_impedance: float = 0.0
    filter_frequency: float = 0.0
    stick_slip_frequency: float = 0.0
    tuned: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise ValueError(f"controller = {self.controller!r}: must be one of {', '.join(CONTROLLERS)}")
        if not self.imposed:
            for name in ("inertia", "max_torque"):
                if not getattr(self, name) > 0.0:
                    raise ValueError(f"top_drive.{name} = {getattr(self, name)!r}: must be > 0")
            for name in ("proportional_gain", "integral_gain", "ramp_time"):
                value = getattr(self, name)
                if not (math.isfinite(value) and value >= 0.0):
                    raise ValueError(f"top_drive.{name} = {value!r}: must be a finite number >= 0")
            if self.controller == "z_torque" and not (self.pipe_impedance > 0.0 and self.filter_frequency > 0.0):
                raise ValueError("z_torque needs pipe_impedance > 0 and filter_frequency > 0")

    @property
    def imposed(self) -> bool:
        return self.controller == "imposed_speed"

    @property
    def drives(self) -> bool:  # type: ignore[override]
        """True when a motor drives the quill (every controller but the imposed speed)."""
        return not self.imposed

    @property
    def top_inertia(self) -> float:
        """J_td [kg·m²], lumped at the quill."""
        return self.inertia

    @property
    def starts_at_rest(self) -> bool:  # type: ignore[override]
        """True when the set point is ramped from 0 (the run starts at rest)."""
        return self.ramp_time > 0.0

    def steady_speed(self, motor_torque: float) -> float:
        """The quill speed [rad/s] of steady rotation with the motor torque ``motor_torque`` [N·m]: the set point
        with integral action (k_i > 0), ``Ω − τ_m/k_p`` without; ValueError when that is not positive."""
        if self.integral_gain > 0.0:
            return self.set_point
        updated = self.set_point - motor_torque / self.proportional_gain if self.proportional_gain > 0 else -np.inf
        if not updated > 0.0:
            raise ValueError(f"no steady rotation: proportional_gain = {self.proportional_gain:.6g} N*m*s/rad"
                             f" cannot carry the load torque {motor_torque:.6g} N*m at a positive speed")
        return float(updated)

    def check_steady_torque(self, motor_torque: float) -> None:
        """ValueError when ``motor_torque`` [N·m] exceeds τ_max."""
        if abs(motor_torque) > self.max_torque:
            raise ValueError(f"no steady drilling: the motor torque needed, {motor_torque:.6g} N*m, exceeds "
                             f"top_drive.max_torque = {self.max_torque:.6g} N*m")

    @property
    def code(self) -> int:
        return CONTROLLERS.index(self.controller)

    @property
    def n_states(self) -> int:
        """The component's own states: none (imposed speed), z (pi, soft_torque), z and x (z_torque)."""
        return {IMPOSED_SPEED: 0, PI: 1, SOFT_TORQUE: 1, Z_TORQUE: 2}[self.code]

    def kernel_args(self) -> np.ndarray:
        """``[code, J_td, k_p, k_i, τ_max, Ω, ramp_time, Z_p, ω_f]`` as the compiled kernel reads them."""
        return np.array([self.code, self.inertia, self.proportional_gain, self.integral_gain, self.max_torque,
                         self.set_point, self.ramp_time, self.pipe_impedance, self.filter_frequency],
                        dtype=np.float64)

    def kernel_array(self) -> np.ndarray:
        """The numbers :func:`top_drive_kernel` reads: :meth:`kernel_args`."""
        return self.kernel_args()

    @classmethod
    def from_case(cls, case, stick_slip_frequency=None) -> TopDriveParameters:
        """:func:`top_drive_from_case`."""
        return top_drive_from_case(case, stick_slip_frequency)

    def jacobian(self) -> np.ndarray:
        """:func:`top_drive_jacobian` of this top boundary: rows τ_m then the rate of each of its
        :attr:`n_states` states, columns θ̇₀, T_s then each state; the same at every operating point where the
        motor torque is not saturated (the law is affine there)."""
        return top_drive_jacobian(self)[:1 + self.n_states, :2 + self.n_states]

    def jacobian_at(self, ctx: TopContext, states) -> np.ndarray:
        """The Jacobian at the operating point ``ctx``, ``states`` (the protocol's): :meth:`jacobian`, the
        unsaturated law's (steady drilling never saturates it: :meth:`check_steady_torque`)."""
        return self.jacobian()

    def evaluate_at(self, ctx: TopContext, states) -> tuple[float, np.ndarray]:
        """The law at ``ctx``, ``states`` from Python: ``(τ_m [N·m], rates of the states)`` of
        :func:`top_drive_law`, the one implementation the compiled kernel calls too."""
        rates = np.zeros(self.n_states)
        if not self.n_states:
            return 0.0, rates
        torque, rates[0], filtered_rate = top_drive_law(
            self.kernel_args(), float(ctx.time), float(ctx.quill_speed), float(ctx.surface_torque),
            float(states[0]), float(states[1]) if self.n_states > 1 else 0.0)
        rates[1:] = filtered_rate
        return torque, rates

    def steady_states(self, motor_torque: float, surface_torque: float) -> np.ndarray:
        """The controller's states in steady rotation with the motor torque ``motor_torque`` [N·m] and the
        surface torque ``surface_torque`` [N·m]: ``z = τ_m / k_i`` (0 without integral action), the
        z_torque filter ``x = T_s``."""
        states = np.zeros(self.n_states)
        if states.size:
            states[0] = motor_torque / self.integral_gain if self.integral_gain > 0 else 0.0
        if states.size > 1:
            states[1] = surface_torque
        return states

    def impedance(self, omega) -> np.ndarray:
        """``Z_td(iω) = iωJ_td + k_p + k_i/(iω)`` [N·m·s/rad] (ω [rad/s] > 0), the linear top drive seen
        from the string; for z_torque with an ideal inner loop the same holds with the corrections of the
        torque feedback left out (use :func:`reflection_coefficient` for pi and soft_torque)."""
        w = np.asarray(omega, dtype=float)
        return 1j * w * self.inertia + self.proportional_gain + self.integral_gain / (1j * w)

    def describe(self) -> dict:
        """JSON-ready summary: the controller, its gains (SI) and which of them were tuned."""
        out = {"controller": self.controller}
        if not self.imposed:
            out.update(inertia=self.inertia, proportional_gain=self.proportional_gain,
                       integral_gain=self.integral_gain, max_torque=self.max_torque, ramp_time=self.ramp_time,
                       pipe_impedance=self.pipe_impedance, tuned=list(self.tuned))
            if self.controller == "z_torque":
                out["filter_frequency"] = self.filter_frequency
            if self.stick_slip_frequency:
                out["stick_slip_frequency"] = self.stick_slip_frequency
        return out


def pipe_impedance(polar_moment: float, shear_modulus: float, density: float) -> float:
    """Characteristic torsional impedance ``Z_p = I_p √(G ρ)`` [N·m·s/rad] of a pipe of polar area moment
    ``I_p`` [m⁴], shear modulus G [Pa] and density ρ [kg/m³] (torque per angular speed of a travelling wave)."""
    return polar_moment * math.sqrt(shear_modulus * density)


def soft_torque_gains(inertia: float, impedance: float, stick_slip_frequency: float) -> tuple[float, float]:
    """SoftTorque tuning (Kyllingstad & Nessjøen 2009): ``k_p = Z_p``, ``k_i = J_td ω_s²``."""
    return impedance, inertia * stick_slip_frequency**2


def z_torque_gains(inertia: float, impedance: float) -> tuple[float, float]:
    """The stiff inner speed loop of z_torque: ``k_p = 10 Z_p``, ``k_i = k_p²/(4 J_td)`` (critically damped
    quill under the loop alone)."""
    k_p = Z_TORQUE_STIFFNESS * impedance
    return k_p, k_p * k_p / (4.0 * inertia)


def reflection_coefficient(omega, params: TopDriveParameters, impedance: float) -> np.ndarray:
    """Eq. (2): ``r(iω) = (Z_p − Z_td(iω)) / (Z_p + Z_td(iω))`` of the linear pi / soft_torque top drive for a
    pipe of characteristic impedance ``impedance`` [N·m·s/rad]; −1 for the imposed speed."""
    w = np.asarray(omega, dtype=float)
    if params.imposed:
        return -np.ones_like(w, dtype=complex)
    z_td = params.impedance(w)
    return (impedance - z_td) / (impedance + z_td)


@njit(cache=True)
def set_point_speed(t, set_point, ramp_time):
    """Ω_ref(t) [rad/s]: the set point, ramped linearly from 0 over ``ramp_time`` [s] when that is > 0."""
    if ramp_time > 0.0 and t < ramp_time:
        return set_point * t / ramp_time
    return set_point


@njit(cache=True)
def top_drive_law(args, t, quill_speed, surface_torque, integral, filtered):
    """Eq. (1) and the z_torque feedback: ``(τ_m [N·m], ż [rad], ẋ [N·m/s])`` at time ``t`` [s] for the quill
    speed [rad/s], the surface torque T_s [N·m], the integral state z [rad] and the filter state x [N·m];
    ``args`` from :meth:`TopDriveParameters.kernel_args`."""
    code = int(args[0])
    k_p, k_i, t_max = args[2], args[3], args[4]
    reference = set_point_speed(t, args[5], args[6])
    d_filtered = 0.0
    if code == Z_TORQUE:
        reference -= (surface_torque - filtered) / args[7]
        d_filtered = args[8] * (surface_torque - filtered)
    error = reference - quill_speed
    torque = k_p * error + k_i * integral
    d_integral = error
    if torque > t_max:
        torque = t_max
        if error > 0.0:
            d_integral = 0.0
    elif torque < -t_max:
        torque = -t_max
        if error < 0.0:
            d_integral = 0.0
    return torque, d_integral, d_filtered


@njit(cache=True)
def top_drive_kernel(args, ctx, states, rates):
    """The component's compiled kernel: the motor torque τ_m [N·m] at the context ``ctx``
    (:class:`~drillstring.forces.registry.TopContext`) for the numbers ``args`` of
    :meth:`TopDriveParameters.kernel_args`, reading the controller's states ``states`` (z, then x for
    z_torque) and writing their rates in ``rates`` (:func:`top_drive_law`)."""
    z_torque = args[0] == Z_TORQUE
    filtered = states[1] if z_torque else 0.0
    torque, d_integral, d_filtered = top_drive_law(args, ctx.time, ctx.quill_speed, ctx.surface_torque, states[0],
                                                   filtered)
    rates[0] = d_integral
    if z_torque:
        rates[1] = d_filtered
    return torque


TopDriveParameters.kernel = top_drive_kernel


def top_drive_jacobian(params: TopDriveParameters) -> np.ndarray:
    """Partial derivatives of ``(τ_m, ż, ẋ)`` (rows) with respect to ``(θ̇₀, T_s, z, x)`` (columns) of the
    unsaturated law after the ramp, in closed form: ``e = Ω − θ̇₀ − c (T_s − x)/Z_p`` (c = 1 for
    z_torque, else 0), ``τ = k_p e + k_i z``, ``ż = e``, ``ẋ = c ω_f (T_s − x)``."""
    c = 1.0 if params.controller == "z_torque" else 0.0
    zp = params.pipe_impedance if c else 1.0
    de = np.array([-1.0, -c / zp, 0.0, c / zp])
    jac = np.zeros((3, 4))
    jac[0] = params.proportional_gain * de
    jac[0, 2] += params.integral_gain
    jac[1] = de
    jac[2] = c * params.filter_frequency * np.array([0.0, 1.0, 0.0, -1.0])
    return jac


def case_top_drive(case, stick_slip_frequency=None) -> TopBoundary:
    """The top boundary of a :class:`~drillstring.case.Case`: the registered boundary ``top_drive.boundary``
    names, built by its ``from_case(case, stick_slip_frequency)`` (the top drive's: :func:`top_drive_from_case`)."""
    return top_boundary(case.top_drive.boundary, "top_drive.boundary").from_case(case, stick_slip_frequency)


def top_drive_from_case(case, stick_slip_frequency=None) -> TopDriveParameters:
    """The top drive of a :class:`~drillstring.case.Case` (``[top_drive]``), with the tuned gains of
    soft_torque and z_torque computed where the case leaves them out. ``stick_slip_frequency``: a callable
    returning ω_s [rad/s] (the first torsional natural frequency with the top held), called only when a
    tuning rule needs it. Z_p is that of the top section."""
    td = case.top_drive
    omega = case.operation.top_speed
    if td.controller == "imposed_speed":
        return TopDriveParameters("imposed_speed", omega)
    top = case.sections[0]
    material = case.material_of(top)
    polar = math.pi * (top.outer_diameter**4 - top.inner_diameter**4) / 32.0
    z_p = pipe_impedance(polar, material.shear_modulus, material.density)
    k_p, k_i = td.proportional_gain, td.integral_gain
    tuned: list[str] = []
    omega_s = 0.0
    filter_frequency = td.filter_frequency or 0.0
    if td.controller == "soft_torque" and (k_p is None or k_i is None):
        omega_s = float(stick_slip_frequency())
        tuned_p, tuned_i = soft_torque_gains(td.inertia, z_p, omega_s)
    elif td.controller == "z_torque":
        tuned_p, tuned_i = z_torque_gains(td.inertia, z_p)
        if td.filter_frequency is None:
            omega_s = float(stick_slip_frequency())
            filter_frequency = omega_s / Z_TORQUE_FILTER_RATIO
            tuned.append("filter_frequency")
    else:
        tuned_p = tuned_i = 0.0
    if k_p is None:
        k_p = tuned_p
        tuned.append("proportional_gain")
    if k_i is None:
        k_i = tuned_i
        tuned.append("integral_gain")
    return TopDriveParameters(
        td.controller, omega, inertia=td.inertia, proportional_gain=float(k_p), integral_gain=float(k_i),
        max_torque=td.max_torque, ramp_time=td.ramp_time, pipe_impedance=z_p,
        filter_frequency=float(filter_frequency), stick_slip_frequency=omega_s, tuned=tuple(sorted(tuned)),
    )
