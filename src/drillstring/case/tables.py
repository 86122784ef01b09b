"""The tables of a case that describe the string, the hole and the fluid, the laws and the operating point,
and the model, mesh, reduced model, time integration, initial state and uncertainty settings: one pydantic
model per TOML table, every value in SI units.
"""

from __future__ import annotations

import math
from typing import Any, Literal, Mapping

from pydantic import ConfigDict, Field, model_validator

from drillstring.case.base import (
    Acceleration,
    Angle,
    AngularSpeed,
    AxialDamping,
    Density,
    Dimensionless,
    Force,
    ForceAngle,
    Length,
    LengthPerAngle,
    LinearDamping,
    MomentOfInertia,
    PenetrationPerForce,
    Pressure,
    RotationalDamping,
    RotationalStiffness,
    Stiffness,
    StiffnessPerLength,
    Time,
    Torque,
    Velocity,
    _Base,
    _RPM,
)
from drillstring.case.errors import _Problems
from drillstring.constants import STANDARD_GRAVITY


class Material(_Base):
    """Isotropic linear-elastic material."""

    young_modulus: Pressure = Field(gt=0, description="Young's modulus E [Pa]")
    density: Density = Field(gt=0, description="mass density rho [kg/m^3]")
    poisson_ratio: Dimensionless = Field(gt=0, lt=0.5, description="Poisson's ratio nu [-]")
    solid_density: Density | None = Field(
        None, gt=0, description="density of the solid itself when ``density`` smears extra parts (tool joints) "
        "over the section's area [kg/m^3]: the section's steel then occupies, and displaces, mass / solid_density "
        "per length; left out: ``density`` (the section is all solid)")

    @property
    def solid_fraction(self) -> float:
        """Volume of solid per volume of section [-]: ``density / solid_density`` (1 for a plain material; above 1
        when tool joints are smeared: their steel lies outside the pipe body's area)."""
        return 1.0 if self.solid_density is None else self.density / self.solid_density

    @property
    def shear_modulus(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)) [Pa]."""
        return self.young_modulus / (2.0 * (1.0 + self.poisson_ratio))



def _default_materials() -> dict[str, Material]:
    return {"steel": Material(young_modulus=210e9, density=7850.0, poisson_ratio=0.29)}


class ImbalanceKeys(_Base):
    """The case keys of a section's mass imbalance (the turning-load source ``"imbalance"``,
    :class:`~drillstring.forces.turning_loads.MassImbalance`), with their units and bounds."""

    eccentricity: Length = Field(
        0.0, ge=0, description="mass imbalance: offset e of the section's mass centre from its axis [m]; the "
        "centrifugal force rho A e (spin speed)^2 per metre turns with the string (0: none)")
    eccentricity_angle: Angle = Field(
        0.0, description="direction of the offset from y when the section's rotation is 0 [rad]")


class _SectionShape(_Base):
    name: str
    length: Length = Field(gt=0, description="length [m]")
    outer_diameter: Length = Field(gt=0, description="outer diameter D_o [m]")
    inner_diameter: Length = Field(ge=0, description="inner (bore) diameter D_i [m]; 0 for a solid section")
    material: str = Field("steel", description="key into Case.materials")
    shear_factor: Dimensionless = Field(6.0 / 7.0, gt=0, le=1, description="Timoshenko shear factor k_s [-]")


class Section(ImbalanceKeys, _SectionShape):
    """A hollow circular section of the string (drill pipe, drill collar, ...), listed from top to bit; its
    imbalance keys are :class:`ImbalanceKeys`."""

    @model_validator(mode="after")
    def _inner_less_than_outer(self) -> Section:
        if self.inner_diameter >= self.outer_diameter:
            raise _Problems(
                [
                    (
                        ("inner_diameter",),
                        self.inner_diameter,
                        f"must be less than outer_diameter ({self.outer_diameter:g} m)",
                    )
                ]
            )
        return self

    @property
    def outer_area(self) -> float:
        """pi D_o^2 / 4 [m^2]."""
        return math.pi * self.outer_diameter**2 / 4.0

    @property
    def inner_area(self) -> float:
        """pi D_i^2 / 4 [m^2] (the bore, where the mud flows down)."""
        return math.pi * self.inner_diameter**2 / 4.0

    @property
    def area(self) -> float:
        """Steel cross-section pi (D_o^2 - D_i^2) / 4 [m^2]."""
        return self.outer_area - self.inner_area


class Bow(_Base):
    """A stress-free bow of the string (a bent collar) turning with it: the unloaded shape is offset by
    ``amplitude sin²(π (x − start)/(end − start))`` between ``start`` and ``end`` (0 elsewhere; no kink), in
    the direction ``angle`` from y when the section's rotation is 0. ``amplitude = 0``: no bow."""

    amplitude: Length = Field(0.0, ge=0, description="largest offset of the unloaded shape [m]; 0: no bow")
    start: Length = Field(0.0, ge=0, description="upper end of the bow, from the top [m]")
    end: Length = Field(0.0, ge=0, description="lower end of the bow, from the top [m]; > start")
    angle: Angle = Field(0.0, description="direction of the bow from y at zero rotation [rad]")


class Borehole(_Base):
    """The (rigid, straight, vertical) borehole."""

    diameter: Length = Field(gt=0, description="borehole diameter D_ch [m]")


class Stabilizer(_Base):
    """A stabilizer: linear lateral springs on v and w at one point of the string."""

    position: Length = Field(description="x of the stabilizer, measured down from the top [m]; in (0, L]")
    stiffness: Stiffness = Field(gt=0, description="lateral stiffness k_stab [N/m]")


class Fluid(_Base):
    """Drilling fluid (mud): flows down the bore at ``inlet_velocity`` and up the annulus."""

    density: Density = Field(1200.0, ge=0, description="mud density rho_f [kg/m^3]")
    inlet_velocity: Velocity = Field(1.5, ge=0, description="flow speed U_i inside the string [m/s]")
    friction_coefficient: Dimensionless = Field(0.0125, ge=0, description="fluid friction coefficient C_f [-]")
    viscous_coefficient: LinearDamping = Field(0.0, ge=0, description="viscous damping k [N*s/m^2]")
    added_mass: bool = True
    coriolis: bool = True
    centrifugal: bool = True
    viscous_damping: bool = True
    axial_loads: bool = False


class TuckerWangKeys(_Base):
    """The case keys of the Tucker–Wang bit–rock law (``bit_rock.law = "tucker_wang"``,
    :mod:`drillstring.forces.bit_rock`), with their units and bounds."""

    a1: Velocity = Field(3.429e-3, ge=0, description="a1 [m/s]")
    a2: PenetrationPerForce = Field(5.672e-8, gt=0, description="a2 [m/(N*s)]")
    a3: LengthPerAngle = Field(1.374e-4, ge=0, description="a3 [m/rad]")
    a4: ForceAngle = Field(9.537e6, ge=0, description="a4 [N*rad]")
    a5: Torque = Field(1.475e3, ge=0, description="a5 [N*m]")
    regularization: AngularSpeed = Field(2.0, gt=0, description="e in Z = w / sqrt(w^2 + e^2) [rad/s]")
    stick_stiffening_limit: Dimensionless = Field(
        100.0, gt=1, description="largest ratio of the axial resistance 1/(a2 Z^2) to its value at the top speed;"
        " 1/Z^2 is frozen below the bit speed where it is reached (integrable stick) [-]"
    )


class DetournayKeys(_Base):
    """The case keys of the Detournay bit–rock law (``bit_rock.law = "detournay"``,
    :mod:`drillstring.forces.detournay`), with their units and bounds."""

    # -- law = "detournay" (Detournay & Defourny 1992; Richard, Germay & Detournay 2007) --------------------
    blades: int = Field(4, ge=1, le=100, description="detournay: number of blades n [-]")
    bit_radius: Length = Field(0.108, gt=0, description="detournay: bit radius a [m]")
    intrinsic_specific_energy: Pressure = Field(
        60e6, gt=0, description="detournay: intrinsic specific energy of the rock eps [Pa]")
    cutting_inclination: Dimensionless = Field(
        0.6, ge=0, description="detournay: inclination zeta of the cutting force, W_c = zeta T_c 2/a [-]")
    contact_stress: Pressure = Field(
        60e6, ge=0, description="detournay: contact stress sigma under the wear flats [Pa]")
    wear_flat_length: Length = Field(0.011, ge=0, description="detournay: wear-flat length l, W_f = a sigma l [m]")
    friction_coefficient: Dimensionless = Field(
        0.6, ge=0, description="detournay: friction coefficient mu of the wear flats on the rock [-]")
    bit_geometry: Dimensionless = Field(
        1.0, ge=0, description="detournay: bit geometry factor gamma, T_f = mu gamma a W_f / 2 [-]")
    contact_velocity: Velocity = Field(
        2.5e-4, gt=0, description="detournay: v_r, the wear-flat force ramps from 0 to a sigma l as the bit's "
        "axial velocity goes from 0 to v_r (a bit at rest creeps down at most v_r) [m/s]")
    friction_speed: AngularSpeed = Field(
        5e-3, gt=0, description="detournay: omega_r, the torque ramps from 0 to its full value as the bit "
        "speed goes from 0 to omega_r (a stuck bit turns at most omega_r) [rad/s]")


class _ComponentTables(_Base):
    """A kind's case table (``[bit_rock]``, ``[top_drive]``, ``[contact]``, ``[motor]``): besides its own keys,
    one sub-table per component, ``[bit_rock.<name>]``, holding that component's keys; the component reads and
    validates it itself (its ``keys`` model, :func:`drillstring.forces.registry.case_keys`), so a component
    added to the package or registered by a script needs no edit here, and two components may use the same
    key name."""

    model_config = ConfigDict(frozen=True, extra="allow")

    @model_validator(mode="after")
    def _tables_only(self) -> Any:
        wrong = [(name, value) for name, value in (self.model_extra or {}).items() if not isinstance(value, Mapping)]
        if wrong:
            name, value = wrong[0]
            raise _Problems([((name,), value, f"unknown key; allowed keys here: {', '.join(type(self).model_fields)}"
                                              f", or a component's table of keys ([...{name}])")])
        return self


class _BitRockLaw(_ComponentTables):
    law: str = Field("tucker_wang", min_length=1, description="bit-rock law: a registered law's name "
                     "(tucker_wang, off_bottom, detournay, or one added to the package or by a script)")


class BitRock(DetournayKeys, TuckerWangKeys, _BitRockLaw):
    """Bit-rock interaction law (docs/model.md, §5 and "Bit–rock law: Detournay"):

    - ``law = "tucker_wang"`` (the default): Tucker & Wang's law, coefficients ``a1`` .. ``a5`` and the
      regularisation ``e`` (``regularization``, ``stick_stiffening_limit``);
    - ``"off_bottom"``: the bit hangs free: no bit-rock force, weight-on-bit 0, the hook carries the whole
      string (``operation.weight_on_bit`` is then not used);
    - ``"detournay"``: the Detournay law of drag (PDC) bits, cutting plus wear-flat friction with the depth of
      cut set by the bit's own motion one blade passage earlier (:mod:`drillstring.forces.detournay`):
      ``blades`` n, ``bit_radius`` a, ``intrinsic_specific_energy`` ε, ``cutting_inclination`` ζ,
      ``contact_stress`` σ, ``wear_flat_length`` l, ``friction_coefficient`` μ, ``bit_geometry`` γ
      (``W = a ζ ε n d_n + a σ l``, ``T = ½ a² ε n d_n + ½ μ γ a · a σ l``), and the regularisations of its
      set-valued parts, ``contact_velocity`` v_r and ``friction_speed`` ω_r.

    Each law reads its own keys only; the others keep their defaults and are not used.
    A law's keys are its own model (:class:`TuckerWangKeys`, :class:`DetournayKeys`; the law declares it as
    its ``keys``, :mod:`drillstring.forces.registry`); the built-in laws' keys are written in this table itself,
    as case files always have; any other law's in its own sub-table, ``[bit_rock.<law>]``."""


class Contact(_ComponentTables):
    """String-borehole shocks and rubbing. The wall is a distributed stiffness: a length ℓ of string pressed
    δ into it is pushed back by ``shock_stiffness`` ℓ δ, whatever the mesh. ``law``: the registered contact law
    (``"penalty"``, whose keys are this table's; another law's keys in ``[contact.<law>]``)."""

    law: str = Field("penalty", min_length=1, description="contact law: a registered law's name")
    shock_stiffness: StiffnessPerLength = Field(
        1e8, ge=0, description="k_sh, per metre of string [N/m per m]")
    friction_coefficient: Dimensionless = Field(0.0005, ge=0, description="mu_sh [-]")
    tangential_friction: bool = False
    speed_regularization: AngularSpeed = Field(
        0.1, gt=0, description="regularises sign() of the spin speed in the friction torque [rad/s]"
    )


class Operation(_Base):
    """Operating point: what the driller controls."""

    top_speed: AngularSpeed = Field(
        100.0 * _RPM, gt=0, description="rotation speed imposed at the top [rad/s]"
    )
    weight_on_bit: Force = Field(1e5, gt=0, description="initial (static) weight-on-bit [N]")


class TopDrive(_ComponentTables):
    """The top boundary of the torsion (:mod:`drillstring.forces.top_drive`). ``controller =
    "imposed_speed"``: the top turns at ``operation.top_speed`` exactly (the reference study); ``"pi"``,
    ``"soft_torque"``, ``"z_torque"``: a top drive of rotary inertia ``inertia`` at the quill, driven by a
    motor whose torque, saturated at ``max_torque``, a controller sets from the quill speed (and the
    surface torque for ``z_torque``), with ``operation.top_speed`` as set point, reached after
    ``ramp_time`` from rest when that is > 0. ``pi`` needs both gains; the tuned controllers compute the
    gains left out (docs/model.md, "Top drive"). ``boundary``: the registered top boundary (``"top_drive"``,
    whose keys are this table's; another boundary drives the string, its keys in ``[top_drive.<boundary>]``)."""

    boundary: str = Field("top_drive", min_length=1, description="top boundary: a registered boundary's name")
    controller: Literal["imposed_speed", "pi", "soft_torque", "z_torque"] = Field(
        "imposed_speed", description="top boundary of the torsion")
    inertia: MomentOfInertia = Field(
        1000.0, gt=0, description="rotary inertia of motor, gearbox and quill at the quill J_td [kg*m^2]")
    proportional_gain: RotationalDamping | None = Field(
        None, ge=0, description="k_p of the speed controller [N*m*s/rad]; tuned when left out")
    integral_gain: RotationalStiffness | None = Field(
        None, ge=0, description="k_i of the speed controller [N*m/rad]; tuned when left out")
    max_torque: Torque = Field(60e3, gt=0, description="largest motor torque tau_max [N*m]")
    ramp_time: Time = Field(0.0, ge=0, description="set point ramped from 0 over this time [s]; 0: none")
    filter_frequency: AngularSpeed | None = Field(
        None, gt=0, description="z_torque: corner of the high-pass filter on the surface torque [rad/s];"
        " tuned when left out")

    @model_validator(mode="after")
    def _gains_given(self) -> TopDrive:
        if self.controller == "pi":
            missing = [k for k in ("proportional_gain", "integral_gain") if getattr(self, k) is None]
            if missing:
                raise _Problems([((missing[0],), None, 'must be given for controller = "pi" (in N*m*s/rad'
                                  ' and N*m/rad; "soft_torque" and "z_torque" tune their gains)')])
        return self


class Damping(_Base):
    """Structural damping: modal ratio on elastic modes, viscous coefficients on the rigid-body motions.

    ``basis = "free_free"``: xi, c1 and c2 are defined on the modes of the unconstrained string (axial and
    torsional families; the rigid modes get c1 and c2), then projected on the reduced basis;
    ``"constrained"``: xi on every mode of the reduced basis (torsional modes top-held), c2 unused.
    ``mass_proportional`` α [1/s] and ``stiffness_proportional`` β [s] add Rayleigh damping ``α M + β K`` of
    the string (``α`` alone: the distributed viscous damping ``k ρA u̇``, ``k ρJ θ̇`` of Aarsnes & van de Wouw's
    model, with ``k = α``), on top of the above. See :mod:`drillstring.damping`.
    """

    modal_damping_ratio: Dimensionless = Field(0.3, ge=0, lt=1, description="xi [-]")
    rigid_axial: AxialDamping = Field(0.05, ge=0, description="c1, rigid axial motion [N*s/m]")
    rigid_rotation: RotationalDamping = Field(0.05, ge=0, description="c2, rigid rotation [N*m*s/rad]")
    basis: Literal["free_free", "constrained"] = Field(
        "free_free", description="modes on which xi, c1, c2 are defined"
    )
    mass_proportional: float = Field(0.0, ge=0, le=1e6, description="Rayleigh alpha [1/s]: C += alpha M")
    stiffness_proportional: Time = Field(0.0, ge=0, le=1e3, description="Rayleigh beta [s]: C += beta K")


class Environment(_Base):
    gravity: Acceleration = Field(
        STANDARD_GRAVITY, ge=0, description="gravitational acceleration g [m/s^2]; standard gravity by default")


class Model(_Base):
    """Model switches."""

    gravity: bool = True
    buoyancy: bool = False
    nonlinear: Literal["bit_and_contact", "full"] = "bit_and_contact"


class Mesh(_Base):
    max_element_length: Length = Field(10.0, gt=0, description="largest finite element [m]")
    probes: list[Length] = Field(
        default_factory=lambda: [1560.0], description="x of the output probes, from the top [m]; in [0, L]"
    )


class ReducedModel(_Base):
    """Normal modes kept per family (lateral: per plane): ``lateral_modes`` at least, and every lateral mode
    whose frequency is below ``lateral_cutoff`` times the rotation frequency (all the family's modes at most);
    ``truncation_correction``: "static" (the default for new cases) appends to the axial and torsional families
    their residual-flexibility attachment modes at the bit (and the top with a top drive, and a downhole motor's
    torque pair: :func:`drillstring.rotor.released_torsional_modes`), "none" keeps the modes alone
    (:func:`drillstring.modal.compute_modes`; docs/model.md §8)."""

    axial_modes: int = Field(10, ge=0)
    torsional_modes: int = Field(10, ge=1, description="elastic torsional modes (a top drive adds the rigid rotation)")
    lateral_modes: int = Field(20, ge=0)
    lateral_cutoff: Dimensionless = Field(
        1.5, ge=0, description="keep every lateral mode below this multiple of the rotation frequency [-]")
    truncation_correction: Literal["none", "static"] = Field(
        "static", description="correction for the modes left out: 'static' appends to the axial and torsional "
        "families their residual-flexibility attachment modes at the bit (and the top with a top drive); "
        "'none', the modes alone")
    lateral_basis: Literal["straight", "well"] = Field(
        "straight", description="'straight': the straight string's modes under the axial force (lateral dynamics "
        "of a vertical hole); 'well': the modes about the stiff string's static state along the well path, chosen "
        "by kind (axial_modes, torsional_modes, 2 x lateral_modes), the spin about each node's tangent "
        "(docs/stiff_string.md, The well basis)")


class Simulation(_Base):
    """Time integration: adaptive Runge-Kutta, explicit or implicit-explicit (``method``)."""

    t_end: Time = Field(30.0, gt=0, description="end time [s]")
    output_step: Time = Field(0.01, gt=0, description="output sampling step [s]; <= t_end")
    rtol: Dimensionless = Field(1e-6, gt=0, lt=1)
    atol: Dimensionless = Field(1e-9, gt=0)
    max_steps: int = Field(2_000_000, gt=0, le=10**12)
    min_step: Time = Field(1e-12, gt=0, description="smallest step before giving up [s]")
    method: Literal["dopri5", "bs32", "ark43", "ark32", "erk32"] = Field(
        "ark43", description="'dopri5' (Dormand-Prince 5(4)) or 'bs32' (Bogacki-Shampine 3(2)), explicit; 'ark43' "
        "(the default for new cases) or 'ark32' (Kennedy-Carpenter ARK4(3)6L, ARK3(2)4L): the linear modal part "
        "and the bit law implicit, so that the attachment modes of the default basis (truncation_correction = "
        "'static') do not set the step (docs/model.md §9); 'erk32' (Hochbruck-Ostermann exponential Runge-Kutta, "
        "stiff order 3): the linear modal part exact, the rest explicit (docs/performance.md)")

    @model_validator(mode="after")
    def _output_step_within_run(self) -> Simulation:
        if self.output_step > self.t_end:
            raise _Problems([(("output_step",), self.output_step, f"must be <= t_end ({self.t_end:g} s)")])
        return self


class RampStartKeys(_Base):
    """The case keys of the ramped start (``initial.start = "ramp"``, the hook load
    :class:`~drillstring.forces.hook_load.HookLoadRamp`), with their units and bounds."""

    clearance: Length = Field(0.005, ge=0, le=1.0, description="ramp: bit height above the rock at t = 0 [m]")
    weight_ramp_time: Time = Field(
        10.0, gt=0, le=1e4, description="ramp: time over which the weight on bit reaches its value [s]")


class _InitialState(_Base):
    lateral_perturbation: Length = Field(1e-4, ge=0, description="amplitude [m]; < smallest radial gap")
    seed: int = Field(0, ge=0, le=2**64 - 1)
    start: Literal["ramp", "on_bottom"] = Field("ramp", description="how the run starts")


class Initial(RampStartKeys, _InitialState):
    """Initial state and start. ``start`` names the hook load (:mod:`drillstring.forces.registry`):
    ``"ramp"`` (the default for new cases): the string turns off bottom,
    the bit ``clearance`` above the rock, the hook carrying the whole string; the hook load is then slacked off
    so that the weight on bit grows linearly from 0 to ``operation.weight_on_bit`` over ``weight_ramp_time``
    (:mod:`drillstring.forces.hook_load`; its keys :class:`RampStartKeys`). ``"on_bottom"`` (the reference
    study's start): the static state spinning at the top speed, the bit-rock law switched on at t = 0. Both add a
    seeded lateral perturbation."""


class CorrelationTable(_Base):
    """Correlation of uncertain normal parameters (the MaxEnt joint law is then the multivariate normal)."""

    parameters: list[str] = Field(min_length=2, description="paths of the correlated parameters")
    matrix: list[list[float]] = Field(description="their correlation matrix, one row per parameter")


class ModelUncertaintyTable(_Base):
    """Nonparametric model uncertainty: the dispersions δ of the random reduced mass, stiffness and damping
    matrices of Soize's SE+ ensemble (:mod:`drillstring.stochastic.random_matrices`), each in [0, 1) and
    below sqrt((n+1)/(n+5)) for every mode family of n modes (checked when a study uses them)."""

    mass_dispersion: float = Field(0.0, ge=0, lt=1, description="δ_M of the random reduced mass matrix [-]")
    stiffness_dispersion: float = Field(0.0, ge=0, lt=1, description="δ_K of the random reduced stiffness matrix [-]")
    damping_dispersion: float = Field(0.0, ge=0, lt=1, description="δ_D of the random reduced damping matrix [-]")


class UncertaintyTable(_Base):
    """Uncertain parameters for studies and sensitivity analyses (``drillstring study``, ``drillstring
    sensitivity``): case-parameter path -> law, as a spec string (``"uniform 1.2 1.8 m/s"``) or a table
    (``{law = "uniform", min = 1.2, max = 1.8, unit = "m/s"}``). The paths and laws are checked against the
    case when a study uses them (:mod:`drillstring.stochastic.uncertainty`); a single run ignores them."""

    parameters: dict[str, str | dict[str, str | float]] = Field(default_factory=dict)
    correlation: CorrelationTable | None = None
    model: ModelUncertaintyTable | None = Field(
        None, description="random reduced mass, stiffness and damping matrices of a study's realizations "
        "(:mod:`drillstring.stochastic.random_matrices`)")

    @model_validator(mode="after")
    def _something(self) -> UncertaintyTable:
        if not self.parameters and self.model is None:
            raise _Problems([(("parameters",), self.parameters, "give at least one uncertain parameter (or a "
                              "[uncertainty.model] table)")])
        return self
