"""The one uncertainty settings object (stochastic/uncertainty_settings.py): its validation, held by the study,
sampled-map, optimisation and sensitivity settings (the same laws drawn by each), and the stores' fingerprints
unchanged by the composition (a store written before it resumes)."""

import dataclasses
import pickle

import numpy as np
import pytest

from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic import optimize as opt
from drillstring.stochastic import probabilistic_map as pm
from drillstring.stochastic import sensitivity_study as ss
from drillstring.stochastic.operating_map import MapSettings
from drillstring.stochastic.store import fingerprint
from drillstring.stochastic.uncertainty_settings import UncertaintySettings

DENSITY = ("fluid.density", "uniform 1100 1300")
VELOCITY = ("fluid.inlet_velocity", "normal 1.5 0.1")
SPEED = ("operation.top_speed", "normal 12 0.5")


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(laws="fluid.density=uniform 1 2"), TypeError, "^laws = "),
    (dict(laws=(("fluid.density",),)), ValueError, r"^laws\[0\] = .*\(path, law spec\) pair"),
    (dict(laws=(("  ", "uniform 1 2"),)), ValueError, r"^laws\[0\] = .*the path is empty"),
    (dict(laws=(DENSITY, (" fluid.density", "uniform 1 3"))), ValueError, "^fluid.density is declared twice in laws"),
    (dict(laws=(VELOCITY,), correlated=("fluid.inlet_velocity", "weight_on_hook")), ValueError,
     "^correlated = .*give both"),
    (dict(laws=(VELOCITY,), correlation=((1.0,),)), ValueError, "^correlated = .*give both"),
    (dict(correlated=("a", "a"), correlation=((1, 0), (0, 1))), ValueError, "^correlated: a is listed twice"),
    (dict(correlated=("a", "b"), correlation=((1, 0.2), (0.2,))), ValueError, r"^correlation\[1\] has 1 entries"),
    (dict(correlated=("a", "b"), correlation=((1, 0.2),)), ValueError, "^correlation has 1 rows: must have 2"),
    (dict(correlated=("a", "b"), correlation=((1, "x"), (0.2, 1))), ValueError, r"^correlation\[0\] = .*numbers"),
    (dict(correlated=("a", "b"), correlation=((1, float("nan")), (0.2, 1))), ValueError,
     r"^correlation\[0\] = .*finite"),
    (dict(correlated="ab", correlation=((1,),)), TypeError, "^correlated = "),
    (dict(model_dispersion=(0.1, 0.2)), ValueError, "^model_dispersion = "),
    (dict(model_dispersion=(-0.1, 0.0, 0.0)), ValueError, "mass_dispersion"),
])
def test_each_bad_field_is_named(kwargs, error, message):
    with pytest.raises(error, match=message):
        UncertaintySettings(**kwargs)


def test_canonical_form_is_hashable_and_picklable():
    u = UncertaintySettings(laws=[[" fluid.density ", "uniform 1100 1300"]], correlated=["fluid.density"],
                            correlation=[[1]], model_dispersion=[0, 0.1, 0])
    assert u.laws == (("fluid.density", "uniform 1100 1300"),)
    assert u.correlated == ("fluid.density",) and u.correlation == ((1.0,),)
    assert u.model_dispersion == (0.0, 0.1, 0.0) and u.model.stiffness == 0.1 and u.model.active
    assert hash(u) == hash(pickle.loads(pickle.dumps(u)))
    assert u == UncertaintySettings(laws=(("fluid.density", "uniform 1100 1300"),), correlated=("fluid.density",),
                                    correlation=((1.0,),), model_dispersion=(0.0, 0.1, 0.0))


def _grid():
    return MapSettings((10.0, 12.0), (6e4, 8e4), t_end=1.0, output_step=0.05)


@pytest.mark.parametrize("build", [
    lambda **k: mc.StudySettings(samples=2, **k),
    lambda **k: pm.SampledMapSettings(_grid(), samples=2, **k),
    lambda **k: opt.OptimizationSettings(variables=(("operation.top_speed", 8.0, 15.0),), **k),
])
def test_every_settings_refuses_through_the_one_validation(build):
    """The same bad uncertainty is refused by each settings class with the one message, given as keywords or
    as an UncertaintySettings; giving both is refused."""
    with pytest.raises(ValueError, match="^fluid.density is declared twice in laws"):
        build(laws=(DENSITY, DENSITY))
    with pytest.raises(ValueError, match=r"^correlation\[0\] has 1 entries"):
        build(laws=(VELOCITY,), correlated=("fluid.inlet_velocity", "weight_on_hook"), correlation=((1.0,), (0.0,)))
    with pytest.raises(ValueError, match="^uncertainty and laws: give"):
        build(laws=(DENSITY,), uncertainty=UncertaintySettings(laws=(DENSITY,)))
    with pytest.raises(TypeError, match="^uncertainty = "):
        build(uncertainty=(DENSITY,))
    u = UncertaintySettings(laws=(DENSITY,), model_dispersion=(0.0, 0.05, 0.0))
    flat, composed = build(laws=(DENSITY,), model_dispersion=(0.0, 0.05, 0.0)), build(uncertainty=u)
    assert flat == composed and composed.uncertainty is u
    assert (composed.laws, composed.model_dispersion, composed.model) == (u.laws, u.model_dispersion, u.model)
    assert dataclasses.replace(composed, seed=7).uncertainty is u


def test_owners_keep_their_own_rules():
    with pytest.raises(ValueError, match="^no random parameter"):
        mc.StudySettings(samples=2)
    with pytest.raises(ValueError, match="^weight_on_hook: cannot carry a law on a map"):
        pm.SampledMapSettings(_grid(), samples=2, laws=(("weight_on_hook", "normal 1 0.1"),))
    with pytest.raises(ValueError, match="^operation.top_speed: a decision variable cannot carry a law too"):
        opt.OptimizationSettings(variables=(("operation.top_speed", 8.0, 15.0),), laws=(SPEED,))
    with pytest.raises(ValueError, match="^uncertainty: Sobol' indices need independent"):
        ss.SensitivitySettings(8, UncertaintySettings(laws=(DENSITY,), model_dispersion=(0.1, 0.0, 0.0)))
    # the sensitivity settings' earlier positional laws still work
    assert ss.SensitivitySettings(8, (DENSITY,)).uncertainty == UncertaintySettings(laws=(DENSITY,))


def test_a_study_a_map_and_a_search_built_from_one_uncertainty_draw_the_same_laws(small_case):
    """One UncertaintySettings (two correlated normals and a uniform) held by a study, a one-point sampled map at
    the case's own operating point, a search's design point and a sensitivity run (the independent part): the
    joint laws built by each are equal, and so are their draws of the same (seed, realizations)."""
    u = UncertaintySettings(laws=(VELOCITY, DENSITY, ("fluid.friction_coefficient", "normal 0.02 0.002")),
                            correlated=("fluid.inlet_velocity", "fluid.friction_coefficient"),
                            correlation=((1.0, -0.4), (-0.4, 1.0)))
    op = small_case.operation
    study = mc.StudySettings(samples=4, seed=5, t_end=1.0, output_step=0.05, uncertainty=u)
    grid = MapSettings((op.top_speed,), (op.weight_on_bit,), t_end=1.0, output_step=0.05)
    sampled = pm.SampledMapSettings(grid, samples=4, seed=5, uncertainty=u)
    search = opt.OptimizationSettings(variables=(("operation.top_speed", 0.5 * op.top_speed, 2 * op.top_speed),),
                                      samples=4, seed=5, t_end=1.0, output_step=0.05, uncertainty=u)
    laws = [mc.study_uncertainty(small_case, study), pm.point_uncertainty(small_case, sampled, 0),
            pm.point_uncertainty(small_case, opt.point_settings(small_case, search), 0)]
    assert laws[0].paths == ("fluid.inlet_velocity", "fluid.density", "fluid.friction_coefficient")
    assert laws[0].correlation is not None and laws[0].correlation[0, 1] == pytest.approx(-0.4)
    draws = [law.draw(5, [0, 1, 2, 3]) for law in laws]
    for law, drawn in zip(laws[1:], draws[1:]):
        assert law == laws[0]
        np.testing.assert_array_equal(drawn, draws[0])
    # the same law as built directly from the declaration (an independent path through uncertainty())
    from drillstring.stochastic.uncertainty import uncertainty

    direct = uncertainty(small_case, dict(u.laws), correlated=u.correlated,
                         correlation=[list(r) for r in u.correlation], tolerance=1.0)
    np.testing.assert_array_equal(direct.draw(5, [0, 1, 2, 3]), draws[0])
    independent = UncertaintySettings(laws=(DENSITY, VELOCITY))
    design = ss.sensitivity_design(small_case, ss.SensitivitySettings(8, independent, t_end=1.0, output_step=0.05))
    assert design.uncertainty == mc.study_uncertainty(small_case, mc.StudySettings(samples=2, uncertainty=independent))


def _main_study_settings(samples, seed, t_end, output_step, laws, correlated, correlation, model_dispersion):
    """The settings dictionary a study store fingerprinted before the composition: ``asdict`` of the flat
    StudySettings (its fields in order, canonical values)."""
    return {"samples": samples, "seed": seed, "t_end": t_end, "output_step": output_step, "laws": laws,
            "correlated": correlated, "correlation": correlation, "model_dispersion": model_dispersion}


def test_a_study_store_keeps_its_fingerprint(small_case, tmp_path):
    """A study built the old way (flat keywords) or from an UncertaintySettings fingerprints its store as
    before (so a study started earlier resumes): the store's fingerprint equals the hash of the earlier flat
    settings dictionary, and a store written with that dictionary is resumed."""
    laws = (mc.weight_on_hook_normal(small_case, 2000.0), VELOCITY)
    old = dict(samples=3, seed=9, t_end=0.2, output_step=0.05, laws=laws, correlated=(VELOCITY[0], "weight_on_hook"),
               correlation=((1.0, 0.3), (0.3, 1.0)), model_dispersion=(0.0, 0.0, 0.0))
    settings = mc.StudySettings(**old)
    composed = mc.StudySettings(samples=3, seed=9, t_end=0.2, output_step=0.05,
                                uncertainty=UncertaintySettings(laws, old["correlated"], old["correlation"]))
    assert composed == settings
    earlier = _main_study_settings(**old)
    assert settings.store_settings() == earlier and list(settings.store_settings()) == list(earlier)
    store = mc.StudyStore(tmp_path / "study.zarr", small_case, settings)
    assert store.group.attrs["fingerprint"] == fingerprint(small_case.to_toml(), earlier)
    assert dict(store.group.attrs["settings"]) == {k: _json(v) for k, v in earlier.items()}
    # reopened with the composed settings: same fingerprint, no "case or settings differ"
    again = mc.StudyStore(tmp_path / "study.zarr", small_case, composed)
    assert again.group.attrs["fingerprint"] == store.group.attrs["fingerprint"]
    with pytest.raises(Exception, match="differ"):
        mc.StudyStore(tmp_path / "study.zarr", small_case, dataclasses.replace(composed, seed=10))


def _json(value):
    return [_json(v) for v in value] if isinstance(value, (tuple, list)) else value


def test_the_other_stores_keep_their_flat_settings():
    """Map, search and sensitivity stores fingerprint the flat dictionaries of their earlier settings."""
    grid = _grid()
    sampled = pm.SampledMapSettings(grid, samples=3, seed=2, sigma=1000.0, laws=(DENSITY,),
                                    model_dispersion=(0.0, 0.1, 0.0))
    assert sampled.store_settings() == {
        "grid": dataclasses.asdict(grid), "samples": 3, "seed": 2, "sigma": 1000.0, "laws": (DENSITY,),
        "correlated": (), "correlation": (), "model_dispersion": (0.0, 0.1, 0.0)}
    search = opt.OptimizationSettings(variables=(("operation.top_speed", 8.0, 15.0),), samples=3, laws=(DENSITY,))
    flat = search.store_settings()
    assert list(flat)[-5:] == ["sigma", "laws", "correlated", "correlation", "model_dispersion"]
    assert flat["laws"] == (DENSITY,) and flat["model_dispersion"] == (0.0, 0.0, 0.0)
    assert "uncertainty" not in flat
    # the search's store settings rebuild the same settings (optimization_result reads them back)
    assert opt.OptimizationSettings(**flat) == search
    sensitivity = ss.SensitivitySettings(8, (DENSITY,), t_end=2.0, output_step=0.05)
    assert sensitivity.store_settings(("laws",)) == {"base_samples": 8, "laws": (DENSITY,), "seed": 0, "t_end": 2.0,
                                                     "output_step": 0.05, "transient": 1.0}
