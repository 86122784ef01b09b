"""Monte Carlo studies of a case turned by a top drive: the quill speed and the surface torque stored per
realization, their statistics, dispersion rows, figures and per-realization metrics, checked against the
stored histories; with an imposed speed the store is unchanged."""

import json
import math

import numpy as np
import pytest
import zarr

from drillstring.dynamics.indicators import TOP_DRIVE_METRICS, steady_window, top_drive_metrics
from drillstring.quantities import STUDY_OBSERVABLES, TOP_DRIVE_OBSERVABLES, stored_observables
from drillstring.stochastic import execution
from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic.analysis import load_study, study_statistics, study_summary
from drillstring.stochastic.store import DONE

#: A PI top drive on the small reference string (gains of the order of a stiff speed controller).
PI_DRIVE = {"controller": "pi", "inertia": 1000.0, "proportional_gain": 2000.0, "integral_gain": 5000.0}


def _with_top_drive(case, **fields):
    return case.model_copy(update={"top_drive": case.top_drive.model_copy(update=fields)})


@pytest.fixture(scope="module")
def top_drive_study(small_case, tmp_path_factory):
    """Four realizations of 2 s of the small string under a PI top drive, its raw data and statistics."""
    case = _with_top_drive(small_case, **PI_DRIVE)
    settings = mc.StudySettings(laws=(mc.weight_on_hook_normal(case, 5000.0),), samples=4, seed=3, t_end=2.0,
                                output_step=0.02)
    path = tmp_path_factory.mktemp("top_drive") / "study.zarr"
    run = mc.run_study(case, settings, path, execution.Engine(workers=1))
    assert run.failed == 0
    raw = load_study(path)
    return case, settings, path, raw, study_statistics(raw)


def test_top_drive_metrics_of_a_known_signal():
    t = np.linspace(0.0, 20.0, 2001)  # every 0.01 s: the extremes of the 1 Hz sine are samples
    torque = 8e3 + 3e3 * np.sin(2.0 * np.pi * t)
    torque[t < 5.0] = 50e3  # a start-up transient that must be left out
    speed = 10.0 + 0.5 * np.cos(2.0 * np.pi * t)
    speed[t < 5.0] = 0.0
    out = top_drive_metrics(t, {"surface_torque": torque, "quill_speed": speed}, 5.0)
    assert set(out) == set(TOP_DRIVE_METRICS)
    assert out["surface_torque_amplitude"] == pytest.approx(3e3, rel=1e-12)
    assert out["quill_speed_min"] == pytest.approx(9.5, rel=1e-12)
    assert out["quill_speed_max"] == pytest.approx(10.5, rel=1e-12)
    nothing = top_drive_metrics(t, {"surface_torque": np.full_like(t, np.nan), "quill_speed": speed}, 5.0)
    assert math.isnan(nothing["surface_torque_amplitude"]) and nothing["quill_speed_max"] == pytest.approx(10.5)


def test_imposed_speed_store_has_no_top_drive_arrays(small_case, tmp_path):
    assert small_case.top_drive.controller == "imposed_speed"
    assert mc.study_observables(small_case) == STUDY_OBSERVABLES
    settings = mc.StudySettings(laws=(mc.weight_on_hook_normal(small_case, 5000.0),), samples=2, t_end=1.0,
                                output_step=0.05)
    store = mc.StudyStore(tmp_path / "imposed.zarr", small_case, settings)
    layout = dict(store.group.attrs["layout"])
    for name in (*TOP_DRIVE_OBSERVABLES, *TOP_DRIVE_METRICS):
        assert name not in layout and f"nominal_{name}" not in layout


def test_top_drive_histories_are_stored_per_realization_and_nominal(top_drive_study):
    case, settings, path, raw, _ = top_drive_study
    assert mc.study_observables(case) == STUDY_OBSERVABLES + TOP_DRIVE_OBSERVABLES
    assert stored_observables(raw) == STUDY_OBSERVABLES + TOP_DRIVE_OBSERVABLES
    group = zarr.open_group(str(path), mode="r")
    for name in TOP_DRIVE_OBSERVABLES:
        assert group[name].shape == (settings.samples, len(settings.time))
        assert np.all(np.isfinite(group[name][:])) and np.all(np.isfinite(group[f"nominal_{name}"][:]))
    # the quill is driven, not imposed: its speed varies in time (starting from rest) and between draws
    quill = raw["quill_speed"].values
    assert np.ptp(quill[0]) > 0.1 * case.operation.top_speed
    assert np.ptp(raw["surface_torque"].values[:, -1]) > 0.0
    # the nominal run is the mean draw: its own history, not one of the realizations'
    assert not any(np.array_equal(raw["nominal_surface_torque"].values, row) for row in raw["surface_torque"].values)


def test_top_drive_statistics_equal_those_of_the_stored_histories(top_drive_study):
    _, _, _, raw, stats = top_drive_study
    ok = raw.status.values == DONE
    for name in TOP_DRIVE_OBSERVABLES:
        x = raw[name].values[ok]
        np.testing.assert_allclose(stats[f"{name}_mean"].values, x.mean(axis=0), rtol=1e-13, atol=0)
        np.testing.assert_allclose(stats[f"{name}_std"].values, x.std(axis=0, ddof=1), rtol=1e-12, atol=1e-300)
        lower, upper = np.quantile(x, [0.025, 0.975], axis=0)
        np.testing.assert_allclose(stats[f"{name}_lower"].values, lower, rtol=1e-13)
        np.testing.assert_allclose(stats[f"{name}_upper"].values, upper, rtol=1e-13)
        with np.errstate(invalid="ignore", divide="ignore"):  # the surface torque's mean is 0 at t = 0
            expected = np.where(x.mean(axis=0) != 0.0, x.std(axis=0, ddof=1) / np.abs(x.mean(axis=0)), np.nan)
        np.testing.assert_allclose(stats[f"{name}_dispersion"].values, expected, rtol=1e-12)
        np.testing.assert_array_equal(stats[f"{name}_nominal"].values, raw[f"nominal_{name}"].values)
        assert stats[f"{name}_convergence"].size == ok.sum()


def test_top_drive_metrics_per_realization_from_the_stored_histories(top_drive_study):
    _, settings, _, raw, stats = top_drive_study
    t = raw.time.values
    for t_transient in (None, 0.5):  # the workers' window (stored), and another one (recomputed)
        found = stats if t_transient is None else study_statistics(raw, t_transient=t_transient)
        window = steady_window(t, mc.metrics_transient(settings) if t_transient is None else t_transient)
        for j in found.realization.values:
            torque = raw["surface_torque"].values[j][window]
            quill = raw["quill_speed"].values[j][window]
            assert found["realization_surface_torque_amplitude"].sel(realization=j) == pytest.approx(
                0.5 * (torque.max() - torque.min()), rel=1e-12)
            assert found["realization_quill_speed_min"].sel(realization=j) == pytest.approx(quill.min(), rel=1e-12)
            assert found["realization_quill_speed_max"].sel(realization=j) == pytest.approx(quill.max(), rel=1e-12)
        nominal = raw["nominal_surface_torque"].values[window]
        assert found["realization_surface_torque_amplitude"].attrs["nominal"] == pytest.approx(
            0.5 * (nominal.max() - nominal.min()), rel=1e-12)


def test_top_drive_rows_in_the_summary_and_figures(top_drive_study, tmp_path):
    from drillstring.plots import plot_dispersion, plot_envelopes

    _, settings, _, _, stats = top_drive_study
    summary = study_summary(stats, t_transient=mc.metrics_transient(settings))
    assert list(summary["observables"]) == list(STUDY_OBSERVABLES + TOP_DRIVE_OBSERVABLES)
    window = stats.time.values >= mc.metrics_transient(settings) - 1e-12
    for name in TOP_DRIVE_OBSERVABLES:
        expected = stats[f"{name}_dispersion"].values[window]
        assert summary["observables"][name]["dispersion_max"] == pytest.approx(np.nanmax(expected), rel=1e-12)
        assert name in summary["time_convergence"]["observables"]
    amplitude = stats["realization_surface_torque_amplitude"].values
    entry = summary["realizations"]["surface_torque_amplitude"]
    assert entry["mean"] == pytest.approx(amplitude.mean(), rel=1e-12) and entry["n"] == amplitude.size
    assert entry["unit"] == "N m"
    json.dumps(summary, allow_nan=True)
    from rich.console import Console

    from drillstring.cli import _realizations_table, _study_table

    console = Console(width=250, record=True)
    console.print(_study_table(summary), _realizations_table(summary))
    text = console.export_text()
    for label in ("quill speed", "surface torque", "surface torque amplitude", "quill speed min", "quill speed max"):
        assert label in text
    for plot in (plot_envelopes, plot_dispersion):
        path = plot(stats, tmp_path / f"{plot.__name__}.png", **({"t_transient": 1.0}
                                                                  if plot is plot_dispersion else {}))
        assert path.stat().st_size > 0


def test_maps_give_the_surface_torque_amplitude_with_a_top_drive(small_case, tmp_path):
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model
    from drillstring.stochastic import operating_map as om
    from drillstring.stochastic import probabilistic_map as pm
    from drillstring.stochastic.parameters import with_parameters
    from drillstring.stochastic.runs import simulation_options

    grid = om.MapSettings(top_speed=(8.0, 12.0), weight_on_bit=(9e4,), t_end=2.0, output_step=0.02)
    imposed = om.MapStore(tmp_path / "imposed" / "map.zarr", small_case, grid, 1e5)
    assert "surface_torque_amplitude" not in dict(imposed.group.attrs["layout"])
    case = _with_top_drive(small_case, **PI_DRIVE)
    om.run_map(case, grid, tmp_path / "map.zarr", execution.Engine(workers=1))
    found = om.map_dataset(tmp_path / "map.zarr")
    assert found["surface_torque_amplitude"].attrs["units"] == "N m"
    # the point's amplitude is (max − min)/2 of the surface torque of the same run simulated here
    point = with_parameters(case, {"operation.top_speed": 12.0, "operation.weight_on_bit": 9e4})
    result = simulate_model(case_reduced_model(point), **simulation_options(point, grid.t_end, grid.output_step))
    torque = np.asarray(result.observables["surface_torque"])[steady_window(result.time, grid.transient)]
    assert float(found["surface_torque_amplitude"].sel(top_speed=12.0, weight_on_bit=9e4)) == pytest.approx(
        0.5 * (torque.max() - torque.min()), rel=1e-9)

    sampled = pm.SampledMapSettings(grid, samples=2, seed=5, sigma=3000.0)
    pm.run_sampled_map(case, sampled, tmp_path / "sampled" / "map.zarr", execution.Engine(workers=1))
    ds = pm.sampled_map_dataset(tmp_path / "sampled" / "map.zarr")
    per_sample = ds["surface_torque_amplitude"].values
    assert np.all(np.isfinite(per_sample)) and np.all(per_sample > 0.0)
    np.testing.assert_allclose(ds["surface_torque_amplitude_mean"].values, per_sample.mean(axis=2), rtol=1e-14)
    summary = pm.sampled_map_summary(ds)
    assert summary["surface_torque_amplitude_mean"] == ds["surface_torque_amplitude_mean"].values.tolist()
