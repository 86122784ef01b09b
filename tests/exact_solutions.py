"""Closed-form and exact reference solutions used by the verification tests.

Kept independent of the package: nothing here imports drillstring.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq


def two_section_rod_frequencies(
    lengths: tuple[float, float],
    impedances: tuple[float, float],
    wave_speed: float,
    top: str,
    count: int,
) -> np.ndarray:
    """Exact natural frequencies [Hz] of a rod of two sections (same wave speed c), bit end free.

    Valid for axial waves (impedance ∝ EA, c = sqrt(E/ρ)) and torsional waves (impedance ∝ G I_p,
    c = sqrt(G/ρ)). With k = ω/c, section 1 on [0, L1], section 2 on [L1, L1+L2], free at the bit:

    - top free:  Z1 sin(kL1) cos(kL2) + Z2 cos(kL1) sin(kL2) = 0  (first root k = 0: rigid motion)
    - top fixed: Z1 cos(kL1) cos(kL2) − Z2 sin(kL1) sin(kL2) = 0

    from continuity of displacement and force at the section change.
    """
    l1, l2 = lengths
    z1, z2 = impedances
    if top == "free":
        def f(k):
            return z1 * math.sin(k * l1) * math.cos(k * l2) + z2 * math.cos(k * l1) * math.sin(k * l2)
    elif top == "fixed":
        def f(k):
            return z1 * math.cos(k * l1) * math.cos(k * l2) - z2 * math.sin(k * l1) * math.sin(k * l2)
    else:
        raise ValueError(top)
    roots = [0.0] if top == "free" else []
    grid = np.linspace(1e-9, 200.0 / (l1 + l2), 200_000)
    values = np.array([f(k) for k in grid])
    for i in np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0]:
        roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-15))
        if len(roots) == count:
            break
    return np.array(roots) * wave_speed / (2 * math.pi)


def timoshenko_pinned_frequencies(
    n_modes: int, length: float, ei: float, rho_a: float, rho_i: float, kga: float,
    rho_a_extra: float = 0.0,
) -> np.ndarray:
    """Pinned–pinned uniform Timoshenko beam [Hz] (Timoshenko 1921; Han, Benaroya & Wei 1999).

    With w = sin(kx) e^{iωt}, ψ = Ψ cos(kx) e^{iωt}, k = nπ/L, the two Timoshenko equations
    ρA' ẅ = k_sGA (w'' − ψ') and ρI ψ̈ = EI ψ'' + k_sGA (w' − ψ) give
    (ρI ρA'/k_sGA) ω⁴ − (ρA' + ρI k² + EI ρA' k²/k_sGA) ω² + EI k⁴ = 0, where
    ρA' = ρA + m_f includes any added translational (fluid) mass; the lower root is the flexural
    branch.
    """
    out = []
    for n in range(1, n_modes + 1):
        k = n * math.pi / length
        a = rho_i * (rho_a + rho_a_extra) / kga
        b = (rho_a + rho_a_extra) + rho_i * k**2 + ei * (rho_a + rho_a_extra) * k**2 / kga
        c = ei * k**4
        omega2 = (b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
        out.append(math.sqrt(omega2) / (2 * math.pi))
    return np.array(out)


def spinning_timoshenko_whirl(
    mode: int, length: float, ei: float, rho_a: float, rho_i: float, rho_ip: float, kga: float, spin: float,
) -> tuple[float, float]:
    """Forward and backward whirl [rad/s] of a pinned–pinned Timoshenko shaft spinning at ``spin`` [rad/s].

    With r = v + i w = R sin(kx) e^{iωt}, Θ = θz + iψ = P cos(kx) e^{iωt} (ψ = −θy), k = nπ/L, the
    equations ρA r̈ = k_sGA (r'' − Θ'), ρI Θ̈ − i ρI_p Ω Θ̇ = EI Θ'' + k_sGA (r' − Θ) give
    (k_sGA k² − ρA ω²)(EI k² + k_sGA − ρI ω² + ρI_p Ω ω) − (k_sGA k)² = 0; the flexural roots are
    the smallest positive (forward) and negative (backward) ω (Lalanne & Ferraris, *Rotordynamics
    Prediction in Engineering*, 1998, ch. 2; Timoshenko 1921).
    """
    k = mode * np.pi / length
    poly = np.polymul([-rho_a, 0.0, kga * k * k], [-rho_i, rho_ip * spin, ei * k * k + kga])
    poly[-1] -= (kga * k) ** 2
    roots = np.roots(poly)
    roots = roots[np.abs(roots.imag) < 1e-9 * np.abs(roots).max()].real
    return roots[roots > 0].min(), -roots[roots < 0].max()


def engesser_buckling_load(length: float, ei: float, kga: float) -> float:
    """Critical compressive load [N] of a pinned–pinned column with shear deformation (Engesser):
    P = P_E / (1 + P_E / k_sGA), P_E = π² EI / L²."""
    p_euler = math.pi**2 * ei / length**2
    return p_euler / (1.0 + p_euler / kga)


def heavy_column_critical_load(
    segments: list[tuple[float, float, float, float]],
    springs: tuple[tuple[float, float], ...] = (),
    search_max: float = 1e7,
    n_grid: int = 60,
) -> float:
    """Smallest bit load W [N] that buckles a heavy pinned–pinned column hanging from its top.

    Euler–Bernoulli column, x down from the top (pinned: w = 0, M = 0) to the bit (pinned); the
    segments, top first, are ``(length [m], EI [N·m²], weight per length q [N/m], extra compression
    p [N])`` and the axial force is ``N(x) = ∫ₓᴸ q dx − W − p(x)`` (tension positive). ``springs``
    are ``(x [m], k [N/m])`` lateral point springs. Equilibrium of the bent column:

        (EI w'')'' − (N w')' + Σ k w δ(x − x_s) = 0,

    written for the state z = (w, θ = w', M = EI w'', Q = M' − N θ), continuous at section changes:
    z' = (θ, M/EI, Q + N θ, 0), and Q jumps by −k w at a spring.

    The two solutions that satisfy the top conditions span a plane in z-space; it is carried down
    by the compound-matrix method (Ng & Reid): the antisymmetric Φ = z₁z₂ᵀ − z₂z₁ᵀ obeys
    Φ' = AΦ + ΦAᵀ and is renormalised continuously, so exponential growth in the tension zone does
    not make the two solutions collinear (plain shooting fails beyond ~10 (EI/q)^{1/3}). A bit
    state with w = M = 0 exists when the minor Φ[w, M](L) vanishes; its sign changes are found on a
    grid of W and refined with brentq. Independent of the package (SciPy ODE solver only).
    """
    from scipy.integrate import solve_ivp

    lengths = [s[0] for s in segments]
    total_weight = sum(s[0] * s[2] for s in segments)
    bounds = np.concatenate([[0.0], np.cumsum(lengths)])

    def end_minor(load: float) -> float:
        phi = np.zeros((4, 4))
        phi[1, 3], phi[3, 1] = 1.0, -1.0  # free at the top: θ and Q
        below = total_weight  # ∫ₓᴸ q dx at the segment top
        for (length, ei, q, p), x0 in zip(segments, bounds[:-1]):
            x1 = x0 + length
            cuts = sorted({x0, x1, *[x for x, _ in springs if x0 < x < x1 + 1e-9]})
            for a, b in zip(cuts[:-1], cuts[1:]):
                def rhs(x, y, a=a, ei=ei, q=q, p=p, top=below):
                    n = top - q * (x - x0) - load - p
                    mat = np.zeros((4, 4))
                    mat[0, 1], mat[1, 2], mat[2, 1], mat[2, 3] = 1.0, 1.0 / ei, n, 1.0
                    f = y.reshape(4, 4)
                    d = mat @ f + f @ mat.T
                    d -= np.sum(f * d) / np.sum(f * f) * f  # stay on the unit sphere
                    return d.ravel()

                sol = solve_ivp(rhs, (a, b), phi.ravel(), method="DOP853", rtol=1e-9, atol=1e-12)
                phi = sol.y[:, -1].reshape(4, 4)
                for x, k in springs:
                    if abs(x - b) < 1e-9 and b < bounds[-1]:
                        jump = np.eye(4)
                        jump[3, 0] = -k
                        phi = jump @ phi @ jump.T
                phi /= np.linalg.norm(phi)
            below -= q * length
        return phi[0, 2]

    grid = np.linspace(0.0, search_max, n_grid)
    values = [end_minor(w) for w in grid]
    for i in range(n_grid - 1):
        if np.sign(values[i]) != np.sign(values[i + 1]):
            return brentq(end_minor, grid[i], grid[i + 1], xtol=1e-10 * search_max, rtol=1e-12)
    raise ValueError("no critical load below search_max")


def free_free_damping_on_first_fixed_free_mode(
    damping_ratio: float, rigid_coefficient: float, rigid_inertia: float, wave_speed: float,
    length: float, terms: int = 200_000,
) -> float:
    """ψ₁ᵀ C ψ₁ / (2 ω₁) for a uniform rod (or bar) of length L whose damping matrix is built on its
    free–free modes, C = M Φ diag(c_k) Φᵀ M (c_0 = c/J on the rigid mode, c_k = 2ξω_k), and ψ₁ the
    first mode of the same rod with the top (x = 0) held and the bottom free.

    Mass-normalised shapes (mass per length μ, J = μL): φ_0 = 1/√J, φ_k = √(2/J) cos(kπx/L),
    ω_k = kπc/L; ψ₁ = √(2/J) sin(πx/2L), ω₁ = πc/(2L). The projections a_k = ∫ μ ψ₁ φ_k dx are
    a_0 = 2√2/π and a_k = −1/(π (k² − ¼)) (Σ a_k² = 1), so

        ψ₁ᵀ C ψ₁ / (2ω₁) = (c/J) a_0² / (2ω₁) + ξ Σ_{k≥1} (ω_k/ω₁) a_k²,   ω_k/ω₁ = 2k.
    """
    k = np.arange(1, terms + 1, dtype=float)
    a = -1.0 / (math.pi * (k**2 - 0.25))
    omega_1 = math.pi * wave_speed / (2.0 * length)
    rigid = (rigid_coefficient / rigid_inertia) * (8.0 / math.pi**2) / (2.0 * omega_1)
    return rigid + damping_ratio * float(np.sum(2.0 * k * a**2))


def beam_resting_on_a_wall(stiffness, rows, station_stiffness, gaps, initial):
    """Static equilibrium of a (possibly buckled) beam in one bending plane pushed against a wall on one
    side: ``K v + Σ_i k_i (v[rows_i] − g_i)₊ e_i = 0`` with the wall at ``v = g_i`` for station ``i`` acting
    on the DOF ``rows_i`` (penalty springs of stiffness ``k_i`` [N/m]). Piecewise linear: solved by an
    active-set iteration (solve with the springs of the stations beyond their gap, update, repeat until
    the set stops changing), started from ``initial``.

    Returns ``(v, forces)``: the DOF vector and the wall force on each station [N] (>= 0, pushing back).
    """
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    v = np.asarray(initial, dtype=float)
    rows = np.asarray(rows)
    active = v[rows] > gaps
    for _ in range(200):
        diagonal = np.zeros(len(v))
        rhs = np.zeros(len(v))
        np.add.at(diagonal, rows[active], station_stiffness[active])
        np.add.at(rhs, rows[active], station_stiffness[active] * gaps[active])
        v = spla.spsolve((stiffness + sp.diags(diagonal)).tocsc(), rhs)
        now = v[rows] > gaps
        if np.array_equal(now, active):
            return v, station_stiffness * np.clip(v[rows] - gaps, 0.0, None)
        active = now
    raise RuntimeError("the active set did not settle")


def torsional_rod_top_drive_roots(lengths: tuple[float, float], impedances: tuple[float, float], wave_speed: float,
                                  top_drive: tuple[float, float, float], max_frequency: float) -> np.ndarray:
    """Exact closed-loop eigenvalues s (Im s > 0, |Im s| < 2π max_frequency) of a distributed two-section
    torsional rod (impedances Z_i = I_i √(Gρ), one wave speed c = √(G/ρ)), bit end free, turned at the top by
    an inertia J under a PI speed controller, ``top_drive = (J, k_p, k_i)``, no damping.

    Each section carries θ(x) = A cosh(γx) + B sinh(γx), γ = s/c, torque T = G I θ' = Z s (A sinh + B cosh),
    so across a section of length ℓ: θ(ℓ) = ch θ(0) + sh T(0)/(Z s), T(ℓ) = Z s sh θ(0) + ch T(0). The top
    obeys J θ̈₀ = τ_m + T(0) with the linearised PI law τ_m = −(k_p s + k_i) θ₀ (the integral of the speed
    error is −θ₀), so T(0) = (J s² + k_p s + k_i) θ₀; the bit is free, T(L) = 0. With θ₀ = 1 the
    characteristic function is T(L; s). Roots by Newton's method from a grid of starts along the imaginary
    axis (no finite-element information used), deduplicated."""
    (l1, l2), (z1, z2) = lengths, impedances
    inertia, proportional_gain, integral_gain = top_drive

    def f(s):
        theta, torque = 1.0 + 0j, inertia * s * s + proportional_gain * s + integral_gain
        for length, z in ((l1, z1), (l2, z2)):
            g = s * length / wave_speed
            ch, sh = np.cosh(g), np.sinh(g)
            theta, torque = ch * theta + sh * torque / (z * s), z * s * sh * theta + ch * torque
        return torque / (z1 * s)  # scaled: O(1) near the roots

    roots: list[complex] = []
    w_max = 2 * math.pi * max_frequency
    for w0 in np.linspace(0.05, 1.2 * w_max, 400):
        s = complex(-0.01 * w0, w0)
        for _ in range(100):
            h = 1e-7 * abs(s)
            step = f(s) / ((f(s + h) - f(s - h)) / (2 * h))
            s -= step
            if abs(step) < 1e-13 * abs(s):
                break
        else:
            continue
        if 0.0 < s.imag < w_max and abs(f(s)) < 1e-9 and all(abs(s - r) > 1e-6 * abs(s) for r in roots):
            roots.append(s)
    return np.array(sorted(roots, key=lambda r: r.imag))
