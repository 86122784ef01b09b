"""Surrogate-based search for a chance-constrained optimum of noisy Monte Carlo estimates.

The problem (Schonlau, Welch & Jones 1998; Gardner et al. 2014, "Bayesian optimization with inequality
constraints", ICML): over a box ``x ∈ [low, high]`` of decision variables,

    maximise  f(x)        subject to   g_k(x) ≤ b_k,  k = 1..m,

where ``f`` (an expected value or a quantile) and every ``g_k`` (a probability ``P(event)``) are known only
through Monte Carlo estimates at evaluated points, each with its sampling variance. This module is pure
numerics: it never runs a simulation (:mod:`drillstring.stochastic.optimize` does), so it is tested on
analytic functions.

**Surrogate.** One Gaussian process per output (:class:`GaussianProcess`): a constant mean (or, for the
constraints with :attr:`SearchProblem.trend`, a linear one estimated by generalised least squares), a Matérn-5/2
covariance with one length per variable (inputs scaled to the unit box, outputs standardised), the Monte Carlo
variance of each estimate on the diagonal (heteroscedastic noise, known) plus a fitted nugget; the
hyperparameters maximise the log marginal likelihood (Rasmussen & Williams 2006, eq. 2.30 and §5.4.1).

**Sequential sampling.** The next point maximises, over a scrambled Sobol' set of candidates in the box, the
constrained expected improvement ``EI(x) · Π_k Φ((b_k − μ_k(x))/s_k(x))`` (Gardner et al. 2014, eq. 5; ``EI``
of Jones, Schonlau & Welch 1998 over the best feasible posterior mean). While no evaluated point is feasible in
the posterior mean it maximises the probability of feasibility alone (the expected-feasibility phase). Both
factors are large only near the optimum and near the constraint boundaries, where the samples go.
Several points can be chosen at once, to be evaluated together (:func:`next_batch`): each point of a batch
is proposed as above after the previous ones were added to the surrogates as observations equal to their
posterior means, the Kriging believer of Ginsbourger, Le Riche & Carraro (2010).

**Recommendation.** The point of largest posterior mean of ``f`` among the candidates and the evaluated points
whose posterior means satisfy every constraint. Its constraints' confidence (:func:`constraint_confidence`)
combines the Monte Carlo binomial error of the estimate there and the surrogate's posterior standard deviation.
When no point is feasible, the least-infeasible one (smallest largest violation, each violation in units of
its constraint's combined standard deviation) is given instead, flagged infeasible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.optimize import minimize
from scipy.special import ndtr
from scipy.stats import qmc

__all__ = ["Estimates", "GaussianProcess", "Recommendation", "SearchProblem", "constraint_confidence",
           "initial_design", "next_batch", "next_point", "propose", "recommend", "search"]

#: Candidates of the acquisition's search (a scrambled Sobol' set in the unit box; a power of two).
CANDIDATES = 1024
#: Smallest distance (unit box) of a new point from an evaluated one: a point is evaluated once.
MIN_DISTANCE = 0.02


def _matern52(a: np.ndarray, b: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Matérn-5/2 correlation ``(1 + √5 r + 5r²/3) exp(−√5 r)``, ``r`` the length-scaled distance."""
    d = np.sqrt(np.maximum(((a[:, None, :] - b[None, :, :]) / lengths) ** 2, 0.0).sum(axis=2))
    s = math.sqrt(5.0) * d
    return (1.0 + s + s * s / 3.0) * np.exp(-s)


@dataclass
class GaussianProcess:
    """A Gaussian-process regression of noisy observations ``y`` at ``x`` (unit box, ``n × d``), each with its
    known noise variance (module docstring). :meth:`fit` returns the fitted process; :meth:`predict` gives the
    posterior mean and standard deviation of the latent function (without the noise).

    With ``trend`` the prior mean is linear in the inputs, ``h(x)ᵀβ`` with ``h = (1, x − ½)``, its
    coefficients given a flat prior, i.e. estimated by generalised least squares, their uncertainty added to
    the posterior variance, the hyperparameters by the restricted likelihood (Rasmussen & Williams 2006, §2.7,
    eqs. 2.41, 2.42 and 2.45; universal kriging): far from the data the process returns to the fitted plane,
    not to the data's mean. It needs ``n ≥ d + 2`` points (fewer: a constant mean)."""

    x: np.ndarray
    y: np.ndarray
    noise: np.ndarray
    lengths: np.ndarray = field(default_factory=lambda: np.ones(1))
    variance: float = 1.0
    nugget: float = 1e-6
    _mean: float = 0.0
    _scale: float = 1.0
    trend: bool = False

    @classmethod
    def fit(cls, x, y, noise=None, *, trend: bool = False) -> GaussianProcess:
        x = np.atleast_2d(np.asarray(x, dtype=float))
        y = np.asarray(y, dtype=float)
        noise = np.zeros_like(y) if noise is None else np.asarray(noise, dtype=float)
        if x.shape[0] != y.size or noise.shape != y.shape or not np.all(np.isfinite(y)):
            raise ValueError("x, y and noise must be finite and of one length")
        mean = float(y.mean())
        scale = float(y.std()) if y.size > 1 and y.std() > 0 else 1.0
        gp = cls(x, y, noise, np.ones(x.shape[1]), 1.0, 1e-6, mean, scale, bool(trend) and y.size >= x.shape[1] + 2)
        gp._optimise()
        return gp

    def _basis(self, x: np.ndarray) -> np.ndarray:
        return np.column_stack([np.ones(len(x)), x - 0.5])

    def _generalised_least_squares(self, factor, y: np.ndarray):
        """(``β``, ``K⁻¹H``, Cholesky factor of ``A = HᵀK⁻¹H``) of the linear trend (R&W eq. 2.42)."""
        basis = self._basis(self.x)
        solved = cho_solve(factor, basis)
        a = cho_factor(basis.T @ solved + 1e-12 * np.eye(basis.shape[1]), lower=True)
        return cho_solve(a, solved.T @ y), solved, a

    def _standard(self) -> tuple[np.ndarray, np.ndarray]:
        return (self.y - self._mean) / self._scale, self.noise / self._scale**2

    def _negative_log_likelihood(self, theta: np.ndarray) -> float:
        """Minus the log marginal likelihood (Rasmussen & Williams eq. 2.30) of ``θ = log(lengths, σ², τ²)``."""
        d = self.x.shape[1]
        lengths, variance, nugget = np.exp(theta[:d]), math.exp(theta[d]), math.exp(theta[d + 1])
        y, noise = self._standard()
        k = variance * _matern52(self.x, self.x, lengths) + np.diag(noise + nugget + 1e-10)
        try:
            factor = cho_factor(k, lower=True)
        except np.linalg.LinAlgError:
            return 1e10
        penalty = 0.0
        if self.trend:  # the restricted likelihood (R&W eq. 2.45): residuals of the GLS plane, ½ log|A|
            try:
                beta, _, a = self._generalised_least_squares(factor, y)
            except np.linalg.LinAlgError:
                return 1e10
            y = y - self._basis(self.x) @ beta
            penalty = np.log(np.diag(a[0])).sum() - 0.5 * len(beta) * math.log(2 * math.pi)
        alpha = cho_solve(factor, y)
        return float(0.5 * y @ alpha + np.log(np.diag(factor[0])).sum() + 0.5 * y.size * math.log(2 * math.pi)
                     + penalty)

    def _optimise(self) -> None:
        d = self.x.shape[1]
        bounds = [(math.log(0.05), math.log(5.0))] * d + [(math.log(1e-2), math.log(1e2)), (math.log(1e-8), 0.0)]
        best = None
        for length in (0.2, 0.6):  # two deterministic starts
            start = np.array([math.log(length)] * d + [0.0, math.log(1e-4)])
            found = minimize(self._negative_log_likelihood, start, method="L-BFGS-B", bounds=bounds)
            if best is None or found.fun < best.fun:
                best = found
        self.lengths, self.variance, self.nugget = (np.exp(best.x[:d]), math.exp(best.x[d]), math.exp(best.x[d + 1]))
        self._factorise()

    def _factorise(self) -> None:
        y, noise = self._standard()
        k = self.variance * _matern52(self.x, self.x, self.lengths) + np.diag(noise + self.nugget + 1e-10)
        self._factor = cho_factor(k, lower=True)
        if self.trend:
            self._beta, self._solved_basis, self._trend_factor = self._generalised_least_squares(self._factor, y)
            y = y - self._basis(self.x) @ self._beta
        self._alpha = cho_solve(self._factor, y)

    def believe(self, points) -> GaussianProcess:
        """The process conditioned on noise-free observations at ``points`` (unit box) equal to its own posterior
        mean there, the hyperparameters and standardisation kept: the Kriging believer of Ginsbourger, Le Riche &
        Carraro (2010, "Kriging is well-suited to parallelize optimization", §4.1). The mean is unchanged
        everywhere; the standard deviation shrinks near ``points``, so a batch's next point goes elsewhere."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        mean, _ = self.predict(points)
        gp = GaussianProcess(np.vstack([self.x, points]), np.concatenate([self.y, mean]),
                             np.concatenate([self.noise, np.zeros(len(points))]), self.lengths, self.variance,
                             self.nugget, self._mean, self._scale, self.trend)
        gp._factorise()
        return gp

    def predict(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and standard deviation of the latent function at ``points`` (unit box)."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        cross = self.variance * _matern52(points, self.x, self.lengths)
        mean = cross @ self._alpha
        v = cho_solve(self._factor, cross.T)
        var = self.variance - np.einsum("ij,ji->i", cross, v)
        if self.trend:  # R&W eq. 2.41: the plane, and the variance of its coefficients
            basis = self._basis(points)
            mean = mean + basis @ self._beta
            r = basis.T - self._solved_basis.T @ cross.T
            var = var + np.einsum("ij,ij->j", r, cho_solve(self._trend_factor, r))
        return self._mean + self._scale * mean, self._scale * np.sqrt(np.maximum(var, 0.0))


@dataclass(frozen=True)
class SearchProblem:
    """A constrained search: ``bounds`` (``d × 2``, low and high of each variable), the constraints' upper
    ``limits`` ``b_k`` (probabilities), whether ``f`` is maximised (else minimised), the number of
    ``initial`` points (a scrambled Sobol' design), the ``seed`` of that design and of the candidates, and
    whether the constraints' processes have a linear ``trend`` (:class:`GaussianProcess`; else a constant
    mean)."""

    bounds: tuple[tuple[float, float], ...]
    limits: tuple[float, ...]
    maximize: bool = True
    initial: int = 8
    seed: int = 0
    trend: bool = False

    def to_unit(self, x) -> np.ndarray:
        b = np.asarray(self.bounds, dtype=float)
        return (np.atleast_2d(np.asarray(x, dtype=float)) - b[:, 0]) / (b[:, 1] - b[:, 0])

    def from_unit(self, u) -> np.ndarray:
        b = np.asarray(self.bounds, dtype=float)
        return b[:, 0] + np.atleast_2d(np.asarray(u, dtype=float)) * (b[:, 1] - b[:, 0])


def initial_design(problem: SearchProblem, count: int | None = None) -> np.ndarray:
    """The first ``count`` (default ``problem.initial``) points (rows, in the variables' units): the box's
    centre, then a scrambled Sobol' sequence of ``problem.seed``."""
    d = len(problem.bounds)
    count = problem.initial if count is None else count
    sobol = qmc.Sobol(d, scramble=True, seed=np.random.default_rng([problem.seed, 7])).random_base2(
        max(math.ceil(math.log2(max(count - 1, 1))), 0))
    unit = np.vstack([np.full(d, 0.5), sobol])[:count]
    return problem.from_unit(unit)


def _candidates(problem: SearchProblem) -> np.ndarray:
    d = len(problem.bounds)
    return qmc.Sobol(d, scramble=True, seed=np.random.default_rng([problem.seed, 11])).random(CANDIDATES)


@dataclass
class Surrogates:
    """Gaussian processes of the objective (sign: larger is better) and of each constraint, on the unit box."""

    objective: GaussianProcess | None
    constraints: list[GaussianProcess]

    def believe(self, unit) -> Surrogates:
        """Every process conditioned on its own posterior mean at ``unit`` (:meth:`GaussianProcess.believe`)."""
        return Surrogates(None if self.objective is None else self.objective.believe(unit),
                          [gp.believe(unit) for gp in self.constraints])


def fit_surrogates(problem: SearchProblem, x, objective, objective_variance, constraints,
                   constraint_variances) -> Surrogates:
    """Fit the surrogates to the estimates at the evaluated points ``x`` (rows, variables' units): the
    objective's estimates and their variances (non-finite ones are left out of the objective's fit) and, per
    constraint (columns), the probability estimates and their variances."""
    unit = problem.to_unit(x)
    sign = 1.0 if problem.maximize else -1.0
    objective = sign * np.asarray(objective, dtype=float)
    ok = np.isfinite(objective)
    obj = GaussianProcess.fit(unit[ok], objective[ok], np.asarray(objective_variance, dtype=float)[ok]) \
        if ok.sum() >= 2 else None
    constraints = np.asarray(constraints, dtype=float).reshape(len(unit), -1)
    variances = np.asarray(constraint_variances, dtype=float).reshape(len(unit), -1)
    return Surrogates(obj, [GaussianProcess.fit(unit, constraints[:, k], variances[:, k], trend=problem.trend)
                            for k in range(constraints.shape[1])])


def _feasibility(problem: SearchProblem, surrogates: Surrogates, unit: np.ndarray) -> np.ndarray:
    """``Π_k Φ((b_k − μ_k)/s_k)``: the posterior probability that every constraint holds."""
    p = np.ones(len(unit))
    for gp, limit in zip(surrogates.constraints, problem.limits):
        mean, sd = gp.predict(unit)
        p *= ndtr((limit - mean) / np.maximum(sd, 1e-12))
    return p


def _feasible_mean(problem: SearchProblem, surrogates: Surrogates, unit: np.ndarray) -> np.ndarray:
    ok = np.ones(len(unit), dtype=bool)
    for gp, limit in zip(surrogates.constraints, problem.limits):
        ok &= gp.predict(unit)[0] <= limit
    return ok


def propose(problem: SearchProblem, x, surrogates: Surrogates) -> np.ndarray:
    """The next point to evaluate (variables' units): the candidate, at least :data:`MIN_DISTANCE` from every
    evaluated point ``x``, of largest constrained expected improvement, or of largest probability of
    feasibility while no evaluated point is feasible (module docstring)."""
    evaluated = problem.to_unit(x)
    cand = _candidates(problem)
    far = np.min(np.linalg.norm(cand[:, None, :] - evaluated[None, :, :], axis=2), axis=1) >= MIN_DISTANCE
    cand = cand[far] if far.any() else cand
    feasibility = _feasibility(problem, surrogates, cand)
    feasible_here = _feasible_mean(problem, surrogates, evaluated)
    if surrogates.objective is None or not feasible_here.any():
        return problem.from_unit(cand[int(np.argmax(feasibility))])[0]
    best = float(np.max(surrogates.objective.predict(evaluated[feasible_here])[0]))

    def acquisition(unit: np.ndarray) -> np.ndarray:
        mean, sd = surrogates.objective.predict(unit)
        sd = np.maximum(sd, 1e-12)
        z = (mean - best) / sd
        improvement = (mean - best) * ndtr(z) + sd * np.exp(-0.5 * z * z) / math.sqrt(2 * math.pi)
        return improvement * _feasibility(problem, surrogates, unit)

    start = cand[int(np.argmax(acquisition(cand)))]
    polished = _polish(lambda u: -float(acquisition(u[None, :])[0]), start)
    if np.min(np.linalg.norm(evaluated - polished, axis=1)) < MIN_DISTANCE:
        polished = start
    return problem.from_unit(polished)[0]


def _polish(loss, start: np.ndarray, constraints=()) -> np.ndarray:
    """A local refinement of a candidate in the unit box (the candidates are about 0.03 apart): L-BFGS-B, or
    SLSQP with ``constraints``; the start when that does not improve ``loss``."""
    bounds = [(0.0, 1.0)] * len(start)
    method = "SLSQP" if constraints else "L-BFGS-B"
    found = minimize(loss, start, method=method, bounds=bounds, constraints=list(constraints),
                     options={"maxiter": 50})
    point = np.clip(found.x, 0.0, 1.0)
    ok = all(c["fun"](point) >= -1e-9 for c in constraints)
    return point if ok and np.isfinite(found.fun) and loss(point) < loss(start) else start


@dataclass
class Recommendation:
    """The recommended point (variables' units), whether it is feasible in the posterior mean, its posterior
    objective mean and standard deviation (in the objective's own sign) and per constraint the posterior mean
    and standard deviation."""

    point: np.ndarray
    feasible: bool
    objective: float
    objective_sd: float
    constraint_means: np.ndarray
    constraint_sds: np.ndarray


def recommend(problem: SearchProblem, x, surrogates: Surrogates, *, candidates: bool = True) -> Recommendation:
    """The point of largest posterior objective among the evaluated points ``x`` (and the candidates, unless
    ``candidates`` is false) whose posterior constraint means hold; none: the least-infeasible one (module
    docstring)."""
    unit = np.vstack([problem.to_unit(x), _candidates(problem)]) if candidates else problem.to_unit(x)
    means = np.column_stack([gp.predict(unit)[0] for gp in surrogates.constraints]) if surrogates.constraints \
        else np.zeros((len(unit), 0))
    sds = np.column_stack([gp.predict(unit)[1] for gp in surrogates.constraints]) if surrogates.constraints \
        else np.zeros((len(unit), 0))
    limits = np.asarray(problem.limits, dtype=float)
    ok = np.all(means <= limits + 1e-9, axis=1)
    if ok.any() and surrogates.objective is not None:
        value = surrogates.objective.predict(unit)[0]
        index = int(np.flatnonzero(ok)[np.argmax(value[ok])])
        if candidates:  # refined between the candidates: max μ_f subject to μ_k ≤ b_k
            polished = _polish(lambda u: -float(surrogates.objective.predict(u[None, :])[0][0]), unit[index], [
                {"type": "ineq", "fun": (lambda u, gp=gp, b=b: b - float(gp.predict(u[None, :])[0][0]))}
                for gp, b in zip(surrogates.constraints, limits)])
            unit = np.vstack([unit, polished])
            means = np.vstack([means, [gp.predict(polished[None, :])[0][0] for gp in surrogates.constraints]]) \
                if surrogates.constraints else np.zeros((len(unit), 0))
            sds = np.vstack([sds, [gp.predict(polished[None, :])[1][0] for gp in surrogates.constraints]]) \
                if surrogates.constraints else np.zeros((len(unit), 0))
            ok = np.append(ok, bool(np.all(means[-1] <= limits + 1e-9)))
            index = len(unit) - 1
    else:
        violation = np.max((means - limits) / np.maximum(sds, 1e-3), axis=1, initial=-np.inf)
        index = int(np.argmin(violation))
    sign = 1.0 if problem.maximize else -1.0
    if surrogates.objective is not None:
        mean, sd = surrogates.objective.predict(unit[index:index + 1])
        mean, sd = sign * float(mean[0]), float(sd[0])
    else:
        mean, sd = math.nan, math.nan
    return Recommendation(problem.from_unit(unit[index])[0], bool(ok[index]), mean, sd, means[index], sds[index])


def constraint_confidence(estimate: float, count: int, limit: float, surrogate_sd: float) -> tuple[float, float]:
    """(combined standard deviation, confidence ``P(p ≤ limit)``) of a probability constraint at a point whose
    Monte Carlo estimate is ``estimate`` from ``count`` realizations: the binomial standard error with the
    Jeffreys-adjusted ``p̃ = (k + ½)/(n + 1)`` (so that 0 of n still carries an error) and the surrogate's
    posterior standard deviation there, independent, added in quadrature; the confidence is
    ``Φ((limit − estimate)/s)``."""
    n = max(int(count), 1)
    tilde = (estimate * n + 0.5) / (n + 1)
    s = math.sqrt(tilde * (1 - tilde) / n + float(surrogate_sd) ** 2)
    return s, float(ndtr((limit - estimate) / s))


@dataclass
class Estimates:
    """Monte Carlo estimates at evaluated points: the objective and its variance (``n``), each constraint's
    probability and its variance (``n × m``)."""

    objective: np.ndarray
    objective_variance: np.ndarray
    constraints: np.ndarray
    constraint_variances: np.ndarray

    def fit(self, problem: SearchProblem, x) -> Surrogates:
        return fit_surrogates(problem, x, self.objective, self.objective_variance, self.constraints,
                              self.constraint_variances)


def next_batch(problem: SearchProblem, x, estimates: Estimates | None, budget: int, start: int,
               size: int = 1) -> np.ndarray:
    """Points number ``start`` to ``start + size − 1`` (rows; fewer where the budget ends) of a search of
    ``budget`` points, from the ``estimates`` at the points ``x`` before ``start`` (those with an estimate),
    to be evaluated together.

    The initial design's points first (and while fewer than 2 points have estimates). Then a batch by the
    Kriging believer (Ginsbourger, Le Riche & Carraro 2010, §4.1): :func:`propose` on the surrogates, the point
    added to every process as an observation equal to its posterior mean (:meth:`Surrogates.believe`), the
    next point proposed on those, and so on (each point at least :data:`MIN_DISTANCE` from the evaluated
    and the batch's points). A batch that holds the budget's last point ends with the current recommendation
    (from the estimates alone, so that the answer is a point with its own Monte Carlo estimate), unless it was
    already evaluated. Deterministic: the same estimates give the same points (a resumed search repeats
    them)."""
    stop = min(start + size, budget)
    if start < problem.initial or x is None or len(x) < 2:
        return initial_design(problem, stop)[start:stop]
    x = np.atleast_2d(np.asarray(x, dtype=float))
    surrogates = estimates.fit(problem, x)
    last = None
    if stop == budget:
        found = recommend(problem, x, surrogates).point
        if np.min(np.linalg.norm(problem.to_unit(x) - problem.to_unit(found), axis=1)) >= MIN_DISTANCE:
            last = found
    if last is not None:
        surrogates = surrogates.believe(problem.to_unit(last))
        x = np.vstack([x, last])
    chosen = []
    for _ in range(stop - start - (last is not None)):
        point = propose(problem, x, surrogates)
        chosen.append(point)
        surrogates = surrogates.believe(problem.to_unit(point))
        x = np.vstack([x, point])
    return np.array(chosen + ([last] if last is not None else [])).reshape(stop - start, -1)


def next_point(problem: SearchProblem, x, estimates: Estimates | None, budget: int, *,
               index: int | None = None) -> np.ndarray:
    """Point number ``index`` (default ``len(x)``) of a search of ``budget`` points evaluated one at a time:
    :func:`next_batch` of one point."""
    index = (0 if x is None else len(x)) if index is None else index
    return next_batch(problem, x, estimates, budget, index, 1)[0]


def search(problem: SearchProblem, evaluate, budget: int, batch: int = 1) -> tuple[np.ndarray, Estimates,
                                                                                    Recommendation]:
    """Run a whole search of ``budget`` points, the initial design in one batch, then ``batch`` points at a
    time (:func:`next_batch`): ``evaluate(point)`` returns ``(objective, its variance, constraints (m), their
    variances (m))``. Returns the points, their estimates and the recommendation."""
    points: list[np.ndarray] = []
    rows: list[tuple] = []
    estimates = None
    while len(points) < budget:
        size = problem.initial if not points else batch
        chosen = next_batch(problem, np.array(points) if points else None, estimates, budget, len(points), size)
        points += list(chosen)
        rows += [evaluate(point) for point in chosen]
        estimates = Estimates(np.array([r[0] for r in rows], dtype=float), np.array([r[1] for r in rows], dtype=float),
                              np.array([r[2] for r in rows], dtype=float).reshape(len(rows), -1),
                              np.array([r[3] for r in rows], dtype=float).reshape(len(rows), -1))
    x = np.array(points)
    return x, estimates, recommend(problem, x, estimates.fit(problem, x))
