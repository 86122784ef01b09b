"""Explicit embedded Runge–Kutta integration with adaptive step size and dense output (docs/model.md §9).

Design (after SciPy's ``solve_ivp`` and diffrax): the *method* is data — a :class:`ButcherTableau` —, the
*step-size controller* is a separate object (:class:`StepSizeController`), the *stepper*
(:class:`RungeKuttaStepper`) performs one step attempt per :meth:`~RungeKuttaStepper.step` call, and the
*driver* (:func:`integrate`) produces output on a user-set grid through the stepper's dense output. The
arithmetic of one attempt (stages, error estimate, dense-output stages) is the NumPy reference of the method's
step kind (:class:`drillstring.dynamics.steps.explicit_rk.ReferenceStep` for a :class:`ButcherTableau`), the
kind whose compiled step the compiled loop (:mod:`drillstring.dynamics.compiled`) runs: the same split into
step and loop on both paths.

Methods
-------
- :data:`DORMAND_PRINCE_54` — J. R. Dormand & P. J. Prince, "A family of embedded Runge–Kutta formulae",
  J. Comput. Appl. Math. 6 (1980) 19–26: 7 stages, FSAL, 5th-order solution, 4th-order embedded error
  estimate ("local extrapolation"), with a 4th-order continuous extension (see below).
- :data:`BOGACKI_SHAMPINE_32` — P. Bogacki & L. F. Shampine, "A 3(2) pair of Runge–Kutta formulas",
  Appl. Math. Lett. 2 (1989) 321–325: 4 stages, FSAL, 3rd-order solution, 2nd-order embedded, with a
  3rd-order continuous extension (see below).

Step-size control
-----------------
E. Hairer, S. P. Nørsett & G. Wanner, *Solving Ordinary Differential Equations I* (2nd ed., Springer 1993),
§II.4: the error of a step is measured in the weighted RMS norm
``‖err / (atol + rtol·max(|y|, |y_new|))‖_RMS`` and the step is accepted when that norm is ≤ 1; the initial
step size comes from the algorithm of §II.4 ("Starting step size"). The new step size follows the
proportional–integral (PI) controller of K. Gustafsson, "Control theoretic techniques for stepsize
selection in explicit Runge–Kutta methods", ACM TOMS 17 (1991) 533–554 (see also Hairer–Wanner, *Solving
ODEs II*, §IV.2)::

    h_next = h · clip(safety · err_n^(−β1/k) · err_{n−1}^(β2/k), min_factor, max_factor),   k = q + 1

with ``q`` the order of the error estimate (the lower of the two orders of the pair). After a rejected step
the controller falls back to the pure integral rule ``safety · err^(−1/k)`` and forbids growth on the next
accepted step (Hairer–Nørsett–Wanner §II.4). The rules live in two compiled functions,
:func:`error_norm` and :func:`step_factor`, called both by :class:`StepSizeController` (this module's
Python stepper) and by the compiled integrator of :mod:`drillstring.dynamics.compiled`: one
implementation for both paths.

Dense output
------------
A continuous extension (HNW §II.6) replaces the weights ``b_i`` by polynomials
``b_i(θ) = Σ_j dense[i, j−1] θ^j`` so that ``y(t + θh) ≈ y + h Σ_i b_i(θ) k_i``. It is of order ``p*`` when
``Σ_i b_i(θ) Φ_i(τ) = θ^ρ(τ)/γ(τ)`` for every rooted tree ``τ`` with ``ρ(τ) ≤ p*`` and every θ. For
Dormand–Prince 5(4) with ``b_2(θ) ≡ 0``, quartic ``b_i(θ)``, ``b_i(1) = b_i`` (continuity) and
``b_i'(1) = δ_i7`` (C¹ continuity through the FSAL stage), these 4th-order conditions leave a two-parameter
family (our own derivation in exact rational arithmetic). We take the member published by L. F. Shampine,
"Some practical Runge–Kutta formulas", Math. Comp. 46 (1986) 135–150 (the one used by Hairer's DOPRI5
code); its θ-averaged sum of squared 5th-order error coefficients is within 3 % of the minimum over the
family.

For Bogacki–Shampine 3(2) the continuous extension is the cubic Hermite interpolant of ``(y, f)`` at both
ends of the step (Bogacki & Shampine 1989, §3), written in the stages: FSAL makes ``f(t + h) = k_4``, so
``y0 + h[h10(θ) k_1 + h01(θ) Σ b_i k_i + h11(θ) k_4]`` (``h10 = θ − 2θ² + θ³``, ``h01 = 3θ² − 2θ³``,
``h11 = θ³ − θ²``) gives ``b_1(θ) = θ − 4/3 θ² + 5/9 θ³``, ``b_2(θ) = θ² − 2/3 θ³``,
``b_3(θ) = 4/3 θ² − 8/9 θ³``, ``b_4(θ) = −θ² + θ³``: exactly that interpolant, and of order 3 for every θ
(all four order conditions up to ``ρ(τ) = 3`` hold identically in θ).
``tests/dynamics/test_runge_kutta.py`` checks all the order conditions, the continuity conditions, and the
observed convergence order of both methods and both continuous extensions.

Failures (docs/model.md §9: stick and impacts must not crash or hang)
-----------------------------------------------------------
A stage with non-finite values (NaN, ±inf, overflow; NumPy floating-point warnings are silenced inside a
step) counts as a rejected step and shrinks the step by ``min_factor``. :class:`IntegrationError` is raised
— carrying every output point computed so far in ``.solution`` — when the step size falls below
``min_step``, when ``max_steps`` attempts are exceeded, or when the state itself becomes non-finite.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from drillstring.dynamics.additive_rk import IMEX_TABLEAUS
from drillstring.dynamics.exponential_rk import EXPONENTIAL_TABLEAUS
from drillstring.dynamics.step_control import RHS, StepSizeController, error_norm, step_factor
from drillstring.dynamics.steps import kind_of
from drillstring.dynamics.tableaus import (
    BOGACKI_SHAMPINE_32,
    DORMAND_PRINCE_54,
    TABLEAUS,
    ButcherTableau,
    dense_weights,
)

__all__ = [
    "ButcherTableau",
    "DORMAND_PRINCE_54",
    "BOGACKI_SHAMPINE_32",
    "TABLEAUS",
    "method_named",
    "dense_weights",
    "StepSizeController",
    "error_norm",
    "step_factor",
    "RungeKuttaStepper",
    "Solution",
    "IntegrationError",
    "integrate",
]



def method_named(name: str):
    """The integration method called ``name``: an explicit pair of :data:`TABLEAUS`, an implicit–explicit
    additive pair of :data:`drillstring.dynamics.additive_rk.IMEX_TABLEAUS` or an exponential pair of
    :data:`drillstring.dynamics.exponential_rk.EXPONENTIAL_TABLEAUS` (``simulation.method``)."""

    methods = {**TABLEAUS, **IMEX_TABLEAUS, **EXPONENTIAL_TABLEAUS}
    try:
        return methods[name]
    except KeyError:
        raise ValueError(f"unknown tableau {name!r}; known: {sorted(methods)}") from None


# ---------------------------------------------------------------------------------------------------------
# Errors and results
# ---------------------------------------------------------------------------------------------------------


class IntegrationError(RuntimeError):
    """The integration could not continue. ``.solution`` holds the output computed so far
    (status ``"failed"``); it is ``None`` when raised by a bare :class:`RungeKuttaStepper`."""

    def __init__(self, message: str, solution: Solution | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.solution = solution


@dataclass
class Solution:
    """Result of :func:`integrate`: outputs ``y[i] = observe(t[i], y(t[i]))`` (or the state itself)."""

    t: np.ndarray
    y: np.ndarray
    status: str
    message: str
    n_rhs: int
    n_accepted: int
    n_rejected: int
    wall_time: float

    @property
    def success(self) -> bool:
        return self.status == "success"

    @property
    def stats(self) -> dict[str, Any]:
        return {
            "status": self.status,
            "n_out": int(self.t.shape[0]),
            "n_rhs": self.n_rhs,
            "n_accepted": self.n_accepted,
            "n_rejected": self.n_rejected,
            "n_steps": self.n_accepted + self.n_rejected,
            "wall_time": self.wall_time,
        }


def _describe_nonfinite(x: np.ndarray) -> str:
    if np.isnan(x).any():
        return "NaN"
    return "inf"



# ---------------------------------------------------------------------------------------------------------
# Stepper
# ---------------------------------------------------------------------------------------------------------


class RungeKuttaStepper:
    """One explicit embedded Runge–Kutta step per :meth:`step` call.

    Parameters
    ----------
    rhs:
        ``rhs(t, y) -> dy/dt`` (array of the shape of ``y``). It must not modify ``y`` in place.
    t0, y0:
        Initial time and state (``y0`` is copied, 1-D).
    tableau:
        The method.
    controller:
        A :class:`StepSizeController`, or ``None`` for fixed steps of size ``h0`` (every step accepted; the
        last one is shortened to land on ``t_bound``).
    h0:
        First step size (magnitude); ``None`` chooses it by :meth:`StepSizeController.initial_step`.
    t_bound:
        Steps never go past this time (default ``+inf``); it also sets the direction of integration.
    min_step:
        :class:`IntegrationError` when the step size to attempt falls below this (a last step shortened to
        land on ``t_bound`` is exempt).

    State: ``t``, ``y``, ``f`` (= ``rhs(t, y)``, reused as first stage, FSAL), ``h`` (next step to
    attempt, signed), counters ``n_rhs``, ``n_accepted``, ``n_rejected``; ``last_error_norm`` and
    ``last_cause`` (why the last attempt was rejected, or ``None``).
    """

    def __init__(self, rhs: RHS, t0: float, y0: np.ndarray, tableau: ButcherTableau,
                 controller: StepSizeController | None, h0: float | None = None, *,
                 t_bound: float = math.inf, min_step: float = 0.0) -> None:
        self.rhs = rhs
        self.tableau = tableau
        self.controller = controller
        self.t = float(t0)
        self.t_bound = float(t_bound)
        if self.t_bound == self.t:
            raise ValueError("t_bound equals t0: nothing to integrate")
        self.direction = 1.0 if self.t_bound > self.t else -1.0
        self.min_step = float(min_step)
        y = np.array(y0, dtype=np.result_type(np.asarray(y0), np.float64))
        if y.ndim != 1:
            raise ValueError(f"y0 must be 1-D, got shape {y.shape}")
        self.y = y
        self.n_rhs = 0
        self.n_accepted = 0
        self.n_rejected = 0
        self.last_error_norm = math.nan
        self.last_cause: str | None = None

        with np.errstate(all="ignore"):
            f = np.asarray(rhs(self.t, self.y), dtype=y.dtype)
        self.n_rhs += 1
        if f.shape != y.shape:
            raise ValueError(f"rhs returned shape {f.shape}, expected {y.shape}")
        if not np.isfinite(f).all():
            raise IntegrationError(
                f"non-finite right-hand side at the initial state, t = {self.t:.10g} s: "
                f"{_describe_nonfinite(f)} in rhs(t0, y0)"
            )
        self.f = f

        # the step itself: the NumPy reference of the method's step kind (drillstring.dynamics.steps)
        kind = kind_of(tableau)
        if kind.reference is None:
            raise TypeError(f"the step kind of {tableau.name} has no NumPy reference: compiled path only")
        self._step = kind.reference(tableau, y)
        self._q = self._step.order

        self._t0 = self.t
        self._fixed = controller is None
        self._stretch = 1e-6 if self._fixed else 0.01
        if controller is None:
            if h0 is None or not h0 > 0:
                raise ValueError("fixed-step integration (controller=None) needs h0 > 0")
            h = float(h0)
        elif h0 is None:
            h = controller.initial_step(rhs, self.t, self.y, self.f, self._q, self.direction)
            self.n_rhs += 1
            h = max(h, self.min_step)
        else:
            h = min(abs(float(h0)), controller.max_step)
        if not h > 0:
            raise ValueError("initial step size must be positive")
        self.h = self.direction * h

        # dense-output data of the last accepted step
        self.t_old = math.nan
        self.h_last = math.nan
        self._y_old: np.ndarray | None = None
        self._f_old: np.ndarray | None = None

    # -- helpers -------------------------------------------------------------------------------------------
    def _fail(self, cause: str, h: float | None = None) -> IntegrationError:
        hh = abs(self.h if h is None else h)
        return IntegrationError(f"integration failed at t = {self.t:.10g} s (h = {hh:.3g} s): {cause}")

    @property
    def finished(self) -> bool:
        return self.t == self.t_bound

    # -- the step ------------------------------------------------------------------------------------------
    def step(self) -> bool:
        """Attempt one step; return ``True`` when accepted (``t``, ``y``, ``f`` advance), ``False`` when
        rejected (only ``h`` shrinks). Raises :class:`IntegrationError` when the step size falls below
        ``min_step`` or the accepted state is non-finite."""
        t, y = self.t, self.y
        remaining = self.t_bound - t
        if remaining == 0.0:
            raise RuntimeError("the stepper has already reached t_bound")
        h = self.h
        # land exactly on t_bound, stretching the step slightly rather than leaving a sliver (Hairer's
        # DOPRI5 stretches by up to 1 %; fixed steps only absorb round-off)
        if abs(h) * (1.0 + self._stretch) >= abs(remaining):
            h = remaining
            last = True
        else:
            last = False
            if abs(h) < self.min_step:
                cause = f"step size fell below min_step = {self.min_step:.3g} s"
                if self.last_cause:
                    cause += f"; last rejection: {self.last_cause}"
                raise self._fail(cause)
            if t + h == t:
                raise self._fail("step size below the floating-point resolution of t")

        y_new, err, evaluations, cause = self._step.attempt(self.rhs, t, h, y, self.f)
        self.n_rhs += evaluations

        ctrl = self.controller
        if cause is not None:
            self.last_cause = cause
            self.last_error_norm = math.nan
            if ctrl is None:
                raise self._fail(cause, h)
            self.n_rejected += 1
            self.h = ctrl.accept(math.nan, h, self._q)[1]  # a rejection by min_factor
            return False

        if ctrl is None:
            accepted, h_next = True, self.h
            self.last_error_norm = math.nan
        else:
            with np.errstate(all="ignore"):
                en = ctrl.error_norm(y, y_new, err)
            self.last_error_norm = en
            accepted, h_next = ctrl.accept(en, h, self._q)
            if not accepted:
                self.last_cause = (f"error estimate not met (error norm {en:.3g})" if math.isfinite(en)
                                   else "non-finite error estimate")
                self.n_rejected += 1
                self.h = h_next
                return False

        if not np.isfinite(y_new).all():
            raise self._fail(f"non-finite state ({_describe_nonfinite(y_new)}) after an accepted step", h)
        f_new, evaluations = self._step.accept(self.rhs, t + h, y_new)
        if evaluations:
            self.n_rhs += evaluations
            if not np.isfinite(f_new).all():
                raise self._fail(f"{_describe_nonfinite(f_new)} in the right-hand side at the accepted state", h)

        # commit; the step kept the accepted step's data for dense output
        self.t_old, self.h_last = t, h
        self._y_old, self._f_old = y, self.f
        if last:
            self.t = self.t_bound
        elif self._fixed:  # t0 + n·h: no drift over many fixed steps
            self.t = self._t0 + (self.n_accepted + 1) * h
        else:
            self.t = t + h
        self.y, self.f = y_new, f_new
        self.h = h_next
        self.n_accepted += 1
        self.last_cause = None
        return True

    # -- dense output --------------------------------------------------------------------------------------
    def dense_polynomial(self) -> tuple[float, float, np.ndarray, np.ndarray]:
        """The last accepted step's continuous extension as a polynomial in ``s ∈ [0, 1]``: returns
        ``(t_old, h, y_old, coef)`` with ``y(t_old + s·h) = y_old + Σ_p coef[p] s^(p+1)``, ``coef`` of
        shape ``(p, n)``, ``coef[p] = h Σ_i dense[i, p] k_i`` (the same values :meth:`interpolate`
        gives). For a caller that records the solution's history (e.g. :mod:`.delay`). Valid until the
        next accepted step; raises ``ValueError`` when the tableau has no continuous extension."""
        if self._step.dense is None:
            raise ValueError(f"{self.tableau.name} has no dense-output coefficients: no dense polynomial")
        if self._y_old is None:
            raise RuntimeError("no accepted step yet: no dense polynomial")
        h = self.h_last
        coef = h * (self._step.dense.T @ self._step.dense_stages)
        return self.t_old, h, self._y_old.copy(), coef

    def interpolate(self, t: float | np.ndarray) -> np.ndarray:
        """State at time(s) ``t`` inside the last accepted step ``[t_old, t]``: shape ``(n,)`` for a
        scalar, ``(m, n)`` for ``m`` times. Uses the tableau's continuous extension, or cubic Hermite
        interpolation of ``y`` and ``f`` at both ends when the tableau has none. Valid until the next
        accepted step."""
        if self._y_old is None:
            raise RuntimeError("no accepted step yet: nothing to interpolate")
        tt = np.asarray(t, dtype=np.float64)
        h = self.h_last
        theta = (tt - self.t_old) / h
        if np.any(theta < -1e-9) or np.any(theta > 1.0 + 1e-9):
            raise ValueError("interpolate: time outside the last accepted step")
        y0 = self._y_old
        if self._step.dense is not None:
            w = dense_weights(self._step.dense, theta)  # (s,) or (m, s)
            return y0 + h * (w @ self._step.dense_stages)
        # cubic Hermite on (y0, f0), (y1, f1)
        th = theta[..., None]
        th2 = th * th
        th3 = th2 * th
        h00 = 2 * th3 - 3 * th2 + 1
        h10 = th3 - 2 * th2 + th
        h01 = -2 * th3 + 3 * th2
        h11 = th3 - th2
        out = h00 * y0 + (h * h10) * self._f_old + h01 * self.y + (h * h11) * self.f
        return out


# ---------------------------------------------------------------------------------------------------------
# Driver
# ---------------------------------------------------------------------------------------------------------


class _Rows:
    """Output rows: preallocated for a known grid, grown by doubling otherwise."""

    def __init__(self, capacity: int) -> None:
        self.t = np.empty(max(capacity, 1))
        self.y: np.ndarray | None = None
        self.n = 0

    def add(self, t: np.ndarray, rows: np.ndarray) -> None:
        m = t.shape[0]
        if m == 0:
            return
        if self.y is None:
            self.y = np.empty((self.t.shape[0], rows.shape[1]), dtype=rows.dtype)
        need = self.n + m
        if need > self.t.shape[0]:
            cap = max(need, 2 * self.t.shape[0])
            self.t = np.resize(self.t, cap)
            y = np.empty((cap, self.y.shape[1]), dtype=self.y.dtype)
            y[: self.n] = self.y[: self.n]
            self.y = y
        self.t[self.n:need] = t
        self.y[self.n:need] = rows
        self.n = need

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        y = self.y[: self.n].copy() if self.y is not None else np.empty((0, 0))
        return self.t[: self.n].copy(), y


def _output_grid(t0: float, t_end: float, t_out: Any, output_step: float | None) -> np.ndarray | None:
    span = t_end - t0
    direction = 1.0 if span >= 0 else -1.0
    if t_out is not None:
        if output_step is not None:
            raise ValueError("give t_out or output_step, not both")
        g = np.array(t_out, dtype=np.float64).ravel()
        tol = 1e-12 * max(abs(t0), abs(t_end), abs(span))
        if g.size and np.any(np.diff(g) * direction <= 0):
            raise ValueError("t_out must be strictly monotone in the direction of integration")
        if g.size and (direction * (g[0] - t0) < -tol or direction * (g[-1] - t_end) > tol):
            raise ValueError("t_out must lie inside t_span")
        if g.size:  # snap round-off at the ends
            g[0] = t0 if abs(g[0] - t0) <= tol else g[0]
            g[-1] = t_end if abs(g[-1] - t_end) <= tol else g[-1]
        return g
    if output_step is not None:
        dt = abs(float(output_step))
        if not dt > 0:
            raise ValueError("output_step must be positive")
        n = int(math.floor(abs(span) / dt + 1e-9))
        g = t0 + direction * dt * np.arange(n + 1)
        if abs(g[-1] - t_end) <= 1e-9 * dt:
            g[-1] = t_end
        else:
            g = np.append(g, t_end)
        return g
    return None


def integrate(
    rhs: RHS,
    t_span: tuple[float, float],
    y0: np.ndarray,
    *,
    t_out: np.ndarray | None = None,
    output_step: float | None = None,
    tableau: ButcherTableau | str = DORMAND_PRINCE_54,
    rtol: float = 1e-6,
    atol: float | np.ndarray = 1e-9,
    max_step: float = math.inf,
    min_step: float = 1e-12,
    max_steps: int = 1_000_000,
    first_step: float | None = None,
    fixed_step: float | None = None,
    progress: Callable[[float], None] | None = None,
    observe: Callable[[float, np.ndarray], np.ndarray] | None = None,
    raise_on_failure: bool = True,
    controller: StepSizeController | None = None,
    on_step: Callable[[float, np.ndarray], None] | None = None,
    on_dense_step: Callable[[float, float, np.ndarray, np.ndarray], None] | None = None,
) -> Solution:
    """Integrate ``y' = rhs(t, y)`` over ``t_span = (t0, t_end)`` (``t_end < t0`` integrates backwards).

    Output grid: ``t_out`` (monotone, inside ``t_span``), or ``t0 + k·output_step`` up to ``t_end``, with
    ``t_end`` itself always included exactly (appended when the span is not a multiple of the step); with
    neither, every accepted step is output. Values between steps come from the stepper's dense output.
    ``observe(t, y)`` maps the state to what is stored (1-D; a scalar is stored as one column).
    ``on_step(t, y)`` is called after every accepted step with its end time and state;
    ``on_dense_step(t_old, h, y_old, coef)`` after every accepted step (never a rejected one) with its
    dense-output polynomial (:meth:`RungeKuttaStepper.dense_polynomial`), before ``on_step`` — to record
    the solution's history for a delayed right-hand side.

    Step control: ``rtol``, ``atol`` (scalar or per-component), ``max_step``, ``first_step``; a fully
    configured ``controller`` overrides those four. ``fixed_step`` switches control off (every step of
    that size accepted, the last one shortened to land on ``t_end``) — for convergence studies.

    Failure: when the step size falls below ``min_step``, after ``max_steps`` step attempts (accepted +
    rejected), or when the state becomes non-finite, :class:`IntegrationError` is raised with the partial
    :class:`Solution` in ``.solution``; with ``raise_on_failure=False`` that partial solution (status
    ``"failed"``) is returned instead. ``progress(t)`` is called at most every 0.5 % of the span, and at
    the end.
    """
    wall0 = time.perf_counter()
    if isinstance(tableau, str):
        tableau = method_named(tableau)
    if on_dense_step is not None and tableau.dense is None:
        raise ValueError(f"on_dense_step needs a tableau with dense output; {tableau.name} has none")
    t0, t_end = float(t_span[0]), float(t_span[1])
    if not (math.isfinite(t0) and math.isfinite(t_end)):
        raise ValueError("t_span must be finite")
    y0 = np.asarray(y0)
    y0 = y0.astype(np.result_type(y0, np.float64), copy=False)
    span = abs(t_end - t0)
    direction = 1.0 if t_end >= t0 else -1.0
    grid = _output_grid(t0, t_end, t_out, output_step)

    def obs(t: float, y: np.ndarray) -> np.ndarray:
        if observe is None:
            return y
        return np.atleast_1d(np.asarray(observe(t, y))).ravel()

    rows = _Rows(grid.shape[0] if grid is not None else 1024)
    gi = 0  # next grid index to fill
    if grid is None:
        rows.add(np.array([t0]), obs(t0, y0)[None, :])
    else:
        while gi < grid.shape[0] and grid[gi] == t0:
            rows.add(grid[gi: gi + 1], obs(t0, y0)[None, :])
            gi += 1

    stepper: RungeKuttaStepper | None = None

    def result(status: str, message: str) -> Solution:
        t_arr, y_arr = rows.arrays()
        return Solution(
            t=t_arr, y=y_arr, status=status, message=message,
            n_rhs=stepper.n_rhs if stepper else 0,
            n_accepted=stepper.n_accepted if stepper else 0,
            n_rejected=stepper.n_rejected if stepper else 0,
            wall_time=time.perf_counter() - wall0,
        )

    def failed(exc: IntegrationError) -> Solution:
        sol = result("failed", exc.message)
        exc.solution = sol
        if raise_on_failure:
            raise exc
        return sol

    if span == 0.0:
        return result("success", "empty time span")

    if fixed_step is not None:
        ctrl = None
        h0 = float(fixed_step)
    else:
        ctrl = controller if controller is not None else StepSizeController(
            rtol=rtol, atol=atol, max_step=max_step)
        ctrl.reset()
        h0 = first_step
    try:
        stepper = RungeKuttaStepper(rhs, t0, y0, tableau, ctrl, h0, t_bound=t_end, min_step=min_step)
    except IntegrationError as exc:
        return failed(exc)

    dgrid = direction * grid if grid is not None else None
    prog_every = 0.005 * span
    prog_last = t0
    if progress is not None:
        progress(t0)
    try:
        while not stepper.finished:
            if stepper.n_accepted + stepper.n_rejected >= max_steps:
                raise stepper._fail(f"maximum number of step attempts exceeded (max_steps = {max_steps})")
            if not stepper.step():
                continue
            t_new = stepper.t
            if on_dense_step is not None:
                on_dense_step(*stepper.dense_polynomial())
            if on_step is not None:
                on_step(t_new, stepper.y)
            if grid is None:
                rows.add(np.array([t_new]), obs(t_new, stepper.y)[None, :])
            else:
                j = int(np.searchsorted(dgrid, direction * t_new, side="right"))
                if j > gi:
                    tg = grid[gi:j]
                    exact_end = tg[-1] == t_new
                    inner = tg[:-1] if exact_end else tg
                    if inner.size:
                        ys = stepper.interpolate(inner)
                        if observe is None:
                            rows.add(inner, ys)
                        else:
                            rows.add(inner, np.stack([obs(ti, yi) for ti, yi in zip(inner, ys)]))
                    if exact_end:
                        rows.add(tg[-1:], obs(t_new, stepper.y)[None, :])
                    gi = j
            if progress is not None and abs(t_new - prog_last) >= prog_every:
                progress(t_new)
                prog_last = t_new
    except IntegrationError as exc:
        return failed(exc)

    if progress is not None and prog_last != t_end:
        progress(t_end)
    return result("success", f"reached t_end = {t_end:.10g} s")
