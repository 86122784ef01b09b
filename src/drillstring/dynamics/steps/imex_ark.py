"""The implicit–explicit additive Runge–Kutta step (an :class:`~drillstring.dynamics.additive_rk.AdditiveTableau`):
the stiff part of the reduced model implicit, the rest explicit, for the compiled loop
(:mod:`drillstring.dynamics.steps.kinds`).

The split. At the start of each step attempt the right-hand side ``f`` is split exactly as ``f = f_E + f_I``
with a *linear* implicit part ``f_I(Y) = J (Y − y_n)`` and ``f_E = f − f_I``: whatever ``J``, the method keeps
its order (an additive method of the pair's order, its coupling conditions included), and ``J`` only decides
which rates are damped implicitly. ``J`` is the reduced model's linear part and its stiff part
(:func:`~drillstring.dynamics.rom.stiff_part`):

- the kinematics ``η' = η̇`` and the linear modal forces ``−Ω²η − Dη̇`` (every mode, ``D`` block-diagonal by
  its damping blocks; a block of more than :data:`MAX_DENSE_BLOCK` modes, or slow for the step
  (:data:`DENSE_BLOCK_RATE`), by its diagonal): the high attachment modes of the truncation-corrected basis
  are stiff, and a stiff term driven by an *explicit* slow one suffers order reduction (the explicit part would carry the stiff
  rate times the slow motion over the step, as on the Prothero–Robinson problem: measured, with only the bit
  law implicit the reference realization needed 3× more steps for the same tolerance);
- the bit–rock law, ``J_bit = U G Vᵀ`` of rank ≤ 3: its force and torque act along the bit's axial and
  torsional mode-shape rows ``b_u``, ``b_t`` (``U``) and depend on the bit's velocity ``b_uᵀη̇``, speed
  ``b_tᵀη̇`` and position ``b_uᵀη`` (``Vᵀ``; a delayed law's depth of cut moves with the position), ``G``
  (2 × 3) the law's partial derivatives from its own compiled Jacobian (``jacobian_kernel``, the one its
  ``jacobian_at`` calls; :func:`~drillstring.forces.registry.bit_law_jacobian`), at each attempt.
  Measured (``benchmarks/stiff_part_survey.py``): −945…−1180 1/s on ``reference`` (the axial dashpot), up to
  −1e5 1/s on ``aarsnes2019`` (the wear flats' dashpot, the regularised stick);
- a downhole motor's torque slope across its rotor, ``m (dT/dω_m) mᵀ`` of rank 1: the rotor's relative
  torsional row ``m`` (:attr:`~drillstring.dynamics.rom.ReducedOrderModel.motor_shapes`) is a fourth column of
  ``V`` and a third of ``U``, ``dT/dω_m`` from the registered motor's compiled Jacobian (about
  −1530 1/s on the 1.2 kg·m² below the rotor of the ``motor`` case, the model's fastest rate there).

What stays explicit: the contact forces, the turning loads, the top drive's controller, the hook-load ramp,
case 1's kinetic- and strain-energy forces and the law's curvature over a step.

Each implicit stage solves ``(I − hγJ) z = r``: with ``A = I − hγJ_linear``, ``A z = r`` is
``S z_v = r_v − hγΩ² r_p``, ``z_p = r_p + hγ z_v`` with ``S = I + hγD + (hγ)²Ω²`` LU-factored block by block
(the damping blocks, 10–20 modes each) once per attempt; the bit law by the Sherman–Morrison–Woodbury formula,
``z = A⁻¹r + hγ A⁻¹U G w`` with ``(I₄ − hγ (VᵀA⁻¹U) G) w = VᵀA⁻¹r`` (4 × 4; ``U`` n × 3, ``G`` 3 × 4, the
motor's column not solved without a motor). No dense LU of the state.
The stages are ``Y_i = y_n + z_i`` with ``r_i = h Σ_{j<i} (a^E_ij f_E(Y_j) + a^I_ij f_I(Y_j))``; since the pair
shares ``b``, ``b̂`` and ``b*(θ)``, the solution ``y_n + h Σ b_i f(Y_i)``, the error estimate and the dense
output need only ``f(Y_i)`` (kept as the dense stages, so the observations and the delayed bit history are
recorded as with an explicit pair). The error estimate ``h Σ (b_i − b̂_i) f(Y_i)`` is filtered by
``(I − hγJ)⁻¹`` (Shampine's filter, Hairer & Wanner, *Solving ODEs II*, §IV.8): unfiltered, its stiff
components (the bit's velocity) set steps 10–30× shorter on ``aarsnes2019``. The explicit part's last stage is
not at the new state (it is not stiffly accurate), so the loop evaluates ``f`` there: an accepted step costs
``s`` right-hand sides (4 for ARK3(2)4L, 6 for ARK4(3)6L) and one Jacobian (one call of the law's compiled
Jacobian and O(n) work besides the block factorisation).

:class:`ReferenceStep` is the NumPy reference of the same step for a right-hand side in Python, with a dense
``J``: ``rhs.stiff_jacobian(t, y)`` when the right-hand side offers it, else forward differences of ``rhs``
(``len(y)`` evaluations, counted); it solves with a dense LU and does not filter the error estimate.
``tests/dynamics/test_imex_step.py`` checks its order of convergence on problems with known solutions, the
compiled stiff part against the law's closed-form partials, and the compiled step against DOPRI5.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from drillstring.dynamics.additive_rk import AdditiveTableau
from drillstring.dynamics.rom import evaluate_rhs, stiff_part
from drillstring.dynamics.steps.kinds import StepKind, register

#: Damping blocks larger than this many modes enter ``J`` by their diagonal only (a dense block's LU costs
#: k³/3 per attempt: the contact case's lateral block, coupled by the fluid's Coriolis damping, has 166 modes
#: and made a step cost 3× DOPRI5's; its off-diagonal damping is not stiff).
MAX_DENSE_BLOCK = 32
#: A damping block enters ``J`` whole only where it is fast for the step: ``h (max ω_i + max_i Σ_j |D_ij|)``
#: above this [-]; a slow block (the reference case's lateral ones) by its diagonal, which costs no LU.
DENSE_BLOCK_RATE = 0.05

# indices of the memo: the number of modal coordinates, how many Jacobians were computed
_MODES, _JACOBIANS = 0, 1


class ImexStep(NamedTuple):
    """The compiled loop's data of an IMEX additive Runge–Kutta step: the pair and the step's buffers."""

    a_explicit: np.ndarray  # (s, s)
    a_implicit: np.ndarray  # (s, s)
    gamma: float
    c: np.ndarray  # (s,)
    b: np.ndarray  # (s,)
    error_weights: np.ndarray  # (s,) b − b_hat
    dense: np.ndarray  # (s, p)
    order: float  # q, order of the error estimate
    k: np.ndarray  # (s, n) f(Y_i) of the step being attempted
    k_implicit: np.ndarray  # (s, n) f_I(Y_i) = J (Y_i − y_n)
    z: np.ndarray  # (n,) scratch: the stage increment
    r: np.ndarray  # (n,) scratch: the stage's right side
    v: np.ndarray  # (n,) scratch: a velocity-sized vector
    shapes: np.ndarray  # (3, n) the bit's axial and torsional rows, the motor's (first n_modal entries)
    partials: np.ndarray  # (3, 3) the bit law's partial derivatives; [2, 0] the motor's dT/dω_m (G)
    base: np.ndarray  # (n, n) S = I + hγD + (hγ)²Ω², LU-factored block by block (damping blocks)
    pivots: np.ndarray  # (n,) int64, the blocks' row pivots
    dense_blocks: np.ndarray  # (n,) bool, per damping block: entered whole (factored) or by its diagonal
    columns: np.ndarray  # (3, n) S⁻¹ b_u, S⁻¹ b_t, S⁻¹ m (the velocity parts of A⁻¹U)
    small: np.ndarray  # (4, 4) (I − hγ (VᵀA⁻¹U) G)⁻¹
    woodbury: np.ndarray  # (4, 4) scratch: I − hγ (VᵀA⁻¹U) G, before its inversion
    products: np.ndarray  # (4, 3) scratch: P = VᵀA⁻¹U
    law_matrix: np.ndarray  # (3, 4) scratch: G
    covered: np.ndarray  # (n,) bool: the modal coordinates inside a damping block (set by _factor)
    memo: np.ndarray  # (2,) the number of modal coordinates, Jacobians computed
    dense_stages: np.ndarray  # (s, n) f(Y_i) of the last accepted step (dense output)

    @property
    def n_jacobians(self) -> int:
        """The stiff parts computed so far (one per step attempt)."""
        return int(self.memo[_JACOBIANS])


def allocate(tableau: AdditiveTableau, n: int) -> ImexStep:
    """The step's data for ``tableau`` and a state of ``n`` components."""
    c = np.ascontiguousarray
    s = tableau.n_stages
    return ImexStep(
        a_explicit=c(tableau.a_explicit), a_implicit=c(tableau.a_implicit), gamma=float(tableau.gamma),
        c=c(tableau.c), b=c(tableau.b), error_weights=c(tableau.error_weights), dense=c(tableau.dense),
        order=float(tableau.controller_order), k=np.zeros((s, n)), k_implicit=np.zeros((s, n)), z=np.zeros(n),
        r=np.zeros(n), v=np.zeros(n), shapes=np.zeros((3, n)), partials=np.zeros((3, 3)), base=np.zeros((n, n)),
        pivots=np.zeros(n, dtype=np.int64), dense_blocks=np.zeros(n, dtype=np.bool_), columns=np.zeros((3, n)),
        small=np.zeros((4, 4)), woodbury=np.zeros((4, 4)), products=np.zeros((4, 3)), law_matrix=np.zeros((3, 4)),
        covered=np.zeros(n, dtype=np.bool_), memo=np.zeros(2),
        dense_stages=np.zeros((s, n)))


@njit(cache=True)
def _invert_small(m, out):
    """out = m⁻¹ for a small square matrix (Gauss–Jordan with partial pivoting; ``m`` is overwritten);
    returns False when m is singular or not finite."""
    k = m.shape[0]
    for i in range(k):
        for j in range(k):
            out[i, j] = 1.0 if i == j else 0.0
    for col in range(k):
        best = col
        for row in range(col + 1, k):
            if abs(m[row, col]) > abs(m[best, col]):
                best = row
        pivot = m[best, col]
        if pivot == 0.0 or not math.isfinite(pivot):
            return False
        for j in range(k):
            m[col, j], m[best, j] = m[best, j], m[col, j]
            out[col, j], out[best, j] = out[best, j], out[col, j]
        for j in range(k):
            m[col, j] /= pivot
            out[col, j] /= pivot
        for row in range(k):
            if row != col and m[row, col] != 0.0:
                factor = m[row, col]
                for j in range(k):
                    m[row, j] -= factor * m[col, j]
                    out[row, j] -= factor * out[col, j]
    return True


@njit(cache=True)
def _lu_block(a, pivots, start, end):
    """LU factorisation with partial pivoting of ``a[start:end, start:end]`` in place (pivots: the row
    swapped with each row, absolute indices). Returns False when a pivot is 0 or not finite."""
    for col in range(start, end):
        best = col
        for row in range(col + 1, end):
            if abs(a[row, col]) > abs(a[best, col]):
                best = row
        pivots[col] = best
        if best != col:
            for j in range(start, end):
                a[col, j], a[best, j] = a[best, j], a[col, j]
        pivot = a[col, col]
        if pivot == 0.0 or not math.isfinite(pivot):
            return False
        for row in range(col + 1, end):
            factor = a[row, col] / pivot
            a[row, col] = factor
            if factor != 0.0:
                for j in range(col + 1, end):
                    a[row, j] -= factor * a[col, j]
    return True


@njit(cache=True)
def _base_solve(data, blocks, nm, x):
    """x ← S⁻¹ x for the velocity-sized vector ``x`` (S factored by :func:`_factor`, which also marks the
    coordinates inside a damping block in ``data.covered``)."""
    a, pivots, covered = data.base, data.pivots, data.covered
    inside = 0
    for b in range(blocks.shape[0]):
        inside += blocks[b, 1] - blocks[b, 0]
    if inside < nm:  # the diagonal entries outside every damping block
        for i in range(nm):
            if not covered[i]:
                x[i] /= a[i, i]
    for b in range(blocks.shape[0]):
        start, end = blocks[b, 0], blocks[b, 1]
        if not data.dense_blocks[b]:
            for i in range(start, end):
                x[i] /= a[i, i]
            continue
        for i in range(start, end):
            p = pivots[i]
            if p != i:
                x[i], x[p] = x[p], x[i]
        for i in range(start, end):
            acc = x[i]
            for j in range(start, i):
                acc -= a[i, j] * x[j]
            x[i] = acc
        for i in range(end - 1, start - 1, -1):
            acc = x[i]
            for j in range(i + 1, end):
                acc -= a[i, j] * x[j]
            x[i] = acc / a[i, i]


@njit(cache=True)
def _factor(data, h, omega2, damping_t, blocks):
    """Factor ``S = I + hγD + (hγ)²Ω²`` by damping blocks, then ``A⁻¹U`` and the 4 × 4 Woodbury matrix's
    inverse for the step ``h``. Returns False when either is singular. Allocates nothing (its small matrices
    are the step's scratch), so the loop runs without reference counting (``StepKind.allocates``)."""
    hg = h * data.gamma
    nm = omega2.shape[0]
    a, g, cols, covered = data.base, data.partials, data.columns, data.covered
    for i in range(nm):
        a[i, i] = 1.0 + hg * hg * omega2[i]
        covered[i] = False
    for b in range(blocks.shape[0]):
        for i in range(blocks[b, 0], blocks[b, 1]):
            covered[i] = True
    for b in range(blocks.shape[0]):
        start, end = blocks[b, 0], blocks[b, 1]
        rate = 0.0
        if end - start <= MAX_DENSE_BLOCK:  # (a large block is never whole: no need for its rate)
            for i in range(start, end):
                row = 0.0
                for j in range(start, end):
                    row += abs(damping_t[j, i])
                rate = max(rate, math.sqrt(max(omega2[i], 0.0)) + row)
        data.dense_blocks[b] = h * rate > DENSE_BLOCK_RATE
        if not data.dense_blocks[b]:
            for i in range(start, end):
                a[i, i] += hg * damping_t[i, i]
            continue
        for i in range(start, end):
            for j in range(start, end):
                a[i, j] = (1.0 + hg * hg * omega2[i] if i == j else 0.0) + hg * damping_t[j, i]
        if not _lu_block(a, data.pivots, start, end):
            return False
    # U = [b_u, b_t, m] (velocity rows; m the motor's, zero without one: its column is then not solved)
    rank = 3 if g[2, 0] != 0.0 else 2
    for k in range(3):
        for i in range(nm):
            cols[k, i] = data.shapes[k, i] if k < rank else 0.0
        if k < rank:
            _base_solve(data, blocks, nm, cols[k])
    # P = Vᵀ A⁻¹ U, rows: velocity along b_u, along b_t, position along b_u (A⁻¹U's position part: hγ S⁻¹ b),
    # velocity along m
    p = data.products
    for i in range(4):
        for k in range(3):
            p[i, k] = 0.0
    for k in range(rank):
        for i in range(nm):
            p[0, k] += data.shapes[0, i] * cols[k, i]
            p[1, k] += data.shapes[1, i] * cols[k, i]
            p[2, k] += hg * data.shapes[0, i] * cols[k, i]
            p[3, k] += data.shapes[2, i] * cols[k, i]
    # G (3 × 4): the bit law's force and torque in (u̇, θ̇, u), the motor's torque in ω_m = mᵀη̇
    gm = data.law_matrix
    for j in range(4):
        gm[0, j] = g[0, j] if j < 3 else 0.0
        gm[1, j] = g[1, j] if j < 3 else 0.0
        gm[2, j] = g[2, 0] if j == 3 else 0.0
    m = data.woodbury
    for i in range(4):
        for j in range(4):
            m[i, j] = 1.0 if i == j else 0.0
    for i in range(4):
        for j in range(4):
            m[i, j] -= hg * (p[i, 0] * gm[0, j] + p[i, 1] * gm[1, j] + p[i, 2] * gm[2, j])
    return _invert_small(m, data.small)


@njit(cache=True)
def _solve(data, h, omega2, blocks, r, z):
    """z = (I − hγ J)⁻¹ r (module docstring): the linear part's block solve, then Woodbury for the bit law and
    the motor."""
    hg = h * data.gamma
    nm = omega2.shape[0]
    sh, g, small, cols, x = data.shapes, data.partials, data.small, data.columns, data.v
    for j in range(r.shape[0]):
        z[j] = r[j]
    for i in range(nm):
        x[i] = r[nm + i] - hg * omega2[i] * r[i]
    _base_solve(data, blocks, nm, x)
    v0 = 0.0
    v1 = 0.0
    v2 = 0.0
    v3 = 0.0
    for i in range(nm):
        z[nm + i] = x[i]
        z[i] = r[i] + hg * x[i]
        v0 += sh[0, i] * z[nm + i]
        v1 += sh[1, i] * z[nm + i]
        v2 += sh[0, i] * z[i]
        v3 += sh[2, i] * z[nm + i]
    w0 = small[0, 0] * v0 + small[0, 1] * v1 + small[0, 2] * v2 + small[0, 3] * v3
    w1 = small[1, 0] * v0 + small[1, 1] * v1 + small[1, 2] * v2 + small[1, 3] * v3
    w2 = small[2, 0] * v0 + small[2, 1] * v1 + small[2, 2] * v2 + small[2, 3] * v3
    w3 = small[3, 0] * v0 + small[3, 1] * v1 + small[3, 2] * v2 + small[3, 3] * v3
    gw0 = hg * (g[0, 0] * w0 + g[0, 1] * w1 + g[0, 2] * w2)
    gw1 = hg * (g[1, 0] * w0 + g[1, 1] * w1 + g[1, 2] * w2)
    gw2 = hg * g[2, 0] * w3
    for i in range(nm):
        column = gw0 * cols[0, i] + gw1 * cols[1, i] + gw2 * cols[2, i]
        z[nm + i] += column
        z[i] += hg * column


@njit
def attempt(data, rhs_data, t, h, y, f, y_new, err):
    """Stages from ``f`` (the first), the candidate ``y_new`` and the error estimate ``err`` (filtered by
    ``(I − hγJ)⁻¹``); stops at the first stage with a non-finite value. Returns (evaluations, finite)."""
    k, ki, ae, ai, c = data.k, data.k_implicit, data.a_explicit, data.a_implicit, data.c
    n = y.shape[0]
    s = c.shape[0]
    # (data.z, free until the first stage, takes a downhole motor's state rates: not needed here)
    omega2, damping_t, blocks = stiff_part(rhs_data, t, y, data.shapes, data.partials, data.z)
    data.memo[_MODES] = omega2.shape[0]
    data.memo[_JACOBIANS] += 1.0
    for j in range(3):
        if not (math.isfinite(data.partials[0, j]) and math.isfinite(data.partials[1, j])
                and math.isfinite(data.partials[2, j])):
            return 0, False
    if not _factor(data, h, omega2, damping_t, blocks):
        return 0, False
    for j in range(n):
        k[0, j] = f[j]
        ki[0, j] = 0.0
    r = data.r
    hg = h * data.gamma
    for i in range(1, s):
        # r = h Σ_{m<i} (a^E_im f_E(Y_m) + a^I_im f_I(Y_m)), f_E = f − f_I: row by row, contiguous
        for j in range(n):
            r[j] = 0.0
        for m in range(i):
            explicit = h * ae[i, m]
            implicit = h * (ai[i, m] - ae[i, m])
            for j in range(n):
                r[j] += explicit * k[m, j] + implicit * ki[m, j]
        _solve(data, h, omega2, blocks, r, data.z)
        # f_I(Y_i) = J z = (z − r)/(hγ) from the stage equation (I − hγJ) z = r: no product with J (rounding
        # ε|f|/γ, z and r being of size h|f|; a product cost 30 % more per attempt on the reference case)
        for j in range(n):
            ki[i, j] = (data.z[j] - r[j]) / hg
        for j in range(n):
            y_new[j] = y[j] + data.z[j]
        evaluate_rhs(rhs_data, t + c[i] * h, y_new, k[i])
        for j in range(n):
            if not math.isfinite(k[i, j]):
                return i, False
    b, ew = data.b, data.error_weights
    for j in range(n):
        y_new[j] = y[j]
        r[j] = 0.0
    for m in range(s):
        weight = h * b[m]
        error = h * ew[m]
        for j in range(n):
            y_new[j] += weight * k[m, j]
            r[j] += error * k[m, j]
    # the estimate filtered by (I − hγJ)⁻¹ (Shampine; Hairer & Wanner II §IV.8): its stiff components damped
    _solve(data, h, omega2, blocks, data.r, err)
    return s - 1, True


@njit
def accept(data, y, f):
    """Keep the accepted step's f(Y_i) for its dense output; ``f`` at the new state is not known (the
    explicit part is not stiffly accurate): return False, the loop evaluates it."""
    k, kept = data.k, data.dense_stages
    for m in range(k.shape[0]):
        for j in range(k.shape[1]):
            kept[m, j] = k[m, j]
    return False


def _forward_jacobian(rhs, t: float, y: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Forward differences of ``rhs`` at ``(t, y)`` with ``f = rhs(t, y)``: (n, n)."""
    jac = np.empty((y.size, y.size), dtype=np.result_type(y, f))
    for j in range(y.size):
        step = 1e-7 * max(1.0, abs(y[j]))
        shifted = y.copy()
        shifted[j] += step
        jac[:, j] = (np.asarray(rhs(t, shifted)) - f) / step
    return jac


class ReferenceStep:
    """The NumPy reference of the IMEX step for ``tableau`` and states like ``y``, with a dense ``J``
    (module docstring): the same stages, error estimate and dense output, a dense LU per attempt."""

    def __init__(self, tableau: AdditiveTableau, y: np.ndarray) -> None:
        s = tableau.n_stages
        self.tableau = tableau
        self.order = tableau.controller_order
        self.dense = tableau.dense
        self.fsal = False
        self._k = np.empty((s, y.size), dtype=y.dtype)
        self.dense_stages = np.empty_like(self._k)
        self._jacobian: tuple[float, np.ndarray] | None = None
        self.n_jacobians = 0

    def _stiff(self, rhs, t: float, y: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, int]:
        if self._jacobian is not None and self._jacobian[0] == t:
            return self._jacobian[1], 0
        self.n_jacobians += 1
        given = getattr(rhs, "stiff_jacobian", None)
        if given is not None:
            jac, evaluations = np.asarray(given(t, y), dtype=float), 0
        else:
            jac, evaluations = _forward_jacobian(rhs, t, y, f), y.size
        self._jacobian = (t, jac)
        return jac, evaluations

    def attempt(self, rhs, t: float, h: float, y: np.ndarray, f: np.ndarray):
        """Returns ``(y_new, err, evaluations, cause)`` as :class:`~.explicit_rk.ReferenceStep` does."""
        tab = self.tableau
        k = self._k
        with np.errstate(all="ignore"):
            try:
                jac, evaluations = self._stiff(rhs, t, y, f)
                lu = np.eye(y.size) - h * tab.gamma * jac
                ki = np.zeros_like(k)
                k[0] = f
                for i in range(1, tab.n_stages):
                    r = h * (tab.a_explicit[i, :i] @ (k[:i] - ki[:i]) + tab.a_implicit[i, :i] @ ki[:i])
                    z = np.linalg.solve(lu, r)
                    ki[i] = jac @ z
                    k[i] = rhs(t + tab.c[i] * h, y + z)
                    evaluations += 1
                    if not np.all(np.isfinite(k[i])):
                        return None, None, evaluations, f"non-finite values in the right-hand side (stage {i + 1})"
            except (FloatingPointError, OverflowError, np.linalg.LinAlgError) as exc:
                return None, None, evaluations, f"{type(exc).__name__} in the stage solve: {exc}"
        return y + h * (tab.b @ k), h * (tab.error_weights @ k), evaluations, None

    def accept(self, rhs, t_new: float, y_new: np.ndarray) -> tuple[np.ndarray, int]:
        """Keep the stages for the dense output; returns ``(f(t_new, y_new), 1)``."""
        self._k, self.dense_stages = self.dense_stages, self._k
        with np.errstate(all="ignore"):
            return np.asarray(rhs(t_new, y_new), dtype=y_new.dtype), 1


KIND = register(StepKind(method=AdditiveTableau, data=ImexStep, allocate=allocate, attempt=attempt,
                         accept=accept, reference=ReferenceStep, allocates=False))
