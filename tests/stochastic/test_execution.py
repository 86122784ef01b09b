"""The task runner: in-process and local processes give the same outcomes; interruption keeps what
finished; a task that kills its worker is recorded as failed (the study-level tests cover Dask, SIGKILL
of the parent and the lock)."""

import os

import numpy as np
import pytest

from drillstring.stochastic import execution
from drillstring.stochastic.execution import TaskOutcome
from drillstring.stochastic.store import DONE, FAILED


def square(argument):
    index, x = argument
    if x == 13:
        os._exit(3)  # a crash that kills the worker process
    return TaskOutcome(index, DONE, "", {"y": x * x})


def collect(items, **kwargs):
    got = []
    execution.execute(square, items, got.append, **kwargs)
    return {o.index: (o.status, o.values.get("y"), o.message) for o in got}


def test_processes_and_in_process_agree_and_a_crash_is_isolated():
    items = [(i, (i, float(i))) for i in range(6)]
    assert collect(items, workers=1) == collect(items, workers=2) == {i: (DONE, i * i, "") for i in range(6)}
    crashing = items + [(6, (6, 13.0))]
    result = collect(crashing, workers=2, noun="rows")
    assert result[6][0] == FAILED and "worker process died" in result[6][2]
    assert all(result[i] == (DONE, i * i, "") for i in range(6))


class Memory:
    """A minimal store for run_tasks."""

    path = "memory"

    def __init__(self, total):
        self.total, self.rows, self.sessions = total, {}, []

    def counts(self):
        return sum(o.status == DONE for o in self.rows.values()), sum(o.status == FAILED for o in self.rows.values())

    def write_many(self, outcomes):
        self.rows.update({o.index: o for o in outcomes})

    def record_session(self, *args):
        self.sessions.append(args)


def test_interruption_writes_what_finished():
    store = Memory(5)

    def stop(done, failed, total):
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(execution.Interrupted, match="map interrupted after 3 of 5 points"):
        execution.run_tasks(store, square, [(i, (i, float(i))) for i in range(5)],
                            execution.Engine(workers=1, progress=stop), what="map", noun="points")
    assert sorted(store.rows) == [0, 1, 2] and len(store.sessions) == 1
    report = execution.run_tasks(store, square, [(i, (i, float(i))) for i in (3, 4)], execution.Engine(workers=1))
    assert report.completed == 5 and report.computed == 2


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(workers=0), ValueError, "^workers = 0: must be an integer >= 1"),
    (dict(workers=1.5), TypeError, "^workers = 1.5: must be an integer"),
    (dict(workers=True), TypeError, "^workers = True: must be an integer"),
    (dict(workers=2, scheduler="tcp://x:1"), ValueError, "not both"),
    (dict(scheduler=8786), TypeError, "^scheduler = 8786: must be an address like 'tcp://host:8786' or a"),
    (dict(progress="bar"), TypeError, "^progress = 'bar': must be a callable"),
    (dict(worker_timeout=0.0), ValueError, "^worker_timeout = 0.0 s: must be a finite number > 0"),
])
def test_bad_engine_options(kwargs, error, message):
    with pytest.raises(error, match=message):
        execution.Engine(**kwargs)


def test_engine_takes_numpy_integers():
    engine = execution.Engine(workers=np.int64(2))
    assert type(engine.workers) is int and engine.workers == 2


def test_run_locked_in_passes_each_choosing_from_what_the_previous_wrote(tmp_path):
    """A run in passes (the optimiser's batches): the second pass reads the first's outcomes from the store;
    an empty pass is skipped, the run's counts are the whole store's, and ``prepare`` runs once."""
    store = Memory(4)
    seen, prepared = [], []

    def passes(memory):
        yield [(0, (0, 2.0)), (1, (1, 4.0))]
        yield []  # nothing to run: skipped
        first = [memory.rows[i].values["y"] for i in (0, 1)]
        seen.append(first)
        yield [(2, (2, first[0] + first[1])), (3, (3, 1.0))]

    run = execution.run_locked(tmp_path / "store", lambda: store, None, square, execution.Engine(workers=1),
                               passes=passes, prepare=lambda: prepared.append(1))
    assert seen == [[4.0, 16.0]]
    assert store.rows[2].values["y"] == 20.0 ** 2
    assert (run.completed, run.failed, run.computed) == (4, 0, 4)
    assert prepared == [1]
    assert len(store.sessions) == 2  # the empty pass recorded no session
    with pytest.raises(TypeError, match="one of pending and passes"):
        execution.run_locked(tmp_path / "other", lambda: store, lambda s: [], square, passes=passes)


def test_batches_hold_at_most_the_store_flush_count():
    """A store that asks for batches (a long flush_interval) gets them no larger than its flush_count, the last
    one at the end of the run; every outcome written once."""
    store = Memory(7)
    store.flush_interval, store.flush_count = 1e9, 3
    sizes = []
    write = store.write_many
    store.write_many = lambda outcomes: (sizes.append(len(outcomes)), write(outcomes))
    execution.run_tasks(store, square, [(i, (i, float(i))) for i in range(7)], execution.Engine(workers=1))
    assert sizes == [3, 3, 1] and sorted(store.rows) == list(range(7))


def test_cancelled_futures_of_a_lost_scheduler_say_so():
    """The client cancels its futures itself when its scheduler's connection drops (seen first on a loaded
    machine when the scheduler is killed): that is a lost scheduler, not a scheduler that cancelled them."""
    from drillstring.stochastic.dask_watch import cancelled_reason

    class Client:
        def __init__(self, status, answers):
            self.status, self.answers = status, answers
            self.scheduler = type("Scheduler", (), {"identity": None})()

        def sync(self, function, callback_timeout):
            if not self.answers:
                raise OSError("connection refused")
            return {}

    address = "tcp://127.0.0.1:1"
    assert cancelled_reason(Client("closed", True), address).startswith(f"lost the Dask scheduler at {address}")
    assert cancelled_reason(Client("running", False), address) == f"lost the Dask scheduler at {address} (OSError)"
    assert cancelled_reason(Client("running", True), address) == f"the Dask scheduler at {address} cancelled the tasks"
