import numpy as np
import pytest

from drillstring.dynamics.simulate import SimulationResult
from drillstring.results import read_netcdf, run_dataset, write_netcdf


@pytest.fixture
def result():
    t = np.linspace(0, 1, 11)
    names = ["rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit", "bit_depth",
             "nodes_in_contact", "contact_force"]
    return SimulationResult(
        time=t, observables={n: np.sin(t + i) for i, n in enumerate(names)},
        radial_displacement=np.c_[t, 2 * t], lateral_displacement=np.stack([np.c_[t, 0 * t], np.c_[0 * t, 2 * t]], -1),
        probe_positions=np.array([1500.0, 1560.0]),
        probe_gaps=np.array([0.03, 0.035]), impacts=3, status="success", message="",
        stats={"n_rhs": 10, "wall_time": 0.1},
    )


def test_dataset_names_units_and_roundtrip(result, tmp_path):
    ds = run_dataset(result, case_toml="name = 'x'", extra_attrs={"weight_on_bit": 1e5})
    assert ds.rate_of_penetration.attrs["units"] == "m/s"
    assert ds.torque_on_bit.attrs["units"] == "N m"
    assert ds.radial_displacement.dims == ("time", "probe")
    assert ds.lateral_displacement.dims == ("time", "probe", "direction")
    assert ds.contact_force.attrs["units"] == "N"
    np.testing.assert_array_equal(ds.lateral_displacement.sel(direction="z").values[:, 1], 2 * result.time)
    np.testing.assert_array_equal(ds.x.values, [1500.0, 1560.0])
    assert ds.attrs["solver_n_rhs"] == 10 and ds.attrs["impacts"] == 3
    back = read_netcdf(write_netcdf(ds, tmp_path / "sub" / "run.nc"))
    np.testing.assert_array_equal(back.bit_speed.values, ds.bit_speed.values)
    assert back.attrs["case"] == "name = 'x'"
    assert back.radial_displacement.attrs["units"] == "m"
