"""Global sensitivity analysis: Sobol' indices of several outputs from one Saltelli design (SALib).

For a model output ``Y = f(X_1, …, X_k)`` of independent parameters, the first-order index of ``X_j`` is the
share of the variance of ``Y`` explained by ``X_j`` alone, and the total index the share it explains with all
its interactions (Sobol' 2001; Saltelli et al. 2010):

    S_j  = Var(E{Y | X_j}) / Var(Y),        S_Tj = E{Var(Y | X_{~j})} / Var(Y) = 1 − Var(E{Y | X_{~j}}) / Var(Y).

Design and estimators
---------------------
* **Design** (:func:`saltelli_design`): ``SALib.sample.sobol.sample`` without second-order terms — a scrambled
  Sobol' sequence in ``2k`` dimensions gives the base matrices ``A`` and ``B`` (``N`` rows each), and each
  base sample ``i`` contributes the block ``A_i, A_i^(B,1), …, A_i^(B,k), B_i`` (``A^(B,j)``: ``A`` with
  column ``j`` from ``B``), i.e. ``N(k + 2)`` runs. The design lives in the unit hypercube; the points are
  mapped to parameter values through each parameter's inverse distribution function
  (:meth:`~drillstring.stochastic.uncertainty.Uncertainty.from_unit`), so any declared law works.
  ``N`` must be a power of 2 (the balance of the Sobol' sequence).
* **Estimators** (:func:`sobol_indices`): ``SALib.analyze.sobol.analyze`` — first order by Saltelli et al.
  (2010), ``S_j ≈ mean(f(B)(f(A^(B,j)) − f(A))) / Var``, total order by Jansen (1999),
  ``S_Tj ≈ mean((f(A) − f(A^(B,j)))²) / (2 Var)``. Confidence intervals by bootstrap over the base samples:
  ``S ± z_{(1+c)/2} · std(bootstrap)`` (SALib's normal approximation), for the confidence level ``c``.
* **Convergence in N**: the first ``n(k + 2)`` rows of the design for ``N`` are the design for ``n`` (a prefix
  of the Sobol' sequence), so the indices at ``N/4``, ``N/2`` and ``N`` come from the same runs;
  :attr:`SobolResult.convergence_change` is the largest change of any index between successive levels.
* **Too small a sample** (:meth:`SobolResult.sample_notes`): an index is known to about its interval's
  half-width, so a result is flagged, per output, when a half-width exceeds both the index it qualifies and
  :data:`RESOLUTION`, an index is below −:data:`RESOLUTION` or a total index below its first-order one by more
  than :data:`RESOLUTION` (impossible for the exact indices: sampling error), or an index changed by more
  than 2 :data:`RESOLUTION` from N/2 to N. The reference study (8 parameters, N = 512) has none of these
  (docs/sensitivity.md: each index known to about ±0.05); N = 8 has them all.
* **Failed runs**: a base sample whose block holds a non-finite output is left out of that output's
  estimate (a block is self-contained in both estimators); the count is reported (``dropped``). Failures that
  depend on the parameters bias the indices: keep the count near zero.
* **Independence**: Sobol' indices of this kind need independent parameters; a correlated
  :class:`~drillstring.stochastic.uncertainty.Uncertainty` is refused.

Model evaluation
----------------
The model is a callable over a batch: ``model(values)`` with ``values`` of shape ``(n, k)`` in SI units
(columns in the order of ``uncertainty.paths``) returns ``{output name: array of shape (n,)}``;
:func:`sobol_analysis` calls it in batches and analyses. The design and the analysis can also be used
separately (:func:`saltelli_design`, :func:`sobol_indices`) when the runs are made elsewhere: drilling
simulations run each design row on the study engine (local processes or Dask, a resumable store),
:mod:`drillstring.stochastic.sensitivity_study`.

References: I. M. Sobol', Math. Comput. Simul. 55, 271–280 (2001); A. Saltelli et al., "Variance based
sensitivity analysis of model output. Design and estimator for the total sensitivity index", Comput. Phys.
Commun. 181, 259–270 (2010); M. J. W. Jansen, Comput. Phys. Commun. 117, 35–43 (1999); J. Herman &
W. Usher, "SALib: an open-source Python library for sensitivity analysis", JOSS 2(9), 97 (2017).
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drillstring.stochastic.uncertainty import Uncertainty

__all__ = [
    "SaltelliDesign",
    "SobolResult",
    "saltelli_design",
    "sobol_analysis",
    "sobol_indices",
]

#: Model evaluated over a batch: values (n, k) [SI] -> {output: (n,)}.
BatchModel = Callable[[np.ndarray], Mapping[str, Any]]

_LEVELS = (4, 2, 1)  # convergence check at N/4, N/2, N
#: The resolution of an index below which differences are not read: half-widths, negative values and ST < S1
#: smaller than this are sampling noise of no consequence (the reference study's indices are known to ±0.05).
RESOLUTION = 0.05


def _problem(k: int, names: tuple[str, ...]) -> dict[str, Any]:
    return {"num_vars": k, "names": list(names), "bounds": [[0.0, 1.0]] * k}


@dataclass(frozen=True, eq=False)
class SaltelliDesign:
    """A Saltelli design of ``N`` base samples for ``k`` parameters: ``N(k + 2)`` runs.

    Attributes
    ----------
    uncertainty:
        The parameters and their laws.
    base_samples:
        ``N`` (a power of 2).
    seed:
        The scrambling seed of the Sobol' sequence.
    unit:
        Points of the unit hypercube, shape ``(N(k + 2), k)``, in SALib's block order.
    values:
        The parameter values of each run [SI], ``uncertainty.from_unit(unit)``.
    """

    uncertainty: Uncertainty
    base_samples: int
    seed: int
    unit: np.ndarray = field(repr=False)
    values: np.ndarray = field(repr=False)

    @property
    def runs(self) -> int:
        """Number of model runs, ``N(k + 2)``."""
        return self.unit.shape[0]

    @property
    def block(self) -> int:
        """Runs per base sample, ``k + 2``."""
        return self.uncertainty.size + 2


#: Largest number of base samples N: the design holds N(k + 2) rows of k values (k = 10: 3.1 million rows,
#: 250 MB), each row one simulation.
MAX_BASE_SAMPLES = 2**18


def _check_power_of_two(n: Any, what: str) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"{what} = {n!r}: must be an integer (a power of 2), not {type(n).__name__}")
    if n < 8 or (int(n) & (int(n) - 1)) != 0:
        raise ValueError(f"{what} = {n!r}: must be a power of 2 and >= 8 (e.g. 256, 1024), for the balance of the "
                         "Sobol' sequence and the convergence check at N/4, N/2, N")
    if n > MAX_BASE_SAMPLES:
        raise ValueError(f"{what} = {int(n)}: above the limit of {MAX_BASE_SAMPLES} (2**18) base samples")
    return int(n)


def saltelli_design(uncertainty: Uncertainty, base_samples: int, *, seed: int = 0) -> SaltelliDesign:
    """The Saltelli design of ``base_samples`` (``N``, a power of 2, >= 8) for the declared parameters,
    mapped through their laws (see the module docstring). Depends only on ``(uncertainty, N, seed)``."""
    n = _check_power_of_two(base_samples, "base samples N")
    if not isinstance(uncertainty, Uncertainty):
        raise TypeError(f"uncertainty must be an Uncertainty, got {type(uncertainty).__name__}")
    if not uncertainty.independent:
        raise ValueError(
            f"Sobol' indices need independent parameters; {', '.join(uncertainty.correlated)} are correlated "
            "(drop the correlation for a sensitivity study, or use a Monte Carlo study for the joint law)"
        )
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}: must be an integer >= 0")
    from SALib.sample import sobol as salib_sample  # imported here: SALib imports pandas (~0.5 s)

    k = uncertainty.size
    unit = salib_sample.sample(_problem(k, uncertainty.paths), n, calc_second_order=False, scramble=True,
                               seed=int(seed))
    values = uncertainty.from_unit(unit)
    return SaltelliDesign(uncertainty, n, int(seed), unit, values)


# ---------------------------------------------------------------------------------------------------------
# The result
# ---------------------------------------------------------------------------------------------------------


def _nan_to_none(x: float) -> float | None:
    return None if not math.isfinite(x) else float(x)


@dataclass(frozen=True, eq=False)
class SobolResult:
    """First-order and total Sobol' indices with bootstrap confidence intervals, per output and parameter.

    Arrays are indexed ``[output, parameter]`` in the order of ``outputs`` and ``parameters``; the convergence
    arrays ``[level, output, parameter]`` for ``convergence_samples`` (``N/4, N/2, N``). An index is NaN when
    it is undefined (a constant output, or fewer than 2 base samples left).

    Attributes
    ----------
    parameters, laws:
        Parameter paths and their law specs.
    outputs:
        Output names.
    base_samples, runs, seed:
        ``N``, ``N(k + 2)`` and the design seed.
    confidence_level, resamples:
        The bootstrap's confidence level and number of resamples.
    S1, S1_conf, ST, ST_conf:
        Indices and the half-widths of their confidence intervals, shape ``(outputs, parameters)``.
    convergence_samples, S1_convergence, ST_convergence:
        The indices at each level of the convergence check.
    dropped:
        Base samples left out of each output's estimate (non-finite outputs).
    """

    parameters: tuple[str, ...]
    laws: tuple[str, ...]
    outputs: tuple[str, ...]
    base_samples: int
    runs: int
    seed: int
    confidence_level: float
    resamples: int
    S1: np.ndarray
    S1_conf: np.ndarray
    ST: np.ndarray
    ST_conf: np.ndarray
    convergence_samples: tuple[int, ...]
    S1_convergence: np.ndarray
    ST_convergence: np.ndarray
    dropped: dict[str, int]

    @property
    def S1_interval(self) -> np.ndarray:
        """``[lower, upper]`` of each first-order index, shape ``(outputs, parameters, 2)``."""
        return np.stack([self.S1 - self.S1_conf, self.S1 + self.S1_conf], axis=-1)

    @property
    def ST_interval(self) -> np.ndarray:
        """``[lower, upper]`` of each total index, shape ``(outputs, parameters, 2)``."""
        return np.stack([self.ST - self.ST_conf, self.ST + self.ST_conf], axis=-1)

    def _row(self, output: str) -> int:
        try:
            return self.outputs.index(output)
        except ValueError:
            raise KeyError(f"unknown output {output!r}; outputs: {', '.join(self.outputs)}") from None

    def convergence_change(self, output: str) -> np.ndarray:
        """Largest ``|ΔS|`` over both index kinds and all parameters between successive levels of the
        convergence check (``N/4 -> N/2``, ``N/2 -> N``), for one output."""
        o = self._row(output)
        s = np.concatenate([self.S1_convergence[:, o, :], self.ST_convergence[:, o, :]], axis=1)
        return np.max(np.abs(np.diff(s, axis=0)), axis=1)

    def sample_notes(self, output: str) -> list[str]:
        """What says the sample is too small for one output's indices (module docstring, "Too small a sample"):
        intervals wider than their indices, negative indices, total indices below first-order ones, large
        changes from N/2 to N; empty when none."""
        o = self._row(output)
        notes = []
        for kind, values, half in (("S1", self.S1[o], self.S1_conf[o]), ("ST", self.ST[o], self.ST_conf[o])):
            with np.errstate(invalid="ignore"):
                wide = [p for p, v, c in zip(self.parameters, values, half) if c > max(abs(v), RESOLUTION)]
                negative = [p for p, v in zip(self.parameters, values) if v < -RESOLUTION]
            if wide:
                notes.append(f"{kind} interval wider than the index for {', '.join(wide)}")
            if negative:
                notes.append(f"{kind} negative for {', '.join(negative)}")
        with np.errstate(invalid="ignore"):
            below = [p for p, s1, st in zip(self.parameters, self.S1[o], self.ST[o]) if st < s1 - RESOLUTION]
        if below:
            notes.append(f"ST below S1 for {', '.join(below)}")
        change = self.convergence_change(output)
        if change.size and np.isfinite(change[-1]) and change[-1] > 2 * RESOLUTION:
            notes.append(f"indices changed by up to {change[-1]:.2f} from N/2 to N")
        return notes

    def indices(self, output: str) -> dict[str, dict[str, Any]]:
        """The indices of one output by kind and parameter: ``{"S1": {path: value}, "S1_ci": {path: [lo, hi]},
        "ST": ..., "ST_ci": ...}``."""
        o = self._row(output)
        out: dict[str, dict[str, Any]] = {}
        for kind, values, interval in (("S1", self.S1, self.S1_interval), ("ST", self.ST, self.ST_interval)):
            out[kind] = {p: _nan_to_none(values[o, j]) for j, p in enumerate(self.parameters)}
            out[f"{kind}_ci"] = {
                p: [_nan_to_none(interval[o, j, 0]), _nan_to_none(interval[o, j, 1])]
                for j, p in enumerate(self.parameters)
            }
        return out

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready; NaN as ``None``)."""
        outputs = {}
        for o, name in enumerate(self.outputs):
            entry: dict[str, Any] = self.indices(name)
            entry["dropped_base_samples"] = int(self.dropped.get(name, 0))
            entry["sample_notes"] = self.sample_notes(name)
            levels = {"S1": self.S1_convergence, "ST": self.ST_convergence}
            entry["convergence"] = {
                "base_samples": list(self.convergence_samples),
                **{
                    kind: {p: [_nan_to_none(v) for v in values[:, o, j]] for j, p in enumerate(self.parameters)}
                    for kind, values in levels.items()
                },
                "max_change": [_nan_to_none(v) for v in self.convergence_change(name)],
            }
            outputs[name] = entry
        return {
            "method": "Sobol' indices from a Saltelli design (SALib): first order Saltelli et al. 2010, total "
            "order Jansen 1999, bootstrap confidence intervals (normal approximation)",
            "parameters": dict(zip(self.parameters, self.laws)),
            "base_samples": self.base_samples,
            "runs": self.runs,
            "seed": self.seed,
            "confidence_level": self.confidence_level,
            "resamples": self.resamples,
            "outputs": outputs,
        }

    def to_json(self, path: str | Path | None = None) -> str:
        """The result as JSON text (:meth:`to_dict`); also written to ``path`` when given."""
        text = json.dumps(self.to_dict(), indent=2, allow_nan=False)
        if path is not None:
            Path(path).write_text(text + "\n", encoding="utf-8")
        return text


# ---------------------------------------------------------------------------------------------------------
# Analysis
# ---------------------------------------------------------------------------------------------------------


def _analyse(y_blocks: np.ndarray, k: int, names: tuple[str, ...], confidence: float, resamples: int,
             seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """S1, S1_conf, ST, ST_conf of one output from its blocks ``(n, k + 2)`` (finite values)."""
    nan = np.full(k, np.nan)
    if y_blocks.shape[0] < 2 or np.ptp(y_blocks) <= 4.0 * np.finfo(float).eps * float(np.max(np.abs(y_blocks))):
        return nan, nan.copy(), nan.copy(), nan.copy()
    from SALib.analyze import sobol as salib_analyze

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # SALib's std of a 2-sample bootstrap and the like
        si = salib_analyze.analyze(
            _problem(k, names), y_blocks.reshape(-1), calc_second_order=False, num_resamples=resamples,
            conf_level=confidence, print_to_console=False, seed=seed + 1,  # SALib treats seed 0 as "unseeded"
        )
    return (np.asarray(si["S1"], float), np.asarray(si["S1_conf"], float), np.asarray(si["ST"], float),
            np.asarray(si["ST_conf"], float))


def sobol_indices(
    design: SaltelliDesign,
    outputs: Mapping[str, Any],
    *,
    confidence: float = 0.95,
    resamples: int = 1000,
    seed: int = 0,
) -> SobolResult:
    """Sobol' indices of each output from the runs of ``design`` (see the module docstring).

    ``outputs`` maps output names to arrays of shape ``(design.runs,)`` in the design's row order.
    ``seed`` seeds the bootstrap resampling.
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence = {confidence!r}: must be in (0, 1), e.g. 0.95")
    if isinstance(resamples, bool) or not isinstance(resamples, (int, np.integer)) or resamples < 10:
        raise ValueError(f"resamples = {resamples!r}: must be an integer >= 10 (e.g. 1000)")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}: must be an integer >= 0")
    if not isinstance(outputs, Mapping) or not outputs:
        raise ValueError("outputs must be a non-empty mapping name -> array of one value per run")
    k, n, block = design.uncertainty.size, design.base_samples, design.block
    names = design.uncertainty.paths
    levels = tuple(n // d for d in _LEVELS)
    output_names = tuple(str(name) for name in outputs)
    shape = (len(output_names), k)
    S1, S1c, ST, STc = (np.full(shape, np.nan) for _ in range(4))
    S1v, STv = np.full((len(levels), *shape), np.nan), np.full((len(levels), *shape), np.nan)
    dropped: dict[str, int] = {}
    for o, name in enumerate(output_names):
        y = np.asarray(outputs[name], dtype=float)
        if y.shape != (design.runs,):
            raise ValueError(f"output {name!r} has shape {y.shape}; it must be ({design.runs},), one value per run")
        blocks = y.reshape(n, block)
        finite = np.all(np.isfinite(blocks), axis=1)
        dropped[name] = int(n - finite.sum())
        for level, m in enumerate(levels):
            s1, s1c, st, stc = _analyse(blocks[:m][finite[:m]], k, names, confidence, int(resamples), int(seed))
            S1v[level, o], STv[level, o] = s1, st
            if m == n:
                S1[o], S1c[o], ST[o], STc[o] = s1, s1c, st, stc
    return SobolResult(
        parameters=names,
        laws=tuple(p.law.to_spec() for p in design.uncertainty.parameters),
        outputs=output_names,
        base_samples=n,
        runs=design.runs,
        seed=design.seed,
        confidence_level=float(confidence),
        resamples=int(resamples),
        S1=S1, S1_conf=S1c, ST=ST, ST_conf=STc,
        convergence_samples=levels,
        S1_convergence=S1v, ST_convergence=STv,
        dropped=dropped,
    )


def sobol_analysis(
    uncertainty: Uncertainty,
    model: BatchModel,
    base_samples: int,
    *,
    seed: int = 0,
    batch_size: int | None = None,
    confidence: float = 0.95,
    resamples: int = 1000,
) -> SobolResult:
    """Design, evaluate and analyse: the Sobol' indices of every output of ``model`` (see the module docstring).

    ``model(values)`` is called on consecutive batches of at most ``batch_size`` rows (all rows at once by
    default) of the design's values ``(n, k)`` [SI] and returns ``{output: (n,)}`` with the same outputs for
    every batch. ``seed`` seeds the design and the bootstrap.
    """
    design = saltelli_design(uncertainty, base_samples, seed=seed)
    size = design.runs if batch_size is None else int(batch_size)
    if size < 1:
        raise ValueError(f"batch_size = {batch_size!r}: must be >= 1")
    collected: dict[str, list[np.ndarray]] = {}
    for start in range(0, design.runs, size):
        batch = design.values[start:start + size]
        result = model(batch)
        if not isinstance(result, Mapping) or not result:
            raise TypeError(f"the model must return a non-empty mapping output -> array, got {type(result).__name__}")
        if collected and set(result) != set(collected):
            raise ValueError(f"the model returned outputs {sorted(result)} for rows {start}.., "
                             f"{sorted(collected)} before")
        for name, values in result.items():
            arr = np.asarray(values, dtype=float).reshape(-1)
            if arr.shape != (len(batch),):
                raise ValueError(f"the model returned {arr.size} values of {name!r} for a batch of {len(batch)} rows")
            collected.setdefault(name, []).append(arr)
    outputs = {name: np.concatenate(parts) for name, parts in collected.items()}
    return sobol_indices(design, outputs, confidence=confidence, resamples=resamples, seed=seed)
