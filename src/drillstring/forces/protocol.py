"""The component protocol's base classes and named contexts (docs/extending.md): what each kind of component
declares (:class:`BitLaw`, :class:`TopBoundary`, :class:`Motor`, :class:`ContactLaw`, :class:`TurningLoadSource`,
:class:`HookLoad`, :class:`StringFriction`) and what it may read (:class:`BitContext`, :class:`TopContext`,
:class:`MotorContext`, :class:`ContactContext`, :class:`HookContext`, :class:`StringFrictionContext`). The registry (:mod:`drillstring.forces.registry`) registers the
components, lays out their numbers and states and writes the compiled dispatch; it re-exports these names.
SI units throughout.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

__all__ = ["BIT_LAW_SCALES", "BIT_LAW_STEP", "BitContext", "BitLaw", "BitSteadyState", "ContactContext",
           "ContactLaw", "HookContext", "HookLoad", "Motor", "MotorContext", "StringFriction",
           "StringFrictionContext", "TopBoundary", "TopContext", "TurningLoadSource", "bit_context",
           "differenced_bit_jacobian", "differenced_motor_slope"]

#: Relative step of the central differences that stand for the Jacobian of a law that declares none
#: (:func:`differenced_bit_jacobian`, :func:`differenced_motor_slope`) [-], and the floors of the differenced
#: quantities' scales: axial velocity [m/s], bit speed (and a motor's relative speed) [rad/s], depth of cut [m].
BIT_LAW_STEP = 1e-6
BIT_LAW_SCALES = (1e-3, 1.0, 1e-3)


class BitContext(NamedTuple):
    """What a bit–rock law may read (SI; floats in the compiled kernels, array-likes in the references):
    ``time`` [s], ``position`` u [m] of the bit from the static state (down), ``angle`` θ [rad],
    ``axial_velocity`` u̇ [m/s] (> 0 drilling), ``bit_speed`` θ̇ [rad/s], ``depth_of_cut`` [m] per blade
    (delayed laws; 0 for the others), ``weight_on_bit`` [N], the static one."""

    time: Any
    position: Any
    angle: Any
    axial_velocity: Any
    bit_speed: Any
    depth_of_cut: Any
    weight_on_bit: Any


def bit_context(axial_velocity=0.0, bit_speed=0.0, depth_of_cut=0.0, *, time=0.0, position=0.0, angle=0.0,
                weight_on_bit=0.0) -> BitContext:
    """A :class:`BitContext` by keyword (the fields a law does not read default to 0)."""
    return BitContext(time, position, angle, axial_velocity, bit_speed, depth_of_cut, weight_on_bit)


class TopContext(NamedTuple):
    """What a top boundary may read: ``time`` [s], ``quill_speed`` θ̇₀ [rad/s], ``surface_torque`` T_s [N·m]
    (the elastic torque of the top element)."""

    time: Any
    quill_speed: Any
    surface_torque: Any


class MotorContext(NamedTuple):
    """What a downhole motor may read: ``time`` [s] and ``relative_speed`` ω_m [rad/s], the rotor's speed
    relative to its stator."""

    time: Any
    relative_speed: Any


class ContactContext(NamedTuple):
    """What a contact law may read, one entry per contact station outside its gap (1-D float64 arrays, SI):
    lateral displacements ``v``, ``w`` [m] and velocities ``v_dot``, ``w_dot`` [m/s] (0 unless the law
    ``reads_lateral_velocity``), ``spin_speed`` θ̇x [rad/s], ``gap`` [m], ``outer_diameter`` [m] and the
    station's ``stiffness`` [N/m]."""

    v: Any
    w: Any
    v_dot: Any
    w_dot: Any
    spin_speed: Any
    gap: Any
    outer_diameter: Any
    stiffness: Any


class StringFrictionContext(NamedTuple):
    """What an along-string friction law may read, one entry per friction station (a node resting on the wall
    in the static state; 1-D float64 arrays, SI): the station's ``axial_velocity`` u̇ [m/s] along the string
    (down positive), its ``spin_speed`` θ̇x [rad/s], the wall's static ``normal_force`` N [N] on it, the contact
    ``radius`` r [m] (pipe body or tool joint) and the ``friction`` coefficient μ [-] there."""

    axial_velocity: Any
    spin_speed: Any
    normal_force: Any
    radius: Any
    friction: Any


class HookContext(NamedTuple):
    """What a hook load may read: ``time`` [s] and the static ``weight_on_bit`` [N]."""

    time: Any
    weight_on_bit: Any


@functools.cache
def differenced_bit_jacobian(kernel):
    """The fallback Jacobian of a bit law that declares no ``jacobian_kernel``: ``jacobian(args, ctx) -> (f_u,
    f_θ, f_d, t_u, t_θ, t_d)`` by central differences of its ``kernel`` in u̇, θ̇ and the depth of cut (six
    evaluations; the step :data:`BIT_LAW_STEP` times the value, at least its scale :data:`BIT_LAW_SCALES`).
    Plain Python calling ``kernel``; the registry compiles it into the dispatch with the kernel inlined."""

    def jacobian(args, ctx):
        values = (ctx.axial_velocity, ctx.bit_speed, ctx.depth_of_cut)
        f_u = f_w = f_d = t_u = t_w = t_d = 0.0
        for k in range(3):
            step = BIT_LAW_STEP * max(abs(values[k]), BIT_LAW_SCALES[k])
            force_sum = 0.0
            torque_sum = 0.0
            for sign in (1.0, -1.0):
                dv = sign * step if k == 0 else 0.0
                dw = sign * step if k == 1 else 0.0
                dd = sign * step if k == 2 else 0.0
                force, torque = kernel(args, BitContext(ctx.time, ctx.position, ctx.angle, values[0] + dv,
                                                        values[1] + dw, values[2] + dd, ctx.weight_on_bit))
                force_sum += sign * force
                torque_sum += sign * torque
            if k == 0:
                f_u, t_u = force_sum / (2.0 * step), torque_sum / (2.0 * step)
            elif k == 1:
                f_w, t_w = force_sum / (2.0 * step), torque_sum / (2.0 * step)
            else:
                f_d, t_d = force_sum / (2.0 * step), torque_sum / (2.0 * step)
        return f_u, f_w, f_d, t_u, t_w, t_d

    return jacobian


@functools.cache
def differenced_motor_slope(kernel):
    """The fallback torque slope of a motor that declares no ``jacobian_kernel``: ``slope(args, ctx, states,
    rates) -> dT/dω_m`` by a central difference of its ``kernel`` (step as :func:`differenced_bit_jacobian`'s;
    ``rates`` takes the states' rates the kernel writes, not kept)."""

    def slope(args, ctx, states, rates):
        speed = ctx.relative_speed
        step = BIT_LAW_STEP * max(abs(speed), BIT_LAW_SCALES[1])
        return (kernel(args, MotorContext(ctx.time, speed + step), states, rates)
                - kernel(args, MotorContext(ctx.time, speed - step), states, rates)) / (2.0 * step)

    return slope


@dataclass(frozen=True)
class BitSteadyState:
    """Steady drilling of a bit law at a bit speed: ``rate_of_penetration`` V [m/s] (0: rotation without
    penetration), the ``axial_force`` [N] and ``torque`` [N·m] on the string, ``depth_of_cut`` [m] per blade
    (0 for a law that reads none)."""

    rate_of_penetration: float
    axial_force: float
    torque: float
    depth_of_cut: float = 0.0


class BitLaw:
    """Base of the bit–rock laws (module docstring). Subclasses set the class attributes and the methods;
    instances are the law's parameters (SI)."""

    name: ClassVar[str]
    #: numbers of :meth:`kernel_array`
    kernel_size: ClassVar[int]
    #: the compiled kernel ``kernel(args, ctx) -> (axial_force [N], torque [N·m])`` on the string
    kernel: ClassVar[Any]
    #: reads the depth of cut (the bit's history)
    delayed: ClassVar[bool] = False
    #: touches the rock (False: the bit hangs free)
    on_bottom: ClassVar[bool] = True
    #: its case keys, read from ``[bit_rock]``: its own pydantic model, with units and bounds
    #: (:class:`~drillstring.case.TuckerWangKeys`, ...; None: it has none); ``[bit_rock]`` is their union
    keys: ClassVar[Any] = None
    #: code in the kernels' array (set by :func:`register`)
    component_code: ClassVar[float] = 0.0
    #: its compiled Jacobian ``jacobian_kernel(args, ctx) -> (f_u, f_θ, f_d, t_u, t_θ, t_d)``: the partials of
    #: :attr:`kernel`'s force and torque in u̇, θ̇ and the depth of cut; None: central differences of
    #: :attr:`kernel` stand for it (:func:`differenced_bit_jacobian`)
    jacobian_kernel: ClassVar[Any] = None

    @classmethod
    def from_case(cls, case) -> "BitLaw":
        raise NotImplementedError

    def kernel_array(self) -> np.ndarray:
        raise NotImplementedError

    def evaluate_at(self, ctx: BitContext):
        """The law at a context whose fields may be arrays (broadcast together): ``(axial_force, torque)``
        arrays (0-d for scalars), :attr:`kernel` applied elementwise, so the law is written once, in its
        kernel (docs/extending.md). A law may override it with a faster loop (the Tucker–Wang and Detournay
        laws compile one)."""
        fields = np.broadcast_arrays(*(np.asarray(field, dtype=np.float64) for field in ctx))
        args = self.kernel_array()
        kernel = type(self).kernel
        values = [kernel(args, BitContext(*(float(field.flat[i]) for field in fields)))
                  for i in range(fields[0].size)]
        out = np.array(values, dtype=np.float64).reshape(fields[0].shape + (2,))
        return out[..., 0], out[..., 1]

    def partials_at(self, ctx: BitContext) -> np.ndarray:
        """``[[f_u, f_θ, f_d], [t_u, t_θ, t_d]]``: partials of the force [N] and torque [N·m] in u̇ [m/s], θ̇
        [rad/s] and the depth of cut d [m] at a scalar ``ctx``: the law's compiled :attr:`jacobian_kernel`
        called from Python (the one implementation the compiled stiff part also calls), or central
        differences of :attr:`kernel` (:func:`differenced_bit_jacobian`) for a law that declares none."""
        jacobian = type(self).jacobian_kernel
        if jacobian is None:
            jacobian = differenced_bit_jacobian(type(self).kernel)
        values = jacobian(np.asarray(self.kernel_array(), dtype=np.float64),
                          BitContext(*(float(field) for field in ctx)))
        return np.array(values, dtype=np.float64).reshape(2, 3)

    def jacobian_at(self, ctx: BitContext) -> np.ndarray:
        """``[[f_u, f_θ], [t_u, t_θ]]``: partials of the force and torque in u̇ and θ̇ at ``ctx``
        (:meth:`partials_at`)."""
        return self.partials_at(ctx)[:, :2]

    def depth_partials(self, ctx: BitContext) -> tuple[float, float]:
        """``(f_d [N/m], t_d [N·m/m])``: the partials in the depth of cut (:meth:`partials_at`; read for a
        ``delayed`` law, whose depth of cut moves with the bit's position)."""
        partials = self.partials_at(ctx)
        return float(partials[0, 2]), float(partials[1, 2])

    def steady_drilling(self, bit_speed: float, axial_load: float, resistance: float) -> BitSteadyState:
        """Steady drilling at ``bit_speed`` Ω [rad/s] when the string pushes the bit with ``axial_load`` W [N]
        less ``resistance`` c [N·s/m] times the rate of penetration: the V ≥ 0 with ``−f(V, Ω) = W − c V``
        (a :class:`BitSteadyState`), None when there is none."""
        raise NotImplementedError

    def start_depth_of_cut(self, weight_on_bit: float, bit_speed: float) -> float:
        """A delayed law's depth of cut [m] per blade under the bit at the start of a run on the static state:
        that of its steady drilling under ``weight_on_bit`` [N] at ``bit_speed`` [rad/s] (0 when none)."""
        steady = self.steady_drilling(bit_speed, weight_on_bit, 0.0)
        return steady.depth_of_cut if steady is not None else 0.0

    # -- conveniences over the context ---------------------------------------------------------------------
    def evaluate(self, bit_axial_velocity, bit_speed, depth_of_cut=0.0):
        """:meth:`evaluate_at` at the bit's axial velocity [m/s], speed [rad/s] and depth of cut [m] per blade."""
        return self.evaluate_at(bit_context(bit_axial_velocity, bit_speed, depth_of_cut))


class TopBoundary:
    """Base of the top boundaries (module docstring). Instances are the boundary's parameters (SI).

    A boundary that drives the string (``drives``) lumps ``top_inertia`` [kg·m²] at the quill (the torsional
    basis is then free at the top, its first mode the rigid rotation), declares its ``n_states``, its kernel
    ``kernel(args, ctx, states, rates) -> τ_m`` and ``evaluate_at(ctx, states) -> (τ_m,
    rates)``, ``jacobian_at(ctx, states)`` (at that operating point; rows τ_m then each state's rate; columns
    θ̇₀, T_s, then each state), ``steady_states(motor_torque, surface_torque)``, ``steady_speed(motor_torque)``
    (the quill speed [rad/s] at which it gives that torque; ValueError when none) and
    ``check_steady_torque(motor_torque)``. ``from_case(case, stick_slip_frequency)`` builds it from the case
    (``stick_slip_frequency``: a callable giving the first torsional natural frequency with the top held
    [rad/s], for tuning rules)."""

    name: ClassVar[str]
    #: drives the string through a motor torque (False: the top speed is imposed)
    drives: ClassVar[bool] = True
    kernel_size: ClassVar[int] = 0
    kernel: ClassVar[Any] = None
    component_code: ClassVar[float] = 0.0
    #: its case keys (a pydantic model with units and bounds)
    keys: ClassVar[Any] = None
    #: the run starts from rest (a ramped set point) instead of spinning at the top speed
    starts_at_rest: ClassVar[bool] = False
    # J_td [kg·m²] lumped at the quill by a driving boundary; a plain comment: each boundary documents its own
    top_inertia: float = 0.0

    @classmethod
    def from_case(cls, case, stick_slip_frequency=None) -> "TopBoundary":
        raise NotImplementedError

    @property
    def n_states(self) -> int:
        return 0

    def kernel_array(self) -> np.ndarray:
        return np.zeros(0)

    def evaluate_at(self, ctx: TopContext, states) -> tuple[float, np.ndarray]:
        """:attr:`kernel`'s law from Python (the same implementation, not a second one): ``(τ_m [N·m], rates of
        the states)``."""
        raise NotImplementedError

    def jacobian_at(self, ctx: TopContext, states) -> np.ndarray:
        """``(1 + n_states, 2 + n_states)``: partials of ``(τ_m, each state's rate)`` in ``(θ̇₀, T_s, each
        state)`` at the operating point ``ctx``, ``states``."""
        raise NotImplementedError

    def steady_states(self, motor_torque: float, surface_torque: float) -> np.ndarray:
        """Its states in steady rotation with the motor torque and surface torque [N·m] (none by default)."""
        return np.zeros(self.n_states)

    def check_steady_torque(self, motor_torque: float) -> None:
        """ValueError when the boundary cannot give ``motor_torque`` [N·m] in steady rotation (none here)."""

    def describe(self) -> dict:
        """JSON-ready summary (SI)."""
        return {"top_boundary": self.name}


class Motor:
    """Base of the downhole motors: a rotor between two sections of the string (docs/extending.md). The string
    below the rotor station turns relative to the string above (:mod:`drillstring.rotor` releases that
    rotation in the torsional family); the motor applies a torque ``T`` across it, ``+T`` on the rotor side and
    ``−T`` on the stator side, from the relative speed ``ω_m`` [rad/s] (rotor minus stator). A motor declares
    ``name``, ``keys``, ``from_case(case)`` (None when the case has no such motor), ``kernel_size``,
    ``kernel_array()``, ``kernel(args, ctx, states, rates) -> torque [N·m]`` (compiled; the named context
    :class:`MotorContext`; it writes its states' rates), ``evaluate_at(ctx, states) -> (torque, rates)`` (the
    kernel's law from Python), ``jacobian_at(ctx, states)`` (rows the torque then each state's rate, columns
    ``ω_m`` then each state), ``steady_states(relative_speed)``, ``n_states`` and ``position`` [m] (the rotor
    station from the top)."""

    name: ClassVar[str]
    kernel_size: ClassVar[int] = 0
    kernel: ClassVar[Any] = None
    #: its compiled torque slope ``jacobian_kernel(args, ctx, states) -> dT/dω_m`` [N·m·s/rad] (its states
    #: held); None: a central difference of :attr:`kernel` stands for it (:func:`differenced_motor_slope`)
    jacobian_kernel: ClassVar[Any] = None
    keys: ClassVar[Any] = None
    component_code: ClassVar[float] = 0.0
    position: float

    @property
    def n_states(self) -> int:
        return 0

    def kernel_array(self) -> np.ndarray:
        raise NotImplementedError

    def evaluate_at(self, ctx: MotorContext, states) -> tuple[float, np.ndarray]:
        """:attr:`kernel`'s law from Python (the same implementation, not a second one): ``(torque [N·m], rates
        of the states)``."""
        raise NotImplementedError

    def jacobian_at(self, ctx: MotorContext, states) -> np.ndarray:
        """``(1 + n_states, 1 + n_states)``: partials of ``(T, each state's rate)`` in ``(ω_m, each state)`` at
        the operating point ``ctx``, ``states``; for a motor without states ``[[dT/dω_m]]``
        (:meth:`torque_slope_at`); one with states writes its own."""
        if self.n_states:
            raise NotImplementedError(f"motor {self.name!r} has states: it declares its own jacobian_at")
        return np.array([[self.torque_slope_at(ctx, states)]])

    def torque_slope_at(self, ctx: MotorContext, states) -> float:
        """``dT/dω_m`` [N·m·s/rad] at ``ctx``, its ``states`` held: the compiled :attr:`jacobian_kernel` called
        from Python (the one implementation the compiled stiff part also calls), or a central difference of
        :attr:`kernel` (:func:`differenced_motor_slope`) for a motor that declares none."""
        slope = type(self).jacobian_kernel
        states = np.ascontiguousarray(states, dtype=np.float64).reshape(-1)
        args = np.asarray(self.kernel_array(), dtype=np.float64)
        ctx = MotorContext(float(ctx.time), float(ctx.relative_speed))
        if slope is None:
            return float(differenced_motor_slope(type(self).kernel)(args, ctx, states, np.zeros(states.size)))
        return float(slope(args, ctx, states))

    def steady_states(self, relative_speed: float) -> np.ndarray:
        """Its states in steady rotation at the relative speed ``relative_speed`` [rad/s] (none by default)."""
        return np.zeros(self.n_states)

    # -- conveniences in steady rotation at a relative speed -----------------------------------------------
    def evaluate(self, relative_speed):
        """The torque [N·m] in steady rotation at ``relative_speed`` ω_m [rad/s] (its states steady)."""
        return self.evaluate_at(MotorContext(0.0, relative_speed), self.steady_states(relative_speed))[0]

    def jacobian(self, relative_speed=0.0) -> float:
        """``dT/dω_m`` [N·m·s/rad] at ``relative_speed`` with its states held (:meth:`jacobian_at`)."""
        speed = float(relative_speed)
        return float(self.jacobian_at(MotorContext(0.0, speed), self.steady_states(speed))[0, 0])

    def describe(self) -> dict:
        """JSON-ready summary (SI)."""
        return {"motor": self.name}


class ContactLaw:
    """Base of the contact laws (module docstring). Instances are the law's parameters (SI)."""

    name: ClassVar[str]
    kernel_size: ClassVar[int] = 0
    #: the compiled kernel ``kernel(args, ctx, force_v, force_w, torque)``: fills the forces [N] and torques [N·m]
    kernel: ClassVar[Any] = None
    component_code: ClassVar[float] = 0.0
    #: its case keys (a pydantic model with units and bounds), read from ``[contact]``
    keys: ClassVar[Any] = None
    # k'_sh [N/m per m of string], the wall's distributed stiffness: station i gets k'_sh ℓ_i (the context's
    # ``stiffness``, ContactStations.stiffness); a plain comment, not a documented attribute: each law documents
    # its own field (a second description of the same attribute is a documentation-build error)
    shock_stiffness: float

    @classmethod
    def from_case(cls, case) -> "ContactLaw":
        raise NotImplementedError

    @property
    def reads_lateral_velocity(self) -> bool:
        """Whether the law reads the stations' lateral velocities (the kernels gather them only then)."""
        return True

    def kernel_array(self) -> np.ndarray:
        return np.zeros(0)

    def evaluate_at(self, ctx: ContactContext):
        """:attr:`kernel`'s law from Python (the same implementation, not a second one): ``(force_v, force_w,
        torque)`` arrays, one entry per station."""
        raise NotImplementedError

    def jacobian_at(self, ctx: ContactContext) -> np.ndarray:
        """(n, 3, 5): rows force_v, force_w, torque; columns v, w, v̇, ẇ, θ̇x; one block per station."""
        raise NotImplementedError


class StringFriction:
    """Base of the along-string friction laws (module docstring of :mod:`drillstring.forces.registry`): the
    wall's friction on the string at the stations in contact in the static state, from the named context
    :class:`StringFrictionContext`. Instances are the law's parameters (SI)."""

    name: ClassVar[str]
    kernel_size: ClassVar[int] = 0
    #: the compiled kernel ``kernel(args, ctx, force, torque)``: fills the axial forces [N] and torques [N·m]
    kernel: ClassVar[Any] = None
    component_code: ClassVar[float] = 0.0
    #: its case keys (a pydantic model with units and bounds), read from ``[string_friction.<name>]``
    keys: ClassVar[Any] = None

    @classmethod
    def from_case(cls, case) -> "StringFriction":
        raise NotImplementedError

    def kernel_array(self) -> np.ndarray:
        return np.zeros(0)

    def evaluate_at(self, ctx: StringFrictionContext):
        """:attr:`kernel`'s law from Python (the same implementation): ``(force, torque)`` arrays, one entry per
        station."""
        n = np.asarray(ctx.axial_velocity, dtype=float).shape[0]
        force, torque = np.zeros(n), np.zeros(n)
        type(self).kernel(np.asarray(self.kernel_array(), dtype=float),
                          StringFrictionContext(*(np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=float),
                                                                                       (n,))) for a in ctx)),
                          force, torque)
        return force, torque

    def jacobian_at(self, ctx: StringFrictionContext) -> np.ndarray:
        """(n, 2, 2): rows force, torque; columns u̇, θ̇x; one block per station."""
        raise NotImplementedError


class TurningLoadSource:
    """Base of the turning-load sources (module docstring). Instances are the source's parameters (SI)."""

    name: ClassVar[str]
    #: its case keys (a pydantic model with units and bounds)
    keys: ClassVar[Any] = None
    #: rank among the package's sources when the case builds them (their entries are concatenated in this order)
    order: ClassVar[int] = 0
    component_code: ClassVar[float] = 0.0

    @classmethod
    def from_case(cls, case) -> "TurningLoadSource":
        raise NotImplementedError

    def loads(self, mesh):
        """Its entries on ``mesh`` (a :class:`~drillstring.forces.excitation.TurningLoads`, empty when none)."""
        raise NotImplementedError


class HookLoad:
    """Base of the hook loads (module docstring). Instances are the load's parameters (SI). A load that adds
    nothing (``adds = False``, the reference start) has code 0 and no kernel."""

    name: ClassVar[str]
    #: adds a force (False: the kernels add nothing, code 0)
    adds: ClassVar[bool] = True
    kernel_size: ClassVar[int] = 0
    #: the compiled kernel ``kernel(args, ctx) -> extra axial force [N]`` on the top along +x (down)
    kernel: ClassVar[Any] = None
    component_code: ClassVar[float] = 0.0
    #: its case keys (a pydantic model with units and bounds), read from ``[initial]``
    keys: ClassVar[Any] = None
    #: the run starts off bottom, the string hanging from the hook, the bit ``clearance`` [m] above the rock
    active: ClassVar[bool] = False
    clearance: float = 0.0

    @classmethod
    def from_case(cls, case, weight_on_bit: float) -> "HookLoad":
        """The load of a :class:`~drillstring.case.Case` whose static weight-on-bit is ``weight_on_bit`` [N]."""
        raise NotImplementedError

    def kernel_array(self) -> np.ndarray:
        return np.zeros(0)

    def evaluate_at(self, ctx: HookContext):
        """:attr:`kernel`'s load from Python (the same implementation): the extra axial force [N] at the top
        (``ctx.time`` may be an array)."""
        return np.zeros_like(np.asarray(ctx.time, dtype=float))

    def force(self, t):
        """:meth:`evaluate_at` at time(s) ``t`` [s]."""
        return self.evaluate_at(HookContext(t, 0.0))
