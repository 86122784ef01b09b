"""Fast path: the embedded Runge–Kutta loop for the reduced-order model, compiled with Numba.

The same method data (:class:`~drillstring.dynamics.runge_kutta.ButcherTableau`), the same PI
step-size controller rules and error norm, and the same dense output as the reference integrator
:func:`~drillstring.dynamics.runge_kutta.integrate`, with the ROM's right-hand side and observation
kernels called directly from compiled code, so that no Python runs inside the step loop. Tests check
that both paths agree to within the integration tolerance.

The loop runs in chunks of the output grid so a progress callback can be called between chunks; the
step sequence does not depend on the chunking (steps never land on chunk boundaries, only on t_end).
"""

from __future__ import annotations

import math
import time as _time
from typing import Callable

import numpy as np
from numba import njit

from drillstring.dynamics.rom import _observe_kernel, rhs_dispatch
from drillstring.dynamics.runge_kutta import TABLEAUS, ButcherTableau, StepSizeController

SUCCESS, MIN_STEP, MAX_STEPS, NON_FINITE = 0, 1, 2, 3
# indices into the integrator's scalar state array
T, H, ERR_PREV, REJECTED_LAST, N_RHS, N_ACCEPTED, N_REJECTED, IMPACTS, N_OUT, LAST_CAUSE = range(10)
CAUSES = {0: "", 1: "error estimate not met", 2: "non-finite values in the right-hand side"}


@njit(cache=True)
def _observe(t, y, out, row, obs_args, previous):
    _observe_kernel(y, out[row], *obs_args)
    in_contact = obs_args[-1]
    new = 0
    for i in range(in_contact.shape[0]):
        if in_contact[i] and not previous[i]:
            new += 1
        previous[i] = in_contact[i]
    return new


@njit(cache=True)
def _run_chunk(state, y, f, k, k_old, y_old, grid, t_stop, t_end, a, b, e, c, dense, fsal,
               q_order, rtol, atol, safety, min_factor, max_factor, beta1, beta2, max_step,
               min_step, max_steps, stretch, full, case2_args, full_args, obs_args, out, previous,
               y_tmp):
    """Advance until the output grid is filled up to ``t_stop`` (or t_end). Returns a status code."""
    n = y.shape[0]
    s = c.shape[0]
    kk = q_order + 1.0
    n_grid = grid.shape[0]
    while True:
        t = state[T]
        row = int(state[N_OUT])
        if row >= n_grid or grid[row] > t_stop:
            return SUCCESS
        if state[N_ACCEPTED] + state[N_REJECTED] >= max_steps:
            return MAX_STEPS
        h = state[H]
        remaining = t_end - t
        last = False
        if h * (1.0 + stretch) >= remaining:
            h = remaining
            last = True
        elif h < min_step:
            return MIN_STEP
        # stages
        for j in range(n):
            k[0, j] = f[j]
        finite = True
        for i in range(1, s):
            for j in range(n):
                acc = 0.0
                for m in range(i):
                    acc += a[i, m] * k[m, j]
                y_tmp[j] = y[j] + h * acc
            rhs_dispatch(y_tmp, k[i], full, case2_args, full_args)
            for j in range(n):
                if not math.isfinite(k[i, j]):
                    finite = False
            if not finite:
                state[N_RHS] += i
                break
        if finite:
            state[N_RHS] += s - 1
            # y_new (FSAL: the last stage argument) and error norm
            err2 = 0.0
            for j in range(n):
                if fsal:
                    y_new_j = y_tmp[j]
                else:
                    acc = 0.0
                    for m in range(s):
                        acc += b[m] * k[m, j]
                    y_new_j = y[j] + h * acc
                    y_tmp[j] = y_new_j
                er = 0.0
                for m in range(s):
                    er += e[m] * k[m, j]
                er *= h
                scale = atol + rtol * max(abs(y[j]), abs(y_new_j))
                err2 += (er / scale) ** 2
            error_norm = math.sqrt(err2 / n)
            finite = math.isfinite(error_norm)
        if not finite:
            state[N_REJECTED] += 1
            state[REJECTED_LAST] = 1.0
            state[LAST_CAUSE] = 2.0
            state[H] = min(h * min_factor, max_step)
            continue
        if error_norm > 1.0:
            factor = max(min_factor, safety * error_norm ** (-1.0 / kk))
            state[N_REJECTED] += 1
            state[REJECTED_LAST] = 1.0
            state[LAST_CAUSE] = 1.0
            state[H] = min(h * factor, max_step)
            continue
        if error_norm == 0.0:
            factor = max_factor
        else:
            factor = safety * error_norm ** (-beta1 / kk) * state[ERR_PREV] ** (beta2 / kk)
            factor = min(max_factor, max(min_factor, factor))
        if state[REJECTED_LAST] > 0.0:
            factor = min(1.0, factor)
        state[ERR_PREV] = max(error_norm, 1e-4)
        state[REJECTED_LAST] = 0.0
        state[LAST_CAUSE] = 0.0
        for j in range(n):
            if not math.isfinite(y_tmp[j]):
                return NON_FINITE
        # commit: keep the step's stages for dense output
        for j in range(n):
            y_old[j] = y[j]
            y[j] = y_tmp[j]
        for m in range(s):
            for j in range(n):
                k_old[m, j] = k[m, j]
        if fsal:
            for j in range(n):
                f[j] = k[s - 1, j]
        else:
            rhs_dispatch(y, f, full, case2_args, full_args)
            state[N_RHS] += 1
        t_new = t_end if last else t + h
        state[T] = t_new
        state[H] = min(h * factor, max_step)
        state[N_ACCEPTED] += 1
        # outputs inside (t, t_new]
        while row < n_grid and grid[row] <= t_new:
            tg = grid[row]
            if tg == t_new:
                state[IMPACTS] += _observe(tg, y, out, row, obs_args, previous)
            else:
                theta = (tg - t) / h
                for j in range(n):
                    acc = 0.0
                    for m in range(s):
                        bm = 0.0
                        power = theta
                        for p in range(dense.shape[1]):
                            bm += dense[m, p] * power
                            power *= theta
                        acc += bm * k_old[m, j]
                    y_tmp[j] = y_old[j] + h * acc
                state[IMPACTS] += _observe(tg, y_tmp, out, row, obs_args, previous)
            row += 1
            state[N_OUT] = row
        if last:
            return SUCCESS


def integrate_compiled(
    model,
    y0: np.ndarray,
    grid: np.ndarray,
    *,
    tableau: ButcherTableau | str = "dopri5",
    rtol: float = 1e-6,
    atol: float = 1e-9,
    max_step: float = math.inf,
    min_step: float = 1e-12,
    max_steps: int = 2_000_000,
    progress: Callable[[float], None] | None = None,
    chunks: int = 100,
):
    """Integrate ``model`` (a :class:`~drillstring.dynamics.rom.ReducedOrderModel`) from ``y0`` at t = 0
    over the output ``grid`` (starting at 0, ending at t_end) in compiled code.

    Returns ``(outputs, stats, message)``: outputs (n_written, n_observables) rows for the first
    n_written grid times, a dict of solver statistics, and an empty message or the cause of failure.
    """
    tab = TABLEAUS[tableau] if isinstance(tableau, str) else tableau
    if tab.dense is None:
        raise ValueError(f"the compiled path needs a tableau with dense output; {tab.name} has none")
    ctrl = StepSizeController(rtol=rtol, atol=atol, max_step=max_step)
    grid = np.ascontiguousarray(grid, dtype=float)
    t_end = float(grid[-1])
    y = np.array(y0, dtype=float)
    n = y.size
    s = tab.n_stages
    f = model.rhs(0.0, y)
    h0 = ctrl.initial_step(model.rhs, 0.0, y, f, tab.controller_order)
    state = np.zeros(10)
    state[H] = h0
    state[ERR_PREV] = 1.0
    state[N_RHS] = 2
    out = np.full((len(grid), len(model.observable_names) + len(model.probe_nodes)), np.nan)
    previous = np.zeros(model.static.mesh.n_nodes, dtype=np.bool_)
    k, k_old, y_old, y_tmp = np.zeros((s, n)), np.zeros((s, n)), np.zeros(n), np.zeros(n)
    obs_args = model.observe_args
    e = np.ascontiguousarray(tab.b - tab.b_hat)
    start = _time.perf_counter()
    status = SUCCESS
    if grid[0] == 0.0:
        state[IMPACTS] += _observe(0.0, y, out, 0, obs_args, previous)
        state[N_OUT] = 1
    stops = grid[np.linspace(0, len(grid) - 1, min(chunks, len(grid)) + 1).astype(int)[1:]]
    for t_stop in stops:
        status = _run_chunk(
            state, y, f, k, k_old, y_old, grid, float(t_stop), t_end, np.ascontiguousarray(tab.a),
            np.ascontiguousarray(tab.b), e, np.ascontiguousarray(tab.c),
            np.ascontiguousarray(tab.dense), bool(tab.fsal), float(tab.controller_order),
            float(rtol), float(atol), ctrl.safety, ctrl.min_factor, ctrl.max_factor, ctrl.beta1,
            ctrl.beta2, float(max_step), float(min_step), float(max_steps), 0.01,
            model.full, model._rhs_args, model.full_args, obs_args, out, previous, y_tmp,
        )
        if progress is not None:
            progress(float(state[T]))
        if status != SUCCESS:
            break
    n_written = int(state[N_OUT])
    stats = {
        "status": "success" if status == SUCCESS else "failed",
        "n_out": n_written,
        "n_rhs": int(state[N_RHS]),
        "n_accepted": int(state[N_ACCEPTED]),
        "n_rejected": int(state[N_REJECTED]),
        "n_steps": int(state[N_ACCEPTED] + state[N_REJECTED]),
        "wall_time": _time.perf_counter() - start,
        "impacts": int(state[IMPACTS]),
    }
    message = ""
    if status != SUCCESS:
        t, h = state[T], state[H]
        cause = {
            MIN_STEP: f"step size fell below min_step = {min_step:.3g} s",
            MAX_STEPS: f"maximum number of steps ({max_steps}) exceeded",
            NON_FINITE: "non-finite state after an accepted step",
        }[status]
        last = CAUSES.get(int(state[LAST_CAUSE]), "")
        if last and status != NON_FINITE:
            cause += f"; last rejection: {last}"
        message = f"integration failed at t = {t:.10g} s (h = {h:.3g} s): {cause}"
    return out[:n_written], stats, message
