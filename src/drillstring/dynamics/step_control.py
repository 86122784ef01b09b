"""The step-size controller of the adaptive Runge–Kutta integration: the weighted error norm and the PI
step factor (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.4; Hairer & Wanner, *Solving ODEs II*, §IV.2), as
compiled kernels shared by the NumPy stepper and the compiled step loop (see
:mod:`drillstring.dynamics.runge_kutta`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numba import njit

#: A right-hand side ``f(t, y) -> dy/dt``.
RHS = Callable[[float, np.ndarray], np.ndarray]

#: Floor of the previous error norm remembered by the PI controller (HNW's DOPRI5 code).
ERROR_NORM_FLOOR = 1e-4


@njit(cache=True)
def error_norm(y, y_new, err, rtol, atol):
    """``‖err / (atol + rtol·max(|y|, |y_new|))‖_RMS`` (HNW I, eq. II.4.11); ``atol`` has one entry per
    component. 0 for an empty state. One implementation for both integrators (module docstring)."""
    n = y.shape[0]
    if n == 0:
        return 0.0
    total = 0.0
    for j in range(n):
        ratio = abs(err[j]) / (atol[j] + rtol * max(abs(y[j]), abs(y_new[j])))
        total += ratio * ratio
    return math.sqrt(total / n)


@njit(cache=True)
def step_factor(norm, err_prev, rejected_last, order, safety, min_factor, max_factor, beta1, beta2):
    """The PI controller's decision on a step whose error norm is ``norm`` (module docstring).

    ``err_prev``: the previous accepted step's (floored) error norm; ``rejected_last``: whether the
    previous attempt was rejected; ``order``: ``q``, that of the error estimate (exponents ∝ 1/(q + 1)).
    Returns ``(accepted, factor, err_prev_next)``: the step is accepted when ``norm ≤ 1``; the next step
    size is ``factor · h``; a non-finite norm is a rejection by ``min_factor``. The caller keeps
    ``err_prev_next`` and ``rejected_last = not accepted`` for the next decision."""
    k = order + 1.0
    if not math.isfinite(norm):
        return False, min_factor, err_prev
    if norm > 1.0:
        return False, max(min_factor, safety * norm ** (-1.0 / k)), err_prev
    if norm == 0.0:
        factor = max_factor
    else:
        factor = safety * norm ** (-beta1 / k) * err_prev ** (beta2 / k)
        factor = min(max_factor, max(min_factor, factor))
    if rejected_last:
        factor = min(1.0, factor)
    return True, factor, max(norm, ERROR_NORM_FLOOR)



@dataclass
class StepSizeController:
    """PI step-size controller (Gustafsson 1991; Hairer–Nørsett–Wanner I §II.4, II §IV.2).

    ``beta1`` and ``beta2`` are the gains in units of ``1/k`` (``k = order + 1``, ``order`` being that of
    the error estimate): the exponents are ``β1/k`` on the current error and ``β2/k`` on the previous
    accepted error. The defaults ``β1 = 0.85, β2 = 0.2`` are those of Hairer's DOPRI5 code
    (HNW I §II.4: ``α = 1/k − 0.75 β``, ``β = 0.04`` for ``k = 5``) scaled by ``k``; Gustafsson's own gains
    ``k_I = 0.3, k_P = 0.4`` give ``β1 = k_I + k_P = 0.7, β2 = k_P = 0.4`` (smoother but ~30 % more steps:
    with ``safety`` the PI loop settles at an error norm ``safety^(k/(β1−β2))``, 0.44 with the defaults,
    0.17 with Gustafsson's); ``β1 = 1, β2 = 0`` is the classical integral (I) controller (0.59).

    The controller keeps the previous accepted error norm and whether the last attempt was rejected;
    call :meth:`reset` before reusing it for another integration.
    """

    rtol: float = 1e-6
    atol: float | np.ndarray = 1e-9
    safety: float = 0.9
    min_factor: float = 0.2
    max_factor: float = 10.0
    beta1: float = 0.85
    beta2: float = 0.2
    max_step: float = math.inf
    _err_prev: float = field(default=1.0, init=False, repr=False)
    _rejected_last: bool = field(default=False, init=False, repr=False)

    def __post_init__(self) -> None:
        if np.any(np.asarray(self.rtol) < 0) or np.any(np.asarray(self.atol) < 0):
            raise ValueError("rtol and atol must be non-negative")
        if not np.all(np.asarray(self.atol) + np.asarray(self.rtol) > 0):
            raise ValueError("atol + rtol must be positive")
        if not (0 < self.safety <= 1 and 0 < self.min_factor < 1 < self.max_factor):
            raise ValueError("need 0 < safety <= 1 and 0 < min_factor < 1 < max_factor")
        if not self.max_step > 0:
            raise ValueError("max_step must be positive")
        if not isinstance(self.atol, float | int):
            self.atol = np.asarray(self.atol, dtype=np.float64)

    def reset(self) -> None:
        self._err_prev = 1.0
        self._rejected_last = False

    def atol_vector(self, n: int) -> np.ndarray:
        """``atol`` as a contiguous array of ``n`` entries (what :func:`error_norm` takes)."""
        return np.ascontiguousarray(np.broadcast_to(np.asarray(self.atol, dtype=np.float64), (n,)))

    def error_norm(self, y: np.ndarray, y_new: np.ndarray, err: np.ndarray) -> float:
        """RMS of ``err / (atol + rtol·max(|y|, |y_new|))`` (HNW I, eq. II.4.11; :func:`error_norm`)."""
        return float(error_norm(y, y_new, err, float(self.rtol), self.atol_vector(y.shape[0])))

    def _norm(self, x: np.ndarray, scale: np.ndarray) -> float:
        r = np.abs(x) / scale
        return float(np.sqrt(np.mean(r * r))) if r.size else 0.0

    def initial_step(self, rhs: RHS, t0: float, y0: np.ndarray, f0: np.ndarray, order: int,
                     direction: float = 1.0) -> float:
        """Starting step size, HNW I §II.4 (makes exactly one extra ``rhs`` call). Returns ``|h|``.

        ``order`` is that of the error estimate (``q``); the exponent is ``1/(q + 1)``."""
        scale = self.atol + self.rtol * np.abs(y0)
        scale = np.broadcast_to(scale, np.shape(y0))
        d0 = self._norm(y0, scale)
        d1 = self._norm(f0, scale)
        h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
        h0 = min(h0, self.max_step)
        with np.errstate(all="ignore"):
            try:
                y1 = y0 + direction * h0 * f0
                f1 = np.asarray(rhs(t0 + direction * h0, y1))
                d2 = self._norm(f1 - f0, scale) / h0
            except (FloatingPointError, OverflowError):
                d2 = math.nan
        if not math.isfinite(d2):
            return h0
        dmax = max(d1, d2)
        h1 = max(1e-6, h0 * 1e-3) if dmax <= 1e-15 else (0.01 / dmax) ** (1.0 / (order + 1))
        return float(min(100.0 * h0, h1, self.max_step))

    def accept(self, error_norm: float, h: float, order: int) -> tuple[bool, float]:
        """Decide on a step with error norm ``error_norm`` taken with size ``h`` (signed).

        Returns ``(accepted, h_next)``; a non-finite ``error_norm`` is a rejection by ``min_factor``
        (:func:`step_factor`)."""
        accepted, factor, self._err_prev = step_factor(
            float(error_norm), self._err_prev, self._rejected_last, float(order), self.safety,
            self.min_factor, self.max_factor, self.beta1, self.beta2)
        self._rejected_last = not accepted
        return bool(accepted), self._limit(h * factor)

    def _limit(self, h: float) -> float:
        return math.copysign(min(abs(h), self.max_step), h)

