"""The numerical dual of a Maximum-Entropy density (eqs. (5)-(6) of :mod:`drillstring.stochastic.maxent`):
double-exponential maps of the support (Takahasi & Mori 1974), trapezoid rules in the mapped variable, an
orthonormal basis of the constraints, and Newton's method on the convex dual function.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import linalg

from drillstring.stochastic.maxent_constraints import LOG_MEAN, MEAN, SECOND_MOMENT, Constraint

# Numerical-dual settings (see the docstring of drillstring.stochastic.maxent).
# Numerical-dual settings (see the module docstring).
_H_START = 1.0 / 8.0  # first step of the trapezoid rule in the mapped variable t
_MAX_LEVELS = 8  # h down to 1/1024
_LEVEL_TOL = 1e-10  # agreement between the h and h/2 rules (normalisation and moments)
_NOISE_TOL = 1e-7  # accepted agreement / moment residual when round-off in the g_k limits it
_GRAD_TOL = 1e-12  # Newton stop: max |∇Γ| in orthonormal units
_MAX_NEWTON = 400
_FAR = 1e12  # truncation of infinite ends, in units of the scale s
_FAR_STEPS = (8.0, 64.0, 1e3, 1e5, 1e8, _FAR)  # domain continuation on infinite ends
_ESCAPE_DISTANCE = 1e6  # mass beyond this many scales counts as "escaping to infinity"
_ESCAPE_TOL = 1e-9
_TABLE_INTERVALS = 4096
_TABLE_GAUSS = 10
_TABLE_TAIL = 1e-17  # CDF table covers the mass between these tail probabilities



# ---------------------------------------------------------------------------------------------------------
# Double-exponential maps of the support (Takahasi & Mori 1974)
# ---------------------------------------------------------------------------------------------------------


class _Map:
    """``x(t)``, ``ln dx/dt`` and ``t(x)`` for one support, plus the reference log-density of the
    standardised variable used to orthonormalise the constraints."""

    def __init__(self, a: float, b: float, location: float, scale: float) -> None:
        self.a, self.b, self.c, self.s = a, b, location, scale
        fa, fb = math.isfinite(a), math.isfinite(b)
        if fa and fb:
            self.kind = "bounded"
        elif fa:
            self.kind = "lower"
        elif fb:
            self.kind = "upper"
        else:
            self.kind = "real"

    def t_range(self, far: float) -> tuple[float, float]:
        """Range of the mapped variable: where the weight underflows at a finite end (``|z| ≤ 350`` or
        ``e^z ≥ 1e-304``), and at ``far`` scales from the location on an infinite end."""
        k = math.pi / 2
        if self.kind == "bounded":
            return -math.asinh(350.0 / k), math.asinh(350.0 / k)
        if self.kind in ("lower", "upper"):
            return -math.asinh(700.0 / k), math.asinh(math.log(far) / k)
        tm = math.asinh(math.asinh(far) / k)
        return -tm, tm

    def nodes(self, h: float, far: float) -> np.ndarray:
        t0, t1 = self.t_range(far)
        return np.arange(math.ceil(t0 / h), math.floor(t1 / h) + 1, dtype=float) * h

    def x_logdxdt(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``x(t)``, ``ln dx/dt`` and the standardised distance ``d`` (for tail checks)."""
        z = (math.pi / 2) * np.sinh(t)
        log_cosh_t = np.abs(t) + np.log1p(np.exp(-2.0 * np.abs(t))) - math.log(2.0)
        base = math.log(math.pi / 2) + log_cosh_t
        if self.kind == "bounded":
            a, b = self.a, self.b
            az = np.abs(z)
            e = np.exp(-2.0 * az)
            frac = e / (1.0 + e)  # distance to the nearer end / (b − a)
            x = np.where(z < 0, a + (b - a) * frac, b - (b - a) * frac)
            # dx/dt = (b − a)/2 · sech² z · (π/2) cosh t,  sech² z = 4 e^{−2|z|} / (1 + e^{−2|z|})²
            logd = math.log((b - a) / 2) + math.log(4.0) - 2.0 * az - 2.0 * np.log1p(e) + base
            return x, logd, np.zeros_like(x)
        if self.kind in ("lower", "upper"):
            u = np.exp(z)
            x = self.a + self.s * u if self.kind == "lower" else self.b - self.s * u
            logd = math.log(self.s) + z + base
            return x, logd, u
        y = np.sinh(z)
        az = np.abs(z)
        log_cosh_z = az + np.log1p(np.exp(-2.0 * az)) - math.log(2.0)
        x = self.c + self.s * y
        logd = math.log(self.s) + log_cosh_z + base
        return x, logd, np.abs(y)

    def reference_logdensity(self, t: np.ndarray) -> np.ndarray:
        z = (math.pi / 2) * np.sinh(t)
        if self.kind == "bounded":
            return np.zeros_like(t)
        if self.kind in ("lower", "upper"):
            return -np.exp(z)
        return -0.5 * np.sinh(z) ** 2

    def t_of_x(self, x: np.ndarray) -> np.ndarray:
        """Inverse map; ``±inf`` at and beyond the ends of the support."""
        x = np.asarray(x, dtype=float)
        with np.errstate(all="ignore"):
            if self.kind == "bounded":
                z = 0.5 * (np.log(x - self.a) - np.log(self.b - x))
            elif self.kind == "lower":
                z = np.log((x - self.a) / self.s)
            elif self.kind == "upper":
                z = np.log((self.b - x) / self.s)
            else:
                z = np.arcsinh((x - self.c) / self.s)
            t = np.arcsinh(z / (math.pi / 2))
        if self.kind == "upper":
            t = -t  # keep t increasing with x
        t = np.where(x <= self.a, -np.inf, t)
        t = np.where(x >= self.b, np.inf, t)
        return t

    def x_of_t_increasing(self, t: np.ndarray) -> np.ndarray:
        """``x`` for a ``t`` that increases with ``x`` (the ``upper`` map runs backwards in its own t)."""
        if self.kind == "upper":
            return self.x_logdxdt(-t)[0]
        return self.x_logdxdt(t)[0]

    def logdxdt_increasing(self, t: np.ndarray) -> np.ndarray:
        if self.kind == "upper":
            return self.x_logdxdt(-t)[1]
        return self.x_logdxdt(t)[1]


# ---------------------------------------------------------------------------------------------------------
# Numerical solution of the dual
# ---------------------------------------------------------------------------------------------------------


class _Rule:
    """Quadrature nodes of one step ``h`` with the constraint values in the orthonormal basis."""

    def __init__(
        self, mapping: _Map, h: float, far: float, constraints: Sequence[Constraint], basis: _Basis | None
    ) -> None:
        t = mapping.nodes(h, far)
        x, logd, dist = mapping.x_logdxdt(t)
        logw = logd + math.log(h)
        G = np.column_stack([c.evaluate(x) for c in constraints]) if constraints else np.zeros((x.size, 0))
        keep = (x > mapping.a) & (x < mapping.b) & np.isfinite(logw) & np.all(np.isfinite(G), axis=1)
        self.h, self.far = h, far
        self.t, self.x, self.logw, self.dist, self.G = t[keep], x[keep], logw[keep], dist[keep], G[keep]
        self.ref = mapping.reference_logdensity(self.t)
        self.H = basis.transform(self.G) if basis is not None else None


class _Basis:
    """Centring ``ḡ`` and triangular factor ``R`` with ``h = (g − ḡ) R⁻¹`` orthonormal under the reference."""

    def __init__(self, rule: _Rule, names: Sequence[str]) -> None:
        K = rule.G.shape[1]
        self.K = K
        if K == 0:
            self.gbar = np.zeros(0)
            self.R = np.zeros((0, 0))
            return
        lq = rule.logw + rule.ref
        q = np.exp(lq - lq.max())
        q /= q.sum()
        self.gbar = q @ rule.G
        W = np.sqrt(q)[:, None] * (rule.G - self.gbar)
        R = linalg.qr(W, mode="r")[0][:K, :K]
        d = np.abs(np.diag(R))
        if K > 0 and (not np.all(np.isfinite(R)) or d.min() <= 1e-11 * max(d.max(), np.finfo(float).tiny)):
            raise ValueError(
                f"the constraint functions {list(names)} are linearly dependent (together with the constant) "
                "on the support: drop the redundant constraint"
            )
        signs = np.sign(np.diag(R))
        self.R = R * signs[:, None]

    def transform(self, G: np.ndarray) -> np.ndarray:
        if self.K == 0:
            return np.zeros((G.shape[0], 0))
        return linalg.solve_triangular(self.R, (G - self.gbar).T, trans="T", lower=False).T

    def lam(self, nu: np.ndarray) -> np.ndarray:
        if self.K == 0:
            return np.zeros(0)
        return linalg.solve_triangular(self.R, nu, lower=False)


def _dual_terms(nu: np.ndarray, rule: _Rule, target: np.ndarray, hessian: bool = True):
    """Discrete dual (5) in the orthonormal basis: value, gradient (6), Hessian (6), ln Z, node masses."""
    a = rule.logw - rule.H @ nu
    amax = float(a.max())
    e = np.exp(a - amax)
    Z = float(e.sum())
    lnZ = amax + math.log(Z)
    p = e / Z
    value = lnZ + float(nu @ target)
    Eh = p @ rule.H
    grad = target - Eh
    hess = None
    if hessian:
        mask = p > 0.0
        Hc = rule.H[mask] - Eh
        hess = (Hc * p[mask, None]).T @ Hc
    return value, grad, hess, lnZ, p


def _newton(nu: np.ndarray, rule: _Rule, target: np.ndarray) -> tuple[np.ndarray, int, float]:
    """Damped Newton on the convex discrete dual; returns ``ν``, iterations and the final max |∇Γ|."""
    K = nu.size
    if K == 0:
        return nu, 0, 0.0
    value, grad, hess, _, _ = _dual_terms(nu, rule, target)
    gnorm = float(np.max(np.abs(grad)))
    for it in range(1, _MAX_NEWTON + 1):
        if gnorm < _GRAD_TOL:
            return nu, it - 1, gnorm
        try:
            step = linalg.solve(hess + 1e-14 * np.eye(K) * max(1.0, np.trace(hess)), -grad, assume_a="pos")
        except (linalg.LinAlgError, ValueError):
            step = -grad
        slope = float(grad @ step)
        if not slope < 0.0:
            step, slope = -grad, -float(grad @ grad)
        alpha = 1.0
        accepted = False
        for _ in range(60):
            trial = nu + alpha * step
            tv, tg, th, _, _ = _dual_terms(trial, rule, target)
            if math.isfinite(tv) and tv <= value + 1e-4 * alpha * slope + 1e-15 * abs(value):
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            break  # no further decrease possible at machine precision
        nu, value, grad, hess = trial, tv, tg, th
        gnorm = float(np.max(np.abs(grad)))
        if np.max(np.abs(nu)) > 1e12:
            break
    return nu, _MAX_NEWTON, gnorm


@dataclass
class _NumericalSolution:
    mapping: _Map
    basis: _Basis
    rule: _Rule
    constraints: tuple[Constraint, ...]
    nu: np.ndarray
    lnZ: float
    p: np.ndarray
    _table: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def logpdf(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        flat = x.reshape(-1)
        out = np.full(flat.shape, -np.inf)
        a, b = self.mapping.a, self.mapping.b
        inside = (flat >= a) & (flat <= b) & ~np.isnan(flat) & np.isfinite(flat)
        if np.any(inside):
            xi = flat[inside]
            if self.constraints:
                G = np.column_stack([c.evaluate(xi) for c in self.constraints])
                with np.errstate(all="ignore"):
                    val = -self.lnZ - self.basis.transform(G) @ self.nu
            else:
                val = np.full(xi.shape, -self.lnZ)
            out[inside] = val
        out[np.isnan(flat)] = np.nan
        return out.reshape(x.shape)

    def expect(self, function: Callable[[np.ndarray], np.ndarray]) -> float:
        with np.errstate(all="ignore"):
            f = np.asarray(function(self.rule.x), dtype=float)
        return float(self.p @ np.broadcast_to(f, self.rule.x.shape))

    def entropy(self) -> float:
        # −∫ p ln p = ln Z + ν·E{h}  (eq. (5) at the optimum)
        if self.nu.size == 0:
            return float(self.lnZ)
        return float(self.lnZ + self.nu @ (self.p @ self.rule.H))

    # -- tabulated distribution function, in the increasing mapped variable t ------------------------------
    def _density_t(self, t: np.ndarray) -> np.ndarray:
        x = self.mapping.x_of_t_increasing(t)
        with np.errstate(all="ignore"):
            f = np.exp(self.logpdf(x) + self.mapping.logdxdt_increasing(t))
        return np.where(np.isfinite(f), f, 0.0)

    def table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self._table is None:
            t = self.rule.t if self.mapping.kind != "upper" else -self.rule.t
            order = np.argsort(t)
            t, p = t[order], self.p[order]
            cum = np.cumsum(p)
            h = self.rule.h
            i_lo = int(np.searchsorted(cum, _TABLE_TAIL))
            i_hi = int(np.searchsorted(cum, 1.0 - _TABLE_TAIL))
            t_lo = t[max(i_lo - 1, 0)] - h
            t_hi = t[min(i_hi + 1, t.size - 1)] + h
            knots = np.linspace(t_lo, t_hi, _TABLE_INTERVALS + 1)
            gx, gw = np.polynomial.legendre.leggauss(_TABLE_GAUSS)
            half = 0.5 * (knots[1:] - knots[:-1])
            mid = 0.5 * (knots[1:] + knots[:-1])
            tt = mid[:, None] + half[:, None] * gx[None, :]
            pieces = (self._density_t(tt.reshape(-1)).reshape(tt.shape) * gw).sum(axis=1) * half
            F = np.concatenate([[0.0], np.cumsum(pieces)])
            total = F[-1]
            F /= total
            dF = self._density_t(knots) / total
            self._table = (knots, F, dF)
        return self._table

    def _hermite(self, j: np.ndarray, t: np.ndarray) -> np.ndarray:
        knots, F, dF = self.table()
        t0, t1 = knots[j], knots[j + 1]
        dt = t1 - t0
        s = (t - t0) / dt
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h10 = s * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h11 = s * s * (s - 1)
        return h00 * F[j] + h10 * dt * dF[j] + h01 * F[j + 1] + h11 * dt * dF[j + 1]

    def cdf(self, x: np.ndarray) -> np.ndarray:
        knots, F, _ = self.table()
        x = np.asarray(x, dtype=float)
        t = self.mapping.t_of_x(x).reshape(-1)
        out = np.where(t <= knots[0], 0.0, 1.0)
        mid = (t > knots[0]) & (t < knots[-1])
        if np.any(mid):
            j = np.clip(np.searchsorted(knots, t[mid], side="right") - 1, 0, knots.size - 2)
            out[mid] = np.clip(self._hermite(j, t[mid]), 0.0, 1.0)
        out[np.isnan(x.reshape(-1))] = np.nan
        return out.reshape(x.shape)

    def ppf(self, q: np.ndarray, clip: bool) -> np.ndarray:
        knots, F, dF = self.table()
        q = np.asarray(q, dtype=float)
        flat = q.reshape(-1)
        out = np.full(flat.shape, np.nan)
        ok = (flat >= 0.0) & (flat <= 1.0)
        qq = np.clip(flat[ok], 0.0, 1.0)
        j = np.clip(np.searchsorted(F, qq, side="right") - 1, 0, knots.size - 2)
        # solve the cubic Hermite piece P(σ) = q on σ ∈ [0, 1] by Newton's method safeguarded by bisection
        t0, dt = knots[j], knots[j + 1] - knots[j]
        F0, F1 = F[j], F[j + 1]
        d0, d1 = dt * dF[j], dt * dF[j + 1]
        den = F1 - F0
        with np.errstate(all="ignore"):
            sig = np.clip(np.where(den > 0, (qq - F0) / den, 0.5), 0.0, 1.0)
        lo, hi = np.zeros_like(sig), np.ones_like(sig)
        for _ in range(60):
            s2 = sig * sig
            P = (1 + 2 * sig) * (1 - sig) ** 2 * F0 + sig * (1 - sig) ** 2 * d0 + s2 * (3 - 2 * sig) * F1
            P += s2 * (sig - 1) * d1 - qq
            dP = (6 * s2 - 6 * sig) * (F0 - F1) + (3 * s2 - 4 * sig + 1) * d0 + (3 * s2 - 2 * sig) * d1
            lo = np.where(P < 0, sig, lo)
            hi = np.where(P < 0, hi, sig)
            with np.errstate(all="ignore"):
                new = sig - P / dP
            bad = ~((new > lo) & (new < hi))
            new = np.where(bad, 0.5 * (lo + hi), new)
            done = np.max(np.abs(new - sig), initial=0.0) < 1e-15
            sig = new
            if done:
                break
        res = self.mapping.x_of_t_increasing(t0 + sig * dt)
        if not clip:
            res = np.where(qq <= 0.0, self.mapping.a, res)
            res = np.where(qq >= 1.0, self.mapping.b, res)
        out[ok] = res
        return out.reshape(q.shape)


def _raise_if_escaping(mapping: _Map, rule: _Rule, nu: np.ndarray, target: np.ndarray, names: list[str]) -> None:
    """Information that does not define a normalisable density pushes the mass to the truncated ends."""
    if mapping.kind == "bounded":
        return
    _, _, _, _, p = _dual_terms(nu, rule, target, hessian=False)
    escaped = float(p[rule.dist > min(_ESCAPE_DISTANCE, rule.far / 8.0)].sum())
    if escaped > _ESCAPE_TOL:
        a, b = mapping.a, mapping.b
        raise ValueError(
            f"the information {names} does not define a normalisable maximum-entropy density on the "
            f"support ({a}, {b}): probability {escaped:.3g} escapes to infinity "
            "(the supremum of the entropy is not attained: a constraint that controls the tails is missing, "
            "e.g. a second moment, or the moments are such that none exists, e.g. a kurtosis > 3 with "
            "moments up to order 4 on the real line)"
        )


def _location_scale(
    a: float, b: float, named: dict[str, float], location: float | None, scale: float | None
) -> tuple[float, float]:
    m = named.get(MEAN)
    m2 = named.get(SECOND_MOMENT)
    lm = named.get(LOG_MEAN)
    if math.isfinite(a) and math.isfinite(b):
        c, s = 0.5 * (a + b), 0.5 * (b - a)
    elif math.isfinite(a):
        c = a
        if m is not None:
            s = m - a
        elif m2 is not None and a == 0.0:
            s = math.sqrt(m2)
        elif lm is not None and a == 0.0:
            s = math.exp(lm)
        else:
            s = 1.0
    elif math.isfinite(b):
        c = b
        s = b - m if m is not None else (math.sqrt(m2) if m2 is not None and b == 0.0 else 1.0)
    else:
        c = m if m is not None else 0.0
        if m2 is not None:
            v = m2 - c * c
            s = math.sqrt(v) if v > 0 else math.sqrt(m2)
        else:
            s = 1.0
    if location is not None:
        c = float(location)
    if scale is not None:
        s = float(scale)
    if not (math.isfinite(c) and math.isfinite(s) and s > 0.0):
        raise ValueError(f"location = {c!r} and scale = {s!r} must be finite with scale > 0")
    return c, s


