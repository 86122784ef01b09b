"""The leading growth rates of a reduced model's families, the study's per-realization stability figures, by
blocks of the linearised state matrix.

:func:`~drillstring.dynamics.stability.family_growth_rates` solves one dense eigenproblem of the whole state
matrix (121 × 121 on ``reference``, 3.6 ms of the 5.6 ms it costs) and builds a
:class:`~drillstring.dynamics.stability.ModeStability` per root. The linearised matrix of a vertical string
about steady drilling is block-diagonal after a permutation: the lateral families are uncoupled from the axial
and torsional ones (and from each other, ``reference``: blocks of 41, 40 and 40 states), and the cost of a
dense eigenproblem grows as the cube of its size. :func:`family_growth_rates` finds the blocks (the connected
components of the matrix's nonzero pattern), solves each block's eigenproblem, and classifies the roots by
:func:`~drillstring.dynamics.stability.energy_shares`, as :func:`~drillstring.dynamics.stability.stability` does
— the family holding most of a root's modal energy, a root whose attachment modes hold
:data:`~drillstring.dynamics.stability.RESIDUAL_SHARE` of it left out — without a result object per root. The
eigenvalues of a block equal those of the whole matrix to round-off (LAPACK's order of operations differs),
so the rates agree with :func:`~drillstring.dynamics.stability.family_growth_rates` to about 1e-12 relative
(``tests/dynamics/test_growth_rates.py``); a model whose matrix is one block (random matrices that couple the
families), and a delayed bit–rock law (characteristic roots), take the whole-matrix route itself.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from drillstring.dynamics import stability
from drillstring.dynamics.rom import ReducedOrderModel

__all__ = ["family_growth_rates"]


def _block_eig(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The eigenvalues and unit eigenvectors of ``matrix`` from the eigenproblems of its diagonal blocks (the
    connected components of its nonzero pattern, after a permutation); None when it is one block."""
    pattern = matrix != 0.0
    count, labels = connected_components(csr_matrix(pattern | pattern.T), directed=False)
    if count < 2:
        return None
    size = matrix.shape[0]
    values = np.empty(size, dtype=complex)
    vectors = np.zeros((size, size), dtype=complex)
    done = 0
    for block in range(count):
        rows = np.flatnonzero(labels == block)
        own_values, own_vectors = sla.eig(matrix[np.ix_(rows, rows)])
        columns = slice(done, done + rows.size)
        values[columns] = own_values
        vectors[rows, columns] = own_vectors
        done += rows.size
    return values, vectors


def family_growth_rates(model: ReducedOrderModel) -> dict[str, float]:
    """:func:`drillstring.dynamics.stability.family_growth_rates` of ``model`` (the leading growth rate [1/s] of
    every resolved root, ``growth_rate``, and of each family's, ``{family}_growth_rate``, NaN for a family
    without roots) by blocks of the state matrix (module docstring). ValueError when there is no steady
    drilling."""
    if model.bit_rock.delayed:
        return stability.family_growth_rates(model)
    steady = stability.steady_drilling(model)
    matrix, keep = stability._informative_matrix(model, steady)
    found = _block_eig(matrix)
    if found is None:
        return stability.family_growth_rates(model)
    values, vectors = found
    full = np.zeros((model.state_size, values.size), dtype=complex)
    full[keep] = vectors
    values, shares, residual = stability.energy_shares(model, values, full)
    total = shares.sum(axis=1)
    residual_share = np.where(total > 0.0, residual / np.where(total > 0.0, total, 1.0), 0.0)
    resolved = residual_share < stability.RESIDUAL_SHARE
    if not resolved.any():
        return stability.family_growth_rates(model)  # (its error: no resolved root)
    family = np.argmax(shares, axis=1)
    growth = values.real
    out = {"growth_rate": float(growth[resolved].max())}
    for k, name in enumerate(stability.STABILITY_FAMILIES):
        own = resolved & (family == k)
        out[f"{name}_growth_rate"] = float(growth[own].max()) if own.any() else math.nan
    return out
