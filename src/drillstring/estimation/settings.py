"""The ensemble estimator's settings (:class:`EstimatorSettings`, named as the ``[estimator]`` table's case keys,
:mod:`drillstring.case.estimator_table`) and :func:`case_estimator_settings`, a case's settings over the defaults;
the filter that reads them is :mod:`drillstring.estimation.ensemble` (issue 36)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from drillstring.checks import integer, real_number
from drillstring.checks import seed as checked_seed

#: ``friction_factor`` -> the well's key of that wall's friction factor (None: no friction factor estimated).
FRICTION_WALLS = {"open": "open_hole_friction", "cased": "cased_hole_friction", "none": None}
#: ``stiffness_factor`` -> the estimated factor's name (None: no stiffness factor estimated).
STIFFNESS_FAMILIES = {"torsional": "torsional_stiffness", "none": None}


@dataclass(frozen=True)
class EstimatorSettings:
    """The estimator's settings, named as the case keys they become (SI units).

    Attributes:
        ensemble_size: members N, in [4, 1000]. Default 256: with fewer the analyses narrow the parameters'
            bands beyond what the record holds (on perfect-model twins 256 held the coefficient's truth 5 times of
            6 against 1 of 6 with 64, the torque on bit .84 against .68; docs/estimation.md "The filter's own
            share"); 2.3-3.1 times faster than real time for a 1 Hz record on one core (four times 64's cost).
        top_speed_noise: standard deviation of the top-speed measurement [rad/s], > 0.
        surface_torque_noise: of the surface torque [N·m], > 0.
        block_position_noise: of the block position [m], > 0.
        hook_load_window: the hook load's averaging window [s], > 0.
        inflation: multiplicative prior inflation of the anomalies [-], in [1, 2]; it widens the parameters at
            every analysis, and where the record does not narrow them as fast the run stops
            (:class:`~drillstring.estimation.ensemble.EstimateDiverged`; 1.1 did on a 300 s twin).
        model_speed_noise: additive model error: the torsional modal velocities of each member are perturbed before
            each forecast, white over the lowest ``model_noise_modes`` torsional columns, scaled so that the bit
            speed's perturbation has this standard deviation per √s of the interval [rad/s/√s], >= 0. Default 1.5:
            large kicks bias the estimated coefficient (on a twin whose truth is the case's full basis on its
            nominal matrices, ``a5`` ended 13-17 % high on 3 of 4 runs at 3, within 2 % on all 4 at 1 or 0.3),
            small ones leave the bands too narrow against another model; with 256 members 1.5 holds seven twins'
            truths (random-matrix models) .90 (bit speed) and .91 (torque on bit) of the time pooled over three
            seeds, 13 of 21 runs with both in 85-95 % (docs/estimation.md "The defaults"; 64 members at 2 before:
            1 of 12).
        model_noise_modes: the torsional columns so perturbed, the lowest (with a top drive the first is the rigid
            rotation; at most the basis's), in [1, 40]. Default all: on the stick-slip twin, noise in the lowest two
            alone gave bands covering the truth 0.6-0.7 of the time against 0.86-1.0 (the truncated higher modes are
            part of the model's error), but the ringing of the higher modes biases the stick-slip index up ~2-10 %.
        model_noise_stick_speed: below this bit speed [rad/s] a member's kick is scaled down in proportion
            (:func:`~drillstring.estimation.ensemble.kick_scale`: none at a standing bit), >= 0; 0 (the default):
            every kick whole. Kicks while the bit sticks bias the coefficient (docs/estimation.md "Long records: the
            kicks and the coefficient").
        initial_speed_spread: standard deviation of the members' initial string speed [rad/s], >= 0.
        spin_up: the members run this long [s] from the model's initial state, with the model error and without
            observations, before the record's first time, >= 0: a record starts in operation (in stick-slip, the
            string twisted), not in the static state; 0 starts the filter from the initial state (a record that
            starts where its run does). The spin-up puts the ensemble on the model's own cycle with the members'
            phases spread by their parameters and the model error (docs/estimation.md, "The shipped record").
        assimilation_step: the assimilation window [s], > 0: one analysis per window, of the means of its samples
            (module docstring); 1 s: the rate of the twin experiments the noises were set on.
        bit_rock_coefficient: the estimated coefficient of the case's bit–rock law (a field of its parameters), or
            ``"none"``: no bit–rock coefficient estimated (off bottom, where the law has none).
        coefficient_spread: prior standard deviation of its logarithm [-], in (0, 2].
        coefficient_walk: its random walk, standard deviation of the logarithm's change per √s [1/√s], >= 0.
        friction_factor: the wall whose along-string friction factor μ is estimated: ``"open"`` (the well's
            ``open_hole_friction``, at the stations at and below the casing shoe), ``"cased"``
            (``cased_hole_friction``, above it) or ``"none"`` (none estimated); the case needs a ``[well]`` and a
            ``[string_friction] law`` with stations on that wall.
        friction_spread: prior standard deviation of log μ [-], in (0, 2].
        friction_walk: its random walk [1/√s], >= 0.
        stiffness_factor: ``"torsional"``: a factor κ on the torsional stiffness of the estimator's model is
            estimated (every torsional ω² and the stiffness reaction at the top times κ, the elastic modes' damping
            times √κ, as a shear modulus κ G would give: :func:`~drillstring.estimation.ensemble.member_model`), or
            ``"none"`` (default). The stick-slip cycle's period is the lowest torsional mode's: a model whose
            frequency is off by a few per cent drifts out of phase with the record (docs/estimation.md "The
            torsional stiffness": with κ and ``model_speed_noise = 0.8`` the bit speed's RMSE fell by a third on
            seven twins, their torque on bit's bands over-covering, .94 pooled).
        stiffness_spread: prior standard deviation of log κ [-], in (0, 2]; its prior is centred on 1.
        stiffness_walk: its random walk [1/√s], >= 0.
        model_dispersion: each member's own reduced model, its mass, stiffness and damping matrices drawn once
            from the random-matrix model with this dispersion
            (:func:`~drillstring.estimation.ensemble.member_models`) [-], in [0, 1) and below the family sizes'
            bound sqrt((n+1)/(n+5)); 0 (default): every member runs the estimator's model.
        relaxation: relaxation to the prior spread (RTPS,
            :func:`~drillstring.estimation.analysis.relax_to_prior_spread`) of the model state's rows after each
            analysis [-], in [0, 1]; 0 none.
        parameter_relaxation: the same for the parameters' rows (coefficient, μ, κ, bias, block zero) [-], in [0, 1].
        particle_share: the share ``1 − γ`` of each analysis's likelihood given to a particle filter, the rest to a
            Kalman step (the ensemble Kalman particle filter,
            :func:`~drillstring.estimation.analysis.enkpf_analysis`; members drawn by their weights, each taking
            over its parent's model and recent outputs) [-], in [0, 1); 0 (the default): the ETKF alone
            (:func:`~drillstring.estimation.analysis.etkf_analysis`), deterministic.
        particle_effective_size: the least effective sample size of the particle weights, a fraction of the
            members [-], in [0, 1): where ``particle_share`` would leave fewer, that analysis uses the largest share
            that leaves this many (0: the share always as given).
        weight_on_bit_bias_spread: prior standard deviation of the weight-on-bit bias [N], > 0.
        weight_on_bit_bias_walk: its random walk [N/√s], >= 0.
        stick_slip_window: the window of the stick-slip index [s], > 0.
        output_step: the forecasts' sampling of the bit speed for that index [s], > 0.
        axial_modes, torsional_modes: the estimator's basis (elastic modes; no lateral ones), in [1, 40].
        rtol: the integrator's relative tolerance [-], in (0, 1e-2]; atol its absolute one (state units), > 0.
        divergence_speed_ratio: a member whose bit speed exceeds this times the top speed has diverged [-], > 1.
        seed: the random stream's seed (initial ensemble, random walks).
    """

    ensemble_size: int = 256
    top_speed_noise: float = 0.05
    surface_torque_noise: float = 300.0
    block_position_noise: float = 0.005
    hook_load_window: float = 10.0
    inflation: float = 1.0
    model_speed_noise: float = 1.5
    model_noise_modes: int = 40
    model_noise_stick_speed: float = 0.0
    initial_speed_spread: float = 0.5
    spin_up: float = 20.0
    assimilation_step: float = 1.0
    bit_rock_coefficient: str = "a5"
    coefficient_spread: float = 0.3
    coefficient_walk: float = 0.003
    friction_factor: str = "none"
    friction_spread: float = 0.3
    friction_walk: float = 0.003
    stiffness_factor: str = "none"
    stiffness_spread: float = 0.05
    stiffness_walk: float = 0.001
    model_dispersion: float = 0.0
    relaxation: float = 0.0
    parameter_relaxation: float = 0.0
    particle_share: float = 0.0
    particle_effective_size: float = 0.0
    weight_on_bit_bias_spread: float = 20e3
    weight_on_bit_bias_walk: float = 100.0
    stick_slip_window: float = 20.0
    output_step: float = 0.1
    axial_modes: int = 3
    torsional_modes: int = 5
    rtol: float = 1e-4
    atol: float = 1e-6
    divergence_speed_ratio: float = 10.0
    seed: int = 0

    def __post_init__(self) -> None:
        integer("ensemble_size", self.ensemble_size, low=4, high=1000)
        for name in ("top_speed_noise", "surface_torque_noise", "block_position_noise", "hook_load_window",
                     "weight_on_bit_bias_spread", "stick_slip_window", "output_step", "atol",
                     "assimilation_step"):
            real_number(name, getattr(self, name), low=0.0, low_open=True)
        for name in ("initial_speed_spread", "coefficient_walk", "weight_on_bit_bias_walk", "model_speed_noise",
                     "spin_up", "friction_walk", "model_noise_stick_speed", "stiffness_walk"):
            real_number(name, getattr(self, name), low=0.0)
        real_number("inflation", self.inflation, low=1.0, high=2.0)
        real_number("coefficient_spread", self.coefficient_spread, low=0.0, high=2.0, low_open=True)
        real_number("friction_spread", self.friction_spread, low=0.0, high=2.0, low_open=True)
        real_number("stiffness_spread", self.stiffness_spread, low=0.0, high=2.0, low_open=True)
        real_number("relaxation", self.relaxation, low=0.0, high=1.0)
        real_number("model_dispersion", self.model_dispersion, low=0.0, high=1.0, high_open=True)
        real_number("parameter_relaxation", self.parameter_relaxation, low=0.0, high=1.0)
        real_number("particle_share", self.particle_share, low=0.0, high=1.0, high_open=True)
        real_number("particle_effective_size", self.particle_effective_size, low=0.0, high=1.0, high_open=True)
        real_number("rtol", self.rtol, low=0.0, high=1e-2, low_open=True)
        real_number("divergence_speed_ratio", self.divergence_speed_ratio, low=1.0, low_open=True)
        integer("axial_modes", self.axial_modes, low=1, high=40)
        integer("torsional_modes", self.torsional_modes, low=1, high=40)
        integer("model_noise_modes", self.model_noise_modes, low=1, high=40)
        checked_seed(self.seed)
        if not isinstance(self.bit_rock_coefficient, str) or not self.bit_rock_coefficient:
            raise ValueError(f"bit_rock_coefficient = {self.bit_rock_coefficient!r}: must be the name of a "
                             "coefficient of the case's bit-rock law (e.g. 'a5') or 'none'")
        if self.friction_factor not in FRICTION_WALLS:
            raise ValueError(f"friction_factor = {self.friction_factor!r}: must be one of "
                             f"{', '.join(repr(k) for k in FRICTION_WALLS)}")
        if self.stiffness_factor not in STIFFNESS_FAMILIES:
            raise ValueError(f"stiffness_factor = {self.stiffness_factor!r}: must be one of "
                             f"{', '.join(repr(k) for k in STIFFNESS_FAMILIES)}")

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def case_estimator_settings(case, **overrides) -> EstimatorSettings:
    """The estimator's settings of ``case``: its ``[estimator]`` table's keys (:mod:`drillstring.case.
    estimator_table`, SI) over the defaults, then ``overrides`` (the same names). A bad value raises a ValueError
    naming ``estimator.<key>`` (its range from :class:`EstimatorSettings`); an unknown override, a TypeError."""
    given = {} if getattr(case, "estimator", None) is None else case.estimator.given()
    unknown = sorted(set(overrides) - {f.name for f in dataclasses.fields(EstimatorSettings)})
    if unknown:
        raise TypeError(f"unknown estimator setting(s): {', '.join(unknown)}")
    given.update(overrides)
    try:
        return EstimatorSettings(**given)
    except ValueError as error:
        raise ValueError(f"estimator.{error}") from None
