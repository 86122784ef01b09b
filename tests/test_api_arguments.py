"""The Python API checks its arguments as the command line does, before any work: TypeError for a value of
the wrong kind, ValueError for one out of range, each one line naming the argument and its value; sizes are
checked against their stated limits before anything is allocated; NumPy integers count as integers."""

import math

import numpy as np
import pytest

from drillstring import api
from drillstring.dynamics import rom
from drillstring.stochastic import montecarlo, operating_map, sensitivity_study


@pytest.fixture
def no_work(monkeypatch):
    """Building a model or running a study, map or sensitivity design fails the test: the refusal must come
    first."""
    def work(*args, **kwargs):
        raise AssertionError("work started before the arguments were checked")

    monkeypatch.setattr(rom, "case_reduced_model", work)
    for module in (montecarlo, operating_map, sensitivity_study):
        monkeypatch.setattr(module, "run_locked", work)


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(t_end=-1.0), ValueError, r"^t_end = -1.0 s: must be a finite number > 0$"),
    (dict(t_end=math.nan), ValueError, r"^t_end = nan s: must be a finite number > 0$"),
    (dict(t_end=math.inf), ValueError, r"^t_end = inf s: must be a finite number > 0$"),
    (dict(t_end="3"), TypeError, r"^t_end = '3' s: must be a number, not str$"),
    (dict(t_end=0), ValueError, r"^t_end = 0 s: must be a finite number > 0$"),
    (dict(t_end=1.0, output_step=0.0), ValueError, r"^output_step = 0.0 s: must be a number in \(0, t_end = 1 s\]$"),
    (dict(t_end=1.0, output_step=-0.1), ValueError, r"^output_step = -0.1 s: must be a number in \(0, t_end"),
    (dict(t_end=1.0, output_step=2.0), ValueError, r"^output_step = 2.0 s: must be a number in \(0, t_end = 1 s\]$"),
    (dict(t_end=1e7, output_step=0.01), ValueError,
     r"^t_end = 1e\+07 s at output_step = 0.01 s: 1000000001 output times, above the limit of 2000000 "),
    (dict(rtol=2.0), ValueError, r"^rtol = 2.0: must be a number in \(0, 1\), e.g. 1e-6$"),
    (dict(rtol=1), ValueError, r"^rtol = 1: must be a number in \(0, 1\)"),
    (dict(atol="tight"), TypeError, r"^atol = 'tight': must be a number, not str$"),
    (dict(weight_on_bit=-5.0), ValueError, r"^weight_on_bit = -5.0 N: must be a finite number > 0$"),
    (dict(progress=3), TypeError, r"^progress = 3: must be a callable or None$"),
])
def test_simulate_refuses_bad_arguments_before_building_anything(small_case, no_work, kwargs, error, message):
    with pytest.raises(error, match=message):
        api.simulate(small_case, **kwargs)


@pytest.mark.parametrize("call, kwargs, error, message", [
    ("stability", dict(weight_on_bit="100 kN"), TypeError, r"^weight_on_bit = '100 kN' N: must be a number, not str$"),
    ("stability", dict(weight_on_bit=-1.0), ValueError, r"^weight_on_bit = -1.0 N: must be a finite number > 0$"),
    ("modes", dict(count=0), ValueError, r"^count = 0: must be an integer in \[1, 1000\]$"),
    ("modes", dict(count=2.5), TypeError, r"^count = 2.5: must be an integer, not float$"),
    ("compare", dict(t_end=-1.0), ValueError, r"^t_end = -1.0 s: must be a finite number > 0$"),
])
def test_other_functions_refuse_bad_arguments(small_case, no_work, call, kwargs, error, message):
    with pytest.raises(error, match=message):
        getattr(api, call)(small_case, **kwargs)


@pytest.mark.parametrize("case", [{"name": "mine", "sections": []}, 42, None])
def test_a_case_must_be_a_case_a_name_or_a_path(case, no_work):
    """A dict is refused (not guessed at): Case objects come from load_case or case_from_dict."""
    hint = r" \(build one from a dict with drillstring.case.case_from_dict\)" if isinstance(case, dict) else ""
    with pytest.raises(TypeError, match=rf"^case = {type(case).__name__}: must be a Case, a built-in case name or "
                                        rf"a path to a TOML file{hint}$"):
        api.simulate(case)
    with pytest.raises(TypeError, match=rf"^case = {type(case).__name__}:"):
        api.study(case)


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(parameters=["operation.top_speed"]), TypeError, r"^parameters = list: must be a dict \(path -> law spec\)"),
    (dict(correlation=[[1, 0.5], [0.5, 1]]), TypeError, r"^correlation = list: must be a dict"),
    (dict(scheduler=8786), TypeError, r"^scheduler = 8786: must be an address like 'tcp://host:8786' or a "
                                      r"distributed.Client$"),
    (dict(workers=0), ValueError, r"^workers = 0: must be an integer >= 1$"),
    (dict(workers=2.0), TypeError, r"^workers = 2.0: must be an integer, not float$"),
    (dict(samples=2.0), TypeError, r"^samples = 2.0: must be an integer, not float$"),
    (dict(samples=1_000_000_000), ValueError,
     r"^samples = 1000000000 realizations of 11 output times: their time histories take 410 GiB, above the limit "
     r"of 4 GiB"),
    (dict(seed=2**64), ValueError, r"^seed = 18446744073709551616: must be an integer in \[0, 2\*\*64 - 1 = "
                                   r"18446744073709551615\]$"),
    (dict(seed=-1), ValueError, r"^seed = -1: must be an integer in \[0, 2\*\*64 - 1"),
    (dict(t_end="1"), TypeError, r"^t_end = '1' s: must be a number, not str$"),
    (dict(transient=1.0), ValueError, r"^transient = 1.0 s: must be a number in \[0, t_end = 1 s\)$"),
    (dict(out=3), TypeError, r"^out = 3: must be a folder path \(str or Path\) or None$"),
    (dict(sigma="5 kN"), TypeError, r"^sigma = '5 kN' N: must be a number, not str$"),
    (dict(parameters={"simulation.t_end": "uniform 20 30"}), ValueError,
     r"^simulation.t_end = 'uniform 20 30': cannot be random: every run of a study keeps the study's one time grid"),
    (dict(parameters={"simulation.output_step": "uniform 0.01 0.02"}), ValueError,
     r"^simulation.output_step = 'uniform 0.01 0.02': cannot be random"),
    (dict(parameters={"mesh.probes[0]": "uniform 100 200"}), ValueError,
     r"^mesh.probes\[0\] = 'uniform 100 200': cannot be random: the runs' displacements are stored at the case's "
     r"probe positions$"),
])
def test_study_refuses_bad_arguments_before_running(small_case, tmp_path, no_work, kwargs, error, message):
    kwargs = {"samples": 2, "t_end": 1.0, "output_step": 0.1, "out": tmp_path / "s", **kwargs}
    with pytest.raises(error, match=message):
        api.monte_carlo_study(small_case, **kwargs)
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(resamples=0), ValueError, r"^resamples = 0: must be an integer in \[1, 100000\]$"),
    (dict(resamples=10.0), TypeError, r"^resamples = 10.0: must be an integer, not float$"),
    (dict(confidence=1.5), ValueError, r"^confidence = 1.5: must be a number in \(0, 1\), e.g. 0.95$"),
    (dict(samples=100), ValueError, r"^samples = 100: must be a power of 2 and >= 8"),
    (dict(samples=2**40), ValueError, r"^samples = 1099511627776: above the limit of 262144 \(2\*\*18\) base samples$"),
    (dict(seed=2**64), ValueError, r"^seed = 18446744073709551616: must be an integer in \[0, 2\*\*64 - 1"),
    (dict(parameters=[("operation.top_speed", "uniform 60 140 rpm")]), TypeError, r"^parameters = list: must be a dict"),
    (dict(parameters={"simulation.t_end": "uniform 20 30"}), ValueError, r"^simulation.t_end = .*cannot be random"),
    (dict(t_end=1.0, transient=1.0), ValueError, r"^transient = 1.0 s: must be a number in \[0, t_end = 1 s\)$"),
])
def test_sensitivity_refuses_bad_arguments_before_running(small_case, tmp_path, no_work, kwargs, error, message):
    kwargs = {"parameters": {"operation.top_speed": "uniform 60 140 rpm"}, "samples": 8, "t_end": 1.0, **kwargs}
    with pytest.raises(error, match=message):
        api.sensitivity(small_case, out=tmp_path / "s", **kwargs)
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(top_speed="40:200:999999999999"), ValueError,
     r"^top_speed = '40:200:999999999999': N = 999999999999 values, above the limit of 100000 grid points$"),
    (dict(top_speed="40:200:400 rpm", weight_on_bit="40:160:400 kN"), ValueError,
     r"^the grid has 400 x 400 = 160000 points, above the limit of 100000$"),
    (dict(t_end=-1.0), ValueError, r"^t_end = -1.0 s: must be a finite number > 0$"),
    (dict(t_end=1.0, transient=1.0), ValueError, r"^transient = 1.0 s: must be a number in \[0, t_end = 1 s\)$"),
    (dict(scheduler=object()), TypeError, r"^scheduler = <object object at .*>: must be an address"),
])
def test_map_refuses_bad_arguments_before_running(small_case, tmp_path, no_work, kwargs, error, message):
    with pytest.raises(error, match=message):
        api.operating_map(small_case, out=tmp_path / "m", **kwargs)
    assert not (tmp_path / "m").exists()


def test_numpy_integers_are_accepted_where_integers_are(small_case, tmp_path):
    outcome = api.monte_carlo_study(small_case, samples=np.int64(2), seed=np.uint64(3), workers=np.int64(1),
                                    t_end=np.float64(0.2), output_step=np.float32(0.05), out=tmp_path / "s")
    assert outcome.summary["samples"] == 2 and outcome.summary["n_samples"] == 2
    found, _ = api.modes(small_case, count=np.int64(2))
    assert len(found.torsional.frequencies) == 2


def test_study_takes_the_arguments_of_monte_carlo_study(no_work):
    """``study`` is ``monte_carlo_study``'s statistics: its signature (help(), the reference) is that recipe's, with
    its defaults and settings objects, and a keyword that is neither an argument nor a field of a settings object
    is refused before anything runs, naming what is allowed."""
    import inspect

    full = inspect.signature(api.monte_carlo_study).parameters
    short = inspect.signature(api.study)
    assert list(short.parameters) == list(full)
    assert all(short.parameters[n] == full[n] for n in short.parameters)
    assert "Dataset" in str(short.return_annotation)
    with pytest.raises(TypeError, match=r"^monte_carlo_study\(\) got an unexpected keyword argument 'notes'; it "
                                        r"takes the settings objects inputs, window, run or their fields as "
                                        r"keywords: .*\bnote\b"):
        api.study("reference", notes=print)
    with pytest.raises(TypeError, match=r"^study\(\) "):  # one positional argument, the case
        api.study("reference", 10)
