"""The settings objects of the engine functions (drillstring.api.settings): checked when built (the field, its value
and range named), frozen; the earlier keywords still accepted and gathered into them (an unknown keyword, a field
given both ways or a field the function does not use refused before any work); the same settings, results and
store fingerprints either way, and the fingerprints those calls had before the objects (a store started then
resumes)."""

import dataclasses
import hashlib
import json
from dataclasses import asdict

import numpy as np
import pytest

import drillstring
from drillstring import RandomInputs, RunOptions, SearchOptions, SimulationWindow, api
from drillstring.case import load_case
from drillstring.stochastic.store import fingerprint


@pytest.mark.parametrize("build, error, message", [
    (lambda: RunOptions(workers=0), ValueError, r"^workers = 0: must be an integer >= 1$"),
    (lambda: RunOptions(workers=2.0), TypeError, r"^workers = 2.0: must be an integer, not float$"),
    (lambda: RunOptions(workers=2, scheduler="tcp://h:8786"), ValueError, r"^give workers .* or scheduler .*not both$"),
    (lambda: RunOptions(scheduler=8786), TypeError, r"^scheduler = 8786: must be an address like 'tcp://host:8786'"),
    (lambda: RunOptions(out=3), TypeError, r"^out = 3: must be a folder path \(str or Path\) or None$"),
    (lambda: RunOptions(units="imperial"), ValueError, r"^units = 'imperial': must be one of si, field$"),
    (lambda: RunOptions(worker_timeout=0.0), ValueError, r"^worker_timeout = 0.0 s: must be a finite number > 0$"),
    (lambda: RunOptions(progress=3), TypeError, r"^progress = 3: must be a callable or None$"),
    (lambda: RunOptions(stage="figures"), TypeError, r"^stage = 'figures': must be a callable or None$"),
    (lambda: SimulationWindow(t_end=-1.0), ValueError, r"^t_end = -1.0 s: must be a finite number > 0$"),
    (lambda: SimulationWindow(t_end="3"), TypeError, r"^t_end = '3' s: must be a number, not str$"),
    (lambda: SimulationWindow(t_end=1.0, output_step=2.0), ValueError,
     r"^output_step = 2.0 s: must be a number in \(0, t_end = 1 s\]$"),
    (lambda: SimulationWindow(output_step=0.0), ValueError, r"^output_step = 0.0 s: must be a finite number > 0$"),
    (lambda: SimulationWindow(t_end=1.0, transient=1.0), ValueError,
     r"^transient = 1.0 s: must be a number in \[0, t_end = 1 s\)$"),
    (lambda: SimulationWindow(transient=-1.0), ValueError, r"^transient = -1.0 s: must be a finite number >= 0$"),
    (lambda: RandomInputs(sigma=-5.0), ValueError, r"^sigma = -5.0 N: must be a finite number > 0$"),
    (lambda: RandomInputs(sigma="5 kN"), TypeError, r"^sigma = '5 kN' N: must be a number, not str$"),
    (lambda: RandomInputs(dispersion=0.0), ValueError, r"^dispersion = 0.0: must be a finite number > 0$"),
    (lambda: RandomInputs(sigma=1.0, dispersion=0.1), ValueError, r"^give sigma \[N\] or dispersion"),
    (lambda: RandomInputs(parameters=["operation.top_speed"]), TypeError, r"^parameters = list: must be a dict"),
    (lambda: RandomInputs(model=[0.1]), TypeError, r"^model = list: must be a dict"),
    (lambda: SearchOptions(samples=1), ValueError, r"^samples = 1: must be an integer from 2 to 1000"),
    (lambda: SearchOptions(initial=1), ValueError, r"^initial = 1: must be an integer from 2 to 200"),
    (lambda: SearchOptions(initial=4, points=3), ValueError, r"^points = 3: must be an integer from initial = 4 to"),
    (lambda: SearchOptions(batch=0), ValueError, r"^batch = 0: must be an integer from 1 to 200"),
    (lambda: SearchOptions(probability_mean="cubic"), ValueError, (r"^probability_mean = 'cubic': must be one of "
                                                                  r"constant, linear$")),
])
def test_a_bad_field_is_refused_when_the_object_is_built(build, error, message):
    with pytest.raises(error, match=message) as raised:
        build()
    assert "\n" not in str(raised.value)


def test_the_objects_are_frozen_and_keep_their_own_tables():
    laws = {"operation.top_speed": "uniform 60 140 rpm"}
    inputs = RandomInputs(parameters=laws)
    laws["fluid.density"] = "uniform 1100 1300"
    assert inputs.parameters == {"operation.top_speed": "uniform 60 140 rpm"}
    for obj, field in ((inputs, "sigma"), (RunOptions(), "workers"), (SimulationWindow(), "t_end"),
                       (SearchOptions(), "samples")):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(obj, field, 1)
    assert RunOptions(workers=np.int64(2)).workers == 2 and type(RunOptions(workers=np.int64(2)).workers) is int
    assert drillstring.RunOptions is api.RunOptions is RunOptions  # offered by the package and the API


@pytest.fixture
def no_work(monkeypatch):
    """Running a study, map, sensitivity design or search fails the test: a refusal must come first."""
    from drillstring.stochastic import (
        montecarlo,
        operating_map,
        optimize,
        sensitivity_study,
    )

    def work(*args, **kwargs):
        raise AssertionError("work started before the arguments were checked")

    for module in (montecarlo, operating_map, sensitivity_study, optimize):
        monkeypatch.setattr(module, "run_locked", work)


@pytest.mark.parametrize("function, kwargs, error, message", [
    ("monte_carlo_study", {"t_ends": 3.0}, TypeError,
     (r"^monte_carlo_study\(\) got an unexpected keyword argument 't_ends'; it takes the settings objects inputs, "
     r"window, run or their fields as keywords: correlation, dispersion, model, note, out, output_step, parameters, "
     r"progress, scheduler, sigma, stage, t_end, transient, units, worker_timeout, workers$")),
    ("sensitivity", {"sigma": 3000.0}, TypeError, r"^sensitivity\(\) got an unexpected keyword argument 'sigma'"),
    ("operating_map", {"dispersion": 0.1}, TypeError, (r"^operating_map\(\) got an unexpected keyword argument "
                                                       r"'dispersion'")),
    ("monte_carlo_study", {"t_end": 1.0, "window": SimulationWindow(t_end=2.0)}, TypeError,
     r"^monte_carlo_study\(\): t_end is given both as a keyword and in window= \(SimulationWindow\); give it once$"),
    ("operating_map", {"workers": 1, "run": RunOptions()}, TypeError, r"^operating_map\(\): workers is given both"),
    ("monte_carlo_study", {"window": {"t_end": 1.0}}, TypeError,
     r"^window = \{'t_end': 1.0\}: must be a SimulationWindow or None$"),
    ("operating_map", {"samples": 2, "inputs": RandomInputs(dispersion=0.1)}, ValueError,
     r"^operating_map\(\): inputs.dispersion = 0.1: not used here; it uses parameters, correlation, sigma, model$"),
    ("sensitivity", {"inputs": RandomInputs(parameters={"operation.top_speed": "uniform 60 140 rpm"}, sigma=1e3)},
     ValueError, r"^sensitivity\(\): inputs.sigma = 1000.0: not used here; it uses parameters$"),
    ("optimize", {"variables": {"top_speed": "60 rpm:140 rpm"}, "points": 8, "search": SearchOptions()}, TypeError,
     r"^optimize\(\): points is given both as a keyword and in search= \(SearchOptions\)"),
    ("optimize", {"variables": {"top_speed": "60 rpm:140 rpm"}, "inputs": RandomInputs(dispersion=0.1)}, ValueError,
     r"^optimize\(\): inputs.dispersion = 0.1: not used here"),
])
def test_keywords_and_objects_are_refused_before_any_work(no_work, function, kwargs, error, message):
    with pytest.raises(error, match=message):
        getattr(drillstring, function)("reference", **kwargs)


class _Captured(Exception):
    pass


def _stored_settings(monkeypatch, function, **kwargs):
    """The case and the settings a call hands its store (the dictionary its fingerprint hashes), stopped there."""
    from drillstring.stochastic import (
        montecarlo,
        operating_map,
        optimize,
        probabilistic_map,
        sensitivity_study,
    )

    seen = {}

    def runner(stored):
        def run(case, settings, *args, **kw):
            seen.update(case=case, settings=stored(settings))
            raise _Captured
        return run

    for module, name, stored in ((montecarlo, "run_study", lambda s: s.store_settings()),
                                 (operating_map, "run_map", asdict),
                                 (probabilistic_map, "run_sampled_map", lambda s: s.store_settings()),
                                 (sensitivity_study, "run_sensitivity", lambda s: s.store_settings(("laws",))),
                                 (optimize, "run_optimization", lambda s: s.store_settings())):
        monkeypatch.setattr(module, name, runner(stored))
    with pytest.raises(_Captured):
        getattr(drillstring, function)(load_case("reference"), **kwargs)
    return seen["case"], seen["settings"]


_WINDOW = {"t_end": 0.5, "output_step": 0.05, "transient": 0.2}
_LAW = {"operation.top_speed": "uniform 60 140 rpm"}
_GRID = {"top_speed": "60 rpm:100 rpm:2", "weight_on_bit": "80 kN,100 kN"}

#: Each call with its earlier keywords, the same with the settings objects, and the digest (SHA-256 of the sorted
#: JSON, 16 digits) of the settings its store held on the main line before the objects existed.
_CALLS = {
    "study": ("monte_carlo_study",
              dict(samples=4, seed=7, parameters=_LAW, sigma=3000.0, model={"stiffness_dispersion": 0.1}, workers=1,
                   **_WINDOW),
              {"samples": 4, "seed": 7,
               "inputs": RandomInputs(parameters=_LAW, sigma=3000.0, model={"stiffness_dispersion": 0.1}),
               "run": RunOptions(workers=1), "window": SimulationWindow(**_WINDOW)},
              "3ba65d4670eaafe2"),
    "map": ("operating_map", dict(**_GRID, workers=1, **_WINDOW),
            dict(**_GRID, run=RunOptions(workers=1), window=SimulationWindow(**_WINDOW)), "7e34ec0e345510a6"),
    "sampled map": ("operating_map", dict(**_GRID, samples=3, sigma=2000.0, seed=5, **_WINDOW),
                    dict(**_GRID, samples=3, seed=5, inputs=RandomInputs(sigma=2000.0),
                         window=SimulationWindow(**_WINDOW)), "5b5b444a3c5ac37e"),
    "sensitivity": ("sensitivity", dict(parameters=_LAW, samples=8, seed=1, **_WINDOW),
                    {"samples": 8, "seed": 1, "inputs": RandomInputs(parameters=_LAW),
                     "window": SimulationWindow(**_WINDOW)},
                    "77dde75a6859e07e"),
    "optimize": ("optimize",
                 dict(variables={"top_speed": "60 rpm:140 rpm"}, constraints={"stick_slip": 0.1}, samples=3, points=6,
                      initial=4, batch=2, seed=3, sigma=2000.0, **_WINDOW),
                 {"variables": {"top_speed": "60 rpm:140 rpm"}, "constraints": {"stick_slip": 0.1}, "seed": 3,
                  "search": SearchOptions(samples=3, points=6, initial=4, batch=2),
                  "inputs": RandomInputs(sigma=2000.0), "window": SimulationWindow(**_WINDOW)},
                 "e23e400b0b0ff078"),
}


@pytest.mark.parametrize("kind", list(_CALLS))
def test_old_keywords_and_objects_give_the_same_store_fingerprint_as_before(monkeypatch, kind):
    """The settings a store is fingerprinted with are those of the earlier keyword signatures (a store started
    before resumes): the same dictionary either way, its digest the one recorded before the settings objects, and
    the fingerprint the store's formula (SHA-256 of the case's TOML and the sorted JSON of the settings)."""
    function, old, new, before = _CALLS[kind]
    case, settings_old = _stored_settings(monkeypatch, function, **old)
    _, settings_new = _stored_settings(monkeypatch, function, **new)
    assert settings_new == settings_old
    text = json.dumps(settings_old, sort_keys=True)
    assert hashlib.sha256(text.encode()).hexdigest()[:16] == before
    assert fingerprint(case.to_toml(), settings_new) == hashlib.sha256(
        (case.to_toml() + text).encode()).hexdigest()[:16]


def test_a_tiny_study_gives_the_same_results_either_way(small_case, tmp_path):
    """Two realizations of 0.2 s, once with the keywords and once with the objects: the same statistics, the same
    store fingerprint."""
    import zarr

    old = api.monte_carlo_study(small_case, samples=2, seed=3, t_end=0.2, output_step=0.05, transient=0.1,
                                sigma=4000.0, workers=1, out=tmp_path / "old")
    new = api.monte_carlo_study(small_case, samples=2, seed=3, inputs=RandomInputs(sigma=4000.0),
                                window=SimulationWindow(t_end=0.2, output_step=0.05, transient=0.1),
                                run=RunOptions(workers=1, out=tmp_path / "new"))
    assert set(old.statistics.data_vars) == set(new.statistics.data_vars)
    for name in old.statistics.data_vars:
        np.testing.assert_array_equal(old.statistics[name].values, new.statistics[name].values, err_msg=name)
    prints = [zarr.open_group(str(tmp_path / side / "study.zarr"), mode="r").attrs["fingerprint"]
              for side in ("old", "new")]
    assert prints[0] == prints[1]


def test_the_engine_functions_take_objects_not_keyword_lists():
    """Their signatures (help(), the reference) list the settings objects, not the fields one by one (issue 33: 15
    to 25 parameters before); each field stays accepted as a keyword through ``**keywords``."""
    import inspect

    sizes = {name: inspect.signature(getattr(drillstring, name)).parameters
             for name in ("monte_carlo_study", "study", "operating_map", "sensitivity", "optimize")}
    assert {name: len(p) for name, p in sizes.items()} == {
        "monte_carlo_study": 7, "study": 7, "operating_map": 9, "sensitivity": 9, "optimize": 11}
    for parameters in sizes.values():
        assert {"window", "run"} <= set(parameters) and "t_end" not in parameters and "workers" not in parameters
        assert list(parameters.values())[-1].kind is inspect.Parameter.VAR_KEYWORD
