"""Monte Carlo engine: reproducibility across worker counts, resume, failures recorded and excluded."""

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from functools import partial

import numpy as np
import pytest
import zarr
from scipy.stats import norm

from drillstring.stochastic import execution
from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic.analysis import load_study, study_statistics
from drillstring.stochastic.locks import StudyLocked
from drillstring.stochastic.maxent import realization_generator
from drillstring.stochastic.store import DONE, FAILED, StoreError

ARRAYS = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit",
          "radial_displacement", "weight_on_hook", "status", "nominal_bit_speed")


def woh_settings(case, sigma=5000.0, **kwargs):
    """Study settings of a random weight-on-hook, Normal of standard deviation ``sigma`` [N] (what a study's
    ``sigma`` declares)."""
    return mc.StudySettings(laws=(mc.weight_on_hook_normal(case, sigma),), **kwargs)


@pytest.fixture
def study5(small_case):
    return woh_settings(small_case, samples=5, seed=11, t_end=1.0, output_step=0.05)


def arrays(path):
    g = zarr.open_group(str(path), mode="r")
    return {name: g[name][:] for name in ARRAYS}


def assert_same(a, b):
    for name in ARRAYS:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def woh_draw(case, settings, index):
    """The weight-on-hook [N] of realization ``index`` (the first random parameter of ``woh_settings``)."""
    return float(mc.draw_inputs(case, settings, index)[0])


def test_draws_depend_only_on_seed_and_index(small_case, study5):
    first = [woh_draw(small_case, study5, i) for i in (3, 0, 4)]
    again = [woh_draw(small_case, study5, i) for i in (0, 3, 4)]
    assert first[0] == again[1] and first[1] == again[0] and first[2] == again[2]
    mean = mc.nominal_weight_on_hook(small_case)
    # the inverse distribution function of the Normal law at the realization's own uniform draw
    expected = norm.ppf(realization_generator(11, 3).random(1)[0], loc=mean, scale=5000.0)
    assert first[0] == pytest.approx(expected, rel=1e-12)
    assert woh_draw(small_case, study5, mc.NOMINAL) == mean


def test_one_and_two_workers_give_identical_results(small_case, study5, tmp_path):
    one = mc.run_study(small_case, study5, tmp_path / "one.zarr", execution.Engine(workers=1))
    two = mc.run_study(small_case, study5, tmp_path / "two.zarr", execution.Engine(workers=2))
    assert one.completed == two.completed == study5.samples
    assert_same(arrays(tmp_path / "one.zarr"), arrays(tmp_path / "two.zarr"))


def test_interrupted_study_resumes_to_the_same_result(small_case, study5, tmp_path):
    reference = mc.run_study(small_case, study5, tmp_path / "ref.zarr", execution.Engine(workers=1))
    assert reference.failed == 0

    def interrupt_after_two(done, failed, total):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(execution.Interrupted, match="resume"):
        mc.run_study(small_case, study5, tmp_path / "cut.zarr",
                     execution.Engine(workers=1, progress=interrupt_after_two))
    status = zarr.open_group(str(tmp_path / "cut.zarr"))["status"][:]
    assert np.sum(status == DONE) == 2
    resumed = mc.run_study(small_case, study5, tmp_path / "cut.zarr", execution.Engine(workers=1))
    assert resumed.completed == study5.samples
    assert_same(arrays(tmp_path / "ref.zarr"), arrays(tmp_path / "cut.zarr"))


#: Realizations of the killed study: on the 2-core machine 40 were all written within 0.2 s of the first batch
#: (measured: 0, 8, 40 at 0.2 s polls), so a poll under load (CI's tests on two workers) could see 0 and then 40
#: and the study was never killed mid-way (a CI failure); 200 keep it writing for about 2 s (10 polls).
KILLED_SAMPLES = 200

KILL_SCRIPT = """
import sys
from drillstring.case import case_from_dict
import tomllib
from drillstring.stochastic import execution, montecarlo as mc
if __name__ == "__main__":
    case = case_from_dict(tomllib.loads(open(sys.argv[1]).read()))
    settings = mc.StudySettings(samples=int(sys.argv[3]), seed=11, t_end=1.0, output_step=0.05,
                                laws=(mc.weight_on_hook_normal(case, 5000.0),))
    mc.run_study(case, settings, sys.argv[2], execution.Engine(workers=2))
"""


def _done_in(store) -> int:
    try:
        return int(np.sum(zarr.open_group(str(store), mode="r")["status"][:] == DONE))
    except Exception:  # not created yet
        return 0


def test_killed_process_resumes_to_the_same_result(small_case, tmp_path):
    """kill -9 of a study running on 2 worker processes: the rerun takes over the stale lock (with a
    note), its workers are gone, and it resumes to exactly the uninterrupted result."""
    settings = woh_settings(small_case, 5000.0, samples=KILLED_SAMPLES, seed=11, t_end=1.0, output_step=0.05)
    case_file = tmp_path / "case.toml"
    case_file.write_text(small_case.to_toml())
    script = tmp_path / "kill_me.py"  # a file, so that spawned workers can import the main module
    script.write_text(KILL_SCRIPT)
    store = tmp_path / "killed.zarr"
    proc = subprocess.Popen([sys.executable, str(script), str(case_file), str(store), str(KILLED_SAMPLES)])
    deadline = time.time() + 180
    done = 0
    while time.time() < deadline and proc.poll() is None and done < 3:
        time.sleep(0.2)
        done = _done_in(store)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert 3 <= done < KILLED_SAMPLES, "the process should have been killed mid-study"
    assert (tmp_path / "killed.zarr.lock").read_text().strip(), "the killed study left its lock record"
    with pytest.warns(RuntimeWarning, match=f"stale lock .*pid {proc.pid}"):
        resumed = mc.run_study(small_case, settings, store, execution.Engine(workers=2))
    assert resumed.completed == KILLED_SAMPLES and resumed.computed == KILLED_SAMPLES - _done_before(resumed)
    assert not (tmp_path / "killed.zarr.lock").exists()  # released cleanly
    mc.run_study(small_case, settings, tmp_path / "full.zarr", execution.Engine(workers=1))
    assert_same(arrays(store), arrays(tmp_path / "full.zarr"))


def _done_before(run) -> int:
    return run.completed + run.failed - run.computed


def test_failed_realizations_are_recorded_and_excluded(small_case, study5, tmp_path, monkeypatch):
    """Two failure kinds: a diverging integration, and a draw that is physically impossible."""
    real = mc.simulate_model
    nominal_wob = small_case.operation.weight_on_bit

    def diverge_above_nominal(model, **kwargs):
        if model.weight_on_bit > nominal_wob:
            kwargs["max_steps"] = 5  # the integrator gives up: a genuine SimulationError
        return real(model, **kwargs)

    monkeypatch.setattr(mc, "simulate_model", diverge_above_nominal)
    run = mc.run_study(small_case, study5, tmp_path / "f.zarr", execution.Engine(workers=1))
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

    # A draw outside (0, string weight) cannot run: recorded as failed with the cause (a study with
    # such a sigma is refused before running, see test_impossible_sigma_is_refused_before_running).
    wild = woh_settings(small_case, 3e5, samples=6, seed=1, t_end=0.2, output_step=0.05)
    draws = [woh_draw(small_case, wild, i) for i in range(6)]
    impossible = next(i for i, woh in enumerate(draws) if not 0 < small_case.weight - woh < small_case.weight)
    outcome = mc.run_realization(small_case, wild, impossible)
    assert outcome.status == FAILED and "weight_on_bit" in outcome.message


def test_store_with_other_settings_is_refused(small_case, study5, tmp_path):
    mc.run_study(small_case, study5, tmp_path / "s.zarr", execution.Engine(workers=1))
    other = woh_settings(small_case, 1000.0, samples=5, seed=11, t_end=1.0, output_step=0.05)
    with pytest.raises(ValueError, match="different study"):
        mc.run_study(small_case, other, tmp_path / "s.zarr", execution.Engine(workers=1))


TOP_SPEED = (("operation.top_speed", "normal 100 5 rpm"),)


@pytest.mark.parametrize("kwargs, field", [
    (dict(samples=0), "samples"), (dict(samples=1), "samples"), (dict(samples=2.5), "samples"),
    (dict(samples=2, seed=-3), "seed"), (dict(samples=2, seed=2**64), "seed"), (dict(samples=2, seed=1.0), "seed"),
    (dict(samples=2, t_end=0.0), "t_end"), (dict(samples=2, t_end=float("inf")), "t_end"),
    (dict(samples=2, t_end=1.0, output_step=float("nan")), "output_step"),
    (dict(samples=2, t_end=1.0, output_step=-0.1), "output_step"),
    (dict(samples=2, laws=TOP_SPEED * 2), "operation.top_speed is declared twice"),
])
def test_bad_settings_are_refused(kwargs, field):
    with pytest.raises((TypeError, ValueError), match=f"^{field}"):
        mc.StudySettings(**{"laws": TOP_SPEED, **kwargs})


def test_numpy_integers_are_integers():
    settings = mc.StudySettings(samples=np.int64(3), seed=np.uint64(2**64 - 1), laws=TOP_SPEED)
    assert type(settings.samples) is int and settings.samples == 3 and settings.seed == 2**64 - 1


def test_out_of_range_probability_against_the_normal_law(small_case):
    """P(wob outside (0, W)) = Φ(−wob/σ) + Φ(−(W − wob)/σ), checked against SciPy's Normal law and by
    sampling; the largest accepted sigma puts it exactly at the threshold."""
    from scipy.stats import norm

    weight, wob = small_case.weight, small_case.operation.weight_on_bit
    for sigma in (1e4, 3e4, 1e5, 1e6):
        expected = norm.cdf(0.0, loc=wob, scale=sigma) + norm.sf(weight, loc=wob, scale=sigma)
        assert mc.weight_on_bit_out_of_range_probability(small_case, sigma) == pytest.approx(expected, rel=1e-9)
    wide = woh_settings(small_case, 1e5, samples=2, seed=3)  # the study's own draws
    drawn = small_case.weight - mc.study_uncertainty(small_case, wide).draw(wide.seed, range(200_000))[:, 0]
    observed = np.mean((drawn <= 0) | (drawn >= weight))
    assert observed == pytest.approx(mc.weight_on_bit_out_of_range_probability(small_case, 1e5), rel=0.02)
    limit = mc.largest_accepted_sigma(small_case)
    assert mc.weight_on_bit_out_of_range_probability(small_case, limit) == pytest.approx(
        mc.OUT_OF_RANGE_PROBABILITY, rel=1e-6)
    assert limit == pytest.approx(wob / norm.isf(mc.OUT_OF_RANGE_PROBABILITY), rel=1e-3)  # the W side is negligible


def test_impossible_sigma_is_refused_before_running(small_case, tmp_path):
    settings = woh_settings(small_case, 1e6, samples=10, seed=0, t_end=1.0, output_step=0.05)
    with pytest.raises(ValueError, match=r"^sigma = 1e\+06 N: .* probability 0\.\d+, above 0\.001.* at most 32,\d+ N \(32\.\d+ kN\)"):
        mc.run_study(small_case, settings, tmp_path / "s.zarr", execution.Engine(workers=1))
    assert not (tmp_path / "s.zarr").exists()
    accepted = woh_settings(small_case, 0.99 * mc.largest_accepted_sigma(small_case), samples=2, t_end=0.1,
                                output_step=0.05)
    mc.check_study(small_case, accepted)  # just below the threshold: accepted


def test_a_finished_study_keeps_its_computation_time(small_case, study5, tmp_path):
    first = mc.run_study(small_case, study5, tmp_path / "s.zarr", execution.Engine(workers=1))
    again = mc.run_study(small_case, study5, tmp_path / "s.zarr", execution.Engine(workers=1))
    assert first.computed == study5.samples and again.computed == 0
    sessions = again.store.sessions()
    assert len(sessions) == 1 and sessions[0]["realizations"] == study5.samples
    assert execution.computation_time(sessions) == (first.wall_time, 1)


# --- store checks and locks ---------------------------------------------------------------------


def test_a_folder_that_is_not_a_study_store_is_refused(small_case, study5, tmp_path):
    mc.run_study(small_case, study5, tmp_path / "s.zarr", execution.Engine(workers=1))
    group = zarr.open_group(str(tmp_path / "s.zarr"), mode="a")
    del group["status"]
    for attempt in (lambda: mc.run_study(small_case, study5, tmp_path / "s.zarr", execution.Engine(workers=1)),
                    lambda: load_study(tmp_path / "s.zarr")):
        with pytest.raises(StoreError, match=r"missing array\(s\): status\); delete it"):
            attempt()
    foreign = tmp_path / "foreign.zarr"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(StoreError, match="not a drillstring study store .no zarr.json"):
        mc.run_study(small_case, study5, foreign, execution.Engine(workers=1))
    assert (foreign / "notes.txt").read_text() == "mine"  # left alone
    other = tmp_path / "other.zarr"
    zarr.open_group(str(other), mode="w").create_array("a", shape=(2,), dtype="f8")
    with pytest.raises(StoreError, match="no fingerprint, settings, case attribute"):
        load_study(other)
    (other / "zarr.json").write_text("{not json")
    with pytest.raises(StoreError, match="not a readable Zarr store"):
        load_study(other)


HOLD_SCRIPT = """
import sys, time
from drillstring.stochastic.locks import StudyLock
with StudyLock(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(120)
"""


def test_a_store_in_use_is_refused_for_writing_and_reading(small_case, study5, tmp_path):
    """Another process holds the study's lock: running or reading that store is refused at once,
    naming the holder; once it is gone (kill -9), its stale lock is taken over with a note."""
    store = tmp_path / "s.zarr"
    mc.run_study(small_case, study5, store, execution.Engine(workers=1))
    holder = subprocess.Popen([sys.executable, "-c", HOLD_SCRIPT, str(store)], stdout=subprocess.PIPE,
                              text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(StudyLocked, match=f"in use by pid {holder.pid} on host .*another --out"):
            mc.run_study(small_case, study5, store, execution.Engine(workers=1))
        with pytest.raises(StudyLocked, match="no study is writing it"):
            load_study(store)
    finally:
        holder.kill()
        holder.wait()
    notes = []
    run = mc.run_study(small_case, study5, store, execution.Engine(workers=1, note=notes.append))
    assert run.completed == study5.samples and len(notes) == 1
    assert f"stale lock (pid {holder.pid}" in notes[0] and run.note == notes[0]
    assert load_study(store).sizes["realization"] == study5.samples


def test_a_store_is_created_whole_or_not_at_all(small_case, study5, tmp_path, monkeypatch):
    """A creation that fails midway leaves no store (and no temporary folder) behind."""
    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(mc.StudyStore, "_create", staticmethod(broken))
    with pytest.raises(OSError, match="disk full"):
        mc.run_study(small_case, study5, tmp_path / "s.zarr", execution.Engine(workers=1))
    assert sorted(p.name for p in tmp_path.iterdir()) == []


# --- Dask ----------------------------------------------------------------------------------------


def test_dask_cluster_gives_the_same_result_and_stops_resumably_without_workers(small_case, study5, tmp_path):
    """A real cluster (2 worker processes) computes exactly the local result. When every worker
    leaves mid-study, the study says so and stops; with workers back, the rerun resumes."""
    from distributed import LocalCluster

    local = mc.run_study(small_case, study5, tmp_path / "local.zarr", execution.Engine(workers=1))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        whole = mc.run_study(small_case, study5, tmp_path / "dask.zarr",
                             execution.Engine(scheduler=cluster.scheduler_address))
        assert whole.completed == local.completed and whole.workers == cluster.scheduler_address
        worker = next(iter(cluster.scheduler_info["workers"]))
        with pytest.raises(execution.SchedulerUnreachable, match="that is a Dask Worker, not a scheduler"):
            execution.connect_scheduler(worker)

        def workers_leave(done, failed, total):
            # scale() only asks: the workers close on the cluster's loop. Wait until they have, so that the
            # realizations they finished but the study has not fetched yet leave with them (otherwise a fast
            # machine fetches all five before the workers close, and nothing is lost).
            if done == 2 and cluster.workers:
                cluster.scale(0)
                deadline = time.monotonic() + 30.0
                while cluster.workers and time.monotonic() < deadline:
                    time.sleep(0.02)
                assert not cluster.workers, "the local cluster's workers did not close within 30 s"

        with pytest.raises(execution.WorkersLost, match="no worker for 2 s.*saved.*resume"):
            mc.run_study(small_case, study5, tmp_path / "lost.zarr", execution.Engine(
                scheduler=cluster.scheduler_address, progress=workers_leave, worker_timeout=2.0))
        assert 2 <= _done_in(tmp_path / "lost.zarr") < study5.samples
        cluster.scale(2)
        cluster.wait_for_workers(2)
        resumed = mc.run_study(small_case, study5, tmp_path / "lost.zarr",
                               execution.Engine(scheduler=cluster.scheduler_address))
        assert resumed.completed == study5.samples and _done_before(resumed) >= 2
    assert_same(arrays(tmp_path / "local.zarr"), arrays(tmp_path / "dask.zarr"))
    assert_same(arrays(tmp_path / "local.zarr"), arrays(tmp_path / "lost.zarr"))


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _tcp_server(greeting: bytes | None) -> socket.socket:
    """A loopback TCP server that is not a Dask scheduler: it accepts connections and sends
    ``greeting`` (or nothing) and then stays silent."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    kept = []

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            kept.append(conn)
            if greeting:
                conn.sendall(greeting)

    threading.Thread(target=serve, daemon=True).start()
    return server


@pytest.mark.parametrize("kind, message", [
    ("closed", "connection refused"),
    ("silent", "the server there sent no Dask greeting within 1 s .not a Dask scheduler"),
    ("ssh", "the server there does not speak the Dask protocol .not a Dask scheduler"),
    ("http", "the server there does not speak the Dask protocol .not a Dask scheduler"),
    ("malformed", "not an address like tcp://host:8786"),
])
def test_a_scheduler_address_that_is_no_scheduler_fails_fast(small_case, study5, tmp_path, kind, message):
    server = None
    if kind == "closed":
        address = f"tcp://127.0.0.1:{_closed_port()}"
    elif kind == "malformed":
        address = "tcp://127.0.0.1:notaport"
    else:
        greeting = {"silent": None, "ssh": b"SSH-2.0-OpenSSH_9.6\r\n",
                    "http": b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n"}[kind]
        server = _tcp_server(greeting)
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    try:
        with pytest.raises(execution.SchedulerUnreachable, match=f"^scheduler = '{address}': {message}"):
            execution.connect_scheduler(address, timeout=1.0)
        with pytest.raises(execution.SchedulerUnreachable):  # nothing created
            mc.run_study(small_case, study5, tmp_path / "s.zarr", execution.Engine(scheduler=address))
        assert not (tmp_path / "s.zarr").exists()
    finally:
        if server is not None:
            server.close()


# --- worker processes that die -----------------------------------------------------------------


def die_on_index_2(case, settings, index):
    """A realization task whose worker process dies on realization 2 (as on a crash or OOM kill); it
    logs "index pid" first to the file named by $DRILLSTRING_TEST_LOG."""
    with open(os.environ["DRILLSTRING_TEST_LOG"], "a") as log:
        log.write(f"{index} {os.getpid()}\n")
    if index == 2:
        os._exit(1)
    return mc.run_realization(case, settings, index)


def test_realization_that_kills_its_worker_is_isolated_and_the_others_stay_parallel(
        small_case, tmp_path, monkeypatch):
    """Only the realizations running when the worker died are rerun alone (the culprit is recorded as
    failed, the innocent one finishes); the others keep running on the 2-process pool: at most 3 pools'
    worth of processes, not one fresh process per remaining realization."""
    settings = woh_settings(small_case, 5000.0, samples=10, seed=11, t_end=1.0, output_step=0.05)
    log = tmp_path / "log.txt"
    monkeypatch.setenv("DRILLSTRING_TEST_LOG", str(log))
    store = mc.StudyStore(tmp_path / "crash.zarr", small_case, settings)
    execution._run_processes(partial(die_on_index_2, small_case, settings),
                             [(i, i) for i in range(settings.samples)], 2, store.write,
                             lost=partial(mc._worker_died, small_case, settings))
    status = store.status()
    assert status[2] == FAILED and "worker process died" in store.failures()["2"]
    others = [i for i in range(settings.samples) if i != 2]
    assert np.all(status[others] == DONE)
    started = [line.split() for line in log.read_text().splitlines()]  # (index, pid) per start
    pids = {pid for _, pid in started}
    assert len(pids) <= 3 * 2, f"{len(pids)} worker processes for {settings.samples} realizations"
    assert [index for index, _ in started].count("2") == 2  # in the pool, then alone
    # The others are exactly what an undisturbed run computes.
    mc.run_study(small_case, settings, tmp_path / "ref.zarr", execution.Engine(workers=1))
    a, b = arrays(tmp_path / "crash.zarr"), arrays(tmp_path / "ref.zarr")
    for name in ("rate_of_penetration", "bit_speed", "weight_on_hook"):
        np.testing.assert_array_equal(a[name][others], b[name][others])


def test_drawn_weights_agree_with_the_statics_with_fluid_axial_loads(small_case, study5):
    """One source of truth for the string's weight: with the mud's axial loads on (8.7 kN on the
    reference string), the mean weight-on-hook is the static hook load and each drawn weight-on-hook is
    the hook load of the static state at the derived weight-on-bit."""
    from drillstring.statics import case_static_state

    case = small_case.model_copy(update={"fluid": small_case.fluid.model_copy(update={"axial_loads": True})})
    assert abs(case.weight - small_case.weight) > 5e3
    assert mc.nominal_weight_on_hook(case) == pytest.approx(case_static_state(case).weight_on_hook, rel=1e-10)
    for index in (0, 3):
        woh = woh_draw(case, woh_settings(case, 5000.0, samples=5, seed=11), index)
        outcome = mc.run_realization(case, woh_settings(case, 5000.0, samples=5, seed=11, t_end=0.1,
                                                        output_step=0.05), index)
        assert outcome.weight_on_hook == woh
        static = case_static_state(case, weight_on_bit=outcome.weight_on_bit)
        assert static.weight_on_hook == pytest.approx(woh, rel=1e-10)


# --- random parameters other than the weight-on-hook --------------------------------------------

LAWS = (("fluid.inlet_velocity", "uniform 1.2 1.8 m/s"), ("operation.top_speed", "normal 100 5 rpm"))


def test_a_realization_is_the_case_with_its_drawn_values(small_case, monkeypatch):
    """Realization i of a study drawing two parameters is exactly the deterministic run of the case with
    the values Uncertainty.draw(seed, i) gives them when its model is rebuilt, and equal to it to the
    parametric model's round-off (1e-9) from the study's parametric model; those values are recorded with it."""
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model
    from drillstring.stochastic.parameters import with_parameters
    from drillstring.stochastic.runs import simulation_options
    from drillstring.stochastic.study_model import REBUILD_VARIABLE
    from drillstring.stochastic.uncertainty import uncertainty

    settings = mc.StudySettings(samples=4, seed=5, t_end=0.5, output_step=0.05, laws=LAWS)
    law = uncertainty(small_case, dict(LAWS))
    outcome = mc.run_realization(small_case, settings, 3)
    assert outcome.status == DONE
    drawn = law.draw(5, [3])[0]
    np.testing.assert_array_equal(outcome.inputs, drawn)
    assert 1.2 <= drawn[0] <= 1.8 and drawn[1] != small_case.operation.top_speed
    realized = with_parameters(small_case, {"fluid.inlet_velocity": drawn[0], "operation.top_speed": drawn[1]})
    direct = simulate_model(case_reduced_model(realized), **simulation_options(realized, 0.5, 0.05))
    np.testing.assert_allclose(outcome.observables["bit_speed"], direct.observables["bit_speed"], rtol=1e-9)
    monkeypatch.setenv(REBUILD_VARIABLE, "1")
    rebuilt = mc.run_realization(small_case, settings, 3)
    np.testing.assert_array_equal(rebuilt.observables["bit_speed"], direct.observables["bit_speed"])
    assert outcome.weight_on_hook == small_case.weight_on_hook  # not random here
    nominal = mc.run_realization(small_case, settings, mc.NOMINAL)
    np.testing.assert_allclose(nominal.inputs, [1.5, 100 * np.pi / 30], rtol=1e-12)  # the means


def test_study_of_several_parameters_records_draws_laws_and_refuses_other_laws(small_case, tmp_path):
    settings = mc.StudySettings(samples=3, seed=2, t_end=0.3, output_step=0.05, laws=LAWS)
    run = mc.run_study(small_case, settings, tmp_path / "s.zarr", execution.Engine(workers=1))
    assert run.completed == 3
    raw = load_study(tmp_path / "s.zarr")
    assert raw.attrs["parameters"] == ["fluid.inlet_velocity", "operation.top_speed"]
    assert raw.attrs["laws"] == ["uniform 1.2 1.8 m/s", "normal 100 5 rpm"]
    assert raw.attrs["parameter_units"] == ["m/s", "rad/s"]
    expected = mc.study_uncertainty(small_case, settings).draw(2, range(3))
    np.testing.assert_array_equal(raw.input_values.values, expected)
    stats = study_statistics(raw)
    np.testing.assert_array_equal(stats.input_values.values, expected)
    other = mc.StudySettings(samples=3, seed=2, t_end=0.3, output_step=0.05,
                             laws=(LAWS[0], ("operation.top_speed", "normal 100 6 rpm")))
    with pytest.raises(ValueError, match="different study .*laws"):
        mc.run_study(small_case, other, tmp_path / "s.zarr", execution.Engine(workers=1))


def test_correlated_normal_draws(small_case):
    """Top speed and weight-on-hook drawn jointly with correlation −0.6: the study's draws are the
    multivariate normal (sample correlation, means and standard deviations)."""
    settings = mc.StudySettings(samples=2, laws=(mc.weight_on_hook_normal(small_case, 5000.0), *TOP_SPEED),
                                correlated=("operation.top_speed", "weight_on_hook"),
                                correlation=((1.0, -0.6), (-0.6, 1.0)))
    law = mc.study_uncertainty(small_case, settings)
    assert law.paths == ("weight_on_hook", "operation.top_speed")
    values = np.array([mc.draw_inputs(small_case, settings, i) for i in range(4000)])
    r = np.corrcoef(values.T)[0, 1]
    assert r == pytest.approx(-0.6, abs=4 / np.sqrt(4000))
    assert values[:, 0].std() == pytest.approx(5000.0, rel=0.05)
    assert values[:, 1].mean() == pytest.approx(100 * np.pi / 30, abs=4 * (5 * np.pi / 30) / np.sqrt(4000))


@pytest.mark.parametrize("laws, message", [
    # below the top speed's floor, 1e-3 rad/s (0.0095 rpm): P = Φ((0.0095 - 10)/5) = 0.0229
    ((("operation.top_speed", "normal 10 5 rpm"),), r"probability 0\.0229 outside .*at most 0\.001"),
    ((("operation.top_sped", "normal 100 5 rpm"),), "did you mean 'top_speed'"),
    ((("fluid.inlet_velocity", "uniform 1.8 1.2 m/s"),), "fluid.inlet_velocity"),
    ((("weight_on_hook", "normal 1063 300 kN"),), r"^sigma = 300000 N: .* at most 32,\d+ N \(32\.\d+ kN\)"),
])
def test_impossible_laws_are_refused_before_running(small_case, tmp_path, laws, message):
    settings = mc.StudySettings(samples=2, t_end=0.2, output_step=0.05, laws=laws)
    with pytest.raises(ValueError, match=message):
        mc.run_study(small_case, settings, tmp_path / "s.zarr", execution.Engine(workers=1))
    assert not (tmp_path / "s.zarr").exists()


def test_settings_need_a_random_parameter():
    with pytest.raises(ValueError, match="no random parameter"):
        mc.StudySettings(samples=2)


def test_store_without_the_per_realization_metrics_is_refused(small_case, tmp_path):
    """A store written before the workers stored their cycle metrics and growth rate is refused with one
    line (a resumed study would have nowhere to write them)."""
    path = tmp_path / "old.zarr"
    store = mc.StudyStore(path, small_case, woh_settings(small_case, 1000.0, samples=2, t_end=0.2))
    assert "growth_rate" in store.group.attrs["layout"]
    layout = dict(store.group.attrs["layout"])
    del layout["growth_rate"]
    store.group.attrs["layout"] = layout
    from drillstring.stochastic.store import metadata_checksum  # an old store, consistent with itself

    store.group.attrs["metadata_checksum"] = metadata_checksum(dict(store.group.attrs))
    with pytest.raises(StoreError, match="older drillstring version .*no growth_rate"):
        mc.open_study_group(path)


def test_store_with_the_earlier_spelling_of_the_time_means_is_read(small_case, tmp_path):
    """A study store written when the realizations' time means were spelled ``rate_of_penetration_mean``,
    ... (before maps and studies shared ``mean_rate_of_penetration``, ...) reads as before: the same values
    under the one spelling, and the per-family growth rates it lacks are left out of the summary."""
    from drillstring.dynamics.indicators import RENAMED_METRICS
    from drillstring.stochastic.analysis import study_summary

    path = tmp_path / "old.zarr"
    mc.run_study(small_case, woh_settings(small_case, 1000.0, samples=2, t_end=0.2, output_step=0.05), path,
                 execution.Engine(workers=1))
    fresh = study_statistics(load_study(path))
    group = zarr.open_group(str(path), mode="a")
    layout = dict(group.attrs["layout"])
    for old, new in RENAMED_METRICS.items():
        for prefix in ("", "nominal_"):
            array = group[prefix + new]
            group.create_array(prefix + old, data=array[...], dimension_names=list(layout[prefix + new]),
                               attributes=dict(array.attrs))
            del group[prefix + new]
            layout[prefix + old] = layout.pop(prefix + new)
    for name in ("axial_growth_rate", "torsional_growth_rate", "lateral_growth_rate"):
        for prefix in ("", "nominal_"):
            del group[prefix + name]
            layout.pop(prefix + name)
    group.attrs["layout"] = layout
    # A store of that version had no metadata checksum either (both came with the same release).
    attrs = dict(group.attrs)
    attrs.pop("metadata_checksum")
    group.attrs.clear()
    group.attrs.update(attrs)
    raw = load_study(path)
    assert "rate_of_penetration_mean" not in raw and "mean_rate_of_penetration" in raw
    stats = study_statistics(raw)
    for new in RENAMED_METRICS.values():
        np.testing.assert_array_equal(stats[f"realization_{new}"].values, fresh[f"realization_{new}"].values)
    summary = study_summary(stats, t_transient=0.1)
    assert summary["stability"]["by_family"] == {}
    assert "mean_rate_of_penetration" in summary["realizations"]
