"""Characteristic roots of a linear delay system ``x'(t) = A0 x(t) + A1 x(t − τ)``.

The roots ``s`` [1/s] solve ``det Δ(s) = 0``, ``Δ(s) = s I − A0 − A1 e^{−sτ}``: infinitely many, with
finitely many to the right of any vertical line, so the rightmost decide stability. They are found in
two steps:

1. **Infinitesimal generator, Chebyshev collocation** (Breda, Maset & Vermiglio, SIAM J. Sci. Comput.
   27(2), 2005, 482–495; the method of TRACE-DDE and of DDE-BIFTOOL's ``eigAppr``). The state is the
   history ``φ(θ) = x(t + θ)``, ``θ ∈ [−τ, 0]``, whose generator is ``d/dθ`` with the domain condition
   ``φ'(0) = A0 φ(0) + A1 φ(−τ)``. Collocating ``φ`` at the ``M + 1`` Chebyshev points
   ``θ_j = (τ/2)(cos(jπ/M) − 1)`` (``θ_0 = 0``, ``θ_M = −τ``) gives the ``N(M+1)`` square matrix whose first
   block row is ``[A0, 0, …, 0, A1]`` and whose other block rows are ``D_{j·} ⊗ I_N`` (``D`` the Chebyshev
   differentiation matrix scaled by ``2/τ``). Its eigenvalues approximate the roots with spectral accuracy
   in ``M``; as a rule, roots with ``|s| τ ≲ M`` are resolved (the polynomial of degree ``M`` must follow
   ``e^{sθ}`` over ``[−τ, 0]``), so ``M ≥ 2π f_max τ`` for the frequencies ``f_max`` [Hz] of interest.
   When ``A1`` has rank ``p < N`` (a bit law: ``p = 1``) only the history of the ``p`` delayed signals is
   collocated (:func:`chebyshev_generator`), a matrix of size ``N + pM``.
2. **Newton's method on det Δ** from each of the rightmost eigenvalues (Im ≥ 0; the conjugates follow):
   ``s ← s − 1/tr(Δ(s)⁻¹ Δ'(s))``, ``Δ'(s) = I + τ e^{−sτ} A1`` (Jacobi's formula). A root counts as
   converged when its relative residual ``σ_min(Δ(s)) / (|s| + ‖A0‖ + ‖A1‖ e^{−Re(s) τ})`` is at most
   ``residual_tol``; the starting values that did not converge are reported, not used.

**Choice of M.** Every root with ``Re s ≥ 0`` has ``|s| ≤ R`` (:func:`right_half_plane_radius`, a balanced
norm bound), so the default ``M = max(16, ⌈τR⌉)`` puts all of them in the resolved region (``resolved`` in
the result; a size cap ``max_size`` on ``N + pM`` may lower ``M``, and then ``resolved`` is False). With
``verify`` the leading root is computed with ``⌈M/2⌉`` and with twice that, and ``M`` doubled again (while
``M ≤ M_max`` and the size ``≤ max_size``) until two successive leading roots agree to ``1e-8`` relative;
the result keeps the last ``M`` and the change it saw (``leading_change``).

**Neutral roots.** An invariance (the rigid axial translation ``u → u + c`` leaves the depth of cut
``u(t) − u(t − τ)`` unchanged; so does a rigid rotation) puts a root at ``s = 0`` for every parameter.
Roots with ``|s| ≤ neutral_tol`` [1/s] are reported apart, in ``neutral``, and never decide stability;
the default tolerance is ``1e-8 (R + 1/τ)`` (``R`` above: the roots' scale, free of the units of the
states; a computed neutral root sits within about ``1e-15 R`` of 0), and ``neutral_tol=0`` turns this off.
A genuine root closer to 0 than the tolerance would be called neutral; the caller who knows the number of
invariances checks ``len(neutral)``.

:func:`second_order_delay_matrices` builds ``A0``, ``A1`` for modal equations with a bit force and torque
that depend on the regenerative depth of cut; :func:`append_states` borders them with first-order states.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

#: Relative agreement of the leading root between ``M`` and ``2M`` that ends the doubling.
LEADING_ROOT_RTOL = 1e-8


@dataclass(frozen=True)
class DelayRoots:
    """Characteristic roots of ``x' = A0 x + A1 x(t − τ)``.

    ``roots`` [1/s]: converged roots, neutral ones excluded, sorted by decreasing real part (conjugate
    pairs both listed); ``residuals``: their relative residuals; ``neutral`` [1/s]: roots within
    ``neutral_tol`` of 0; ``unconverged`` [1/s]: eigenvalues of the discretisation from which Newton's
    method did not converge; ``M``: Chebyshev degree used; ``tau`` [s]; ``leading_change``: relative change
    of the leading root in the last doubling of ``M`` (NaN without ``verify``); ``radius`` [1/s]: every root
    with ``Re s ≥ 0`` has ``|s| ≤ radius``."""

    roots: np.ndarray
    residuals: np.ndarray
    neutral: np.ndarray
    unconverged: np.ndarray
    M: int
    tau: float
    leading_change: float
    radius: float

    @property
    def resolved(self) -> bool:
        """Every root with ``Re s ≥ 0`` lies in the resolved region ``|s| τ ≤ M`` (``radius`` ``R`` [1/s]:
        :func:`right_half_plane_radius`), so none can have been missed for want of ``M``."""
        return self.radius * self.tau <= self.M

    @property
    def leading(self) -> complex:
        """The rightmost non-neutral root [1/s] (NaN when none converged)."""
        return complex(self.roots[0]) if self.roots.size else complex(math.nan, math.nan)

    @property
    def growth_rate(self) -> float:
        """Real part of the leading root [1/s]."""
        return self.leading.real

    @property
    def frequency(self) -> float:
        """Frequency of the leading root [Hz], ``|Im s| / 2π``."""
        return abs(self.leading.imag) / (2 * math.pi)

    @property
    def stable(self) -> bool:
        """Every non-neutral root found has a negative real part, and no starting value from which Newton's
        method failed lies in the closed right half-plane (then the answer is not trusted: False)."""
        return bool(self.roots.size) and self.growth_rate < 0 and bool(np.all(self.unconverged.real < 0))


def chebyshev_differentiation(tau: float, M: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes ``θ_j = (τ/2)(cos(jπ/M) − 1)`` [s], ``j = 0…M`` (``θ_0 = 0``, ``θ_M = −τ``), and the
    differentiation matrix on them [1/s] (Trefethen, Spectral Methods in MATLAB, SIAM 2000, ``cheb``)."""
    j = np.arange(M + 1)
    x = np.cos(np.pi * j / M)
    c = np.where((j == 0) | (j == M), 2.0, 1.0) * (-1.0) ** j
    D = np.outer(c, 1 / c) / (x[:, None] - x[None, :] + np.eye(M + 1))
    D -= np.diag(D.sum(axis=1))
    return tau / 2 * (x - 1), D * (2 / tau)


def delayed_factors(A1: np.ndarray, rtol: float = 1e-13) -> tuple[np.ndarray, np.ndarray]:
    """``A1 = U Vᵀ`` with ``U`` ``N×p``, ``V`` ``N×p``, ``p`` the numerical rank of ``A1`` (SVD)."""
    W, sigma, Vt = np.linalg.svd(A1)
    p = int(np.sum(sigma > rtol * max(sigma[0] if sigma.size else 0.0, np.finfo(float).tiny)))
    return W[:, :p] * sigma[:p], Vt[:p].T


def chebyshev_generator(A0: np.ndarray, A1: np.ndarray, tau: float, M: int) -> np.ndarray:
    """Collocation matrix of the infinitesimal generator (Breda, Maset & Vermiglio 2005) of the equivalent
    system ``x' = A0 x + U w(t − τ)``, ``w = Vᵀx`` (``A1 = U Vᵀ``, :func:`delayed_factors`): only the
    history of the ``p`` delayed signals ``w`` is collocated, on the nodes ``θ_1…θ_M``
    (``w(θ_0) = Vᵀx``). State ``[x, w(θ_1), …, w(θ_M)]``, size ``N + pM``: block row 0
    ``[A0, 0, …, U]``, block row ``j ≥ 1`` ``[D_j0 Vᵀ, D_j1 I_p, …, D_jM I_p]``. For ``p = N`` it is the
    ``N(M+1)`` matrix of the reference; for ``p < N`` it lacks only the eigenvalues of the history of the
    components the delay never reads (``D_{≥1,≥1}``'s, ``N − p`` times), which are not roots."""
    U, V = delayed_factors(A1)
    N, p = A0.shape[0], U.shape[1]
    _, D = chebyshev_differentiation(tau, M)
    G = np.zeros((N + p * M, N + p * M))
    G[:N, :N] = A0
    G[:N, N + p * (M - 1):] = U
    G[N:, :N] = np.kron(D[1:, :1], V.T)
    G[N:, N:] = np.kron(D[1:, 1:], np.eye(p))
    return G


def _newton(A0, A1, tau, s, maxiter=40, rtol=1e-13):
    """Newton on det Δ from the starting values ``s`` (vectorised); returns the iterates."""
    eye = np.eye(A0.shape[0])
    s = np.array(s, dtype=complex)
    active = np.ones(s.size, dtype=bool)
    for _ in range(maxiter):
        lost = active & ~(np.isfinite(s) & (s.real * tau > -600))  # diverged to the far left (e^{−sτ} overflows)
        s[lost], active[lost] = complex(math.nan, math.nan), False
        if not active.any():
            break
        sa = s[active]
        e = np.exp(-sa * tau)[:, None, None]
        delta, rhs = sa[:, None, None] * eye - A0 - e * A1, eye + tau * e * A1
        with np.errstate(all="ignore"):
            try:
                trace = np.trace(np.linalg.solve(delta, rhs), axis1=1, axis2=2)
            except np.linalg.LinAlgError:  # one Δ exactly singular: that iterate is a root (step 0)
                trace = np.array([_trace_solve(d, r) for d, r in zip(delta, rhs)])
            step = 1 / trace
        step = np.where(np.isfinite(step), step, 0)
        s[active] = sa - step
        active[np.flatnonzero(active)[np.abs(step) <= rtol * np.maximum(np.abs(sa), 1 / tau)]] = False
    return s


def _trace_solve(delta, rhs):
    try:
        return np.trace(np.linalg.solve(delta, rhs))
    except np.linalg.LinAlgError:
        return complex(math.inf)


def _residuals(A0, A1, tau, s):
    """Relative residual ``σ_min(Δ(s)) / (|s| + ‖A0‖₂ + ‖A1‖₂ e^{−Re(s)τ})`` of each root (∞ for a lost
    one)."""
    out = np.full(s.size, math.inf)
    ok = np.isfinite(s) & (s.real * tau > -600)
    e = np.exp(-s[ok] * tau)
    delta = s[ok, None, None] * np.eye(A0.shape[0]) - A0 - e[:, None, None] * A1
    smin = np.linalg.svd(delta, compute_uv=False)[:, -1]
    out[ok] = smin / (np.abs(s[ok]) + np.linalg.norm(A0, 2) + np.linalg.norm(A1, 2) * np.abs(e))
    return out


def right_half_plane_radius(A0: np.ndarray, A1: np.ndarray) -> float:
    """``R`` [1/s] with ``|s| ≤ R`` for every root with ``Re s ≥ 0``: at a root ``s`` is an eigenvalue of
    ``A0 + A1 e^{−sτ}``, so ``|s| ≤ ‖T⁻¹A0T‖₂ + ‖T⁻¹A1T‖₂ e^{−Re(s)τ}`` for any invertible ``T``; ``T`` is
    the diagonal balancing of ``|A0| + |A1|`` (LAPACK ``gebal``), which brings modal equations'
    ``[[0, I], [−K, ·]]`` from ``‖K‖`` down to about the highest frequency."""
    if not A0.size:
        return 0.0
    _, (scale, _) = sla.matrix_balance(np.abs(A0) + np.abs(A1), permute=False, separate=True)
    return float(sum(np.linalg.norm(A / scale[:, None] * scale[None, :], 2) for A in (A0, A1)))


def _roots_at(A0, A1, tau, M, n_refine, radius, residual_tol):
    """Refined roots (Im ≥ 0) from the discretisation of degree ``M``, the starting values that failed.
    Starting values: the ``n_refine`` rightmost eigenvalues, and every one with ``|λ| ≤ 1.1 R`` and
    ``Re λ > −1/τ`` (the approximations of the roots in the right half-plane)."""
    lam = sla.eigvals(chebyshev_generator(A0, A1, tau, M), overwrite_a=True, check_finite=False)
    lam = lam[lam.imag >= -1e-12 * np.maximum(np.abs(lam), 1 / tau)]
    lam = lam[np.argsort(-lam.real)]
    pick = np.arange(lam.size) < n_refine
    pick |= (np.abs(lam) <= 1.1 * radius) & (lam.real > -1 / tau)
    lam = lam[pick]
    s = _newton(A0, A1, tau, lam)
    res = _residuals(A0, A1, tau, s)
    ok = np.isfinite(s) & (res <= residual_tol)
    s = np.where(np.abs(s.imag) <= 1e-12 * np.maximum(np.abs(s), 1 / tau), s.real + 0j, s)
    # Newton may jump from a poor starting value to a root already found: keep one copy, but keep the
    # copies that start next to it (a multiple root, approximated by several eigenvalues).
    keep = []
    for i in np.flatnonzero(ok):
        scale = max(abs(s[i]), 1 / tau)
        same = [j for j in keep if abs(s[j] - s[i]) <= 1e-7 * scale]
        if same and abs(lam[i] - s[i]) > 1e-4 * scale:
            continue
        keep.append(i)
    return s[keep], res[keep], lam[~ok & (lam.imag >= 0)]


def characteristic_roots(A0, A1, tau: float, *, M: int | None = None, verify: bool = True,
                         M_max: int = 512, max_size: int = 2000, n_refine: int | None = None,
                         neutral_tol: float | None = None, residual_tol: float = 1e-10) -> DelayRoots:
    """The rightmost roots of ``det(s I − A0 − A1 e^{−sτ}) = 0`` (module docstring).

    ``A0``, ``A1``: real ``N×N`` [1/s]; ``tau`` [s] > 0; ``M``: the (final) Chebyshev degree, default
    ``max(16, ⌈τR⌉)`` (:func:`right_half_plane_radius`: then every root with ``Re s ≥ 0`` is in the resolved
    region ``|s|τ ≤ M``), lowered to keep the matrix's size ``N + pM`` within ``max_size``; ``verify``:
    compare the leading root at ``⌈M/2⌉`` and ``2⌈M/2⌉`` and double again until they agree (while
    ``M ≤ M_max`` and the size ``≤ max_size``); ``n_refine``: the rightmost starting values always refined
    (default ``max(2N, 20)``, one per conjugate pair); ``neutral_tol`` [1/s]; ``residual_tol``: the largest
    relative residual of a converged root."""
    A0 = np.atleast_2d(np.asarray(A0, dtype=float))
    A1 = np.atleast_2d(np.asarray(A1, dtype=float))
    N = A0.shape[0]
    if A0.shape != (N, N) or A1.shape != (N, N):
        raise ValueError(f"A0 and A1: square matrices of one size expected, got {A0.shape} and {A1.shape}")
    if not np.all(np.isfinite(A0)) or not np.all(np.isfinite(A1)):
        raise ValueError("A0 and A1: finite entries expected")
    if not (math.isfinite(tau) and tau > 0):
        raise ValueError(f"tau = {tau}: a delay > 0 s expected")
    if M is not None and M < 2:
        raise ValueError(f"M = {M}: a Chebyshev degree >= 2 expected")
    p = max(delayed_factors(A1)[0].shape[1], 1)
    radius = right_half_plane_radius(A0, A1)
    if M is None:
        M = max(16, math.ceil(tau * radius))
        M = int(max(8, min(M, (max_size - N) // p)))
    n_refine = max(2 * N, 20) if n_refine is None else n_refine
    if neutral_tol is None:
        neutral_tol = 1e-8 * (radius + 1 / tau)

    def leading(s):
        s = s[np.abs(s) > neutral_tol]
        return s[np.argmax(s.real)] if s.size else complex(math.nan)

    change = math.nan
    if verify:
        M = max(2, math.ceil(M / 2))
    s, res, bad = _roots_at(A0, A1, tau, M, n_refine, radius, residual_tol)
    first = True
    while verify and (first or (2 * M <= M_max and N + 2 * p * M <= max_size)):
        s2, res2, bad2 = _roots_at(A0, A1, tau, 2 * M, n_refine, radius, residual_tol)
        a, b = leading(s), leading(s2)
        change = abs(a - b) / max(abs(b), 1 / tau)
        s, res, bad, M, first = s2, res2, bad2, 2 * M, False
        if change <= LEADING_ROOT_RTOL:
            break
    is_neutral = np.abs(s) <= neutral_tol
    both = lambda z: np.concatenate([z, np.conj(z[z.imag > 0])])  # noqa: E731
    neutral, s, res = s[is_neutral].real, s[~is_neutral], res[~is_neutral]
    roots, residuals = both(s), np.concatenate([res, res[s.imag > 0]])
    order = np.lexsort((-roots.imag, -roots.real))
    return DelayRoots(roots=roots[order], residuals=residuals[order], neutral=neutral, unconverged=both(bad),
                      M=M, tau=float(tau), leading_change=float(change), radius=radius)


def second_order_delay_matrices(K, C, b_u, b_t, *, f_du: float, f_dtheta: float, f_d: float,
                                t_du: float, t_dtheta: float, t_d: float, rate_of_penetration: float,
                                bit_speed: float) -> tuple[np.ndarray, np.ndarray]:
    """``A0``, ``A1`` (``2n×2n``, state ``x = [δη, δη']``) of modal equations with a regenerative bit law.

    The modal equations ``η'' = −K η − C η' + b_u f + b_t t`` (``K`` [1/s²], ``C`` [1/s], ``n×n``; ``b_u``,
    ``b_t`` (n,), the bit's axial position ``u = b_uᵀη`` [m] and angle ``θ = b_tᵀη`` [rad] in the modal
    units) carry the force on bit ``f`` [N] along ``u`` and the torque ``t`` [N·m] along ``θ``, linearised
    about steady drilling (rate of penetration ``V`` [m/s], bit speed ``Ω`` [rad/s] ≠ 0)::

        δf = f_du δu' + f_dtheta δθ' + f_d δd,   δt = t_du δu' + t_dtheta δθ' + t_d δd

    (``f_du`` [N·s/m], ``f_dtheta`` [N·s/rad], ``f_d`` [N/m], ``t_du`` [N·s], ``t_dtheta`` [N·m·s/rad],
    ``t_d`` [N]). The depth of cut ``d = u(t) − u(t − τ)`` has the state-dependent delay
    ``θ(t) − θ(t − τ) = Δ`` (``Δ = 2π/n`` for ``n`` blades; Richard, Germay & Detournay, J. Sound Vib. 305,
    2007). With ``u = Vt + δu``, ``θ = Ωt + δθ``, ``τ = τ0 + δτ``, ``Ω τ0 = Δ``, to first order the delay
    condition gives ``Ω δτ = −(δθ(t) − δθ(t − τ0))`` and ``d = V τ + δu(t) − δu(t − τ0)`` (so
    ``d0 = V τ0 = VΔ/Ω``, the steady depth of cut), hence

        δd = [δu(t) − δu(t − τ0)] − (V/Ω) [δθ(t) − δθ(t − τ0)] = gᵀ (δη(t) − δη(t − τ0)),
        g = b_u − (V/Ω) b_t.

    With ``h = f_d b_u + t_d b_t`` and
    ``P = b_u (f_du b_uᵀ + f_dtheta b_tᵀ) + b_t (t_du b_uᵀ + t_dtheta b_tᵀ)``::

        A0 = [[0, I], [−K + h gᵀ, −C + P]],   A1 = [[0, 0], [−h gᵀ, 0]].

    ``τ0 = Δ/Ω`` is the caller's delay for :func:`characteristic_roots`."""
    K, C = np.atleast_2d(np.asarray(K, float)), np.atleast_2d(np.asarray(C, float))
    b_u, b_t = np.asarray(b_u, float).ravel(), np.asarray(b_t, float).ravel()
    n = K.shape[0]
    for name, value in (("C", C), ("b_u", b_u), ("b_t", b_t)):
        if value.shape != ((n, n) if name == "C" else (n,)):
            raise ValueError(f"{name}: shape {value.shape} does not match K {K.shape}")
    if not (math.isfinite(bit_speed) and bit_speed != 0):
        raise ValueError(f"bit_speed = {bit_speed}: a nonzero steady bit speed [rad/s] expected")
    coupling = regenerative_coupling(b_u, b_t, f_d=f_d, t_d=t_d, rate_of_penetration=rate_of_penetration,
                                     bit_speed=bit_speed)
    P = np.outer(b_u, f_du * b_u + f_dtheta * b_t) + np.outer(b_t, t_du * b_u + t_dtheta * b_t)
    A0 = np.zeros((2 * n, 2 * n))
    A1 = np.zeros((2 * n, 2 * n))
    A0[:n, n:] = np.eye(n)
    A0[n:, :n] = -K + coupling
    A0[n:, n:] = -C + P
    A1[n:, :n] = -coupling
    return A0, A1


def regenerative_coupling(b_u, b_t, *, f_d: float, t_d: float, rate_of_penetration: float,
                          bit_speed: float) -> np.ndarray:
    """``h gᵀ`` (n×n): the modal force of the depth of cut's perturbation, ``h (gᵀδη(t) − gᵀδη(t − τ0))``,
    with ``h = f_d b_u + t_d b_t`` and ``g = b_u − (V/Ω) b_t`` (:func:`second_order_delay_matrices`); it
    enters ``A0`` with ``+`` and ``A1`` with ``−`` in the accelerations' rows, the positions' columns."""
    b_u, b_t = np.asarray(b_u, float).ravel(), np.asarray(b_t, float).ravel()
    g = b_u - (rate_of_penetration / bit_speed) * b_t
    return np.outer(f_d * b_u + t_d * b_t, g)


def append_states(A0, A1, A_xz, A_zx, A_zz) -> tuple[np.ndarray, np.ndarray]:
    """Border ``x' = A0 x + A1 x(t − τ)`` with undelayed first-order states ``z`` (e.g. a controller's):
    ``x' = A0 x + A_xz z + A1 x(t − τ)``, ``z' = A_zx x + A_zz z``. Returns the bordered ``A0`` and ``A1``."""
    A0, A1 = np.asarray(A0, float), np.asarray(A1, float)
    A_zz = np.atleast_2d(np.asarray(A_zz, float))
    N, m = A0.shape[0], A_zz.shape[0]
    A_xz = np.asarray(A_xz, float).reshape(N, m)
    A_zx = np.asarray(A_zx, float).reshape(m, N)
    B1 = np.zeros((N + m, N + m))
    B1[:N, :N] = A1
    return np.block([[A0, A_xz], [A_zx, A_zz]]), B1
