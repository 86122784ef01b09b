"""Friction calibration: the grid posterior covers the true friction factors at its stated level, and friction
factors are uncertain parameters like any other."""

import numpy as np
import pytest

from drillstring.case import case_from_dict
from drillstring.stochastic.parameters import case_parameter, with_parameters
from drillstring.stochastic.uncertainty import uncertainty
from drillstring.well.calibration import (
    HookLoadMeasurements,
    calibrate,
    posterior_from_predictions,
    predicted_hook_loads,
    read_measurements,
    torque_drag_draws,
)


@pytest.fixture(scope="module")
def well_case(reference_case):
    data = reference_case.model_dump()
    data["model"]["buoyancy"] = True
    data["well"] = {"survey": [[0, 0, 0], [200, 0, 0], [800, 50, 30], [1600, 50, 30]], "casing_shoe": 600.0}
    return case_from_dict(data)


def _plan():
    depths = np.repeat([500.0, 900.0, 1200.0, 1600.0], 2)
    ops = ("trip_out", "trip_in") * 4
    return depths, ops


def test_posterior_covers_the_truth_at_its_level(well_case):
    """Known friction factors plus Gaussian noise of known sigma, 300 synthetic records: the 90 % highest-
    posterior-density region holds the truth in about 90 % of them (binomial 3-sigma band)."""
    depths, ops = _plan()
    grid_c = np.linspace(0.05, 0.45, 41)
    grid_o = np.linspace(0.10, 0.50, 41)
    mu_c, mu_o = np.meshgrid(grid_c, grid_o, indexing="ij")
    plan = HookLoadMeasurements(depths, ops, np.zeros(len(depths)))
    predictions = predicted_hook_loads(well_case, plan, mu_c.ravel(), mu_o.ravel(), max_step=20.0)
    i_true, j_true = 15, 26  # mu_c = 0.20, mu_o = 0.36
    truth = predictions[:, i_true * len(grid_o) + j_true]
    sigma = 15e3
    rng = np.random.default_rng(7)
    draws, level = 300, 0.9
    inside = 0
    for _ in range(draws):
        measured = truth + sigma * rng.standard_normal(len(truth))
        posterior = posterior_from_predictions(predictions, measured, grid_c, grid_o, sigma)
        inside += posterior.in_region(i_true, j_true, level)
    share = inside / draws
    band = 3 * np.sqrt(level * (1 - level) / draws)
    assert abs(share - level) < band, share
    # the posterior is not degenerate on the grid: several cells wide in both factors
    assert min(posterior.std()) > 2 * (grid_c[1] - grid_c[0])


def test_noise_free_calibration_finds_the_truth_and_sigma_integrated_out(well_case, tmp_path):
    depths, ops = _plan()
    plan = HookLoadMeasurements(depths, ops, np.zeros(len(depths)))
    loads = predicted_hook_loads(well_case, plan, 0.2, 0.3, max_step=20.0)[:, 0]
    csv = tmp_path / "hook.csv"
    csv.write_text("bit_depth [ft],operation,hook_load [klbf]\n" + "".join(
        f"{float(d) / 0.3048!r},{op},{float(h) / 4448.2216152605!r}\n" for d, op, h in zip(depths, ops, loads)))
    measured = read_measurements(csv)
    assert np.allclose(measured.bit_depth, depths) and np.allclose(measured.hook_load, loads)
    posterior = calibrate(well_case, measured, sigma=None, maximum=0.6, points=31, max_step=20.0)
    assert posterior.mode() == pytest.approx((0.2, 0.3))
    low, high = posterior.interval("open_hole", 0.9)
    assert low <= 0.3 <= high


def test_friction_factors_are_uncertain_parameters(well_case):
    parameter = case_parameter(well_case, "well.open_hole_friction")
    assert parameter.bounds.contains(0.3) and not parameter.bounds.contains(-0.1)
    assert with_parameters(well_case, {"well.open_hole_friction": 0.45}).well.open_hole_friction == 0.45
    law = uncertainty(well_case, {"well.open_hole_friction": "uniform 0.2 0.4"})
    draws = torque_drag_draws(well_case, law, 6, seed=3, operations=("trip_out", "trip_in"))
    mu = law.draw(3, np.arange(6))[:, 0]
    order = np.argsort(mu)
    assert np.all(np.diff(draws["trip_out"][order, 0]) > 0)  # more friction, more drag pulling out
    assert np.all(np.diff(draws["trip_in"][order, 0]) < 0)
