"""Steady drilling and its linear stability (docs/model.md §5, §7).

**Steady drilling** is the equilibrium of the reduced model in which the whole string turns at the top
speed Ω and advances at a constant rate of penetration: the rigid axial coordinate moves at a constant
speed, every other coordinate sits at a constant offset. The rigid axial equation
``b_r (f + wob) + g_r = D_rr η̇_r``, ``u̇ = b_r η̇_r`` is ``−f(V, Ω) = W − c V`` with ``W = wob + g_r/b_r``
and ``c = D_rr/b_r²``: the bit–rock law solves it itself (its ``steady_drilling``,
:mod:`drillstring.forces.registry`; the analysis never samples the law). For a law affine in the bit's axial
speed at a fixed bit speed, ``f(u̇, Ω) = f0 + f1 u̇`` (Tucker & Wang, docs/model.md §5; Detournay), that is

    ROP = (b_r (f0 + wob) + g_r) / (D_rr / b_r − b_r f1)                                        (1)

which is ``ROP = Z² (a2 wob − a1 + a3 √(Ω² + e²)) / (1 + a2 c1 Z²)`` for the reference model (``c1`` the
rigid axial resistance; with ``c1 = 0`` it is docs/model.md §5's ``Z²(a2 wob − a1) + Z a3 Ω``). The bit speed is
Ω, ``TOB = −t(ROP, Ω)``, ``FOB = −f(ROP, Ω)``, and the elastic offsets follow from ``ω_j² η_j`` = the
constant generalised forces.

**Linear stability.** About that state the reduced equations are linearised, the bit–rock law
included::

    δη̈ = −diag(ω²) δη − (D − J) δη̇,
    J = b_u (f_u b_uᵀ + f_θ b_tᵀ) + b_t (t_u b_uᵀ + t_θ b_tᵀ)                                  (2)

with ``b_u``, ``b_t`` the basis rows of the bit's axial and torsional DOFs and ``f_u = ∂f/∂u̇``,
``f_θ = ∂f/∂θ̇``, ``t_u``, ``t_θ`` the partial derivatives of the law at ``(ROP, Ω)`` (the law's own
Jacobian, :meth:`~drillstring.forces.bit_rock.BitRockParameters.jacobian`). ``t_θ > 0`` is the
velocity-weakening torque that acts as a negative damping on the torsional modes. The rigid axial
position does not enter any equation (the depth drilled is indifferent) and is left out, so every
eigenvalue is informative. Steady drilling is stable when
every eigenvalue has a negative real part. Lateral modes are decoupled from the bit–rock law at the
centred state; they enter with their own damping and stiffness (a negative ω², a buckled string, makes
them unstable). The kinetic- and strain-energy forces of case 1 are at least quadratic in the lateral
motion and are not linearised here. Loads turning with the string (mass imbalance, bow:
:mod:`drillstring.forces.excitation`) are left out too: they make the motion periodic, so there is no
steady state to linearise about; the lateral modes' stability does not depend on them.

**Top drive** (:mod:`drillstring.forces.top_drive`). With a top drive the torsional family is free at the
top: in steady drilling the whole string turns rigidly at the quill speed (the set point Ω when the
controller has integral action; with ``k_i = 0`` the speed at which ``k_p (Ω − ω)`` balances the load,
found by fixed-point iteration), the motor torque ``τ_m`` balances the torque on bit and the rigid-rotation
friction ``c2 ω`` (the rigid-rotation equation), the integral state is ``τ_m / k_i`` and the z_torque filter
holds the surface torque. The linearisation (2) then takes the whole loop: ``δτ_m`` from the controller's
Jacobian at the steady state (the boundary's ``jacobian_at``, :mod:`drillstring.forces.registry`) on the
quill speed ``qᵀδη̇``
and the surface torque ``sᵀδη``, acting through ``q`` (the torsional shapes at the top), and the controller's
states as extra rows. The rigid rotation's angle, like the depth drilled, enters no equation and is left
out. **Off bottom** (``bit_rock.law = "off_bottom"``) the steady state is rotation without penetration
(ROP 0, no bit–rock force) and the bit–rock Jacobian is zero.

**The Detournay law** (:mod:`drillstring.forces.detournay`) is affine in the rate of penetration too in
steady drilling (the depth of cut per blade is ``d = V·2π/(nΩ)``, so ``f = −aσl − a ζ ε n d``), and eq. (1)
holds as written. Its linearisation is a **delay** system: the depth of cut ``d = u(t) − u(t − τ)`` with
``θ(t) − θ(t − τ) = 2π/n`` perturbs as ``δd = gᵀ(δη(t) − δη(t − τ0))``, ``g = b_u − (V/Ω) b_t``,
``τ0 = 2π/(nΩ)`` (:func:`~drillstring.dynamics.delay_stability.second_order_delay_matrices`), so that

    δẋ = A0 δx(t) + A1 δx(t − τ0),   A0 = A + [h gᵀ in the accelerations' rows],   A1 = −[h gᵀ there]   (3)

with ``A`` the matrix of eq. (2) (the law's partials in ``u̇`` and ``θ̇``, zero in steady drilling: neither
regularised set-valued part is active there) and ``h = f_d b_u + t_d b_t`` its partials in the depth of cut.
The roots of ``det(sI − A0 − A1 e^{−sτ0}) = 0`` (:func:`~drillstring.dynamics.delay_stability.characteristic_roots`:
Chebyshev collocation of the infinitesimal generator, refined by Newton's method) replace the eigenvalues;
the rigid positions now enter (through differences), so they are kept and their invariance shows as a
neutral root at 0, reported apart (``neutral_roots``), never as a mode.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np
import scipy.linalg as sla

from drillstring.dynamics.delay_stability import (
    DelayRoots,
    _newton,
    _residuals,
    characteristic_roots,
    regenerative_coupling,
)
from drillstring.dynamics.rom import ReducedOrderModel, rigid_axial_column
from drillstring.forces.registry import BitContext, BitSteadyState, MotorContext, TopContext
from drillstring.units import quantity_text

#: Families reported for the eigenvalues (lateral y and z together).
STABILITY_FAMILIES = ("axial", "torsional", "lateral")
#: A root is *mixed* when no family holds at least this share of its modal energy (:attr:`ModeStability.shares`).
MIXED_SHARE = 0.8
#: Without the convergence check (a model alone, e.g. a study's realization): a root is *beyond the basis* when
#: its attachment modes hold at least this share of its modal energy.
RESIDUAL_SHARE = 0.5
#: The convergence check (:func:`check_convergence`): a root ``s`` of the basis is *converged* when the basis with
#: twice the modes of every family has a root ``s'`` with ``|s' − s| ≤ CONVERGENCE_GROWTH |Re s| +
#: CONVERGENCE_DAMPING |s|``: its growth rate within 5 % or its damping ratio within 0.001.
CONVERGENCE_GROWTH = 0.05
CONVERGENCE_DAMPING = 1e-3
#: Newton steps on the larger basis's ``det Δ`` from a root (a root that persists is found in a few).
CONVERGENCE_NEWTON_STEPS = 12
#: Roots refined at once on the larger basis (in decreasing growth rate).
CONVERGENCE_BATCH = 8


@dataclass(frozen=True)
class SteadyDrilling:
    """Steady drilling (SI): ``rate_of_penetration`` [m/s], ``bit_speed`` [rad/s], ``torque_on_bit``
    [N·m], ``force_on_bit`` [N]; ``state`` is the reduced state ``[η, η̇]`` at t = 0 (rigid axial
    coordinate 0); ``depth_of_cut`` [m] per blade and ``delay`` [s] of a delayed law (0 otherwise); ``note``:
    '' or one line saying that the state is not at the set point asked for (:func:`steady_drilling`)."""

    rate_of_penetration: float
    bit_speed: float
    torque_on_bit: float
    force_on_bit: float
    state: np.ndarray
    depth_of_cut: float = 0.0
    delay: float = 0.0
    note: str = ""
    motor: dict | None = None  # a downhole motor's steady state: motor_speed [rad/s], motor_torque [N·m],
    #                            differential_pressure [Pa], string_speed [rad/s] (of the string above it)

    def to_dict(self) -> dict[str, float]:
        out = {"rate_of_penetration": self.rate_of_penetration, "bit_speed": self.bit_speed,
               "torque_on_bit": self.torque_on_bit, "force_on_bit": self.force_on_bit}
        if self.delay > 0.0:
            out.update(depth_of_cut=self.depth_of_cut, delay=self.delay)
        if self.motor is not None:
            out.update(self.motor)
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class ModeStability:
    """One eigenvalue λ of the linearised model (one of each complex-conjugate pair).

    ``frequency`` = |Im λ| / 2π [Hz], ``damping_ratio`` = −Re λ / |λ| [-], ``growth_rate`` = Re λ [1/s]
    (> 0: the mode grows), ``family`` the family holding most of the mode's modal energy, ``shares`` the
    share of each family (:data:`STABILITY_FAMILIES`) in that energy, ``½ Σ (|δη̇_j|² + |ω_j²| |δη_j|²)``
    over the family's modal coordinates j of the root's eigenvector (they add up to 1). ``residual_share``: the
    share of that energy in the basis's residual-flexibility attachment modes (``reduced_model.
    truncation_correction = "static"``). ``converged``: whether the root persists when the basis grows
    (:func:`check_convergence`: True, False, or None when not checked) and ``basis_change`` [1/s] how far it
    moved, ``|s' − s|`` (None when not checked or no root of the larger basis was found near it).
    """

    family: str
    frequency: float
    damping_ratio: float
    growth_rate: float
    shares: dict[str, float] | None = None
    residual_share: float = 0.0
    converged: bool | None = None
    basis_change: float | None = None

    @property
    def beyond_basis(self) -> bool:
        """A root of the basis's cut-off, not of the string: it does not persist when the basis grows
        (``converged`` False); a root not checked (``converged`` None) when it lives mostly in the attachment
        modes (:data:`RESIDUAL_SHARE`). Listed but not counted by :attr:`StabilityResult.leading` and
        :attr:`StabilityResult.stable`."""
        if self.converged is not None:
            return not self.converged
        return self.residual_share >= RESIDUAL_SHARE

    def to_dict(self) -> dict:
        """JSON-ready: the fields and ``beyond_basis``."""
        return {**asdict(self), "beyond_basis": self.beyond_basis}

    @property
    def eigenvalue(self) -> complex:
        return complex(self.growth_rate, 2.0 * math.pi * self.frequency)

    @property
    def mixed(self) -> bool:
        """No family holds :data:`MIXED_SHARE` of the root's modal energy (False without shares)."""
        return bool(self.shares) and max(self.shares.values()) < MIXED_SHARE


@dataclass(frozen=True)
class StabilityResult:
    """Steady drilling and the eigenvalues of the reduced model linearised about it.

    ``modes`` are sorted by frequency; ``stable`` is True when every growth rate is negative. The roots
    :attr:`ModeStability.beyond_basis` (that do not persist when the basis grows) stay in ``modes`` but are left
    out of ``stable``, ``leading`` and the per-family results: the basis does not resolve them. ``convergence``:
    the check's facts (:func:`check_convergence`), None when not checked.
    """

    steady_state: SteadyDrilling
    modes: list[ModeStability]
    top_drive: dict | None = None  # the top drive's controller and gains (TopDriveParameters.describe)
    delay: dict | None = None  # a delayed law: the delay system's roots (:func:`delay_roots_summary`)
    convergence: dict | None = None  # the convergence check (:func:`check_convergence`)

    @property
    def resolved(self) -> list[ModeStability]:
        """The roots that are not :attr:`ModeStability.beyond_basis` (all of them without attachment modes)."""
        return [m for m in self.modes if not m.beyond_basis]

    @property
    def stable(self) -> bool:
        return all(m.growth_rate < 0.0 for m in self.resolved)

    @property
    def leading(self) -> ModeStability:
        """The mode with the largest growth rate (among :attr:`resolved`)."""
        return max(self.resolved, key=lambda m: m.growth_rate)

    @property
    def leading_by_family(self) -> dict[str, ModeStability | None]:
        """The root of largest growth rate of each family (:data:`STABILITY_FAMILIES`; a root belongs to the
        family holding most of its energy), None for a family without a root. Unlike :attr:`leading`, the
        torsional and axial roots stay visible above the buckling load, where a lateral divergence leads."""
        out: dict[str, ModeStability | None] = {}
        for family in STABILITY_FAMILIES:
            own = [m for m in self.resolved if m.family == family]
            out[family] = max(own, key=lambda m: m.growth_rate) if own else None
        return out

    def family_stable(self, family: str) -> bool | None:
        """Every root of ``family`` decays (None: the family has no root)."""
        own = [m for m in self.resolved if m.family == family]
        return all(m.growth_rate < 0.0 for m in own) if own else None

    @property
    def mixed_roots(self) -> list[ModeStability]:
        """The roots no family dominates (:attr:`ModeStability.mixed`), sorted by frequency."""
        return [m for m in self.modes if m.mixed]

    def to_dict(self) -> dict:
        """JSON-ready (SI): ``stable``, ``steady_state``, ``leading`` (the leading resolved root), ``modes``
        (list sorted by frequency, each with its family's energy ``shares``, ``converged``, ``basis_change`` and
        ``beyond_basis``), ``leading_by_family`` (per family: the leading root or None, and ``stable``),
        ``mixed_roots`` and ``convergence`` (the check's facts, None when not checked)."""
        out = {"stable": self.stable, "steady_state": self.steady_state.to_dict(),
               "leading": self.leading.to_dict() if self.resolved else None,
               "modes": [m.to_dict() for m in self.modes],
               "leading_by_family": {f: (None if m is None else {**m.to_dict(), "stable": self.family_stable(f)})
                                     for f, m in self.leading_by_family.items()},
               "mixed_roots": [m.to_dict() for m in self.mixed_roots],
               "convergence": self.convergence}
        if self.top_drive is not None:
            out["top_drive"] = self.top_drive
        if self.delay is not None:
            out["delay"] = self.delay
        return out


def _steady_law(model: ReducedOrderModel, omega: float, r: int) -> BitSteadyState:
    """The bit law's steady drilling at the bit speed ``omega`` [rad/s] (the law's own
    :meth:`~drillstring.forces.registry.BitLaw.steady_drilling`): the rigid axial equation
    ``b_r (f + wob) + g_r = D_rr V / b_r`` is ``−f(V, Ω) = W − c V`` with the axial load
    ``W = wob + g_r / b_r`` and the resistance ``c = D_rr / b_r²`` (plus the along-string friction's,
    :meth:`~drillstring.dynamics.reduced.model.ReducedOrderModel.friction_axial_resistance`); eq. (1) for a law affine in V."""
    b_r = model.bit_u[r]
    steady = model.bit_rock.steady_drilling(omega, model.weight_on_bit + model.generalized_force[r] / b_r,
                                            model.damping[r, r] / b_r**2 + model.friction_axial_resistance(omega))
    if steady is None:
        raise ValueError(
            f"no steady drilling at weight_on_bit = {quantity_text(model.weight_on_bit, 'force')}, top_speed = "
            f"{quantity_text(omega, 'angular_speed')}:"
            f" the bit-rock law {model.bit_rock.name!r} gives no rate_of_penetration > 0 (rate_of_penetration <= 0)"
        )
    return steady


def _steady_load(model: ReducedOrderModel, omega: float, r: int):
    """Steady drilling with the string turning at ``omega`` (the bit too, without a downhole motor): (the law's
    steady state, modal velocity, generalized load without the top boundary's motor torque, that torque τ_m
    which the rigid rotation's equation asks for, the downhole motor's speed ω_m [rad/s], 0 without one)."""
    motor_speed = 0.0 if model.motor is None else _steady_motor_speed(model, omega, r)
    return _steady_load_at(model, omega, motor_speed, r) + (motor_speed,)


def _steady_load_at(model: ReducedOrderModel, omega: float, motor_speed: float, r: int):
    """:func:`_steady_load` for a given downhole motor speed ``motor_speed`` ω_m: the bit turns at ``omega +
    motor_speed``, the string below the rotor station turning rigidly relative to the string above
    (:attr:`~drillstring.rotor.RotorRelease.lower_rotation`), the motor's torque pair on the modes."""
    law = _steady_law(model, omega + motor_speed, r)
    n = model.size
    velocity = np.zeros(n)
    velocity[r] = law.rate_of_penetration / model.bit_u[r]
    spin = model.rigid_rotation_column
    if spin is not None:
        velocity[spin] = omega / model.quill_shapes[spin]
    if model.motor is not None:
        velocity = velocity + motor_speed * _lower_rotation(model)
    load = (model.bit_u * (law.axial_force + model.weight_on_bit) + model.bit_t * law.torque
            + model.generalized_force - model.damping @ velocity + model.friction_load(velocity))
    if model.motor is not None:
        load = load + model.motor_shapes * float(model.motor.evaluate(motor_speed))
    motor = 0.0 if spin is None else float(-load[spin] / model.quill_shapes[spin])
    return law, velocity, load, motor


def _lower_rotation(model: ReducedOrderModel) -> np.ndarray:
    """(n,) the modal coordinates of the unit rotation of the string below a downhole motor's rotor station
    relative to the string above (:attr:`~drillstring.rotor.RotorRelease.lower_rotation`)."""
    out = np.zeros(model.size)
    out[model.blocks[2]:model.blocks[3]] = model.rotor.lower_rotation
    return out


#: Samples per ω₀ of the scan for a downhole motor's steady speed in (−Ω, 2ω₀] (:func:`_steady_motor_speed`).
MOTOR_SCAN = 256


def _steady_motor_speed(model: ReducedOrderModel, omega: float, r: int) -> float:
    """The downhole motor's steady speed ω_m [rad/s] with the string above it turning at ``omega``: the root of
    the torque balance of the string below the rotor station (the generalized load on its rigid rotation
    relative to the string above, ``cᵀ load = T(ω_m) − TOB(Ω + ω_m) − its damping torque``; the top boundary's
    torque does no work on that motion) **nearest the no-load speed** ω₀: scanned down from 2 ω₀ (where the motor
    brakes with its stall torque) to the first sign change, then Brent's method; down to a bit speed of 0. ValueError (one line) when the motor stalls (no root
    with the bit turning)."""
    from scipy.optimize import brentq

    lower = _lower_rotation(model)

    def residual(motor_speed: float) -> float:
        return float(lower @ _steady_load_at(model, omega, motor_speed, r)[2])

    upper = 2.0 * model.motor.no_load_speed  # the motor brakes with its stall torque: the balance is < 0
    grid = np.linspace(upper, -omega, 2 * MOTOR_SCAN + 1)[1:-1]
    last = residual(upper)
    for motor_speed in grid:
        try:
            value = residual(float(motor_speed))
        except ValueError:  # no steady drilling at that bit speed: the scan ends
            break
        if (value >= 0.0) != (last >= 0.0):
            return float(brentq(residual, float(motor_speed), upper, xtol=1e-14 * max(upper, omega), rtol=1e-13))
        upper, last = float(motor_speed), value
    raise ValueError(f"no steady drilling: the downhole motor stalls (the bit's torque exceeds what the motor "
                     f"gives at every bit speed above 0; stall torque {model.motor.stall_torque:.6g} N*m at "
                     f"weight_on_bit = {model.weight_on_bit:.6g} N)")


#: Samples of the scan for a drooping top boundary's steady speed in (0, Ω] (:func:`boundary_steady_speed`).
DROOP_SCAN = 256
#: A steady speed this close to the set point (relative) counts as the set point.
SET_POINT_TOLERANCE = 1e-3


def boundary_steady_speed(motor_torque, boundary_speed, set_point: float) -> float:
    """The steady quill speed ω [rad/s] of a driving top boundary: the root of ``ω − ω_b(τ_m(ω)) = 0``
    **nearest the set point** Ω in (0, Ω], with ``motor_torque(ω)`` [N·m] the torque steady drilling at ω
    needs and ``boundary_speed(τ)`` [rad/s] the speed at which the boundary gives that torque (Ω with integral
    action, so ω = Ω at once; ``Ω − τ/k_p`` for a proportional controller, ``integral_gain = 0``). Found by
    scanning down from Ω (:data:`DROOP_SCAN` steps) to the first sign change, then Brent's method. A
    velocity-weakening load may have other roots further down: they are other branches, never taken (a
    fixed-point iteration could jump there). ValueError (one line, naming the torque at the set point) when
    no root exists in (0, Ω]."""
    from scipy.optimize import brentq

    def residual(omega: float) -> float:
        return omega - boundary_speed(motor_torque(omega))

    at_set_point = residual(set_point)
    if at_set_point == 0.0:
        return float(set_point)
    if at_set_point < 0.0:
        raise ValueError(f"no steady rotation below the set point {quantity_text(set_point, 'angular_speed')}: "
                         f"the load torque {quantity_text(motor_torque(set_point), 'torque')} drives the string")
    grid = np.linspace(set_point, 0.0, DROOP_SCAN + 1)[1:-1]
    upper = set_point
    for omega in grid:
        value = residual(float(omega))
        if value <= 0.0:
            return float(brentq(residual, float(omega), upper, xtol=1e-14 * set_point, rtol=1e-13))
        upper = float(omega)
    raise ValueError(f"no steady rotation: the top boundary cannot carry the load torque "
                     f"{motor_torque(set_point):.6g} N*m at a positive speed (no integral action)")


def steady_drilling(model: ReducedOrderModel) -> SteadyDrilling:
    """The steady drilling state of ``model``, eq. (1) (with a top drive: the module docstring). Raises
    ValueError when the law gives no penetration (ROP <= 0: the bit would lift off, the drilling regime does
    not exist) or the motor would need more than its maximum torque. Off bottom: steady rotation, ROP 0.

    With ``integral_gain = 0`` the controller droops: the steady speed is :func:`boundary_steady_speed`, the
    branch nearest the set point, and when it differs from the set point by more than
    :data:`SET_POINT_TOLERANCE` the state's ``note`` says so in one line, naming the speed and the weight on
    bit found (the state is then not the operating point asked for)."""
    r = rigid_axial_column(model)
    drive = model.top_drive
    omega = model.top_speed
    law, velocity, load, motor, motor_speed = _steady_load(model, omega, r)
    note = ""
    if drive.drives:
        set_point = omega

        def speed_of_boundary(motor_torque: float) -> float:
            try:  # the boundary refuses a speed that is not positive: the residual stays positive there
                return drive.steady_speed(motor_torque)
            except ValueError:
                return 0.0

        omega = boundary_steady_speed(lambda w: _steady_load(model, w, r)[3], speed_of_boundary, set_point)
        if omega != set_point:
            law, velocity, load, motor, motor_speed = _steady_load(model, omega, r)
        if abs(omega - set_point) > SET_POINT_TOLERANCE * set_point:
            note = (f"steady drilling at {omega * 30.0 / math.pi:.4g} rpm with "
                    f"{quantity_text(model.weight_on_bit, 'force')} on bit, not the set point "
                    f"{set_point * 30.0 / math.pi:.4g} rpm: without integral action "
                    f"the top boundary's speed droops with the load torque")
        drive.check_steady_torque(motor)
    n = model.size
    if model.rigid_rotation_column is not None:
        load = load + model.quill_shapes * motor
    offsets = np.zeros(n)
    elastic = model.omega2 != 0.0
    offsets[elastic] = load[elastic] / model.omega2[elastic]
    states = np.zeros(model.state_size - 2 * n)
    if drive.drives:
        first = model.layout.states["top_boundary"] - 2 * n
        states[first:first + drive.n_states] = drive.steady_states(motor, float(model.surface_torque_shapes @ offsets))
    downhole = None
    if model.motor is not None:
        first = model.layout.states["motor"] - 2 * n
        states[first:first + model.motor.n_states] = model.motor.steady_states(motor_speed)
        torque = float(model.motor.evaluate(motor_speed))
        downhole = {"motor_speed": motor_speed, "motor_torque": torque,
                    "differential_pressure": float(model.motor.differential_pressure(torque)),
                    "string_speed": float(omega)}
    bit_speed = float(omega + motor_speed)
    return SteadyDrilling(rate_of_penetration=law.rate_of_penetration, bit_speed=bit_speed,
                          torque_on_bit=-law.torque, force_on_bit=-law.axial_force,
                          state=np.concatenate([offsets, velocity, states]), depth_of_cut=law.depth_of_cut,
                          delay=model.bit_rock.sector / bit_speed if model.bit_rock.delayed else 0.0, note=note,
                          motor=downhole)


def linearized_matrix(model: ReducedOrderModel, steady: SteadyDrilling) -> np.ndarray:
    """State matrix ``A`` of eq. (2) for ``[δη, δη̇, δs]`` (:attr:`ReducedOrderModel.state_size` square, rigid
    positions included; ``s`` the top drive controller's states)."""
    n = model.size
    size = model.state_size
    jac = model.bit_rock.jacobian_at(_context(model, steady))
    bu, bt = model.bit_u, model.bit_t
    coupling = (np.outer(bu, jac[0, 0] * bu + jac[0, 1] * bt) + np.outer(bt, jac[1, 0] * bu + jac[1, 1] * bt))
    a = np.zeros((size, size))
    a[:n, n:2 * n] = np.eye(n)
    a[n:2 * n, :n] = -np.diag(model.omega2)
    a[n:2 * n, n:2 * n] = coupling - model.damping + model.friction_jacobian(steady.state[n:2 * n])
    if model.motor is not None:  # the downhole motor's torque pair: dT/dω_m (ω_m = motor_shapesᵀ η̇), its states
        m, first, k = model.motor_shapes, model.layout.states["motor"], model.motor.n_states
        # rows (T, each state's rate), columns (ω_m, each state), at the steady state
        law = model.motor.jacobian_at(*_motor_point(model, steady))
        a[n:2 * n, n:2 * n] += law[0, 0] * np.outer(m, m)
        if k:
            a[n:2 * n, first:first + k] += np.outer(m, law[0, 1:])
            a[first:first + k, n:2 * n] += np.outer(law[1:, 0], m)
            a[first:first + k, first:first + k] += law[1:, 1:]
    drive = model.top_drive
    if drive.drives:
        q, s = model.quill_shapes, model.surface_torque_shapes
        # rows (τ_m, then each state's rate), columns (θ̇₀, T_s, then each state), at the steady state
        law = drive.jacobian_at(*_top_point(model, steady))
        first = model.layout.states["top_boundary"]
        rows = [(slice(n, 2 * n), q, law[0])] + [(first + k, 1.0, law[1 + k]) for k in range(drive.n_states)]
        for row, weight, d in rows:
            a[row, :n] += np.multiply.outer(weight, d[1] * s)
            a[row, n:2 * n] += np.multiply.outer(weight, d[0] * q)
            for k in range(drive.n_states):
                a[row, first + k] += weight * d[2 + k]
    return a


def _top_point(model: ReducedOrderModel, steady: SteadyDrilling) -> tuple[TopContext, np.ndarray]:
    """The top boundary's operating point in steady drilling: its context (the quill speed and surface torque of
    the steady state; ``time`` infinite, past any start-up ramp) and its states."""
    n, first = model.size, model.layout.states["top_boundary"]
    y = steady.state
    ctx = TopContext(math.inf, float(model.base_speed + model.quill_shapes @ y[n:2 * n]),
                     float(model.surface_torque_shapes @ y[:n]))
    return ctx, y[first:first + model.top_drive.n_states]


def _motor_point(model: ReducedOrderModel, steady: SteadyDrilling) -> tuple[MotorContext, np.ndarray]:
    """A downhole motor's operating point in steady drilling: its context (its steady speed) and its states."""
    first = model.layout.states["motor"]
    return (MotorContext(math.inf, steady.motor["motor_speed"]),
            steady.state[first:first + model.motor.n_states])


def _context(model: ReducedOrderModel, steady: SteadyDrilling) -> BitContext:
    """The bit law's context in steady drilling (at t = 0, the bit at its static position)."""
    return BitContext(0.0, 0.0, 0.0, steady.rate_of_penetration, steady.bit_speed, steady.depth_of_cut,
                      model.weight_on_bit)


def _family_of(model: ReducedOrderModel) -> np.ndarray:
    return np.array(["lateral" if f.startswith("lateral") else ("axial" if f.endswith("axial") else f)
                     for f in model.family])


def _informative_matrix(model: ReducedOrderModel, steady: SteadyDrilling) -> tuple[np.ndarray, np.ndarray]:
    """The state matrix without the rigid axial position (the depth drilled: no equation depends on it) and,
    with a top drive, the rigid rotation's angle (likewise) and any state of a component that no equation
    depends on (its column of the matrix zero: the integral state of a controller with ``integral_gain = 0``),
    and the mask of the rows kept."""
    keep = np.ones(model.state_size, dtype=bool)
    keep[rigid_axial_column(model)] = False
    if model.rigid_rotation_column is not None:
        keep[model.rigid_rotation_column] = False
    if model.rotor is not None:  # the rigid rotations' angles (the rotor's relative one included): likewise
        torsional = np.array([f == "torsional" for f in model.family])
        keep[:model.size][torsional & (model.omega2 == 0.0)] = False
    matrix = linearized_matrix(model, steady)
    components = np.arange(model.state_size) >= 2 * model.size
    keep[components & ~matrix.any(axis=0)] = False  # a component's state no equation depends on
    return matrix[np.ix_(keep, keep)], keep


def delay_matrices(model: ReducedOrderModel, steady: SteadyDrilling) -> tuple[np.ndarray, np.ndarray]:
    """``A0``, ``A1`` of eq. (3) for a delayed law, on the whole state ``[δη, δη̇, δs]`` (rigid positions
    included), with the delay ``steady.delay``."""
    n = model.size
    a0 = linearized_matrix(model, steady)
    f_d, t_d = model.bit_rock.depth_partials(_context(model, steady))
    coupling = regenerative_coupling(model.bit_u, model.bit_t, f_d=f_d, t_d=t_d,
                                     rate_of_penetration=steady.rate_of_penetration, bit_speed=steady.bit_speed)
    a1 = np.zeros_like(a0)
    a0[n:2 * n, :n] += coupling
    a1[n:2 * n, :n] = -coupling
    return a0, a1


def delay_roots(model: ReducedOrderModel, steady: SteadyDrilling | None = None, **options) -> DelayRoots:
    """The characteristic roots of eq. (3) about steady drilling (:func:`~drillstring.dynamics.delay_stability.
    characteristic_roots`, ``options`` passed on) for a model with a delayed bit–rock law."""
    steady = steady_drilling(model) if steady is None else steady
    a0, a1 = delay_matrices(model, steady)
    return characteristic_roots(a0, a1, steady.delay, **options)


def delay_roots_summary(roots: DelayRoots) -> dict:
    """JSON-ready facts of a delay system's roots: the delay [s], the Chebyshev degree used and the leading
    root's relative change at the last doubling of it, whether every root of the right half-plane is within
    the range the degree resolves (``resolved``; ``radius`` [1/s] bounds their moduli), the neutral roots
    [1/s] (invariances) and how many starting values did not converge."""
    return {"delay": roots.tau, "chebyshev_degree": int(roots.M), "leading_change": roots.leading_change,
            "resolved": bool(roots.resolved), "radius": float(roots.radius),
            "neutral_roots": [float(v) for v in roots.neutral], "unconverged": int(len(roots.unconverged))}


def leading_growth_rate(model: ReducedOrderModel, larger: ReducedOrderModel | None = None) -> float:
    """The largest real part [1/s] of the eigenvalues of ``model`` linearised about steady drilling (> 0:
    steady drilling is unstable): :func:`stability`'s ``leading.growth_rate`` from the eigenvalues alone
    (no eigenvectors, no families), for a study's every realization; for a delayed law the leading
    characteristic root's (:func:`delay_roots`). With ``larger`` (:func:`larger_basis`) or attachment modes, that
    of :func:`stability` (the roots beyond the basis left out). ValueError when there is no steady drilling."""
    if larger is not None or model.residual_columns.any():  # roots beyond the basis: told apart by stability
        return float(stability(model, larger).leading.growth_rate)
    steady = steady_drilling(model)
    if model.bit_rock.delayed:
        return float(delay_roots(model, steady).growth_rate)
    matrix, _ = _informative_matrix(model, steady)
    return float(np.max(sla.eigvals(matrix).real))


def family_growth_rates(model: ReducedOrderModel) -> dict[str, float]:
    """The leading growth rate [1/s] of every root (``growth_rate``, as :func:`leading_growth_rate`) and of each
    family's roots (``{family}_growth_rate`` for :data:`STABILITY_FAMILIES`; NaN for a family without roots),
    from :func:`stability` (eigenvectors needed to tell the families apart). ValueError when there is no
    steady drilling."""
    found = stability(model)
    out = {"growth_rate": found.leading.growth_rate}
    for family, root in found.leading_by_family.items():
        out[f"{family}_growth_rate"] = math.nan if root is None else root.growth_rate
    return out


def energy_shares(model: ReducedOrderModel, values: np.ndarray, full: np.ndarray):
    """The roots ``values`` [1/s] with Im ≥ 0, each one's modal energy ``½ Σ (|δη̇_j|² + |ω_j²| |δη_j|²)``
    (its state vector a column of ``full``) per family of :data:`STABILITY_FAMILIES` and in the attachment modes."""
    n = model.size
    upper = values.imag >= 0.0
    vectors = full[:, upper]
    energy = np.abs(vectors[n:2 * n]) ** 2 + np.abs(model.omega2)[:, None] * np.abs(vectors[:n]) ** 2
    masks = [_family_of(model) == f for f in STABILITY_FAMILIES] + [model.residual_columns]
    sums = np.array([[energy[mask, k].sum() for mask in masks] for k in range(energy.shape[1])])
    sums = sums.reshape(-1, len(masks))  # each root's 1-D sums (summed across roots, the last bits would differ)
    return values[upper], sums[:, :-1], sums[:, -1]


def stability(model: ReducedOrderModel, larger: ReducedOrderModel | None = None) -> StabilityResult:
    """Steady drilling of ``model`` and the eigenvalues of the model linearised about it (for a delayed law
    the characteristic roots of eq. (3) and, for each, the null vector of ``sI − A0 − A1 e^{−sτ0}``); with
    ``larger`` (the same model on a larger basis, :func:`larger_basis`) each root that matters checked for
    convergence (:func:`check_convergence`)."""
    steady = steady_drilling(model)
    delay = None
    if model.bit_rock.delayed:
        a0, a1 = delay_matrices(model, steady)
        roots = characteristic_roots(a0, a1, steady.delay)
        values = roots.roots
        full = np.zeros((model.state_size, len(values)), dtype=complex)
        identity = np.eye(model.state_size)
        for k, s in enumerate(values):  # the mode shape: the null vector of the characteristic matrix
            full[:, k] = np.linalg.svd(s * identity - a0 - a1 * np.exp(-s * steady.delay))[2][-1].conj()
        delay = delay_roots_summary(roots)
    else:
        matrix, keep = _informative_matrix(model, steady)
        values, vectors = sla.eig(matrix)
        full = np.zeros((model.state_size, len(values)), dtype=complex)
        full[keep] = vectors
    modes = []
    for lam, shares, residual in zip(*energy_shares(model, values, full)):
        family = STABILITY_FAMILIES[int(np.argmax(shares))]
        total = float(shares.sum())
        magnitude = abs(lam)
        modes.append(ModeStability(
            family=family, frequency=float(lam.imag / (2.0 * math.pi)),
            damping_ratio=float(-lam.real / magnitude) if magnitude > 0 else 0.0,
            growth_rate=float(lam.real),
            shares={f: float(v / total) if total > 0 else math.nan for f, v in zip(STABILITY_FAMILIES, shares)},
            residual_share=float(residual) / total if total > 0 else 0.0,
        ))
    modes.sort(key=lambda m: (m.frequency, m.growth_rate))
    convergence = None
    if larger is not None:
        modes, convergence = check_convergence(modes, larger)
    return StabilityResult(steady, modes, model.top_drive.describe() if model.top_drive.drives else None, delay,
                           convergence)


def _root_distance_ok(root: complex, partner: complex) -> bool:
    """``|s' − s| ≤ CONVERGENCE_GROWTH |Re s| + CONVERGENCE_DAMPING |s|`` (:data:`CONVERGENCE_GROWTH`)."""
    return bool(abs(partner - root) <= CONVERGENCE_GROWTH * abs(root.real) + CONVERGENCE_DAMPING * abs(root))


def _partners(larger: ReducedOrderModel, roots: np.ndarray, steady: SteadyDrilling, eigenvalues) -> np.ndarray:
    """The root of ``larger`` that each of ``roots`` [1/s] persists as (NaN where none): for a delayed law
    Newton's method on the larger basis's ``det Δ`` from the root itself (:data:`CONVERGENCE_NEWTON_STEPS`
    steps, relative residual ≤ 1e-10); otherwise the nearest of the larger basis's ``eigenvalues``."""
    if not larger.bit_rock.delayed:
        return np.array([eigenvalues[np.argmin(np.abs(eigenvalues - r))] for r in roots], dtype=complex)
    a0, a1 = delay_matrices(larger, steady)
    found = _newton(a0, a1, steady.delay, roots, maxiter=CONVERGENCE_NEWTON_STEPS)
    found[~(_residuals(a0, a1, steady.delay, found) <= 1e-10)] = complex(math.nan, math.nan)
    return found


def check_convergence(modes: list[ModeStability], larger: ReducedOrderModel) -> tuple[list[ModeStability], dict]:
    """Whether the roots ``modes`` of a basis persist on ``larger``, the same model with twice the modes of every
    family (:func:`larger_basis`): a root ``s`` is converged when ``larger`` has a root ``s'`` with
    ``|s' − s| ≤ CONVERGENCE_GROWTH |Re s| + CONVERGENCE_DAMPING |s|`` (:data:`CONVERGENCE_GROWTH`), the root
    ``s'`` that Newton's method on the larger basis's ``det Δ`` reaches from ``s`` (a delayed law) or the nearest
    eigenvalue of the larger basis. A root of the basis's cut-off moves with the cut-off (to the larger basis's
    highest frequencies) or changes its growth rate: it is not converged, :attr:`ModeStability.beyond_basis`.

    Without a delay every root is checked (the larger basis's eigenvalues cost one dense eigenproblem). With a
    delay the roots are checked in decreasing growth rate, :data:`CONVERGENCE_BATCH` at a time, until every
    root that grows and, in each family, the root of largest growth rate that converges are checked; the roots
    below are left unchecked (``converged`` None): they decide neither :attr:`StabilityResult.leading`,
    :attr:`StabilityResult.stable` nor the per-family results. Returns the modes with ``converged`` and
    ``basis_change`` set, and the check's facts (JSON-ready): the larger basis's modes per family, the
    tolerances, how many roots were checked and how many did not converge."""
    steady = steady_drilling(larger)
    eigenvalues = None
    if not larger.bit_rock.delayed:
        eigenvalues = sla.eigvals(_informative_matrix(larger, steady)[0])
    order = sorted(range(len(modes)), key=lambda k: -modes[k].growth_rate)
    out = list(modes)
    families = {m.family for m in modes}
    settled: set[str] = set()
    checked = 0
    while checked < len(order):
        batch = order[checked:] if eigenvalues is not None else order[checked:checked + CONVERGENCE_BATCH]
        roots = np.array([modes[k].eigenvalue for k in batch])
        for k, root, partner in zip(batch, roots, _partners(larger, roots, steady, eigenvalues)):
            ok = bool(np.isfinite(partner) and _root_distance_ok(root, partner))
            out[k] = replace(modes[k], converged=ok,
                             basis_change=float(abs(partner - root)) if np.isfinite(partner) else None)
            if ok:
                settled.add(modes[k].family)
        checked += len(batch)
        rest = order[checked:]
        if settled >= families and (not rest or modes[rest[0]].growth_rate < 0.0):
            break
    facts = {"larger_basis": {"axial": int(sum(f == "axial" for f in larger.family)),
                              "torsional": int(sum(f == "torsional" for f in larger.family)),
                              "lateral": int(sum(f.startswith("lateral") for f in larger.family))},
             "growth_tolerance": CONVERGENCE_GROWTH, "damping_tolerance": CONVERGENCE_DAMPING,
             "checked": checked, "unconverged": int(sum(m.converged is False for m in out))}
    return out, facts


def larger_basis(case, model: ReducedOrderModel) -> ReducedOrderModel | None:
    """``case``'s reduced model on twice the modes of every family of its ``reduced_model`` (the lateral cut-off
    kept), on ``model``'s static state; None when the mesh has too few modes for it."""
    from drillstring.dynamics.rom import case_reduced_model

    r = case.reduced_model
    try:
        return case_reduced_model(case, static=model.static, axial_modes=2 * r.axial_modes,
                                  torsional_modes=2 * r.torsional_modes, lateral_modes=2 * r.lateral_modes,
                                  lateral_cutoff=r.lateral_cutoff)
    except ValueError:
        return None


def case_stability(case, *, weight_on_bit: float | None = None, check: bool = True) -> StabilityResult:
    """:func:`stability` of a :class:`~drillstring.case.Case`'s reduced model (``weight_on_bit`` [N]
    overrides the case's), with the convergence check on twice the basis (:func:`check_convergence`) unless
    ``check`` is False."""
    from drillstring.dynamics.rom import case_reduced_model

    model = case_reduced_model(case, weight_on_bit=weight_on_bit)
    return stability(model, larger_basis(case, model) if check else None)


#: Relative step of the bracket search of :func:`growth_rate_root` (multiplied by 1.5 at each step).
BOUNDARY_FIRST_STEP = 0.02
#: Tolerance of the boundary [N].
BOUNDARY_TOLERANCE = 1.0


def growth_rate_root(growth, start: float, lower: float, upper: float, *, first_step: float = BOUNDARY_FIRST_STEP,
                     xtol: float = BOUNDARY_TOLERANCE) -> float | None:
    """The root nearest ``start`` of a growth rate ``growth(x)`` [1/s] along one parameter x, searched over
    the whole range ``(lower, upper)``: brackets grow from ``start`` outward on both sides in turn
    (steps ``first_step·start``, × 1.5 each), the side where the sign should change first — downwards when
    ``growth(start) > 0`` (the growth rate of steady drilling rises with the weight-on-bit) —, then the
    root is found by Brent's method to ``xtol``. ``growth`` may raise ValueError (no steady state there):
    past a step that lands there, the edge of the defined range is found by bisection (within
    1e-4·``start``), every defined piece checked for a sign change, and the search ends on that side. None when no sign change is found on either side."""
    from scipy.optimize import brentq

    def safe(x: float) -> float | None:
        try:
            value = float(growth(x))
        except ValueError:
            return None
        return value if math.isfinite(value) else None

    g0 = safe(start)
    if g0 is None:
        return None
    if g0 == 0.0:
        return float(start)
    expected = -1.0 if g0 > 0.0 else 1.0
    edge_tolerance = max(xtol, 1e-4 * abs(start))  # how close to the edge of the defined range a side ends
    # per side: [last defined x, its growth rate, next step, still searching]
    sides = {d: [float(start), g0, first_step * abs(start), True] for d in (expected, -expected)}
    while any(side[3] for side in sides.values()):
        for direction, side in sides.items():
            near, g_near, step, searching = side
            if not searching:
                continue
            far = near + direction * step
            if not lower < far < upper:
                far = lower if direction < 0 else upper
            g_far = safe(far)
            if g_far is None:  # past the edge of the defined range: bisect towards it, checking each piece
                while abs(far - near) > edge_tolerance:
                    middle = 0.5 * (near + far)
                    g_middle = safe(middle)
                    if g_middle is None:
                        far = middle
                        continue
                    if g_middle == 0.0 or (g_middle > 0.0) != (g_near > 0.0):
                        far, g_far = middle, g_middle
                        break
                    near, g_near = middle, g_middle
                if g_far is None:
                    side[3] = False  # the edge is reached without a sign change
                    continue
            if g_far == 0.0:
                return float(far)
            if (g_far > 0.0) != (g_near > 0.0):
                return float(brentq(lambda x: growth(x), min(near, far), max(near, far), xtol=xtol))
            side[:] = [far, g_far, step * 1.5, far not in (lower, upper)]
    return None


def weight_on_bit_boundary(case) -> dict:
    """The stability boundary of steady drilling of ``case`` along the weight-on-bit at its top speed (SI):
    ``weight_on_bit`` [N] where the leading growth rate of :func:`case_stability` crosses 0 nearest the
    case's weight-on-bit (:func:`growth_rate_root`, searched on both sides over (0, string weight), to the
    edge of steady drilling; each leading root checked for convergence on twice the basis), None when it does
    not in that range; ``top_speed`` [rad/s]; the case's ``nominal_weight_on_bit`` [N] and its
    ``nominal_growth_rate`` [1/s]. Above the boundary steady drilling is unstable (a Hopf bifurcation: the
    torsional mode's damping turns negative through the velocity-weakening bit torque)."""
    from functools import lru_cache

    from drillstring.dynamics.rom import case_reduced_model

    @lru_cache(maxsize=None)
    def growth(weight_on_bit: float) -> float:  # the leading root that persists on twice the basis
        model = case_reduced_model(case, weight_on_bit=weight_on_bit)
        return leading_growth_rate(model, larger_basis(case, model))

    wob = float(case.operation.weight_on_bit)
    nominal = growth(wob)
    root = growth_rate_root(growth, wob, 1e-3 * case.weight, case.weight)
    return {"weight_on_bit": root, "top_speed": float(case.operation.top_speed),
            "nominal_weight_on_bit": float(wob), "nominal_growth_rate": float(nominal)}
