"""The explicit embedded Runge–Kutta step (a :class:`~drillstring.dynamics.runge_kutta.ButcherTableau`): its
stages, its local error estimate ``h Σ (b_i − b̂_i) k_i`` and its continuous extension, for the compiled loop
(:mod:`drillstring.dynamics.steps.kinds`) — Dormand–Prince 5(4) and Bogacki–Shampine 3(2) of
:mod:`drillstring.dynamics.runge_kutta`, or any tableau with dense output.

With FSAL ("first same as last") the last stage is the derivative at the new state, so an accepted step costs
``s − 1`` right-hand sides; without it ``s``. :class:`ReferenceStep` is the NumPy reference of the same step,
for the Python stepper :class:`~drillstring.dynamics.runge_kutta.RungeKuttaStepper` (a right-hand side
``rhs(t, y)`` in Python); ``tests/dynamics/test_compiled.py`` checks that both paths take the same steps.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from drillstring.dynamics.rom import evaluate_rhs
from drillstring.dynamics.tableaus import ButcherTableau
from drillstring.dynamics.steps.kinds import StepKind, register


class ExplicitRungeKuttaStep(NamedTuple):
    """The compiled loop's data of an explicit Runge–Kutta step: the tableau and the stages."""

    a: np.ndarray  # (s, s) stage coefficients
    b: np.ndarray  # (s,) weights of the propagated solution
    error_weights: np.ndarray  # (s,) b − b_hat
    c: np.ndarray  # (s,) nodes
    dense: np.ndarray  # (s, p) continuous extension
    fsal: bool
    order: float  # q, order of the error estimate
    k: np.ndarray  # (s, n) stages of the step being attempted
    dense_stages: np.ndarray  # (s, n) stages of the last accepted step (dense output)


def allocate(tableau: ButcherTableau, n: int) -> ExplicitRungeKuttaStep:
    """The step's data for ``tableau`` and a state of ``n`` components."""
    if tableau.dense is None:
        raise ValueError(f"the compiled path needs a tableau with dense output; {tableau.name} has none")
    c = np.ascontiguousarray
    s = tableau.n_stages
    return ExplicitRungeKuttaStep(
        a=c(tableau.a), b=c(tableau.b), error_weights=c(tableau.error_weights), c=c(tableau.c),
        dense=c(tableau.dense), fsal=bool(tableau.fsal), order=float(tableau.controller_order),
        k=np.zeros((s, n)), dense_stages=np.zeros((s, n)))


@njit
def attempt(data, rhs_data, t, h, y, f, y_new, err):
    """Stages from ``f`` (the first), the candidate ``y_new`` (FSAL: the last stage's argument) and the
    error estimate ``err``; stops at the first stage with a non-finite value. Returns (evaluations, finite).

    Each sum ``Σ_m a[i, m] k[m, j]`` is accumulated in ``y_new[j]`` (``err[j]`` for the estimate) stage by
    stage, the loop over the state innermost: the same additions in the same order for every component as
    a sum per component, on contiguous rows (no temporaries, vectorised). Zero coefficients are skipped
    (adding ``0·k`` changes nothing but the sign of a zero; the stages are finite where they are used)."""
    k, a, b, c, error_weights, fsal = data.k, data.a, data.b, data.c, data.error_weights, data.fsal
    n = y.shape[0]
    s = c.shape[0]
    for j in range(n):
        k[0, j] = f[j]
    for i in range(1, s):
        _stage_sum(a[i], i, k, y_new)
        for j in range(n):
            y_new[j] = y[j] + h * y_new[j]
        evaluate_rhs(rhs_data, t + c[i] * h, y_new, k[i])
        finite = True
        for j in range(n):
            if not math.isfinite(k[i, j]):
                finite = False
        if not finite:
            return i, False
    if not fsal:
        _stage_sum(b, s, k, y_new)
        for j in range(n):
            y_new[j] = y[j] + h * y_new[j]
    _stage_sum(error_weights, s, k, err)
    for j in range(n):
        err[j] = h * err[j]
    return s - 1, True


@njit(inline="always")
def _stage_sum(weights, count, k, out):
    """out = Σ_{m < count} weights[m] k[m], accumulated in ``out`` stage by stage (zero weights skipped)."""
    n = out.shape[0]
    for j in range(n):
        out[j] = 0.0
    for m in range(count):
        w = weights[m]
        if w != 0.0:
            km = k[m]
            for j in range(n):
                out[j] += w * km[j]


@njit
def accept(data, y, f):
    """Keep the accepted step's stages for its dense output; with FSAL ``f`` at the new state ``y`` is the
    last stage: set it and return True; else return False (the loop evaluates it)."""
    k, kept = data.k, data.dense_stages
    n = y.shape[0]
    s = k.shape[0]
    for m in range(s):
        for j in range(n):
            kept[m, j] = k[m, j]
    if data.fsal:
        for j in range(n):
            f[j] = k[s - 1, j]
        return True
    return False


def _describe_nonfinite(x: np.ndarray) -> str:
    return "NaN" if np.isnan(x).any() else "inf"


class ReferenceStep:
    """The NumPy reference of :func:`attempt` and :func:`accept` for ``tableau`` and states like ``y``
    (any float or complex dtype): the same stages, error estimate and dense output, vectorised. A tableau
    without dense output is allowed here (``dense`` is then None; the stepper interpolates otherwise)."""

    def __init__(self, tableau: ButcherTableau, y: np.ndarray) -> None:
        s = tableau.n_stages
        self.fsal = tableau.fsal
        self.order = tableau.controller_order
        self.dense = tableau.dense
        self._c = tableau.c
        self._a_rows = tuple(np.ascontiguousarray(tableau.a[i, :i]) for i in range(s))
        self._b = tableau.b
        self._e = tableau.error_weights
        self._k = np.empty((s, y.size), dtype=y.dtype)  # stages of the step being attempted
        self.dense_stages = np.empty_like(self._k)  # stages of the last accepted step (dense output)

    def attempt(self, rhs, t: float, h: float, y: np.ndarray, f: np.ndarray):
        """Returns ``(y_new, err, evaluations, cause)``: ``cause`` is None, or why the attempt failed (a
        non-finite stage or a floating-point error in ``rhs``; ``y_new`` and ``err`` are then None)."""
        c, k, a_rows = self._c, self._k, self._a_rows
        k[0] = f
        cause, y_new, err, evaluations = None, None, None, 0
        with np.errstate(all="ignore"):
            try:
                for i in range(1, k.shape[0]):
                    yi = y + h * (a_rows[i] @ k[: i])
                    k[i] = rhs(t + c[i] * h, yi)
                evaluations = k.shape[0] - 1
                if not np.isfinite(k).all():
                    bad = int(np.argmax(~np.isfinite(k).all(axis=1)))
                    cause = f"{_describe_nonfinite(k[bad])} in the right-hand side (stage {bad + 1})"
                else:
                    # FSAL: the last stage argument *is* y_new; otherwise weight the stages with b
                    y_new = yi if self.fsal else y + h * (self._b @ k)
                    err = h * (self._e @ k)
            except (FloatingPointError, OverflowError) as exc:
                evaluations = i  # stages evaluated, including the failing one
                cause = f"{type(exc).__name__} in the right-hand side: {exc}"
        return y_new, err, evaluations, cause

    def accept(self, rhs, t_new: float, y_new: np.ndarray) -> tuple[np.ndarray, int]:
        """Keep the accepted step's stages (:attr:`dense_stages`); returns ``(f, evaluations)``, ``f`` the
        derivative at ``(t_new, y_new)`` (FSAL: the last stage; the caller checks it is finite)."""
        if self.fsal:
            f_new, evaluations = self._k[-1].copy(), 0
        else:
            with np.errstate(all="ignore"):
                f_new = np.asarray(rhs(t_new, y_new), dtype=y_new.dtype)
            evaluations = 1
        self._k, self.dense_stages = self.dense_stages, self._k
        return f_new, evaluations


KIND = register(StepKind(method=ButcherTableau, data=ExplicitRungeKuttaStep, allocate=allocate,
                         attempt=attempt, accept=accept, reference=ReferenceStep, allocates=False))
