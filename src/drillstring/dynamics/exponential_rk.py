"""Exponential Runge–Kutta pairs as validated data, and the φ functions they are written in: the methods of the
exponential step (:mod:`drillstring.dynamics.steps.exponential`).

An exponential Runge–Kutta (ERK) method integrates ``y' = A y + N(t, y)`` with a constant linear ``A`` exactly
in ``A`` (M. Hochbruck & A. Ostermann, "Explicit exponential Runge–Kutta methods for semilinear parabolic
problems", SIAM J. Numer. Anal. 43 (2005) 1069–1090, eqs. (2.2); "Exponential integrators", Acta Numerica 19
(2010) 209–286, §2.3; HO below)::

    Y_i     = e^{c_i hA} y_n + h Σ_{j<i} a_ij(hA) N(t_n + c_j h, Y_j)
    y_{n+1} = e^{hA} y_n + h Σ_i b_i(hA) N(t_n + c_i h, Y_i)

whose coefficients are linear combinations of the entire functions ``φ_0(z) = e^z``,
``φ_{k+1}(z) = (φ_k(z) − 1/k!)/z`` (``φ_k(z) = Σ_{j≥0} z^j/(j + k)!``). Here they are data: ``a_ij(Z) =
Σ_k alpha[i, j, k] φ_k(c_i Z)`` and ``b_i(Z) = Σ_k beta[i, k] φ_k(Z)``, and the embedded weights ``b̂_i(Z)``
(``beta_hat``) give the error estimate ``h Σ (b_i − b̂_i)(hA) N_i``. With ``N = 0`` every such method is
``y_{n+1} = e^{hA} y_n``, exact at any step.

Stiff order conditions (HO 2005, Table 5.1; Acta Numerica Table 2.2), which hold uniformly in ``‖hA‖`` and so
are not spoilt by the stiff modes: with ``ψ_{j,i}(Z) = Σ_k a_ik(Z) c_k^{j−1}/(j−1)! − c_i^j φ_j(c_i Z)``,
order 1: ``Σ b_i = φ_1``; order 2: ``Σ b_i c_i = φ_2``; order 3: ``Σ b_i c_i²/2 = φ_3`` and ``Σ b_i J ψ_{2,i} = 0``
for every bounded ``J``; the internal condition ``Σ_j a_ij = c_i φ_1(c_i ·)`` (``ψ_{1,i} = 0``) holds for every
method here (checked on construction). HO 2005 §5.2 show that order 3 needs the third condition only in the
weakened form ``Σ b_i(0) c_i² = 1/3`` (their Theorem 4.7 with (4.16)); ``tests/dynamics/test_exponential.py`` checks
every condition of each pair's order, the weakened one, that the embedded weights meet those of their own
order and fail the next, and the measured convergence order on problems with known solutions.

Methods:

- :data:`ERK32` (``"erk32"``) — HO 2005, eq. (5.8): 3 stages, ``c = (0, 1/3, 2/3)``, stiff order 3;
  the embedded weights ``b̂ = (φ_1 − 3φ_2, 3φ_2, 0)`` are our own: the exponential Runge–Kutta method of stiff
  order 2 on the first two stages (conditions 1 and 2 above), so that ``b − b̂ = (3/2) φ_2 (1, −2, 1)`` and the
  estimate is ``(3/2) h φ_2(hA)(N_1 − 2N_2 + N_3)``, a second difference of ``N`` over the step (``O(h³)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from drillstring.dynamics.tableaus import EmbeddedPair, _readonly

__all__ = ["ExponentialTableau", "ERK32", "EXPONENTIAL_TABLEAUS", "phi_functions"]

_TOL = 1e-12
#: Below this |z| the φ functions are summed from their Taylor series (then the downward recurrence
#: ``φ_k = z φ_{k+1} + 1/k!``, stable there); above it from ``e^z`` by the upward recurrence (its rounding grows
#: like ``k!/|z|^k``, below 1e-15 relative for |z| ≥ 1 and k ≤ 3).
SERIES_RADIUS = 1.0
#: Terms of the Taylor series at |z| < SERIES_RADIUS: the first left out is below 1/(TERMS)! < 1e-18 of φ_k.
SERIES_TERMS = 20


def phi_functions(z, count: int) -> np.ndarray:
    """``φ_0(z) … φ_{count−1}(z)`` (module docstring) for an array ``z`` (any shape, complex or real), shape
    ``(count,) + z.shape``, complex: by the Taylor series and the downward recurrence for ``|z| <``
    :data:`SERIES_RADIUS`, else from ``e^z`` by the upward recurrence (no cancellation near 0)."""
    z = np.asarray(z, dtype=complex)
    out = np.empty((count,) + z.shape, dtype=complex)
    small = np.abs(z) < SERIES_RADIUS
    top = count - 1
    series = np.zeros(z.shape, dtype=complex)
    for j in range(SERIES_TERMS, -1, -1):  # φ_top(z) = Σ_j z^j/(j + top)!, Horner
        series = series * z + 1.0 / math.factorial(j + top)
    with np.errstate(all="ignore"):
        large = np.exp(z)
    out[0] = large
    for k in range(1, count):
        with np.errstate(all="ignore"):
            out[k] = np.where(small, 0.0, (out[k - 1] - 1.0 / math.factorial(k - 1)) / np.where(small, 1.0, z))
    down = series
    for k in range(top, -1, -1):
        out[k] = np.where(small, down, out[k])
        down = z * down + 1.0 / math.factorial(k - 1) if k > 0 else down
    return out


@dataclass(frozen=True, eq=False)
class ExponentialTableau(EmbeddedPair):
    """An exponential Runge–Kutta pair (module docstring): nodes ``c`` (s,), ``c[0] = 0``; ``alpha`` (s, s, K),
    ``a_ij(Z) = Σ_k alpha[i, j, k] φ_k(c_i Z)``, zero for ``j ≥ i`` (explicit); ``beta``, ``beta_hat`` (s, K),
    ``b_i(Z) = Σ_k beta[i, k] φ_k(Z)``. Construction checks the shapes, the explicit structure, the internal
    condition ``Σ_j a_ij(Z) = c_i φ_1(c_i Z)`` and ``Σ b_i = Σ b̂_i = φ_1`` (as identities of the φ
    coefficients, the φ_k being linearly independent), and that ``b̂ ≠ b``. Arrays are read-only copies."""

    name: str
    c: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    beta_hat: np.ndarray
    order: int
    error_order: int
    error_weights: np.ndarray = field(init=False, repr=False)  # (s, K) beta − beta_hat

    def __post_init__(self) -> None:
        c, alpha = _readonly(self.c, 1), _readonly(self.alpha, 3)
        beta, beta_hat = _readonly(self.beta, 2), _readonly(self.beta_hat, 2)
        s, count = c.shape[0], alpha.shape[2]
        if s < 2 or alpha.shape != (s, s, count) or beta.shape != (s, count) or beta_hat.shape != (s, count) \
                or count < 2:
            raise ValueError(f"{self.name}: inconsistent shapes c{c.shape}, alpha{alpha.shape}, "
                             f"beta{beta.shape}, beta_hat{beta_hat.shape}")
        if c[0] != 0.0 or np.any(c < 0.0) or np.any(c > 1.0):
            raise ValueError(f"{self.name}: nodes c must lie in [0, 1] with c[0] = 0, got {c.tolist()}")
        for i in range(s):
            if np.any(alpha[i, i:] != 0.0):
                raise ValueError(f"{self.name}: alpha[{i}, j] must vanish for j ≥ {i} (explicit method)")
            target = np.zeros(count)
            target[1] = c[i]
            if not np.allclose(alpha[i].sum(axis=0), target, rtol=0.0, atol=_TOL):
                raise ValueError(f"{self.name}: stage {i}: Σ_j a_ij(Z) must equal c_i φ_1(c_i Z)")
        unit = np.zeros(count)
        unit[1] = 1.0
        for label, weights in (("beta", beta), ("beta_hat", beta_hat)):
            if not np.allclose(weights.sum(axis=0), unit, rtol=0.0, atol=_TOL):
                raise ValueError(f"{self.name}: Σ_i of {label} must be φ_1 (consistency)")
        if np.array_equal(beta, beta_hat):
            raise ValueError(f"{self.name}: beta_hat equals beta; no error estimate")
        if not (int(self.order) >= 1 and int(self.error_order) >= 1):
            raise ValueError(f"{self.name}: orders must be positive integers")
        ew = beta - beta_hat
        ew.setflags(write=False)
        for name, value in (("c", c), ("alpha", alpha), ("beta", beta), ("beta_hat", beta_hat),
                            ("order", int(self.order)), ("error_order", int(self.error_order)),
                            ("error_weights", ew)):
            object.__setattr__(self, name, value)

    @property
    def n_phi(self) -> int:
        """How many φ functions (φ_0 … φ_{K−1}) the coefficients are written in."""
        return int(self.alpha.shape[2])

    def coefficients(self, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(a_ij(z), b_i(z), b̂_i(z))`` at the scalar ``z`` (complex): shapes (s, s), (s,), (s,)."""
        z = complex(z)
        k = self.n_phi
        at_nodes = [phi_functions(ci * z, k) for ci in self.c]
        a = np.array([[self.alpha[i, j] @ at_nodes[i] for j in range(self.n_stages)]
                      for i in range(self.n_stages)])
        whole = phi_functions(z, k)
        return a, self.beta @ whole, self.beta_hat @ whole


def _erk32() -> ExponentialTableau:
    alpha = np.zeros((3, 3, 3))
    alpha[1, 0] = (0.0, 1.0 / 3.0, 0.0)
    alpha[2, 0] = (0.0, 2.0 / 3.0, -4.0 / 3.0)
    alpha[2, 1] = (0.0, 0.0, 4.0 / 3.0)
    beta = np.array([(0.0, 1.0, -1.5), (0.0, 0.0, 0.0), (0.0, 0.0, 1.5)])
    beta_hat = np.array([(0.0, 1.0, -3.0), (0.0, 0.0, 3.0), (0.0, 0.0, 0.0)])
    return ExponentialTableau(name="erk32", c=(0.0, 1.0 / 3.0, 2.0 / 3.0), alpha=alpha, beta=beta,
                              beta_hat=beta_hat, order=3, error_order=2)


#: Hochbruck & Ostermann (2005) eq. (5.8), stiff order 3, with an embedded stiff-order-2 solution (module docstring).
ERK32 = _erk32()

EXPONENTIAL_TABLEAUS: dict[str, ExponentialTableau] = {"erk32": ERK32}
