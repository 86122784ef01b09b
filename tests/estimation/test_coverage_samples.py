"""The coverage benchmark's count of independent samples (benchmarks/estimator_coverage.py ``effective_samples``):
how much a run's truth-in-band series says about its coverage, against series whose answer is known."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from estimator_coverage import effective_samples  # noqa: E402


def test_independent_samples_count_once_and_repeated_ones_once_per_block():
    rng = np.random.default_rng(0)
    draws = rng.random(20000) < 0.9
    assert effective_samples(draws) == pytest.approx(20000, rel=0.05)
    blocks = np.repeat(rng.random(2000) < 0.9, 10)  # each value held 10 samples: 2000 independent ones
    assert effective_samples(blocks) == pytest.approx(2000, rel=0.1)
    assert effective_samples(np.ones(50, dtype=bool)) == 50.0  # a constant series: nothing to correlate


def test_a_markov_chain_has_its_integrated_autocorrelation_time():
    """A two-state chain that keeps its state with probability q has the lag-k autocorrelation (2q − 1)^k, so
    τ = (1 + r)/(1 − r) with r = 2q − 1: q = 0.9 gives τ = 9."""
    rng = np.random.default_rng(1)
    n, q = 200000, 0.9
    flips = rng.random(n) > q
    state = np.cumsum(flips) % 2
    assert effective_samples(state) == pytest.approx(n / 9.0, rel=0.1)
