"""Running many independent tasks: local worker processes or a Dask cluster, outcomes recorded as they
finish, resumable through a :class:`~drillstring.stochastic.store.TaskStore`.

A *task* is a picklable callable ``task(argument) -> outcome``; each run is an *item* ``(index, argument)``
and its outcome carries ``index``, ``status`` (:data:`DONE` or :data:`FAILED`), ``message`` and
``wall_time`` (a :class:`TaskOutcome`, or any object with those attributes that its store can write).
Monte Carlo studies (one realization per index), operating maps (one grid point per index) and
sensitivity designs (one design row per index) all run through :func:`run_tasks`, which

- runs the items in this process (one worker), on a pool of spawned local processes, or on the Dask
  cluster of a ``distributed.Client`` (:func:`execute`);
- isolates a worker process that dies: the items that were running when the pool broke are set aside
  and each rerun alone at the end; the one that kills its worker again is recorded as failed with that
  cause, the others go on in parallel (:func:`_process_loop`);
- on Dask, records an item whose workers keep dying (``KilledWorker``) as failed, and stops resumably
  (:class:`WorkersLost`, one line) when, for ``worker_timeout`` seconds (:data:`DASK_WORKER_TIMEOUT`),
  the cluster has had no worker, or none of its workers has answered the scheduler (stopped with SIGSTOP,
  frozen), or the scheduler has not answered (each request bounded by :data:`SCHEDULER_TIMEOUT`); at once
  when the scheduler is gone (connection closed). While nothing finishes but some worker answers, a
  note says so every ``worker_timeout`` seconds (:class:`~drillstring.stochastic.dask_watch.ClusterWatch`);
- writes outcomes to the store in batches (at most :data:`FLUSH_INTERVAL` seconds apart; data first,
  then status flags), reports ``progress(done, failed, total)`` after each outcome, and on Ctrl-C
  writes what finished and raises :class:`Interrupted`;
- records each run that computed something as a *session* (start, wall time, count, workers), so that
  a resumed study's computation time is the sum of its sessions.

Reaching a scheduler is checked by hand first (:func:`connect_scheduler`): an address that is no Dask
scheduler fails within seconds with one line, instead of a client waiting forever.

No physics here; nothing above :mod:`drillstring.files`, :mod:`drillstring.stochastic.locks` and
:mod:`drillstring.stochastic.store` (the status flags) is imported.
"""

from __future__ import annotations

import concurrent.futures as cf
import datetime as _dt
import multiprocessing
import os
import threading
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Iterable, Sequence

from drillstring.stochastic.dask_watch import SCHEDULER_TIMEOUT, ClusterWatch, cancelled_reason, is_timeout
from drillstring.stochastic.store import DONE, FAILED

#: Seconds a Dask run waits, once nothing finishes, with no worker in the cluster, with no worker
#: answering the scheduler (their heartbeats stopped), or with no answer from the scheduler (two requests
#: of :data:`SCHEDULER_TIMEOUT` in a row at least), before stopping (resumably). The stop comes within
#: about ``DASK_WORKER_TIMEOUT + SCHEDULER_TIMEOUT + 2`` seconds of the fault (36 s; a lost scheduler
#: connection at once).
DASK_WORKER_TIMEOUT = 30.0
#: Largest delay [s] between an outcome's arrival and its write to the store, unless the store sets its
#: own ``flush_interval`` (outcomes are written in batches: a kill loses at most this much work; stores of
#: many cheap scalar rows rewrite their small arrays once per batch instead of once per outcome).
FLUSH_INTERVAL = 0.5

#: Thread counts for worker processes: one process per core, each single-threaded, so linear
#: algebra libraries do not oversubscribe the cores.
WORKER_ENVIRONMENT = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                      "NUMBA_NUM_THREADS": "1"}


@dataclass
class TaskOutcome:
    """What one task returns (picklable): its ``values`` are the store's row values by array name."""

    index: int
    status: int
    message: str = ""
    values: dict[str, Any] = field(default_factory=dict)
    wall_time: float = 0.0


class Interrupted(RuntimeError):
    """The run was interrupted; what finished is in the store and a rerun resumes."""


class WorkersLost(RuntimeError):
    """No worker is left to compute the tasks (Dask workers gone, worker processes that cannot start);
    what finished is in the store and a rerun resumes."""


class SchedulerUnreachable(ValueError):
    """The ``scheduler`` address does not lead to a Dask scheduler (refused, no answer, another
    protocol, malformed address)."""


ProgressCallback = Callable[[int, int, int], None]  # (done, failed, total)
#: Outcome of an item whose worker died: ``lost(index, argument, message)``.
LostOutcome = Callable[[int, Any, str], Any]


def bare_failure(index: int, argument: Any, message: str) -> TaskOutcome:
    """The default outcome of an item whose worker died: failed, with the cause, no values."""
    return TaskOutcome(index, FAILED, message)


# --- how a run executes --------------------------------------------------------------------------


@dataclass(frozen=True)
class Engine:
    """How a study, map or sensitivity run executes, given once to :func:`run_locked` (through
    ``run_study``, ``run_map``, ``run_sensitivity``) instead of one argument per layer.

    Attributes:
        workers: local worker processes (an integer >= 1; None: one per core; 1 runs in this process).
        scheduler: a Dask scheduler address (``tcp://host:8786``) or a connected ``distributed.Client``
            (left open); the tasks then run on its cluster. Not together with ``workers``.
        progress: called as ``progress(done, failed, total)`` after each outcome.
        note: called with one-line notes for the user (a stale lock taken over); None: a RuntimeWarning.
        worker_timeout: seconds a Dask run waits with no worker left before stopping (resumably).

    Checked when built: TypeError or ValueError naming the argument.
    """

    workers: int | None = None
    scheduler: Any = None
    progress: ProgressCallback | None = None
    note: Callable[[str], None] | None = None
    worker_timeout: float = DASK_WORKER_TIMEOUT

    def __post_init__(self) -> None:
        from drillstring.checks import integer, real_number

        if self.workers is not None:
            object.__setattr__(self, "workers", integer("workers", self.workers, low=1))
        scheduler = self.scheduler
        if scheduler is not None and not isinstance(scheduler, str) and not (
                hasattr(scheduler, "map") and hasattr(scheduler, "scheduler")):
            raise TypeError(f"scheduler = {scheduler!r}: must be an address like 'tcp://host:8786' or a "
                            "distributed.Client")
        if self.workers is not None and scheduler is not None:
            raise ValueError("give workers (local processes) or scheduler (Dask cluster), not both")
        for name in ("progress", "note"):
            if getattr(self, name) is not None and not callable(getattr(self, name)):
                raise TypeError(f"{name} = {getattr(self, name)!r}: must be a callable or None")
        object.__setattr__(self, "worker_timeout", real_number("worker_timeout", self.worker_timeout, unit="s",
                                                               low=0.0, low_open=True))


def local_workers(workers: int | None) -> int:
    """The number of local processes: ``workers``, or one per core."""
    return max(1, workers or multiprocessing.cpu_count())


def notify(note: Callable[[str], None] | None, text: str) -> None:
    """Give ``text`` to ``note``, or issue it as a RuntimeWarning when there is no ``note``, attributed to the
    caller's own code (the first frame outside this package and the standard library's decorators), not to a
    file of the standard library."""
    if note is None:
        import warnings

        warnings.warn(text, RuntimeWarning, stacklevel=_caller_level())
    else:
        note(text)


def _caller_level() -> int:
    """The ``stacklevel`` of :func:`notify`'s warning: the first frame, from :func:`notify`'s caller out, whose
    file is neither in this package nor ``contextlib`` (the decorators of the API functions)."""
    import contextlib
    import sys

    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    frame, level = sys._getframe(2), 2  # notify's caller is level 2 of warnings.warn
    while frame is not None:
        name = frame.f_code.co_filename
        if not name.startswith(package) and name != contextlib.__file__:
            return level
        frame, level = frame.f_back, level + 1
    return 2


def computation_time(sessions: list[dict]) -> tuple[float, int | str | None]:
    """(total wall time [s] of the runs that computed tasks, the workers of the last one)."""
    total = float(sum(float(s.get("wall_time", 0.0)) for s in sessions))
    return total, (sessions[-1].get("workers") if sessions else None)


# --- running into a store ------------------------------------------------------------------------


@dataclass
class RunReport:
    """What :func:`run_tasks` did.

    Attributes:
        completed, failed: items finished and failed in the store (all runs together).
        wall_time: wall time of this call [s].
        workers: what this call ran on (local process count or scheduler address).
        computed: items computed by this call (0 when everything was already done).
    """

    completed: int
    failed: int
    wall_time: float
    workers: int | str
    computed: int = 0


@dataclass
class StoreRun:
    """What :func:`run_locked` did: the ``store``, its items finished and failed (all runs together), this
    call's wall time [s], what it ran on (local process count or scheduler address), the items it
    computed, a ``note`` for the user (a stale lock taken over) or None, and ``result``: what ``finish``
    returned (None without one)."""

    store: Any
    completed: int
    failed: int
    wall_time: float
    workers: int | str
    computed: int = 0
    note: str | None = None
    result: Any = None

    @property
    def already(self) -> int:
        """Items that were in the store before this call (a resumed or finished run)."""
        return self.completed + self.failed - self.computed


def run_locked(
    store_path,
    open_store: Callable[[], Any],
    pending: Callable[[Any], Sequence[tuple[int, Any]]] | None,
    task: Callable[[Any], Any],
    engine: Engine = Engine(),
    *,
    passes: Callable[[Any], Iterable[Sequence[tuple[int, Any]]]] | None = None,
    lost: LostOutcome = bare_failure,
    prepare: Callable[[], Callable[[], None] | None] | None = None,
    finish: Callable[["StoreRun"], Any] | None = None,
    what: str = "study",
    noun: str = "realizations",
    lock_name: str | None = None,
) -> StoreRun:
    """The one way studies, maps and sensitivity runs execute: reach the ``engine``'s scheduler (an address —
    refused within about 12 s when it is no Dask scheduler — or a connected ``distributed.Client``, left
    open), lock the store at ``store_path`` (:class:`~drillstring.stochastic.locks.StudyLock`, named
    ``lock_name``, default ``what``) once, open or create it (``open_store()``), run its ``pending(store)``
    items with ``task`` (:func:`run_tasks`), then ``finish(run)`` (reading the store and writing the
    result files, still under the lock; its value is the run's ``result``) and release everything.
    ``prepare()`` runs once, in this process, before any local worker process takes an item (compiling the
    kernels here, so the workers load them), while the workers start (their imports overlap it); it may
    return a *setup*, a picklable callable each local worker runs once before its first item (e.g. installing
    a model built here, instead of building it again in each worker). Not run for a Dask cluster.

    ``passes`` instead of ``pending``: a run in passes, each choosing its items from what the previous ones
    wrote (the optimiser's batches of design points): ``passes(store)`` yields the items of each pass, run in
    turn, an empty pass skipped."""
    from drillstring.stochastic.locks import StudyLock

    if (pending is None) == (passes is None):
        raise TypeError("run_locked: give one of pending and passes")
    scheduler = engine.scheduler
    client = connect_scheduler(scheduler) if isinstance(scheduler, str) else scheduler
    try:
        with StudyLock(store_path, what=lock_name or what) as guard:
            if guard.note:
                notify(engine.note, guard.note)
            address = None if client is None else str(getattr(client.scheduler, "address", scheduler))
            store = open_store()
            for repair in getattr(store, "repairs", ()):  # damaged chunks found: their rows run again
                notify(engine.note, repair)
            single = passes is None
            computed, wall, used, counts = 0, 0.0, 1, None
            preparation = _Preparation(prepare)
            for items in ([list(pending(store))] if single else passes(store)):
                items = list(items)
                if not items and not single:
                    continue
                report = run_tasks(store, task, items, replace(engine, scheduler=client),
                                   address=address, lost=lost, what=what, noun=noun, prepare=preparation)
                computed, wall, used = computed + report.computed, wall + report.wall_time, report.workers
                counts = report.completed, report.failed  # the whole store's
            done, failed = store.counts() if counts is None else counts
            run = StoreRun(store, done, failed, wall, used, computed, guard.note)
            if finish is not None:
                run.result = finish(run)
            return run
    finally:
        if isinstance(scheduler, str) and client is not None:
            close_client(client)


def close_client(client, timeout: float = SCHEDULER_TIMEOUT) -> None:
    """Close a ``distributed.Client`` within about ``timeout`` seconds, whatever state its scheduler is in
    (gone, stopped): a client that cannot close cleanly is abandoned without a traceback."""
    import logging

    quiet = [logging.getLogger(name) for name in ("distributed", "distributed.client", "distributed.comm",
                                                  "distributed.core", "distributed.batched", "tornado")]
    levels = [logger.level for logger in quiet]
    for logger in quiet:  # the client's own complaints about a lost scheduler: the caller said it in one line
        logger.setLevel(logging.CRITICAL)
    try:
        client.close(timeout=timeout)
    except BaseException as error:  # noqa: BLE001 - a closing client may raise anything, even AllExit
        if isinstance(error, KeyboardInterrupt):
            raise
    finally:
        for logger, level in zip(quiet, levels):
            logger.setLevel(level)


def run_tasks(
    store,
    task: Callable[[Any], Any],
    items: Sequence[tuple[int, Any]],
    engine: Engine = Engine(),
    *,
    address: str | None = None,
    lost: LostOutcome = bare_failure,
    what: str = "study",
    noun: str = "realizations",
    prepare: Callable[[], Callable[[], None] | None] | None = None,
) -> RunReport:
    """Run ``items`` (``(index, argument)``, the store's pending ones) with ``task`` and write each
    outcome to ``store``; the caller holds the store's lock.

    ``store`` provides ``counts() -> (done, failed)``, ``total`` (items of the whole run),
    ``write_many(outcomes)``, ``record_session(started, wall_time, count, workers)``, ``path`` and
    optionally ``flush_interval`` [s] (default :data:`FLUSH_INTERVAL`; 0 writes each outcome at once) and
    ``flush_count`` (a batch is written once it holds that many outcomes, however recent; default no limit).
    Items with an index outside ``[0, total)`` (a study's nominal run) are written but not counted.
    ``engine`` (:class:`Engine`): its ``scheduler``, a connected ``distributed.Client`` (``address`` its
    scheduler's; :func:`run_locked` connects an address), runs them on Dask, otherwise its ``workers`` local
    processes (default one per core; 1 runs in this process); its ``progress``, ``note`` and ``worker_timeout``.
    Raises :class:`Interrupted` on Ctrl-C and :class:`WorkersLost` when no worker is left, after writing
    every outcome received; ``what`` and ``noun`` name the run and its items in those messages.
    ``prepare``: as :func:`run_locked`'s, run (locally, when there are items) before the first item.
    """
    client, workers, progress = engine.scheduler, engine.workers, engine.progress
    if isinstance(client, str):
        raise TypeError(f"run_tasks: scheduler = {client!r}: connect it first (a distributed.Client; run_locked does)")
    done, failed = store.counts()
    total = store.total
    started = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    start = time.perf_counter()
    computed = 0
    buffer: list = []
    last_flush = time.monotonic()
    interval = float(getattr(store, "flush_interval", FLUSH_INTERVAL))
    most = getattr(store, "flush_count", None)

    def flush() -> None:
        nonlocal last_flush
        if buffer:
            store.write_many(buffer)
            buffer.clear()
        last_flush = time.monotonic()

    def record(outcome) -> None:
        nonlocal done, failed, computed
        buffer.append(outcome)
        if 0 <= outcome.index < total:
            computed += 1
            if outcome.status == DONE:
                done += 1
            else:
                failed += 1
        if time.monotonic() - last_flush >= interval or (most is not None and len(buffer) >= most):
            flush()
        if progress:
            progress(done, failed, total)

    if client is not None:
        used: int | str = address or str(getattr(client.scheduler, "address", "Dask cluster"))
    elif local_workers(workers) == 1 or len(items) <= 1:
        used = 1
    else:
        used = local_workers(workers)
    if progress:
        progress(done, failed, total)
    try:
        try:
            execute(task, items, record, workers=used if isinstance(used, int) else None, client=client,
                    address=address, worker_timeout=engine.worker_timeout, lost=lost, noun=noun, note=engine.note,
                    prepare=prepare)
        finally:
            flush()
    except KeyboardInterrupt as error:
        raise Interrupted(
            f"{what} interrupted after {done + failed} of {total} {noun}; they are saved in "
            f"{store.path}; run the same command again to resume"
        ) from error
    finally:
        elapsed = time.perf_counter() - start
        if computed:
            store.record_session(started, elapsed, computed, used)
    return RunReport(done, failed, elapsed, used, computed)


def execute(task: Callable[[Any], Any], items: Sequence[tuple[int, Any]], record: Callable[[Any], None], *,
            workers: int | None = 1, client=None, address: str | None = None,
            worker_timeout: float = DASK_WORKER_TIMEOUT, lost: LostOutcome = bare_failure,
            noun: str = "realizations", note: Callable[[str], None] | None = None,
            prepare: Callable[[], Callable[[], None] | None] | None = None) -> None:
    """Compute ``task(argument)`` for each ``(index, argument)`` of ``items`` and pass each outcome to
    ``record`` as it arrives (in completion order): on the Dask cluster of ``client``, in this process
    (``workers`` 1) or on ``workers`` spawned local processes. ``note`` receives the Dask run's notes
    while nothing finishes. ``prepare`` (local runs with items only): run here before the first item, while
    the worker processes start; the setup it returns runs once in each worker (:func:`run_locked`)."""
    items = list(items)
    if client is not None:
        _run_dask(client, address or "the Dask scheduler", task, items, record, worker_timeout, lost, noun,
                  note)
    elif (workers or 1) <= 1:
        if items and prepare is not None:
            setup = prepare()
            if setup is not None:
                setup()
        for _, argument in items:
            record(task(argument))
    else:
        _run_processes(task, items, workers, record, lost=lost, noun=noun,
                       prepare=prepare if items else None)


# --- local processes -----------------------------------------------------------------------------

#: In a worker process: the shared flags "item started" (one per slot, the item's position).
_STARTED = None
#: Put in a pool's setup queue when the parent's preparation failed: the waiting workers exit.
_ABORT = "abort"


class _Preparation:
    """A run's ``prepare()`` (:func:`run_locked`), run at most once; its setup (or None) kept for the next
    pools of the run (a pool started again after a worker died)."""

    def __init__(self, prepare: Callable[[], Callable[[], None] | None] | None):
        self._prepare, self._done, self._setup = prepare, prepare is None, None

    def __call__(self) -> Callable[[], None] | None:
        if not self._done:
            self._setup = self._prepare()
            self._done = True
        return self._setup


def _worker_start(parent_pid: int, started=None, task=None, setups=None) -> None:
    """Worker initializer: keep the shared "started" flags, and exit as soon as the parent process is
    gone (killed, not just interrupted), instead of computing tasks nobody will record. ``task`` is only
    unpickled (with the initializer's arguments, at the process's start): its modules are imported while the
    parent prepares. ``setups``: a queue from which this worker takes the parent's setup (:func:`run_locked`)
    and runs it before its first item; it waits for it (the parent's preparation runs meanwhile)."""
    global _STARTED
    _STARTED = started

    def watch() -> None:
        while True:
            time.sleep(1.0)
            if os.getppid() != parent_pid:
                os._exit(0)

    threading.Thread(target=watch, daemon=True).start()
    if setups is not None:
        setup = setups.get()
        if isinstance(setup, str) and setup == _ABORT:
            os._exit(0)
        if setup is not None:
            setup()


def _start_pool(context, workers: int, parent_pid: int, task, started, prepare
                ) -> tuple[cf.ProcessPoolExecutor, Callable[[], None]]:
    """A pool of ``workers`` processes, each waiting for the setup of ``prepare`` (run here, once per run:
    :class:`_Preparation`) before its first item, and the ``release()`` that runs the preparation and hands the
    setup to each process (if it fails, the waiting processes are told to exit and the error is raised). The
    processes start at the pool's first ``submit``: call ``release()`` after it, so that they start meanwhile."""
    setups = context.SimpleQueue() if prepare is not None else None
    pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_worker_start,
                                  initargs=(parent_pid, started, task, setups))

    def release() -> None:
        if setups is None:
            return
        try:
            setup = prepare()
        except BaseException:
            for _ in range(workers):
                setups.put(_ABORT)
            raise
        # a 6 MB setup fills the pipe until a worker reads it (after its imports): put from a thread, so that a
        # worker dying before it reads cannot hold this process (the pool then breaks as before)
        threading.Thread(target=lambda: [setups.put(setup) for _ in range(workers)], daemon=True).start()

    return pool, release


def _tracked(task: Callable, slot: int, argument):
    """Run ``task`` in a worker after flagging ``slot`` as started (a plain store into shared memory:
    no lock that a killed worker could leave held)."""
    if _STARTED is not None:
        _STARTED[slot] = 1
    return task(argument)


def _run_processes(task: Callable, items: Sequence[tuple[int, Any]], workers: int, record,
                   lost: LostOutcome = bare_failure, noun: str = "realizations", prepare=None) -> None:
    """Run ``items`` on ``workers`` spawned processes (single-threaded linear algebra in each), ``prepare``
    (:func:`execute`) run here while they start."""
    context = multiprocessing.get_context("spawn")
    saved = {k: os.environ.get(k) for k in WORKER_ENVIRONMENT}
    os.environ.update(WORKER_ENVIRONMENT)  # inherited by the spawned workers only at start-up
    try:
        _process_loop(context, task, list(items), workers, record, os.getpid(), lost, noun, prepare)
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _process_loop(context, task, items, workers, record, parent_pid, lost, noun, prepare=None) -> None:
    """Run ``items`` on a pool of ``workers`` processes.

    If a worker dies (killed, out of memory, crash) the pool breaks and every running item is lost with
    it. The items that had started and not returned (at most one per worker) are set aside as suspects;
    the others go on in a fresh pool of ``workers`` processes. At the end each suspect runs alone in its
    own single-process pool (up to ``workers`` such pools at once): the one that kills its worker there
    is recorded as failed with that cause (``lost``), the innocent ones finish normally. A pool that
    breaks before any item started (workers that cannot start) raises :class:`WorkersLost`. ``prepare`` runs
    here once, after the first pool's items are submitted (its processes importing meanwhile); each pool's
    processes run its setup before their first item (:func:`_start_pool`).
    """
    started = context.Array("b", max(len(items), 1), lock=False)
    remaining = list(range(len(items)))  # slots: positions in items
    suspects: list[int] = []
    recorded: set[int] = set()
    while remaining:
        for slot in remaining:
            started[slot] = 0
        pool, release = _start_pool(context, min(workers, len(remaining)), parent_pid, task, started, prepare)
        broken = False
        try:
            futures = {pool.submit(_tracked, task, slot, items[slot][1]): slot for slot in remaining}
            release()
            for future in cf.as_completed(futures):
                error = future.exception()
                if error is None:
                    record(future.result())
                    recorded.add(futures[future])
                elif isinstance(error, cf.process.BrokenProcessPool):
                    broken = True
                else:
                    raise error
        finally:
            pool.shutdown(wait=False, cancel_futures=True)
        in_flight = [slot for slot in remaining if started[slot] and slot not in recorded]
        if broken and not in_flight:
            raise WorkersLost(f"local worker processes died before computing any of the {noun} (they "
                              "cannot start); finished ones are saved, rerun to resume")
        suspects.extend(in_flight)
        remaining = [slot for slot in remaining if slot not in recorded and slot not in in_flight]
    for first in range(0, len(suspects), workers):
        batch = suspects[first:first + workers]
        started_pools = [_start_pool(context, 1, parent_pid, task, None, prepare) for _ in batch]
        pools = [pool for pool, _ in started_pools]
        try:
            futures = {p.submit(task, items[slot][1]): slot for p, slot in zip(pools, batch)}
            for _, release in started_pools:
                release()
            for future in cf.as_completed(futures):
                error = future.exception()
                if error is None:
                    record(future.result())
                elif isinstance(error, cf.process.BrokenProcessPool):
                    index, argument = items[futures[future]]
                    record(lost(index, argument, "worker process died (killed or crashed) while computing "
                                                 "this task alone"))
                else:
                    raise error
        finally:
            for p in pools:
                p.shutdown(wait=False, cancel_futures=True)


# --- Dask ----------------------------------------------------------------------------------------


def _receive(sock, n: int, deadline: float) -> bytes:
    """``n`` bytes from ``sock`` by ``deadline`` (``time.monotonic()``), however slowly they come: a server
    that answers one byte at a time still fails by then (TimeoutError)."""
    data = b""
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError("no complete answer in time")
        sock.settimeout(left)
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed the connection")
        data += chunk
    return data


def _probe_tcp_scheduler(address: str, host: str, port: int, timeout: float) -> None:
    """Check that ``host:port`` answers as a Dask server: a TCP connection within ``timeout`` and,
    within ``timeout`` more, the greeting every Dask server sends first (an 8-byte length, then a
    msgpack handshake). Raises :class:`SchedulerUnreachable`."""
    import socket
    import struct

    def refuse(why: str) -> SchedulerUnreachable:
        return SchedulerUnreachable(f"scheduler = {address!r}: {why}")

    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except ConnectionRefusedError:
        raise refuse("connection refused (no server listens on that port)") from None
    except socket.gaierror as error:
        raise refuse(f"unknown host {host!r} ({error.strerror})") from None
    except TimeoutError:
        raise refuse(f"no answer within {timeout:g} s (unreachable address or filtered port)") from None
    except OSError as error:
        raise refuse(f"cannot connect ({error.strerror or error})") from None
    with sock:
        deadline = time.monotonic() + timeout  # for the whole greeting, not each byte of it
        not_dask = "the server there does not speak the Dask protocol (not a Dask scheduler)"
        try:
            (length,) = struct.unpack("<Q", _receive(sock, 8, deadline))
            if not 0 < length <= 1 << 20:
                raise refuse(not_dask)
            payload = _receive(sock, length, deadline)
        except TimeoutError:
            raise refuse(f"the server there sent no Dask greeting within {timeout:g} s "
                         "(not a Dask scheduler)") from None
        except (ConnectionError, OSError):
            raise refuse(f"{not_dask}: it closed the connection") from None
    try:
        import msgpack
        from distributed.protocol.utils import unpack_frames

        greetings = [msgpack.loads(bytes(frame)) for frame in unpack_frames(payload)]
    except Exception:
        raise refuse(not_dask) from None
    if not any(isinstance(g, dict) and "pickle-protocol" in g for g in greetings):
        raise refuse(not_dask)


def _server_type(address: str, timeout: float) -> str:
    """The type of the Dask server at ``address`` ("Scheduler", "Worker", "Nanny", ...) from its
    ``identity``, within ``timeout`` seconds (in a thread of its own, so that it also works where an
    event loop is already running, as in a notebook)."""
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    from distributed.core import rpc

    async def identity() -> dict:
        async with rpc(address, timeout=timeout) as server:
            return await asyncio.wait_for(server.identity(), timeout)

    def ask() -> str:
        try:
            info = asyncio.run(asyncio.wait_for(identity(), timeout))
        except (TimeoutError, asyncio.TimeoutError):
            raise SchedulerUnreachable(f"scheduler = {address!r}: no answer to a Dask request within "
                                       f"{timeout:g} s") from None
        except Exception as error:
            message = str(error).splitlines()[0] if str(error) else type(error).__name__
            raise SchedulerUnreachable(f"scheduler = {address!r}: cannot connect ({message})") from None
        return str(info.get("type", "server of unknown type")) if isinstance(info, dict) else "server"

    with ThreadPoolExecutor(max_workers=1) as pool:
        return pool.submit(ask).result()


def connect_scheduler(address: str, timeout: float = SCHEDULER_TIMEOUT):
    """A :class:`distributed.Client` connected to the scheduler at ``address``, or
    :class:`SchedulerUnreachable` (one line) within about ``3 × timeout`` seconds: a TCP address is
    first probed by hand (:func:`_probe_tcp_scheduler`), since the client waits forever for the
    greeting of a server that is not a Dask server; then the server must say it is a scheduler (not a
    worker or nanny)."""
    from distributed import Client
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port

    if not isinstance(address, str) or not address.strip():
        raise SchedulerUnreachable(f"scheduler = {address!r}: give an address like tcp://host:8786")
    try:
        scheme, location = parse_address(address.strip())
        if scheme == "tcp":
            host, port = parse_host_port(location, 8786)
    except (ValueError, TypeError) as error:
        raise SchedulerUnreachable(f"scheduler = {address!r}: not an address like tcp://host:8786 "
                                   f"({error})") from None
    if scheme == "tcp":
        _probe_tcp_scheduler(address, host, int(port), timeout)
    kind = _server_type(address.strip(), timeout)
    if kind != "Scheduler":
        raise SchedulerUnreachable(f"scheduler = {address!r}: that is a Dask {kind}, not a scheduler "
                                   "(give the scheduler's address, e.g. tcp://host:8786)")
    try:
        return Client(address.strip(), timeout=timeout, set_as_default=False)
    except Exception as error:  # one line, whatever went wrong on the way
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise SchedulerUnreachable(f"scheduler = {address!r}: cannot connect ({message})") from None


def _run_dask(client, scheduler: str, task, items, record, worker_timeout: float, lost: LostOutcome,
              noun: str, note: Callable[[str], None] | None = None) -> None:
    """Run ``items`` on the cluster of ``client``. An item whose workers keep dying (``KilledWorker``)
    is recorded as failed with that cause; a cluster left without any worker, or without any worker that
    answers, or a scheduler that does not answer, for ``worker_timeout`` seconds, or a lost scheduler,
    raises :class:`WorkersLost` (:class:`~drillstring.stochastic.dask_watch.ClusterWatch`)."""
    from distributed.scheduler import KilledWorker

    if not items:
        return
    futures = client.map(task, [argument for _, argument in items], pure=False)
    item_of = {future.key: item for future, item in zip(futures, items)}
    pending = list(futures)
    watch = ClusterWatch(client, scheduler, worker_timeout, noun, note)

    def gone(why: str) -> WorkersLost:
        return WorkersLost(f"{why}; the finished {noun} are saved, rerun the same command (with workers "
                           "available) to resume")

    tries: dict[Any, int] = {}  # finished futures whose result could not be fetched yet: attempts

    try:
        while pending:
            finished = []
            deadline = time.monotonic() + 1.0  # fetching results never delays the watch by more than this
            for future in sorted(pending, key=lambda f: tries.get(f.key, 0)):  # statuses: the client's loop
                status = future.status
                if status == "finished":
                    if time.monotonic() >= deadline:
                        continue
                    try:  # a result held by a stopped worker does not come: tried again later
                        outcome = future.result(timeout=max(0.05, deadline - time.monotonic()))
                    except Exception as error:
                        if not is_timeout(error):
                            raise gone(f"lost the Dask scheduler at {scheduler} ({type(error).__name__})") from None
                        tries[future.key] = tries.get(future.key, 0) + 1
                        continue
                    finished.append(future)
                    record(outcome)
                elif status == "error":
                    finished.append(future)
                    error = future.exception()
                    index, argument = item_of[future.key]
                    if not isinstance(error, KilledWorker):
                        raise gone(f"the Dask cluster at {scheduler} could not compute item {index} "
                                   f"({type(error).__name__}: {error})")
                    record(lost(index, argument, "Dask workers died (killed or crashed) while computing "
                                                 f"this task: {error}"))
                elif status == "cancelled":
                    raise gone(cancelled_reason(client, scheduler))
                # "pending", or "lost" (its result left with its worker; recomputed): wait
            if finished:
                done_now = set(map(id, finished))
                pending = [f for f in pending if id(f) not in done_now]
                watch.progress()
            else:
                time.sleep(0.05)
            why = watch.check() if pending else None
            if why:
                raise gone(why)
    finally:
        if pending:
            try:
                client.sync(client._cancel, list(pending), callback_timeout=SCHEDULER_TIMEOUT)
            except BaseException:  # noqa: BLE001 - the scheduler may be gone: nothing left to cancel there
                pass
