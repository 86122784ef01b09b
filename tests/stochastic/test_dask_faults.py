"""Dask faults on loopback clusters of real processes (a scheduler and workers without nannies, so that a
killed or stopped process stays so): workers killed or stopped (SIGSTOP), a scheduler killed or stopped, a
server answering one byte at a time. Each stops within the documented bound with one line, resumably, and
the resumed study equals the local one."""

import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time

import pytest

from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic.execution import (
    SCHEDULER_TIMEOUT,
    Engine,
    SchedulerUnreachable,
    WorkersLost,
    connect_scheduler,
)

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGSTOP"), reason="POSIX signals")


def _settings(case):
    """Six realizations of a random weight-on-hook (Normal, σ = 5 kN), 1 s each."""
    return mc.StudySettings(laws=(mc.weight_on_hook_normal(case, 5000.0),), samples=6, seed=11, t_end=1.0,
                            output_step=0.01)

TIMEOUT = 2.0  # worker_timeout of these tests [s]
#: The bound of a stop after the fault: two unanswered scheduler requests and the 1 s polls (the
#: documented worker_timeout + SCHEDULER_TIMEOUT + 2 s, where the timeout is shorter than a request), plus
#: 3 s for the loopback processes of a loaded 2-core machine.
BOUND = max(TIMEOUT, 2 * SCHEDULER_TIMEOUT + 1.0) + SCHEDULER_TIMEOUT + 2.0 + 3.0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _process(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", "import sys; from distributed.cli import " + args[0] + " as m; "
                             "sys.argv[0] = 'dask'; m.main()", *args[1:]],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})


class Cluster:
    """A scheduler and ``n`` single-threaded workers (no nanny), each its own process, on 127.0.0.1."""

    def __init__(self, n: int = 1) -> None:
        self.address = f"tcp://127.0.0.1:{_free_port()}"
        port = self.address.rsplit(":", 1)[1]
        self.scheduler = _process("dask_scheduler", "--host", "127.0.0.1", "--port", port, "--no-dashboard")
        self.workers = [_process("dask_worker", self.address, "--no-nanny", "--nthreads", "1", "--host",
                                 "127.0.0.1", "--no-dashboard") for _ in range(n)]
        from distributed import Client

        deadline = time.time() + 60
        while True:
            try:
                with Client(self.address, timeout=5) as client:
                    client.wait_for_workers(n, timeout=max(1, deadline - time.time()))
                break
            except Exception:
                if time.time() > deadline:
                    self.close()
                    raise
                time.sleep(0.5)

    def signal(self, which, sig) -> None:
        for proc in which:
            os.kill(proc.pid, sig)

    def close(self) -> None:
        for proc in [*self.workers, self.scheduler]:
            try:
                os.kill(proc.pid, signal.SIGCONT)
                proc.kill()
            except ProcessLookupError:
                pass
            proc.wait(timeout=30)


@pytest.fixture
def cluster():
    made = Cluster(1)
    yield made
    made.close()


@pytest.fixture(scope="module")
def local_result(small_case, tmp_path_factory):
    store = tmp_path_factory.mktemp("local") / "local.zarr"
    mc.run_study(small_case, _settings(small_case), store, Engine(workers=1))
    return store


def _arrays(store):
    import zarr

    group = zarr.open_group(str(store), mode="r")
    return {name: group[name][...] for name in ("status", "weight_on_hook", "rate_of_penetration", "bit_speed",
                                                 "nominal_rate_of_penetration")}


def _same(a, b) -> None:
    import numpy as np

    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def _stop_after(done_at: int, action):
    """A progress callback calling ``action()`` once ``done_at`` realizations are finished; it records
    when."""
    state = {"at": None}

    def progress(done, failed, total):
        if done >= done_at and state["at"] is None:
            state["at"] = time.monotonic()
            action()

    return progress, state


@pytest.mark.parametrize("fault, message", [
    ("workers killed", r"has had no worker for 2 s|none of the 1 Dask worker\(s\) .* has answered for 2 s"),
    ("workers stopped", r"none of the 1 Dask worker\(s\) of tcp://127\.0\.0\.1:\d+ has answered for 2 s "
                        r"\(stopped or frozen\)"),
    ("scheduler killed", r"lost the Dask scheduler at tcp://127\.0\.0\.1:\d+|the Dask scheduler at .* has not answered"),
    ("scheduler stopped", r"the Dask scheduler at tcp://127\.0\.0\.1:\d+ has not answered for \d+ s"),
])
def test_dask_fault_stops_in_bounded_time_and_resumes(small_case, tmp_path, cluster, local_result, fault, message):
    import numpy as np

    which = cluster.workers if fault.startswith("workers") else [cluster.scheduler]
    sig = signal.SIGKILL if fault.endswith("killed") else signal.SIGSTOP
    progress, state = _stop_after(2, lambda: cluster.signal(which, sig))
    notes: list[str] = []
    store = tmp_path / "dask.zarr"
    settings = _settings(small_case)
    with pytest.raises(WorkersLost) as raised:
        mc.run_study(small_case, settings, store, Engine(scheduler=cluster.address, progress=progress,
                                                         worker_timeout=TIMEOUT, note=notes.append))
    elapsed = time.monotonic() - state["at"]
    text = str(raised.value)
    assert re.search(message, text), text
    assert "\n" not in text and "saved, rerun the same command" in text
    assert elapsed < BOUND, elapsed
    done = _arrays(store)["status"]
    assert 2 <= int(np.sum(done == 1)) < settings.samples
    for name, values in _arrays(local_result).items():  # what was stored is the local result's
        if name != "status" and values.ndim >= 1 and values.shape[0] == settings.samples:
            np.testing.assert_array_equal(_arrays(store)[name][done == 1], values[done == 1], err_msg=name)
    # A long wait with a worker answering (the workers' start: imports, kernels) is noted in this form; whether
    # the start outlasts the note's interval depends on the machine's load, so the note itself is not required.
    assert all(re.match(r"no realizations finished for \d+ s on the Dask cluster at tcp://127\.0\.0\.1:\d+: "
                        r"1 of 1 worker\(s\) answering", n) for n in notes), notes
    assert not any("0 of" in n for n in notes), notes  # a wait without an answering worker ends in the stop
    mc.run_study(small_case, settings, store, Engine(workers=1))  # resumed locally
    _same(_arrays(store), _arrays(local_result))


def _trickling_server(greeting: bytes, gap: float):
    """A loopback TCP server (``socketserver``, serving in a thread) that sends ``greeting`` to each
    connection one byte every ``gap`` seconds."""
    import socketserver

    class Trickle(socketserver.BaseRequestHandler):
        def handle(self):
            try:
                for byte in greeting:
                    self.request.sendall(bytes([byte]))
                    time.sleep(gap)
            except OSError:
                pass

    server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), Trickle)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def test_a_server_answering_one_byte_at_a_time_is_refused_in_bounded_time(small_case, tmp_path):
    """Each byte within the per-read timeout, the whole greeting never in time: refused after the
    greeting's timeout, not after the greeting's length times it."""
    greeting = (64).to_bytes(8, "little") + b"\x81" * 64
    server = _trickling_server(greeting, 0.2)
    address = f"tcp://127.0.0.1:{server.server_address[1]}"
    try:
        start = time.monotonic()
        with pytest.raises(SchedulerUnreachable, match=r"sent no Dask greeting within 1 s"):
            connect_scheduler(address, timeout=1.0)
        assert time.monotonic() - start < 3.0
    finally:
        server.shutdown()
        server.server_close()
