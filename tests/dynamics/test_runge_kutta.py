"""Tests of the embedded Runge–Kutta integrator (SPEC §7): tableaus, order conditions, dense output,
step-size control, driver output grid, failure handling."""

from __future__ import annotations

import math
import re
from functools import lru_cache

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from drillstring.dynamics.runge_kutta import (
    BOGACKI_SHAMPINE_32,
    DORMAND_PRINCE_54,
    TABLEAUS,
    ButcherTableau,
    IntegrationError,
    RungeKuttaStepper,
    Solution,
    StepSizeController,
    integrate,
)

# ---------------------------------------------------------------------------------------------------------
# test problems with exact solutions
# ---------------------------------------------------------------------------------------------------------


def decay(t, y):
    return -y


def oscillator(t, y):
    return np.array([y[1], -y[0]])


def tan_rhs(t, y):
    return 1.0 + y * y


PROBLEMS = {
    # name: (rhs, y0, t_end, exact(t) -> (n_t, n))
    "decay": (decay, np.array([1.0]), 5.0, lambda t: np.exp(-np.atleast_1d(t))[:, None]),
    "oscillator": (oscillator, np.array([1.0, 0.0]), 20.0,
                   lambda t: np.stack([np.cos(np.atleast_1d(t)), -np.sin(np.atleast_1d(t))], axis=1)),
    "tan": (tan_rhs, np.array([0.0]), 1.4, lambda t: np.tan(np.atleast_1d(t))[:, None]),
}


# ---------------------------------------------------------------------------------------------------------
# rooted trees and elementary weights (Butcher; HNW I §II.2)
# ---------------------------------------------------------------------------------------------------------


@lru_cache(maxsize=None)
def trees(order: int) -> tuple[tuple, ...]:
    """All rooted trees with ``order`` vertices, a tree being the sorted tuple of its children."""
    if order == 1:
        return ((),)
    out = set()

    def forests(n: int, max_child: tuple | None) -> list[tuple]:
        # multisets of trees with n vertices in total, children in non-increasing canonical order
        if n == 0:
            return [()]
        res = []
        for m in range(1, n + 1):
            for child in trees(m):
                key = (m, child)
                if max_child is not None and key > max_child:
                    continue
                for rest in forests(n - m, key):
                    res.append(((m, child),) + rest)
        return res

    for f in forests(order - 1, None):
        out.add(tuple(child for _, child in f))
    return tuple(sorted(out, key=repr))


def tree_order(t: tuple) -> int:
    return 1 + sum(tree_order(ch) for ch in t)


def gamma(t: tuple) -> int:
    return tree_order(t) * math.prod(gamma(ch) for ch in t)


def stage_weights(a: np.ndarray, t: tuple) -> np.ndarray:
    """Φ_i(t): product over the children of (A Φ(child))_i."""
    phi = np.ones(a.shape[0])
    for ch in t:
        phi = phi * (a @ stage_weights(a, ch))
    return phi


def test_tree_counts():
    assert [len(trees(q)) for q in range(1, 6)] == [1, 1, 2, 4, 9]


def order_defect(tab: ButcherTableau, weights: np.ndarray, q: int) -> float:
    return max(abs(weights @ stage_weights(tab.a, t) - 1.0 / gamma(t)) for t in trees(q))


@pytest.mark.parametrize("tab", [DORMAND_PRINCE_54, BOGACKI_SHAMPINE_32], ids=lambda t: t.name)
def test_tableau_order_conditions(tab):
    for q in range(1, tab.order + 1):
        assert order_defect(tab, tab.b, q) < 1e-14, q
    assert order_defect(tab, tab.b, tab.order + 1) > 1e-6  # exactly of that order
    for q in range(1, tab.error_order + 1):
        assert order_defect(tab, tab.b_hat, q) < 1e-14, q
    assert order_defect(tab, tab.b_hat, tab.error_order + 1) > 1e-6
    assert tab.fsal
    assert TABLEAUS[tab.name] is tab


def test_dopri5_dense_output_conditions():
    """Continuous extension of order 4 (HNW I §II.6): Σ b_i(θ) Φ_i(τ) = θ^ρ(τ)/γ(τ) for ρ(τ) ≤ 4, all θ;
    b(0) = 0, b(1) = b, b'(0) = e_1, b'(1) = e_7 (C¹ through the FSAL stage)."""
    tab = DORMAND_PRINCE_54
    d = tab.dense
    assert d.shape == (7, 4)
    np.testing.assert_array_equal(d[1], 0.0)
    for theta in np.linspace(0.0, 1.0, 11):
        w = tab.dense_weights(theta)
        for q in range(1, 5):
            for t in trees(q):
                assert abs(w @ stage_weights(tab.a, t) - theta**q / gamma(t)) < 1e-13, (theta, q)
    np.testing.assert_allclose(tab.dense_weights(1.0), tab.b, atol=1e-14)
    np.testing.assert_allclose(tab.dense_weights(0.0), 0.0, atol=0)
    deriv = lambda th: d @ (np.arange(1, 5) * th ** np.arange(0, 4))  # noqa: E731
    np.testing.assert_allclose(deriv(0.0), np.eye(7)[0], atol=1e-14)
    np.testing.assert_allclose(deriv(1.0), np.eye(7)[6], atol=1e-13)
    # not of order 5 (so the test above is not vacuous about which order it is)
    w = tab.dense_weights(0.5)
    assert max(abs(w @ stage_weights(tab.a, t) - 0.5**5 / gamma(t)) for t in trees(5)) > 1e-6


def test_tableau_validation():
    good = BOGACKI_SHAMPINE_32
    kw = dict(name="x", c=good.c, a=good.a, b=good.b, b_hat=good.b_hat, order=3, error_order=2, fsal=True)
    ButcherTableau(**kw)
    with pytest.raises(ValueError, match="row sums"):
        ButcherTableau(**{**kw, "c": [0.0, 0.5, 0.7, 1.0]})
    upper = np.array(good.a)
    upper[0, 1] = 0.1
    with pytest.raises(ValueError, match="lower triangular"):
        ButcherTableau(**{**kw, "a": upper})
    with pytest.raises(ValueError, match="sum to 1"):
        ButcherTableau(**{**kw, "b": np.array(good.b) * 1.1})
    with pytest.raises(ValueError, match="FSAL"):
        ButcherTableau(**{**kw, "b": good.b_hat, "b_hat": good.b})
    with pytest.raises(ValueError, match="dense"):
        ButcherTableau(**{**kw, "dense": np.ones((4, 3))})
    # frozen and read-only
    with pytest.raises(AttributeError):
        good.order = 4  # type: ignore[misc]
    with pytest.raises(ValueError):
        good.b[0] = 1.0


# ---------------------------------------------------------------------------------------------------------
# accuracy against exact solutions
# ---------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["dopri5", "bs32"])
@pytest.mark.parametrize("name", list(PROBLEMS))
def test_exact_solutions(name, method):
    rhs, y0, t_end, exact = PROBLEMS[name]
    rtol = 1e-6 if method == "dopri5" else 1e-5
    sol = integrate(rhs, (0.0, t_end), y0, output_step=t_end / 50, tableau=method, rtol=rtol, atol=1e-10)
    assert isinstance(sol, Solution) and sol.status == "success"
    assert sol.t.shape == (51,) and sol.y.shape == (51, y0.size)
    ref = exact(sol.t)
    # global error: a few tolerances times the solution scale (it accumulates over the steps)
    scale = np.maximum(np.abs(ref), 1.0)
    err = np.max(np.abs(sol.y - ref) / scale)
    assert err < 30 * rtol, err
    assert sol.n_accepted > 0 and sol.n_rhs > sol.n_accepted and sol.wall_time >= 0
    assert sol.stats["n_steps"] == sol.n_accepted + sol.n_rejected


@pytest.mark.parametrize("name", list(PROBLEMS))
def test_error_decreases_with_rtol(name):
    rhs, y0, t_end, exact = PROBLEMS[name]
    errs = []
    for rtol in (1e-3, 1e-5, 1e-7, 1e-9):
        sol = integrate(rhs, (0.0, t_end), y0, t_out=[0.0, t_end], rtol=rtol, atol=rtol * 1e-3)
        errs.append(np.max(np.abs(sol.y[-1] - exact(t_end)[0])))
    assert all(e2 < e1 for e1, e2 in zip(errs, errs[1:])), errs
    assert errs[-1] < 1e-4 * errs[0]


def _observed_order(hs, errs):
    return np.polyfit(np.log(hs), np.log(errs), 1)[0]


def logistic(t, y):
    return y * (1.0 - y)


CONVERGENCE_PROBLEMS = {
    # linear and nonlinear; the end times are multiples of all step sizes below
    "oscillator": (oscillator, np.array([1.0, 0.0]), 2.0, lambda t: np.array([np.cos(t), -np.sin(t)])),
    "logistic": (logistic, np.array([0.1]), 10.0, lambda t: np.array([1.0 / (1.0 + 9.0 * np.exp(-t))])),
}


@pytest.mark.parametrize("tab", [DORMAND_PRINCE_54, BOGACKI_SHAMPINE_32], ids=lambda t: t.name)
@pytest.mark.parametrize("name", list(CONVERGENCE_PROBLEMS))
def test_fixed_step_convergence_order(tab, name):
    """Controller off: the global error at t_end falls like h^order (slope within ±0.2). Step sizes are
    chosen in the asymptotic range, above round-off."""
    rhs, y0, t_end, exact = CONVERGENCE_PROBLEMS[name]
    hs = np.array([0.4, 0.2, 0.1, 0.05]) if tab.order >= 5 else np.array([0.1, 0.05, 0.025, 0.0125])
    errs = []
    for h in hs:
        sol = integrate(rhs, (0.0, t_end), y0, t_out=[t_end], fixed_step=h, tableau=tab)
        assert sol.n_accepted == round(t_end / h) and sol.n_rejected == 0
        assert sol.n_rhs == 1 + (tab.n_stages - 1) * sol.n_accepted  # FSAL
        errs.append(np.max(np.abs(sol.y[-1] - exact(t_end))))
    p = _observed_order(hs, errs)
    assert abs(p - tab.order) < 0.2, (p, errs)


def test_bs32_dense_output_is_the_cubic_hermite_interpolant_of_order_3():
    """BS32's continuous extension: order conditions up to ρ(τ) = 3 for every θ (not 4), b(0) = 0,
    b(1) = b, b'(0) = e_1, b'(1) = e_4 (C¹ through the FSAL stage), and it reproduces the cubic Hermite
    interpolant of (y, f) at both ends of a step to round-off."""
    tab = BOGACKI_SHAMPINE_32
    d = tab.dense
    assert d.shape == (4, 3)
    for theta in np.linspace(0.0, 1.0, 11):
        w = tab.dense_weights(theta)
        for q in range(1, 4):
            for t in trees(q):
                assert abs(w @ stage_weights(tab.a, t) - theta**q / gamma(t)) < 1e-14, (theta, q)
    w = tab.dense_weights(0.5)
    assert max(abs(w @ stage_weights(tab.a, t) - 0.5**4 / gamma(t)) for t in trees(4)) > 1e-6
    np.testing.assert_allclose(tab.dense_weights(1.0), tab.b, atol=1e-15)
    deriv = lambda th: d @ (np.arange(1, 4) * th ** np.arange(0, 3))  # noqa: E731
    np.testing.assert_allclose(deriv(0.0), np.eye(4)[0], atol=1e-15)
    np.testing.assert_allclose(deriv(1.0), np.eye(4)[3], atol=1e-14)
    hermite = ButcherTableau("bs32-hermite", tab.c, tab.a, tab.b, tab.b_hat, 3, 2, fsal=True, dense=None)
    steppers = [RungeKuttaStepper(van_der_pol, 0.1, [2.0, -0.5], t, None, h0=0.3) for t in (tab, hermite)]
    for st in steppers:
        assert st.step()
    times = 0.1 + 0.3 * np.linspace(0.0, 1.0, 7)
    np.testing.assert_allclose(steppers[0].interpolate(times), steppers[1].interpolate(times),
                               rtol=1e-14, atol=1e-14)


#: Order p* of each method's continuous extension.
DENSE_ORDER = {"dopri5": 4, "bs32": 3}


@pytest.mark.parametrize("tab", [DORMAND_PRINCE_54, BOGACKI_SHAMPINE_32], ids=lambda t: t.name)
def test_dense_output_local_order(tab):
    """One step of size h from (0.3, tan 0.3); interpolant error at θ = 1/2 is O(h^(p*+1)), p* = 4 for
    the DOPRI5 continuous extension, 3 for the cubic Hermite one of BS32."""
    t0 = 0.3
    hs = np.array([0.2, 0.1, 0.05, 0.025])
    errs = []
    for h in hs:
        st = RungeKuttaStepper(tan_rhs, t0, [math.tan(t0)], tab, None, h0=h)
        assert st.step() is True
        tm = t0 + 0.5 * h
        errs.append(abs(st.interpolate(tm)[0] - math.tan(tm)))
        # the interpolant reproduces the step's end points
        np.testing.assert_allclose(st.interpolate(t0), [math.tan(t0)], rtol=0, atol=1e-15)
        np.testing.assert_allclose(st.interpolate(st.t), st.y, rtol=1e-14, atol=1e-15)
    assert _observed_order(hs, errs) > DENSE_ORDER[tab.name] + 1 - 0.2, errs


def test_dense_output_global_accuracy_between_steps():
    """Output on a fine grid (many points per step) is as accurate as the steps themselves."""
    rhs, y0, t_end, exact = PROBLEMS["oscillator"]
    sol = integrate(rhs, (0.0, t_end), y0, output_step=0.01, rtol=1e-8, atol=1e-12)
    assert sol.t.size == 2001 and sol.n_accepted < 400  # many output points per step
    assert np.max(np.abs(sol.y - exact(sol.t))) < 1e-6


# ---------------------------------------------------------------------------------------------------------
# comparison with SciPy's RK45 (same method, same tolerances)
# ---------------------------------------------------------------------------------------------------------


def van_der_pol(t, y):
    return np.array([y[1], 5.0 * (1.0 - y[0] ** 2) * y[1] - y[0]])


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
@pytest.mark.parametrize("case", ["oscillator", "tan", "vdp"])
def test_work_comparable_to_scipy_rk45(case, rtol):
    if case == "vdp":
        rhs, y0, t_end = van_der_pol, np.array([2.0, 0.0]), 20.0
    else:
        rhs, y0, t_end, _ = PROBLEMS[case]
    atol = rtol * 1e-3
    ours = integrate(rhs, (0.0, t_end), y0, rtol=rtol, atol=atol)
    ref = solve_ivp(rhs, (0.0, t_end), y0, method="RK45", rtol=rtol, atol=atol)
    n_ref = ref.t.size - 1
    assert ours.n_accepted / n_ref < 1.5 and n_ref / ours.n_accepted < 1.5, (ours.n_accepted, n_ref)
    assert ours.n_rhs / ref.nfev < 1.5 and ref.nfev / ours.n_rhs < 1.5, (ours.n_rhs, ref.nfev)
    # and without output grid every accepted step is an output
    assert ours.t.size == ours.n_accepted + 1 and ours.t[-1] == t_end


# ---------------------------------------------------------------------------------------------------------
# output grid, observe, progress, direction
# ---------------------------------------------------------------------------------------------------------


def test_output_grid_includes_end_exactly():
    rhs, y0, _, exact = PROBLEMS["decay"]
    sol = integrate(rhs, (0.0, 1.0), y0, output_step=0.1)
    assert sol.t.size == 11 and sol.t[-1] == 1.0
    np.testing.assert_allclose(sol.t, np.linspace(0, 1, 11), rtol=0, atol=1e-15)
    sol = integrate(rhs, (0.0, 1.0), y0, output_step=0.3)  # not a multiple: end appended
    np.testing.assert_allclose(sol.t[:-1], [0.0, 0.3, 0.6, 0.9], atol=1e-15)
    assert sol.t[-1] == 1.0
    np.testing.assert_allclose(sol.y, exact(sol.t), rtol=1e-5)
    t_out = np.array([0.0, 0.123, 0.5, 0.77, 1.0])
    sol = integrate(rhs, (0.0, 1.0), y0, t_out=t_out, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(sol.t, t_out)
    np.testing.assert_allclose(sol.y, exact(t_out), rtol=1e-8)
    # output starting after t0
    sol = integrate(rhs, (0.0, 1.0), y0, t_out=[0.5, 1.0])
    np.testing.assert_array_equal(sol.t, [0.5, 1.0])
    with pytest.raises(ValueError):
        integrate(rhs, (0.0, 1.0), y0, t_out=[0.5, 1.5])
    with pytest.raises(ValueError):
        integrate(rhs, (0.0, 1.0), y0, t_out=[0.5, 0.2])


def test_backward_integration():
    sol = integrate(decay, (1.0, 0.0), [math.exp(-1.0)], output_step=0.25, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sol.t, [1.0, 0.75, 0.5, 0.25, 0.0], atol=1e-15)
    np.testing.assert_allclose(sol.y[:, 0], np.exp(-sol.t), rtol=1e-8)


def test_observe_stores_mapped_state():
    rhs, y0, t_end, exact = PROBLEMS["oscillator"]
    energy = integrate(rhs, (0.0, t_end), y0, output_step=0.5, rtol=1e-9, atol=1e-12,
                       observe=lambda t, y: 0.5 * (y[0] ** 2 + y[1] ** 2))
    assert energy.y.shape == (41, 1)
    np.testing.assert_allclose(energy.y[:, 0], 0.5, rtol=1e-7)
    both = integrate(rhs, (0.0, t_end), y0, output_step=0.5, rtol=1e-9, atol=1e-12,
                     observe=lambda t, y: np.array([t, y[0]]))
    np.testing.assert_allclose(both.y[:, 0], both.t, rtol=0, atol=1e-14)
    np.testing.assert_allclose(both.y[:, 1], np.cos(both.t), atol=1e-7)


def test_progress_callback():
    calls = []
    integrate(oscillator, (0.0, 100.0), [1.0, 0.0], output_step=1.0, rtol=1e-10, atol=1e-12,
              progress=calls.append)
    assert calls[0] == 0.0 and calls[-1] == 100.0
    assert np.all(np.diff(calls) > 0)
    assert len(calls) <= 203
    assert np.all(np.diff(calls)[:-1] >= 0.5 - 1e-12)  # at most every 0.5 % of the span


def test_tableau_by_name_and_unknown():
    sol = integrate(decay, (0.0, 1.0), [1.0], tableau="bs32", t_out=[1.0])
    assert sol.y[0, 0] == pytest.approx(math.exp(-1.0), rel=1e-5)
    with pytest.raises(ValueError, match="unknown tableau"):
        integrate(decay, (0.0, 1.0), [1.0], tableau="rk4")


def test_array_atol_and_max_step():
    """An array atol weighs each component by its own tolerance. Two copies of y' = −y, the second with an
    atol so large that its error never counts: the RMS of the error ratios is that of the first copy divided
    by √2, i.e. the problem alone with rtol and atol both × √2, so the steps are the same (41). Reading the
    array wrongly gives other steps: its first entry for both copies 44, its largest 8. max_step bounds every
    step."""
    def decay(t, y):
        return -y

    rtol, atol = 1e-6, 1e-9
    pair = integrate(decay, (0.0, 10.0), [1.0, 1.0], rtol=rtol, atol=np.array([atol, 1e30]))
    alone = integrate(decay, (0.0, 10.0), [1.0], rtol=rtol * math.sqrt(2.0), atol=atol * math.sqrt(2.0))
    assert (pair.n_accepted, pair.n_rejected) == (alone.n_accepted, alone.n_rejected) == (41, 0)
    np.testing.assert_allclose(pair.t, alone.t, rtol=1e-8)  # the same steps, to the rounding of the √2 factors
    np.testing.assert_allclose(np.asarray(pair.y)[:, 0], np.asarray(alone.y)[:, 0], rtol=0, atol=1e-8)
    first = integrate(decay, (0.0, 10.0), [1.0, 1.0], rtol=rtol, atol=atol)
    largest = integrate(decay, (0.0, 10.0), [1.0, 1.0], rtol=rtol, atol=1e30)
    assert (first.n_accepted, largest.n_accepted) == (44, 8)
    sol = integrate(oscillator, (0.0, 10.0), [1.0, 0.0], atol=np.array([1e-9, 1e-9]), max_step=0.01)
    assert sol.n_accepted >= 1000 and np.all(np.diff(sol.t) <= 0.01 * (1 + 1e-12))


# ---------------------------------------------------------------------------------------------------------
# stepper and controller
# ---------------------------------------------------------------------------------------------------------


def test_stepper_api_and_counters():
    ctrl = StepSizeController(rtol=1e-6, atol=1e-9)
    st = RungeKuttaStepper(oscillator, 0.0, [1.0, 0.0], DORMAND_PRINCE_54, ctrl)
    assert st.n_rhs == 2  # f(t0, y0) and the initial-step probe
    assert st.h > 0 and st.f.shape == (2,)
    attempts = 0
    while st.t < 5.0:
        accepted = st.step()
        attempts += 1
        assert isinstance(accepted, bool)
    assert st.n_accepted + st.n_rejected == attempts
    assert st.n_rhs == 2 + 6 * attempts  # FSAL: six new stages per attempt
    np.testing.assert_allclose(st.y, [math.cos(st.t), -math.sin(st.t)], atol=1e-5)
    np.testing.assert_allclose(st.f, oscillator(st.t, st.y), rtol=1e-14)
    tm = st.t_old + 0.3 * st.h_last
    np.testing.assert_allclose(st.interpolate(tm), [math.cos(tm), -math.sin(tm)], atol=1e-5)
    assert st.interpolate(np.array([st.t_old, tm, st.t])).shape == (3, 2)
    with pytest.raises(ValueError):
        st.interpolate(st.t + 10 * abs(st.h_last))


def test_stepper_lands_on_t_bound():
    st = RungeKuttaStepper(decay, 0.0, [1.0], DORMAND_PRINCE_54, StepSizeController(), t_bound=0.77)
    while not st.finished:
        st.step()
    assert st.t == 0.77
    with pytest.raises(RuntimeError):
        st.step()


def test_controller_behaviour():
    c = StepSizeController(rtol=1e-3, atol=1e-6)
    y = np.array([1.0, -2.0])
    y_new = np.array([3.0, 0.0])
    err = np.array([1e-3, 2e-3])
    sc = 1e-6 + 1e-3 * np.array([3.0, 2.0])
    assert c.error_norm(y, y_new, err) == pytest.approx(np.sqrt(np.mean((err / sc) ** 2)))
    ok, h = c.accept(0.0, 0.1, 4)
    assert ok and h == pytest.approx(1.0)  # max_factor
    c.reset()
    ok, h = c.accept(0.5, 0.1, 4)  # fresh controller: previous error taken as 1
    assert ok and h == pytest.approx(0.1 * 0.9 * 0.5 ** (-c.beta1 / 5))
    ok, h = c.accept(0.5, 0.1, 4)  # PI: the previous error enters with exponent beta2/k
    assert ok and h == pytest.approx(0.1 * 0.9 * 0.5 ** (-c.beta1 / 5) * 0.5 ** (c.beta2 / 5))
    ok, h = c.accept(1e6, 0.1, 4)
    assert not ok and h == pytest.approx(0.02)  # min_factor
    ok, h = c.accept(1e-8, 0.1, 4)
    assert ok and h <= 0.1  # no growth right after a rejection
    ok, h = c.accept(math.nan, 0.1, 4)
    assert not ok and h == pytest.approx(0.02)
    ok, h = c.accept(1e-3, -0.1, 4)
    assert h < 0  # sign kept
    c2 = StepSizeController(max_step=0.05)
    assert c2.accept(1e-3, 0.04, 4)[1] == 0.05
    h0 = StepSizeController(rtol=1e-6, atol=1e-9).initial_step(oscillator, 0.0, np.array([1.0, 0.0]),
                                                               np.array([0.0, -1.0]), 4)
    assert 1e-4 < h0 < 1.0
    with pytest.raises(ValueError):
        StepSizeController(rtol=0.0, atol=0.0)


# ---------------------------------------------------------------------------------------------------------
# failures: non-finite values, step size floor, max_steps
# ---------------------------------------------------------------------------------------------------------


def test_nonfinite_stage_is_a_rejection_and_recovers():
    """The rhs is undefined (NaN) for y < 0; a huge first step overshoots into that region, the step is
    rejected and the integration goes on."""

    def rhs(t, y):
        return np.where(y >= 0, -y, np.nan)

    sol = integrate(rhs, (0.0, 3.0), [1.0], first_step=50.0, t_out=[3.0], rtol=1e-8, atol=1e-12)
    assert sol.status == "success" and sol.n_rejected >= 1
    assert sol.y[-1, 0] == pytest.approx(math.exp(-3.0), rel=1e-6)

    def rhs_raises(t, y):
        if y[0] < 0.5:
            raise FloatingPointError("overflow in model")
        return -y

    sol = integrate(rhs_raises, (0.0, 0.5), [1.0], first_step=2.0, t_out=[0.5])
    assert sol.status == "success" and sol.n_rejected >= 1


def _nan_after_one(t, y):
    return -y if t <= 1.0 else np.full_like(y, np.nan)


def test_nan_rhs_raises_with_time_and_keeps_outputs():
    with pytest.raises(IntegrationError) as info:
        integrate(_nan_after_one, (0.0, 3.0), [1.0], output_step=0.1, rtol=1e-8, atol=1e-12)
    exc = info.value
    msg = str(exc)
    m = re.search(r"t = ([0-9.eE+-]+) s", msg)
    assert m and float(m.group(1)) == pytest.approx(1.0, abs=1e-6), msg
    assert "h = " in msg and "NaN" in msg and "min_step" in msg
    sol = exc.solution
    assert isinstance(sol, Solution) and sol.status == "failed" and sol.message == msg
    assert sol.t.size >= 10 and sol.t[-1] <= 1.0
    np.testing.assert_allclose(sol.t[:10], np.arange(10) * 0.1, atol=1e-15)
    np.testing.assert_allclose(sol.y[:, 0], np.exp(-sol.t), rtol=1e-7)
    # without raising: the same partial solution is returned
    sol2 = integrate(_nan_after_one, (0.0, 3.0), [1.0], output_step=0.1, rtol=1e-8, atol=1e-12,
                     raise_on_failure=False)
    assert sol2.status == "failed" and not sol2.success
    np.testing.assert_array_equal(sol2.t, sol.t)


def test_nan_at_initial_state():
    with pytest.raises(IntegrationError, match="initial state") as info:
        integrate(lambda t, y: y * np.nan, (0.0, 1.0), [1.0], output_step=0.5)
    assert info.value.solution.t.size == 1  # the initial output point


def test_nonfinite_in_fixed_step_raises():
    with pytest.raises(IntegrationError, match="NaN"):
        integrate(_nan_after_one, (0.0, 3.0), [1.0], fixed_step=0.1)


def test_stiff_problem_hits_min_step():
    """y' = −10⁴ (y − cos t): an explicit method needs h ≲ 3·10⁻⁴ for stability."""

    def stiff(t, y):
        return -1e4 * (y - np.cos(t))

    with pytest.raises(IntegrationError) as info:
        integrate(stiff, (0.0, 1.0), [0.0], min_step=1e-3, output_step=0.1)
    msg = str(info.value)
    assert "min_step" in msg and re.search(r"h = [0-9.e+-]+ s", msg), msg
    assert info.value.solution.status == "failed"
    # with the default floor it is merely slow, and correct
    sol = integrate(stiff, (0.0, 1.0), [0.0], t_out=[1.0], rtol=1e-6, atol=1e-9)
    assert sol.y[-1, 0] == pytest.approx(math.cos(1.0), rel=1e-3)


def test_max_steps_exceeded():
    with pytest.raises(IntegrationError, match="max_steps") as info:
        integrate(oscillator, (0.0, 100.0), [1.0, 0.0], output_step=1.0, max_steps=50)
    sol = info.value.solution
    assert sol.n_accepted + sol.n_rejected == 50
    assert 0 < sol.t.size < 101 and sol.status == "failed"


def test_overflowing_problem_fails_cleanly():
    """Blow-up of y' = y² at t = 1: no hang, no crash, a clear error at the singularity."""
    with pytest.raises(IntegrationError) as info:
        integrate(lambda t, y: y * y, (0.0, 2.0), [1.0], output_step=0.1)
    sol = info.value.solution
    assert sol.t[-1] <= 1.0 + 1e-6 and np.all(np.isfinite(sol.y))
    np.testing.assert_allclose(sol.y[:-1, 0], 1.0 / (1.0 - sol.t[:-1]), rtol=1e-5)
    m = re.search(r"t = ([0-9.eE+-]+) s", str(info.value))
    assert m and float(m.group(1)) == pytest.approx(1.0, abs=1e-2)


@pytest.mark.parametrize("tab", [DORMAND_PRINCE_54, BOGACKI_SHAMPINE_32], ids=lambda t: t.name)
def test_dense_polynomial_equals_interpolate(tab):
    ctrl = StepSizeController(rtol=1e-6, atol=1e-9)
    stepper = RungeKuttaStepper(van_der_pol, 0.0, [2.0, 0.0], tab, ctrl, h0=0.05)
    with pytest.raises(RuntimeError, match="no accepted step"):
        stepper.dense_polynomial()
    while stepper.n_accepted < 5:
        stepper.step()
    t_old, h, y_old, coef = stepper.dense_polynomial()
    assert coef.shape == (tab.dense.shape[1], 2)
    assert t_old == stepper.t_old and t_old + h == pytest.approx(stepper.t, abs=1e-15)
    s = np.linspace(0.0, 1.0, 7)
    poly = y_old + (s[:, None] ** np.arange(1, coef.shape[0] + 1)) @ coef
    np.testing.assert_allclose(poly, stepper.interpolate(t_old + s * h), rtol=0, atol=1e-14)
    np.testing.assert_allclose(poly[-1], stepper.y, rtol=0, atol=1e-14)


def test_dense_polynomial_needs_dense_coefficients():
    tab = BOGACKI_SHAMPINE_32
    hermite = ButcherTableau("bs32-hermite", tab.c, tab.a, tab.b, tab.b_hat, 3, 2, fsal=True, dense=None)
    stepper = RungeKuttaStepper(decay, 0.0, [1.0], hermite, None, h0=0.1)
    stepper.step()
    with pytest.raises(ValueError, match="bs32-hermite has no dense-output coefficients"):
        stepper.dense_polynomial()
    with pytest.raises(ValueError, match="on_dense_step needs a tableau with dense output"):
        integrate(decay, (0.0, 1.0), [1.0], tableau=hermite, on_dense_step=lambda *a: None)


def test_on_dense_step_sees_accepted_steps_only():
    steps = []
    sol = integrate(van_der_pol, (0.0, 2.0), [2.0, 0.0], rtol=1e-8, first_step=1.0,
                    on_dense_step=lambda t_old, h, y_old, coef: steps.append((t_old, h, y_old, coef)))
    assert sol.n_rejected > 0 and len(steps) == sol.n_accepted
    ends = [t_old + h for t_old, h, _, _ in steps]
    assert steps[0][0] == 0.0 and ends[-1] == pytest.approx(2.0, abs=1e-14)
    np.testing.assert_allclose([t for t, *_ in steps[1:]], ends[:-1], rtol=0, atol=1e-14)  # contiguous
    # each polynomial ends where the next begins: accepted states only
    for (_, _, y0, c0), (_, _, y1, _) in zip(steps[:-1], steps[1:]):
        np.testing.assert_allclose(y0 + c0.sum(axis=0), y1, rtol=0, atol=1e-13)
