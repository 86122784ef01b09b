"""The bit's past, indexed by angle: the bottom-hole profile behind a regenerative (delayed) law.

A law whose depth of cut per blade is ``d_n(t) = u(t) − u(t − t_n)``, with the delay ``t_n`` solving
``θ(t) − θ(t − t_n) = 2π/n`` (T. Richard, C. Germay & E. Detournay, "A simplified model to explore the
root cause of stick–slip vibrations in drilling systems with drag bits", J. Sound Vib. 305 (2007)
432–456), needs ``u`` at the latest time the bit passed the angle ``θ(t) − Δ``, ``Δ = 2π/n`` (the *lag*).
That value is a function of angle — the height of the hole bottom the preceding blade left — so the
history is stored by angle, not by time: its size does not depend on the number of steps, and when the
bit sticks (``t_n`` grows without bound) the window it needs stays one blade sector.

Design
------
- **Bins.** Values sit on the uniform grid of bin angles ``φ_j = j·δφ``, ``δφ = Δ / bins_per_lag``
  (every integer ``j``, negative too), in a ring buffer whose capacity is the power of two
  ``≥ 4·bins_per_lag``: bin ``j`` lives in slot ``j mod capacity`` and the slot remembers which ``j``
  wrote it, so an unwritten slot or one overwritten by a bin ``capacity`` further on is recognised.
- **Recording** (:func:`record_step`), once per *accepted* integration step and never from a rejected
  step or a stage: the step's dense output gives ``θ(s)`` and ``u(s)`` as polynomials in
  ``s ∈ [0, 1]``; for every bin angle the step crosses (``θ_old < φ_j ≤ θ_new`` forward,
  ``θ_new ≤ φ_j < θ_old`` backward) the crossing ``s`` is found by Newton's method from the linear guess
  and ``u(s)`` stored. The latest crossing wins: a bin the bit passes again (backward rotation, then
  forward again) holds the value of its last passage. Within one step ``θ(s)`` is taken as monotone
  (the step resolves the motion).
- **The hole bottom** (:func:`record_bottom`): for the bit, what a blade leaves behind is the rock, not
  the bit's path: where the bit passes *above* the bottom the previous blade left (it has bounced off the
  rock: ``d_n ≤ 0``, nothing is cut) the bottom stays where it was. :func:`record_bottom` therefore
  stores ``max(u(s), bottom one lag back)`` (``x`` and ``u`` point down: deeper is larger), so that after a
  bounce, or while the bit is lowered towards a flat bottom, the next blade meets the rock and not the air
  the bit passed through. While the bit cuts (``d_n > 0``) this is ``u(s)``, the law's
  ``d_n = u(t) − u(t − t_n)``.
- **Prehistory.** A bin never written takes the line ``value(φ) = reference_value + slope·(φ −
  reference_angle)`` set by :func:`start`: slope 0 is a flat hole bottom; ``slope = d_blade/Δ`` the
  helical bottom of steady drilling at depth of cut ``d_blade`` per blade.
- **Reading** (:func:`lookup`): 4-point Lagrange (cubic) interpolation over the bins ``i−1 … i+2``
  around the angle (``i = ⌊angle/δφ⌋``); at a bin angle it returns that bin's value exactly.

Accuracy: the interpolation error is ``O(δφ⁴)`` for a smooth profile (about ``|u''''|·δφ⁴/24``; at the
default 2048 bins per lag and ``Δ = π/2``, ``δφ = 7.7e-4`` rad); the recorded values carry the dense
output's error (order 4 for Dormand–Prince, 3 for Bogacki–Shampine). Validity: the stencil of a lookup
at ``θ − Δ`` must lie in the recorded past, so a step must advance the angle by less than ``Δ − 3δφ``;
after backward rotation by more than about ``capacity·δφ − 2Δ`` the oldest bins are forgotten and the
prehistory line is read in their place.

Breakpoints: where the recorded history meets the prehistory with a jump in slope (a start from rest on
a flat bottom), the solution's derivatives jump again each time the angle passes ``θ_start + kΔ``; an
embedded Runge–Kutta error estimate does not see these jumps (on ``x'(t) = −x(t − 1)`` at rtol 1e-9 they
leave an error of 6.5e-8, against 3e-16 with the integration restarted there;
``tests/dynamics/test_delay.py``). A prehistory tangent to the initial motion moves the jump to higher
derivatives.

Everything compiled allocates nothing. The history lives in **one float64 array** (:func:`allocate_storage`:
``[meta (5), values (capacity), bins (capacity)]``, the bin indices stored as floats, exact below 2⁵³) so that
a model can carry it among its other numbers without a field of its own (every field of the reduced model's
right-hand-side data is an argument of each inner kernel: a field of three arrays made the reference
realization 30 % slower); :func:`view` gives the :class:`AngleHistory` of views that the functions read and
write, in compiled code and from Python alike.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

__all__ = ["AngleHistory", "allocate_storage", "view", "start", "record_step", "record_bottom", "lookup",
           "delayed_difference", "UNWRITTEN", "META_SIZE"]

#: Bin index marking a slot nobody wrote (no bin index is infinite).
UNWRITTEN = -np.inf
#: Entries of the storage before the values: the meta numbers (:class:`AngleHistory`).
META_SIZE = 5

# entries of AngleHistory.meta
_STEP, _LAG, _REF_ANGLE, _REF_VALUE, _SLOPE = 0, 1, 2, 3, 4
_NEWTON_ITERATIONS = 8


class AngleHistory(NamedTuple):
    """A value (the bit's axial position [m] for the depth of cut) as a function of angle [rad].

    ``values[slot]`` is the value at the bin angle ``bins[slot]·δφ`` (``bins[slot] == UNWRITTEN``: none);
    ``meta = [δφ [rad], Δ (the lag) [rad], reference angle [rad], reference value, slope [value/rad]]``,
    the last three the prehistory line (module docstring). All three are views of one storage array
    (:func:`allocate_storage`, :func:`view`)."""

    values: np.ndarray  # (capacity,) float64
    bins: np.ndarray  # (capacity,) float64, the absolute bin index j that wrote each slot (a whole number)
    meta: np.ndarray  # (5,) float64

    @classmethod
    def allocate(cls, lag: float, bins_per_lag: int = 2048) -> AngleHistory:
        """An empty history for the lag ``Δ`` [rad] (``2π/n`` for n blades), with the flat prehistory 0
        (call :func:`start` to set it): the views of :func:`allocate_storage`."""
        return view(allocate_storage(lag, bins_per_lag))

    @property
    def lag(self) -> float:
        """Δ [rad]."""
        return float(self.meta[_LAG])

    @property
    def bin_angle(self) -> float:
        """δφ [rad]."""
        return float(self.meta[_STEP])


def allocate_storage(lag: float, bins_per_lag: int = 2048) -> np.ndarray:
    """The float64 array that holds an empty history (module docstring) for the lag ``Δ`` [rad], with
    ``bins_per_lag`` bins per lag and the flat prehistory 0: ``[meta, values, bins]``, capacity the power of
    two ``≥ 4·bins_per_lag``."""
    lag = float(lag)
    if not (math.isfinite(lag) and lag > 0.0):
        raise ValueError(f"lag = {lag!r} rad: must be finite and > 0")
    if int(bins_per_lag) != bins_per_lag or bins_per_lag < 4:
        raise ValueError(f"bins_per_lag = {bins_per_lag!r}: must be an integer >= 4")
    capacity = 1 << int(math.ceil(math.log2(4 * int(bins_per_lag))))
    storage = np.empty(META_SIZE + 2 * capacity)
    storage[:META_SIZE] = [lag / int(bins_per_lag), lag, 0.0, 0.0, 0.0]
    start(view(storage), 0.0, 0.0, 0.0)
    return storage


@njit(cache=True, inline="always")
def view(storage):
    """The :class:`AngleHistory` whose arrays are views of ``storage`` (:func:`allocate_storage`)."""
    capacity = (storage.shape[0] - META_SIZE) // 2
    return AngleHistory(storage[META_SIZE:META_SIZE + capacity], storage[META_SIZE + capacity:],
                        storage[:META_SIZE])


@njit(cache=True)
def start(history, reference_angle, reference_value, slope):
    """Forget everything recorded; the prehistory becomes ``reference_value + slope·(φ −
    reference_angle)`` (angle [rad], value in the history's unit, slope in that unit per rad)."""
    history.bins[:] = UNWRITTEN
    history.values[:] = np.nan
    history.meta[_REF_ANGLE] = reference_angle
    history.meta[_REF_VALUE] = reference_value
    history.meta[_SLOPE] = slope


@njit(cache=True)
def _rise(coef, s):
    """``Σ_p coef[p] s^(p+1)`` and its derivative in ``s`` (Horner)."""
    p = coef.shape[0]
    value = 0.0
    slope = 0.0
    for q in range(p - 1, -1, -1):
        slope = slope * s + (q + 1) * coef[q]
        value = value * s + coef[q]
    return value * s, slope


@njit(cache=True)
def _write(history, j, theta_old, theta_coef, value_old, value_coef, s_linear, deepest):
    """Store the value where ``θ(s)`` crosses the bin angle ``φ_j`` (Newton from ``s_linear``); with
    ``deepest``, the larger of it and the value of the bin one lag back (:func:`record_bottom`)."""
    target = j * history.meta[_STEP] - theta_old
    s = min(max(s_linear, 0.0), 1.0)
    for _ in range(_NEWTON_ITERATIONS):
        rise, dtheta = _rise(theta_coef, s)
        if dtheta == 0.0:
            break
        ds = (rise - target) / dtheta
        s_next = min(max(s - ds, 0.0), 1.0)
        if abs(s_next - s) <= 1e-15:
            s = s_next
            break
        s = s_next
    value = value_old + _rise(value_coef, s)[0]
    if deepest:
        value = max(value, _bin_value(history, j - int(round(history.meta[_LAG] / history.meta[_STEP]))))
    slot = j & (history.bins.shape[0] - 1)
    history.values[slot] = value
    history.bins[slot] = float(j)


@njit(cache=True)
def record_step(history, theta_old, theta_coef, value_old, value_coef):
    """Record one accepted step given by its dense output ``θ(s) = theta_old + Σ_p theta_coef[p]
    s^(p+1)`` [rad] and ``value(s) = value_old + Σ_p value_coef[p] s^(p+1)``, ``s ∈ [0, 1]``: every bin
    angle crossed between the step's ends gets the value at its crossing (module docstring)."""
    _record(history, theta_old, theta_coef, value_old, value_coef, False)


@njit(cache=True)
def record_bottom(history, theta_old, theta_coef, value_old, value_coef):
    """:func:`record_step` for the hole bottom under a bit (``value`` its axial position [m], down):
    every bin crossed gets the deeper of the bit's position and the bottom one lag back (module
    docstring: where the bit passes above the rock, the rock stays)."""
    _record(history, theta_old, theta_coef, value_old, value_coef, True)


@njit(cache=True)
def _record(history, theta_old, theta_coef, value_old, value_coef, deepest):
    step = history.meta[_STEP]
    capacity = history.bins.shape[0]
    theta_new = theta_old + _rise(theta_coef, 1.0)[0]
    span = theta_new - theta_old
    if span > 0.0:  # θ_old < φ_j ≤ θ_new
        j_first = int(math.floor(theta_old / step)) + 1
        j_last = int(math.floor(theta_new / step))
        j_first = max(j_first, j_last - capacity + 1)
        for j in range(j_first, j_last + 1):
            _write(history, j, theta_old, theta_coef, value_old, value_coef, (j * step - theta_old) / span,
                   deepest)
    elif span < 0.0:  # θ_new ≤ φ_j < θ_old, crossed from the top down
        j_first = int(math.ceil(theta_old / step)) - 1
        j_last = int(math.ceil(theta_new / step))
        j_last = max(j_last, j_first - capacity + 1)
        for j in range(j_first, j_last - 1, -1):
            _write(history, j, theta_old, theta_coef, value_old, value_coef, (j * step - theta_old) / span,
                   deepest)


@njit(cache=True)
def _bin_value(history, j):
    slot = j & (history.bins.shape[0] - 1)
    if history.bins[slot] == float(j):
        return history.values[slot]
    meta = history.meta
    return meta[_REF_VALUE] + meta[_SLOPE] * (j * meta[_STEP] - meta[_REF_ANGLE])


@njit(cache=True)
def lookup(history, angle):
    """The value at ``angle`` [rad]: cubic Lagrange interpolation over the four bins around it, each from
    the record or, where unrecorded, from the prehistory line."""
    x = angle / history.meta[_STEP]
    i = int(math.floor(x))
    t = x - i
    tm1, tm2, tp1 = t - 1.0, t - 2.0, t + 1.0
    return (-t * tm1 * tm2 / 6.0 * _bin_value(history, i - 1)
            + tp1 * tm1 * tm2 / 2.0 * _bin_value(history, i)
            - tp1 * t * tm2 / 2.0 * _bin_value(history, i + 1)
            + tp1 * t * tm1 / 6.0 * _bin_value(history, i + 2))


@njit(cache=True)
def delayed_difference(history, angle, value):
    """``value − lookup(history, angle − Δ)``: with the bit's axial position as value [m] and its angle
    [rad], the depth of cut per blade ``d_n = u(t) − u(t − t_n)``."""
    return value - lookup(history, angle - history.meta[_LAG])
