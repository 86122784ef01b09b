"""Friction factors from measured hook loads, with their uncertainty; torque and drag propagated from it.

Measurements
------------
A CSV file with a header naming the columns ``bit_depth``, ``operation`` and ``hook_load``, units in brackets
(``bit_depth [ft], operation, hook_load [klbf]``), one measurement per line; operations are those of
:data:`drillstring.well.torque_drag.OPERATIONS` (``trip_out``, ``trip_in``, ``rotating_off_bottom``, ...).

Noise model and posterior
-------------------------
Each measured hook load is the soft-string prediction plus independent Gaussian noise,

    y_i = H(d_i, op_i; mu_c, mu_o) + eps_i,          eps_i ~ N(0, sigma^2),

with H the hook load of :func:`drillstring.well.torque_drag.torque_drag` at bit depth d_i, mu_c the cased-hole
and mu_o the open-hole friction factor. The prior is uniform on the box [0, mu_max]^2. With sigma known the
posterior is ``p(mu | y) ∝ exp(-S(mu) / (2 sigma^2))``, S the sum of squared residuals; with sigma unknown
and Jeffreys' prior p(sigma) ∝ 1/sigma, integrating sigma out gives ``p(mu | y) ∝ S(mu)^(-n/2)`` (Box & Tiao
1973, sec. 2.3). The posterior is evaluated on a grid (every grid point's n hook loads in one vectorised pass
along the string), which is exact up to the grid's resolution and needs no assumption of normality; its
marginal means, standard deviations and equal-tailed credible intervals, and the highest-posterior-density
region of any level, are read from the grid.

Propagation: draws from the grid posterior (a cell by its probability, uniform inside it) give the hook
loads and torques of every operation as bands (:func:`posterior_bands`). Friction factors are ordinary case
fields (``well.cased_hole_friction``, ``well.open_hole_friction``), so a study declares them uncertain like
any other parameter (``--param well.open_hole_friction="uniform 0.2 0.4"``; :func:`torque_drag_draws`).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drillstring.files import read_input_text
from drillstring.units import FORCE, LENGTH, to_si
from drillstring.well.torque_drag import OPERATIONS, case_trajectory, string_in_well, torque_drag

#: Most measurements (rows) calibrated at once, and most distinct bit depths among them (each costs one
#: soft-string pass per operation over the whole friction grid: about 0.06 s on the built-in deviated case, so
#: 200 depths tripping out and in take about 25 s; a rig's trip records one depth per stand, about 110 in 3 km).
MAX_MEASUREMENTS = 2_000
MAX_BIT_DEPTHS = 200
#: Largest measurements file [bytes].
MAX_MEASUREMENTS_FILE_BYTES = 1_000_000
#: Range of the hook-load noise sigma [N]: beyond it the posterior's exponent under- or overflows.
SIGMA_RANGE = (1e-3, 1e8)
#: Most grid points per friction factor (the predictions hold n x points^2 numbers).
MAX_GRID_POINTS = 201

__all__ = ["FrictionPosterior", "HookLoadMeasurements", "broomstick", "calibrate", "posterior_bands",
           "posterior_from_predictions", "predicted_hook_loads", "read_measurements", "torque_drag_draws"]


@dataclass(frozen=True)
class HookLoadMeasurements:
    """Measured hook loads: bit depth [m], operation name, hook load [N] (equal-length sequences)."""

    bit_depth: np.ndarray
    operation: tuple[str, ...]
    hook_load: np.ndarray

    def __post_init__(self) -> None:
        if not len(self.bit_depth) == len(self.operation) == len(self.hook_load):
            raise ValueError("bit_depth, operation and hook_load must have the same length")
        if len(self.bit_depth) > MAX_MEASUREMENTS:
            raise ValueError(f"measurements: {len(self.bit_depth):,}, more than the {MAX_MEASUREMENTS:,} allowed")
        for i, (d, op, h) in enumerate(zip(self.bit_depth, self.operation, self.hook_load)):
            if op not in OPERATIONS:
                raise ValueError(f"measurement {i}: operation = {op!r}: must be one of {', '.join(OPERATIONS)}")
            if not (math.isfinite(d) and d > 0.0 and math.isfinite(h)):
                raise ValueError(f"measurement {i}: bit_depth = {d!r} m, hook_load = {h!r} N: must be finite, "
                                 "depth > 0")
        depths = len(np.unique(self.bit_depth))
        if depths > MAX_BIT_DEPTHS:
            raise ValueError(f"measurements: {depths:,} distinct bit depths, more than the {MAX_BIT_DEPTHS:,} "
                             "allowed (each is one soft-string solution per grid point: round the depths, e.g. "
                             "to the stand)")

    def to_csv(self) -> str:
        """CSV text in SI units (the format :func:`read_measurements` reads)."""
        lines = ["bit_depth [m],operation,hook_load [N]"]
        lines += [f"{d:.6g},{op},{h:.8g}" for d, op, h in zip(self.bit_depth, self.operation, self.hook_load)]
        return "\n".join(lines) + "\n"


def read_measurements(path: str | Path) -> HookLoadMeasurements:
    """Measurements from a CSV file (module docstring): a regular file of at most
    :data:`MAX_MEASUREMENTS_FILE_BYTES` and :data:`MAX_MEASUREMENTS` rows (a FIFO or a device is refused
    unread). Raises ValueError naming the line at fault or the limit."""
    text = read_input_text(path, what="measurements file", max_bytes=MAX_MEASUREMENTS_FILE_BYTES)
    rows = [r for r in csv.reader(io.StringIO(text)) if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise ValueError(f"{path}: no header")
    if len(rows) - 1 > MAX_MEASUREMENTS:
        raise ValueError(f"{path}: {len(rows) - 1:,} measurements, more than the {MAX_MEASUREMENTS:,} allowed")
    names, units = [], []
    for cell in rows[0]:
        name, _, unit = cell.partition("[")
        names.append(name.strip().lower())
        units.append(unit.rstrip("] ").strip())
    try:
        i_d, i_op, i_h = names.index("bit_depth"), names.index("operation"), names.index("hook_load")
    except ValueError:
        raise ValueError(f"{path}: the header must name bit_depth, operation and hook_load") from None
    try:
        metre, newton = to_si(f"1 {units[i_d] or 'm'}", LENGTH), to_si(f"1 {units[i_h] or 'N'}", FORCE)
    except ValueError as exc:
        raise ValueError(f"{path}: the header's unit: {exc}") from None
    depth, ops, load = [], [], []
    for line, row in enumerate(rows[1:], start=2):
        try:
            depth.append(float(row[i_d]) * metre)
            load.append(float(row[i_h]) * newton)
            ops.append(row[i_op].strip())
        except (IndexError, ValueError) as exc:
            raise ValueError(f"{path}, line {line}: {row!r}: {exc}") from None
    return HookLoadMeasurements(np.array(depth), tuple(ops), np.array(load))


def predicted_hook_loads(case, measurements: HookLoadMeasurements, cased_friction, open_hole_friction, *,
                         max_step: float = 5.0, progress=None) -> np.ndarray:
    """Soft-string hook loads [N] of every measurement for G pairs of friction factors (arrays broadcast to
    G): shape (n, G). One string per distinct bit depth, all G pairs in one pass; ``progress(done, total)``
    is called after each bit depth."""
    path = case_trajectory(case)
    mu_c, mu_o = np.broadcast_arrays(np.atleast_1d(np.asarray(cased_friction, float)),
                                     np.atleast_1d(np.asarray(open_hole_friction, float)))
    out = np.empty((len(measurements.hook_load), mu_c.size))
    tob = 0.0 if case.well is None else case.well.torque_on_bit
    depths = np.unique(measurements.bit_depth)
    for done, depth in enumerate(depths, start=1):
        string = string_in_well(case, path, bit_depth=float(depth), max_step=max_step)
        here = np.nonzero(measurements.bit_depth == depth)[0]
        for op in {measurements.operation[i] for i in here}:
            result = torque_drag(string, op, cased_friction=mu_c, open_hole_friction=mu_o,
                                 weight_on_bit=case.operation.weight_on_bit, torque_on_bit=tob)
            for i in here:
                if measurements.operation[i] == op:
                    out[i] = result.hook_load
        if progress is not None:
            progress(done, len(depths))
    return out


@dataclass(frozen=True)
class FrictionPosterior:
    """The grid posterior of (mu_c, mu_o) (module docstring).

    Attributes: cased, open_hole: grid values [-]; probability: cell probabilities (sum 1), shape
    (len(cased), len(open_hole)); sigma: the noise standard deviation [N] (given, or None when
    integrated out); residual_sigma: sqrt(S/n) at the posterior mode [N]; n: number of measurements.
    """

    cased: np.ndarray
    open_hole: np.ndarray
    probability: np.ndarray
    sigma: float | None
    residual_sigma: float
    n: int

    def marginal(self, which: str) -> np.ndarray:
        return self.probability.sum(axis=1 if which == "cased" else 0)

    def mean(self) -> tuple[float, float]:
        return (float(self.marginal("cased") @ self.cased), float(self.marginal("open_hole") @ self.open_hole))

    def std(self) -> tuple[float, float]:
        out = []
        for which, grid in (("cased", self.cased), ("open_hole", self.open_hole)):
            p = self.marginal(which)
            m = p @ grid
            out.append(float(math.sqrt(max(p @ (grid - m) ** 2, 0.0))))
        return out[0], out[1]

    def interval(self, which: str, level: float = 0.9) -> tuple[float, float]:
        """Equal-tailed credible interval of one factor (grid values)."""
        grid = self.cased if which == "cased" else self.open_hole
        cdf = np.cumsum(self.marginal(which))
        tail = (1.0 - level) / 2.0
        upper = min(int(np.searchsorted(cdf, 1.0 - tail)), len(grid) - 1)
        return float(grid[np.searchsorted(cdf, tail)]), float(grid[upper])

    def in_region(self, i: int, j: int, level: float) -> bool:
        """Whether grid point (i, j) lies in the highest-posterior-density region of probability ``level``:
        the probability of the points denser than it is below ``level``."""
        p = self.probability
        return float(p[p > p[i, j]].sum()) < level

    def mode(self) -> tuple[float, float]:
        i, j = np.unravel_index(np.argmax(self.probability), self.probability.shape)
        return float(self.cased[i]), float(self.open_hole[j])

    def draw(self, count: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """``count`` draws (mu_c, mu_o): a cell by its probability, uniform within it."""
        rng = np.random.default_rng(seed)
        flat = rng.choice(self.probability.size, size=count, p=self.probability.ravel())
        i, j = np.unravel_index(flat, self.probability.shape)
        dc = self.cased[1] - self.cased[0] if len(self.cased) > 1 else 0.0
        do = self.open_hole[1] - self.open_hole[0] if len(self.open_hole) > 1 else 0.0
        mu_c = np.clip(self.cased[i] + dc * (rng.random(count) - 0.5), 0.0, None)
        mu_o = np.clip(self.open_hole[j] + do * (rng.random(count) - 0.5), 0.0, None)
        return mu_c, mu_o


def _check_sigma(sigma: float) -> None:
    if not (math.isfinite(sigma) and SIGMA_RANGE[0] <= sigma <= SIGMA_RANGE[1]):
        raise ValueError(f"sigma = {sigma!r} N: must be within [{SIGMA_RANGE[0]:g}, {SIGMA_RANGE[1]:g}] N "
                         "(or None: estimated)")


def posterior_from_predictions(predictions: np.ndarray, measured: np.ndarray, cased: np.ndarray,
                               open_hole: np.ndarray, sigma: float | None) -> FrictionPosterior:
    """The grid posterior from the hook loads predicted at every grid point, shape (n, len(cased) *
    len(open_hole)) in C order (cased the slow index), and the measured ones [N]."""
    residual = predictions - np.asarray(measured, float)[:, None]
    ssr = np.einsum("ij,ij->j", residual, residual)
    n = len(measured)
    if sigma is None:
        log_density = -0.5 * n * np.log(np.maximum(ssr, 1e-300))
    else:
        _check_sigma(sigma)
        log_density = -ssr / (2.0 * sigma**2)
    p = np.exp(log_density - log_density.max())
    p /= p.sum()
    return FrictionPosterior(np.asarray(cased), np.asarray(open_hole), p.reshape(len(cased), len(open_hole)),
                             sigma, float(math.sqrt(ssr.min() / n)), n)


def calibrate(case, measurements: HookLoadMeasurements, *, sigma: float | None = None, maximum: float = 0.6,
              points: int = 61, max_step: float = 5.0, progress=None) -> FrictionPosterior:
    """The posterior of (mu_c, mu_o) on a ``points`` x ``points`` grid over [0, maximum]^2 (module
    docstring); ``sigma`` [N] the noise standard deviation, or None to integrate it out; ``progress(done,
    total)`` after each bit depth (:func:`predicted_hook_loads`)."""
    if not (math.isfinite(maximum) and maximum > 0.0):
        raise ValueError(f"maximum = {maximum!r}: must be > 0")
    if not 2 <= points <= MAX_GRID_POINTS:
        raise ValueError(f"points = {points!r}: must be within [2, {MAX_GRID_POINTS}]")
    if sigma is not None:
        _check_sigma(sigma)
    grid = np.linspace(0.0, maximum, points)
    mu_c, mu_o = np.meshgrid(grid, grid, indexing="ij")
    predictions = predicted_hook_loads(case, measurements, mu_c.ravel(), mu_o.ravel(), max_step=max_step,
                                       progress=progress)
    return posterior_from_predictions(predictions, measurements.hook_load, grid, grid, sigma)


def posterior_bands(case, posterior: FrictionPosterior, bit_depths, *, operations=("trip_out",
                    "rotating_off_bottom", "trip_in"), draws: int = 200, seed: int = 0,
                    quantiles=(0.05, 0.5, 0.95), max_step: float = 5.0) -> dict[str, np.ndarray]:
    """Hook-load quantiles [N] of each operation at each bit depth under the posterior: shape
    (len(bit_depths), len(quantiles)) per operation; ``"surface_torque"`` the same for rotating off bottom."""
    mu_c, mu_o = posterior.draw(draws, seed)
    path = case_trajectory(case)
    tob = 0.0 if case.well is None else case.well.torque_on_bit
    out = {op: np.empty((len(bit_depths), len(quantiles))) for op in operations}
    out["surface_torque"] = np.empty((len(bit_depths), len(quantiles)))
    for k, depth in enumerate(bit_depths):
        string = string_in_well(case, path, bit_depth=float(depth), max_step=max_step)
        for op in operations:
            r = torque_drag(string, op, cased_friction=mu_c, open_hole_friction=mu_o,
                            weight_on_bit=case.operation.weight_on_bit, torque_on_bit=tob)
            out[op][k] = np.quantile(r.hook_load, quantiles)
            if op == "rotating_off_bottom":
                out["surface_torque"][k] = np.quantile(r.surface_torque, quantiles)
    return out


def torque_drag_draws(case, law, count: int, seed: int = 0, operations=("trip_out", "trip_in",
                      "rotating_off_bottom", "drilling")) -> dict[str, np.ndarray]:
    """Hook loads and surface torques [N, N*m] of each operation for ``count`` draws of ``law`` (a
    :class:`drillstring.stochastic.uncertainty.Uncertainty` over any case parameters, friction factors
    included): ``{op: array (count, 2)}`` of (hook_load, surface_torque)."""
    from drillstring.well.torque_drag import case_torque_drag

    rows = law.draw(seed, np.arange(count))
    out = {op: np.empty((count, 2)) for op in operations}
    for k, row in enumerate(rows):
        results = case_torque_drag(law.apply(case, row), operations, with_buckling=False)
        for op, r in results.items():
            out[op][k] = (float(r.hook_load), float(r.surface_torque))
    return out


def broomstick(case, bit_depths, frictions, *, operations=("trip_out", "rotating_off_bottom", "trip_in"),
               max_step: float = 10.0) -> dict[str, np.ndarray]:
    """The broomstick chart: hook loads [N] of each operation at each bit depth [m] for each friction factor
    of ``frictions`` (the same in cased and open hole): ``{op: array (len(bit_depths), len(frictions))}``."""
    path = case_trajectory(case)
    mu = np.asarray(frictions, float)
    tob = 0.0 if case.well is None else case.well.torque_on_bit
    out = {op: np.empty((len(bit_depths), mu.size)) for op in operations}
    for k, depth in enumerate(bit_depths):
        string = string_in_well(case, path, bit_depth=float(depth), max_step=max_step)
        for op in operations:
            out[op][k] = torque_drag(string, op, cased_friction=mu, open_hole_friction=mu,
                                     weight_on_bit=case.operation.weight_on_bit, torque_on_bit=tob).hook_load
    return out
