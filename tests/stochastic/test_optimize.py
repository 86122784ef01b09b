"""The robust operating point: the surrogate search on analytic problems with known constrained optima (one of
them chance-constrained, estimated by Monte Carlo), infeasible constraints, the Gaussian process, and on the
simulator: resume, the fingerprint and the refusals."""

import math

import numpy as np
import pytest
from scipy.special import ndtr, ndtri

from drillstring.stochastic import optimize as opt
from drillstring.stochastic.surrogate import GaussianProcess, SearchProblem, constraint_confidence, search

RPM = math.pi / 30.0


def test_gaussian_process_interpolates_and_knows_its_noise():
    """Noise-free samples of a smooth function: the posterior mean passes through them (sd ~ 0 there) and
    predicts between them; with a known noise variance the posterior sd at a sample is below the noise's."""
    x = np.linspace(0.0, 1.0, 9)[:, None]
    y = np.sin(6.0 * x[:, 0])
    gp = GaussianProcess.fit(x, y)
    mean, sd = gp.predict(x)
    assert np.max(np.abs(mean - y)) < 1e-3 and np.max(sd) < 1e-2
    between = (x[:-1] + x[1:]) / 2
    assert np.max(np.abs(gp.predict(between)[0] - np.sin(6.0 * between[:, 0]))) < 0.02
    noisy = GaussianProcess.fit(x, y + 0.01 * np.cos(40 * x[:, 0]), np.full(9, 0.05**2))
    assert np.all(noisy.predict(x)[1] < 0.05)


def test_kriging_believer_keeps_the_mean_and_removes_the_uncertainty_at_the_believed_point():
    """Conditioning on the posterior mean at a point (Ginsbourger et al. 2010) leaves the mean unchanged
    everywhere and the standard deviation ~0 there, and no larger anywhere."""
    rng = np.random.default_rng(1)
    x = rng.uniform(size=(7, 2))
    gp = GaussianProcess.fit(x, np.sin(3 * x[:, 0]) + x[:, 1], np.full(7, 1e-3))
    point, grid = np.array([[0.5, 0.5]]), rng.uniform(size=(50, 2))
    believed = gp.believe(point)
    assert np.allclose(believed.predict(grid)[0], gp.predict(grid)[0], atol=1e-6)
    assert believed.predict(point)[1][0] < 0.05 * gp.predict(point)[1][0]
    assert np.all(believed.predict(grid)[1] <= gp.predict(grid)[1] + 1e-9)


def test_linear_trend_returns_to_the_fitted_plane_far_from_data():
    """Noise-free samples of a plane in a corner of the unit square: with a linear trend (universal kriging)
    the posterior mean at the far corner is the plane exactly, with a small standard deviation, where the
    constant-mean process falls back towards the data's mean; the believer keeps its mean too."""
    rng = np.random.default_rng(0)
    x = rng.uniform(0.0, 0.5, (10, 2))
    plane = lambda u: 0.3 + 0.8 * u[:, 0] - 0.4 * u[:, 1]  # noqa: E731
    far = np.array([[1.0, 1.0], [0.9, 0.1]])
    trend = GaussianProcess.fit(x, plane(x), np.full(10, 1e-4), trend=True)
    mean, sd = trend.predict(far)
    assert np.allclose(mean, plane(far), atol=1e-3) and np.all(sd < 0.05)
    constant = GaussianProcess.fit(x, plane(x), np.full(10, 1e-4))
    assert np.max(np.abs(constant.predict(far)[0] - plane(far))) > 0.03
    grid = rng.uniform(size=(20, 2))
    assert np.allclose(trend.believe([[0.7, 0.7]]).predict(grid)[0], trend.predict(grid)[0], atol=1e-6)


@pytest.mark.parametrize("batch, trend", [(1, False), (4, False), (4, True)])
def test_deterministic_constrained_optimum(batch, trend):
    """max −(x1 − 0.7)² − (x2 − 0.8)² s.t. (x1 + x2)/2 ≤ 0.5: the projection of (0.7, 0.8) on the line, (0.45,
    0.55); found within 0.03 in each variable from 16 points, one at a time or in batches of 4 (two batches
    after the initial design), and with a linear trend of the constraint's surrogate."""
    def evaluate(x):
        return -(x[0] - 0.7) ** 2 - (x[1] - 0.8) ** 2, 1e-8, [(x[0] + x[1]) / 2], [1e-8]

    problem = SearchProblem(((0.0, 1.0), (0.0, 1.0)), (0.5,), maximize=True, initial=8, seed=1, trend=trend)
    points, _, found = search(problem, evaluate, 16, batch=batch)
    assert found.feasible
    assert np.allclose(found.point, [0.45, 0.55], atol=0.03)
    # a batch's points are distinct (the believer moves each next one away from the others)
    unit = problem.to_unit(points)
    assert np.min(np.linalg.norm(unit[:, None] - unit[None], axis=2) + np.eye(16)) >= 0.02


@pytest.mark.parametrize("batch", [1, 4])
def test_chance_constrained_optimum_from_monte_carlo_estimates(batch):
    """max E[x1 + x2 + 0.1 Z'] s.t. P(x1² + x2 + 0.3 Z > 2) ≤ 0.05, Z, Z' standard normal, each point estimated
    from the same n = 2000 draws (common random numbers) with its binomial variance. The constraint is
    x2 ≤ 2 − 0.3 z₀.₉₅ − x1², so the optimum is x1 = 1/2, x2 = 1.75 − 0.3 z₀.₉₅ = 1.2565, objective 1.7565.
    The objective is flat along the boundary there (a shift δ in x1 costs δ²), so the tolerance is stated on
    what matters: the exact probability at the answer within 2.5 binomial standard errors of 0.05 (±0.012),
    the objective within 0.03 of the optimum, and the point within 0.06 of it in each variable; one point at a
    time (14 steps) or 4 at a time (4 steps), the same budget."""
    draws = np.random.default_rng(5).standard_normal((2000, 2))
    z95 = float(ndtri(0.95))

    def evaluate(x):
        hit = x[0] ** 2 + x[1] + 0.3 * draws[:, 0] > 2.0
        p, n = hit.mean(), hit.size
        tilde = (p * n + 0.5) / (n + 1)
        value = x[0] + x[1] + 0.1 * draws[:, 1]
        return value.mean(), value.var() / n, [p], [tilde * (1 - tilde) / n]

    problem = SearchProblem(((0.0, 2.0), (0.0, 2.0)), (0.05,), maximize=True, initial=8, seed=0)
    points, estimates, found = search(problem, evaluate, 22, batch=batch)
    assert found.feasible
    x1, x2 = found.point
    exact = float(ndtr((x1**2 + x2 - 2.0) / 0.3))
    assert abs(exact - 0.05) < 2.5 * math.sqrt(0.05 * 0.95 / 2000)
    assert abs((x1 + x2) - (0.5 + 1.75 - 0.3 * z95)) < 0.03
    assert np.allclose(found.point, [0.5, 1.75 - 0.3 * z95], atol=0.06)
    # the sequential points went near the constraint boundary x2 = 2 − 0.3 z₀.₉₅ − x1²
    later = points[problem.initial:]
    assert np.median(np.abs(later[:, 1] - (2.0 - 0.3 * z95 - later[:, 0] ** 2))) < 0.15


def test_infeasible_constraints_give_the_least_infeasible_point():
    """P(Z > 1 − x) ≤ 0.05 over x in [0, 1] is infeasible (P ≥ P(Z > 1) = 0.159); the least-infeasible point
    is x = 0, flagged infeasible."""
    draws = np.random.default_rng(2).standard_normal(400)

    def evaluate(x):
        p = np.mean(draws > 1.0 - x[0])
        return x[0], 1e-6, [p], [p * (1 - p) / 400 + 1e-6]

    problem = SearchProblem(((0.0, 1.0),), (0.05,), initial=4)
    _, _, found = search(problem, evaluate, 8)
    assert not found.feasible
    assert found.point[0] < 0.1


def test_constraint_confidence():
    """The combined standard deviation adds the (Jeffreys-adjusted) binomial and surrogate variances; a
    probability at its bound has confidence 1/2."""
    s, c = constraint_confidence(0.05, 100, 0.05, 0.01)
    tilde = 5.5 / 101
    assert s == pytest.approx(math.sqrt(tilde * (1 - tilde) / 100 + 1e-4))
    assert c == pytest.approx(0.5)
    assert constraint_confidence(0.0, 400, 0.05, 0.0)[1] > 0.99


def _settings(**extra):
    base = dict(variables=(("top_speed", 80 * RPM, 120 * RPM), ("weight_on_bit", 80e3, 100e3)),
                constraints=(("buckling", 0.05), ("stick_slip", 0.5)), samples=2, points=4, initial=3, t_end=0.6,
                output_step=0.05, sigma=5e3)
    return opt.OptimizationSettings(**(base | extra))


def test_search_on_the_simulator_resumes_to_the_same_answer(small_case, tmp_path):
    """drillstring.optimize writes its results file, dataset and figure; a search whose last batch (of 2
    points) was interrupted after its first point (the second's realizations set back to pending) reruns only
    those and ends with the same design and answer; a store of other settings (samples, batch) is refused by
    its fingerprint."""
    import json

    import zarr

    import drillstring
    from drillstring.operating_point import optimization_settings
    from drillstring.stochastic.execution import Engine

    arguments = dict(variables={"top_speed": "80 rpm:120 rpm", "weight_on_bit": "80 kN:100 kN"},
                     constraints={"buckling": 0.05, "stick_slip": 0.5}, samples=2, points=5, initial=3, batch=2,
                     t_end=0.6, output_step=0.05, sigma=5e3, out=tmp_path, workers=1)
    first = drillstring.optimize(small_case, **arguments)
    summary = first.summary
    assert summary["realizations"] == 10 and not summary["failures"]
    assert summary["recommended"]["values"] in summary["design"]
    assert json.loads((tmp_path / "optimize.json").read_text())["recommended"] == summary["recommended"]
    assert (tmp_path / "optimize.png").stat().st_size > 20_000
    assert first.dataset.mean_rate_of_penetration.shape == (5, 2)
    point = summary["recommended"]["point"]
    assert first.dataset.objective_estimate[point] == pytest.approx(
        float(first.dataset.mean_rate_of_penetration[point].mean()))
    zarr.open_group(str(tmp_path / "optimize.zarr"), mode="a")["status"][8:10] = 0
    settings = optimization_settings(small_case, **{k: v for k, v in arguments.items() if k not in ("out", "workers")})
    again = opt.run_optimization(small_case, settings, tmp_path / "optimize.zarr", Engine(workers=1),
                                 finish=lambda run: opt.optimization_result(run.store))
    assert again.computed == 2
    for key in ("design", "estimates", "recommended"):
        assert again.result[key] == summary[key]
    for change in ({"samples": 3}, {"batch": 1}):
        with pytest.raises(ValueError, match="holds a different optimization"):
            opt.run_optimization(small_case, optimization_settings(small_case, **(
                {k: v for k, v in arguments.items() if k not in ("out", "workers")} | change)),
                tmp_path / "optimize.zarr", Engine(workers=1))


@pytest.mark.parametrize("extra, message", [
    ({"variables": (("top_speed", 120 * RPM, 80 * RPM),)}, "reversed or equal"),
    ({"constraints": (("buckling", 1.5),)}, r"must be a probability in \(0, 1\)"),
    ({"objective": "rate_of_penetration_q0"}, "rate_of_penetration_qNN"),
    ({"model_dispersion": (0.0, 1.2, 0.0)}, "stiffness_dispersion"),
    ({"variables": (("weight_on_bit", 8e4, 9e4), ("weight_on_hook", 1e5, 2e5))}, "give one of them"),
    ({"points": 2}, r"points = 2: must be an integer from initial = 3 to 200"),
    ({"points": 100_000_000}, r"points = 100000000: must be an integer from initial = 3 to 200"),
    ({"initial": 100_000}, r"initial = 100000: must be an integer from 2 to 200"),
    ({"samples": 10**9}, r"samples = 1000000000: must be an integer from 2 to 1000"),
    ({"batch": 0}, r"batch = 0: must be an integer from 1 to 200"),
    ({"batch": 2.0}, "batch = 2.0: must be an integer"),
    ({"probability_mean": "quadratic"}, "probability_mean = 'quadratic': must be one of constant, linear"),
])
def test_bad_settings_are_refused_in_one_line(extra, message):
    with pytest.raises((ValueError, TypeError), match=message) as error:
        _settings(**extra)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("extra, message", [
    ({"variables": (("top_drive.proportional_gain", 1.0, 10.0),)}, "the case cannot vary it"),
    ({"variables": (("top_drive.inertia", 1.0, 10.0),)}, "the case cannot vary it"),
    ({"variables": (("operation.top_sped", 1.0, 10.0),)}, "the case cannot vary it"),
    ({"constraints": (("bucklin", 0.1),)}, "the event must be one of"),
    ({"constraints": (("surface_torque_amplitude>8000", 0.1),)}, "an output of a top drive only"),
    ({"constraints": (("torque>8000", 0.1),)}, "no per-realization output"),
    ({"variables": (("weight_on_bit", 8e4, 1e9),)}, "weight_on_bit"),
])
def test_a_variable_the_case_cannot_vary_is_refused(small_case, extra, message):
    with pytest.raises(ValueError, match=message) as error:
        opt.check_optimization(small_case, _settings(**extra))
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("argv, message", [
    (["--vary", "top_speed=140:60"], "reversed or equal"),
    (["--vary", "proportional_gain=1:100"], "the case cannot vary it"),
    (["--vary", "top_speed=60:140", "-c", "buckling<=1.5"], "probability in (0, 1)"),
    (["--vary", "top_speed=60:140", "-p", "uncertainty.model.stiffness_dispersion=2"], "stiffness_dispersion"),
    (["--vary", "top_speed"], "NAME=LOW:HIGH"),
    (["--vary", "top_speed=60:140", "--batch", "0"], "--batch = 0: must be an integer from 1 to 200"),
    (["--vary", "top_speed=60:140", "--points", "100000000"], "--points = 100000000: must be an integer from "
                                                               "--initial = 4 to 200"),
    (["--vary", "top_speed=60:140", "--initial", "100000"], "--initial = 100000: must be an integer from 2 to 200"),
    (["--vary", "top_speed=60:140", "--samples", "100000000"], "--samples = 100000000: must be an integer from 2 "
                                                                "to 1000"),
    (["--vary", "top_speed=60:140", "--probability-mean", "cubic"], "--probability-mean = 'cubic'"),
    ([], "give at least one decision variable"),
])
def test_cli_refuses_bad_input_in_one_line_with_exit_2(tmp_path, argv, message):
    from typer.testing import CliRunner

    from drillstring.cli import app

    result = CliRunner().invoke(app, ["optimize", "reference", *argv, "--out", str(tmp_path / "o")])
    assert result.exit_code == 2, result.output
    assert message in result.stderr and "Traceback" not in result.output
    assert len(result.stderr.strip().splitlines()) == 1


def test_points_equal_to_initial_runs_the_initial_design_and_writes_a_report(small_case, tmp_path):
    """``--points`` equal to ``--initial`` is accepted (the initial design alone, its best point the answer); with
    no ``--constraint`` no constraints table is printed; the run writes report.html (the search, the answer, the
    design points, the figure inline)."""
    from typer.testing import CliRunner

    from drillstring.cli import app

    case = tmp_path / "small.toml"
    case.write_text(small_case.to_toml(), encoding="utf-8")
    out = tmp_path / "o"
    result = CliRunner().invoke(app, ["optimize", str(case), "--vary", "top_speed=80:120", "--initial", "3",
                                      "--points", "3", "--samples", "2", "--t-end", "0.6", "--workers", "1",
                                      "--out", str(out)], env={"COLUMNS": "120", "DRILLSTRING_UNITS": None})
    assert result.exit_code == 0, result.output
    assert "Chance constraints" not in result.stdout and "event" not in result.stdout
    assert f"report: {out / 'report.html'}" in result.stdout
    page = (out / "report.html").read_text(encoding="utf-8")
    for part in ("<h2>Search</h2>", "<h2>Answer</h2>", "<h2>Design points</h2>", "data:image/png;base64,",
                 "top_speed (operation.top_speed)"):
        assert part in page
    assert "Chance constraints at the answer" not in page
    assert page.count("<tr") - page.count("<tr><th") >= 3  # a row per design point


def test_a_search_notes_each_batch_the_surrogates_choose_and_resumes_after_ctrl_c(small_case, tmp_path):
    """Between the passes of the engine, a note says which design points the surrogates are choosing (the
    progress of a search whose surrogates take long). Ctrl-C there (a KeyboardInterrupt from the note) stops the
    search with the initial design kept: the rerun computes only the two points left."""
    from drillstring.stochastic.execution import Engine

    def interrupt(text: str) -> None:
        raise KeyboardInterrupt

    settings = _settings(variables=(("top_speed", 80 * RPM, 120 * RPM),), points=5, initial=3, batch=1)
    with pytest.raises(KeyboardInterrupt):
        opt.run_optimization(small_case, settings, tmp_path / "optimize.zarr", Engine(workers=1, note=interrupt))
    notes: list[str] = []
    run = opt.run_optimization(small_case, settings, tmp_path / "optimize.zarr", Engine(workers=1, note=notes.append))
    assert run.computed == 2 * settings.samples
    assert notes == ["design point 4 of 5: chosen by the surrogates fitted to 3 points",
                     "design point 5 of 5: chosen by the surrogates fitted to 4 points"]


def test_point_estimates_from_realizations():
    """Per design point, over its finished realizations only: the mean objective and its variance/n, a
    quantile objective (as numpy's quantile, with a positive bootstrap variance), an MSE left undefined when a
    finished realization has none, and each probability k/n with the Jeffreys-adjusted variance."""
    rng = np.random.default_rng(0)
    samples, points = 6, 3
    rop = rng.uniform(1e-3, 5e-3, points * samples)
    stick = np.tile([0.0, 0.2, 0.0, 0.0, 0.5, 0.0], points)
    status = np.ones(points * samples, dtype=np.int8)
    status[samples + 1] = 2  # a failed realization of point 1: left out
    mse = np.full(points * samples, 1e8)
    mse[2 * samples + 3] = np.nan  # point 2: one finished realization without penetration
    arrays = {"mean_rate_of_penetration": rop, "stick_time_fraction": stick, "mechanical_specific_energy": mse,
              "lowest_lateral_eigenvalue": np.ones(points * samples)}
    outputs = tuple(arrays)
    settings = _settings(constraints=(("stick_slip", 0.1), ("mean_rate_of_penetration<0.002", 0.2)), samples=samples,
                         points=points, initial=2)
    found = opt.point_estimates(settings, arrays, status, outputs)
    assert list(found["count"]) == [6, 5, 6]
    kept = np.delete(rop[samples:2 * samples], 1)
    assert found["objective"][1] == pytest.approx(kept.mean())
    assert found["objective_variance"][1] == pytest.approx(kept.var(ddof=1) / 5)
    hits = np.delete(stick[samples:2 * samples], 1) > 0
    assert found["probabilities"][1, 0] == pytest.approx(hits.mean())
    assert found["probability_variances"][1, 0] == pytest.approx((hits.sum() + 0.5) / 6 * (1 - (hits.sum() + 0.5) / 6) / 5)
    assert found["probabilities"][0, 1] == pytest.approx(np.mean(rop[:samples] < 0.002))
    quantile = opt.point_estimates(_settings(objective="rate_of_penetration_q10", samples=samples, points=points,
                                             initial=2), arrays, status, outputs)
    assert quantile["objective"][0] == pytest.approx(np.quantile(rop[:samples], 0.1))
    assert np.all(quantile["objective_variance"] > 0)
    energy = opt.point_estimates(_settings(objective="mechanical_specific_energy", samples=samples, points=points,
                                           initial=2), arrays, status, outputs)
    assert energy["objective"][0] == pytest.approx(1e8) and np.isnan(energy["objective"][2])
