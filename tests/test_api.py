import tomllib
import typing

import numpy as np
import pytest

import drillstring
from drillstring.case import Simulation, case_from_dict
from drillstring.dynamics.simulate import SimulationError


def test_simulate_returns_dataset_with_case_and_stats(tmp_path):
    ds = drillstring.simulate("reference", t_end=1.0, output_step=0.05)
    assert ds.time.values[-1] == pytest.approx(1.0)
    assert ds.attrs["status"] == "success"
    # the stored case is the whole case: read back, it equals the one simulated
    assert case_from_dict(tomllib.loads(ds.attrs["case"])) == drillstring.load_case("reference")
    assert ds.attrs["solver_n_rhs"] > 0
    assert ds.attrs["solver_wall_time"] > 0 and ds.attrs["solver_compile_time"] >= 0
    assert float(ds.x[0]) == 1560.0
    assert np.all(np.isfinite(ds.rate_of_penetration))


def test_simulate_failure_keeps_partial_dataset():
    case = drillstring.load_case("reference")
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"max_steps": 30})})
    with pytest.raises(SimulationError) as info:
        drillstring.simulate(case, t_end=2.0)
    assert info.value.dataset.attrs["status"] == "failed"
    assert 0 < info.value.dataset.sizes["time"] < 41
    ds = drillstring.simulate(case, t_end=2.0, raise_on_failure=False)
    assert ds.attrs["status"] == "failed" and "t =" in ds.attrs["message"]


#: Every value the case accepts for ``simulation.method``.
METHODS = typing.get_args(Simulation.model_fields["method"].annotation)


def test_every_simulation_method_runs_through_simulate_and_agrees():
    reference_case = drillstring.load_case("reference")
    assert set(METHODS) == {"dopri5", "bs32", "ark43", "ark32", "erk32"}
    mesh = reference_case.mesh.model_copy(update={"max_element_length": 40.0})
    runs = {}
    for method in METHODS:
        simulation = reference_case.simulation.model_copy(update={"method": method, "rtol": 1e-8})
        case = reference_case.model_copy(update={"mesh": mesh, "simulation": simulation})
        runs[method] = drillstring.simulate(case, t_end=1.0, output_step=0.01)
        assert runs[method].attrs["status"] == "success", method
    # a 3rd-order method takes more steps than the 5th-order one for the same tolerance ...
    assert runs["bs32"].attrs["solver_n_accepted"] > 2 * runs["dopri5"].attrs["solver_n_accepted"]
    # ... and both solve the same equations
    for method in ("bs32", "ark43", "ark32", "erk32"):
        for name in ("rate_of_penetration", "bit_speed", "torque_on_bit"):
            a, b = runs[method][name].values, runs["dopri5"][name].values
            assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(b)), (method, name)  # observed: <= 4e-8
