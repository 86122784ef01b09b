"""The ``[estimator]`` table: the settings of the ensemble estimator (``drillstring estimate``,
:mod:`drillstring.estimation.ensemble`) as case keys, with their units. Units are converted here; the ranges are
checked once, where the estimator's settings are built
(:class:`~drillstring.estimation.ensemble.EstimatorSettings`, its errors naming ``estimator.<key>``). Keys left
out take the estimator's defaults."""

from __future__ import annotations

from pydantic import Field

from drillstring.case.base import AngularSpeed, Dimensionless, Force, Length, Time, Torque, _Base


class Estimator(_Base):
    """The ensemble estimator's keys (docs/estimation.md); None: the estimator's default."""

    ensemble_size: int | None = Field(None, description="members of the ensemble")
    top_speed_noise: AngularSpeed | None = Field(None, description="top-speed sensor noise, std [rad/s]")
    surface_torque_noise: Torque | None = Field(None, description="surface-torque sensor noise, std [N*m]")
    block_position_noise: Length | None = Field(None, description="block-position sensor noise, std [m]")
    hook_load_window: Time | None = Field(None, description="averaging window of the hook load [s]")
    inflation: Dimensionless | None = Field(None, description="multiplicative prior inflation [-]")
    model_speed_noise: float | None = Field(None, description="model error on the bit speed [rad/s per sqrt(s)]")
    model_noise_modes: int | None = Field(None, description="torsional modes the model error is spread over")
    model_noise_stick_speed: AngularSpeed | None = Field(None, description="bit speed below which the model "
                                                         "error's kicks are scaled down in proportion [rad/s]")
    initial_speed_spread: AngularSpeed | None = Field(None, description="initial string-speed spread, std [rad/s]")
    spin_up: Time | None = Field(None, description="the members' run before the record's first time [s]")
    assimilation_step: Time | None = Field(None, description="assimilation window: one analysis of its means [s]")
    bit_rock_coefficient: str | None = Field(None, description="the estimated coefficient of the bit-rock law")
    coefficient_spread: Dimensionless | None = Field(None, description="its prior spread (of its logarithm) [-]")
    coefficient_walk: float | None = Field(None, description="its random walk [1/sqrt(s)]")
    friction_factor: str | None = Field(None, description="the wall whose friction factor is estimated: open, "
                                        "cased or none")
    friction_spread: Dimensionless | None = Field(None, description="prior spread of its logarithm [-]")
    friction_walk: float | None = Field(None, description="its random walk [1/sqrt(s)]")
    stiffness_factor: str | None = Field(None, description="the stiffness whose factor is estimated: torsional or "
                                         "none")
    stiffness_spread: Dimensionless | None = Field(None, description="prior spread of its logarithm [-]")
    stiffness_walk: float | None = Field(None, description="its random walk [1/sqrt(s)]")
    model_dispersion: Dimensionless | None = Field(None, description="dispersion of each member's random reduced "
                                                   "mass, stiffness and damping matrices, drawn once [-]")
    relaxation: Dimensionless | None = Field(None, description="relaxation to the prior spread of the state [-]")
    parameter_relaxation: Dimensionless | None = Field(None, description="relaxation to the prior spread of the "
                                                       "parameters [-]")
    particle_share: Dimensionless | None = Field(None, description="share of each analysis's likelihood given to "
                                                 "particle weights (ensemble Kalman particle filter), in [0, 1) [-]")
    particle_effective_size: Dimensionless | None = Field(None, description="the particle weights' least "
                                                          "effective sample size, a fraction of the members [-]")
    weight_on_bit_bias_spread: Force | None = Field(None, description="prior std of the weight-on-bit bias [N]")
    weight_on_bit_bias_walk: float | None = Field(None, description="its random walk [N/sqrt(s)]")
    stick_slip_window: Time | None = Field(None, description="window of the stick-slip index [s]")
    output_step: Time | None = Field(None, description="forecasts' sampling of the bit speed [s]")
    axial_modes: int | None = Field(None, description="elastic axial modes of the estimator's model")
    torsional_modes: int | None = Field(None, description="elastic torsional modes of the estimator's model")
    rtol: Dimensionless | None = Field(None, description="integrator's relative tolerance [-]")
    atol: float | None = Field(None, description="integrator's absolute tolerance (state units)")
    divergence_speed_ratio: Dimensionless | None = Field(None, description="a member above this times the top "
                                                         "speed has diverged [-]")
    seed: int | None = Field(None, description="seed of the estimator's random stream")

    def given(self) -> dict:
        """The keys the case sets (SI values)."""
        return {key: value for key, value in self.model_dump().items() if value is not None}
