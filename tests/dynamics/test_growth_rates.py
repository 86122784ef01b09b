"""The study's leading growth rates by blocks of the state matrix against the whole-matrix analysis."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla

from drillstring.dynamics import growth_rates, stability
from drillstring.dynamics.rom import case_reduced_model
from drillstring.stochastic import DEFAULT_SEED
from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic.random_matrices import model_generator, random_reduced_model


def test_block_eigenproblem_is_the_whole_ones():
    rng = np.random.default_rng(3)
    blocks = [rng.standard_normal((k, k)) for k in (5, 3, 4)]
    order = rng.permutation(12)
    matrix = sla.block_diag(*blocks)[np.ix_(order, order)]
    values, vectors = growth_rates._block_eig(matrix)
    np.testing.assert_allclose(np.sort_complex(values), np.sort_complex(sla.eigvals(matrix)), rtol=1e-12)
    np.testing.assert_allclose(matrix @ vectors, vectors * values, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(vectors, axis=0), 1.0, rtol=1e-12)
    assert growth_rates._block_eig(rng.standard_normal((6, 6))) is None  # one block


def _agree(model):
    whole, blocks = stability.family_growth_rates(model), growth_rates.family_growth_rates(model)
    assert whole.keys() == blocks.keys()
    for name, value in whole.items():
        assert math.isnan(value) == math.isnan(blocks[name])
        if not math.isnan(value):
            assert blocks[name] == pytest.approx(value, rel=1e-11, abs=1e-13), name
    return whole


def test_family_growth_rates_by_blocks(reference_case):
    model = case_reduced_model(reference_case)
    found = growth_rates._block_eig(stability._informative_matrix(model, stability.steady_drilling(model))[0])
    assert found is not None  # the lateral families uncoupled: several blocks
    whole = _agree(model)
    assert whole["torsional_growth_rate"] > 0.0 > whole["axial_growth_rate"]  # stick-slip grows, axial decays
    settings = mc.StudySettings(samples=4, seed=DEFAULT_SEED, laws=(mc.weight_on_hook_normal(reference_case, 5000.0),))
    _agree(random_reduced_model(model, settings.model, model_generator(DEFAULT_SEED, 1)))  # a study's realization
