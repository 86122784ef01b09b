"""Benchmark: the rightmost characteristic roots of a linear delay system of N = 60 first-order states
(30 modes: 15 axial, 15 torsional, a bit law with the regenerative depth of cut, delay τ = 0.5 s, the
scales of Aarsnes & van de Wouw 2019's 2000 m string at 30 rpm), with the Chebyshev degree M = 20.

Prints the wall time of the collocation matrix's eigenvalues, of the Newton refinement, of a whole
:func:`~drillstring.dynamics.delay_stability.characteristic_roots` call with and without the check
(``verify``: M/2 against M) and with the default M, and how many of the rightmost roots at M = 20 agree
with those at M = 80. The bit law's delay has rank one (collocation matrix N + M); the same N with a
full-rank delay (matrix N(M+1)) is the worst case. One BLAS thread. Run:

    .venv/bin/python benchmarks/delay_stability.py [--repeat 3] [--M 20]
"""

from __future__ import annotations

import argparse
import math

from cost_table import best  # before NumPy: one BLAS thread

import numpy as np  # noqa: E402
import scipy.linalg as sla  # noqa: E402

from drillstring.dynamics.delay_stability import (  # noqa: E402
    _newton,
    characteristic_roots,
    chebyshev_generator,
    second_order_delay_matrices,
)


def string_like_system(n_axial=15, n_torsional=15, tau=0.5):
    """Modal equations of a free–free string: axial modes j·1.25 Hz, torsional j·0.78 Hz (j = 0 the rigid
    modes), 1 % modal damping plus a small rigid-body resistance; the bit's modal participation of a free
    end, √2 for the elastic modes (unit-mass normalisation scaled by the string's mass and inertia)."""
    m, inertia = 1.2e5, 41.0 + 60.0
    w_a = 2 * math.pi * 1.25 * np.arange(n_axial)
    w_t = 2 * math.pi * 0.78 * np.arange(n_torsional)
    w = np.concatenate([w_a, w_t])
    K = np.diag(w**2)
    C = np.diag(np.maximum(0.02 * w, 0.05))
    n = n_axial + n_torsional
    b_u = np.zeros(n)
    b_t = np.zeros(n)
    b_u[:n_axial] = np.where(np.arange(n_axial) == 0, 1.0, math.sqrt(2)) / math.sqrt(m)
    b_t[n_axial:] = np.where(np.arange(n_torsional) == 0, 1.0, math.sqrt(2)) / math.sqrt(inertia)
    # Detournay law at 30 rpm, 30 m/h, n = 4 blades: W_c = aζεn d, T_c = ½a²εn d (forces oppose the motion)
    a, zeta, eps, blades = 0.108, 0.6, 60e6, 4
    f_d, t_d = -a * zeta * eps * blades, -0.5 * a**2 * eps * blades
    A0, A1 = second_order_delay_matrices(K, C, b_u, b_t, f_du=0.0, f_dtheta=0.0, f_d=f_d, t_du=0.0,
                                         t_dtheta=0.0, t_d=t_d, rate_of_penetration=30 / 3600,
                                         bit_speed=math.pi)
    return A0, A1, tau


def full_rank_system(N=60, tau=0.5, seed=1):
    """A delay matrix of full rank (the worst case, matrix N(M+1)): A0 with eigenvalues in
    −5…−0.1 ± i(0…100) 1/s, A1 random, scaled to ‖A1‖₂ = 2 1/s."""
    rng = np.random.default_rng(seed)
    Q = np.linalg.qr(rng.standard_normal((N, N)))[0]
    blocks = [np.array([[-a, w], [-w, -a]]) for a, w in zip(rng.uniform(0.1, 5, N // 2),
                                                           rng.uniform(0, 100, N // 2))]
    A0 = Q @ sla.block_diag(*blocks) @ Q.T
    A1 = rng.standard_normal((N, N))
    return A0, 2 * A1 / np.linalg.norm(A1, 2), tau


def report(name, A0, A1, tau, M, repeat):
    N = A0.shape[0]
    G = chebyshev_generator(A0, A1, tau, M)
    t_eig, lam = best(lambda: sla.eigvals(chebyshev_generator(A0, A1, tau, M), overwrite_a=True,
                                          check_finite=False), repeat)
    starts = lam[lam.imag >= 0]
    starts = starts[np.argsort(-starts.real)][:2 * N]
    t_newton, _ = best(lambda: _newton(A0, A1, tau, starts), repeat)
    t_plain, plain = best(lambda: characteristic_roots(A0, A1, tau, M=M, verify=False), repeat)
    t_verify, checked = best(lambda: characteristic_roots(A0, A1, tau, M=M, verify=True, M_max=M), repeat)
    t_default, default = best(lambda: characteristic_roots(A0, A1, tau), repeat)
    reference = characteristic_roots(A0, A1, tau, M=80, verify=False, max_size=10**6)
    top = reference.roots[:20]
    agree = sum(np.min(np.abs(plain.roots - z)) <= 1e-8 * abs(z) for z in top)
    print(f"{name}: N = {N}, M = {M}, collocation matrix {G.shape[0]}², best of {repeat}")
    print(f"  eigenvalues of the collocation matrix  {t_eig:8.3f} s")
    print(f"  Newton refinement of {starts.size} starts       {t_newton:8.3f} s")
    print(f"  characteristic_roots, M only          {t_plain:8.3f} s")
    print(f"  characteristic_roots, M/2 and M       {t_verify:8.3f} s  (verify; leading change "
          f"{checked.leading_change:.1e})")
    print(f"  characteristic_roots, defaults        {t_default:8.3f} s  (M = {default.M}, "
          f"leading change {default.leading_change:.1e})")
    print(f"  leading root {plain.leading:.6f} 1/s ({plain.frequency:.4f} Hz), stable {plain.stable}, "
          f"neutral {plain.neutral.size}, unconverged starts {plain.unconverged.size}")
    print(f"  R = {default.radius:.1f} 1/s, τR = {default.radius * tau:.1f}: defaults resolved {default.resolved}")
    print(f"  rightmost 20 roots at M = 80 found at M = {M}: {agree}/20")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--M", type=int, default=20)
    args = parser.parse_args()
    report("bit law (delay of rank 1)", *string_like_system(), args.M, args.repeat)
    report("full-rank delay", *full_rank_system(), args.M, args.repeat)


if __name__ == "__main__":
    main()
