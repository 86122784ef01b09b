"""What a Dask run watches while it waits (:mod:`drillstring.stochastic.execution`): the cluster's scheduler and
workers (:class:`ClusterWatch`), and why futures were cancelled (:func:`cancelled_reason`)."""

from __future__ import annotations

import time
from typing import Any, Callable

#: Until the first task of a Dask run finishes, workers that do not answer the scheduler get this many
#: times ``worker_timeout`` (2 min by default): a starting worker imports the program and compiles or
#: loads its kernels, and its interpreter is held meanwhile.
STARTUP_FACTOR = 4
#: Seconds allowed to each step of reaching a Dask scheduler (TCP connection, the server's greeting,
#: its identity, the client's registration) and to each later request to it: an address that is no
#: scheduler fails at one of the first three, so within 12 s.
SCHEDULER_TIMEOUT = 4.0


class ClusterWatch:
    """What a Dask run knows of its cluster while nothing finishes: asked at most once a second
    (:meth:`check`), the scheduler's identity, each request bounded by :data:`SCHEDULER_TIMEOUT`, gives its
    workers and the time each last reported (its heartbeat, every 0.5 s or so on a small cluster). A worker
    whose report has not changed for ``worker_timeout`` seconds is not answering (stopped, frozen, or gone
    without the scheduler noticing yet)."""

    def __init__(self, client, scheduler: str, worker_timeout: float, noun: str,
                 note: Callable[[str], None] | None) -> None:
        self.client, self.scheduler, self.timeout, self.noun, self.note = client, scheduler, worker_timeout, noun, note
        self.reports: dict[str, tuple[Any, float]] = {}  # worker -> (last report, when it changed)
        now = time.monotonic()
        self.answered = now  # the scheduler's last answer
        self.alive = now  # the last time the cluster was seen with workers
        self.finished = now  # the last time an item finished
        self.noted = self.checked = self.started = now
        self.unanswered = 0  # scheduler requests unanswered in a row

    def progress(self) -> None:
        self.finished = self.alive = self.noted = time.monotonic()

    def _identity(self) -> dict | None:
        # identity() lists every worker: later versions take ``n_workers`` (default -1, all), 2024.1 takes none.
        try:
            return self.client.sync(self.client.scheduler.identity, callback_timeout=SCHEDULER_TIMEOUT)
        except (TimeoutError, OSError) as error:
            if not is_timeout(error):
                raise
            return None

    def check(self) -> str | None:
        """Why the run must stop now (one phrase), or None; issues the note of a long wait."""
        now = time.monotonic()
        if now - self.checked < 1.0:
            return None
        self.checked = now
        try:
            info = self._identity()
        except Exception as error:  # the connection to the scheduler is gone
            return f"lost the Dask scheduler at {self.scheduler} ({type(error).__name__})"
        now = time.monotonic()
        if info is None:  # two requests in a row unanswered, the last answer older than the timeout
            self.unanswered += 1
            if self.unanswered >= 2 and now - self.answered > self.timeout:
                return f"the Dask scheduler at {self.scheduler} has not answered for {now - self.answered:.0f} s"
            return None
        self.answered, self.unanswered = now, 0
        workers = dict(info.get("workers") or {})
        self.reports = {address: (report.get("last_seen"), now if self.reports.get(address, (None,))[0]
                                  != report.get("last_seen") else self.reports[address][1])
                        for address, report in workers.items() if isinstance(report, dict)}
        # Before anything finished, workers may be silent while they start (imports, compiling the kernels
        # hold their interpreter): they get STARTUP_FACTOR times the timeout then.
        patience = self.timeout * (1 if self.finished > self.started else STARTUP_FACTOR)
        answering = [a for a, (_, changed) in self.reports.items() if now - changed <= patience]
        if self.reports:
            self.alive = now  # the cluster has workers; whether they answer is their reports' age
            if not answering:
                return (f"none of the {len(self.reports)} Dask worker(s) of {self.scheduler} has answered for "
                        f"{patience:g} s (stopped or frozen)")
        elif now - self.alive > self.timeout:
            return f"the Dask cluster at {self.scheduler} has had no worker for {self.timeout:g} s"
        # A long wait with workers that answer now (within half the timeout, 5 s at least) is said; one
        # whose workers are going silent ends in the stop instead.
        lively = [a for a, (_, changed) in self.reports.items()
                  if now - changed <= min(self.timeout, max(self.timeout / 2, 5.0))]
        if self.note is not None and lively and now - self.noted >= self.timeout:
            self.noted = now
            self.note(f"no {self.noun} finished for {now - self.finished:.0f} s on the Dask cluster at "
                      f"{self.scheduler}: {len(lively)} of {len(self.reports)} worker(s) answering")
        return None


def is_timeout(error: BaseException) -> bool:
    import asyncio

    return isinstance(error, (TimeoutError, asyncio.TimeoutError)) or "timed out" in str(error).lower()


def cancelled_reason(client, scheduler: str) -> str:
    """Why the futures of a Dask run were cancelled (one phrase): the client cancels its futures itself when its
    connection to the scheduler drops (a killed scheduler, seen first as cancelled futures on a loaded machine),
    so a client no longer running, or a scheduler that does not answer, is a lost scheduler; else the scheduler
    cancelled them."""
    if getattr(client, "status", "running") != "running":
        return f"lost the Dask scheduler at {scheduler} (the client's connection closed, its tasks cancelled)"
    try:
        client.sync(client.scheduler.identity, callback_timeout=SCHEDULER_TIMEOUT)
    except Exception as error:  # the connection to the scheduler is gone
        return f"lost the Dask scheduler at {scheduler} ({type(error).__name__})"
    return f"the Dask scheduler at {scheduler} cancelled the tasks"
