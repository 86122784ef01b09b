"""The ensemble estimator (drillstring.estimation.ensemble): its filter core against the exact Kalman filter on
linear Gaussian problems, its settings' checks, the members' cheap re-parametrisation, and twin experiments on the
stick-slip case (the truth from another model: tests/estimation/twin.py), and the members' own random models
(model_dispersion)."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from drillstring.case import load_case
from drillstring.dynamics.compiled import RunState, SolverSettings, advance
from drillstring.dynamics.reduced.build import case_reduced_model
from drillstring.dynamics.reduced.observation import OBSERVABLE_COLUMN
from drillstring.estimation import ensemble
from drillstring.estimation.ensemble import (
    EstimatorSettings,
    coefficient_slot,
    estimate,
    estimator_model,
    kick_scale,
    member_model,
    member_models,
)
from drillstring.estimation.analysis import etkf_analysis
from drillstring.estimation.surface import SPIKE, SurfaceRecord

sys.path.insert(0, str(Path(__file__).resolve().parent))
from twin import twin

# --------------------------------------------------------------------------------------------------------
# The filter core: linear Gaussian problems, against the Kalman filter written here
# --------------------------------------------------------------------------------------------------------


def _kalman(mean, cov, h, r, observed):
    gain = cov @ h.T @ np.linalg.inv(h @ cov @ h.T + r)
    return mean + gain @ (observed - h @ mean), (np.eye(len(mean)) - gain @ h) @ cov


@pytest.mark.parametrize("inflation", [1.0, 1.3])
def test_etkf_analysis_is_the_kalman_update_of_the_sample_moments(inflation):
    """For a linear observation the ETKF's analysis sample mean and covariance are exactly the Kalman filter's
    update of the forecast's (inflated) sample mean and covariance."""
    rng = np.random.default_rng(3)
    n, m, members = 5, 2, 12
    x = rng.standard_normal((n, members)) * np.array([1.0, 2.0, 0.5, 3.0, 1.0])[:, None] + 4.0
    h = rng.standard_normal((m, n))
    noise = np.array([0.3, 1.5])
    observed = rng.standard_normal(m)
    mean = x.mean(axis=1)
    cov = inflation**2 * np.cov(x)
    expected_mean, expected_cov = _kalman(mean, cov, h, np.diag(noise**2), observed)
    analysis = etkf_analysis(x, h @ x, observed, noise, inflation)
    np.testing.assert_allclose(analysis.mean(axis=1), expected_mean, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(np.cov(analysis), expected_cov, rtol=1e-9, atol=1e-10)


def _linear_errors(members, seeds=4, steps=15):
    """Relative errors of the ensemble filter's final mean and covariance against the exact Kalman filter on
    x_{k+1} = F x_k + w, y = H x + v (w, v Gaussian), averaged over ``seeds``."""
    f = np.array([[0.95, 0.2], [-0.2, 0.9]])
    q = np.diag([0.05, 0.02])
    h = np.array([[1.0, 0.0]])
    r = np.array([[0.1]])
    errors = []
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        truth = np.array([1.0, -1.0])
        mean, cov = np.zeros(2), np.eye(2)
        ensemble = rng.multivariate_normal(mean, cov, members).T
        for _ in range(steps):
            truth = f @ truth + rng.multivariate_normal(np.zeros(2), q)
            observed = h @ truth + rng.normal(0.0, np.sqrt(r[0, 0]), 1)
            mean, cov = f @ mean, f @ cov @ f.T + q
            ensemble = f @ ensemble + rng.multivariate_normal(np.zeros(2), q, members).T
            mean, cov = _kalman(mean, cov, h, r, observed)
            ensemble = etkf_analysis(ensemble, h @ ensemble, observed, np.sqrt(np.diag(r)))
        errors.append((np.linalg.norm(ensemble.mean(axis=1) - mean) / np.sqrt(np.trace(cov)),
                       np.linalg.norm(np.cov(ensemble) - cov) / np.linalg.norm(cov)))
    return np.mean(errors, axis=0)


def test_ensemble_filter_approaches_the_kalman_filter_as_the_ensemble_grows():
    """Sampling error ~ N^-1/2: from 20 to 2000 members the errors of the mean and the covariance fall by
    about 10; at 2000 they are a few per cent."""
    small, large = _linear_errors(20), _linear_errors(2000)
    assert np.all(large < small / 4.0), (small, large)
    assert large[0] < 0.05 and large[1] < 0.08, large


# --------------------------------------------------------------------------------------------------------
# Settings and members
# --------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("field, value, words", [
    ("ensemble_size", 2, "ensemble_size = 2: must be an integer in [4, 1000]"),
    ("inflation", 3.0, "inflation = 3.0: must be a number in [1, 2]"),
    ("top_speed_noise", 0.0, "top_speed_noise = 0.0: must be a finite number > 0"),
    ("coefficient_spread", 5.0, "coefficient_spread = 5.0: must be a number in (0, 2]"),
    ("model_speed_noise", -1.0, "model_speed_noise = -1.0: must be a finite number >= 0"),
    ("spin_up", -1.0, "spin_up = -1.0: must be a finite number >= 0"),
    ("assimilation_step", 0.0, "assimilation_step = 0.0: must be a finite number > 0"),
])
def test_settings_refuse_values_out_of_range_naming_them(field, value, words):
    with pytest.raises(ValueError, match=words.replace("[", r"\[").replace("(", r"\(")):
        EstimatorSettings(**{field: value})


@pytest.fixture(scope="module")
def stick_slip():
    return load_case("stick_slip")


@pytest.fixture(scope="module")
def small_model(stick_slip):
    return estimator_model(stick_slip, EstimatorSettings(axial_modes=2, torsional_modes=3))


def test_member_model_runs_as_a_model_built_with_the_changed_law(stick_slip, small_model):
    """Replacing a5 in the packed law array is the model built with that law: the same run bit for bit; the
    shared model is not changed."""
    law = dataclasses.replace(small_model.bit_rock, a5=1.3 * small_model.bit_rock.a5)
    built = case_reduced_model(stick_slip, axial_modes=2, torsional_modes=3, lateral_modes=0, bit_rock=law)
    laws = small_model.case2_data.laws.copy()
    slot = coefficient_slot(small_model, "a5")
    laws[slot] = law.a5
    nominal = small_model.case2_data.laws.copy()
    member = member_model(small_model, laws, small_model.weight_on_bit)
    y0 = small_model.initial_state(0.0, 0)
    grid = np.linspace(0.1, 2.0, 20)
    ours = advance(member, SolverSettings(rtol=1e-5), RunState.start(member, y0), 2.0, output_times=grid)
    theirs = advance(built, SolverSettings(rtol=1e-5), RunState.start(built, y0), 2.0, output_times=grid)
    np.testing.assert_array_equal(ours.outputs, theirs.outputs)
    np.testing.assert_array_equal(small_model.case2_data.laws, nominal)
    with pytest.raises(ValueError, match="bit_rock_coefficient = 'zz'"):
        coefficient_slot(small_model, "zz")


# --------------------------------------------------------------------------------------------------------
# Twin experiments (stick_slip: PI top drive at 100 rpm, the bit sticking and slipping)
# --------------------------------------------------------------------------------------------------------

T_END = 60.0
SPIN_UP = 10.0  # [s] the start, where the prior (the static state spinning) is still being corrected


@pytest.fixture(scope="module")
def experiment(stick_slip):
    # the twin's truth starts at the model's initial state, as its record does: no spin-up. 32 members (the
    # default 256 would take 8 times as long) with the model noise that suits so few, 2 rad/s/sqrt(s), the
    # configuration these tests' figures were measured on (at the default 1.5 the bands of 32 members are too
    # narrow: bit speed 0.68 here; docs/estimation.md "The defaults")
    settings = EstimatorSettings(ensemble_size=32, spin_up=0.0, model_speed_noise=2.0)
    truth = twin(stick_slip, T_END)
    return truth, estimate(stick_slip, truth.record, settings), settings


def test_twin_bands_cover_the_truth(experiment):
    """(a) The 90 % bands of bit speed and torque on bit hold the truth most of the time after the spin-up
    (measured 0.82-0.92 on this 60 s record over seeds 0-2 with 2 rad/s/sqrt(s), 0.86-1.0 with 3; 50 correlated
    samples; the 300 s benchmark gives the long-record figure, docs/estimation.md)."""
    truth, result, _ = experiment
    for name in ("bit_speed", "torque_on_bit"):
        coverage = result.coverage(name, truth.truth[name], SPIN_UP)
        assert 0.75 <= coverage <= 1.0, (name, coverage)
    assert result.replaced_members == 0


def test_twin_bit_speed_beats_the_surface_guess(experiment):
    """(b) The bit speed's RMSE after the spin-up is at least 5 times smaller than that of the surface-only
    guess (bit speed = top speed)."""
    truth, result, _ = experiment
    keep = result.time >= SPIN_UP
    error = np.sqrt(np.mean((result.mean["bit_speed"] - truth.truth["bit_speed"])[keep] ** 2))
    naive = np.sqrt(np.mean((truth.record.channels["top_speed"] - truth.truth["bit_speed"])[keep] ** 2))
    assert error * 5.0 < naive, (error, naive)


def test_twin_detects_stick_slip_while_the_surface_speed_is_held(experiment):
    """(c) The stick-slip index over the last window at the end of the record: the estimate's band reaches the
    truth's index or misses it by under 5 % (measured: band 1.91-2.21 for a truth of 1.83 on seed 0, 1.80-2.12 and
    1.83-2.14 on seeds 1 and 2: the model noise's kicks ring in the higher torsional modes and raise each member's
    max - min, a known bias up, docs/estimation.md), its lower end above 1 (full stick-slip), while the index of
    the top speed -- the surface alone -- stays below 0.2 (the PI top drive holds the speed)."""
    truth, result, settings = experiment
    index = truth.stick_slip_index(settings.stick_slip_window)[-1]
    low, high = result.band("stick_slip_index")
    assert 0.95 * low[-1] <= index <= 1.05 * high[-1], (index, low[-1], high[-1])
    assert low[-1] > 1.0
    top = truth.record.channels["top_speed"][result.time > T_END - settings.stick_slip_window]
    assert (top.max() - top.min()) / (2 * top.mean()) < 0.2


def test_twin_recovers_the_parameters(experiment):
    """(d) a5 (truth 1.3 times the case's, where the prior is centred) and the weight-on-bit bias (truth 15 kN,
    prior 0): the final mean has at most half the prior mean's error."""
    truth, result, _settings = experiment
    prior = load_case("stick_slip").bit_rock.a5
    assert abs(result.mean["a5"][-1] - truth.coefficient) < 0.5 * abs(prior - truth.coefficient)
    assert abs(result.mean["weight_on_bit_bias"][-1] - truth.bias) < 0.5 * truth.bias


def test_flagged_sample_is_not_used(stick_slip, small_model):
    """(e) A spike flagged in the surface torque gives the result of the record with that sample removed; the
    same spike unflagged changes it (so the test can fail)."""
    time = np.arange(0.0, 6.0, 1.0)
    speed = np.full(len(time), small_model.top_speed)
    torque = np.full(len(time), 5000.0)
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=0.0)

    def run(values, flags=None):
        record = SurfaceRecord.from_arrays(time, top_speed=speed, surface_torque=values)
        if flags is not None:
            record = dataclasses.replace(record, flags={**record.flags, "surface_torque": flags})
        return estimate(stick_slip, record, settings, model=small_model)

    spiked = torque.copy()
    spiked[3] = 2e4
    flags = np.zeros(len(time), dtype=np.int8)
    flags[3] = SPIKE
    removed = torque.copy()
    removed[3] = np.nan
    flagged, missing, unflagged = run(spiked, flags), run(removed), run(spiked)
    assert not flagged.used["surface_torque"][3] and flagged.used["top_speed"][3]
    for name in ("bit_speed", "torque_on_bit", "a5"):
        np.testing.assert_array_equal(flagged.mean[name], missing.mean[name])
    assert not np.array_equal(flagged.mean["torque_on_bit"], unflagged.mean["torque_on_bit"])


def test_result_dataset_carries_units(experiment):
    _, result, _ = experiment
    data = result.to_dataset()
    assert data["bit_speed"].attrs["units"] == "rad/s"
    assert data["a5_quantile"].dims == ("time", "quantile")
    assert data["predicted_surface_torque"].attrs["units"] == "N*m"
    assert data.attrs["estimator_ensemble_size"] == 32


def test_failed_forecasts_are_replaced_and_counted(stick_slip, small_model, monkeypatch):
    """A member whose advance fails (here every third call, made to fail) is replaced by a copy of one that
    succeeded and counted; the run goes on. When every member fails, the run stops (the samples before kept; in the
    spin-up, before any, it raises EstimateDiverged)."""
    real = ensemble.advance
    calls = {"n": 0}

    def failing(*args, **kwargs):
        calls["n"] += 1
        result = real(*args, **kwargs)
        if calls["n"] % 3 == 0:
            result.message = "integration failed (made to fail by the test)"
        return result

    time = np.arange(0.0, 4.0, 1.0)
    record = SurfaceRecord.from_arrays(time, top_speed=np.full(len(time), small_model.top_speed),
                                       surface_torque=np.full(len(time), 5000.0))
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=0.0)
    monkeypatch.setattr(ensemble, "advance", failing)
    result = estimate(stick_slip, record, settings, model=small_model)
    assert result.replaced.tolist() == [0, 2, 2, 2]
    assert np.all(np.isfinite(result.mean["bit_speed"]))
    monkeypatch.setattr(ensemble, "advance", lambda *a, **k: (_ for _ in ()).throw(ValueError("no")))
    stopped = estimate(stick_slip, record, settings, model=small_model)
    assert stopped.stopped == "estimate: every member's forecast failed between t = 0 s and 1 s of the record"
    assert stopped.time.tolist() == [0.0]  # the first sample, analysed before any forecast, is kept
    with pytest.raises(ensemble.EstimateDiverged, match="every member's forecast failed between t = -1 s and 0 s"):
        estimate(stick_slip, record, dataclasses.replace(settings, spin_up=1.0), model=small_model)  # nothing to keep


def _constant_record(model, seconds):
    time = np.arange(0.0, seconds, 1.0)
    return SurfaceRecord.from_arrays(time, top_speed=np.full(len(time), model.top_speed),
                                     surface_torque=np.full(len(time), 5000.0))


def test_a_run_whose_members_all_fail_later_keeps_the_samples_before(stick_slip, small_model, monkeypatch):
    """Every forecast after the second fails: the run stops at the third forecast and returns the three samples
    analysed before it, the reason in ``stopped`` and in the dataset's attrs."""
    real = ensemble.advance
    calls = {"n": 0}

    def failing_later(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] > 2 * 6:  # two forecasts of six members
            raise ValueError("made to fail by the test")
        return real(*args, **kwargs)

    monkeypatch.setattr(ensemble, "advance", failing_later)
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=0.0)
    result = estimate(stick_slip, _constant_record(small_model, 6.0), settings, model=small_model)
    assert result.stopped == "estimate: every member's forecast failed between t = 2 s and 3 s of the record"
    assert result.time.tolist() == [0.0, 1.0, 2.0]
    assert all(len(v) == 3 and np.all(np.isfinite(v)) for v in (result.mean["bit_speed"], result.replaced,
                                                                   result.observed["surface_torque"]))
    assert result.quantiles["a5"].shape == (3, 3) and result.used["top_speed"].shape == (3,)
    assert result.to_dataset().attrs["stopped"] == result.stopped


def test_an_interrupted_run_returns_what_it_computed(stick_slip, small_model, monkeypatch):
    """Ctrl-C (KeyboardInterrupt, here from the progress callback after the second sample) stops the run; the
    samples done are returned, the same as an uninterrupted run's; before the first sample (in the spin-up) it is
    raised."""
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=0.0)
    record = _constant_record(small_model, 5.0)

    def interrupt_at(t_stop):
        def progress(t):
            if t >= t_stop:
                raise KeyboardInterrupt
        return progress

    result = estimate(stick_slip, record, settings, model=small_model, progress=interrupt_at(1.0))
    assert result.stopped == "interrupted after t = 1 s of the record"
    whole = estimate(stick_slip, record, settings, model=small_model)
    assert whole.stopped == "" and len(whole.time) == 5 and "stopped" not in whole.to_dataset().attrs
    np.testing.assert_array_equal(result.quantiles["bit_speed"], whole.quantiles["bit_speed"][:2])
    monkeypatch.setattr(ensemble, "advance", lambda *a, **k: (_ for _ in ()).throw(KeyboardInterrupt))
    with pytest.raises(KeyboardInterrupt):
        estimate(stick_slip, record, dataclasses.replace(settings, spin_up=1.0), model=small_model)


def test_a_parameter_ensemble_blown_up_by_inflation_stops_the_run_saying_where(stick_slip, small_model):
    """With inflation 2 the coefficient's spread doubles at each analysis (the record barely narrows it): the run
    stops once its 90 % band spans more than the clip range exp(2 LOG_RANGE), naming the parameter, the time and
    the inflation, and keeps the samples before; inflation 1 on the same record runs to the end."""
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=0.0, inflation=2.0)
    record = _constant_record(small_model, 12.0)
    result = estimate(stick_slip, record, settings, model=small_model)
    assert result.stopped.startswith(f"estimate: the a5 ensemble diverged at t = {result.time[-1] + 1:g} s of "
                                     "the record"), result.stopped
    assert "inflation = 2" in result.stopped and 2 <= len(result.time) < 12  # measured: stops at 4 s
    low, high = np.log(result.quantiles["a5"][-1][[0, 2]])
    assert high - low <= 2 * ensemble.LOG_RANGE
    calm = estimate(stick_slip, record, dataclasses.replace(settings, inflation=1.0), model=small_model)
    assert calm.stopped == "" and len(calm.time) == 12


# --------------------------------------------------------------------------------------------------------
# Assimilation windows and the spin-up
# --------------------------------------------------------------------------------------------------------


def _window_run(stick_slip, small_model, torque, **changes):
    time = np.arange(0.0, len(torque), 1.0)
    record = SurfaceRecord.from_arrays(time, top_speed=np.full(len(time), small_model.top_speed),
                                       surface_torque=np.asarray(torque, dtype=float))
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=0.0,
                                 coefficient_walk=0.0, weight_on_bit_bias_walk=0.0, **changes)
    return estimate(stick_slip, record, settings, model=small_model)


def test_one_analysis_per_assimilation_window_with_the_window_means(stick_slip, small_model):
    """With ``assimilation_step`` 3 s on a 1 s record the windows are {0}, (0, 3], (3, 6]: the parameters (no
    walk) change only at each window's last sample; samples of a window changed with their mean kept give the
    same estimate bit for bit (the analysis reads the means), a changed mean another."""
    torque = [5000.0, 4000.0, 5000.0, 6000.0, 5000.0, 5000.0, 5000.0]
    result = _window_run(stick_slip, small_model, torque, assimilation_step=3.0)
    changed = np.diff(result.mean["a5"]) != 0.0
    assert changed.tolist() == [False, False, True, False, False, True]
    assert result.used["surface_torque"].all()
    same_mean = _window_run(stick_slip, small_model, [5000.0] * 7, assimilation_step=3.0)
    np.testing.assert_array_equal(result.mean["bit_speed"], same_mean.mean["bit_speed"])
    other_mean = _window_run(stick_slip, small_model, [5000.0, 4000.0, 5000.0, 9000.0, 5000.0, 5000.0, 5000.0],
                             assimilation_step=3.0)
    assert not np.array_equal(result.mean["bit_speed"][3:], other_mean.mean["bit_speed"][3:])
    # a window of one sample each: an analysis at every sample
    every = _window_run(stick_slip, small_model, torque, assimilation_step=1.0)
    assert (np.diff(every.mean["a5"]) != 0.0).all()


def test_spin_up_starts_the_members_on_their_run(stick_slip, small_model):
    """After a spin-up the members are twisted (the surface torque predicted at the first sample is that of
    the string turning the bit against the rock, thousands of N·m; the static state spinning has next to none)
    and the predicted block position at the first sample is the first sample (the block's zero is set there)."""
    time = np.arange(0.0, 2.0, 1.0)
    record = SurfaceRecord.from_arrays(time, top_speed=np.full(len(time), small_model.top_speed),
                                       block_position=np.array([29.9, 29.9]),
                                       surface_torque=np.array([np.nan, np.nan]))
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=5.0)
    spun = estimate(stick_slip, record, settings, model=small_model)
    cold = estimate(stick_slip, record, dataclasses.replace(settings, spin_up=0.0), model=small_model)
    assert abs(cold.predicted_mean["surface_torque"][0]) < 1e3
    assert spun.predicted_mean["surface_torque"][0] > 2e3
    assert abs(spun.predicted_mean["block_position"][0] - 29.9) < 3 * settings.block_position_noise


def test_case_table_keys_are_the_settings():
    """The [estimator] case keys are the settings' fields, the new ones included, converted to SI."""
    from drillstring.case.estimator_table import Estimator

    assert set(Estimator.model_fields) == {f.name for f in dataclasses.fields(EstimatorSettings)}
    given = Estimator(spin_up="5 s", assimilation_step="500 ms").given()
    assert given == {"spin_up": 5.0, "assimilation_step": 0.5}
    assert EstimatorSettings(**given).assimilation_step == 0.5


# --------------------------------------------------------------------------------------------------------
# Model uncertainty (model_dispersion): each member its own reduced model drawn once from the random-matrix
# model, compared in the estimator's model's coordinates; 0 (the default) is the one shared model
# --------------------------------------------------------------------------------------------------------


def _dispersed_run(stick_slip, small_model, **changes):
    """A 4 s record (top speed, surface torque at 1 Hz), 6 members on the small model."""
    time = np.arange(0.0, 4.0, 1.0)
    record = SurfaceRecord.from_arrays(time, top_speed=np.full(len(time), small_model.top_speed),
                                       surface_torque=np.array([5000.0, 7000.0, 9000.0, 6000.0]))
    settings = EstimatorSettings(ensemble_size=6, axial_modes=2, torsional_modes=3, spin_up=1.0, **changes)
    return estimate(stick_slip, record, settings, model=small_model)


def test_zero_model_dispersion_is_the_shared_model(small_model):
    models, transforms = member_models(small_model, 0.0, 0, 5)
    assert all(m is small_model for m in models) and transforms == [None] * 5


def test_members_draw_their_own_matrices_reproducibly_from_the_seed(small_model):
    """With a dispersion each member's matrices differ from the nominal and from the other members', the same
    seed draws the same ones (a member's draw depends on (seed, member) only), another seed others; ``X`` maps
    the member's coordinates to the estimator's model's: the realized basis is ``Φ X``, so ``top_u`` and the
    bit's rotation read the same displacement in both."""
    models, transforms = member_models(small_model, 0.1, 7, 4)
    again, _ = member_models(small_model, 0.1, 7, 6)
    other, _ = member_models(small_model, 0.1, 8, 4)
    for i, (model, (x, x_inv)) in enumerate(zip(models, transforms)):
        assert not np.allclose(model.omega2, small_model.omega2)
        np.testing.assert_array_equal(model.omega2, again[i].omega2)
        np.testing.assert_array_equal(model.damping, again[i].damping)
        assert not np.allclose(model.omega2, other[i].omega2)
        np.testing.assert_allclose(model.basis, small_model.basis @ x, rtol=0, atol=1e-12 * np.abs(model.basis).max())
        np.testing.assert_allclose(x_inv @ x, np.eye(len(x)), atol=1e-12)
        q = np.random.default_rng(i).standard_normal(len(x))
        assert small_model.top_u @ (x @ q) == pytest.approx(model.top_u @ q, rel=1e-12, abs=1e-15)
        assert small_model.bit_t @ (x @ q) == pytest.approx(model.bit_t @ q, rel=1e-12, abs=1e-15)
    assert not np.allclose(models[0].omega2, models[1].omega2)


def test_coordinates_change_nothing_when_every_member_is_the_nominal_model(stick_slip, small_model, monkeypatch):
    """The estimate with every member's transform the identity (the states go through ``ξ = X q`` and back) is
    the shared model's bit for bit; drawn models (0.1) give another estimate, the same one twice."""
    shared = _dispersed_run(stick_slip, small_model)
    identity = np.eye(small_model.size)
    monkeypatch.setattr(ensemble, "member_models",
                        lambda model, dispersion, seed, n: ([model] * n, [(identity, identity)] * n))
    through = _dispersed_run(stick_slip, small_model)
    monkeypatch.undo()
    for name in ("bit_speed", "torque_on_bit", "a5", "weight_on_bit_bias"):
        np.testing.assert_array_equal(through.mean[name], shared.mean[name])
        np.testing.assert_array_equal(through.quantiles[name], shared.quantiles[name])
    drawn = _dispersed_run(stick_slip, small_model, model_dispersion=0.1)
    assert np.all(np.isfinite(drawn.mean["bit_speed"]))
    assert not np.array_equal(drawn.quantiles["torque_on_bit"], shared.quantiles["torque_on_bit"])
    again = _dispersed_run(stick_slip, small_model, model_dispersion=0.1)
    np.testing.assert_array_equal(again.quantiles["torque_on_bit"], drawn.quantiles["torque_on_bit"])


def test_a_replaced_member_takes_its_source_model():
    members = ensemble._Members([None, None], np.zeros((2, 1)), 3, ["a", "b"], ["xa", "xb"])
    members.copy_member(0, 1)
    assert members.models == ["b", "b"] and members.transforms == ["xb", "xb"]


def test_resampled_members_take_their_parents_model_state_and_outputs_all_at_once():
    """Member i becomes a copy of member parents[i], read before any is overwritten (a permutation swaps)."""
    members = ensemble._Members(["s0", "s1", "s2"], np.array([[0.0], [1.0], [2.0]]), 2, ["a", "b", "c"],
                                ["xa", "xb", "xc"])
    members.outputs = ["o0", "o1", "o2"]
    members.speed[:] = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    members.reorder([2, 0, 0])
    assert members.states == ["s2", "s0", "s0"] and members.models == ["c", "a", "a"]
    assert members.transforms == ["xc", "xa", "xa"] and members.outputs == ["o2", "o0", "o0"]
    np.testing.assert_array_equal(members.parameters[:, 0], [2.0, 0.0, 0.0])
    np.testing.assert_array_equal(members.speed[:, 0], [2.0, 0.0, 0.0])


def test_particle_share_runs_the_enkpf_and_reports_its_effective_sizes(stick_slip, small_model):
    """With particle_share > 0 each analysis is the EnKPF's: the weights' effective size is reported at each
    analysis (between 1 and N, NaN elsewhere; in the dataset too), the run is reproducible from its seed, and it
    differs from the ETKF's; with members of their own models each resampled member carries its parent's."""
    etkf = _dispersed_run(stick_slip, small_model)
    assert etkf.effective_size is None and "effective_sample_size" not in etkf.to_dataset()
    runs = [_dispersed_run(stick_slip, small_model, particle_share=0.9, model_dispersion=0.05) for _ in range(2)]
    sizes = runs[0].effective_size
    assert np.all(np.isfinite(sizes)) and np.all((sizes >= 1.0) & (sizes <= 6.0 + 1e-9))
    np.testing.assert_array_equal(runs[1].quantiles["torque_on_bit"], runs[0].quantiles["torque_on_bit"])
    assert runs[0].to_dataset()["effective_sample_size"].dims == ("time",)
    plain = _dispersed_run(stick_slip, small_model, particle_share=0.9)
    assert np.all(np.isfinite(plain.mean["bit_speed"]))
    assert not np.array_equal(plain.quantiles["torque_on_bit"], etkf.quantiles["torque_on_bit"])
    held = _dispersed_run(stick_slip, small_model, particle_share=0.999, particle_effective_size=0.9)
    assert np.all(held.effective_size >= 0.9 * 6 - 1e-9)


def test_bad_particle_settings_are_refused_naming_them():
    with pytest.raises(ValueError, match=r"particle_share = 1.0: must be a number in \[0, 1\)"):
        EstimatorSettings(particle_share=1.0)
    with pytest.raises(ValueError, match=r"particle_effective_size = -0.1: must be a number in \[0, 1\)"):
        EstimatorSettings(particle_effective_size=-0.1)


def test_bad_model_dispersion_is_refused_naming_it(stick_slip, small_model):
    for bad in (-0.1, 1.0):
        with pytest.raises(ValueError, match=rf"model_dispersion = {bad}: must be a number in \[0, 1\)"):
            EstimatorSettings(model_dispersion=bad)
    # below 1 but above the bound sqrt((n+1)/(n+5)) of a family of the estimator's model
    with pytest.raises(ValueError, match=r"estimator\.model_dispersion = 0\.9: must be in \[0, 0\.\d+\) = "
                                         r"\[0, sqrt\(\(n\+1\)/\(n\+5\)\)\) for the \w+ family of n = \d modes"):
        _dispersed_run(stick_slip, small_model, model_dispersion=0.9)


# --------------------------------------------------------------------------------------------------------
# The model error's kicks scaled down while the bit is slow (model_noise_stick_speed)
# --------------------------------------------------------------------------------------------------------


def test_kick_scale_is_the_bit_speed_over_the_stick_speed_up_to_one():
    assert kick_scale(0.0, 2.0) == 0.0
    assert kick_scale(-1.0, 2.0) == 0.5
    assert kick_scale(3.0, 2.0) == 1.0
    assert kick_scale(0.0, 0.0) == 1.0  # off
    assert kick_scale(None, 2.0) == 1.0 and kick_scale(float("nan"), 2.0) == 1.0  # no forecast yet, or a failed one


def test_stick_speed_off_or_below_every_bit_speed_changes_nothing_and_a_high_one_narrows_the_bands(
        stick_slip, small_model):
    """0 (the default) and a stick speed below every member's bit speed give the same run bit for bit (each
    kick times 1, the same draws); one far above every bit speed all but removes the kicks, so the members'
    bit speeds spread less (what is left is the prior's spread and the walks')."""
    default = _dispersed_run(stick_slip, small_model)
    below = _dispersed_run(stick_slip, small_model, model_noise_stick_speed=1e-9)
    for name in ("bit_speed", "torque_on_bit", "a5"):
        np.testing.assert_array_equal(below.quantiles[name], default.quantiles[name])
    above = _dispersed_run(stick_slip, small_model, model_noise_stick_speed=1e6)
    width = {run: np.mean(np.diff(result.quantiles["bit_speed"][:, [0, -1]], axis=1))
             for run, result in (("default", default), ("above", above))}
    assert width["above"] < width["default"], width  # measured 1.62 against 2.14 rad/s
    with pytest.raises(ValueError, match=r"model_noise_stick_speed = -1\.0: must be a finite number >= 0"):
        EstimatorSettings(model_noise_stick_speed=-1.0)


def test_own_model_twin_without_its_draws_is_one_run_of_the_estimators_model(stick_slip):
    """The perfect-model twin (benchmarks/estimator_coverage.py --own-truths) with its prior draws, walks and kicks
    off is the estimator's model run once from its initial state: chaining the intervals, rebuilding the member's
    model at the case's coefficient and weight on bit, and reading the observables change nothing beyond the
    integrator's tolerance; its hook load reads the static hook load."""
    from twin import own_model_twin

    settings = EstimatorSettings(axial_modes=2, torsional_modes=3, spin_up=0.0, coefficient_spread=1e-12,
                                 coefficient_walk=0.0, weight_on_bit_bias_spread=1e-9, weight_on_bit_bias_walk=0.0,
                                 model_speed_noise=0.0, initial_speed_spread=0.0, rtol=1e-7, atol=1e-9)
    own = own_model_twin(stick_slip, settings, 6.0, seed=3, sample_step=0.5, hook_load_noise=1e-6)
    model = estimator_model(stick_slip, settings)
    run = advance(model, SolverSettings(rtol=settings.rtol, atol=settings.atol),
                  RunState.start(model, model.initial_state(0.0, 3)), 6.0, output_times=own.time)
    assert run.success
    for name in ("bit_speed", "torque_on_bit", "surface_torque", "force_on_bit"):
        column = OBSERVABLE_COLUMN[name]
        scale = np.max(np.abs(run.outputs[:, column]))
        np.testing.assert_allclose(own.truth[name], run.outputs[:, column], atol=1e-4 * scale, err_msg=name)
    assert np.ptp(own.truth["bit_speed"]) > 1.0  # the run is not at rest: the comparison compares something
    np.testing.assert_allclose(own.truth["a5"], model.bit_rock.a5, rtol=1e-9)
    np.testing.assert_allclose(own.record.channels["hook_load"], model.static.weight_on_hook, atol=1e-3)
