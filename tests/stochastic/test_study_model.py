"""Each realization's reduced model in a study (stochastic/study_model.py): the parametric model where the random
parameters are covered, a rebuild otherwise; a realization's outputs against the rebuilding recipe."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from drillstring.dynamics.reduced.parametric import ParametricReducedModel
from drillstring.dynamics.rom import case_reduced_model
from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic import study_model
from drillstring.stochastic.store import DONE


def settings(case, laws, **kwargs):
    return mc.StudySettings(laws=laws, **{"samples": 4, "seed": 3, "t_end": 1.0, "output_step": 0.05, **kwargs})


def test_coverage_names_the_parameter_outside(small_case):
    covered = settings(small_case, (mc.weight_on_hook_normal(small_case, 5000.0), ("bit_rock.a2", "normal 5.6e-8 1e-9"),
                                    ("contact.friction_coefficient", "uniform 0.0004 0.0006")))
    assert study_model.coverage(small_case, mc.study_uncertainty(small_case, covered)) is None
    geometry = settings(small_case, (mc.weight_on_hook_normal(small_case, 5000.0),
                                     ("sections[0].outer_diameter", "uniform 0.126 0.128")))
    reason = study_model.coverage(small_case, mc.study_uncertainty(small_case, geometry))
    assert reason is not None and "sections[0].outer_diameter" in reason and "rebuilt" in reason


def test_weight_on_bit_range_of_a_normal_weight_on_hook(small_case):
    sigma = 5000.0
    law = mc.study_uncertainty(small_case, settings(small_case, (mc.weight_on_hook_normal(small_case, sigma),)))
    low, high = study_model.weight_on_bit_range(small_case, law)
    z = -norm.ppf(study_model.RANGE_TAIL)  # about 6.0
    wob = small_case.operation.weight_on_bit
    assert low == pytest.approx(wob - z * sigma, rel=1e-6)
    assert high == pytest.approx(wob + z * sigma, rel=1e-6)


def test_geometry_changing_input_falls_back_to_a_rebuild(small_case):
    study = settings(small_case, (mc.weight_on_hook_normal(small_case, 5000.0),
                                  ("sections[1].outer_diameter", "uniform 0.2 0.23")))
    law = mc.study_uncertainty(small_case, study)
    key = (small_case.to_toml(), study)
    note = study_model.study_model_note(small_case, key, law)
    assert note is not None and "sections[1].outer_diameter" in note
    realized = law.apply(small_case, mc.draw_inputs(small_case, study, 0))
    found = study_model.realization_model(small_case, key, law, realized)
    exact = case_reduced_model(realized)
    assert np.array_equal(found.basis, exact.basis) and np.array_equal(found.damping, exact.damping)


def test_covered_study_uses_one_parametric_model_per_study(small_case):
    study = settings(small_case, (mc.weight_on_hook_normal(small_case, 5000.0),))
    law = mc.study_uncertainty(small_case, study)
    key = (small_case.to_toml(), study)
    assert study_model.study_model_note(small_case, key, law) is None
    built = study_model.parametric_model(small_case, key, law)
    assert isinstance(built, ParametricReducedModel)
    assert study_model.parametric_model(small_case, key, law) is built  # kept for the study's realizations
    other = settings(small_case, (mc.weight_on_hook_normal(small_case, 8000.0),))
    assert study_model.parametric_model(small_case, (small_case.to_toml(), other),
                                        mc.study_uncertainty(small_case, other)) is not built
    # a draw outside the built range: rebuilt, exactly
    realized = law.apply(small_case, [small_case.weight - built.range[1] - 100.0])
    found = study_model.realization_model(small_case, key, law, realized)
    assert np.array_equal(found.basis, case_reduced_model(realized).basis)


def test_realization_equals_the_rebuilding_recipe(small_case, monkeypatch):
    """Two realizations and the nominal run of a weight-on-hook study with model uncertainty: the same draws,
    the same random matrices, and outputs equal to the rebuilt model's to 1e-6 of each series' range."""
    study = settings(small_case, (mc.weight_on_hook_normal(small_case, 5000.0),), model_dispersion=(0.05, 0.05, 0.1))
    key, law = (small_case.to_toml(), study), mc.study_uncertainty(small_case, study)
    assert isinstance(study_model.parametric_model(small_case, key, law), ParametricReducedModel)  # not a fallback
    for index in (mc.NOMINAL, 0, 1):
        found = mc.run_realization(small_case, study, index)
        monkeypatch.setenv(study_model.REBUILD_VARIABLE, "1")
        exact = mc.run_realization(small_case, study, index)
        monkeypatch.delenv(study_model.REBUILD_VARIABLE)
        assert found.status == exact.status == DONE, (found.message, exact.message)
        assert found.weight_on_bit == exact.weight_on_bit
        np.testing.assert_array_equal(found.inputs, exact.inputs)
        for name, series in exact.observables.items():
            scale = np.abs(series).max()
            assert np.abs(found.observables[name] - series).max() <= 1e-6 * scale, name
        for name, value in exact.metrics.items():
            if math.isfinite(value):
                assert found.metrics[name] == pytest.approx(value, rel=1e-6, abs=1e-12), name
        assert found.lowest_lateral_eigenvalue == pytest.approx(exact.lowest_lateral_eigenvalue, rel=1e-6)


def test_sensitivity_rows_of_the_three_controls_equal_the_rebuilding_recipe(small_case, monkeypatch):
    """A Saltelli design of the driller's three controls (weight-on-bit, inlet velocity, top speed: all covered)
    runs each row on the design's parametric model: the rows' outputs equal the rebuilt models' to 1e-6; the
    inlet velocity's range is its law's (uniform: its ends)."""
    from drillstring.stochastic import sensitivity_study as ss
    from drillstring.stochastic.parameters import with_parameters

    laws = (("operation.weight_on_bit", "uniform 70 130 kN"), ("fluid.inlet_velocity", "uniform 1 2 m/s"),
            ("operation.top_speed", "uniform 60 140 rpm"))
    design_settings = ss.SensitivitySettings(8, laws, t_end=1.0, output_step=0.05)
    design = ss.sensitivity_design(small_case, design_settings)
    law = design.uncertainty
    assert study_model.coverage(small_case, law) is None
    low, high = study_model.inlet_velocity_range(small_case, law)
    assert low == pytest.approx(1.0, rel=1e-8) and high == pytest.approx(2.0, rel=1e-8)
    key = ss._model_key(small_case, design_settings)
    built = study_model.parametric_model(small_case, key, law)
    assert isinstance(built, ParametricReducedModel) and built.flow_range == (low, high) and built.speed
    for index in (0, 5, 11):
        item = (index, design.values[index])
        built.model(with_parameters(small_case, dict(zip(law.paths, design.values[index]))))  # covered: no rebuild
        found = ss._row_task(small_case, law, design_settings, item)
        monkeypatch.setenv(study_model.REBUILD_VARIABLE, "1")
        exact = ss._row_task(small_case, law, design_settings, item)
        monkeypatch.delenv(study_model.REBUILD_VARIABLE)
        assert found.status == exact.status == DONE, (found.message, exact.message)
        for name, value in exact.values.items():
            if np.all(np.isfinite(value)):
                np.testing.assert_allclose(found.values[name], value, rtol=1e-6, atol=1e-12, err_msg=name)
