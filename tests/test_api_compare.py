"""api.compare: case 1 (full nonlinear model) against case 2 (bit–rock + contact) on the same case."""

import math

import numpy as np
import pytest

from drillstring.api import COMPARED_MODELS, COMPARED_OBSERVABLES, compare
from drillstring.api.runs import _difference_numbers
from drillstring.case import load_case
from drillstring.dynamics.simulate import SimulationError

DIFFERENCE_KEYS = ("max_abs_difference", "rms_relative_difference", "mean_full", "mean_bit_and_contact",
                   "mean_difference", "mean_relative_difference")


def _coarse_reference():
    """The reference case on a 40 m mesh with 3 axial, 3 torsional and 4 lateral modes: seconds to run."""
    case = load_case("reference")
    return case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 40.0}),
        "reduced_model": case.reduced_model.model_copy(
            update={"axial_modes": 3, "torsional_modes": 3, "lateral_modes": 4, "lateral_cutoff": 0.0}),
    })


@pytest.fixture(scope="module")
def compared():
    calls = []
    full, reduced, differences = compare(_coarse_reference(), t_end=1.0,
                                         progress=lambda model, t: calls.append((model, t)))
    return full, reduced, differences, calls


def test_runs_both_models_on_the_same_case(compared):
    full, reduced, _, calls = compared
    assert 'nonlinear = "full"' in full.attrs["case"]
    assert 'nonlinear = "bit_and_contact"' in reduced.attrs["case"]
    # everything else equal: the same case once the switch is set back
    assert full.attrs["case"].replace('"full"', '"bit_and_contact"') == reduced.attrs["case"]
    for ds in (full, reduced):
        assert ds.attrs["status"] == "success"
        assert float(ds.time[-1]) == pytest.approx(1.0)
    np.testing.assert_array_equal(full.time.values, reduced.time.values)
    assert {model for model, _ in calls} == set(COMPARED_MODELS)
    assert max(t for model, t in calls if model == "full") == pytest.approx(1.0)


def test_differences_keys_and_wall_times(compared):
    _, _, differences, _ = compared
    assert differences["t_end"] == pytest.approx(1.0)
    assert differences["t_transient"] == pytest.approx(0.5)  # min(10 s, t_end / 2)
    expected = set(COMPARED_OBSERVABLES) | {"radial_displacement_0"}
    assert set(differences["observables"]) == expected
    for name, entry in differences["observables"].items():
        for key in DIFFERENCE_KEYS:
            assert key in entry, (name, key)
    assert differences["observables"]["radial_displacement_0"]["probe_x"] == pytest.approx(1560.0)
    wall = differences["wall_time"]
    assert wall["full"] > 0.0 and wall["bit_and_contact"] > 0.0
    assert wall["ratio"] == pytest.approx(wall["full"] / wall["bit_and_contact"])
    for model in COMPARED_MODELS:
        assert differences["n_rhs"][model] > 0
        assert 0.0 < differences["solver_wall_time"][model] <= wall[model]
    import json

    json.dumps(differences, allow_nan=False)  # JSON-ready: plain floats, no NaN


def test_reference_centred_string_case_1_close_to_case_2(compared):
    """The reference string stays centred (no impact): the kinetic- and strain-energy forces, quadratic and
    cubic in the small lateral motion, hardly change the response."""
    full, reduced, differences, _ = compared
    assert full.attrs["impacts"] == reduced.attrs["impacts"] == 0
    for name in COMPARED_OBSERVABLES:
        entry = differences["observables"][name]
        for key in DIFFERENCE_KEYS:
            assert math.isfinite(entry[key]), (name, key)
        assert entry["rms_relative_difference"] < 1e-6, name
        assert abs(entry["mean_relative_difference"]) < 1e-6, name
        mean = entry["mean_bit_and_contact"]
        assert entry["max_abs_difference"] < 1e-5 * abs(mean), name
    radial = differences["observables"]["radial_displacement_0"]
    assert math.isfinite(radial["max_abs_difference"]) and math.isfinite(radial["rms_relative_difference"])
    assert radial["rms_relative_difference"] < 1e-2
    gap = float(full.gap[0])
    assert radial["max_abs_difference"] < 1e-4 * gap


def test_difference_numbers_on_known_histories():
    t = np.linspace(0.0, 1.0, 11)
    steady = t >= 0.5
    reduced = np.full_like(t, 2.0)
    full = reduced + np.where(steady, 0.1, -0.3)
    numbers = _difference_numbers(full, reduced, steady)
    assert numbers["max_abs_difference"] == pytest.approx(0.3)
    rms = math.sqrt((5 * 0.3**2 + 6 * 0.1**2) / 11)
    assert numbers["rms_relative_difference"] == pytest.approx(rms / 2.0)
    assert numbers["mean_full"] == pytest.approx(2.1)
    assert numbers["mean_bit_and_contact"] == pytest.approx(2.0)
    assert numbers["mean_difference"] == pytest.approx(0.1)
    assert numbers["mean_relative_difference"] == pytest.approx(0.05)
    zero = _difference_numbers(np.zeros(3), np.zeros(3), np.ones(3, dtype=bool))
    assert zero["max_abs_difference"] == 0.0
    assert zero["rms_relative_difference"] is None and zero["mean_relative_difference"] is None


def test_failed_run_raises_with_the_model_named():
    case = _coarse_reference()
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"max_steps": 30})})
    with pytest.raises(SimulationError) as info:
        compare(case, t_end=1.0)
    assert info.value.nonlinear == "full"  # case 1 runs first
    assert info.value.dataset.attrs["status"] == "failed"
