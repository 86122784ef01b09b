"""Tests of the string–borehole contact forces (SPEC §6)."""

import math

import numpy as np
import pytest
from numba import njit

from drillstring.forces.contact import (
    ContactParameters,
    case_contact,
    contact_forces,
    contact_jacobian,
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


def _station_law_by_hand(v, w, v_dot, w_dot, spin, gap, outer_diameter, k, mu, eps, tangential):
    """docs/model.md §5 written out in plain NumPy, independently of the kernels (which compute it once per
    station in ``_station_contact``): ``F_n = k (r − g)₊`` along −n, ``T = −μ F_n (D_o/2) sgn_ε(θ̇x)``, and
    with ``tangential`` ``F_t = −μ F_n sgn_{εR}(s)`` along ``t = (−w, v)/r``, ``s = θ̇x D_o/2 + (v ẇ − w v̇)/r``."""
    v, w, v_dot, w_dot, spin, gap, outer_diameter, k = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (v, w, v_dot, w_dot, spin, gap, outer_diameter, k)))
    r = np.sqrt(v**2 + w**2)
    normal = np.where(r > gap, k * (r - gap), 0.0)
    radius = outer_diameter / 2
    r_safe = np.where(r > 0.0, r, 1.0)
    force_v = -normal * v / r_safe
    force_w = -normal * w / r_safe
    torque = -mu * normal * radius * spin / np.sqrt(spin**2 + eps**2)
    if tangential:
        slip = spin * radius + (v * w_dot - w * v_dot) / r_safe
        f_t = -mu * normal * slip / np.sqrt(slip**2 + (eps * radius) ** 2)
        force_v = force_v + f_t * (-w / r_safe)
        force_w = force_w + f_t * (v / r_safe)
    return force_v, force_w, torque


@pytest.mark.parametrize("params", [P, PT, ContactParameters(K_SH, 0.3, 0.5, tangential_friction=True)],
                         ids=["normal_and_torque", "tangential", "rough"])
def test_component_kernel_is_the_law_as_written(params):
    """The component's compiled kernel (its numbers, the named context, one stiffness per station) and
    ``evaluate_at`` against the law written out by hand, at stations inside and outside their gap, spinning
    either way and whirling."""
    from drillstring.forces.contact import penalty_contact_kernel
    from drillstring.forces.registry import ContactContext

    rng = np.random.default_rng(6)
    n = 60
    gap = rng.uniform(0.02, 0.05, n)
    r = gap * rng.uniform(0.5, 1.3, n)
    ang = rng.uniform(-np.pi, np.pi, n)
    ctx = ContactContext(r * np.cos(ang), r * np.sin(ang), rng.normal(0.0, 0.5, n), rng.normal(0.0, 0.5, n),
                         rng.normal(0.0, 10.0, n), gap, rng.uniform(0.1, 0.25, n), rng.uniform(1e7, 1e9, n))
    expected = _station_law_by_hand(*ctx, params.friction_coefficient, params.speed_regularization,
                                    params.tangential_friction)
    assert 10 < np.count_nonzero(expected[0]) < n - 10  # both inside and outside the gap
    out = [np.full(n, np.nan) for _ in range(3)]
    penalty_contact_kernel(params.kernel_array(), ctx, *out)
    for got, by_evaluate_at, want in zip(out, params.evaluate_at(ctx), expected):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
        np.testing.assert_array_equal(by_evaluate_at, got)


def test_friction_dissipates_mu_normal_force_over_each_sliding_path():
    """The work of the wall on a station pressed δ into it: over one revolution of a spin Ω without whirl, the
    torque does ``−μ k δ (D_o/2) sgn_ε(Ω) · 2π``; over one forward whirl of its centre round the wall at
    ``r = g + δ`` without spin, the tangential force does ``−μ k δ sgn_{εR}(r φ̇) · 2π r`` and the normal force
    none (it is perpendicular to the path). Integrated over the cycle from the kernel's forces."""
    delta, whirl, spin = 2e-3, 3.0, 7.0
    r = GAP + delta
    normal = K_SH * delta
    # a revolution of the spin: the torque's power T Ω over 2π/Ω
    _, _, torque, _ = one_node(r, 0.0, spin=spin, params=PT)
    assert torque * spin * (2 * np.pi / spin) == pytest.approx(
        -MU * normal * D_O / 2 * 2 * np.pi * spin / math.hypot(spin, EPS), rel=1e-12)
    # a whirl of the centre: ∮ F · dc, the centre at r (cos φ, sin φ), velocity r φ̇ (−sin φ, cos φ)
    phi = np.linspace(0.0, 2 * np.pi, 721)
    v, w = r * np.cos(phi), r * np.sin(phi)
    vd, wd = -r * whirl * np.sin(phi), r * whirl * np.cos(phi)
    radius = D_O / 2
    expected = -MU * normal * 2 * np.pi * r * (r * whirl) / math.hypot(r * whirl, EPS * radius)
    for params, work in ((PT, expected), (P, 0.0)):
        fv, fw, _, touching = evaluate_contact(v, w, vd, wd, 0.0, GAP, D_O, params)
        assert touching == phi.size
        power = fv * vd + fw * wd
        assert np.trapezoid(power, phi / whirl) == pytest.approx(work, abs=1e-9 * abs(expected))
    # a backward whirl dissipates as much: the force turns with the path
    fv, fw, _, _ = evaluate_contact(v, -w, vd, -wd, 0.0, GAP, D_O, PT)
    assert np.trapezoid(fv * vd - fw * wd, phi / whirl) == pytest.approx(expected, rel=1e-12)


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
    expected = _station_law_by_hand(v, w, vd, wd, spin, gap, dia, K_SH, MU, EPS, True)
    for got, want in zip((fv, fw, tq), expected):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=0.0)


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


# --- distributed wall stiffness: contact stations by nodal quadrature (issue 10) -------------------------

from scipy.integrate import quad  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

from drillstring.forces.contact import (  # noqa: E402
    contact_stations, distributed_contact_forces, mesh_contact_stations,
)

K_PER_LENGTH = 1e8  # N/m per m of string (the reference value, read as distributed)
D_PIPE, D_COLLAR, D_HOLE = 0.127, 0.2286, 0.3


def two_section_nodes(h_pipe, h_collar, l_pipe=100.0, l_collar=60.0):
    """Nodes of a pipe-over-collar string (exact node at the change) and each element's diameter."""
    pipe = np.linspace(0.0, l_pipe, max(1, math.ceil(l_pipe / h_pipe)) + 1)
    collar = np.linspace(l_pipe, l_pipe + l_collar, max(1, math.ceil(l_collar / h_collar)) + 1)[1:]
    nodes = np.concatenate([pipe, collar])
    diameter = np.where(0.5 * (nodes[:-1] + nodes[1:]) < l_pipe, D_PIPE, D_COLLAR)
    return nodes, diameter


def station_forces(stations, v_nodes, w_nodes, spin=10.0, params=P):
    n = len(stations)
    v, w = stations.gather(v_nodes), stations.gather(w_nodes)
    return evaluate_contact(v, w, np.zeros(n), np.zeros(n), np.full(n, spin), stations.gap,
                            stations.outer_diameter, params, stiffness=stations.stiffness(K_PER_LENGTH))


def test_stations_split_tributary_lengths_at_section_changes():
    nodes, diameter = two_section_nodes(7.0, 3.0)
    st = contact_stations(nodes, diameter, D_HOLE)
    assert st.length.sum() == pytest.approx(160.0, rel=1e-14)
    change = int(np.argmin(np.abs(nodes - 100.0)))
    at_change = st.node == change
    assert at_change.sum() == 2  # one station per section
    np.testing.assert_allclose(sorted(st.length[at_change]), sorted([1.5, (nodes[change] - nodes[change - 1]) / 2]))
    np.testing.assert_allclose(sorted(st.gap[at_change]), sorted(radial_gap(D_HOLE, [D_PIPE, D_COLLAR])))
    assert np.all(np.diff(st.node) >= 0) and st.node[0] == 0 and st.node[-1] == len(nodes) - 1
    assert st.length[0] == pytest.approx((nodes[1] - nodes[0]) / 2)  # the end nodes get half an element
    np.testing.assert_allclose(st.stiffness(K_PER_LENGTH), K_PER_LENGTH * st.length)
    # Per-node sums of station values.
    np.testing.assert_allclose(st.scatter(st.length, len(nodes)).sum(), 160.0)
    with pytest.raises(ValueError, match="stiffness_per_length"):
        st.stiffness(-1.0)
    with pytest.raises(ValueError):
        contact_stations(nodes, diameter[:-1], D_HOLE)


@pytest.mark.parametrize("h", [(20.0, 20.0), (10.0, 7.0), (3.3, 1.1), (1.0, 0.25)])
def test_uniform_penetration_gives_the_same_total_force_on_any_mesh(h):
    """The whole string offset so that only the collar (smaller gap) penetrates by δ: total force
    k' δ L_collar, torque μ k' δ L_collar D/2, whatever the mesh (nodal quadrature is exact); the
    per-node law instead scales with the number of collar nodes."""
    nodes, diameter = two_section_nodes(*h)
    st = contact_stations(nodes, diameter, D_HOLE)
    delta = 2e-3
    r = float(radial_gap(D_HOLE, D_COLLAR)) + delta
    angle = 0.7
    v, w = np.full(len(nodes), r * math.cos(angle)), np.full(len(nodes), r * math.sin(angle))
    fv, fw, tq, touching = station_forces(st, v, w)
    expected = K_PER_LENGTH * delta * 60.0
    assert math.hypot(fv.sum(), fw.sum()) == pytest.approx(expected, rel=1e-12)
    assert -tq.sum() == pytest.approx(MU * expected * D_COLLAR / 2 * 10.0 / math.hypot(10.0, EPS), rel=1e-12)
    assert touching == np.sum(st.gap < r)
    per_node = evaluate_contact(v, w, 0.0, 0.0, 10.0, radial_gap(D_HOLE, np.append(diameter, D_COLLAR)),
                                np.append(diameter, D_COLLAR), ContactParameters(K_PER_LENGTH, MU, EPS))
    assert math.hypot(per_node[0].sum(), per_node[1].sum()) == pytest.approx(
        K_PER_LENGTH * delta * np.sum(nodes > 100.0 - 1e-9), rel=1e-12)


def _bow(x, length=160.0):
    """An asymmetric bow [m] that touches the collar wall over part of its length."""
    return 0.05 * np.sin(np.pi * x / length) * (0.6 + 0.8 * x / length)


def _exact_resultants(gap_pipe, gap_collar, length=160.0, l_pipe=100.0):
    """∫ k'(r − g)₊ dx and ∫ x k'(r − g)₊ dx by adaptive quadrature between the contact edges."""
    force = moment = 0.0
    for a, b, g in ((0.0, l_pipe, gap_pipe), (l_pipe, length, gap_collar)):
        xs = np.linspace(a, b, 2001)
        d = _bow(xs) - g
        edges = [a] + [brentq(lambda x: _bow(x) - g, xs[i], xs[i + 1], xtol=1e-13)
                       for i in np.nonzero(np.sign(d[:-1]) != np.sign(d[1:]))[0]] + [b]
        for lo, hi in zip(edges[:-1], edges[1:]):
            if _bow(0.5 * (lo + hi)) > g:
                force += quad(lambda x: K_PER_LENGTH * (_bow(x) - g), lo, hi, epsabs=0, epsrel=1e-13)[0]
                moment += quad(lambda x: K_PER_LENGTH * x * (_bow(x) - g), lo, hi, epsabs=0,
                               epsrel=1e-13)[0]
    return force, moment


def test_force_resultant_and_moment_converge_with_the_mesh():
    """A bow penetrating the collar wall over part of its length (one contact edge inside an element,
    wherever the mesh puts it): the resultant and its moment about the top converge at second order
    to the exact integrals. Trapezoidal rule on each element: the smooth part errs by at most
    h² ℓ_c max|F''|/12 and the element holding the contact edge (F has a kink there) by at most
    h² |F'(edge)|/8, F = k'(r − g) or k' x (r − g); the bound is checked on 25 meshes."""
    g_pipe, g_collar = float(radial_gap(D_HOLE, D_PIPE)), float(radial_gap(D_HOLE, D_COLLAR))
    exact_force, exact_moment = _exact_resultants(g_pipe, g_collar)
    assert exact_force > 0
    x = np.linspace(100.0, 160.0, 60001)
    inside = _bow(x) > g_collar
    contact_length = x[inside][-1] - 100.0
    bounds = []
    for weight, exact in ((np.ones_like(x), exact_force), (x, exact_moment)):
        f = K_PER_LENGTH * weight * (_bow(x) - g_collar)
        d1, d2 = np.gradient(f, x), np.gradient(np.gradient(f, x), x)
        bounds.append((contact_length * np.abs(d2[inside]).max() / 12 + np.abs(d1[inside]).max() / 8)
                      / exact)
    worst = 0.0
    for h in np.geomspace(0.1, 8.0, 25):
        nodes, diameter = two_section_nodes(h, h)
        h_collar = nodes[-1] - nodes[-2]
        st = contact_stations(nodes, diameter, D_HOLE)
        fv, fw, _, _ = station_forces(st, _bow(nodes), np.zeros(len(nodes)))
        errors = (abs(-fv.sum() / exact_force - 1), abs(-(fv * nodes[st.node]).sum() / exact_moment - 1))
        for error, bound in zip(errors, bounds):
            assert error <= bound * h_collar**2
            worst = max(worst, error / (bound * h_collar**2))
        if h <= 0.11:
            assert max(errors) < 1e-5
    assert worst > 0.05  # the bound is not loose by orders of magnitude


def test_distributed_kernel_equals_per_node_kernel_for_equal_stiffnesses():
    rng = np.random.default_rng(4)
    n = 40
    gap = np.full(n, GAP)
    dia = np.full(n, D_O)
    r = gap * rng.uniform(0.5, 1.5, n)
    ang = rng.uniform(0, 2 * np.pi, n)
    v, w = r * np.cos(ang), r * np.sin(ang)
    vd, wd, spin = rng.normal(size=n), rng.normal(size=n), rng.normal(10.0, 3.0, n)
    a = [np.empty(n) for _ in range(3)]
    b = [np.empty(n) for _ in range(3)]
    na = contact_forces(v, w, vd, wd, spin, gap, dia, K_SH, MU, EPS, True, *a)
    nb = distributed_contact_forces(v, w, vd, wd, spin, gap, dia, np.full(n, K_SH), MU, EPS, True, *b)
    assert na == nb == np.sum(r > gap)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
    # And a varying stiffness scales each station's force and torque.
    k = rng.uniform(1e6, 1e9, n)
    distributed_contact_forces(v, w, vd, wd, spin, gap, dia, k, MU, EPS, True, *b)
    np.testing.assert_allclose(b[0], a[0] * k / K_SH, rtol=1e-12, atol=0)
    np.testing.assert_allclose(b[2], a[2] * k / K_SH, rtol=1e-12, atol=0)


def test_station_forces_derive_from_the_potential():
    """F = −∇ Σ ½ k_i (r_i − g_i)₊² with k_i = k' ℓ_i (finite differences, μ = 0)."""
    nodes, diameter = two_section_nodes(10.0, 5.0)
    st = contact_stations(nodes, diameter, D_HOLE)
    k = st.stiffness(K_PER_LENGTH)
    params = ContactParameters(K_SH, 0.0, EPS)
    rng = np.random.default_rng(5)
    v = _bow(nodes) + rng.normal(0, 1e-3, len(nodes))
    w = rng.normal(0, 2e-2, len(nodes))

    def energy(vn, wn):
        r = np.hypot(st.gather(vn), st.gather(wn))
        return 0.5 * np.sum(k * np.maximum(r - st.gap, 0.0) ** 2)

    fv, fw, _, _ = station_forces(st, v, w, params=params)
    nodal_v, nodal_w = st.scatter(fv, len(nodes)), st.scatter(fw, len(nodes))
    step = 1e-7
    for i in np.nonzero(np.abs(nodal_v) > 0)[0][:5]:
        e = np.zeros(len(nodes))
        e[i] = step
        dv = (energy(v + e, w) - energy(v - e, w)) / (2 * step)
        dw = (energy(v, w + e) - energy(v, w - e)) / (2 * step)
        assert nodal_v[i] == pytest.approx(-dv, rel=1e-5)
        assert nodal_w[i] == pytest.approx(-dw, rel=1e-5, abs=1e-6 * abs(nodal_v[i]))


def test_mesh_stations_of_the_reference_case(reference_mesh):
    st = mesh_contact_stations(reference_mesh, 0.3)
    assert st.length.sum() == pytest.approx(1600.0)
    assert len(st) == reference_mesh.n_nodes + 1  # the drill pipe / drill collar node has two
    k = st.stiffness(1e8)
    assert k.max() == pytest.approx(1e9) and k[0] == pytest.approx(5e8)  # 10 m elements
    with pytest.raises(ValueError, match="stiffness must be finite"):
        evaluate_contact([0.0], [0.0], 0.0, 0.0, 0.0, GAP, D_O, P, stiffness=[-1.0])


@pytest.fixture
def reference_mesh(drill_pipe, drill_collar):
    from drillstring.fem.mesh import build_mesh

    return build_mesh([1400.0, 200.0], [drill_pipe, drill_collar], 10.0, [1560.0])


def _finite_difference_jacobian(params, x, gap, steps):
    """Central differences of :func:`evaluate_contact` at one station ``x = (v, w, v̇, ẇ, θ̇x)``."""
    jac = np.zeros((3, 5))
    for b in range(5):
        hi, lo = np.array(x, dtype=float), np.array(x, dtype=float)
        hi[b] += steps[b]
        lo[b] -= steps[b]
        f_hi = np.array(evaluate_contact(*hi, gap, D_O, params)[:3]).ravel()
        f_lo = np.array(evaluate_contact(*lo, gap, D_O, params)[:3]).ravel()
        jac[:, b] = (f_hi - f_lo) / (2.0 * steps[b])
    return jac


@pytest.mark.parametrize("params", [P, PT, ContactParameters(K_SH, 0.3, 0.5, tangential_friction=True)])
@pytest.mark.parametrize("state", [
    (GAP + 3e-4, 1e-3, 0.2, -0.1, 0.004),        # spin inside the regularisation band
    (-0.6 * GAP, 0.9 * GAP, -0.05, 0.3, -0.02),  # backward slip
    (0.01, -0.04, 0.0, 0.0, 8.0),                # rotating, no lateral velocity
])
def test_jacobian_matches_finite_differences(params, state):
    """The closed-form Jacobian against central differences of the NumPy reference, every entry."""
    jac = params.jacobian(*state, GAP, D_O)
    assert jac.shape == (1, 3, 5)
    steps = (1e-8, 1e-8, 1e-7, 1e-7, 1e-7)
    fd = _finite_difference_jacobian(params, state, GAP, steps)
    scale = np.abs(fd).max(axis=1, keepdims=True) + 1e-300
    np.testing.assert_allclose(jac[0] / scale, fd / scale, atol=1e-6)
    # the inputs matter: the normal block is the penalty stiffness along n
    n = np.array(state[:2]) / math.hypot(*state[:2])
    assert n @ jac[0, :2, :2] @ n == pytest.approx(-K_SH, rel=1e-12)


def test_jacobian_is_zero_inside_the_gap_and_uses_station_stiffness():
    jac = contact_jacobian([0.5 * GAP, 0.0, GAP], [0.0, 0.0, 0.0], 0.1, 0.2, 10.0, GAP, D_O, PT)
    assert not jac.any()
    state = (GAP + 1e-3, 0.0, 0.0, 0.0, 5.0)
    per_node = P.jacobian(*state, GAP, D_O)
    station = P.jacobian(*state, GAP, D_O, stiffness=[2.0 * K_SH])
    np.testing.assert_allclose(station, 2.0 * per_node, rtol=1e-14)
    f1 = P.evaluate(*state, GAP, D_O, stiffness=[2.0 * K_SH])
    f2 = evaluate_contact(*state, GAP, D_O, P, stiffness=[2.0 * K_SH])
    assert all(np.array_equal(a, b) for a, b in zip(f1, f2))


def test_case_contact_reads_the_case():
    from drillstring.case import load_case

    case = load_case("reference")
    params = case_contact(case)
    c = case.contact
    assert params == ContactParameters(c.shock_stiffness, c.friction_coefficient, c.speed_regularization,
                                       c.tangential_friction)
