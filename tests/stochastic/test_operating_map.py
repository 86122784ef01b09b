"""Operating maps: the grid grammar, the map against closed-form steady drilling at every linearly stable
point, the buckling margin, resume of an interrupted map, the files."""

import math

import numpy as np
import pytest
import xarray as xr

from drillstring import api
from drillstring.case import DIMENSIONS
from drillstring.stochastic import execution
from drillstring.stochastic import operating_map as om
from drillstring.stochastic.store import DONE, StoreError

DIM = {d.name: d for d in DIMENSIONS}
RPM = math.pi / 30.0


@pytest.mark.parametrize("text, default, expected", [
    ("40:200:17", "rpm", np.linspace(40, 200, 17) * RPM),
    ("40 rpm:200 rpm:3", "", np.array([40, 120, 200]) * RPM),
    ("40:200:3 rpm", "", np.array([40, 120, 200]) * RPM),
    ("4:21:2 rad/s", "rpm", np.array([4.0, 21.0])),
    ("120,100 rpm", "", np.array([100, 120]) * RPM),
    ("100", "rpm", np.array([100 * RPM])),
    ("2 rev/s,60", "rpm", np.array([60 * RPM, 4 * math.pi])),
])
def test_grid_axes(text, default, expected):
    values = om.parse_axis(text, DIM["angular speed"], name="top_speed", default_unit=default)
    np.testing.assert_allclose(values, expected, rtol=1e-12)


def test_grid_axes_in_si_and_force():
    np.testing.assert_array_equal(om.parse_axis("40e3:160e3:13", DIM["force"], name="weight_on_bit"),
                                  np.linspace(40e3, 160e3, 13))
    np.testing.assert_array_equal(om.parse_axis("100 kN,120 kN", DIM["force"], name="weight_on_bit"), [1e5, 1.2e5])
    np.testing.assert_array_equal(om.parse_axis([3.0, 1.0], DIM["force"], name="weight_on_bit"), [1.0, 3.0])


@pytest.mark.parametrize("text, message", [
    ("40:200", "write A:B:N"),
    ("40:200:0", "N = 0 must be an integer >= 1"),
    ("40:200:x", "N = 'x' must be an integer"),
    ("200:40:3", "B must be greater than A"),
    ("40,,60", "write A:B:N"),
    ("40,40", "a value is given twice"),
    ("-40,40", "every value must be a finite number > 0"),
    ("40 m/s:60 m/s:3", "top_speed = '40 m/s:60 m/s:3'"),
])
def test_bad_grid_axes_are_refused_in_one_line(text, message):
    with pytest.raises(ValueError, match=message) as error:
        om.parse_axis(text, DIM["angular speed"], name="top_speed", default_unit="rpm")
    assert "\n" not in str(error.value) and str(error.value).startswith("top_speed = ")


def test_map_of_a_torsional_model_against_steady_drilling(torsional_case, tmp_path):
    """Lateral modes off. At every point where the linearised model says steady drilling is stable, the
    simulated means equal the closed-form steady state (ROP, TOB, FOB) and the bit-speed oscillation has
    died out, both to within the decay e^(growth rate × t_transient) of the start-up transient (or the
    integration tolerance rtol, where the transient has decayed below it); at every point where it is
    unstable, the run ends on a limit cycle instead (oscillation > 0.3)."""
    outcome = api.operating_map(torsional_case, top_speed="60 rpm:180 rpm:3", weight_on_bit="50 kN:110 kN:3",
                                t_end=150.0, output_step=0.05, transient=100.0, workers=1, out=tmp_path / "m")
    ds = outcome.dataset
    assert ds.sizes == {"top_speed": 3, "weight_on_bit": 3} and int(ds.attrs["n_done"]) == 9
    growth = ds.growth_rate.values
    stable, unstable = growth < 0, growth > 0
    assert stable.sum() >= 5 and unstable.sum() >= 2  # both sides of the boundary are on the map
    decay = np.maximum(np.exp(growth * 100.0), torsional_case.simulation.rtol)
    for name in ("rate_of_penetration", "torque_on_bit", "force_on_bit"):
        error = np.abs(ds[f"mean_{name}"].values / ds[f"steady_{name}"].values - 1.0)
        assert np.all(error[stable] <= decay[stable]), (name, error[stable], decay[stable])
    oscillation = ds.bit_speed_oscillation.values
    assert np.all(oscillation[stable] <= decay[stable])
    assert np.all(oscillation[unstable] > 0.3)
    np.testing.assert_allclose(ds.steady_force_on_bit.values, np.broadcast_to(ds.weight_on_bit.values, (3, 3)),
                               rtol=1e-8)  # the rock carries the weight-on-bit (less c1·ROP ~ 1e-4 N)
    # MSE (Teale) from the map's own means
    area = math.pi * torsional_case.borehole.diameter ** 2 / 4
    omega = ds.top_speed.values[:, None]
    expected = (ds.mean_force_on_bit / area + omega * ds.mean_torque_on_bit / (area * ds.mean_rate_of_penetration))
    np.testing.assert_allclose(ds.mechanical_specific_energy.values, expected.values, rtol=1e-12)
    assert ds.attrs["bit_area"] == pytest.approx(area)


def test_buckling_margin_does_not_depend_on_top_speed_or_weight_on_bit(torsional_case):
    """The map computes the critical weight-on-bit once: it is the same at any top speed and any reference
    weight-on-bit (the prestressed lateral stiffness is affine in the weight-on-bit, without gyroscopic
    terms)."""
    from drillstring.buckling import case_buckling_margin
    from drillstring.stochastic.parameters import with_parameters

    reference = case_buckling_margin(torsional_case).critical_weight_on_bit
    for speed, wob in (("40 rpm", "40 kN"), ("200 rpm", "150 kN")):
        other = with_parameters(torsional_case, {"operation.top_speed": speed, "operation.weight_on_bit": wob})
        assert case_buckling_margin(other).critical_weight_on_bit == pytest.approx(reference, rel=1e-9)


def test_an_interrupted_map_resumes_to_the_same_map(torsional_case, tmp_path):
    settings = om.MapSettings(top_speed=(8.0, 12.0, 16.0), weight_on_bit=(6e4, 9e4), t_end=4.0, output_step=0.05)
    whole = om.run_map(torsional_case, settings, tmp_path / "whole.zarr", execution.Engine(workers=1))
    assert whole.completed == 6

    def interrupt_after_two(done, failed, total):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(execution.Interrupted, match="map interrupted after 2 of 6 grid points.*resume"):
        om.run_map(torsional_case, settings, tmp_path / "cut.zarr",
                   execution.Engine(workers=1, progress=interrupt_after_two))
    assert om.MapStore.open_group(tmp_path / "cut.zarr")["status"][:].tolist().count(DONE) == 2
    resumed = om.run_map(torsional_case, settings, tmp_path / "cut.zarr", execution.Engine(workers=2))
    assert resumed.completed == 6 and resumed.computed == 4
    a, b = om.map_dataset(tmp_path / "whole.zarr"), om.map_dataset(tmp_path / "cut.zarr")
    for name in om.MAP_OUTPUTS:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    other = om.MapSettings(top_speed=(8.0, 12.0), weight_on_bit=(6e4, 9e4), t_end=4.0, output_step=0.05)
    with pytest.raises(ValueError, match="holds a different map"):
        om.run_map(torsional_case, other, tmp_path / "cut.zarr", execution.Engine(workers=1))
    with pytest.raises(StoreError, match="not a drillstring map store"):
        om.map_dataset(tmp_path)


def test_map_files_and_refusals(torsional_case, tmp_path):
    out = tmp_path / "m"
    outcome = api.operating_map(torsional_case, top_speed=[8.0, 16.0], weight_on_bit="60,90 kN", t_end=2.0,
                                output_step=0.05, workers=1, out=out)
    assert set(outcome.files) == {"store", "map", "summary", "figure", "stability", "report", "interactive"}
    stored = xr.open_dataset(out / "map.nc", engine="h5netcdf").load()
    assert stored.top_speed.attrs["units"] == "rad/s" and stored.weight_on_bit.attrs["units"] == "N"
    assert stored.mean_rate_of_penetration.attrs["units"] == "m/s"
    assert stored.mechanical_specific_energy.attrs["units"] == "Pa"
    assert stored.mean_rate_of_penetration.dims == ("top_speed", "weight_on_bit")
    critical = stored.attrs["critical_weight_on_bit"]
    np.testing.assert_allclose(stored.buckling_margin.values[0], critical - np.array([6e4, 9e4]))
    assert "Operating map" in (out / "report.html").read_text() and (out / "map.png").stat().st_size > 10_000
    assert (out / "stability.png").stat().st_size > 10_000
    report = (out / "report.html").read_text()
    assert "whose torsional roots all decay" in report and "coexisting cycles" in report
    for family in ("axial", "torsional", "lateral"):  # per-family counts from the stored growth rates
        rates = stored[f"{family}_growth_rate"].values
        counts = outcome.summary["linearly_stable_points_by_family"][family]
        assert counts == {"stable": int(np.sum(rates[np.isfinite(rates)] < 0)),
                          "unstable": int(np.sum(rates[np.isfinite(rates)] >= 0))}
    assert np.isnan(stored["lateral_growth_rate"].values).all()  # no lateral modes in this case
    np.testing.assert_array_equal(stored["torsional_growth_rate"].values, stored["growth_rate"].values)
    coexisting = (stored["torsional_growth_rate"] < 0) & (stored["axial_growth_rate"] < 0) & (
        stored["stick_time_fraction"] > 0) & (stored["stick_time_fraction"] < 1)
    np.testing.assert_array_equal(stored["coexisting_cycles"].values, coexisting.values.astype(float))
    assert outcome.summary["coexisting_cycle_points"] == int(coexisting.sum())
    again = api.operating_map(torsional_case, top_speed=[8.0, 16.0], weight_on_bit="60,90 kN", t_end=2.0,
                              output_step=0.05, workers=1, out=out)
    assert again.already == 4 and again.summary["points_this_run"] == 0
    with pytest.raises(ValueError, match="weight_on_bit = 2e\\+06 N: every weight-on-bit of the map must be less"):
        api.operating_map(torsional_case, weight_on_bit=[1e5, 2e6], out=tmp_path / "x")
    assert not (tmp_path / "x").exists()
