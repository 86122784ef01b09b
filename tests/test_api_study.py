"""The study API: one set of defaults and checks, its files, the study's computation time kept."""

import json

import numpy as np
import pytest

from drillstring import api
from drillstring.results import read_netcdf
from drillstring.stochastic import DEFAULT_SIGMA
from drillstring.stochastic.store import FAILED
from drillstring.dynamics.indicators import transient_end


def test_study_files_defaults_and_rerun(small_case, tmp_path):
    out = tmp_path / "s"
    first = api.monte_carlo_study(small_case, samples=3, t_end=0.6, workers=1, out=out)
    summary = first.summary
    assert summary["sigma"] == DEFAULT_SIGMA and summary["t_transient"] == transient_end(0.6) == 0.3
    assert first.already == 0 and summary["realizations_this_run"] == 3
    assert json.loads((out / "summary.json").read_text()) == summary
    assert set(first.files) == {"store", "summary", "statistics", "report", "envelopes", "dispersion",
                                "convergence", "realizations", "interactive"}
    assert all(path.exists() for path in first.files.values())
    stored = read_netcdf(out / "statistics.nc")
    np.testing.assert_array_equal(stored.rate_of_penetration_mean.values,
                                  first.statistics.rate_of_penetration_mean.values)
    html = (out / "report.html").read_text()
    assert f"{summary['wall_time']:.2f}".rstrip("0").rstrip(".") in html

    again = api.monte_carlo_study(small_case, samples=3, t_end=0.6, workers=1, out=out)
    assert again.already == 3 and again.summary["realizations_this_run"] == 0
    assert again.summary["wall_time"] == summary["wall_time"]  # the computation time, not the rerun's
    assert again.summary["wall_time_this_run"] < summary["wall_time"]
    assert "wall time of this run [s]" in (out / "report.html").read_text()
    stats = api.study(small_case, samples=3, t_end=0.6, workers=1, out=out)
    np.testing.assert_array_equal(stats.bit_speed_std.values, first.statistics.bit_speed_std.values)


def test_study_stages_and_a_rerun_that_computes_nothing_keeps_its_figures(small_case, tmp_path):
    """After the realizations, ``stage`` is told what runs (the store, the statistics, the figures, the
    report); a rerun that computes nothing finds its figures current and does not draw them again; another
    unit system (or window) draws them again."""
    out = tmp_path / "s"
    stages = []
    first = api.monte_carlo_study(small_case, samples=3, t_end=0.6, workers=1, out=out, stage=stages.append)
    assert stages == ["reading the store", "statistics", "figures", "report"]
    figures = {name: first.files[name] for name in ("convergence", "envelopes", "dispersion", "realizations")}
    drawn = {name: path.stat().st_mtime_ns for name, path in figures.items()}
    stages.clear()
    again = api.monte_carlo_study(small_case, samples=3, t_end=0.6, workers=1, out=out, stage=stages.append)
    assert stages == ["reading the store", "statistics", "report"]
    assert {name: again.files[name] for name in figures} == figures
    assert {name: path.stat().st_mtime_ns for name, path in figures.items()} == drawn
    assert again.summary["observables"] == first.summary["observables"]
    for changed in (dict(units="field"), dict(transient=0.4)):
        stages.clear()
        api.monte_carlo_study(small_case, samples=3, t_end=0.6, workers=1, out=out, stage=stages.append, **changed)
        assert "figures" in stages, changed
    (out / "envelopes.png").unlink()  # a figure gone: drawn again
    stages.clear()
    api.monte_carlo_study(small_case, samples=3, t_end=0.6, workers=1, out=out, stage=stages.append, transient=0.4)
    assert "figures" in stages and (out / "envelopes.png").is_file()


@pytest.mark.parametrize("kwargs, message", [
    (dict(samples=1), "^samples = 1: must be an integer >= 2"),
    (dict(sigma=1e6), r"^sigma = 1e\+06 N: .*probability"),
    (dict(sigma=1.0, dispersion=0.01), "not both"),
    (dict(dispersion=float("nan")), "^dispersion = nan: must be a finite number > 0"),
    (dict(t_end=float("inf")), "^t_end = inf s"),
    (dict(transient=2.0), r"^transient = 2.0 s: must be a number in \[0, t_end = 1 s\)"),
    (dict(transient=1.0), r"^transient = 1.0 s: must be a number in \[0, t_end = 1 s\)"),
    (dict(workers=0), "^workers = 0"),
    (dict(workers=2, scheduler="tcp://127.0.0.1:1"), "not both"),
])
def test_impossible_settings_refused_before_anything(small_case, tmp_path, kwargs, message):
    kwargs = {"samples": 2, "t_end": 1.0, **kwargs}
    with pytest.raises(ValueError, match=message):
        api.monte_carlo_study(small_case, out=tmp_path / "s", **kwargs)
    assert not (tmp_path / "s").exists()


def test_output_folder_checked_first(small_case, tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="^out = .*f': is a file, not a folder"):
        api.study(small_case, samples=2, t_end=0.2, out=tmp_path / "f")


def test_study_with_too_few_finished_realizations_fails_with_the_causes(small_case, tmp_path, monkeypatch):
    from drillstring.stochastic import montecarlo

    def fail(case, settings, index):
        return montecarlo.RealizationOutcome(index, 1.0, 1.0, FAILED, f"made to fail {index}")

    monkeypatch.setattr(montecarlo, "run_realization", fail)
    with pytest.raises(api.StudyFailed, match=r"only 0 finished realization\(s\): statistics need at least 2 \(3 failure\(s\): nominal: made to fail -1; 0: made to fail 0"):
        api.monte_carlo_study(small_case, samples=2, t_end=0.2, workers=1, out=tmp_path / "s")


def test_study_counts_buckled_realizations_and_warns_before_running(small_case, tmp_path):
    """2 kN below its critical load with σ = 5 kN, a third of the draws buckle the string (P = Φ(−0.4)):
    the study notes it before running (probability from the weight-on-hook law and the critical
    weight-on-bit), records each realization's lowest lateral eigenvalue, negative exactly for the draws
    beyond the critical weight-on-bit, and counts them in the summary."""
    from scipy.stats import norm

    from drillstring.buckling import case_buckling_margin

    critical = case_buckling_margin(small_case).critical_weight_on_bit  # independent of the weight-on-bit
    case = small_case.model_copy(update={"operation": small_case.operation.model_copy(
        update={"weight_on_bit": critical - 2e3})})
    notes = []
    outcome = api.monte_carlo_study(case, sigma=5000.0, samples=8, t_end=0.4, workers=1, out=tmp_path / "b",
                                    note=notes.append)
    buckling = outcome.summary["buckling"]
    assert buckling["critical_weight_on_bit"] == pytest.approx(critical, rel=1e-9)
    assert buckling["probability"] == pytest.approx(norm.cdf(-0.4), rel=1e-6)
    assert buckling["expected"] == pytest.approx(8 * buckling["probability"])
    assert len(notes) == 1 and "buckles" in notes[0] and buckling["warning"] == notes[0]
    stats = outcome.statistics
    lowest = stats.lowest_lateral_eigenvalue.values
    saved = json.loads((tmp_path / "b" / "summary.json").read_text())["buckling"]
    from drillstring.stochastic.analysis import load_study

    wob = load_study(tmp_path / "b" / "study.zarr").weight_on_bit.values
    assert np.array_equal(lowest < 0, wob > critical)
    assert buckling["buckled_realizations"] == int(np.sum(wob > critical)) == saved["buckled_realizations"] >= 1
    assert "buckled realizations" in (tmp_path / "b" / "report.html").read_text()
    quiet = []
    api.monte_carlo_study(small_case, sigma=3000.0, samples=2, t_end=0.2, workers=1, note=quiet.append)
    assert quiet == []  # P = Φ(−14.1/3) ≈ 1e-6: nothing to say


def test_study_of_any_parameters_summarises_each_input(small_case, tmp_path):
    laws = {"fluid.inlet_velocity": "uniform 1.2 1.8 m/s", "operation.top_speed": "normal 100 5 rpm"}
    outcome = api.monte_carlo_study(small_case, parameters=laws, samples=3, t_end=0.6, workers=1,
                                    out=tmp_path / "s")
    summary = outcome.summary
    assert summary["sigma"] is None and summary["weight_on_hook_dispersion"] is None  # not random
    inputs = summary["inputs"]
    assert list(inputs) == list(laws)
    assert inputs["fluid.inlet_velocity"]["dispersion"] == pytest.approx((0.6 / np.sqrt(12)) / 1.5)
    assert inputs["operation.top_speed"]["dispersion"] == pytest.approx(0.05)
    assert inputs["operation.top_speed"]["law"] == "normal 100 5 rpm" and inputs["operation.top_speed"]["unit"] == "rad/s"
    drawn = outcome.statistics.input_values.values
    assert inputs["fluid.inlet_velocity"]["sample_mean"] == pytest.approx(drawn[:, 0].mean())
    for entry in summary["observables"].values():
        assert set(entry["ratio_time_mean"]) == set(laws)  # one ratio per input, no weight-on-bit
        ratio = entry["ratio_time_mean"]["operation.top_speed"]
        assert ratio == pytest.approx(entry["dispersion_time_mean"] / 0.05)
    html = (tmp_path / "s" / "report.html").read_text()
    assert "random fluid.inlet_velocity, operation.top_speed" in html and "uniform 1.2 1.8 m/s" in html
    assert "mean δ / δ(operation.top_speed)" in html


def test_random_top_speed_cycle_metrics_use_each_realizations_speed(torsional_case, tmp_path):
    """With the top speed random, each realization's stick time (bit below 10 % of *its* top speed), its
    oscillation (max − min)/2Ω and its MSE use the realized speed, not the case's nominal 100 rpm."""
    from drillstring.dynamics.indicators import STICK_SPEED_RATIO, bit_area, mechanical_specific_energy
    from drillstring.stochastic.analysis import load_study

    outcome = api.monte_carlo_study(torsional_case, parameters={"operation.top_speed": "uniform 30 170 rpm"},
                                    samples=4, t_end=20.0, workers=1, out=tmp_path / "s")
    stats = outcome.statistics
    raw = load_study(tmp_path / "s" / "study.zarr")
    speeds = raw.input_values.values[:, 0]
    assert np.ptp(speeds) > 3.0  # rad/s: the draws differ from each other and from 100 rpm
    np.testing.assert_array_equal(stats["realization_top_speed"].values, speeds)
    after = raw.time.values >= 10.0
    for j, omega in enumerate(speeds):
        bit = raw.bit_speed.values[j, after]
        assert stats["realization_stick_time_fraction"].values[j] == np.mean(bit < STICK_SPEED_RATIO * omega)
        assert stats["realization_bit_speed_oscillation"].values[j] == pytest.approx(
            (bit.max() - bit.min()) / (2 * omega), rel=1e-12)
        mse = mechanical_specific_energy(raw.force_on_bit.values[j, after].mean(),
                                         raw.torque_on_bit.values[j, after].mean(), omega,
                                         raw.rate_of_penetration.values[j, after].mean(), bit_area(torsional_case))
        assert stats["realization_mechanical_specific_energy"].values[j] == pytest.approx(mse, rel=1e-12)
    assert outcome.summary["realizations"]["stick_slip_realizations"] == int(
        (stats["realization_stick_time_fraction"].values > 0).sum())


def test_case_file_laws_are_the_default_and_options_replace_them(small_case, tmp_path):
    from drillstring.case import case_from_dict
    import tomllib

    data = tomllib.loads(small_case.to_toml())
    data["uncertainty"] = {"parameters": {"bit_rock.a2": {"law": "gamma", "mean": 5.672e-8, "std": 0.5e-8}}}
    case = case_from_dict(data)
    from drillstring.stochastic.montecarlo import nominal_weight_on_hook

    def woh(sigma):  # the law a sigma declares: the weight-on-hook Normal around the hook load, first
        return ("weight_on_hook", f"normal {nominal_weight_on_hook(case)!r} {sigma:g}")

    settings, bare = api.study_settings(case, samples=2)
    assert settings.laws == (("bit_rock.a2", "gamma mean=5.672e-08 std=5e-09"),)
    assert bare.uncertainty is None and "uncertainty" not in bare.to_toml()
    settings, _ = api.study_settings(case, samples=2, sigma=3000.0)  # the weight-on-hook added
    assert settings.laws == (woh(3000.0), ("bit_rock.a2", "gamma mean=5.672e-08 std=5e-09"))
    settings, _ = api.study_settings(case, samples=2, parameters={"fluid.density": "uniform 1100 1300"})
    assert settings.laws == (("fluid.density", "uniform 1100 1300"),)
    settings, _ = api.study_settings(small_case, samples=2)  # nothing declared: the default law
    assert settings.laws == (woh(DEFAULT_SIGMA),)
    data["uncertainty"] = {"parameters": {"bit_rock.a9": "uniform 1 2"}}
    with pytest.raises(ValueError, match=r"^\[uncertainty\] of the case: unknown case parameter 'bit_rock.a9'"):
        api.study_settings(case_from_dict(data), samples=2)
    with pytest.raises(ValueError, match="weight_on_hook is declared twice"):
        api.study_settings(small_case, samples=2, sigma=1000.0, parameters={"weight_on_hook": "normal 1063 1 kN"})
