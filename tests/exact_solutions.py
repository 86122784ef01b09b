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


def engesser_buckling_load(length: float, ei: float, kga: float) -> float:
    """Critical compressive load [N] of a pinned–pinned column with shear deformation (Engesser):
    P = P_E / (1 + P_E / k_sGA), P_E = π² EI / L²."""
    p_euler = math.pi**2 * ei / length**2
    return p_euler / (1.0 + p_euler / kga)


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
