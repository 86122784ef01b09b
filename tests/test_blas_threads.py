"""BLAS threads limited while drillstring computes, from any caller (issue 26): the limit holds inside the
call, the caller's own setting comes back after it (also after an error), and every public API function
carries it."""

from __future__ import annotations

import inspect
import sys

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from drillstring import api
from drillstring.blas_threads import THREADS_ENVIRONMENT, blas_threads, single_threaded_blas


def _blas_threads() -> set[int]:
    return {info["num_threads"] for info in threadpool_info() if info["user_api"] == "blas"}


def test_limit_inside_and_the_callers_setting_restored_after():
    import scipy.linalg  # noqa: F401  (its own OpenBLAS copy is controlled too)

    with threadpool_limits(limits=2, user_api="blas"):
        assert _blas_threads() == {2}
        with single_threaded_blas():
            assert _blas_threads() == {1}
            with single_threaded_blas():  # re-entrant
                assert _blas_threads() == {1}
            assert _blas_threads() == {1}
        assert _blas_threads() == {2}

        @single_threaded_blas()
        def failing():
            assert _blas_threads() == {1}
            raise RuntimeError("boom")

        with pytest.raises(RuntimeError, match="boom"):
            failing()
        assert _blas_threads() == {2}


def test_environment_sets_another_limit(monkeypatch):
    monkeypatch.setenv(THREADS_ENVIRONMENT, "2")
    assert blas_threads() == 2
    for bad in ("0", "-1", "two", ""):
        monkeypatch.setenv(THREADS_ENVIRONMENT, bad)
        assert blas_threads() == 1


@pytest.mark.parametrize("name", ["simulate", "static", "modes", "stability", "stability_boundary", "campbell",
                                  "compare", "study", "monte_carlo_study", "operating_map", "sensitivity"])
def test_every_public_api_function_runs_single_threaded(name, monkeypatch):
    function = getattr(api, name)
    assert inspect.signature(function) == inspect.signature(function.__wrapped__)  # the signature is kept
    seen = []

    def as_case(case):  # the first thing each function does with its case: record the limit then
        seen.append(_blas_threads())
        raise LookupError("stop")

    monkeypatch.setattr(sys.modules[function.__module__], "as_case", as_case)  # where the function reads it
    with threadpool_limits(limits=2, user_api="blas"), pytest.raises(LookupError):
        function("reference")
    assert seen == [{1}]
