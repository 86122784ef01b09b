"""Tests of the string–borehole contact forces (SPEC §6)."""

import math

import numpy as np
import pytest
from numba import njit

from drillstring.forces.contact import (
    ContactParameters,
    contact_forces,
    evaluate_contact,
    radial_gap,
    regularized_sign,
)

K_SH = 1e8
MU = 0.0005
EPS = 1e-2
D_O = 0.2286
GAP = float(radial_gap(0.3, D_O))
P = ContactParameters(K_SH, MU, EPS)
PT = ContactParameters(K_SH, MU, EPS, tangential_friction=True)


def one_node(v, w, vd=0.0, wd=0.0, spin=10.0, params=P, gap=GAP):
    fv, fw, t, n = evaluate_contact([v], [w], [vd], [wd], [spin], gap, D_O, params)
    return fv[0], fw[0], t[0], n


def test_radial_gap():
    assert GAP == pytest.approx(0.0357)


def test_no_force_inside_gap_and_at_gap():
    for params in (P, PT):
        for r in (0.0, 0.5 * GAP, GAP):
            for ang in np.linspace(0.0, 2 * np.pi, 7):
                fv, fw, t, n = one_node(r * math.cos(ang), r * math.sin(ang), 0.3, -0.2, 10.0, params)
                assert (fv, fw, t, n) == (0.0, 0.0, 0.0, 0)
    fv, fw, t, n = one_node(GAP, 0.0)  # exactly r = g
    assert (fv, fw, t, n) == (0.0, 0.0, 0.0, 0)


@pytest.mark.parametrize("ang", np.linspace(-np.pi, np.pi, 9))
def test_restoring_force_magnitude_and_direction(ang):
    delta = 1e-4
    r = GAP + delta
    v, w = r * math.cos(ang), r * math.sin(ang)
    fv, fw, _, n = one_node(v, w)
    assert n == 1
    assert math.hypot(fv, fw) == pytest.approx(K_SH * delta, rel=1e-9)
    # antiparallel to the position (points to the centre)
    assert (fv * v + fw * w) / (math.hypot(fv, fw) * r) == pytest.approx(-1.0, abs=1e-12)
    assert fv * w - fw * v == pytest.approx(0.0, abs=1e-9 * K_SH * delta * r)


def test_torque_opposes_rotation_and_magnitude():
    delta = 2e-4
    f_n = K_SH * delta
    for spin in (10.0, -10.0, 1e3 * EPS, -1e3 * EPS):
        _, _, t, _ = one_node(GAP + delta, 0.0, spin=spin)
        assert t * spin < 0.0
        assert abs(t) == pytest.approx(MU * f_n * D_O / 2, rel=1e-6)


def test_regularised_sign_continuous_through_zero():
    delta = 2e-4
    spins = np.linspace(-5 * EPS, 5 * EPS, 2001)
    n = spins.size
    fv, fw, t, nc = evaluate_contact(np.full(n, GAP + delta), np.zeros(n), 0.0, 0.0, spins, GAP, D_O, P)
    assert nc == n
    assert t[n // 2] == 0.0  # spins[1000] == 0
    assert np.all(np.abs(np.diff(t)) < 1e-2 * MU * K_SH * delta * D_O / 2)
    assert np.all(np.diff(t) < 0.0)  # monotone: sgn_eps increasing, torque = −(...)·sgn
    assert regularized_sign(0.0, EPS) == 0.0
    assert regularized_sign(EPS, EPS) == pytest.approx(1 / math.sqrt(2))
    assert regularized_sign(-3.0, EPS) == -regularized_sign(3.0, EPS)
    assert regularized_sign(0.0, 0.0) == 0.0


@pytest.mark.parametrize(
    "ang, vd, wd, spin",
    [(0.3, 0.0, 0.0, 10.0), (2.0, 0.05, -0.4, 10.0), (-1.0, 1.0, 2.0, -3.0), (4.0, -3.0, 0.5, 0.0)],
)
def test_tangential_force_perpendicular_and_opposes_slip(ang, vd, wd, spin):
    delta = 1e-4
    r = GAP + delta
    v, w = r * math.cos(ang), r * math.sin(ang)
    fv0, fw0, t0, _ = one_node(v, w, vd, wd, spin, P)
    fv1, fw1, t1, _ = one_node(v, w, vd, wd, spin, PT)
    assert t1 == t0  # the torque is the SPEC's, unchanged by the option
    ftv, ftw = fv1 - fv0, fw1 - fw0
    nv, nw = v / r, w / r
    assert ftv * nv + ftw * nw == pytest.approx(0.0, abs=1e-9 * K_SH * delta)
    tv, tw = -nw, nv
    slip = spin * D_O / 2 + (v * wd - w * vd) / r
    ft = ftv * tv + ftw * tw
    assert ft * slip < 0.0
    s_reg = slip / math.hypot(slip, EPS * D_O / 2)
    assert ft == pytest.approx(-MU * K_SH * delta * s_reg, rel=1e-9)


def test_tangential_force_zero_slip():
    # whirl cancelling the spin surface speed: pure rolling, no tangential force
    r = GAP + 1e-4
    spin = 10.0
    wd = -spin * D_O / 2  # at (r, 0): slip = spin R + ẇ
    fv0, fw0, _, _ = one_node(r, 0.0, 0.0, wd, spin, P)
    fv1, fw1, _, _ = one_node(r, 0.0, 0.0, wd, spin, PT)
    assert fw1 - fw0 == pytest.approx(0.0, abs=1e-12)
    assert fv1 == fv0


def test_normal_force_is_gradient_of_potential():
    def potential(v, w):
        r = math.hypot(v, w)
        return 0.5 * K_SH * max(r - GAP, 0.0) ** 2

    h = 1e-8
    for v, w in [(0.037, 0.001), (-0.02, 0.031), (0.0, -0.0365), (0.03, -0.03)]:
        fv, fw, _, _ = one_node(v, w)
        dv = (potential(v + h, w) - potential(v - h, w)) / (2 * h)
        dw = (potential(v, w + h) - potential(v, w - h)) / (2 * h)
        scale = K_SH * (math.hypot(v, w) - GAP)
        assert fv == pytest.approx(-dv, abs=1e-6 * scale)
        assert fw == pytest.approx(-dw, abs=1e-6 * scale)


def test_counts_and_multinode_kernel_in_place():
    rng = np.random.default_rng(1)
    n = 50
    gap = np.where(np.arange(n) < 25, GAP, radial_gap(0.3, 0.127))
    dia = np.where(np.arange(n) < 25, D_O, 0.127)
    r = gap * rng.uniform(0.5, 1.5, n)
    ang = rng.uniform(0, 2 * np.pi, n)
    v, w = r * np.cos(ang), r * np.sin(ang)
    vd, wd, spin = rng.normal(size=n), rng.normal(size=n), rng.normal(10.0, 3.0, n)
    fv = np.full(n, np.nan)
    fw = np.full(n, np.nan)
    tq = np.full(n, np.nan)
    nc = contact_forces(v, w, vd, wd, spin, gap, dia, K_SH, MU, EPS, True, fv, fw, tq)
    assert nc == int(np.sum(r > gap))
    assert np.all(np.isfinite(fv)) and np.all(np.isfinite(fw)) and np.all(np.isfinite(tq))
    assert np.all(fv[r <= gap] == 0.0) and np.all(tq[r <= gap] == 0.0)
    for i in range(n):
        fvi, fwi, ti, _ = evaluate_contact(v[i], w[i], vd[i], wd[i], spin[i], gap[i], dia[i], PT)
        assert (fv[i], fw[i], tq[i]) == (fvi[0], fwi[0], ti[0])


@njit
def _call_many(times, v, w, vd, wd, spin, gap, dia, fv, fw, tq):
    n = 0
    for _ in range(times):
        n = contact_forces(v, w, vd, wd, spin, gap, dia, K_SH, MU, EPS, True, fv, fw, tq)
    return n


def test_repeated_calls_reuse_outputs_without_allocation():
    n = 200
    rng = np.random.default_rng(2)
    v = rng.normal(0.0, 0.03, n)
    w = rng.normal(0.0, 0.03, n)
    vd, wd, spin = rng.normal(size=n), rng.normal(size=n), rng.normal(10.0, 3.0, n)
    gap = np.full(n, GAP)
    dia = np.full(n, D_O)
    fv, fw, tq = np.empty(n), np.empty(n), np.empty(n)
    ids = (id(fv), id(fw), id(tq))
    arrays = (v, w, vd, wd, spin, gap, dia, fv, fw, tq)
    n0 = contact_forces(v, w, vd, wd, spin, gap, dia, K_SH, MU, EPS, True, fv, fw, tq)
    ref = (fv.copy(), fw.copy(), tq.copy())
    assert _call_many(1, *arrays) == n0  # compile

    # Numba's allocation counters: the kernel must not allocate inside a jitted loop. (Stats must be on
    # before they are read; a Numba without this API fails here, loudly, rather than skipping the check.)
    from numba.core.runtime import _nrt_python, rtsys

    _nrt_python.memsys_enable_stats()
    s0 = rtsys.get_allocation_stats()
    _call_many(1, *arrays)
    s1 = rtsys.get_allocation_stats()
    _call_many(1000, *arrays)
    s2 = rtsys.get_allocation_stats()
    # only the boxing of the array arguments at the Python boundary allocates, independent of the count
    assert s2.alloc - s1.alloc == s1.alloc - s0.alloc
    assert s2.alloc - s2.free == s0.alloc - s0.free  # nothing leaked
    for _ in range(100):
        assert contact_forces(v, w, vd, wd, spin, gap, dia, K_SH, MU, EPS, True, fv, fw, tq) == n0
    assert (id(fv), id(fw), id(tq)) == ids
    for a, b in zip((fv, fw, tq), ref):
        np.testing.assert_array_equal(a, b)


def test_parameter_validation_and_wrapper_checks():
    with pytest.raises(ValueError):
        ContactParameters(-1.0, MU, EPS)
    with pytest.raises(ValueError):
        ContactParameters(K_SH, MU, float("nan"))
    with pytest.raises(ValueError):
        evaluate_contact([0.0], [0.0], 0.0, 0.0, 0.0, -0.01, D_O, P)
    with pytest.raises(ValueError):
        evaluate_contact(np.zeros((2, 2)), 0.0, 0.0, 0.0, 0.0, GAP, D_O, P)
