"""The robust operating point: decision variables that maximise the expected rate of penetration (or a quantile
of it), or minimise the expected mechanical specific energy, under chance constraints on the dysfunctions.

**Decision variables** are case parameters (:mod:`~drillstring.stochastic.parameters` paths, with the aliases
of :data:`DECISION_ALIASES`: ``top_speed``, ``weight_on_bit``, ``weight_on_hook``, the top drive's
``proportional_gain`` and ``integral_gain``), each between two bounds. Any numeric path the case can set is
accepted (a motor's flow rate once the case has one); a path the case cannot set, or a top-drive gain of a
case without a top drive, is refused naming it.

**A design point** is the case with the decision values set (:func:`~drillstring.stochastic.parameters.
with_parameters`) and ``samples`` realizations of the declared uncertainty there, exactly as one point of a
probabilistic map (:func:`~drillstring.stochastic.probabilistic_map.run_realization`: the weight-on-hook Normal
around the point's hook load of standard deviation ``sigma``, the other laws, the random reduced matrices
of ``model_dispersion``; realization ``s`` of every point draws from the stream ``(seed, s)``: common random
numbers). Each realization keeps the map's per-realization outputs (:data:`~drillstring.stochastic.
probabilistic_map.SAMPLE_OUTPUTS`).

**Objective** (:data:`OBJECTIVES`): the mean over a point's realizations of the time-mean ROP (maximised), of
the MSE (minimised), or the ``rate_of_penetration_qNN`` quantile (NN %) of the ROP (maximised).
**Constraints**: ``P(event) ≤ bound``, the event one of the map's (:data:`~drillstring.stochastic.
probabilistic_map.PROBABILITIES`: ``stick_slip``, ``buckling``, ``bounce``, ``impact``, ``instability``,
``torsional_instability``, ``axial_instability``, ``coexistence``) or a threshold on any per-realization
output, ``OUTPUT>VALUE`` or ``OUTPUT<VALUE`` [SI] (``surface_torque_amplitude>8000``: the surface torque's
amplitude stays below 8 kN·m with probability ≥ 1 − bound).

**Search** (:mod:`~drillstring.stochastic.surrogate`): an initial scrambled Sobol' design, then ``batch``
points at a time where a Gaussian-process surrogate of each output gives the largest constrained expected
improvement (a batch by the Kriging believer: :func:`~drillstring.stochastic.surrogate.next_batch`); the
realizations of a batch's points run in one pass of the study engine (one pool of workers); the last point of
the budget is the surrogate's recommendation itself. The answer is the evaluated point of
largest posterior objective whose posterior constraint means hold (none: the least-infeasible point,
flagged), with its Monte Carlo estimates, their binomial errors, the surrogate's error there and the
confidence of each constraint (:func:`~drillstring.stochastic.surrogate.constraint_confidence`).

**Resumable**: the realizations go to a Zarr store (:class:`OptimizationStore`, the study engine's
:class:`~drillstring.stochastic.store.TaskStore`) with the design values of each; a resumed search reads the
points already chosen from the store and chooses the next ones as the first run did (the choice is a
deterministic function of the estimates before the batch, so an interrupted batch is completed with the
points it had). A store of another case or settings is refused by its fingerprint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, Callable

import numpy as np

from drillstring.case import Case
from drillstring.checks import integer, real_number
from drillstring.checks import seed as check_seed
from drillstring.dynamics.indicators import has_top_drive
from drillstring.stochastic import MAX_OPTIMIZE_POINTS, MAX_OPTIMIZE_SAMPLES
from drillstring.stochastic.execution import Engine, StoreRun, TaskOutcome, run_locked
from drillstring.stochastic.operating_map import MapSettings
from drillstring.stochastic.parameters import WEIGHT_ON_HOOK, ParameterError, case_parameter, with_parameters
from drillstring.stochastic.probabilistic_map import (PROBABILITIES, SAMPLE_OUTPUTS, SampledMapSettings,
                                                      check_sampled_map, point_uncertainty, run_realization)
from drillstring.stochastic.runs import TOP_DRIVE_OUTPUTS, compile_kernels, with_top_drive_outputs
from drillstring.stochastic.store import DONE, FAILED, PENDING, ArraySpec, TaskStore
from drillstring.stochastic.surrogate import Estimates, SearchProblem, constraint_confidence, next_batch, recommend
from drillstring.stochastic.uncertainty import input_attributes
from drillstring.stochastic.uncertainty_settings import (
    NO_UNCERTAINTY,
    UncertaintyFields,
    UncertaintySettings,
    accepts_uncertainty_fields,
)

__all__ = ["DECISION_ALIASES", "DEFAULT_BATCH", "MAX_POINTS", "MAX_SAMPLES", "OBJECTIVES", "OptimizationSettings", "OptimizationStore",
           "point_estimates", "optimization_result", "run_optimization"]

#: Short names of decision variables -> case parameter path.
DECISION_ALIASES = {"top_speed": "operation.top_speed", "weight_on_bit": "operation.weight_on_bit",
                    "weight_on_hook": WEIGHT_ON_HOOK, "proportional_gain": "top_drive.proportional_gain",
                    "integral_gain": "top_drive.integral_gain"}
#: Objectives: name -> (per-realization output, maximised?); ``rate_of_penetration_qNN`` adds quantiles.
OBJECTIVES = {"rate_of_penetration": ("mean_rate_of_penetration", True),
              "mechanical_specific_energy": ("mechanical_specific_energy", False)}
#: Design points chosen together after the initial design, by default (docs/optimize.md, "Batches").
DEFAULT_BATCH = 4
#: Prior means of the constraints' surrogates.
PROBABILITY_MEANS = ("constant", "linear")
#: Bootstrap resamples of a quantile objective's Monte Carlo variance.
BOOTSTRAP = 200
#: Largest budget of design points (docs/optimize.md, "Limits") and realizations per design point.
MAX_POINTS, MAX_SAMPLES = MAX_OPTIMIZE_POINTS, MAX_OPTIMIZE_SAMPLES


def decision_path(name: str) -> str:
    return DECISION_ALIASES.get(name.strip(), name.strip())


def parse_objective(objective: str) -> tuple[str, bool, float | None]:
    """(output, maximised?, quantile level or None) of an objective name; ValueError (one line) otherwise."""
    text = str(objective).strip()
    if text in OBJECTIVES:
        return (*OBJECTIVES[text], None)
    if text.startswith("rate_of_penetration_q"):
        level = text[len("rate_of_penetration_q"):]
        if level.isdigit() and 1 <= int(level) <= 99:
            return "mean_rate_of_penetration", True, int(level) / 100.0
    raise ValueError(f"objective = {text!r}: must be rate_of_penetration (expected), rate_of_penetration_qNN (its "
                     "NN % quantile, NN from 1 to 99) or mechanical_specific_energy (expected)")


def event_function(event: str, outputs) -> tuple[str, Callable[[np.ndarray], np.ndarray]]:
    """(output, its event) of a constraint's event (module docstring); ValueError naming it otherwise."""
    text = str(event).strip()
    if f"{text}_probability" in PROBABILITIES:
        output, function, _ = PROBABILITIES[f"{text}_probability"]
        return output, function
    for sign in (">", "<"):
        if sign in text:
            output, value = (part.strip() for part in text.split(sign, 1))
            if output in TOP_DRIVE_OUTPUTS and output not in outputs:
                raise ValueError(f"constraint {text!r}: {output} is an output of a top drive only (this case's top "
                                 "turns at an imposed speed: top_drive.controller = 'imposed_speed')")
            if output not in outputs:
                raise ValueError(f"constraint {text!r}: {output!r} is no per-realization output; one of "
                                 f"{', '.join(outputs)}")
            try:
                threshold = float(value)
            except ValueError:
                raise ValueError(f"constraint {text!r}: the threshold {value!r} must be a number [SI]") from None
            if not math.isfinite(threshold):
                raise ValueError(f"constraint {text!r}: the threshold must be finite")
            return output, ((lambda v: v > threshold) if sign == ">" else (lambda v: v < threshold))
    named = ", ".join(name[:-len("_probability")] for name in PROBABILITIES)
    raise ValueError(f"constraint {text!r}: the event must be one of {named}, or OUTPUT>VALUE / OUTPUT<VALUE")


def checked_budget(samples, initial=None, points=None, batch=None, probability_mean="constant"):
    """A search's budget checked (TypeError or ValueError naming the field, its value and range): ``(samples,
    initial, points, batch)`` as Python integers, None left as None (not given yet: a default follows); ``points``
    only with ``initial`` (its lower bound)."""
    samples = integer("samples", samples, low=2, high=MAX_SAMPLES,
                      allowed=f"an integer from 2 to {MAX_SAMPLES} (realizations per design point)")
    if initial is not None:
        initial = integer("initial", initial, low=2, high=MAX_POINTS,
                          allowed=f"an integer from 2 to {MAX_POINTS} (points of the initial design)")
    if points is not None and initial is not None:  # else checked once the default of initial is known
        points = integer("points", points, low=initial, high=MAX_POINTS,
                         allowed=f"an integer from initial = {initial} to {MAX_POINTS} (design points in all)")
    if batch is not None:
        batch = integer("batch", batch, low=1, high=MAX_POINTS,
                        allowed=f"an integer from 1 to {MAX_POINTS} (design points chosen together)")
    if probability_mean not in PROBABILITY_MEANS:
        raise ValueError(f"probability_mean = {probability_mean!r}: must be one of {', '.join(PROBABILITY_MEANS)}")
    return samples, initial, points, batch


@accepts_uncertainty_fields
@dataclass(frozen=True)
class OptimizationSettings(UncertaintyFields):
    """What defines a search; a resumed one must have the same settings.

    Attributes:
        variables: ``((path, low, high), ...)`` decision variables and bounds [SI], ``low < high``.
        objective: see :func:`parse_objective`.
        constraints: ``((event, bound), ...)``: ``P(event) ≤ bound``, bound in (0, 1).
        samples: realizations per design point, 2 to :data:`MAX_SAMPLES`.
        points: design points of the search (budget), ``initial`` to :data:`MAX_POINTS` (equal to
            ``initial``: the initial design alone, the answer its best point).
        initial: points of the initial design (>= 2).
        batch: points chosen together and evaluated in one pass after the initial design (>= 1; more than
            ``points − initial``: all of them at once).
        probability_mean: the prior mean of the constraints' surrogates, ``"constant"`` or ``"linear"`` (a
            plane by generalised least squares: :class:`~drillstring.stochastic.surrogate.GaussianProcess`).
        seed, t_end, output_step, transient, sigma, uncertainty: as for a probabilistic map
            (:class:`~drillstring.stochastic.probabilistic_map.SampledMapSettings`); the uncertainty's fields
            (``laws``, ``correlated``, ``correlation``, ``model_dispersion``) are also accepted as keywords and
            read through.
    """

    variables: tuple[tuple[str, float, float], ...]
    objective: str = "rate_of_penetration"
    constraints: tuple[tuple[str, float], ...] = ()
    samples: int = 8
    points: int = 16
    initial: int = 8
    batch: int = DEFAULT_BATCH
    probability_mean: str = "constant"
    seed: int = 0
    t_end: float = 10.0
    output_step: float = 0.01
    transient: float | None = None
    sigma: float | None = None
    uncertainty: UncertaintySettings = NO_UNCERTAINTY

    def __post_init__(self) -> None:
        if not self.variables:
            raise ValueError("variables: give at least one decision variable with its bounds")
        variables = []
        for item in self.variables:
            path, low, high = item
            path = decision_path(str(path))
            low = real_number(f"{path} lower bound", low)
            high = real_number(f"{path} upper bound", high)
            if not low < high:
                raise ValueError(f"{path}: bounds {low:.6g} to {high:.6g} are reversed or equal (the lower bound "
                                 "must be less than the upper one)")
            if path in (p for p, _, _ in variables):
                raise ValueError(f"{path}: a decision variable given twice")
            variables.append((path, low, high))
        paths = {p for p, _, _ in variables}
        if {"operation.weight_on_bit", WEIGHT_ON_HOOK} <= paths:
            raise ValueError("weight_on_bit and weight_on_hook: give one of them (one sets the other)")
        object.__setattr__(self, "variables", tuple(variables))
        parse_objective(self.objective)
        constraints = []
        for event, bound in self.constraints:
            bound = real_number(f"constraint {event} bound", bound, low=0.0, high=1.0, low_open=True,
                                high_open=True, allowed="a probability in (0, 1)")
            constraints.append((str(event).strip(), bound))
        object.__setattr__(self, "constraints", tuple(constraints))
        budget = checked_budget(self.samples, self.initial, self.points, self.batch, self.probability_mean)
        for name, value in zip(("samples", "initial", "points", "batch"), budget):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "seed", check_seed(self.seed))
        # A law of the top speed, weight-on-bit or hook load is refused by the point's map settings (sigma is
        # the hook load's uncertainty around each point's own value); any other decision variable:
        self._check_uncertainty()
        clash = next((p for p in self.uncertainty.paths if p in paths), None)
        if clash is not None:
            raise ValueError(f"{clash}: a decision variable cannot carry a law too")

    @property
    def problem(self) -> SearchProblem:
        output, maximize, _ = parse_objective(self.objective)
        return SearchProblem(tuple((low, high) for _, low, high in self.variables),
                             tuple(b for _, b in self.constraints), maximize, self.initial, self.seed,
                             self.probability_mean == "linear")

    @property
    def realizations(self) -> int:
        return self.points * self.samples


def design_case(case: Case, settings: OptimizationSettings, values) -> Case:
    """The case at a design point: the decision ``values`` [SI] set."""
    return with_parameters(case, {path: float(v) for (path, _, _), v in zip(settings.variables, values)})


def point_settings(at_point: Case, settings: OptimizationSettings) -> SampledMapSettings:
    """A one-point probabilistic map of the design point's case (its top speed and weight-on-bit)."""
    grid = MapSettings((at_point.operation.top_speed,), (at_point.operation.weight_on_bit,), t_end=settings.t_end,
                       output_step=settings.output_step, transient=settings.transient)
    return SampledMapSettings(grid, samples=settings.samples, seed=settings.seed, sigma=settings.sigma,
                              uncertainty=settings.uncertainty)


def check_optimization(case: Case, settings: OptimizationSettings) -> None:
    """Refuse (ValueError, one line, before anything runs): a decision variable the case cannot vary (an
    unknown path, a top-drive parameter when the top turns at an imposed speed), bounds outside the parameter's range, an event of no
    output, and uncertainty that cannot be drawn at some corner of the box (as a map refuses its points)."""
    for path, low, high in settings.variables:
        if path.startswith("top_drive.") and not has_top_drive(case):
            raise ValueError(f"{path}: the case cannot vary it (top_drive.controller = 'imposed_speed': no top-drive "
                             "controller; choose pi, soft_torque or z_torque in the case)")
        try:
            if path != WEIGHT_ON_HOOK:
                case_parameter(case, path)
        except ParameterError as error:
            raise ValueError(f"decision variable {path}: the case cannot vary it ({error})") from None
    outputs = with_top_drive_outputs(SAMPLE_OUTPUTS, has_top_drive(case))
    for event, _ in settings.constraints:
        event_function(event, outputs)
    corners = np.array(np.meshgrid(*[(low, high) for _, low, high in settings.variables])).reshape(
        len(settings.variables), -1).T
    for corner in corners:
        try:
            at = design_case(case, settings, corner)
        except ParameterError as error:
            raise ValueError(f"bounds: {error}") from None
        check_sampled_map(at, point_settings(at, settings))


class OptimizationStore(TaskStore):
    """A search's Zarr store: one row per realization (``point × samples + sample``), each output of
    :data:`~drillstring.stochastic.probabilistic_map.SAMPLE_OUTPUTS`, the drawn values and the design values."""

    kind = "optimization"
    row_dim = "realization"
    noun = "realizations"
    differ = ("case or settings differ: variables, bounds, objective, constraints, samples, points, batch, "
              "probability_mean, seed, laws, t_end")

    def __init__(self, path: str | Path, case: Case, settings: OptimizationSettings) -> None:
        at = design_case(case, settings, [0.5 * (lo + hi) for _, lo, hi in settings.variables])
        law = point_uncertainty(at, point_settings(at, settings), 0)
        layout = {
            **{name: ArraySpec(("realization",), attributes={"units": unit, "long_name": text})
               for name, (unit, text) in with_top_drive_outputs(SAMPLE_OUTPUTS, has_top_drive(case)).items()},
            "input_values": ArraySpec(("realization", "parameter")),
            "design_values": ArraySpec(("realization", "variable")),
        }
        sizes = {"realization": settings.realizations, "parameter": law.size, "variable": len(settings.variables)}
        super().__init__(path, case_toml=case.to_toml(), settings=settings.store_settings(), layout=layout, sizes=sizes,
                         attrs={"variables": [p for p, _, _ in settings.variables], **input_attributes(law)})


def _task(case: Case, settings: OptimizationSettings, item) -> TaskOutcome:
    """Realization ``row`` of the design point ``values``; never raises."""
    row, values = item
    sample = row % settings.samples
    try:
        at = design_case(case, settings, values)
        outcome = run_realization(at, point_settings(at, settings), sample)
    except (ValueError, ParameterError) as error:
        outcome = TaskOutcome(sample, FAILED, str(error), {name: math.nan for name in SAMPLE_OUTPUTS})
    outcome.index = row
    outcome.values["design_values"] = np.asarray(values, dtype=float)
    return outcome


def _read(store: OptimizationStore, names) -> dict[str, np.ndarray]:
    return {name: np.asarray(store.group[name][...], dtype=float) for name in names}


def point_estimates(settings: OptimizationSettings, arrays: dict[str, np.ndarray], status: np.ndarray,
                    outputs) -> dict[str, np.ndarray]:
    """Per design point (rows of ``samples``), over its finished realizations: ``count``, the objective's
    estimate and Monte Carlo variance (variance/n of a mean; bootstrap of a quantile), each constraint's
    probability ``k/n`` and its variance ``p̃(1 − p̃)/n`` (``p̃ = (k + ½)/(n + 1)``)."""
    output, _, level = parse_objective(settings.objective)
    s = settings.samples
    shape = (len(status) // s, s)
    done = (status == DONE).reshape(shape)
    count = done.sum(axis=1)
    values = np.where(done, arrays[output].reshape(shape), np.nan)
    objective = np.full(shape[0], np.nan)
    variance = np.full(shape[0], np.nan)
    rng = np.random.default_rng([settings.seed, 3])
    for p in range(shape[0]):
        v = values[p][np.isfinite(values[p])]
        if v.size < 2 or v.size < count[p]:  # an undefined output (MSE without penetration): no estimate
            continue
        if level is None:
            objective[p], variance[p] = v.mean(), v.var(ddof=1) / v.size
        else:
            objective[p] = np.quantile(v, level)
            boot = np.quantile(v[rng.integers(0, v.size, (BOOTSTRAP, v.size))], level, axis=1)
            variance[p] = max(boot.var(ddof=1), 1e-30)
    probabilities = np.full((shape[0], len(settings.constraints)), np.nan)
    variances = np.full_like(probabilities, np.nan)
    for k, (event, _) in enumerate(settings.constraints):
        name, function = event_function(event, outputs)
        with np.errstate(invalid="ignore"):
            hits = (function(arrays[name].reshape(shape)) & done).sum(axis=1)
        n = np.maximum(count, 1)
        probabilities[:, k] = np.where(count > 0, hits / n, np.nan)
        tilde = (hits + 0.5) / (n + 1)
        variances[:, k] = tilde * (1 - tilde) / n
    return {"count": count, "objective": objective, "objective_variance": variance,
            "probabilities": probabilities, "probability_variances": variances}


def _history(store: OptimizationStore, settings: OptimizationSettings, outputs, upto: int):
    """(points (rows), Estimates) of the finished design points before ``upto`` with at least one finished
    realization (those the surrogate is fitted to)."""
    status = store.status()
    design = np.asarray(store.group["design_values"][...], dtype=float)
    arrays = _read(store, outputs)
    estimates = point_estimates(settings, arrays, status, outputs)
    s = settings.samples
    keep = [p for p in range(upto) if estimates["count"][p] > 0]
    if not keep:
        return None, None
    x = np.array([design[p * s] for p in keep])
    return x, Estimates(estimates["objective"][keep], estimates["objective_variance"][keep],
                        estimates["probabilities"][keep], estimates["probability_variances"][keep])


def _stored_design(store: OptimizationStore, settings: OptimizationSettings, point: int) -> np.ndarray | None:
    s = settings.samples
    status = store.status()[point * s:(point + 1) * s]
    rows = np.flatnonzero(status != PENDING)
    if not rows.size:
        return None
    return np.asarray(store.group["design_values"][point * s + int(rows[0])], dtype=float)


def run_optimization(case: Case, settings: OptimizationSettings, store_path: str | Path, engine: Engine = Engine(),
                     *, finish: Callable[[StoreRun], Any] | None = None) -> StoreRun:
    """Run (or resume) the search into its Zarr store on ``engine`` (module docstring), then ``finish(run)``
    under the store's lock (checked first: :func:`check_optimization`): one pass of the study engine
    (:func:`~drillstring.stochastic.execution.run_locked`) per batch of design points, each batch chosen from
    the realizations the previous ones wrote (a batch already in the store, from an interrupted run, is kept)."""
    check_optimization(case, settings)
    outputs = tuple(with_top_drive_outputs(SAMPLE_OUTPUTS, has_top_drive(case)))
    problem = settings.problem

    def batches(store: OptimizationStore):
        point = 0
        while point < settings.points:
            batch = range(point, settings.initial) if point < settings.initial else range(
                point, min(point + settings.batch, settings.points))
            stored = [_stored_design(store, settings, p) for p in batch]
            if any(values is None for values in stored):
                x, estimates = _history(store, settings, outputs, batch.start)
                if engine.note is not None and x is not None and batch.start >= settings.initial:
                    which = (f"design point {batch.stop}" if len(batch) == 1 else
                             f"design points {batch.start + 1}–{batch.stop}")
                    engine.note(f"{which} of {settings.points}: chosen by the surrogates fitted to {len(x)} points")
                chosen = next_batch(problem, x, estimates, settings.points, batch.start, len(batch))
                stored = [chosen[k] if values is None else values for k, values in enumerate(stored)]
            status = store.status()
            yield [(r, (r, tuple(float(v) for v in values))) for p, values in zip(batch, stored)
                   for r in range(p * settings.samples, (p + 1) * settings.samples) if status[r] == PENDING]
            point = batch.stop

    return run_locked(store_path, lambda: OptimizationStore(Path(store_path), case, settings), None,
                      partial(_task, case, settings), engine, passes=batches, prepare=partial(compile_kernels, case),
                      finish=finish, what="optimization")


def optimization_result(store: OptimizationStore) -> dict[str, Any]:
    """The search's answer (SI, JSON-ready) from a finished store: the design points and their estimates, the
    recommended point, whether it is feasible, its objective and each constraint's probability with the Monte
    Carlo and surrogate errors and the confidence; plus ``surrogates`` (the fitted processes, for figures)."""
    settings_dict = dict(store.group.attrs["settings"])
    settings = OptimizationSettings(**{k: (tuple(tuple(x) if isinstance(x, list) else x for x in v)
                                           if isinstance(v, list) else v) for k, v in settings_dict.items()})
    outputs = [name for name in with_top_drive_outputs(SAMPLE_OUTPUTS, True) if name in store.group]
    status = store.status()
    arrays = _read(store, outputs)
    estimates = point_estimates(settings, arrays, status, outputs)
    design = np.asarray(store.group["design_values"][...], dtype=float)[::settings.samples]
    problem = settings.problem
    x, history = _history(store, settings, outputs, settings.points)
    if x is None:
        raise ValueError(f"{store.path}: no design point has a finished realization (every run failed; causes in "
                         "the store's failures)")
    surrogates = history.fit(problem, x)
    found = recommend(problem, x, surrogates, candidates=False)
    point = int(np.argmin(np.linalg.norm(design - found.point, axis=1)))
    count = int(estimates["count"][point])
    unit = problem.to_unit(found.point)
    constraints = []
    for k, (event, bound) in enumerate(settings.constraints):
        p = float(estimates["probabilities"][point, k])
        surrogate_mean, surrogate_sd = (float(v[0]) for v in surrogates.constraints[k].predict(unit))
        combined, confidence = constraint_confidence(p, count, bound, surrogate_sd)
        constraints.append({"event": event, "bound": bound, "probability": p,
                            "binomial_standard_error": math.sqrt(p * (1 - p) / max(count, 1)),
                            "surrogate_mean": surrogate_mean, "surrogate_standard_deviation": surrogate_sd,
                            "combined_standard_deviation": combined, "confidence": confidence,
                            "met": p <= bound})
    objective_se = math.sqrt(estimates["objective_variance"][point]) if math.isfinite(
        estimates["objective_variance"][point]) else math.nan
    return {
        "variables": [p for p, _, _ in settings.variables],
        "bounds": [[lo, hi] for _, lo, hi in settings.variables],
        "objective": settings.objective,
        "maximize": problem.maximize,
        "samples": settings.samples,
        "points": settings.points,
        "initial": settings.initial,
        "realizations": settings.realizations,
        "feasible": bool(found.feasible),
        "recommended": {
            "point": point,
            "values": [float(v) for v in design[point]],
            "objective": float(estimates["objective"][point]),
            "objective_standard_error": objective_se,
            "surrogate_objective": found.objective,
            "surrogate_objective_standard_deviation": found.objective_sd,
            "realizations": count,
            "constraints": constraints,
        },
        "design": [[float(v) for v in row] for row in design],
        "estimates": {"count": [int(c) for c in estimates["count"]],
                      "objective": [float(v) for v in estimates["objective"]],
                      "probabilities": [[float(v) for v in row] for row in estimates["probabilities"]]},
        "surrogates": surrogates,
        "problem": problem,
    }
