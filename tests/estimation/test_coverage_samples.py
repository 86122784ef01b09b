"""The coverage benchmark's count of independent samples (benchmarks/estimator_coverage.py ``effective_samples``):
how much a run's truth-in-band series says about its coverage, against series whose answer is known."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from estimator_coverage import effective_samples, spread_between_records  # noqa: E402


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


def test_spread_between_records_separates_the_records_from_the_seeds():
    """Two records, three seeds each: the records' means, their standard deviation and the seeds' own, against
    the values worked by hand (means 0.80 and 0.96; between √((0.08² + 0.08²)/1) = 0.1131; within √((0.01² +
    0.02²)/2) with each record's variance of its three runs)."""
    runs = [("a", 0.79), ("a", 0.80), ("a", 0.81), ("b", 0.94), ("b", 0.96), ("b", 0.98)]
    means, between, within = spread_between_records(runs)
    assert means == pytest.approx({"a": 0.80, "b": 0.96})
    assert between == pytest.approx(0.16 / np.sqrt(2.0))
    assert within == pytest.approx(np.sqrt((0.01**2 + 0.02**2) / 2.0))
    one, none_between, none_within = spread_between_records([("a", 0.9)])
    assert one == {"a": 0.9} and np.isnan(none_between) and np.isnan(none_within)
