"""Tests of the angle-indexed history (dynamics/delay.py): recording and reading back known profiles,
the prehistory, the ring buffer, backward rotation, interpolation order, and delay differential equations
with known solutions solved with the project's Runge–Kutta stepper (constant delay by the method of steps;
a state-dependent delay against an independent reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.polynomial import Polynomial
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from drillstring.dynamics.delay import (
    UNWRITTEN,
    AngleHistory,
    delayed_difference,
    lookup,
    record_bottom,
    record_step,
    start,
)
from drillstring.dynamics.runge_kutta import DORMAND_PRINCE_54, RungeKuttaStepper, StepSizeController, integrate

P = 4  # terms of the dense polynomials (Dormand–Prince)


def in_s(poly: Polynomial, t0: float, h: float) -> tuple[float, np.ndarray]:
    """``poly(t0 + s·h) = value_old + Σ_p coef[p] s^(p+1)``: (value_old, coef padded to P)."""
    c = poly(Polynomial([t0, h])).coef
    coef = np.zeros(P)
    coef[: len(c) - 1] = c[1:]
    return float(c[0]), coef


def record_polynomials(history, theta: Polynomial, value: Polynomial, times: np.ndarray) -> None:
    """Record the steps ``[times[i], times[i+1]]`` of θ(t) and value(t) given as polynomials in t."""
    for t0, t1 in zip(times[:-1], times[1:]):
        th0, thc = in_s(theta, t0, t1 - t0)
        v0, vc = in_s(value, t0, t1 - t0)
        record_step(history, th0, thc, v0, vc)


def test_allocate_and_validation():
    h = AngleHistory.allocate(0.5, bins_per_lag=100)
    assert h.values.shape == h.bins.shape == (512,)  # power of two >= 400
    assert h.bins.dtype == np.float64 and np.all(h.bins == UNWRITTEN)
    assert h.lag == 0.5 and h.bin_angle == pytest.approx(0.005, rel=1e-15)
    assert AngleHistory.allocate(1.0).values.shape == (8192,)
    with pytest.raises(ValueError, match=r"lag = -1\.0 rad: must be finite and > 0"):
        AngleHistory.allocate(-1.0)
    with pytest.raises(ValueError, match="bins_per_lag = 2.5: must be an integer >= 4"):
        AngleHistory.allocate(1.0, 2.5)


def test_prehistory_where_nothing_is_written():
    h = AngleHistory.allocate(2 * math.pi / 4, bins_per_lag=64)
    start(h, 0.3, 2.0, 0.5)
    for a in (-7.3, -0.01, 0.0, 0.3, 1.234567, 55.0):
        assert lookup(h, a) == pytest.approx(2.0 + 0.5 * (a - 0.3), abs=1e-13)
    # the helical bottom of steady drilling: depth of cut d per blade on every lag
    d = 4.17e-3
    start(h, 0.0, -1.0, d / h.lag)
    assert delayed_difference(h, 3.0, lookup(h, 3.0)) == pytest.approx(d, rel=1e-12)


def test_cubic_profile_recorded_and_read_back_exactly_over_many_sectors():
    """θ = Ω t and a cubic of the angle: the record finds every crossing exactly and cubic interpolation
    reproduces a cubic, so lookups are exact to round-off; the ring buffer (4 lags here) wraps ~10 times
    and the slots overwritten are recognised (the prehistory is read there)."""
    lag, bins = 1.0, 64
    h = AngleHistory.allocate(lag, bins)
    start(h, -2.0, 7.0, 0.0)
    omega = 3.0
    theta = Polynomial([-2.0, omega])  # from angle −2 (negative bins) up to 40
    g = Polynomial([0.2, -0.3, 0.05, 0.01])  # value as a cubic of the angle
    rng = np.random.default_rng(1)
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(0.001, 0.05, 2000))])
    times = times[times <= 14.0]
    record_polynomials(h, theta, g(theta), times)
    theta_end = theta(times[-1])
    capacity_angle = h.values.shape[0] * h.bin_angle
    assert theta_end - (-2.0) > 10 * capacity_angle - 4 * lag
    a = np.linspace(theta_end - capacity_angle + 2 * h.bin_angle, theta_end - 2 * h.bin_angle, 1001)
    got = np.array([lookup(h, x) for x in a])
    np.testing.assert_allclose(got, g(a), rtol=0, atol=1e-12 * np.abs(g(a)).max())
    # angles older than the buffer: overwritten slots are recognised -> prehistory
    old = np.linspace(-1.5, theta_end - capacity_angle - 3 * h.bin_angle, 50)
    np.testing.assert_allclose([lookup(h, x) for x in old], 7.0, rtol=0, atol=1e-14)
    # ahead of the record: prehistory
    assert lookup(h, theta_end + 3 * h.bin_angle) == pytest.approx(7.0, abs=1e-14)


def test_nonlinear_angle_crossings_found_by_newton():
    """θ(t) = t + t²/4 over long steps: the bin values equal the value at the exact crossing time
    t_j = 2(√(1 + φ_j) − 1), which a linear guess in s would miss by O(step²)."""
    h = AngleHistory.allocate(1.0, 32)
    theta = Polynomial([0.0, 1.0, 0.25])
    value = Polynomial([0.0, -1.0, 0.0, 1.0])
    record_polynomials(h, theta, value, np.arange(0.0, 2.41, 0.3))  # θ from 0 to 3.84
    j = np.arange(1, int(3.84 / h.bin_angle))
    phi = j * h.bin_angle
    exact = value(2.0 * (np.sqrt(1.0 + phi) - 1.0))
    slots = j & (h.bins.shape[0] - 1)
    np.testing.assert_array_equal(h.bins[slots], j)
    np.testing.assert_allclose(h.values[slots], exact, rtol=0, atol=1e-14)
    np.testing.assert_allclose([lookup(h, x) for x in phi], exact, rtol=0, atol=1e-13)
    # the linear guess alone would be far off: the test can tell
    t_j = 2.0 * (np.sqrt(1.0 + phi) - 1.0)
    t0 = np.floor(t_j / 0.3 + 1e-12) * 0.3
    s_linear = (phi - theta(t0)) / (theta(t0 + 0.3) - theta(t0))
    assert np.abs(value(t0 + 0.3 * s_linear) - exact).max() > 1e-3


def test_backward_rotation_latest_crossing_wins_and_negative_angles():
    h = AngleHistory.allocate(1.0, 64)
    start(h, 0.0, 100.0, 0.0)
    d = h.bin_angle
    # forward from −2 to 2 with value 1 + φ; backward from 2 to 0.5 with value 5 − φ (a lifted bit);
    # forward again from 0.5 to 1.5 with value −φ²
    fwd = Polynomial([-2.0, 1.0])
    record_polynomials(h, fwd, 1.0 + fwd, np.linspace(0.0, 4.0, 41))
    back = Polynomial([2.0, -1.0])
    record_polynomials(h, back, 5.0 - back, np.linspace(0.0, 1.5, 16))
    a = np.linspace(-2.0 + 2 * d, 0.5 - 2 * d, 50)
    np.testing.assert_allclose([lookup(h, x) for x in a], 1.0 + a, rtol=0, atol=1e-13)
    a = np.linspace(0.5 + 2 * d, 2.0 - 2 * d, 50)
    np.testing.assert_allclose([lookup(h, x) for x in a], 5.0 - a, rtol=0, atol=1e-13)
    fwd2 = Polynomial([0.5, 1.0])
    record_polynomials(h, fwd2, -(fwd2**2), np.linspace(0.0, 1.0, 7))
    a = np.linspace(0.5 + 2 * d, 1.5 - 2 * d, 50)
    np.testing.assert_allclose([lookup(h, x) for x in a], -(a**2), rtol=0, atol=1e-13)
    a = np.linspace(1.5 + 2 * d, 2.0 - 2 * d, 20)
    np.testing.assert_allclose([lookup(h, x) for x in a], 5.0 - a, rtol=0, atol=1e-13)
    # every bin between −2 and 2 written exactly once per crossing, by its own index
    j = np.arange(int(round(-2.0 / d)) + 1, int(round(2.0 / d)) + 1)
    np.testing.assert_array_equal(h.bins[j & (h.bins.shape[0] - 1)], j)
    assert lookup(h, 2.0 + 3 * d) == pytest.approx(100.0, abs=1e-13)
    assert lookup(h, -2.0 - 3 * d) == pytest.approx(100.0, abs=1e-13)


def record_sine(history, k: float, theta_end: float, step: float = 1e-3) -> None:
    """Steps of θ linear over [0, theta_end] with sin(kθ) as the value: its quartic Taylor polynomial on
    each step (error (k·step)^5/120, far below the interpolation error measured)."""
    for t0 in np.arange(0.0, theta_end, step):
        derivs = np.array([math.sin(k * t0), math.cos(k * t0), -math.sin(k * t0), -math.cos(k * t0),
                           math.sin(k * t0)]) * k ** np.arange(5)
        coef = derivs[1:] * step ** np.arange(1, 5) / np.array([1, 2, 6, 24])
        record_step(history, t0, np.array([step, 0.0, 0.0, 0.0]), derivs[0], coef)


def test_exact_bins_and_interpolation_order_four():
    k, errors, steps = 3.0, [], []
    for bins in (16, 32, 64, 128):
        h = AngleHistory.allocate(1.0, bins)
        record_sine(h, k, 2.0)
        d = h.bin_angle
        j = np.arange(bins // 4, 7 * bins // 4)
        at_bins = np.array([lookup(h, x * d) for x in j])
        np.testing.assert_allclose(at_bins, np.sin(k * j * d), rtol=0, atol=1e-13)  # the bins themselves
        mid = (j + 0.5) * d
        err = np.abs([lookup(h, x) - math.sin(k * x) for x in mid]).max()
        # cubic Lagrange at the midpoint: |f''''| δφ⁴ · (1.5·0.5·0.5·1.5)/24
        assert err <= k**4 * d**4 * 0.5625 / 24 * 1.01
        errors.append(err)
        steps.append(d)
    orders = np.diff(np.log(errors)) / np.diff(np.log(steps))
    print(f"sin(3φ), midpoint errors at 16, 32, 64, 128 bins per lag: {', '.join(f'{e:.2e}' for e in errors)};"
          f" observed orders {', '.join(f'{o:.3f}' for o in orders)}")
    assert np.all((orders > 3.8) & (orders < 4.2)), orders


# ---------------------------------------------------------------------------------------------------------
# delay differential equations
# ---------------------------------------------------------------------------------------------------------


def method_of_steps(n_pieces: int) -> list[Polynomial]:
    """Exact solution of x'(t) = −x(t − 1), x = 1 for t ≤ 0: piece k on [k, k+1] as a polynomial in t,
    x_k(t) = x_{k−1}(k) − ∫_k^t x_{k−1}(s − 1) ds."""
    pieces, prev = [], Polynomial([1.0])
    for k in range(n_pieces):
        integral = prev(Polynomial([-1.0, 1.0])).integ()
        piece = prev(float(k)) - (integral - integral(float(k)))
        pieces.append(piece)
        prev = piece
    return pieces


def test_method_of_steps_pieces():
    x = method_of_steps(3)
    t = Polynomial([0.0, 1.0])
    assert np.allclose(x[0].coef, (1 - t).coef)
    assert np.allclose(x[1].coef, (1 - t + (t - 1) ** 2 / 2).coef)
    assert np.allclose(x[2].coef, (-0.5 + (t - 2) ** 2 / 2 - (t - 2) ** 3 / 6).coef)
    assert x[2](3.0) == pytest.approx(-1.0 / 6.0, abs=1e-15)


def solve_delay(theta_rate, t_end: float, *, rtol: float, first_step: float | None = None,
                bins_per_lag: int = 2048, breakpoints=(), check=None):
    """x' = −x at the angle θ − 1, θ' = theta_rate(t), x = 1 at every angle ≤ 0 (state [x, θ]), with the
    history recorded after each accepted step from the stepper's dense polynomial. The integration
    restarts at the ``breakpoints`` (the times where θ passes a multiple of the lag: there the solution's
    derivatives jump, which an embedded error estimate does not see). Returns the last stepper, the
    history and the counts of accepted and rejected steps."""
    history = AngleHistory.allocate(1.0, bins_per_lag)
    start(history, 0.0, 1.0, 0.0)

    def rhs(t, y):
        return np.array([-lookup(history, y[1] - 1.0), theta_rate(t)])

    y, n_accepted, n_rejected = np.array([1.0, 0.0]), 0, 0
    ends = [b for b in breakpoints if 0.0 < b < t_end] + [t_end]
    for t0, t1 in zip([0.0] + ends[:-1], ends):
        ctrl = StepSizeController(rtol=rtol, atol=rtol, max_step=0.5)
        stepper = RungeKuttaStepper(rhs, t0, y, DORMAND_PRINCE_54, ctrl, first_step, t_bound=t1)
        while not stepper.finished:
            before = (history.values.copy(), history.bins.copy(),
                      stepper.dense_polynomial() if stepper.n_accepted else None)
            if stepper.step():
                t_old, h, y_old, coef = stepper.dense_polynomial()
                record_step(history, y_old[1], coef[:, 1], y_old[0], coef[:, 0])
                if check is not None:
                    check(stepper)
            else:
                # a rejected attempt changes neither the history nor the accepted step's dense output
                np.testing.assert_array_equal(history.values, before[0])
                np.testing.assert_array_equal(history.bins, before[1])
                if before[2] is not None:
                    for a, b in zip(before[2], stepper.dense_polynomial()):
                        np.testing.assert_array_equal(a, b)
        y = stepper.y
        n_accepted += stepper.n_accepted
        n_rejected += stepper.n_rejected
    return stepper, history, n_accepted, n_rejected


def test_constant_delay_against_the_method_of_steps():
    """With restarts at the breakpoints t = 1, 2 the error is that of the integration tolerance; without,
    the steps across the breakpoints carry an error the step control does not see (printed, bounded)."""
    x = method_of_steps(3)
    for breakpoints, bound in (((1.0, 2.0), 1e-9), ((), 1e-7)):
        errors = []

        def check(stepper):
            k = min(int(stepper.t), 2)
            errors.append((stepper.t, abs(stepper.y[0] - x[k](stepper.t))))

        stepper, history, n_acc, n_rej = solve_delay(lambda t: 1.0, 3.0, rtol=1e-9, breakpoints=breakpoints,
                                                     check=check)
        assert stepper.t == 3.0 and stepper.y[1] == pytest.approx(3.0, abs=1e-13)
        err = np.array(errors)
        err_end = abs(stepper.y[0] - (-1.0 / 6.0))
        per_piece = [err[(err[:, 0] > k) & (err[:, 0] <= k + 1), 1].max() for k in range(3)]
        print(f"constant delay, rtol=atol=1e-9, breakpoints {breakpoints}: {n_acc} steps ({n_rej} rejected), "
              f"max error on [0,1], [1,2], [2,3]: {', '.join(f'{e:.2e}' for e in per_piece)}; "
              f"at t = 3: {err_end:.2e}")
        assert err_end < bound and max(per_piece) < bound
        # the recorded history is the solution as a function of angle (= time here)
        a = np.linspace(0.01, 2.99, 200)
        exact = np.array([x[min(int(v), 2)](v) for v in a])
        assert np.abs([lookup(history, v) for v in a] - exact).max() < bound


def reference_state_dependent(theta_end: float):
    """The state-dependent case θ' = 1 + sin(t)/2, x'(t) = −x at angle θ(t) − 1, rewritten with θ as the
    independent variable: a constant-delay problem dX/dθ = −X(θ − 1)/(1 + sin t/2), dt/dθ = 1/(1 + sin
    t/2), solved piece by piece on [k, k + 1] (method of steps) with SciPy's DOP853 at rtol 1e-13."""
    prev = lambda phi: 1.0  # noqa: E731  the prehistory
    t0, x0, k = 0.0, 1.0, 0
    pieces = []
    while True:
        lo, hi = float(k), min(float(k + 1), theta_end)

        def f(phi, z, prev=prev):
            rate = 1.0 + 0.5 * math.sin(z[0])
            return [1.0 / rate, -prev(phi - 1.0) / rate]

        sol = solve_ivp(f, (lo, hi), [t0, x0], method="DOP853", rtol=1e-13, atol=1e-14, dense_output=True)
        t0, x0 = sol.y[:, -1]
        pieces.append(sol.sol)
        if hi == theta_end:
            return t0, x0, lambda phi: pieces[min(int(phi), k)](phi)[1]
        prev = lambda phi, s=sol.sol: s(phi)[1]  # noqa: E731
        k += 1


def theta_rate(t):
    return 1.0 + 0.5 * math.sin(t)


def theta_times(k_max: int) -> list[float]:
    """Times where θ(t) = t + (1 − cos t)/2 passes 1, …, k_max (the breakpoints)."""
    return [brentq(lambda t, k=k: t + 0.5 * (1.0 - math.cos(t)) - k, 0.0, float(k)) for k in range(1, k_max + 1)]


def test_state_dependent_delay_against_an_independent_reference():
    theta_end = 3.0
    t_end, x_ref, _ = reference_state_dependent(theta_end)
    for breakpoints, bound in ((theta_times(2), 1e-9), ((), 1e-7)):
        stepper, _, n_acc, n_rej = solve_delay(theta_rate, t_end, rtol=1e-9, breakpoints=breakpoints)
        assert stepper.y[1] == pytest.approx(theta_end, abs=1e-9)
        err = abs(stepper.y[0] - x_ref)
        print(f"state-dependent delay, rtol=atol=1e-9, breakpoints {np.round(breakpoints, 6)}: t_end = "
              f"{t_end:.6f}, x = {x_ref:.12f}, {n_acc} steps ({n_rej} rejected), error {err:.2e}")
        assert err < bound


def test_rejected_steps_leave_no_trace():
    """Runs with rejected steps: every rejected attempt leaves the history and the accepted step's dense
    output bit-identical (checked inside solve_delay); a first step of 0.5 (many rejections) and one of
    1e-4 give the same history to the tolerance, and both the reference solution."""
    breakpoints = theta_times(2)
    t_end, x_ref, x_of_theta = reference_state_dependent(3.0)
    big, hist_a, _, rej_a = solve_delay(theta_rate, t_end, rtol=1e-9, first_step=0.5, breakpoints=breakpoints)
    small, hist_b, _, rej_b = solve_delay(theta_rate, t_end, rtol=1e-9, first_step=1e-4,
                                          breakpoints=breakpoints)
    np.testing.assert_array_equal(hist_a.bins, hist_b.bins)  # the same bins written
    written = hist_a.bins != UNWRITTEN
    exact = np.array([x_of_theta(j * hist_a.bin_angle) for j in hist_a.bins[written]])
    error_a = np.abs(hist_a.values[written] - exact).max()
    error_b = np.abs(hist_b.values[written] - exact).max()
    print(f"rejected steps: {rej_a} (first step 0.5), {rej_b} (first step 1e-4); errors at the end "
          f"{abs(big.y[0] - x_ref):.2e}, {abs(small.y[0] - x_ref):.2e}; largest error of a bin {error_a:.2e}, "
          f"{error_b:.2e}")
    assert rej_a > 0
    assert abs(big.y[0] - x_ref) < 1e-8 and abs(small.y[0] - x_ref) < 1e-8
    assert error_a < 3e-8 and error_b < 3e-8


def test_integrate_on_dense_step_records_the_history():
    """The driver's hook gives the accepted steps only (one call per accepted step, rejections present);
    recording from it solves the constant-delay problem."""
    history = AngleHistory.allocate(1.0, 2048)
    start(history, 0.0, 1.0, 0.0)
    calls = []

    def record(t_old, h, y_old, coef):
        calls.append(t_old)
        record_step(history, y_old[1], coef[:, 1], y_old[0], coef[:, 0])

    t_end, x_ref, _ = reference_state_dependent(2.5)
    sol = integrate(lambda t, y: np.array([-lookup(history, y[1] - 1.0), theta_rate(t)]), (0.0, t_end),
                    [1.0, 0.0], rtol=1e-9, atol=1e-9, max_step=0.5, on_dense_step=record)
    assert sol.n_rejected > 0 and len(calls) == sol.n_accepted
    assert abs(sol.y[-1, 0] - x_ref) < 1e-7


def test_the_hole_bottom_keeps_the_rock_where_the_bit_passes_above_it():
    """record_bottom: a bit passing above the bottom the previous blade left (smaller u: x points down) leaves
    that bottom in place — the flat prehistory while it is lowered, the last cut after a bounce —, and a bit
    cutting below it records its own position (then the law's d_n = u(t) − u(t − t_n)). record_step keeps
    the bit's path whatever it is."""
    lag = 1.0
    bottom, path = AngleHistory.allocate(lag, 64), AngleHistory.allocate(lag, 64)
    for h in (bottom, path):
        start(h, 0.0, 1.0, 0.0)  # the rock's flat surface at u = 1

    def advance(history, record, theta0, u0, du):  # the angle up by 0.5, u linear from u0 by du
        record(history, theta0, np.array([0.5, 0.0, 0.0, 0.0]), u0, np.array([du, 0.0, 0.0, 0.0]))

    advance(bottom, record_bottom, 0.0, 0.5, 0.0)  # lowered, 0.5 above the rock, over half a sector
    advance(path, record_step, 0.0, 0.5, 0.0)
    probe = [0.1, 0.3, 0.45]
    np.testing.assert_allclose([lookup(bottom, x) for x in probe], 1.0, atol=1e-14)  # the rock is still there
    np.testing.assert_allclose([lookup(path, x) for x in probe], 0.5, atol=1e-14)  # the path is where it went
    advance(bottom, record_bottom, 0.5, 0.5, 1.5)  # lands at θ = 2/3 (u = 1) and cuts down to u = 2 at θ = 1
    theta = np.array([0.55, 0.6, 0.75, 0.9, 0.98])
    expected = np.maximum(0.5 + 3.0 * (theta - 0.5), 1.0)  # above the rock: the rock; below it: the cut
    np.testing.assert_allclose([lookup(bottom, x) for x in theta], expected, atol=1e-12)
    advance(bottom, record_bottom, 1.0, 2.0, -1.5)  # bounces up over the next half sector (u from 2 to 0.5)
    theta = np.array([1.1, 1.25, 1.4, 1.48])  # one lag back (θ − 1 in [0, 0.5]) the rock was untouched, at 1
    np.testing.assert_allclose([lookup(bottom, x) for x in theta], np.maximum(2.0 - 3.0 * (theta - 1.0), 1.0),
                               atol=1e-12)
