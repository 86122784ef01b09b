"""Figures drawn in a second process while the caller writes the rest of a study's outputs.

The end of a study runs on one core: reading the store, the statistics, the nominal case's stability boundary,
``statistics.nc``, the interactive page and the report. Its figures (Matplotlib's rendering: 2.2 s of the 5.5 s
that end took for the 500-realization reference study, docs/performance.md) are drawn meanwhile by
:class:`ProcessBeside` in a spawned process, started first so that its imports overlap the store's reading. On a
machine of one core, in a run without local worker processes (a script need not then be guarded by
``if __name__ == "__main__":``, which a spawned process needs), where no process can be started, or where the
process dies, the caller draws them itself;
an error of the drawing itself is raised as if the caller had drawn them. The files are the same either way (the
same code on the same numbers).
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Self

__all__ = ["ProcessBeside"]


def _import_plotting() -> None:
    """The process's start: the plotting stack imported before any figure is asked for."""
    import drillstring.outputs.study_plots  # noqa: F401


def _started() -> bool:
    return True


class ProcessBeside:
    """One spawned process for work beside the caller's (:meth:`submit`), started when built; ``enabled=False``,
    a single core or a process that cannot start: the work runs in the caller, when its result is asked for.
    Close it with :meth:`close` (or use it as a context manager)."""

    def __init__(self, enabled: bool = True) -> None:
        self._pool: ProcessPoolExecutor | None = None
        if not enabled or (os.cpu_count() or 1) < 2:
            return
        try:
            self._pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"),
                                             initializer=_import_plotting)
            self._pool.submit(_started)  # the process starts now, not at the first submit
        except (OSError, RuntimeError):  # no process can be started here
            self._pool = None

    def submit(self, function: Callable[..., Any], *args, **kwargs) -> Callable[[], Any]:
        """Run ``function(*args, **kwargs)`` (importable, its arguments picklable) in the process; returns a
        callable that waits for its result, or computes it here if the process is not there or died."""
        pool = self._pool
        future = None
        if pool is not None:
            try:
                future = pool.submit(function, *args, **kwargs)
            except (BrokenProcessPool, RuntimeError):
                future = None

        def result():
            if future is not None:
                try:
                    return future.result()
                except BrokenProcessPool:  # the process died: the work is done here
                    pass
            return function(*args, **kwargs)

        return result

    def close(self) -> None:
        """Stop the process (anything still queued is dropped)."""
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
