"""Dense linear algebra single-threaded while drillstring computes, wherever it is called from.

Every dense linear-algebra problem of the model is small: eigenproblems and solves of a few hundred DOFs per
mode family (``scipy.linalg.eigh`` on ~300 × 300 matrices), products of reduced matrices. A multi-threaded
BLAS only adds synchronisation to them, and with another busy process on the machine its threads wait for
each other: the reference model build took 1.8 s instead of 0.06 s on a loaded 2-core machine
(benchmarks/bench_blas_threads.py measures it). The command line and the study workers set one thread
through the environment before NumPy loads (``OPENBLAS_NUM_THREADS=1``); a user's script has already loaded
NumPy with the default (one thread per core), so the API limits the BLAS libraries at run time, with
`threadpoolctl <https://github.com/joblib/threadpoolctl>`_, for the duration of each call only: the caller's
own NumPy work keeps its threads.

:func:`single_threaded_blas` is a context manager and a decorator (the public functions of
:mod:`drillstring.api` carry it). It is re-entrant, and restores the previous limits on exit, also after an
exception. The environment variable ``DRILLSTRING_BLAS_THREADS`` (:data:`THREADS_ENVIRONMENT`, a positive
integer) sets another limit.

This module imports nothing from the rest of ``drillstring``.
"""

from __future__ import annotations

import functools
import os
from contextlib import contextmanager
from typing import Iterator

__all__ = ["THREADS_ENVIRONMENT", "blas_threads", "single_threaded_blas"]

#: Environment variable with the BLAS threads drillstring uses (default 1).
THREADS_ENVIRONMENT = "DRILLSTRING_BLAS_THREADS"


def blas_threads() -> int:
    """The BLAS threads drillstring's calls use: ``$DRILLSTRING_BLAS_THREADS`` when a positive integer, else 1."""
    text = os.environ.get(THREADS_ENVIRONMENT, "").strip()
    return int(text) if text.isdigit() and int(text) > 0 else 1


@functools.cache
def _controller():
    """threadpoolctl's controller of the BLAS libraries loaded by NumPy and SciPy (each ships its own copy of
    OpenBLAS: both are loaded first so that both are controlled); scanned once (about 2 ms a scan)."""
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Limit the BLAS libraries to :func:`blas_threads` threads (1) inside the block or decorated call
    (``with single_threaded_blas():`` or ``@single_threaded_blas()``); the previous limits come back after."""
    limits = _controller().limit(limits=blas_threads(), user_api="blas")
    try:
        yield
    finally:
        limits.restore_original_limits()
