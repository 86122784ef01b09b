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
