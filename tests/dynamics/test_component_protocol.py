"""The component protocol (drillstring.forces.registry): a bit–rock law defined here, outside the package,
registered with one decorator and run through ``simulate`` (the NumPy reference engine) and ``stability``;
the registry's computed layout; the package's laws behind the compiled dispatch."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
from numba import njit

from drillstring.case import BitRock, TopDrive
from drillstring.dynamics.rom import OBSERVABLE_COLUMN, case_reduced_model, rigid_axial_column
from drillstring.dynamics.simulate import simulate_model
from drillstring.dynamics.stability import linearized_matrix, stability, steady_drilling
from drillstring.forces.registry import (
    BIT_LAW,
    HEADER,
    BitContext,
    BitLaw,
    BitSteadyState,
    ContactContext,
    ContactLaw,
    HookContext,
    HookLoad,
    TopBoundary,
    TopContext,
    bit_context,
    bit_law,
    bit_laws,
    contact_law,
    contact_laws,
    name_code,
    register,
    top_boundaries,
)


@njit(cache=True)
def _weakening_kernel(args, ctx):
    """The law below, compiled: ``args = [W0, a, μR, β, ω_s, ω_r]``."""
    weight = args[0] + ctx.axial_velocity / args[1]
    if weight <= 0.0:
        return 0.0, 0.0
    w = ctx.bit_speed
    shape = (1.0 + args[3] * math.exp(-abs(w) / args[4])) * math.tanh(w / args[5])
    return -weight, -args[2] * weight * shape


@njit(cache=True)
def _weakening_jacobian(args, ctx):
    """The law's partials ``(f_u, f_ω, f_d, t_u, t_ω, t_d)`` in closed form, compiled (its ``jacobian_kernel``:
    the protocol's ``jacobian_at`` calls it)."""
    weight = args[0] + ctx.axial_velocity / args[1]
    if weight <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    w = ctx.bit_speed
    decay = args[3] * math.exp(-abs(w) / args[4])
    tanh = math.tanh(w / args[5])
    slope = -math.copysign(decay / args[4], w) * tanh + (1.0 + decay) * (1.0 - tanh * tanh) / args[5]
    return -1.0 / args[1], 0.0, 0.0, -args[2] * (1.0 + decay) * tanh / args[1], -args[2] * weight * slope, 0.0


@register
@dataclass(frozen=True)
class VelocityWeakeningBit(BitLaw):
    """A bit–rock law that does not exist in the package: the rock carries ``W = W0 + u̇/a`` (a threshold
    ``W0`` [N] and a penetration rate ``a`` [m/(N·s)] per newton above it; no force when W ≤ 0) and resists
    the rotation with a friction torque ``μR W g(ω)`` that weakens with speed, ``g(ω) = (1 + β e^{−|ω|/ω_s})
    tanh(ω/ω_r)``."""

    name: ClassVar[str] = "velocity_weakening_test"
    kernel_size: ClassVar[int] = 6
    kernel: ClassVar = _weakening_kernel
    jacobian_kernel: ClassVar = _weakening_jacobian  # jacobian_at(ctx) is the protocol's: this, from Python

    threshold: float = 2e4  # W0 [N]
    rate: float = 4.4e-8  # a [m/(N·s)]
    friction_arm: float = 0.05  # μR [m]
    weakening: float = 1.0  # β [-]
    weakening_speed: float = 5.0  # ω_s [rad/s]
    regularization: float = 0.5  # ω_r [rad/s]

    @classmethod
    def from_case(cls, case):
        return cls()

    def kernel_array(self):
        return np.array([self.threshold, self.rate, self.friction_arm, self.weakening, self.weakening_speed,
                         self.regularization])

    def _shape(self, w):
        return (1.0 + self.weakening * np.exp(-np.abs(w) / self.weakening_speed)) * np.tanh(w / self.regularization)

    def evaluate_at(self, ctx: BitContext):
        u, w = np.broadcast_arrays(np.asarray(ctx.axial_velocity, float), np.asarray(ctx.bit_speed, float))
        weight = self.threshold + u / self.rate
        contact = weight > 0.0
        return (np.where(contact, -weight, 0.0), np.where(contact, -self.friction_arm * weight * self._shape(w), 0.0))

    def steady_drilling(self, bit_speed, axial_load, resistance):
        rop = (axial_load - self.threshold) / (1.0 / self.rate + resistance)
        if not rop > 0.0:
            return None
        force, torque = self.evaluate(rop, bit_speed)
        return BitSteadyState(rop, float(force), float(torque))


LAW = VelocityWeakeningBit()


def test_the_outside_law_is_registered_outside_the_package():
    assert bit_law("velocity_weakening_test") is VelocityWeakeningBit
    assert "velocity_weakening_test" in bit_laws()
    assert VelocityWeakeningBit.component_code < 0  # never in the compiled dispatch
    package = {name: bit_law(name).component_code for name in ("detournay", "off_bottom", "tucker_wang")}
    assert package == {name: name_code("bit_law", name) for name in package}  # from the names: they never move
    assert len(set(package.values())) == 3
    with pytest.raises(ValueError, match="bit law 'no_such_law': must be one of .*tucker_wang"):
        bit_law("no_such_law")
    with pytest.raises(ValueError, match="'tucker_wang' is already registered by drillstring.forces.bit_rock"):
        register(type("Impostor", (VelocityWeakeningBit,), {"name": "tucker_wang"}))
    assert bit_law("tucker_wang").__module__ == "drillstring.forces.bit_rock"


def test_case_names_are_the_registered_ones():
    """The case format is unchanged; its law names are the registered components (any registered name: a law
    added to the package or by a script needs no edit of the case), its built-in keys the package's laws'."""
    package = {n for n in bit_laws() if bit_law(n).__module__.startswith("drillstring.")}
    assert BitRock.model_fields["law"].annotation is str and BitRock().law in package
    # each law's keys are its own model; [bit_rock] is their union, no key read by two laws
    owned = [set(bit_law(n).keys.model_fields) for n in sorted(package) if bit_law(n).keys is not None]
    assert sum(len(k) for k in owned) == len(set().union(*owned))
    assert set().union(*owned) == set(BitRock.model_fields) - {"law"}
    for n in package:
        for field in getattr(bit_law(n).keys, "model_fields", {}).values():
            assert field.description  # units in the description, bounds in the metadata where they apply
    assert set(TopDrive.model_fields["controller"].annotation.__args__) >= {"imposed_speed"}
    assert "top_drive" in top_boundaries()


def test_outside_law_kernel_reference_and_jacobian():
    rng = np.random.default_rng(2)
    args = LAW.kernel_array()
    for u, w in zip(rng.uniform(-2e-3, 6e-3, 20), rng.uniform(-3.0, 15.0, 20)):
        ctx = bit_context(u, w, time=1.0, weight_on_bit=1e5)
        assert _weakening_kernel(args, ctx) == pytest.approx(tuple(map(float, LAW.evaluate_at(ctx))), rel=1e-13)
        jac = LAW.jacobian_at(ctx)
        for j, (du, dw) in enumerate([(1e-9, 0.0), (0.0, 1e-6)]):
            plus = np.array(LAW.evaluate(u + du, w + dw), dtype=float)
            minus = np.array(LAW.evaluate(u - du, w - dw), dtype=float)
            np.testing.assert_allclose(jac[:, j], (plus - minus) / (2 * (du + dw)), rtol=1e-6,
                                       atol=1e-9 * np.abs(jac).max())


def test_the_protocol_applies_the_kernel_elementwise_by_default():
    """A law that writes only its kernel gets ``evaluate_at`` from the protocol: the kernel applied elementwise
    over the broadcast context, equal to this law's own NumPy form (written independently above)."""
    u = np.linspace(-2e-3, 6e-3, 7).reshape(7, 1)
    w = np.linspace(-3.0, 15.0, 5)
    ctx = bit_context(u, w, time=1.0, weight_on_bit=1e5)
    force, torque = BitLaw.evaluate_at(LAW, ctx)
    own_force, own_torque = LAW.evaluate_at(ctx)
    assert force.shape == torque.shape == (7, 5)
    np.testing.assert_allclose(force, own_force, rtol=1e-13, atol=0.0)
    np.testing.assert_allclose(torque, own_torque, rtol=1e-13, atol=1e-12 * np.abs(own_torque).max())
    assert np.count_nonzero(force == 0.0) > 0  # the bit leaves the rock at some of them
    scalar = BitLaw.evaluate_at(LAW, bit_context(1e-3, 5.0))
    assert scalar[0].shape == ()
    assert float(scalar[0]) == _weakening_kernel(LAW.kernel_array(), bit_context(1e-3, 5.0))[0]


@pytest.fixture(scope="module")
def model(torsional_case):
    return case_reduced_model(torsional_case, bit_rock=LAW)


def test_layout_is_computed(model):
    """The law's numbers sit after the header, the others after them, the offsets from the sizes."""
    layout = model.layout
    assert layout.numbers["bit_law"] == BIT_LAW == len(HEADER)
    assert layout.numbers["top_boundary"] == BIT_LAW + VelocityWeakeningBit.kernel_size
    np.testing.assert_array_equal(model.case2_data.laws[BIT_LAW:BIT_LAW + 6], LAW.kernel_array())
    assert layout.state_size == model.state_size == 2 * model.size  # imposed speed: no states


def test_stability_asks_the_outside_law(model, torsional_case):
    steady = steady_drilling(model)
    r = rigid_axial_column(model)
    b_r = model.bit_u[r]
    load = model.weight_on_bit + model.generalized_force[r] / b_r
    resistance = model.damping[r, r] / b_r**2
    assert steady.rate_of_penetration == pytest.approx((load - LAW.threshold) / (1 / LAW.rate + resistance),
                                                       rel=1e-12)
    # an equilibrium of the NumPy reference right-hand side
    n = model.size
    rhs = model.rhs_reference(0.0, steady.state)
    assert np.abs(rhs[n:]).max() < 1e-9 * np.abs(model.omega2 * steady.state[:n]).max()
    # the linearization (the law's Jacobian) against finite differences of that right-hand side
    a = linearized_matrix(model, steady)
    y = steady.state
    fd = np.zeros_like(a)
    for k in range(len(y)):
        step = 1e-7 * max(1.0, abs(y[k]))
        d = np.zeros_like(y)
        d[k] = step
        fd[:, k] = (model.rhs_reference(0.0, y + d) - model.rhs_reference(0.0, y - d)) / (2 * step)
    np.testing.assert_allclose(a, fd, atol=1e-7 * np.abs(a).max())
    # velocity weakening (β) feeds the torsional modes negative damping: the leading root grows with it
    weak = stability(model).leading.growth_rate
    strong = stability(case_reduced_model(torsional_case, bit_rock=VelocityWeakeningBit(weakening=4.0)))
    assert strong.leading.growth_rate > weak and strong.leading.family == "torsional"


def test_simulate_runs_the_outside_law_through_the_reference_engine(model):
    steady = steady_drilling(model)
    result = simulate_model(model, engine="reference", t_end=0.4, output_step=0.05, initial_state=steady.state)
    obs = result.observables
    np.testing.assert_allclose(obs["rate_of_penetration"], steady.rate_of_penetration, rtol=1e-6)
    np.testing.assert_allclose(obs["force_on_bit"], steady.force_on_bit, rtol=1e-6)
    np.testing.assert_allclose(obs["torque_on_bit"], steady.torque_on_bit, rtol=1e-6)
    with pytest.raises(ValueError, match="'velocity_weakening_test' is registered outside the drillstring package"):
        simulate_model(model, t_end=0.1, output_step=0.05)


# --- a top boundary without states, defined here ------------------------------------------------------------


@njit(cache=True)
def _damper_kernel(args, ctx, states, rates):
    """``[k, Ω]`` -> the motor torque ``k (Ω − θ̇₀)``; no states."""
    return args[0] * (args[1] - ctx.quill_speed)


@register
@dataclass(frozen=True)
class SpeedDamper(TopBoundary):
    """A top drive without controller states: a motor turning at Ω coupled to the quill (inertia J) by a
    viscous coupling k, ``τ_m = k (Ω − θ̇₀)`` — the PI controller with k_i = 0, less its integral state."""

    name: ClassVar[str] = "speed_damper_test"
    kernel_size: ClassVar[int] = 2
    kernel: ClassVar = _damper_kernel

    set_point: float
    gain: float
    inertia: float

    @property
    def top_inertia(self):
        return self.inertia

    def kernel_array(self):
        return np.array([self.gain, self.set_point])

    def evaluate_at(self, ctx: TopContext, states):
        return self.gain * (self.set_point - ctx.quill_speed), np.zeros(0)

    def jacobian_at(self, ctx, states):
        return np.array([[-self.gain, 0.0]])

    def steady_states(self, motor_torque, surface_torque):
        return np.zeros(0)

    def steady_speed(self, motor_torque):
        return self.set_point - motor_torque / self.gain


def test_a_top_boundary_without_states(torsional_case):
    """The state-less boundary against the package's PI controller with k_i = 0 (the same torque; its integral
    state feeds nothing back): the same steady state, the same roots (the PI's extra one is its integral
    state's 0), the same run — the NumPy reference applies the motor torque of a boundary without states."""
    gain, inertia = 3e3, 800.0
    pi_case = torsional_case.model_copy(update={"top_drive": torsional_case.top_drive.model_copy(update={
        "controller": "pi", "proportional_gain": gain, "integral_gain": 0.0, "inertia": inertia})})
    pi = case_reduced_model(pi_case)
    damper = case_reduced_model(torsional_case, top_drive=SpeedDamper(torsional_case.operation.top_speed, gain,
                                                                       inertia))
    assert damper.state_size == 2 * damper.size and pi.state_size == 2 * pi.size + 1
    a, b = stability(pi), stability(damper)
    assert b.steady_state.bit_speed == pytest.approx(a.steady_state.bit_speed, rel=1e-12)
    assert b.steady_state.torque_on_bit == pytest.approx(a.steady_state.torque_on_bit, rel=1e-12)
    roots_pi = sorted((m.growth_rate, m.frequency) for m in a.modes if abs(m.eigenvalue) > 1e-9)
    roots = sorted((m.growth_rate, m.frequency) for m in b.modes)
    np.testing.assert_allclose(roots, roots_pi, rtol=1e-8, atol=1e-10)
    options = dict(t_end=1.0, output_step=0.1, rtol=1e-9, atol=1e-12, lateral_perturbation=0.0)
    expected = simulate_model(pi, **options).observables
    got = simulate_model(damper, engine="reference", **options).observables
    for name in ("bit_speed", "quill_speed", "surface_torque", "torque_on_bit"):
        np.testing.assert_allclose(got[name], expected[name], rtol=0, atol=1e-6 * np.abs(expected[name]).max(),
                                   err_msg=name)


def test_pack_refuses_a_law_whose_numbers_disagree_with_its_size(model):
    """The registry checks the declared size against the numbers: an offset can never shift silently."""
    from drillstring.forces.registry import pack

    class Short(VelocityWeakeningBit):
        kernel_size: ClassVar[int] = 7

    with pytest.raises(ValueError, match="kernel_array\\(\\) has 6 numbers, kernel_size says 7"):
        pack(Short(), model.top_drive, model.hook_load, np.zeros(4), 2 * model.size)


# --- a delayed law (it reads the depth of cut), defined here ---------------------------------------------------


@njit(cache=True)
def _cutting_kernel(args, ctx):
    """``[k, c, ω_r]`` -> ``(−k d, −c d clip(ω/ω_r, −1, 1))`` for a depth of cut d > 0, else no contact."""
    d = ctx.depth_of_cut
    if not d > 0.0:
        return 0.0, 0.0
    turn = min(max(ctx.bit_speed / args[2], -1.0), 1.0)
    return -args[0] * d, -args[1] * d * turn


@register
@dataclass(frozen=True)
class PureCutting(BitLaw):
    """Cutting without wear flats, ``W = k d``, ``T = c d`` (d the depth of cut per blade, one blade sector
    of lag): the Detournay law with σ = 0, written from scratch as a law outside the package."""

    name: ClassVar[str] = "pure_cutting_test"
    kernel_size: ClassVar[int] = 3
    kernel: ClassVar = _cutting_kernel
    delayed: ClassVar[bool] = True

    stiffness: float  # k [N/m]
    torque_rate: float  # c [N·m/m]
    blades: int
    friction_speed: float = 5e-3  # ω_r [rad/s]

    @property
    def sector(self):
        return 2.0 * math.pi / self.blades

    def kernel_array(self):
        return np.array([self.stiffness, self.torque_rate, self.friction_speed])

    def evaluate_at(self, ctx):
        d, w = np.broadcast_arrays(np.asarray(ctx.depth_of_cut, float), np.asarray(ctx.bit_speed, float))
        on = d > 0.0
        turn = np.clip(w / self.friction_speed, -1.0, 1.0)
        return np.where(on, -self.stiffness * d, 0.0), np.where(on, -self.torque_rate * d * turn, 0.0)

    def jacobian_at(self, ctx):
        d, w = float(ctx.depth_of_cut), float(ctx.bit_speed)
        slope = 1.0 / self.friction_speed if d > 0.0 and abs(w) < self.friction_speed else 0.0
        return np.array([[0.0, 0.0], [0.0, -self.torque_rate * d * slope]])

    def depth_partials(self, ctx):
        if not ctx.depth_of_cut > 0.0:
            return 0.0, 0.0
        return -self.stiffness, -self.torque_rate * min(max(ctx.bit_speed / self.friction_speed, -1.0), 1.0)

    def steady_drilling(self, bit_speed, axial_load, resistance):
        rop = axial_load / (self.stiffness * self.sector / bit_speed + resistance)
        if not rop > 0.0:
            return None
        depth = rop * self.sector / bit_speed
        force, torque = self.evaluate_at(bit_context(rop, bit_speed, depth))
        return BitSteadyState(rop, float(force), float(torque), depth)


def test_a_delayed_law_from_outside_equals_the_detournay_law_it_rewrites(torsional_case):
    """The delayed path of the protocol (depth of cut from the bit's history, the start's helical bottom, the
    delay roots) for a law from outside: equal to the package's Detournay law without wear flats."""
    case = torsional_case.model_copy(update={
        "bit_rock": torsional_case.bit_rock.model_copy(update={"law": "detournay", "contact_stress": 0.0}),
        "initial": torsional_case.initial.model_copy(update={"start": "on_bottom"})})
    detournay = case_reduced_model(case)
    law = detournay.bit_rock
    outside = case_reduced_model(case, bit_rock=PureCutting(law.cutting_stiffness, law.cutting_torque_rate,
                                                            law.blades, law.friction_speed))
    a, b = stability(detournay), stability(outside)
    assert b.steady_state.rate_of_penetration == pytest.approx(a.steady_state.rate_of_penetration, rel=1e-12)
    assert b.steady_state.delay == pytest.approx(a.steady_state.delay, rel=1e-12)
    assert b.leading.growth_rate == pytest.approx(a.leading.growth_rate, rel=1e-8, abs=1e-10)
    assert b.leading.frequency == pytest.approx(a.leading.frequency, rel=1e-8)
    options = dict(t_end=0.6, output_step=0.05, rtol=1e-9, atol=1e-12)
    expected = simulate_model(detournay, engine="reference", **options).observables
    got = simulate_model(outside, engine="reference", **options).observables
    for name in ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit", "bit_depth"):
        np.testing.assert_allclose(got[name], expected[name], rtol=0, atol=1e-9 * np.abs(expected[name]).max(),
                                   err_msg=name)
    assert np.abs(expected["force_on_bit"]).max() > 0.0


# --- a hook load defined here --------------------------------------------------------------------------------


@njit(cache=True)
def _heave_kernel(args, ctx):
    """``[A, ω]`` -> ``A sin(ω t)``."""
    return args[0] * math.sin(args[1] * ctx.time)


@register
@dataclass(frozen=True)
class HeavingHook(HookLoad):
    """A hook load that does not exist in the package: a floating rig's heave pulling the top with ``A sin(ω t)``
    [N] (``A`` [N], ``ω`` [rad/s])."""

    name: ClassVar[str] = "heave_test"
    kernel_size: ClassVar[int] = 2
    kernel: ClassVar = _heave_kernel

    amplitude: float = 2e4
    frequency: float = 0.7

    def kernel_array(self):
        return np.array([self.amplitude, self.frequency])

    def evaluate_at(self, ctx: HookContext):
        return self.amplitude * np.sin(self.frequency * np.asarray(ctx.time, dtype=float))


def test_a_hook_load_from_outside_acts_at_the_top_through_the_reference_engine(torsional_case):
    """The outside hook load's force enters the right-hand side at the top's u and nowhere else; the registry
    places its numbers and gives it a negative code; the compiled engine refuses it by name."""
    from dataclasses import replace

    plain = case_reduced_model(torsional_case)
    heaving = replace(plain, hook_load=HeavingHook())
    assert HeavingHook.component_code < 0.0 and not heaving.compiled and plain.compiled
    start = heaving.layout.numbers["hook_load"]
    np.testing.assert_array_equal(heaving.case2_data.laws[start:start + 2], [2e4, 0.7])
    n = plain.size
    y = np.random.default_rng(5).standard_normal(plain.state_size) * 1e-3
    t = 1.3
    difference = heaving.rhs_reference(t, y) - plain.rhs_reference(t, y)
    np.testing.assert_allclose(difference[n:2 * n], plain.top_u * 2e4 * math.sin(0.7 * t), rtol=1e-9, atol=1e-9)
    assert not difference[:n].any() and not difference[2 * n:].any()
    np.testing.assert_allclose(plain.rhs(t, y), plain.rhs_reference(t, y), rtol=1e-10, atol=1e-8)
    with pytest.raises(ValueError, match="hook load 'heave_test' is registered outside the drillstring package"):
        heaving.rhs(t, y)


# --- a contact law defined here ------------------------------------------------------------------------------


@njit(cache=True)
def _frictionless_kernel(args, ctx, force_v, force_w, torque):
    """The wall pushes back ``k_i (r − g)`` along the normal; no friction."""
    for i in range(ctx.v.shape[0]):
        r = math.sqrt(ctx.v[i] ** 2 + ctx.w[i] ** 2)
        push = ctx.stiffness[i] * (r - ctx.gap[i]) / r if r > ctx.gap[i] else 0.0
        force_v[i] = -push * ctx.v[i]
        force_w[i] = -push * ctx.w[i]
        torque[i] = 0.0


@register
@dataclass(frozen=True)
class FrictionlessWall(ContactLaw):
    """A contact law that does not exist in the package: the penalty wall without friction."""

    name: ClassVar[str] = "frictionless_test"
    kernel: ClassVar = _frictionless_kernel

    shock_stiffness: float = 1e8

    @property
    def reads_lateral_velocity(self):
        return False

    def evaluate_at(self, ctx: ContactContext):
        v, w = np.asarray(ctx.v, dtype=float), np.asarray(ctx.w, dtype=float)
        r = np.hypot(v, w)
        push = np.where(r > ctx.gap, np.asarray(ctx.stiffness) * (r - ctx.gap) / np.where(r > 0, r, 1.0), 0.0)
        return -push * v, -push * w, np.zeros_like(v)


def test_contact_is_a_registered_law_and_one_from_outside_runs_through_the_reference_engine(coarse_case):
    """The package's contact law is registered with the case's ``[contact]`` as its keys; a frictionless wall
    written here gives, through the NumPy reference, the package law with μ = 0 through the compiled kernels
    (states far enough out that many stations touch); with tangential friction the compiled dispatch equals the
    reference too; the compiled engine refuses the outside law by name."""
    from dataclasses import replace

    from drillstring.case import Contact
    from drillstring.forces.contact import ContactParameters, case_contact

    assert "penalty" in contact_laws() and contact_law("penalty") is ContactParameters
    assert ContactParameters.keys is Contact and ContactParameters.component_code > 0.0
    assert FrictionlessWall.component_code < 0.0
    assert ContactParameters.from_case(coarse_case) == case_contact(coarse_case)
    package = case_reduced_model(coarse_case, lateral_modes=5)
    k, eps = package.contact.shock_stiffness, package.contact.speed_regularization
    outside = replace(package, contact=FrictionlessWall(k))
    frictionless = replace(package, contact=ContactParameters(k, 0.0, eps))
    tangential = replace(package, contact=ContactParameters(k, 0.3, eps, True))
    assert not outside.compiled and tangential.case2_data.contact.tangential
    rng = np.random.default_rng(7)
    for t in (0.0, 0.37):
        y = rng.normal(size=2 * package.size) * 30.0
        expected = frictionless.rhs(t, y)
        np.testing.assert_allclose(outside.rhs_reference(t, y), expected, rtol=1e-10,
                                   atol=1e-10 * np.abs(expected).max())
        fast, slow = tangential.rhs(t, y), tangential.rhs_reference(t, y)
        np.testing.assert_allclose(fast, slow, rtol=1e-10, atol=1e-10 * np.abs(slow).max())
        assert np.abs(fast - expected).max() > 1e-3 * np.abs(expected).max()  # the friction does act
    assert package.observe(0.0, y)[OBSERVABLE_COLUMN["nodes_in_contact"]] > 0
    with pytest.raises(ValueError, match="contact law 'frictionless_test' is registered outside the drillstring"):
        outside.rhs(0.0, y)
