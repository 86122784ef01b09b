"""Global sensitivity of a case: a Saltelli design of its uncertain parameters run on the study engine,
analysed into Sobol' indices (:mod:`drillstring.stochastic.sensitivity`).

Each row of the design (``N(k + 2)`` rows for ``N`` base samples and ``k`` parameters) is one simulation of
the case with the row's parameter values set (:func:`~drillstring.stochastic.parameters.with_parameters`),
summarised by the scalar outputs of :mod:`drillstring.stochastic.runs`. The rows run through
:func:`~drillstring.stochastic.execution.run_tasks` (local processes or Dask) into a resumable Zarr store
(:class:`SensitivityStore`); the design depends only on the laws, ``N`` and the seed, so an interrupted
run resumes to the same result. The analysed outputs (:data:`SENSITIVITY_OUTPUTS`) are the time means of
ROP, TOB and FOB after the transient, the bit-speed oscillation, and the dispersion in time (standard
deviation) of ROP, TOB and FOB. A row whose values give no valid case (e.g. a weight-on-bit above the
string's weight) or whose run fails is left out with its block (see
:func:`~drillstring.stochastic.sensitivity.sobol_indices`).

The laws must be independent (Sobol' indices of this kind) and must respect their parameters' ranges to
1e-6 (:data:`~drillstring.stochastic.uncertainty.OUT_OF_RANGE_TOLERANCE`): failures that depend on the
parameters would bias the indices.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, Callable

import numpy as np

from drillstring.case import Case, case_from_dict
from drillstring.checks import seed as check_seed
from drillstring.dynamics.simulate import run_window
from drillstring.stochastic.execution import Engine, StoreRun, TaskOutcome, run_locked
from drillstring.stochastic.locks import StudyLock
from drillstring.stochastic.parameters import with_parameters
from drillstring.stochastic.runs import RUN_OUTPUTS, run_outputs
from drillstring.stochastic.sensitivity import (
    SaltelliDesign,
    SobolResult,
    _check_power_of_two,
    saltelli_design,
    sobol_indices,
)
from drillstring.stochastic.store import FAILED, ArraySpec, TaskStore
from drillstring.stochastic.study_model import case_text, note_model, prepare_runs, realization_model
from drillstring.stochastic.uncertainty import OUT_OF_RANGE_TOLERANCE, Uncertainty, input_attributes
from drillstring.stochastic.uncertainty_settings import (
    UncertaintyFields,
    UncertaintySettings,
    accepts_uncertainty_fields,
)

__all__ = [
    "SENSITIVITY_OUTPUTS",
    "SensitivitySettings",
    "SensitivityStore",
    "load_sensitivity",
    "run_sensitivity",
    "sensitivity_design",
]

#: Outputs whose Sobol' indices are computed (names of :data:`~drillstring.stochastic.runs.RUN_OUTPUTS`).
SENSITIVITY_OUTPUTS = ("mean_rate_of_penetration", "bit_speed_oscillation", "mean_torque_on_bit",
                       "mean_force_on_bit", "std_rate_of_penetration", "std_torque_on_bit", "std_force_on_bit")


@accepts_uncertainty_fields
@dataclass(frozen=True)
class SensitivitySettings(UncertaintyFields):
    """What defines a sensitivity run; a resumed run must have the same settings.

    Attributes:
        base_samples: N, a power of 2 (>= 8); the design has N(k + 2) runs.
        uncertainty: the uncertain parameters' laws (:class:`~drillstring.stochastic.uncertainty_settings.
            UncertaintySettings`, independent: no correlation, no model dispersion); also accepted as the
            laws ``((path, spec), ...)`` themselves or the keyword ``laws``, and read through (``settings.laws``).
        seed: scrambling seed of the Sobol' sequence (and of the bootstrap).
        t_end: simulated time per run [s].
        output_step: output step [s].
        transient: start of the window of the outputs [s] (default ``min(10 s, t_end/2)``).
    """

    base_samples: int
    uncertainty: UncertaintySettings
    seed: int = 0
    t_end: float = 30.0
    output_step: float = 0.01
    transient: float | None = None

    def __post_init__(self) -> None:
        _check_power_of_two(self.base_samples, "samples")
        if not isinstance(self.uncertainty, UncertaintySettings):  # the laws themselves (the earlier field)
            object.__setattr__(self, "uncertainty", UncertaintySettings(laws=self.uncertainty))
        if not self.uncertainty.laws:
            raise ValueError("no uncertain parameter: give at least one law (--param PATH=LAW)")
        if self.uncertainty.correlated or self.uncertainty.model.active:
            raise ValueError("uncertainty: Sobol' indices need independent parameter laws (no correlated, no "
                             "correlation) and no model dispersion (model_dispersion = (0, 0, 0))")
        object.__setattr__(self, "seed", check_seed(self.seed))
        window = run_window(self.t_end, self.output_step, self.transient)
        for name in ("t_end", "output_step", "transient"):
            object.__setattr__(self, name, getattr(window, name))


def sensitivity_design(case: Case, settings: SensitivitySettings) -> SaltelliDesign:
    """The Saltelli design of the settings' laws on ``case`` (raises ParameterError / ValueError, one line,
    for unknown paths, bad laws, laws outside their ranges or correlated parameters)."""
    law: Uncertainty = settings.uncertainty.law(case, tolerance=OUT_OF_RANGE_TOLERANCE)
    return saltelli_design(law, settings.base_samples, seed=settings.seed)


class SensitivityStore(TaskStore):
    """A sensitivity run's Zarr store: one row per design row, its parameter values and scalar outputs."""

    kind = "sensitivity"
    row_dim = "run"
    noun = "runs"
    differ = "case or settings differ: laws, samples, seed, t_end, output_step, transient"

    def __init__(self, path: str | Path, case: Case, settings: SensitivitySettings, design: SaltelliDesign) -> None:
        layout = {
            "input_values": ArraySpec(("run", "parameter"), attributes={
                "long_name": "parameter values of each run (SI; see the parameter_units attribute)"}),
            **{name: ArraySpec(("run",), attributes={"units": unit, "long_name": text})
               for name, (unit, text) in RUN_OUTPUTS.items()},
        }
        sizes = {"run": design.runs, "parameter": design.uncertainty.size}
        attrs = {**input_attributes(design.uncertainty), "base_samples": design.base_samples}
        super().__init__(path, case_toml=case.to_toml(), settings=settings.store_settings(("laws",)), layout=layout, sizes=sizes,
                         attrs=attrs)


def _row_task(case: Case, law: Uncertainty, settings: SensitivitySettings, item) -> TaskOutcome:
    """The outcome of one design row (never raises: values that give no valid case fail with the cause); its
    model from the design's parametric model where that covers the laws
    (:func:`~drillstring.stochastic.study_model.realization_model`)."""
    index, row = item
    row = np.asarray(row, dtype=float)
    try:
        run_case = with_parameters(case, dict(zip(law.paths, row)))
    except ValueError as error:
        return TaskOutcome(index, FAILED, str(error), {"input_values": row})
    outcome = run_outputs(run_case, index, t_end=settings.t_end, output_step=settings.output_step,
                          t_transient=settings.transient,
                          build_model=partial(realization_model, case, _model_key(case, settings), law))
    outcome.values["input_values"] = row
    return outcome


def _lost(index: int, item, message: str) -> TaskOutcome:
    return TaskOutcome(index, FAILED, message, {"input_values": np.asarray(item[1], dtype=float)})


@dataclass
class SensitivityRun(StoreRun):
    """What :func:`run_sensitivity` did: a :class:`~drillstring.stochastic.execution.StoreRun` (the store,
    runs finished and failed, wall time, workers, runs computed by this call, a note) and the design."""

    design: SaltelliDesign | None = None


def run_sensitivity(case: Case, settings: SensitivitySettings, store_path: str | Path, engine: Engine = Engine(), *,
                    finish: Callable[[StoreRun], Any] | None = None) -> SensitivityRun:
    """Run (or resume) every pending row of the design into the Zarr store at ``store_path`` on ``engine``,
    then ``finish(run)`` under the store's lock (like :func:`~drillstring.stochastic.montecarlo.run_study`:
    the laws, the scheduler and the lock are checked before anything is created)."""
    design = sensitivity_design(case, settings)
    key = _model_key(case, settings)
    if engine.scheduler is not None:  # a cluster's workers build their own models: the note now
        note_model(case, key, design.uncertainty, engine.note)
    run = run_locked(store_path, partial(SensitivityStore, Path(store_path), case, settings, design),
                     lambda store: [(i, (i, design.values[i])) for i in store.pending()],
                     partial(_row_task, case, design.uncertainty, settings), engine, lost=_lost,
                     prepare=partial(prepare_runs, case, key, design.uncertainty, engine.note), finish=finish,
                     what="sensitivity run", noun="runs", lock_name="sensitivity")
    return SensitivityRun(**vars(run), design=design)


def _model_key(case: Case, settings: SensitivitySettings):
    """The key of the design's parametric model (:mod:`drillstring.stochastic.study_model`): case and laws."""
    return ("sensitivity", case_text(case), settings.laws)


@dataclass
class SensitivityData:
    """A sensitivity store read back: the design, every output of every run (design order), the status,
    the per-run wall time [s] and the store's attributes."""

    design: SaltelliDesign
    outputs: dict[str, np.ndarray]
    status: np.ndarray
    wall_time: np.ndarray
    attrs: dict[str, Any]

    def indices(self, outputs=SENSITIVITY_OUTPUTS, *, confidence: float = 0.95, resamples: int = 1000) -> SobolResult:
        """Sobol' indices of ``outputs`` (failed runs left out with their blocks)."""
        values = {name: np.where(self.status == 1, self.outputs[name], np.nan) for name in outputs}
        return sobol_indices(self.design, values, confidence=confidence, resamples=resamples,
                             seed=self.design.seed)


def load_sensitivity(store_path: str | Path) -> SensitivityData:
    """Read a sensitivity store (shared lock: refused while a run writes it), rebuilding its design from the
    recorded case and laws and checking it against the recorded parameter values."""
    import tomllib

    with StudyLock(store_path, shared=True, what="sensitivity"):
        group = SensitivityStore.open_group(store_path, mode="r")
        attrs = dict(group.attrs)
        outputs = {name: np.asarray(group[name][:], dtype=float) for name in RUN_OUTPUTS}
        status = np.asarray(group["status"][:])
        wall = np.asarray(group["wall_time"][:], dtype=float)
        values = np.asarray(group["input_values"][:], dtype=float)
    settings = SensitivitySettings(**{**attrs["settings"], "laws": tuple(map(tuple, attrs["settings"]["laws"]))})
    case = case_from_dict(tomllib.loads(attrs["case"]), source=str(store_path))
    design = sensitivity_design(case, settings)
    written = np.isfinite(values).all(axis=1)
    if not np.array_equal(values[written], design.values[written]):
        raise ValueError(f"{store_path}: the recorded parameter values differ from the design of its laws "
                         "(written by another version of drillstring?); delete it to start over")
    return SensitivityData(design, outputs, status, wall, attrs)
