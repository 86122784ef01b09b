"""Sensitivity runs on the study engine: indices of outputs with known structure, resume, refusals, files."""

import json

import numpy as np
import pytest

from drillstring import api
from drillstring.stochastic import execution
from drillstring.stochastic import sensitivity_study as ss


LAWS = {"operation.weight_on_bit": "uniform 60 90 kN", "operation.top_speed": "uniform 120 180 rpm",
        "contact.shock_stiffness": "uniform 5e7 2e8 N/m"}


@pytest.fixture(scope="module")
def analysed(torsional_case, tmp_path_factory):
    out = tmp_path_factory.mktemp("sens")
    outcome = api.sensitivity(torsional_case, parameters=LAWS, samples=32, t_end=12.0, output_step=0.05,
                              workers=2, out=out)
    return outcome, out


def test_indices_of_outputs_with_known_structure(analysed):
    """Three checks that a wrong design, mapping or analysis would fail:
    - the borehole's shock stiffness cannot act with lateral modes off: every run of a block is bit-for-bit
      the same whatever its value, so both of its indices are exactly 0 for every output;
    - the mean force on bit is the weight-on-bit (the rock carries it): S1 = ST = 1 for the weight-on-bit
      to within the interval, 0 for the top speed;
    - every output is explained by the other two parameters: the totals of WOB and top speed sum to >= 1."""
    outcome, _ = analysed
    result = outcome.result
    k = result.parameters.index("contact.shock_stiffness")
    assert np.all(result.S1[:, k] == 0.0) and np.all(result.ST[:, k] == 0.0)
    fob = result.outputs.index("mean_force_on_bit")
    w, s = result.parameters.index("operation.weight_on_bit"), result.parameters.index("operation.top_speed")
    assert abs(result.S1[fob, w] - 1.0) <= max(result.S1_conf[fob, w], 1e-3)
    assert abs(result.ST[fob, w] - 1.0) <= result.ST_conf[fob, w] and abs(result.ST[fob, s]) < 1e-6
    rop = result.outputs.index("mean_rate_of_penetration")
    assert result.ST[rop, w] + result.ST[rop, s] >= 1.0 - result.ST_conf[rop, w] - result.ST_conf[rop, s]
    assert result.convergence_samples == (8, 16, 32)


def test_sensitivity_files(analysed):
    outcome, out = analysed
    payload = json.loads((out / "sensitivity.json").read_text())
    assert payload == outcome.payload
    assert list(payload["parameters"]) == list(LAWS) and payload["runs"] == 32 * 5
    entry = payload["outputs"]["mean_rate_of_penetration"]
    for kind in ("S1", "ST", "S1_ci", "ST_ci"):
        assert set(entry[kind]) == set(LAWS)
    assert set(payload["outputs"]) == set(ss.SENSITIVITY_OUTPUTS)
    for name in ("sobol.png", "sobol_convergence.png", "report.html", "interactive.html", "sensitivity.zarr"):
        assert (out / name).exists(), name
    assert "Sobol" in (out / "report.html").read_text()


def test_an_interrupted_sensitivity_run_resumes_to_the_same_runs(torsional_case, tmp_path):
    settings = ss.SensitivitySettings(8, (("operation.top_speed", "uniform 120 180 rpm"),), t_end=2.0,
                                      output_step=0.05)
    ss.run_sensitivity(torsional_case, settings, tmp_path / "whole.zarr", execution.Engine(workers=1))

    def interrupt(done, failed, total):
        if done == 5:
            raise KeyboardInterrupt

    with pytest.raises(execution.Interrupted, match="after 5 of 24 runs"):
        ss.run_sensitivity(torsional_case, settings, tmp_path / "cut.zarr",
                           execution.Engine(workers=1, progress=interrupt))
    resumed = ss.run_sensitivity(torsional_case, settings, tmp_path / "cut.zarr", execution.Engine(workers=1))
    assert resumed.computed == 19 and resumed.completed == 24
    a, b = ss.load_sensitivity(tmp_path / "whole.zarr"), ss.load_sensitivity(tmp_path / "cut.zarr")
    for name in ss.SENSITIVITY_OUTPUTS:
        np.testing.assert_array_equal(a.outputs[name], b.outputs[name], err_msg=name)


@pytest.mark.parametrize("kwargs, message", [
    (dict(parameters={"operation.top_speed": "uniform 60 140 rpm"}, samples=100), "samples = 100: must be a power of 2"),
    (dict(parameters={}), "no uncertain parameter"),
    (dict(parameters={"operation.top_speed": "normal 100 40 rpm"}), r"probability 0\.00621 outside .* at most 1e-06"),
    (dict(parameters={"operation.top_speed": "normal 100 5 rpm", "weight_on_hook": "normal 1063 5 kN"},
          correlation=None), None),
])
def test_bad_sensitivity_settings_are_refused_before_anything(torsional_case, tmp_path, kwargs, message):
    if message is None:  # correlated parameters, through the case file's table
        import tomllib

        from drillstring.case import case_from_dict

        data = tomllib.loads(torsional_case.to_toml())
        data["uncertainty"] = {"parameters": kwargs["parameters"], "correlation": {
            "parameters": list(kwargs["parameters"]), "matrix": [[1, 0.5], [0.5, 1]]}}
        with pytest.raises(ValueError, match="Sobol' indices need independent parameters"):
            api.sensitivity(case_from_dict(data), out=tmp_path / "s")
    else:
        kwargs.pop("correlation", None)
        with pytest.raises(ValueError, match=message):
            api.sensitivity(torsional_case, out=tmp_path / "s", **kwargs)
    assert not (tmp_path / "s").exists()
