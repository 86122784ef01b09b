import numpy as np
import pytest

import drillstring
from drillstring.dynamics.simulate import SimulationError


def test_simulate_returns_dataset_with_case_and_stats(tmp_path):
    ds = drillstring.simulate("reference", t_end=1.0, output_step=0.05)
    assert ds.time.values[-1] == pytest.approx(1.0)
    assert ds.attrs["status"] == "success"
    assert "[[sections]]" in ds.attrs["case"] or "sections" in ds.attrs["case"]
    assert ds.attrs["solver_n_rhs"] > 0
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
