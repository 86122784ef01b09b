"""The exponential Runge–Kutta step (an :class:`~drillstring.dynamics.exponential_rk.ExponentialTableau`): the
reduced model's linear modal part integrated exactly, the rest explicitly, for the compiled loop
(:mod:`drillstring.dynamics.steps.kinds`).

The split. ``y' = f(t, y) = A y + N(t, y)`` with ``A`` the model's constant linear modal part and ``N = f − A y``
the rest (the right-hand side's kernels stay one implementation: ``N`` is never written out). On the state
``y = [η, η̇, s]``, ``A = [[0, I], [−Ω², −D]]`` on the modal coordinates (``Ω²`` the signed ``ω²``, ``D`` the
damping block by block, :attr:`RhsData.damping_blocks`) and zero on the other states ``s`` (a top drive's or a
motor's): no force law enters ``A``. Whatever ``A``, the split is exact; ``A`` only decides which rates the step
follows exactly (:func:`linear_modal_part`):

- each damping block of at most :data:`MAX_DENSE_BLOCK` modes enters whole; a larger one (the contact case's
  lateral block, coupled by the fluid's Coriolis damping: 83 modes) by its diagonal, its off-diagonal damping
  (not stiff) left in ``N``;
- a block whose eigenvalues are all slow (below :data:`SLOW_BLOCK_RATE`) enters by its diagonal;
- a block whose eigenvector matrix is ill-conditioned (condition number above :data:`MAX_CONDITION`) enters
  without its rigid modes (``ω² = 0``: the rigid axial translation, a top drive's free rotation, whose 2 × 2 part
  ``[[0, 1], [0, −d]]`` is nearly or exactly defective for a small ``d``), else by its diagonal; a mode left out
  (rigid, or a single mode so conditioned: critically damped) has its ``η``, ``η̇`` integrated as the states
  ``s`` are, with the coefficients at ``Z = 0``.

Diagonalised once per model (block by block, :func:`numpy.linalg.eig`; cached for the model's arrays),
``A = V Λ V⁻¹`` with complex ``Λ``: of each conjugate pair only one eigenvalue is kept, weighted 2 (``y`` is
real: ``y = Re Σ_e w_e v_e (V⁻¹y)_e``). The step then runs in the eigen-coordinates ``z = V⁻¹ y`` of each block,
where every φ function is a scalar function of ``hλ``: per attempt one table ``φ_k(c hλ)`` for each node ``c``,
``k < K`` and kept eigenvalue (:func:`_phi_table`, series near 0, kept while ``h`` does not change)::

    Z_i = φ_0(c_i hΛ) z_n + h Σ_{j<i} a_ij(hΛ) Ñ_j,    Ñ_j = V⁻¹ f(Y_j) − Λ Z_j,    Y_i = Re V Z_i

(``Ñ_j = V⁻¹ N(Y_j)``: the right-hand side is evaluated at the physical stage ``Y_j``), the solution and the
error estimate ``h Σ (b_i − b̂_i)(hΛ) Ñ_i`` likewise; the states outside ``A`` take the coefficients at
``Z = 0`` (a plain explicit Runge–Kutta step). With ``N = 0`` the step is ``e^{hA}`` applied mode by mode:
exact to round-off at any step size.

Dense output: the cubic Hermite interpolant of ``(y_n, f_n)`` and ``(y_{n+1}, f_{n+1})`` (third order,
``y_n + h[(θ − 2θ² + θ³) f_n + (3θ² − 2θ³)(y_{n+1} − y_n)/h + (θ³ − θ²) f_{n+1}]``), in the loop's
polynomial form; ``f_{n+1}`` is evaluated by the attempt (its last evaluation), so an accepted step costs
``s`` right-hand sides (3 for ``erk32``) and knows ``f`` at the new state.

:func:`reference_step` is the NumPy reference of the same step for a dense ``A`` and a right-hand side in
Python (the tests' problems with known solutions); ``tests/dynamics/test_exponential.py`` checks the compiled
step against it and against DOPRI5 on a built-in case.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from drillstring.dynamics.exponential_rk import ExponentialTableau, phi_functions
from drillstring.dynamics.kernel_data import FullModelData
from drillstring.dynamics.rom import diagonal_blocks, evaluate_rhs, stiff_part
from drillstring.dynamics.steps.kinds import StepKind, register

#: Damping blocks of more modes than this enter ``A`` by their diagonal (module docstring).
MAX_DENSE_BLOCK = 32
#: A block (or single mode) whose eigenvector matrix has a larger 2-norm condition number is split into its
#: modes (or left out of ``A``): the transforms' rounding grows with it.
MAX_CONDITION = 1e6
#: A block whose eigenvalues are all below this modulus [1/s] enters ``A`` by its diagonal (its off-diagonal
#: damping, slow, left in ``N``): the dense transforms of the reference case's 20-mode lateral blocks
#: (|λ| ≤ 3.1 1/s) cost more than the right-hand side.
SLOW_BLOCK_RATE = 10.0
#: Add the bit law's linearisation at the run's start to ``A`` (:func:`bit_law_linearisation`): off, the
#: measured alternative of docs/performance.md ("Exponential step"), not better on the built-in cases (the
#: law's partials move along a run; frozen at the start they left more in ``N`` than they took out).
LINEARISED_LAW = False
#: A mode with ``|ω²|`` at most this fraction of the model's largest is rigid (left out of ``A``).
RIGID = 1e-12

#: The cubic Hermite interpolant as the loop's dense output (rows: f_n, (y_{n+1} − y_n)/h, f_{n+1}).
HERMITE = np.array([[1.0, -2.0, 1.0], [0.0, 3.0, -2.0], [0.0, -1.0, 1.0]])
_SERIES_RADIUS = 1.0
_SERIES_TERMS = 20


class ModalEigen(NamedTuple):
    """The diagonalised linear part (module docstring): kept eigenvalues ``lam`` (m,) with weights (1 real,
    2 for a conjugate pair's representative); per block ``blocks[b] = (first entry in modes, k, e0, e1)``, its
    modes ``modes[...]`` (k of them), its eigenvectors ``V`` (2k × (e1 − e0), rows ``η`` then ``η̇`` of its
    modes, pre-multiplied by the weights) and the rows ``W`` of ``V⁻¹`` ((e1 − e0) × 2k), real and imaginary
    parts apart, flat from ``offsets[b]``; ``free``: the state indices outside ``A``."""

    lam: np.ndarray  # (m,) complex128
    weight: np.ndarray  # (m,)
    blocks: np.ndarray  # (nb, 4) int64
    modes: np.ndarray  # int64
    offsets: np.ndarray  # (nb,) int64
    v_re: np.ndarray
    v_im: np.ndarray
    w_re: np.ndarray
    w_im: np.ndarray
    free: np.ndarray  # int64
    n_modal: int  # n, the modal coordinates (the state's first 2n entries are η, η̇)


def _groups(omega2: np.ndarray, blocks: np.ndarray) -> tuple[list, set]:
    """The mode groups that may enter ``A`` whole (lists of mode indices) and the rigid modes."""
    n = omega2.shape[0]
    scale = max(float(np.max(np.abs(omega2))) if n else 0.0, 1.0)
    rigid = {i for i in range(n) if abs(omega2[i]) <= RIGID * scale}
    in_block = np.zeros(n, dtype=bool)
    groups = []
    for start, end in blocks:
        in_block[start:end] = True
        modes = list(range(start, end))
        if len(modes) > MAX_DENSE_BLOCK:
            groups.extend([i] for i in modes)
        else:
            groups.append(modes)
    groups.extend([i] for i in range(n) if not in_block[i])
    return groups, rigid


def _block_matrix(stiffness, damping, modes, diagonal: bool) -> np.ndarray:
    """[[0, I], [−K, −D]] on ``modes`` (their diagonals only when ``diagonal``)."""
    k = len(modes)
    index = np.ix_(modes, modes)
    kb, db = stiffness[index], damping[index]
    if diagonal:
        kb, db = np.diag(np.diag(kb)), np.diag(np.diag(db))
    return np.block([[np.zeros((k, k)), np.eye(k)], [-kb, -db]])


def _eigen(matrix: np.ndarray):
    lam, vectors = np.linalg.eig(matrix)
    condition = np.linalg.cond(vectors)
    if not np.isfinite(condition) or condition > MAX_CONDITION:
        return None
    return lam, vectors, np.linalg.inv(vectors)


def linear_modal_part(omega2: np.ndarray, damping: np.ndarray, blocks: np.ndarray, state_size: int,
                      stiffness: np.ndarray | None = None) -> ModalEigen:
    """``A`` diagonalised (module docstring) from the signed ``ω²`` [1/s²] (n,), the damping ``D`` [1/s] (n, n)
    and its blocks ``[start, end)`` (:func:`~drillstring.dynamics.reduced.terms.diagonal_blocks`: every nonzero of
    ``D`` and of the stiffness off its diagonal within one), for a state of ``state_size`` ≥ 2n components;
    ``stiffness`` (n, n) in place of ``diag(ω²)`` when given (the bit law's position partials added)."""
    omega2 = np.asarray(omega2, dtype=float)
    n = omega2.shape[0]
    if stiffness is None:
        stiffness = np.diag(omega2)
    groups, rigid = _groups(omega2, np.asarray(blocks).reshape(-1, 2))
    parts, left_out = [], []
    for modes in groups:
        found = _eigen(_block_matrix(stiffness, damping, modes, diagonal=False))
        slow = found is not None and len(modes) > 1 and np.max(np.abs(found[0])) < SLOW_BLOCK_RATE
        if found is not None and not slow:
            parts.append((modes, *found))
            continue
        rest = [i for i in modes if i not in rigid]
        if not slow and len(rest) < len(modes):  # ill-conditioned: whole without its rigid modes
            found = _eigen(_block_matrix(stiffness, damping, rest, diagonal=False)) if rest else None
            if found is not None or not rest:
                left_out.extend(i for i in modes if i in rigid)
                if found is not None:
                    parts.append((rest, *found))
                continue
        for i in modes:  # by its diagonal (slow, or ill-conditioned): mode by mode
            single = _eigen(_block_matrix(stiffness, damping, [i], diagonal=True))
            if single is None:
                left_out.append(i)
            else:
                parts.append(([i], *single))
    lam_all, weight_all, rows, mode_list, offsets, v_re, v_im, w_re, w_im = [], [], [], [], [], [], [], [], []
    offset = 0
    for modes, lam, vectors, inverse in parts:
        keep = [e for e in range(lam.shape[0]) if lam[e].imag >= 0.0]
        weights = np.array([1.0 if lam[e].imag == 0.0 else 2.0 for e in keep])
        e0 = len(lam_all)
        lam_all.extend(lam[keep])
        weight_all.extend(weights)
        rows.append((len(mode_list), len(modes), e0, e0 + len(keep)))
        mode_list.extend(modes)
        offsets.append(offset)
        v = vectors[:, keep] * weights[None, :]  # (2k, ne)
        w = inverse[keep, :]  # (ne, 2k)
        v_re.append(v.real.ravel())
        v_im.append(v.imag.ravel())
        w_re.append(w.real.ravel())
        w_im.append(w.imag.ravel())
        offset += v.size
    free = sorted([i for i in left_out] + [n + i for i in left_out]) + list(range(2 * n, state_size))
    flat = (lambda parts: np.ascontiguousarray(np.concatenate(parts)) if parts else np.zeros(0))
    return ModalEigen(
        lam=np.array(lam_all, dtype=np.complex128), weight=np.array(weight_all, dtype=float),
        blocks=np.array(rows, dtype=np.int64).reshape(-1, 4), modes=np.array(mode_list, dtype=np.int64),
        offsets=np.array(offsets, dtype=np.int64), v_re=flat(v_re), v_im=flat(v_im), w_re=flat(w_re),
        w_im=flat(w_im), free=np.array(free, dtype=np.int64), n_modal=int(n))


class ExponentialStep(NamedTuple):
    """The compiled loop's data of an exponential Runge–Kutta step: the pair, the diagonalised ``A``
    (:class:`ModalEigen`, empty until :func:`prepare` reads the model's data) and the step's buffers."""

    c: np.ndarray  # (s,)
    alpha: np.ndarray  # (s, s, K)
    beta: np.ndarray  # (s, K)
    error_weights: np.ndarray  # (s, K) beta − beta_hat
    a_zero: np.ndarray  # (s, s) a_ij(0), for the states outside A
    b_zero: np.ndarray  # (s,)
    e_zero: np.ndarray  # (s,) (b − b̂)(0)
    nodes: np.ndarray  # (q,) the distinct arguments' factors: c_i > 0, then 1
    node_of: np.ndarray  # (s + 1,) int64: the row of nodes of stage i (entry s: the whole step)
    eigen: ModalEigen
    phi: np.ndarray  # (q, K, m) complex: φ_k(nodes[r] h λ_e)
    z: np.ndarray  # (s + 2, m) complex: Z_i (row 0: z_n), then the new z and the error's
    nt: np.ndarray  # (s, m) complex: Ñ_i
    k: np.ndarray  # (s, n) f(Y_i)
    f_new: np.ndarray  # (n,) f at the candidate
    local: np.ndarray  # (n,) scratch: one block's physical entries
    delta: np.ndarray  # (n,) (y_{n+1} − y_n)/h of the last attempt
    memo: np.ndarray  # (1,) the step size of the φ table [s] (NaN: none)
    order: float
    dense: np.ndarray  # (3, 3) HERMITE
    dense_stages: np.ndarray  # (3, n): f_n, (y_{n+1} − y_n)/h, f_{n+1} of the last accepted step


def _zero_weights(tableau: ExponentialTableau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    inverse_factorials = np.array([1.0 / math.factorial(k) for k in range(tableau.n_phi)])
    return tableau.alpha @ inverse_factorials, tableau.beta @ inverse_factorials, \
        tableau.error_weights @ inverse_factorials


def allocate(tableau: ExponentialTableau, n: int, eigen: ModalEigen | None = None) -> ExponentialStep:
    """The step's data for ``tableau`` and a state of ``n`` components; without ``eigen`` (the model's, set by
    :func:`prepare`) every state is outside ``A`` (the step is then the explicit method at ``Z = 0``)."""
    if eigen is None:
        eigen = ModalEigen(np.zeros(0, dtype=np.complex128), np.zeros(0), np.zeros((0, 4), dtype=np.int64),
                           np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0),
                           np.zeros(0), np.zeros(0), np.arange(n, dtype=np.int64), 0)
    s, count, m = tableau.n_stages, tableau.n_phi, eigen.lam.shape[0]
    positive = sorted({float(ci) for ci in tableau.c[1:] if ci > 0.0} - {1.0}) + [1.0]
    node_of = np.array([positive.index(float(ci)) if ci > 0.0 else 0 for ci in tableau.c]
                       + [len(positive) - 1], dtype=np.int64)
    a0, b0, e0 = _zero_weights(tableau)
    c = np.ascontiguousarray
    return ExponentialStep(
        c=c(tableau.c), alpha=c(tableau.alpha), beta=c(tableau.beta), error_weights=c(tableau.error_weights),
        a_zero=c(a0), b_zero=c(b0), e_zero=c(e0), nodes=np.array(positive), node_of=node_of, eigen=eigen,
        phi=np.zeros((len(positive), count, m), dtype=np.complex128), z=np.zeros((s + 2, m), dtype=np.complex128),
        nt=np.zeros((s, m), dtype=np.complex128), k=np.zeros((s, n)), f_new=np.zeros(n), local=np.zeros(n),
        delta=np.zeros(n),
        memo=np.array([math.nan]), order=float(tableau.controller_order), dense=HERMITE.copy(),
        dense_stages=np.zeros((3, n)))


_EIGEN_CACHE: dict = {}  # key -> (the model's arrays, ModalEigen): the arrays kept alive with it


@njit(cache=True)
def _law_partials(rhs_data, t, y, shapes, partials):
    """The bit law's (and a downhole motor's) partial derivatives at ``(t, y)`` and the rows they act along
    (:func:`~drillstring.dynamics.rom.stiff_part`, the implicit step's own)."""
    stiff_part(rhs_data, t, y, shapes, partials, np.empty(y.shape[0]))


def bit_law_linearisation(rhs_data, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bit–rock law's (and a downhole motor's) linear part at the state ``y`` at ``t`` [s], as modal
    stiffness and damping ``(K_law, D_law)`` (n, n) [1/s², 1/s] to add to ``diag(ω²)`` and ``D``: with the
    bit's axial and torsional rows ``b_u``, ``b_t``, the partials ``P`` of (force, torque) in (u̇, θ̇, u)
    (:func:`~drillstring.dynamics.rom.stiff_part`) and the motor's ``m``, ``dT/dω_m``:
    ``D_law = −[b_u b_t] P[:, :2] [b_u b_t]ᵀ − m (dT/dω_m) mᵀ``, ``K_law = −[b_u b_t] P[:, 2] b_uᵀ``
    (the right-hand side's ``η̈ = … − K η − D η̇``)."""
    d = rhs_data.rhs if isinstance(rhs_data, FullModelData) else rhs_data
    n = d.omega2.shape[0]
    shapes, partials = np.zeros((3, n)), np.zeros((3, 3))
    _law_partials(rhs_data, float(t), np.ascontiguousarray(y, dtype=float), shapes, partials)
    if not np.all(np.isfinite(partials)):
        return np.zeros((n, n)), np.zeros((n, n))
    rows = shapes[:2].T  # (n, 2): b_u, b_t
    damping = -(rows @ partials[:2, :2] @ rows.T) - partials[2, 0] * np.outer(shapes[2], shapes[2])
    stiffness = -np.outer(rows @ partials[:2, 2], shapes[0])
    return stiffness, damping


def prepare(step: ExponentialStep, rhs_data, t: float | None = None, y: np.ndarray | None = None) -> ExponentialStep:
    """``step`` with the linear part of the model whose right-hand-side data is ``rhs_data`` (case 2 or
    case 1) diagonalised (:func:`linear_modal_part`): the modal part, and with :data:`LINEARISED_LAW` and a state
    ``y`` at ``t`` [s] (the run's start) the bit law's linearisation there (:func:`bit_law_linearisation`);
    cached for the model's arrays and the linearisation's values."""
    d = rhs_data.rhs if isinstance(rhs_data, FullModelData) else rhs_data
    n_state = step.k.shape[1]
    damping = np.asarray(d.damping_t).T
    stiffness = np.diag(np.asarray(d.omega2, dtype=float))
    if LINEARISED_LAW and y is not None:
        law_stiffness, law_damping = bit_law_linearisation(rhs_data, 0.0 if t is None else t, y)
        stiffness, damping = stiffness + law_stiffness, damping + law_damping
    key = (id(d.omega2), id(d.damping_t), n_state, stiffness.tobytes(), damping.tobytes())
    hit = _EIGEN_CACHE.get(key)
    if hit is None or hit[0] is not d.omega2 or hit[1] is not d.damping_t:
        if len(_EIGEN_CACHE) > 16:
            _EIGEN_CACHE.clear()
        pattern = (damping != 0.0) | (stiffness - np.diag(np.diag(stiffness)) != 0.0)
        blocks = diagonal_blocks(pattern.astype(float) + np.eye(pattern.shape[0]) * 0.0)
        eigen = linear_modal_part(d.omega2, damping, blocks, n_state, stiffness)
        hit = _EIGEN_CACHE[key] = (d.omega2, d.damping_t, eigen)
    m = hit[2].lam.shape[0]
    return step._replace(eigen=hit[2], phi=np.zeros((step.nodes.shape[0], step.alpha.shape[2], m), np.complex128),
                         z=np.zeros((step.z.shape[0], m), np.complex128), nt=np.zeros((step.nt.shape[0], m),
                                                                                        np.complex128),
                         memo=np.array([math.nan]))


@njit(cache=True)
def _phi_row(z, out):
    """φ_0(z) … φ_{K−1}(z) into ``out`` (K,): the Taylor series of φ_{K−1} (its terms summed until they fall
    below 1e-17 of the first) and the downward recurrence ``φ_{k−1} = z φ_k + 1/(k − 1)!`` for |z| below the
    series radius, else ``e^z`` and the upward recurrence
    (:func:`~drillstring.dynamics.exponential_rk.phi_functions`)."""
    count = out.shape[0]
    top = count - 1
    size = abs(z)
    if size < _SERIES_RADIUS:
        first = 1.0  # 1/top!
        for j in range(2, top + 1):
            first /= j
        terms = 1
        bound = first
        while terms < _SERIES_TERMS and bound > 1e-17 * first:
            bound *= size / (terms + top)
            terms += 1
        coefficient = first
        for j in range(1, terms):
            coefficient /= j + top
        acc = 0.0 + 0.0j
        for j in range(terms - 1, -1, -1):  # Σ_j z^j/(j + top)!, Horner from the last term
            acc = acc * z + coefficient
            coefficient *= j + top
        out[top] = acc
        inverse = first * top if top > 0 else 1.0  # 1/(top − 1)!
        for k in range(top, 0, -1):
            out[k - 1] = z * out[k] + inverse
            if k - 1 > 0:
                inverse *= k - 1
    else:
        out[0] = np.exp(z)
        inverse = 1.0
        for k in range(1, count):
            out[k] = (out[k - 1] - inverse) / z
            inverse /= k


@njit(cache=True)
def _phi_table(data, h):
    """The table φ_k(nodes[r] h λ_e) for the step ``h`` [s], kept while ``h`` is that of the last table."""
    if data.memo[0] == h:
        return
    lam, phi = data.eigen.lam, data.phi
    for r in range(data.nodes.shape[0]):
        scale = data.nodes[r] * h
        for e in range(lam.shape[0]):
            _phi_row(scale * lam[e], phi[r, :, e])
    data.memo[0] = h


@njit(cache=True)
def _to_eigen(eigen, x, n, local, out):
    """out = V⁻¹ x block by block (the kept rows), x a physical state (its η and η̇ entries are read)."""
    blocks, modes = eigen.blocks, eigen.modes
    for b in range(blocks.shape[0]):
        first, k, e0, e1 = blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3]
        width = 2 * k
        for p in range(k):
            local[p] = x[modes[first + p]]
            local[k + p] = x[n + modes[first + p]]
        offset = eigen.offsets[b]
        for e in range(e0, e1):
            row = offset + (e - e0) * width
            re = 0.0
            im = 0.0
            for p in range(width):
                re += eigen.w_re[row + p] * local[p]
                im += eigen.w_im[row + p] * local[p]
            out[e] = complex(re, im)


@njit(cache=True)
def _from_eigen(eigen, z, n, out):
    """out[η, η̇ of A's modes] = Re(V z) (weights included in V); the other entries untouched."""
    blocks, modes = eigen.blocks, eigen.modes
    for b in range(blocks.shape[0]):
        first, k, e0, e1 = blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3]
        ne = e1 - e0
        offset = eigen.offsets[b]
        for p in range(2 * k):
            row = offset + p * ne
            acc = 0.0
            for e in range(ne):
                value = z[e0 + e]
                acc += eigen.v_re[row + e] * value.real - eigen.v_im[row + e] * value.imag
            mode = modes[first + p] if p < k else n + modes[first + p - k]
            out[mode] = acc


@njit
def attempt(data, rhs_data, t, h, y, f, y_new, err):
    """Stages from ``f`` (the first), the candidate ``y_new``, the error estimate ``err`` and ``f`` at the
    candidate (kept for the dense output); stops at the first non-finite stage. Returns (evaluations, finite)."""
    eigen = data.eigen
    lam, z, nt, k, phi = eigen.lam, data.z, data.nt, data.k, data.phi
    alpha, node_of = data.alpha, data.node_of
    n_state = y.shape[0]
    n = eigen.n_modal
    s = data.c.shape[0]
    count = alpha.shape[2]
    m = lam.shape[0]
    free = eigen.free
    _phi_table(data, h)
    for j in range(n_state):
        k[0, j] = f[j]
    _to_eigen(eigen, y, n, data.local, z[0])
    _to_eigen(eigen, f, n, data.local, nt[0])
    for e in range(m):
        nt[0, e] -= lam[e] * z[0, e]
    for i in range(1, s):
        r = node_of[i]
        for e in range(m):
            acc = phi[r, 0, e] * z[0, e]
            for j in range(i):
                a = 0.0 + 0.0j
                for q in range(1, count):
                    a += alpha[i, j, q] * phi[r, q, e]
                acc += h * a * nt[j, e]
            z[i, e] = acc
        _from_eigen(eigen, z[i], n, y_new)
        for x in range(free.shape[0]):
            j = free[x]
            acc = y[j]
            for q in range(i):
                acc += h * data.a_zero[i, q] * k[q, j]
            y_new[j] = acc
        evaluate_rhs(rhs_data, t + data.c[i] * h, y_new, k[i])
        for j in range(n_state):
            if not math.isfinite(k[i, j]):
                return i, False
        _to_eigen(eigen, k[i], n, data.local, nt[i])
        for e in range(m):
            nt[i, e] -= lam[e] * z[i, e]
    # the solution and the error estimate, in the eigen-coordinates, then back
    r = node_of[s]
    beta, ew = data.beta, data.error_weights
    for e in range(m):
        value = phi[r, 0, e] * z[0, e]
        error = 0.0 + 0.0j
        for j in range(s):
            bw = 0.0 + 0.0j
            ewj = 0.0 + 0.0j
            for q in range(1, count):
                bw += beta[j, q] * phi[r, q, e]
                ewj += ew[j, q] * phi[r, q, e]
            value += h * bw * nt[j, e]
            error += h * ewj * nt[j, e]
        z[s, e] = value
        z[s + 1, e] = error
    _from_eigen(eigen, z[s], n, y_new)
    _from_eigen(eigen, z[s + 1], n, err)
    for x in range(free.shape[0]):
        j = free[x]
        value = y[j]
        error = 0.0
        for q in range(s):
            value += h * data.b_zero[q] * k[q, j]
            error += h * data.e_zero[q] * k[q, j]
        y_new[j] = value
        err[j] = error
    for j in range(n_state):
        if not math.isfinite(y_new[j]):
            return s - 1, False
    evaluate_rhs(rhs_data, t + h, y_new, data.f_new)
    for j in range(n_state):
        if not math.isfinite(data.f_new[j]):
            return s, False
    # (y_{n+1} − y_n)/h for the dense output, while y_n is at hand
    for j in range(n_state):
        data.delta[j] = (y_new[j] - y[j]) / h
    return s, True


@njit
def accept(data, y, f):
    """Keep ``f_n``, ``(y_{n+1} − y_n)/h`` and ``f_{n+1}`` for the Hermite dense output and set ``f`` to
    ``f_{n+1}`` (the attempt evaluated it): returns True."""
    kept = data.dense_stages
    n = y.shape[0]
    for j in range(n):
        kept[0, j] = f[j]
        kept[1, j] = data.delta[j]
        kept[2, j] = data.f_new[j]
        f[j] = data.f_new[j]
    return True


def reference_step(tableau: ExponentialTableau, matrix: np.ndarray, rhs, t: float, h: float, y: np.ndarray,
                   f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One step of ``tableau`` for ``y' = rhs(t, y)`` split with the dense linear part ``matrix`` (``N = rhs −
    matrix·y``), in NumPy: the φ functions of ``h·matrix`` from its eigendecomposition (a diagonalisable
    ``matrix``). Returns ``(y_new, err)``."""
    lam, vectors = np.linalg.eig(np.asarray(matrix, dtype=float))
    inverse = np.linalg.inv(vectors)

    def phi_of(factor):
        values = phi_functions(factor * h * lam, tableau.n_phi)  # (K, m)
        return [lambda x, v=v: (vectors @ (v * (inverse @ x))) for v in values]

    s = tableau.n_stages
    at_nodes = [phi_of(ci) for ci in tableau.c]
    whole = phi_of(1.0)
    stages = [np.asarray(y, dtype=float)]
    rests = [np.asarray(f, dtype=float) - matrix @ y]
    for i in range(1, s):
        value = at_nodes[i][0](y)
        for j in range(i):
            for q in range(1, tableau.n_phi):
                if tableau.alpha[i, j, q] != 0.0:
                    value = value + h * tableau.alpha[i, j, q] * at_nodes[i][q](rests[j])
        value = value.real
        stages.append(value)
        rests.append(np.asarray(rhs(t + tableau.c[i] * h, value), dtype=float) - matrix @ value)
    y_new = whole[0](y)
    err = np.zeros_like(y_new)
    for j in range(s):
        for q in range(1, tableau.n_phi):
            if tableau.beta[j, q] != 0.0:
                y_new = y_new + h * tableau.beta[j, q] * whole[q](rests[j])
            if tableau.error_weights[j, q] != 0.0:
                err = err + h * tableau.error_weights[j, q] * whole[q](rests[j])
    return y_new.real, err.real


KIND = register(StepKind(method=ExponentialTableau, data=ExponentialStep, allocate=allocate, attempt=attempt,
                         accept=accept, prepare=prepare))
