"""The ensemble filter's analysis step: from a forecast ensemble and the members' predicted observations to the
analysis ensemble (:mod:`drillstring.estimation.ensemble` runs it once per assimilation window).

**ETKF** (:func:`etkf_analysis`, the default). The ensemble transform Kalman filter (Bishop, Etherton & Majumdar
2001, in the form of Hunt, Kostelich & Szunyogh 2007, Physica D 230, eqs. 20-24), a deterministic square-root
filter: with the forecast anomalies ``A`` (n × N), the predicted observations' anomalies scaled by the noise,
``S = R^-1/2 (Y − ȳ)/√(N−1)`` (m × N), and the innovation ``d = R^-1/2 (y_o − ȳ)``::

    C = I + SᵀS,   w = C⁻¹ Sᵀ d / √(N−1),   x̄_a = x̄ + A w,   A_a = A C^-1/2      (C^-1/2 symmetric)

computed from the thin singular value decomposition of S. It needs no perturbed observations, keeps the ensemble's
mean exactly, and for a linear observation its analysis mean and sample covariance are the Kalman filter's applied
to the forecast's sample mean and covariance (tests/estimation/test_analysis_step.py). Its analysis is a linear
transform of the forecast: a forecast with two modes (members sticking and members slipping) is moved as one
Gaussian.

**EnKPF** (:func:`enkpf_analysis`, ``particle_share`` > 0). The ensemble Kalman particle filter of Frei & Künsch
(2013, Biometrika 100, 781-800, section 2): the likelihood split as ``p(y|x) = p(y|x)^γ p(y|x)^(1−γ)``, i.e. the
noise covariance as ``R/γ`` and ``R/(1−γ)``, with ``1 − γ`` the ``share`` given to the particle filter. The first
factor is a Kalman update of each member with the gain ``K_γ`` of ``γ P`` (``P`` the forecast's sample
covariance), ``ν_i = x_i + K_γ (y_o − y_i)``, which leaves the Gaussian mixture of components ``N(ν_i, Q)``,
``Q = K_γ R K_γᵀ / γ``; the second is exact on that mixture: component ``i`` weighed by its predictive likelihood
``α_i ∝ N(y_o; H ν_i, H Q Hᵀ + R/(1−γ))``, components drawn by those weights (balanced resampling), and each drawn
component updated by the Kalman gain of ``(1−γ) Q`` with perturbed observations. ``γ = 1`` is the stochastic
(perturbed-observation) ensemble Kalman filter, ``γ → 0`` the bootstrap particle filter; in between the weights
can choose between modes that the Kalman step alone moves as one (Frei & Künsch's bimodal examples). For a linear
Gaussian problem every ``γ`` gives the Kalman filter's posterior as the ensemble grows (checked in the tests).
``H`` is the ensemble's linear regression of the predicted observations on the state (as the ETKF's), so all of it
is in the m-dimensional observation space: ``B = K_γ R^1/2 = γ A Sᵀ (γ S Sᵀ + I)⁻¹ / √(N−1)``,
``G = R^-1/2 H B = γ S Sᵀ (γ S Sᵀ + I)⁻¹``, ``Q = B Bᵀ / γ``, ``R^-1/2 H Q Hᵀ R^-1/2 = G² / γ``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


def relax_to_prior_spread(prior: np.ndarray, posterior: np.ndarray, relaxation: np.ndarray) -> np.ndarray:
    """Relaxation to the prior spread (RTPS; Whitaker & Hamill 2012, Mon. Wea. Rev. 140, 3078-3089, eq. 10):
    each row's analysis anomalies scaled by ``1 + α (σ_b − σ_a)/σ_a``, ``σ_b``, ``σ_a`` the row's ensemble
    standard deviations before (``prior``, n × N) and after (``posterior``) the analysis, ``α`` the row's
    ``relaxation`` (n,) in [0, 1] (0: unchanged, 1: the prior's spread back). The mean is kept; a row with no
    spread after the analysis is left as it is."""
    mean = posterior.mean(axis=1, keepdims=True)
    anomalies = posterior - mean
    sigma_b = prior.std(axis=1, ddof=1)
    sigma_a = anomalies.std(axis=1, ddof=1)
    alpha = np.asarray(relaxation, dtype=float)
    factor = np.ones_like(sigma_a)
    spread = sigma_a > 1e-12 * np.maximum(sigma_b, 1e-300)
    factor[spread] = 1.0 + alpha[spread] * (sigma_b[spread] - sigma_a[spread]) / sigma_a[spread]
    return mean + anomalies * factor[:, None]


def _scaled(x: np.ndarray, y: np.ndarray, noise: np.ndarray, inflation: float):
    """What both analyses start from (module docstring): the ensemble's mean ``x̄`` (n × 1) and its anomalies ``A``
    times ``inflation``, the predicted observations' mean ``ȳ`` (m × 1), ``R^-1/2`` as a column (m × 1) and
    ``S = R^-1/2 inflation (Y − ȳ)/√(N−1)`` (m × N)."""
    mean = x.mean(axis=1, keepdims=True)
    anomalies = inflation * (x - mean)
    y_mean = y.mean(axis=1, keepdims=True)
    scale = 1.0 / np.asarray(noise, dtype=float)[:, None]
    s = scale * inflation * (y - y_mean) / math.sqrt(x.shape[1] - 1)
    return mean, anomalies, y_mean, scale, s


def etkf_analysis(ensemble: np.ndarray, predicted: np.ndarray, observed: np.ndarray, noise: np.ndarray,
                  inflation: float = 1.0) -> np.ndarray:
    """The ETKF analysis (module docstring, ETKF) of ``ensemble`` (n × N) given the members' ``predicted``
    observations (m × N), the ``observed`` values (m,) and the noise standard deviations ``noise`` (m,), the
    observation errors independent; the anomalies of both first multiplied by ``inflation``. Returns the
    analysis ensemble (n × N)."""
    x = np.asarray(ensemble, dtype=float)
    n_members = x.shape[1]
    mean, anomalies, y_mean, scale, s = _scaled(x, np.asarray(predicted, dtype=float), noise, inflation)
    d = scale[:, 0] * (np.asarray(observed, dtype=float) - y_mean[:, 0])
    # the thin SVD S = U Σ Vᵀ (m ≤ N rows): C⁻¹Sᵀ = Sᵀ(I + SSᵀ)⁻¹ and C^-1/2 = I + V((1 + Σ²)^-1/2 − 1)Vᵀ,
    # O(m² N) instead of the N × N eigenproblem
    u, sigma, vt = np.linalg.svd(s, full_matrices=False)
    weights = s.T @ (u @ ((u.T @ d) / (1.0 + sigma**2))) / math.sqrt(n_members - 1)
    shrink = 1.0 / np.sqrt(1.0 + sigma**2) - 1.0
    return mean + anomalies @ weights[:, None] + anomalies + ((anomalies @ vt.T) * shrink) @ vt


def balanced_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices of N draws from the members by their ``weights`` (N,) (summing to 1), balanced (systematic)
    resampling: one uniform number, the points ``(u + j)/N``; member ``i`` is drawn ``N w_i`` times rounded down
    or up (Kitagawa 1996, J. Comput. Graph. Stat. 5, 1-25), the least resampling noise. Sorted."""
    n_members = len(weights)
    points = (rng.random() + np.arange(n_members)) / n_members
    cumulative = np.cumsum(weights)
    cumulative[-1] = 1.0
    return np.minimum(np.searchsorted(cumulative, points, side="right"), n_members - 1)


class ParticleAnalysis(NamedTuple):
    """An EnKPF analysis (:func:`enkpf_analysis`): the analysis ensemble (n × N); for each analysis member the index
    of the forecast member whose component it was drawn from (N,; the member whose model and recent outputs it
    takes over); the weights' effective sample size ``1/Σ α_i²`` (1 to N); the share ``1 − γ`` used."""

    ensemble: np.ndarray
    parents: np.ndarray
    effective_size: float
    share: float


def _particle_weights(s: np.ndarray, innovations: np.ndarray, share: float):
    """For the share ``share = 1 − γ``: ``(γ S Sᵀ + I)⁻¹``, ``G``, the residuals ``R^-1/2 (y_o − H ν_i)`` and the
    normalised weights ``α`` (module docstring, EnKPF), from the scaled anomalies ``s`` (m × N) and the members'
    scaled innovations (m × N)."""
    gamma = 1.0 - share
    m = s.shape[0]
    covariance = s @ s.T  # R^-1/2 H P Hᵀ R^-1/2
    inverse = np.linalg.inv(gamma * covariance + np.eye(m))
    g = gamma * covariance @ inverse
    g = 0.5 * (g + g.T)
    residual = inverse @ innovations  # (I − G) d_i
    spread = g @ g / gamma + np.eye(m) / share  # R^-1/2 (H Q Hᵀ + R/(1−γ)) R^-1/2
    log_weight = -0.5 * np.einsum("ij,ij->j", residual, np.linalg.solve(spread, residual))
    weights = np.exp(log_weight - log_weight.max())
    return inverse, g, residual, weights / weights.sum()


def enkpf_analysis(ensemble: np.ndarray, predicted: np.ndarray, observed: np.ndarray, noise: np.ndarray,
                   share: float, rng: np.random.Generator, inflation: float = 1.0,
                   least_effective: float = 0.0) -> ParticleAnalysis:
    """The EnKPF analysis (module docstring, EnKPF) of ``ensemble`` (n × N) given the members' ``predicted``
    observations (m × N), the ``observed`` values (m,), the noise standard deviations ``noise`` (m,), the share
    ``share = 1 − γ`` of the likelihood given to the particle filter, in (0, 1), and the random stream ``rng``
    (the resampling's and the perturbations' draws); the anomalies first multiplied by ``inflation``. Where the
    weights at ``share`` leave an effective sample size below ``least_effective`` × N (a fraction in [0, 1)), the
    largest share that leaves that many is used instead (found by bisection to 1 % of ``share``; Frei & Künsch's
    adaptive γ, section 3): the particle step takes what the ensemble can carry without degenerating."""
    x = np.asarray(ensemble, dtype=float)
    y = np.asarray(predicted, dtype=float)
    if not 0.0 < share < 1.0:
        raise ValueError(f"share = {share!r}: must be in (0, 1)")
    if not 0.0 <= least_effective < 1.0:
        raise ValueError(f"least_effective = {least_effective!r}: must be in [0, 1)")
    m, n_members = y.shape
    root = math.sqrt(n_members - 1)
    x_mean, anomalies, y_mean, scale, s = _scaled(x, y, noise, inflation)
    # each member's innovation, scaled: R^-1/2 (y_o − y_i), y_i its prediction with the anomalies inflated
    innovations = scale * (np.asarray(observed, dtype=float)[:, None] - (y_mean + inflation * (y - y_mean)))

    def effective(weights: np.ndarray) -> float:
        return float(1.0 / np.sum(weights**2))

    inverse, g, residual, weights = _particle_weights(s, innovations, share)
    if effective(weights) < least_effective * n_members:
        low, high = 0.0, share  # the effective size falls as the share grows
        while high - low > 0.01 * share:
            middle = 0.5 * (low + high)
            if effective(_particle_weights(s, innovations, middle)[3]) >= least_effective * n_members:
                low = middle
            else:
                high = middle
        share = max(low, 0.01 * share)
        inverse, g, residual, weights = _particle_weights(s, innovations, share)
    gamma = 1.0 - share
    gain = gamma * (anomalies @ s.T) @ inverse / root  # B = K_γ R^1/2
    nu = x_mean + anomalies + gain @ innovations  # the first, Kalman, step
    parents = balanced_resample(weights, rng)
    # the drawn component's Kalman update with the gain of (1−γ) Q, perturbed observations
    second = (share / gamma) * gain @ g @ np.linalg.inv((share / gamma) * (g @ g) + np.eye(m))
    first_draw = rng.standard_normal((m, n_members)) / math.sqrt(gamma)
    second_draw = rng.standard_normal((m, n_members)) / math.sqrt(share)
    analysis = (nu[:, parents] + gain @ first_draw
                + second @ (residual[:, parents] + second_draw - g @ first_draw))
    return ParticleAnalysis(analysis, parents, effective(weights), share)
