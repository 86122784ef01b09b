"""Monte Carlo study of random case parameters (docs/model.md §11): realizations, their Zarr store and resume.

Each realization ``s`` draws the values of the study's random parameters from their Maximum-Entropy laws
with its own random stream (:meth:`~drillstring.stochastic.uncertainty.Uncertainty.draw`, keyed by
``(seed, s)`` only; a random weight-on-hook is one such parameter, the derived path ``weight_on_hook``,
whose draw sets the consistent weight-on-bit ``wob = weight − woh``), builds the realized case, recomputes
the static state, the prestress and the modes, integrates the time response and returns the observables on
the common output grid.

Realizations run through :func:`~drillstring.stochastic.execution.run_tasks` (local processes by
default, or a Dask distributed cluster when a scheduler address is given; worker deaths isolated) into a
:class:`~drillstring.stochastic.store.TaskStore` (:class:`StudyStore`): each realization's data first,
then its status flag, so an interrupted study (Ctrl-C, killed process, lost worker) resumes with the same
command and skips finished realizations; since each realization depends only on ``(seed, s)`` the
resumed result equals an uninterrupted one. A realization that fails is stored with its cause and
excluded from the statistics.

A study's store is locked while a study runs on it (a second study on the same store is refused at
once, a lock left by a killed study is taken over with a note), created atomically (built under a
temporary name, then renamed), and checked when opened (a folder that is not a complete study store is
refused with what is missing). Settings that would make realizations fail are refused before running:
fewer than 2 realizations, a law that puts a probability above :data:`OUT_OF_RANGE_PROBABILITY` outside its
parameter's range (for the weight-on-hook: a weight-on-bit outside (0, string weight)), or time histories
larger than :data:`MAX_STUDY_BYTES`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any, Callable

import numpy as np
import zarr

from drillstring.case import Case
from drillstring.checks import integer
from drillstring.checks import seed as check_seed
from drillstring.dynamics.indicators import RENAMED_METRICS, TOP_DRIVE_METRICS, has_top_drive
from drillstring.dynamics.rom import case_reduced_model
from drillstring.stochastic.random_matrices import (
    model_generator,
    random_reduced_model,
)
from drillstring.dynamics.growth_rates import family_growth_rates
from drillstring.dynamics.simulate import (
    SimulationError,
    SimulationResult,
    output_grid,
    output_points,
    run_window,
    simulate_model,
)
from drillstring.quantities import STUDY_OBSERVABLES, TOP_DRIVE_OBSERVABLES, stored_observables  # noqa: F401
from drillstring.stochastic.execution import Engine, StoreRun, run_locked
from drillstring.stochastic.parameters import WEIGHT_ON_HOOK
from drillstring.stochastic.runs import (
    FAMILY_GROWTH_METRICS,
    REALIZATION_METRICS,
    metrics_transient,
    realization_metrics,
    simulation_options,
)
from drillstring.stochastic.study_model import case_text, note_model, prepare_runs, realization_model
from drillstring.stochastic.store import DONE, FAILED, PENDING, ArraySpec, StoreError, TaskStore
from drillstring.stochastic.uncertainty import Uncertainty, input_attributes
from drillstring.stochastic.uncertainty_settings import (
    NO_UNCERTAINTY,
    UncertaintyFields,
    UncertaintySettings,
    accepts_uncertainty_fields,
)
from drillstring.units import display_unit, quantity_text



def study_observables(case: Case) -> tuple[str, ...]:
    """The observables a study of ``case`` stores per realization: :data:`STUDY_OBSERVABLES`, and
    :data:`TOP_DRIVE_OBSERVABLES` when the case has a top drive."""
    return STUDY_OBSERVABLES + (TOP_DRIVE_OBSERVABLES if has_top_drive(case) else ())

NOMINAL = -1  # index of the deterministic run at the mean of every uncertain parameter
#: Fewest realizations of a study: the statistics (standard deviation, envelopes) need two.
MIN_SAMPLES = 2
#: Largest accepted probability that a drawn value falls outside its parameter's allowed range (for the
#: weight-on-hook: a weight-on-bit outside (0, string weight)), where the realization cannot run and is
#: recorded as failed. The Normal law is unbounded; 1e-3 lets a 1000-realization study expect about one
#: failed draw, and on the reference case (100 kN on the bit) accepts σ_WOH up to 32.4 kN.
OUT_OF_RANGE_PROBABILITY = 1e-3


#: Largest memory [bytes] of a study's time histories (every realization's observables and radial
#: displacements on the output grid): its statistics load them at once. 4 GiB, e.g. 20,000 realizations of
#: the reference case's 30 s at 0.01 s.
MAX_STUDY_BYTES = 4 * 2**30


@accepts_uncertainty_fields
@dataclass(frozen=True)
class StudySettings(UncertaintyFields):
    """What defines a study's realizations; a resumed study must have the same settings.

    The random parameters are every ``(path, law)`` of ``uncertainty.laws`` (case-parameter paths and law
    specs, :mod:`drillstring.stochastic.uncertainty`; a random weight-on-hook is the path ``weight_on_hook``,
    e.g. :func:`weight_on_hook_normal`), at least one, with the correlation and the model dispersion of
    ``uncertainty`` (:class:`~drillstring.stochastic.uncertainty_settings.UncertaintySettings`). The
    uncertainty's fields are also accepted as keywords and read through (``StudySettings(samples=100,
    laws=..., model_dispersion=...)``, ``settings.laws``).

    Attributes:
        samples: number of realizations n_s.
        seed: root seed of the realizations' random streams, in [0, 2**64 - 1].
        t_end: simulated time per realization [s].
        output_step: output step [s].
        uncertainty: the random parameters' laws, their correlation and the model dispersion
            ``(δ_M, δ_K, δ_D)`` of the random reduced mass, stiffness and damping matrices
            (:mod:`~drillstring.stochastic.random_matrices`; all 0: none). Realization ``i`` draws them from
            :func:`~drillstring.stochastic.random_matrices.model_generator` ``(seed, i)``; the nominal run
            keeps the nominal model.

    Checked when built (TypeError / ValueError naming the field; the uncertainty by
    :class:`~drillstring.stochastic.uncertainty_settings.UncertaintySettings`, the time window by
    :func:`~drillstring.dynamics.simulate.run_window`).
    """

    samples: int
    seed: int = 0
    t_end: float = 30.0
    output_step: float = 0.01
    uncertainty: UncertaintySettings = NO_UNCERTAINTY

    def __post_init__(self) -> None:
        samples = integer("samples", self.samples, low=MIN_SAMPLES,
                          allowed=f"an integer >= {MIN_SAMPLES} (the statistics need at least 2 realizations)")
        self._check_uncertainty()
        if not self.uncertainty.laws:
            raise ValueError("no random parameter: give at least one parameter law (e.g. of weight_on_hook)")
        window = run_window(self.t_end, self.output_step)
        object.__setattr__(self, "samples", samples)
        object.__setattr__(self, "seed", check_seed(self.seed))
        object.__setattr__(self, "t_end", window.t_end)
        object.__setattr__(self, "output_step", window.output_step)

    @property
    def time(self) -> np.ndarray:
        """The common output grid [s] (the integrator's grid: k·Δt, t_end included)."""
        return output_grid(self.t_end, self.output_step)


def check_study_size(case: Case, settings: StudySettings) -> None:
    """Refuse (ValueError, one line with the numbers) a study whose time histories would take more than
    :data:`MAX_STUDY_BYTES`: samples × output times × (observables (4, 6 with a top drive) + probes) × 8
    bytes."""
    points = output_points(settings.t_end, settings.output_step)
    size = settings.samples * points * (len(study_observables(case)) + len(case.mesh.probes)) * 8
    if size > MAX_STUDY_BYTES:
        raise ValueError(f"samples = {settings.samples} realizations of {points} output times: their time histories "
                         f"take {size / 2**30:.3g} GiB, above the limit of {MAX_STUDY_BYTES / 2**30:g} GiB (fewer "
                         "samples, a longer output_step or a shorter t_end)")


def weight_on_hook_normal(case: Case, sigma: float) -> tuple[str, str]:
    """The ``(path, spec)`` of the weight-on-hook Normal around the case's hook load
    (:func:`nominal_weight_on_hook`) of standard deviation ``sigma`` [N] (the law of a study's ``sigma``)."""
    return WEIGHT_ON_HOOK, f"normal {float(nominal_weight_on_hook(case))!r} {float(sigma)!r}"


@dataclass
class RealizationOutcome:
    """What one realization returns to the driver (picklable): the drawn values ``inputs`` [SI] in the
    order of the study's parameters, the resulting weight-on-hook and weight-on-bit [N] (NaN where the
    draw gave no valid case), the observables on the output grid."""

    index: int
    weight_on_hook: float
    weight_on_bit: float
    status: int
    message: str
    observables: dict[str, np.ndarray] = field(default_factory=dict)
    radial_displacement: np.ndarray | None = None
    wall_time: float = 0.0
    n_rhs: int = 0
    lowest_lateral_eigenvalue: float = math.nan
    inputs: np.ndarray | None = None
    metrics: dict[str, float] = field(default_factory=dict)


def nominal_weight_on_hook(case: Case) -> float:
    """Mean weight-on-hook [N] of the default law: the case's static hook load, weight − weight_on_bit."""
    return case.weight - case.operation.weight_on_bit


#: Built uncertainties (their MaxEnt laws), by study, in this process.
_UNCERTAINTIES: dict[tuple, Uncertainty] = {}


def study_uncertainty(case: Case, settings: StudySettings, *, check: bool = False) -> Uncertainty:
    """The study's random parameters and their joint law: ``settings.laws`` in order.

    ``check=True`` refuses (:class:`~drillstring.stochastic.parameters.ParameterError`, one line) a law that
    puts a probability above :data:`OUT_OF_RANGE_PROBABILITY` outside its parameter's range; otherwise any
    law is accepted (draws outside the range fail their realization). Built once per process and study."""
    key = (case_text(case), settings, check)
    if key in _UNCERTAINTIES:
        return _UNCERTAINTIES[key]
    found = settings.uncertainty.law(case, tolerance=OUT_OF_RANGE_PROBABILITY if check else 1.0)
    if len(_UNCERTAINTIES) > 16:
        _UNCERTAINTIES.clear()
    _UNCERTAINTIES[key] = found
    return found


def draw_inputs(case: Case, settings: StudySettings, index: int) -> np.ndarray:
    """The values [SI] of the random parameters of realization ``index`` (their means for
    :data:`NOMINAL`): depend only on ``(seed, index)`` and the laws."""
    law = study_uncertainty(case, settings)
    if index == NOMINAL:
        return law.mean()
    return law.draw(settings.seed, [index])[0]


def _normal_tail(z: float) -> float:
    """P(Z > z) for a standard Normal Z."""
    return 0.5 * math.erfc(z / math.sqrt(2.0))


def weight_on_bit_out_of_range_probability(case: Case, sigma: float) -> float:
    """Probability that a weight-on-hook drawn from the study's Normal law (mean
    :func:`nominal_weight_on_hook`, standard deviation ``sigma`` [N]) gives a weight-on-bit
    ``wob = weight − woh`` outside (0, weight), where no realization can run: with ``wob`` Normal of
    mean ``wob_0`` and standard deviation σ, ``P = Φ(−wob_0/σ) + Φ(−(weight − wob_0)/σ)``."""
    wob = case.operation.weight_on_bit
    return _normal_tail(wob / sigma) + _normal_tail((case.weight - wob) / sigma)


def largest_accepted_sigma(case: Case, probability: float = OUT_OF_RANGE_PROBABILITY) -> float:
    """The σ [N] at which :func:`weight_on_bit_out_of_range_probability` equals ``probability``
    (the probability grows with σ; bisection on a log scale to 1e-9 relative)."""
    low, high = 1e-9 * case.weight, case.weight
    while weight_on_bit_out_of_range_probability(case, high) < probability:
        high *= 2.0
    for _ in range(200):
        middle = math.sqrt(low * high)
        if weight_on_bit_out_of_range_probability(case, middle) < probability:
            low = middle
        else:
            high = middle
        if high / low < 1.0 + 1e-9:
            break
    return low


#: Above this probability of a buckled draw (weight-on-bit beyond the critical one), a study warns before
#: it runs: about one realization in a thousand (σ = 5000 N on the reference case gives 2.35e-3).
BUCKLING_WARNING_PROBABILITY = 1e-3


#: The criterion a study of a case with ``[well]`` states (``summary["buckling"]["criterion"]``).
WELL_BUCKLING_CRITERION = "sinusoidal buckling along the well path, Dawson-Paslay"


def study_buckling_margin(case: Case, settings: StudySettings) -> dict:
    """The lateral buckling margin of a study's draws (SI): ``critical_weight_on_bit`` [N] of the case
    (:func:`drillstring.buckling.case_critical_weight_on_bit`, at the nominal values of every parameter: the
    straight string's, or with ``[well]`` sinusoidal buckling along the well path, then with ``criterion``
    :data:`WELL_BUCKLING_CRITERION`),
    ``probability`` that a draw buckles the string — from the law of the weight-on-hook
    (:func:`drillstring.buckling.buckling_probability`) or of the weight-on-bit when one of them is random,
    else 0 or 1 as the nominal string is straight or buckled —, ``expected`` buckled realizations
    (probability × samples), ``warning``: the note of :func:`buckling_note` (SI) when the probability is above
    :data:`BUCKLING_WARNING_PROBABILITY`, else None, and for that note ``lateral`` (whether the case has lateral
    modes) and ``source`` (which law or value gives the probability)."""
    from drillstring.buckling import buckling_probability, case_critical_weight_on_bit

    critical = case_critical_weight_on_bit(case)
    law = study_uncertainty(case, settings)
    if WEIGHT_ON_HOOK in law.paths:
        density = law.parameters[law.paths.index(WEIGHT_ON_HOOK)].law.density
        probability, what = buckling_probability(density, case.weight, critical), "the weight-on-hook law"
    elif "operation.weight_on_bit" in law.paths:
        density = law.parameters[law.paths.index("operation.weight_on_bit")].law.density
        probability, what = 1.0 - float(density.cdf(critical)), "the weight-on-bit law"
    else:
        probability, what = float(case.operation.weight_on_bit > critical), "the case's weight-on-bit"
    # without lateral modes the model has no lateral motion: a buckled string stays on the axis
    lateral = case.reduced_model.lateral_modes > 0 or case.reduced_model.lateral_cutoff > 0
    out = {"critical_weight_on_bit": float(critical), "probability": float(probability),
           "expected": float(probability * settings.samples), "lateral": lateral, "source": what}
    if case.well is not None:
        out["criterion"] = WELL_BUCKLING_CRITERION
    out["warning"] = buckling_note(out, settings.samples) if probability > BUCKLING_WARNING_PROBABILITY else None
    return out


def buckling_note(buckling: dict, samples: int, units: str | None = "si") -> str:
    """The note a study gives on its draws' buckling (``buckling`` from :func:`study_buckling_margin`), a plain
    sentence with the critical weight-on-bit in the unit system ``units``: what puts the weight-on-bit above
    it, with what probability, about how many of the ``samples`` realizations that makes, and what happens to
    their string."""
    force = display_unit("force", units)
    critical, probability = force(buckling["critical_weight_on_bit"]), buckling["probability"]
    consequence = ("their string buckles laterally near the bit and bows to the borehole wall"
                   if buckling["lateral"] else
                   "their string buckles, but the case has no lateral modes, so it stays on the hole's axis")
    criterion = buckling.get("criterion", "lateral buckling")
    if "criterion" in buckling:  # a well: the model's lateral dynamics is a straight string's, not the hole's
        consequence = ("their string buckles in the well; the reduced model's lateral dynamics is a straight "
                       "string's, not the curved hole's")
    return (f"{buckling['source']} puts the weight-on-bit above the critical {critical:,.2f} {force.label} "
            f"({criterion}) with probability {100 * probability:.3g} %, about "
            f"{probability * samples:.2g} of the {samples} realizations: {consequence}; the study counts them")


def check_study(case: Case, settings: StudySettings) -> None:
    """Refuse (ValueError, one line) settings whose draws would often be impossible: a Normal weight-on-hook
    with a probability above :data:`OUT_OF_RANGE_PROBABILITY` of a weight-on-bit outside (0, string weight)
    (the message names the largest accepted standard deviation), and any law that puts more than that
    probability outside its parameter's range; also unknown paths, bad laws and correlations, drawn
    parameters that would not take effect (:data:`~drillstring.stochastic.parameters.NOT_DRAWN`) and a
    study too large for memory (:func:`check_study_size`)."""
    check_study_size(case, settings)
    law = study_uncertainty(case, settings)
    if WEIGHT_ON_HOOK in law.paths:
        declared = law.parameters[law.paths.index(WEIGHT_ON_HOOK)].law
        sigma = declared.density.std() if declared.law == "normal" else None
        p = weight_on_bit_out_of_range_probability(case, sigma) if sigma else 0.0
        if p > OUT_OF_RANGE_PROBABILITY:
            raise ValueError(
                f"sigma = {sigma:.6g} N: with the weight-on-hook Normal around "
                f"{quantity_text(nominal_weight_on_hook(case), 'force', digits=6)}, the weight-on-bit falls outside (0, "
                f"{quantity_text(case.weight, 'force', digits=6)}) (the string's weight) with probability {p:.3g}, above "
                f"{OUT_OF_RANGE_PROBABILITY:g}: such realizations cannot run; sigma must be at most "
                f"{largest_accepted_sigma(case):,.0f} N ({quantity_text(largest_accepted_sigma(case), 'force')}) "
                "for this case"
            )
    study_uncertainty(case, settings, check=True)
    if settings.model.active:
        settings.model.check_model(case_reduced_model(case))


def run_realization(case: Case, settings: StudySettings, index: int) -> RealizationOutcome:
    """Draw, solve and simulate realization ``index``; never raises for a failed realization."""
    start = time.perf_counter()
    outcome = RealizationOutcome(index, math.nan, math.nan, FAILED, "")
    n_t = len(settings.time)
    try:
        law = study_uncertainty(case, settings)
        values = draw_inputs(case, settings, index)
        outcome.inputs = values
        if WEIGHT_ON_HOOK in law.paths:  # recorded even when the draw is impossible
            outcome.weight_on_hook = float(values[law.paths.index(WEIGHT_ON_HOOK)])
            outcome.weight_on_bit = case.weight - outcome.weight_on_hook
        realized = law.apply(case, values)
        outcome.weight_on_hook = realized.weight_on_hook
        outcome.weight_on_bit = realized.operation.weight_on_bit
        model = realization_model(case, (case_text(case), settings), law, realized, nominal=index == NOMINAL)
        if index != NOMINAL:
            model = random_reduced_model(model, settings.model, model_generator(settings.seed, index))
        outcome.lowest_lateral_eigenvalue = model.lowest_lateral_eigenvalue
        try:
            outcome.metrics.update(family_growth_rates(model))
        except ValueError:  # no steady drilling at these inputs: the bit-rock law gives no penetration
            outcome.metrics.update({name: math.nan for name in ("growth_rate", *FAMILY_GROWTH_METRICS)})
        try:
            result: SimulationResult = simulate_model(
                model, **simulation_options(realized, settings.t_end, settings.output_step))
            outcome.status = DONE
        except SimulationError as error:
            result = error.result
            outcome.message = str(error)
        k = len(result.time)
        for name in study_observables(case):
            series = np.full(n_t, np.nan)
            series[:k] = result.observables[name]
            outcome.observables[name] = series
        radial = np.full((n_t, result.radial_displacement.shape[1]), np.nan)
        radial[:k] = result.radial_displacement
        outcome.radial_displacement = radial
        outcome.n_rhs = int(result.stats.get("n_rhs", 0))
        outcome.metrics.update(realization_metrics(result, realized, metrics_transient(settings)))
    except Exception as error:  # any failure is recorded with its cause, never dropped
        outcome.status = FAILED
        outcome.message = f"{type(error).__name__}: {error}"
    outcome.wall_time = time.perf_counter() - start
    return outcome


# --- the Zarr store ------------------------------------------------------------------------------


def open_study_group(path: str | Path, mode: str = "r") -> zarr.Group:
    """Open the study store at ``path``, checking that it is one (:meth:`StudyStore.open_group`);
    raises :class:`~drillstring.stochastic.store.StoreError` saying what is wrong otherwise."""
    return StudyStore.open_group(path, mode)


class StudyStore(TaskStore):
    """A study's Zarr store: one row per realization, a status flag written after the data, and the
    nominal run's row (index :data:`NOMINAL`, its own arrays and status).

    A new store is built under a temporary name and renamed into place once complete; an existing one
    is checked (:func:`open_study_group`) and must hold the same study (case and settings). Writers
    hold its :class:`~drillstring.stochastic.locks.StudyLock` (as :func:`run_study` does)."""

    kind = "study"
    row_dim = "realization"
    noun = "realizations"
    #: Realizations arriving within this many seconds, at most ``flush_count``, are written together (a kill loses
    #: at most that much work): a write makes one Zarr call per array (~30 arrays, ~0.6 ms of CPU each, the ~22 small
    #: per-realization arrays rewritten whole) plus Zarr's cost per chunk of the rows (0.65 ms, 7 a realization):
    #: 4.1 ms of the driver's CPU per realization in batches of 8 on the reference study
    #: (benchmarks/bench_store_writes.py), CPU taken from the workers when there are as many as cores.
    flush_interval = 1.0
    flush_count = 8
    differ = "case or settings differ: samples, sigma, laws, seed, t_end, output_step, model_dispersion"

    def __init__(self, path: str | Path, case: Case, settings: StudySettings) -> None:
        self.case = case
        self.settings = settings
        n_t = len(settings.time)
        per_row = dict(chunk_rows=1)
        observables = study_observables(case)
        metrics = {**REALIZATION_METRICS, **FAMILY_GROWTH_METRICS, **(TOP_DRIVE_METRICS if has_top_drive(case) else {})}
        layout = {
            "time": ArraySpec(("time",), data=settings.time, attributes={"units": "s"}),
            "x": ArraySpec(("probe",), data=np.asarray(case.mesh.probes, dtype=float), attributes={"units": "m"}),
            "weight_on_hook": ArraySpec(("realization",)),
            "weight_on_bit": ArraySpec(("realization",)),
            "lowest_lateral_eigenvalue": ArraySpec(("realization",)),
            **{name: ArraySpec(("realization",), attributes={"units": unit})
               for name, (unit, _) in metrics.items()},
            **{f"nominal_{name}": ArraySpec(("one",), attributes={"units": unit})
               for name, (unit, _) in metrics.items()},
            **{name: ArraySpec(("realization", "time"), **per_row) for name in observables},
            **{f"nominal_{name}": ArraySpec(("time",)) for name in observables},
            "radial_displacement": ArraySpec(("realization", "time", "probe"), **per_row),
            "nominal_radial_displacement": ArraySpec(("time", "probe")),
            "nominal_status": ArraySpec(("one",), "i1", PENDING),
        }
        law = study_uncertainty(case, settings)
        layout["input_values"] = ArraySpec(("realization", "parameter"))
        layout["nominal_input_values"] = ArraySpec(("parameter",))
        sizes = {"realization": settings.samples, "time": n_t, "probe": len(case.mesh.probes), "one": 1,
                 "parameter": law.size}
        mean = law.mean()
        woh_mean = (float(mean[law.paths.index(WEIGHT_ON_HOOK)]) if WEIGHT_ON_HOOK in law.paths
                    else nominal_weight_on_hook(case))
        attrs = {"weight_on_hook_mean": woh_mean, "weight": case.weight, **input_attributes(law),
                 "metrics_transient": metrics_transient(settings)}
        super().__init__(path, case_toml=case.to_toml(), settings=settings.store_settings(), layout=layout, sizes=sizes,
                         attrs=attrs)

    def owner_status(self, name: str) -> str | None:
        """The nominal run's arrays belong to its status ``nominal_status``."""
        return "nominal_status" if name.startswith("nominal_") else None

    def owner_label(self, owner: str) -> str:
        return "the nominal run"

    @classmethod
    def open_group(cls, path: str | Path, mode: str = "r") -> zarr.Group:
        """:meth:`TaskStore.open_group`, refusing a store written before the per-realization metrics
        (:data:`~drillstring.stochastic.runs.REALIZATION_METRICS`) were stored."""
        group = super().open_group(path, mode)
        layout = dict(group.attrs["layout"])
        old_names = {new: old for old, new in RENAMED_METRICS.items()}  # read under their earlier spelling
        missing = [name for name in REALIZATION_METRICS if name not in layout and old_names.get(name) not in layout]
        if missing:
            raise StoreError(f"{path} is a study store of an older drillstring version (no {missing[0]} per "
                             "realization); delete it (or use another --out folder) to start over")
        return group

    def nominal_done(self) -> bool:
        return int(self.group["nominal_status"][0]) != PENDING

    def entries(self, outcome: RealizationOutcome):
        i = outcome.index
        if i == NOMINAL:
            if outcome.radial_displacement is not None:
                for name, series in outcome.observables.items():
                    yield f"nominal_{name}", Ellipsis, series
                yield "nominal_radial_displacement", Ellipsis, outcome.radial_displacement
            for name, value in outcome.metrics.items():
                yield f"nominal_{name}", 0, value
            if outcome.inputs is not None:
                yield "nominal_input_values", Ellipsis, outcome.inputs
            return
        if outcome.inputs is not None:
            yield "input_values", i, outcome.inputs
        if outcome.radial_displacement is not None:
            for name, series in outcome.observables.items():
                yield name, i, series
            yield "radial_displacement", i, outcome.radial_displacement
        for name in ("weight_on_hook", "weight_on_bit", "wall_time", "lowest_lateral_eigenvalue"):
            yield name, i, getattr(outcome, name)
        for name, value in outcome.metrics.items():
            yield name, i, value

    def status_entry(self, outcome: RealizationOutcome):
        return ("nominal_status", 0) if outcome.index == NOMINAL else ("status", outcome.index)

    def failure_key(self, outcome: RealizationOutcome) -> str:
        return "nominal" if outcome.index == NOMINAL else str(outcome.index)


# --- execution -----------------------------------------------------------------------------------


#: What :func:`run_study` did (:class:`~drillstring.stochastic.execution.StoreRun`: the store, realizations
#: finished and failed, wall time, workers, realizations computed by this call, a note or None).
StudyRun = StoreRun


def run_study(case: Case, settings: StudySettings, store_path: str | Path, engine: Engine = Engine(), *,
              finish: Callable[[StoreRun], Any] | None = None) -> StudyRun:
    """Run (or resume) every pending realization of a study into its Zarr store on ``engine``
    (:class:`~drillstring.stochastic.execution.Engine`: local processes, default one per core, or a Dask
    cluster; progress, notes, the Dask worker timeout), then ``finish(run)`` under the store's lock.

    Before anything is created: the settings are checked against the case (:func:`check_study`), a
    scheduler is reached (:class:`~drillstring.stochastic.execution.SchedulerUnreachable` within about
    12 s), and the store is locked (:class:`~drillstring.stochastic.locks.StudyLocked` if another study
    runs on it). :func:`~drillstring.stochastic.execution.run_locked` does the rest: on local processes the
    study's model is built and the kernels compiled here while the workers start
    (:func:`~drillstring.stochastic.study_model.prepare_runs`).
    """
    check_study(case, settings)
    key, law = (case_text(case), settings), study_uncertainty(case, settings)
    if engine.scheduler is not None:  # a cluster's workers build their own models: the note now
        note_model(case, key, law, engine.note)

    def pending(store: StudyStore):
        return [(i, i) for i in ([] if store.nominal_done() else [NOMINAL]) + store.pending()]

    return run_locked(store_path, partial(StudyStore, Path(store_path), case, settings), pending,
                      partial(_realization_task, case, settings), engine, lost=partial(_worker_died, case, settings),
                      prepare=partial(prepare_runs, case, key, law, engine.note), finish=finish, what="study",
                      noun="realizations")


def _realization_task(case: Case, settings: StudySettings, index: int) -> RealizationOutcome:
    """The task of realization ``index`` (looks :func:`run_realization` up when called)."""
    return run_realization(case, settings, index)


def _worker_died(case: Case, settings: StudySettings, index: int, argument, message: str) -> RealizationOutcome:
    law = study_uncertainty(case, settings)
    values = draw_inputs(case, settings, index)
    woh = float(values[law.paths.index(WEIGHT_ON_HOOK)]) if WEIGHT_ON_HOOK in law.paths else math.nan
    return RealizationOutcome(index, woh, math.nan, FAILED, message.replace("this task", "this realization"),
                              inputs=values)
