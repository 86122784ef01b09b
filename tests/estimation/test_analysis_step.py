"""The analysis step (drillstring.estimation.analysis): the ensemble Kalman particle filter against the exact
Kalman posterior (linear Gaussian) and the exact posterior of a two-mode prior (stick or slip), and balanced
resampling. (The ETKF's own checks are in test_ensemble.py.)"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from drillstring.estimation.analysis import balanced_resample, enkpf_analysis, etkf_analysis


def _kalman(mean, cov, h, r, observed):
    gain = cov @ h.T @ np.linalg.inv(h @ cov @ h.T + r)
    return mean + gain @ (observed - h @ mean), (np.eye(len(mean)) - gain @ h) @ cov


@pytest.mark.parametrize("share", [0.1, 0.5, 0.9])
def test_enkpf_gives_the_kalman_posterior_of_a_linear_gaussian_problem(share):
    """Linear observation of a Gaussian prior: whatever the share, the EnKPF's analysis sample mean and covariance
    are the Kalman filter's posterior up to sampling error (20000 members: ~1 % of a standard deviation)."""
    rng = np.random.default_rng(0)
    n, m, members = 4, 2, 20000
    mean = np.array([1.0, 2.0, -1.0, 0.5])
    root = rng.standard_normal((n, n))
    cov = root @ root.T + np.eye(n)
    prior = rng.multivariate_normal(mean, cov, members).T
    h = rng.standard_normal((m, n))
    noise = np.array([0.5, 2.0])
    observed = np.array([0.3, -1.0])
    expected_mean, expected_cov = _kalman(mean, cov, h, np.diag(noise**2), observed)
    analysis, parents, effective, used = enkpf_analysis(prior, h @ prior, observed, noise, share,
                                                        np.random.default_rng(1))
    assert used == share
    sigma = np.sqrt(np.diag(expected_cov))
    assert np.all(np.abs(analysis.mean(axis=1) - expected_mean) < 0.04 * sigma)
    np.testing.assert_allclose(np.cov(analysis), expected_cov, atol=0.05 * np.max(np.abs(expected_cov)))
    assert 0.5 * members < effective <= members  # a moderate update: the weights far from degenerate
    assert parents.shape == (members,) and np.all(np.diff(parents) >= 0)


def test_enkpf_chooses_between_stick_and_slip_where_the_etkf_moves_both_as_one():
    """A two-mode forecast of the bit speed: half the members stick (0 ± 0.3 rad/s), half slip (12 ± 2 rad/s), a
    channel reading the speed with noise 3 rad/s reads 1 rad/s. The exact posterior is the mixture with each mode
    Kalman-updated and the stick mode's weight 0.992 (its 5-95 % band -0.48 to 0.53). The ETKF moves both modes as
    one Gaussian and leaves 37 % of the members above 4 rad/s; the EnKPF approaches the exact posterior as its
    share grows (at 0.999 the stick fraction within 0.01 of it and the band within 0.4 rad/s of it)."""
    rng = np.random.default_rng(0)
    members = 4000
    prior = np.concatenate([rng.normal(0.0, 0.3, members // 2), rng.normal(12.0, 2.0, members // 2)])[None, :]
    observed, noise = np.array([1.0]), np.array([3.0])
    stick = 0.5 * norm.pdf(1.0, 0.0, np.hypot(0.3, 3.0))
    slip = 0.5 * norm.pdf(1.0, 12.0, np.hypot(2.0, 3.0))
    exact_stick = stick / (stick + slip)
    assert exact_stick == pytest.approx(0.9917, abs=1e-4)
    etkf = etkf_analysis(prior, prior, observed, noise)
    assert np.mean(etkf[0] < 4.0) < 0.7
    fractions = []
    for share in (0.5, 0.9, 0.99, 0.999):
        analysis = enkpf_analysis(prior, prior, observed, noise, share, np.random.default_rng(1)).ensemble
        fractions.append(np.mean(analysis[0] < 4.0))
    assert np.all(np.diff(fractions) > 0), fractions
    assert fractions[-1] == pytest.approx(exact_stick, abs=0.01)
    analysis = enkpf_analysis(prior, prior, observed, noise, 0.999, np.random.default_rng(1)).ensemble
    np.testing.assert_allclose(np.quantile(analysis[0], [0.05, 0.95]), [-0.48, 0.53], atol=0.4)


def test_enkpf_lowers_its_share_where_the_weights_would_degenerate():
    """The two-mode forecast above at share 0.999 leaves half the members their weight (effective size ~0.5 N);
    asked for 0.8 N at least, the analysis lowers the share until it has that many (bisection to 1 % of the
    share), and it keeps a share it does not need to lower."""
    rng = np.random.default_rng(0)
    members = 2000
    prior = np.concatenate([rng.normal(0.0, 0.3, members // 2), rng.normal(12.0, 2.0, members // 2)])[None, :]
    observed, noise = np.array([1.0]), np.array([3.0])
    free = enkpf_analysis(prior, prior, observed, noise, 0.999, np.random.default_rng(1))
    assert free.share == 0.999 and free.effective_size < 0.6 * members
    held = enkpf_analysis(prior, prior, observed, noise, 0.999, np.random.default_rng(1), least_effective=0.8)
    assert held.share < 0.999 and 0.8 * members <= held.effective_size < 0.85 * members
    kept = enkpf_analysis(prior, prior, observed, noise, 0.1, np.random.default_rng(1), least_effective=0.8)
    assert kept.share == 0.1 and kept.effective_size >= 0.8 * members


def test_enkpf_refuses_a_share_outside_its_range():
    x = np.zeros((2, 8))
    for share in (0.0, 1.0, -0.1):
        with pytest.raises(ValueError, match="share"):
            enkpf_analysis(x, x[:1], np.zeros(1), np.ones(1), share, np.random.default_rng(0))
    with pytest.raises(ValueError, match="least_effective"):
        enkpf_analysis(x, x[:1], np.zeros(1), np.ones(1), 0.5, np.random.default_rng(0), least_effective=1.0)


def test_balanced_resampling_draws_each_member_its_weight_times_n_rounded():
    rng = np.random.default_rng(4)
    for _ in range(50):
        weights = rng.random(17) ** 3
        weights /= weights.sum()
        counts = np.bincount(balanced_resample(weights, rng), minlength=17)
        assert counts.sum() == 17
        assert np.all(counts >= np.floor(17 * weights) - 1e-9) and np.all(counts <= np.ceil(17 * weights) + 1e-9)
    equal = np.full(9, 1.0 / 9)
    np.testing.assert_array_equal(balanced_resample(equal, rng), np.arange(9))
