"""The additive Runge–Kutta pairs (drillstring.dynamics.additive_rk): order conditions with the coupling
conditions (bi-coloured trees), the embedded solutions', the continuous extensions', L-stability, and the
tableau validation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from drillstring.dynamics.additive_rk import ARK3_2_4L, ARK4_3_6L, IMEX_TABLEAUS, AdditiveTableau
from tests.dynamics.test_runge_kutta import gamma, tree_order, trees

TABLEAUS = [ARK3_2_4L, ARK4_3_6L]


def coloured(tree: tuple):
    """Every colouring of the non-root vertices of ``tree`` (children tuples) with "E" or "I": each
    coloured tree is a tuple of (colour, coloured child)."""
    options = [[(colour, sub) for colour in "EI" for sub in coloured(child)] for child in tree]
    return [tuple(choice) for choice in itertools.product(*options)]


def weights(tab: AdditiveTableau, tree: tuple) -> np.ndarray:
    """Φ_i of a coloured tree: the product over the children of (a^colour Φ(child))_i."""
    phi = np.ones(tab.n_stages)
    for colour, child in tree:
        a = tab.a_explicit if colour == "E" else tab.a_implicit
        phi = phi * (a @ weights(tab, child))
    return phi


def defect(tab: AdditiveTableau, b: np.ndarray, q: int, theta: float = 1.0) -> float:
    """The largest |Σ b_i Φ_i(τ) − θ^q/γ(τ)| over the coloured trees of order q (uncoloured γ)."""
    return max(abs(b @ weights(tab, ct) - theta**q / gamma(t)) for t in trees(q) for ct in coloured(t))


def test_colourings_count():
    # trees of order 3: the bushy one (2 children: 4 colourings) and the tall one (2 non-root vertices: 4)
    assert sum(len(coloured(t)) for t in trees(3)) == 8
    assert all(tree_order(t) == 4 for t in trees(4))


@pytest.mark.parametrize("tab", TABLEAUS, ids=lambda t: t.name)
def test_order_and_coupling_conditions(tab):
    for q in range(1, tab.order + 1):
        assert defect(tab, tab.b, q) < 1e-11, q
    assert defect(tab, tab.b, tab.order + 1) > 1e-5  # exactly of that order
    for q in range(1, tab.error_order + 1):
        assert defect(tab, tab.b_hat, q) < 1e-11, q
    assert defect(tab, tab.b_hat, tab.error_order + 1) > 1e-5
    assert IMEX_TABLEAUS[tab.name] is tab


@pytest.mark.parametrize("tab", TABLEAUS, ids=lambda t: t.name)
def test_dense_output_conditions(tab):
    """The continuous extension's order p* = number of its columns (2 for ARK3(2)4L, 3 for ARK4(3)6L):
    Σ b*_i(θ) Φ_i(τ) = θ^ρ(τ)/γ(τ) for every coloured tree with ρ ≤ p*, every θ; b*(1) = b."""
    p = tab.dense.shape[1]
    for theta in np.linspace(0.0, 1.0, 7):
        w = tab.dense @ theta ** np.arange(1, p + 1)
        for q in range(1, p + 1):
            assert defect(tab, w, q, theta) < 1e-11, (theta, q)
    w = tab.dense @ 0.5 ** np.arange(1, p + 1)
    assert defect(tab, w, p + 1, 0.5) > 1e-6


def stability(tab: AdditiveTableau, z_explicit: complex, z_implicit: complex) -> complex:
    """R(z_E, z_I) of the pair for y' = λ_E y + λ_I y: Y = 1 + (z_E A^E + z_I A^I) Y, R = 1 + (z_E + z_I) bᵀY."""
    s = tab.n_stages
    stages = np.linalg.solve(np.eye(s) - z_explicit * tab.a_explicit - z_implicit * tab.a_implicit, np.ones(s))
    return 1.0 + (z_explicit + z_implicit) * (tab.b @ stages)


@pytest.mark.parametrize("tab", TABLEAUS, ids=lambda t: t.name)
def test_implicit_part_is_l_stable(tab):
    """|R(0, z)| ≤ 1 on the imaginary axis and the left half plane's samples, R(0, z) → 0 as z → −∞
    (L-stable: a stiff decay is damped in one step, however large h λ)."""
    for z in [-1e8, -1e4, -100.0, -10.0, -1.0, 1j, 10j, 1e3j, 1e6j, -5 + 50j, -1e3 + 1e3j]:
        assert abs(stability(tab, 0.0, z)) <= 1.0 + 1e-12, z
    assert abs(stability(tab, 0.0, -1e10)) < 1e-6


def test_validation():
    t = ARK3_2_4L
    kwargs = dict(name="x", a_explicit=t.a_explicit, a_implicit=t.a_implicit, c=t.c, b=t.b, b_hat=t.b_hat,
                  order=3, error_order=2, dense=t.dense)
    AdditiveTableau(**kwargs)
    with pytest.raises(ValueError, match="strictly lower"):
        AdditiveTableau(**{**kwargs, "a_explicit": t.a_explicit + np.eye(4)})
    with pytest.raises(ValueError, match="ESDIRK"):
        bad = np.array(t.a_implicit)
        bad[2, 2] = 0.3
        AdditiveTableau(**{**kwargs, "a_implicit": bad})
    with pytest.raises(ValueError, match="row sums"):
        AdditiveTableau(**{**kwargs, "c": t.c + 0.01})
    with pytest.raises(ValueError, match="sum to 1"):
        AdditiveTableau(**{**kwargs, "b_hat": t.b_hat * 1.01})
    with pytest.raises(ValueError, match="dense"):
        AdditiveTableau(**{**kwargs, "dense": t.dense * 1.01})
