"""Monte Carlo engine: reproducibility across worker counts, resume, failures recorded and excluded."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import zarr

from drillstring.case import load_case
from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic.analysis import load_study, study_statistics
from drillstring.stochastic.maxent import realization_generator

ARRAYS = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit",
          "radial_displacement", "weight_on_hook", "status", "nominal_bit_speed")


@pytest.fixture(scope="module")
def small_case():
    """The reference string on a coarse mesh with a small basis: ~0.1 s per realization."""
    case = load_case("reference")
    return case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(
            update={"axial_modes": 2, "torsional_modes": 2, "lateral_modes": 3}),
    })


SETTINGS = mc.StudySettings(samples=5, sigma=5000.0, seed=11, t_end=1.0, output_step=0.05)


def arrays(path):
    g = zarr.open_group(str(path), mode="r")
    return {name: g[name][:] for name in ARRAYS}


def assert_same(a, b):
    for name in ARRAYS:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_draws_depend_only_on_seed_and_index(small_case):
    first = [mc.draw_weight_on_hook(small_case, SETTINGS, i) for i in (3, 0, 4)]
    again = [mc.draw_weight_on_hook(small_case, SETTINGS, i) for i in (0, 3, 4)]
    assert first[0] == again[1] and first[1] == again[0] and first[2] == again[2]
    mean = mc.nominal_weight_on_hook(small_case)
    expected = mean + 5000.0 * realization_generator(11, 3).standard_normal()
    assert first[0] == pytest.approx(expected, rel=1e-12)
    assert mc.draw_weight_on_hook(small_case, SETTINGS, mc.NOMINAL) == mean


def test_one_and_two_workers_give_identical_results(small_case, tmp_path):
    one = mc.run_study(small_case, SETTINGS, tmp_path / "one.zarr", workers=1)
    two = mc.run_study(small_case, SETTINGS, tmp_path / "two.zarr", workers=2)
    assert one.completed == two.completed == SETTINGS.samples
    assert_same(arrays(tmp_path / "one.zarr"), arrays(tmp_path / "two.zarr"))


def test_interrupted_study_resumes_to_the_same_result(small_case, tmp_path):
    reference = mc.run_study(small_case, SETTINGS, tmp_path / "ref.zarr", workers=1)
    assert reference.failed == 0

    def interrupt_after_two(done, failed, total):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(mc.StudyInterrupted, match="resume"):
        mc.run_study(small_case, SETTINGS, tmp_path / "cut.zarr", workers=1,
                     progress=interrupt_after_two)
    status = zarr.open_group(str(tmp_path / "cut.zarr"))["status"][:]
    assert np.sum(status == mc.DONE) == 2
    resumed = mc.run_study(small_case, SETTINGS, tmp_path / "cut.zarr", workers=1)
    assert resumed.completed == SETTINGS.samples
    assert_same(arrays(tmp_path / "ref.zarr"), arrays(tmp_path / "cut.zarr"))


KILL_SCRIPT = """
import sys
from drillstring.case import case_from_dict
import tomllib
from drillstring.stochastic import montecarlo as mc
case = case_from_dict(tomllib.loads(open(sys.argv[1]).read()))
settings = mc.StudySettings(samples=40, sigma=5000.0, seed=11, t_end=1.0, output_step=0.05)
mc.run_study(case, settings, sys.argv[2], workers=1)
"""


def test_killed_process_resumes_to_the_same_result(small_case, tmp_path):
    settings = mc.StudySettings(samples=40, sigma=5000.0, seed=11, t_end=1.0, output_step=0.05)
    case_file = tmp_path / "case.toml"
    case_file.write_text(small_case.to_toml())
    store = tmp_path / "killed.zarr"
    proc = subprocess.Popen([sys.executable, "-c", KILL_SCRIPT, str(case_file), str(store)])
    deadline = time.time() + 120
    done = 0
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)
        try:
            done = int(np.sum(zarr.open_group(str(store), mode="r")["status"][:] == mc.DONE))
        except Exception:
            continue
        if done >= 3:
            break
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert 3 <= done < 40, "the process should have been killed mid-study"
    mc.run_study(small_case, settings, store, workers=1)
    mc.run_study(small_case, settings, tmp_path / "full.zarr", workers=1)
    assert_same(arrays(store), arrays(tmp_path / "full.zarr"))


def test_failed_realizations_are_recorded_and_excluded(small_case, tmp_path, monkeypatch):
    """Two failure kinds: a diverging integration, and a draw that is physically impossible."""
    real = mc.simulate_model
    nominal_wob = small_case.operation.weight_on_bit

    def diverge_above_nominal(model, **kwargs):
        if model.weight_on_bit > nominal_wob:
            kwargs["max_steps"] = 5  # the integrator gives up: a genuine SimulationError
        return real(model, **kwargs)

    monkeypatch.setattr(mc, "simulate_model", diverge_above_nominal)
    run = mc.run_study(small_case, SETTINGS, tmp_path / "f.zarr", workers=1)
    raw = load_study(tmp_path / "f.zarr")
    above = raw.weight_on_bit.values > nominal_wob
    assert run.failed == int(above.sum()) > 0 and run.completed == int((~above).sum()) >= 2
    failures = raw.attrs["failures"]
    assert set(failures) == {str(i) for i in np.nonzero(above)[0]}
    assert all("t =" in message for message in failures.values())
    stats = study_statistics(raw)
    assert stats.attrs["n_samples"] == run.completed and stats.attrs["n_failed"] == run.failed
    expected = raw.rate_of_penetration.values[~above].mean(axis=0)
    np.testing.assert_allclose(stats.rate_of_penetration_mean.values, expected, rtol=1e-12)

    # A huge sigma draws weights-on-hook above the string's weight: refused with the cause.
    wild = mc.StudySettings(samples=6, sigma=3e5, seed=1, t_end=0.2, output_step=0.05)
    monkeypatch.setattr(mc, "simulate_model", real)
    run = mc.run_study(small_case, wild, tmp_path / "wild.zarr", workers=1)
    failures = load_study(tmp_path / "wild.zarr").attrs["failures"]
    assert run.failed == len(failures) > 0
    assert all("weight_on_bit" in m for m in failures.values())


def test_store_with_other_settings_is_refused(small_case, tmp_path):
    mc.run_study(small_case, SETTINGS, tmp_path / "s.zarr", workers=1)
    other = mc.StudySettings(samples=5, sigma=1000.0, seed=11, t_end=1.0, output_step=0.05)
    with pytest.raises(ValueError, match="different study"):
        mc.run_study(small_case, other, tmp_path / "s.zarr", workers=1)


@pytest.mark.parametrize("kwargs, field", [
    (dict(samples=0, sigma=1.0), "samples"), (dict(samples=2, sigma=-1.0), "sigma"),
    (dict(samples=2, sigma=1.0, seed=-3), "seed"), (dict(samples=2, sigma=1.0, t_end=0.0), "t_end"),
])
def test_bad_settings_are_refused(kwargs, field):
    with pytest.raises(ValueError, match=field):
        mc.StudySettings(**kwargs)


def test_dask_cluster_gives_the_same_result(small_case, tmp_path):
    from distributed import LocalCluster

    local = mc.run_study(small_case, SETTINGS, tmp_path / "local.zarr", workers=1)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:
        remote = mc.run_study(small_case, SETTINGS, tmp_path / "dask.zarr",
                              scheduler=cluster.scheduler_address)
    assert remote.completed == local.completed
    assert_same(arrays(tmp_path / "local.zarr"), arrays(tmp_path / "dask.zarr"))


def die_on_index_2(case, settings, index):
    """A realization task whose worker process dies on realization 2 (as on a crash or OOM kill)."""
    if index == 2:
        os._exit(1)
    return mc.run_realization(case, settings, index)


def test_realization_that_kills_its_worker_is_recorded_not_retried_forever(small_case, tmp_path):
    store = mc.StudyStore(tmp_path / "crash.zarr", small_case, SETTINGS)
    mc._run_processes(small_case, SETTINGS, list(range(SETTINGS.samples)), 2, store.write,
                      task=die_on_index_2)
    status = store.status()
    assert status[2] == mc.FAILED and "worker process died" in store.failures()["2"]
    assert np.all(status[[0, 1, 3, 4]] == mc.DONE)
    # The others are exactly what an undisturbed run computes.
    mc.run_study(small_case, SETTINGS, tmp_path / "ref.zarr", workers=1)
    a, b = arrays(tmp_path / "crash.zarr"), arrays(tmp_path / "ref.zarr")
    for name in ("rate_of_penetration", "bit_speed"):
        np.testing.assert_array_equal(a[name][[0, 1, 3, 4]], b[name][[0, 1, 3, 4]])


def test_drawn_weights_agree_with_the_statics_with_fluid_axial_loads(small_case):
    """One source of truth for the string's weight: with the mud's axial loads on (8.7 kN on the
    reference string), the mean weight-on-hook is the static hook load and each drawn weight-on-hook is
    the hook load of the static state at the derived weight-on-bit."""
    from drillstring.statics import case_static_state

    case = small_case.model_copy(update={"fluid": small_case.fluid.model_copy(update={"axial_loads": True})})
    assert abs(case.weight - small_case.weight) > 5e3
    assert mc.nominal_weight_on_hook(case) == pytest.approx(case_static_state(case).weight_on_hook, rel=1e-10)
    for index in (0, 3):
        woh = mc.draw_weight_on_hook(case, SETTINGS, index)
        outcome = mc.run_realization(case, mc.StudySettings(samples=5, sigma=5000.0, seed=11, t_end=0.1,
                                                            output_step=0.05), index)
        assert outcome.weight_on_hook == woh
        static = case_static_state(case, weight_on_bit=outcome.weight_on_bit)
        assert static.weight_on_hook == pytest.approx(woh, rel=1e-10)
