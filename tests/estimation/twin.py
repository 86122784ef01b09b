"""Twin experiments for the ensemble estimator (tests/estimation/test_ensemble.py, benchmarks/bench_estimator.py):
a truth simulated by a model other than the estimator's, its surface channels sampled with noise.

The truth: the case's own reduced model (its full basis: 10 axial, 10 torsional modes plus the rigid rotation, 20
lateral modes per plane with the stabilizer's contact), its reduced matrices drawn once from the random-matrix
model (:func:`drillstring.stochastic.random_matrices.random_reduced_model`, dispersion ``dispersion``), the
bit-rock coefficient ``coefficient`` scaled by ``coefficient_factor``; the estimator runs 3 axial and 5 torsional
modes and no lateral one, on the nominal matrices. The hook-load sensor reads ``hook_load_offset`` too high (the
weight-on-bit bias the estimator should find: W = W_case + (H_static - H) + b, b = the offset).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from drillstring.dynamics.compiled import RunState, SolverSettings, advance
from drillstring.dynamics.reduced.build import case_reduced_model
from drillstring.dynamics.reduced.observation import OBSERVABLE_COLUMN
from drillstring.estimation.surface import SurfaceRecord
from drillstring.stochastic.random_matrices import ModelDispersion, random_reduced_model


@dataclass
class Twin:
    record: SurfaceRecord
    time: np.ndarray  # the record's times [s]
    truth: dict  # observable -> values on ``time``
    fine_time: np.ndarray  # every output_step [s]
    fine: dict  # observable -> values on fine_time
    coefficient: float  # the truth's coefficient
    bias: float  # the weight-on-bit bias the estimator should find [N]
    model: object = None  # the truth's reduced model

    def stick_slip_index(self, window: float) -> np.ndarray:
        """The truth's (max - min)/(2 mean) of the bit speed over the last ``window`` s at each record time."""
        out = np.full(len(self.time), np.nan)
        speed = self.fine["bit_speed"]
        for k, t in enumerate(self.time):
            keep = (self.fine_time > t - window + 1e-9) & (self.fine_time <= t + 1e-9)
            s = speed[keep]
            out[k] = (s.max() - s.min()) / (2 * s.mean()) if s.mean() > 0 else np.nan
        return out


def lowest_torsional_frequency(model) -> float:
    """``model``'s lowest elastic torsional angular frequency [rad/s] (the stick-slip mode's; a reduced model)."""
    first, last = int(model.blocks[2]), int(model.blocks[3])
    omega = np.asarray(model.angular_frequencies[first:last], dtype=float)
    return float(np.min(omega[omega > 0.0]))


def twin(case, t_end: float, *, coefficient: str = "a5", coefficient_factor: float = 1.3,
         hook_load_offset: float = 15e3, dispersion: float = 0.05, noise=(0.05, 300.0, 0.005, 2e3),
         sample_step: float = 1.0, output_step: float = 0.1, seed: int = 1) -> Twin:
    """A truth of ``case`` over ``t_end`` [s] and its record at ``sample_step`` [s], the channels with Gaussian
    noise of standard deviations ``noise`` = (top speed [rad/s], surface torque [N m], block position [m],
    hook load [N])."""
    nominal = case_reduced_model(case)
    truth_law = dataclasses.replace(nominal.bit_rock,
                                    **{coefficient: getattr(nominal.bit_rock, coefficient) * coefficient_factor})
    model = case_reduced_model(case, bit_rock=truth_law)
    rng = np.random.default_rng(seed)
    model = random_reduced_model(model, ModelDispersion(dispersion, dispersion, dispersion), rng)
    state = RunState.start(model, model.initial_state(1e-4, seed))
    solver = SolverSettings(rtol=1e-6, atol=1e-9)
    time = np.arange(0.0, t_end + 1e-9, sample_step)
    steps = round(sample_step / output_step)
    fine_time = np.arange(0.0, t_end + 1e-9, output_step)
    rows, top = [model.observe(0.0, state.y)], [model.top_u @ state.y[:model.size]]
    for k in range(1, len(time)):
        grid = fine_time[(k - 1) * steps + 1:k * steps + 1]
        run = advance(model, solver, state, time[k], output_times=grid)
        assert run.success, run.message
        state = run.state
        rows.extend(run.outputs)
        top.append(model.top_u @ state.y[:model.size])
    rows = np.array(rows)
    fine = {name: rows[:, c] for name, c in OBSERVABLE_COLUMN.items()}
    at = np.arange(0, len(fine_time), steps)
    truth = {name: values[at] for name, values in fine.items()}
    n_t = len(time)
    sigma = noise
    record = SurfaceRecord.from_arrays(
        time, source="twin",
        top_speed=truth["quill_speed"] + sigma[0] * rng.standard_normal(n_t),
        surface_torque=truth["surface_torque"] + sigma[1] * rng.standard_normal(n_t),
        block_position=30.0 - np.array(top) + sigma[2] * rng.standard_normal(n_t),
        hook_load=model.static.weight_on_hook + hook_load_offset + sigma[3] * rng.standard_normal(n_t))
    return Twin(record, time, truth, fine_time, fine, getattr(truth_law, coefficient), hook_load_offset, model)


#: The open hole's friction factor of the friction twin's truth [-].
TRUE_FRICTION = 0.25


def off_bottom(case):
    """``case`` with the bit off bottom (``bit_rock.law = "off_bottom"``)."""
    return case.model_copy(update={"bit_rock": case.bit_rock.model_copy(update={"law": "off_bottom"})})


def friction_twin(case, seed: int, t_end: float = 30.0, element: float = 5.0, torsional_modes: int = 20,
                  drilling: bool = False):
    """The record of ``case`` (a case with a well and along-string friction: ``deviated``) off bottom (or as the
    case is, ``drilling``) with the open hole's μ = :data:`TRUE_FRICTION`, simulated on a mesh of ``element``
    [m] (the case's: 10 m) with ``torsional_modes`` torsional and 10 axial modes, no lateral ones: the top
    speed's and the surface torque's samples at 1 Hz with noise 0.05 rad/s and 300 N m."""
    truth_case = case.model_copy(update={"well": case.well.model_copy(update={"open_hole_friction": TRUE_FRICTION})})
    truth_case = (truth_case if drilling else off_bottom(truth_case)).model_copy(
        update={"mesh": case.mesh.model_copy(update={"max_element_length": element})})
    model = case_reduced_model(truth_case, torsional_modes=torsional_modes, lateral_modes=0,
                               nonlinear="bit_and_contact")
    rng = np.random.default_rng(seed)
    state = RunState.start(model, model.initial_state(0.0, seed))
    time = np.arange(0.0, t_end + 1e-9, 1.0)
    rows = [model.observe(0.0, state.y)]
    for t in time[1:]:
        run = advance(model, SolverSettings(rtol=1e-6, atol=1e-9), state, float(t), output_times=[float(t)])
        assert run.success, run.message
        state = run.state
        rows.append(run.outputs[-1])
    rows = np.array(rows)
    n = len(time)
    return SurfaceRecord.from_arrays(
        time, source="friction twin",
        top_speed=rows[:, OBSERVABLE_COLUMN["quill_speed"]] + 0.05 * rng.standard_normal(n),
        surface_torque=rows[:, OBSERVABLE_COLUMN["surface_torque"]] + 300.0 * rng.standard_normal(n))


def own_model_twin(case, settings, t_end: float, *, seed: int = 1, sample_step: float = 1.0,
                   hook_load_noise: float = 2e3) -> Twin:
    """A truth drawn from the estimator's own prior model (``settings``: an
    :class:`~drillstring.estimation.ensemble.EstimatorSettings`), the record's noise the estimator's: the perfect-model
    twin, against which a calibrated filter's 90 % bands cover the truth 90 % of the time on average over truths.

    The truth is one member of the estimator's ensemble as the estimator describes it: its model
    (:func:`~drillstring.estimation.ensemble.estimator_model`), the initial string speed spread by
    ``initial_speed_spread``, the coefficient's logarithm drawn from its prior (``coefficient_spread`` about the
    case's) and the weight-on-bit bias from its (``weight_on_bit_bias_spread`` about 0), both walking
    (``coefficient_walk``, ``weight_on_bit_bias_walk``), the torsional modal velocities kicked before each interval
    as the members' (``model_speed_noise``, ``model_noise_modes``, ``model_noise_stick_speed``), integrated at the
    estimator's tolerances. The hook load reads the static hook load (the truth's weight on bit is the case's plus
    its bias), the other channels have the estimator's noise levels. ``seed``: the truth's stream."""
    from drillstring.estimation.ensemble import (coefficient_slot, estimator_model, kick_scale, member_model,
                                                 model_noise_columns)

    model = estimator_model(case, settings)
    rng = np.random.default_rng(seed)
    n = model.size
    name = settings.bit_rock_coefficient
    slot = coefficient_slot(model, name)
    log_coefficient = np.log(getattr(model.bit_rock, name)) + settings.coefficient_spread * rng.standard_normal()
    bias = settings.weight_on_bit_bias_spread * rng.standard_normal()
    y = model.initial_state(0.0, seed)
    if model.rigid_rotation_column is not None:
        r = model.rigid_rotation_column
        y[n + r] += settings.initial_speed_spread * rng.standard_normal() / model.quill_shapes[r]
    state = RunState.start(model, y)
    kicked, speed_noise = model_noise_columns(model, settings)
    kicked = slice(n + kicked.start, n + kicked.stop)
    solver = SolverSettings(rtol=settings.rtol, atol=settings.atol)
    time = np.arange(0.0, t_end + 1e-9, sample_step)
    coefficients, biases = [np.exp(log_coefficient)], [bias]

    def truth_model():
        laws = model.case2_data.laws.copy()
        laws[slot] = np.exp(log_coefficient)
        return member_model(model, laws, float(model.weight_on_bit) + bias)

    rows, top = [truth_model().observe(0.0, state.y)], [model.top_u @ state.y[:n]]
    for k in range(1, len(time)):
        dt = time[k] - time[k - 1]
        log_coefficient += settings.coefficient_walk * np.sqrt(dt) * rng.standard_normal()
        bias += settings.weight_on_bit_bias_walk * np.sqrt(dt) * rng.standard_normal()
        y = state.y.copy()
        y[kicked] += (speed_noise * np.sqrt(dt) * rng.standard_normal(kicked.stop - kicked.start)
                      * kick_scale(float(rows[-1][OBSERVABLE_COLUMN["bit_speed"]]), settings.model_noise_stick_speed))
        run = advance(truth_model(), solver, state.updated(y), time[k], output_times=[time[k]])
        assert run.success, run.message
        state = run.state
        rows.append(run.outputs[-1])
        top.append(model.top_u @ state.y[:n])
        coefficients.append(np.exp(log_coefficient))
        biases.append(bias)
    rows = np.array(rows)
    truth = {key: rows[:, c] for key, c in OBSERVABLE_COLUMN.items()}
    truth[name], truth["weight_on_bit_bias"] = np.array(coefficients), np.array(biases)
    n_t = len(time)
    record = SurfaceRecord.from_arrays(
        time, source="own-model twin",
        top_speed=truth["quill_speed"] + settings.top_speed_noise * rng.standard_normal(n_t),
        surface_torque=truth["surface_torque"] + settings.surface_torque_noise * rng.standard_normal(n_t),
        block_position=30.0 - np.array(top) + settings.block_position_noise * rng.standard_normal(n_t),
        hook_load=model.static.weight_on_hook + hook_load_noise * rng.standard_normal(n_t))
    return Twin(record, time, truth, time, truth, float(coefficients[-1]), float(biases[-1]))
