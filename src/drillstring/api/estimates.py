"""From a surface record to the downhole state (issue 36): read the record against the case, run the ensemble
estimator (:mod:`drillstring.estimation.ensemble`), and, for a synthetic record whose hidden truth is known,
score the estimate against it. The command ``drillstring estimate`` calls :func:`estimate` and only formats."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from drillstring.api.arguments import as_case
from drillstring.blas_threads import single_threaded_blas
from drillstring.case import Case

#: Suffixes of a built-in case's shipped record and of its hidden truth (``drillstring/cases/<name><suffix>``).
RECORD_SUFFIX, TRUTH_SUFFIX = "_surface.csv", "_surface_truth.csv"
#: The downhole quantities scored against a truth (coverage of the 90 % band, RMSE).
SCORED = ("bit_speed", "torque_on_bit")


def builtin_record(case_name: str) -> tuple[Path, Path | None] | None:
    """The surface record shipped with the built-in case ``case_name`` and its truth (None where none is
    shipped): ``(record, truth)``, or None."""
    from importlib import resources

    folder = resources.files("drillstring").joinpath("cases")
    record = folder.joinpath(case_name + RECORD_SUFFIX)
    if not record.is_file():
        return None
    truth = folder.joinpath(case_name + TRUTH_SUFFIX)
    return Path(str(record)), (Path(str(truth)) if truth.is_file() else None)


@dataclass
class EstimateOutcome:
    """What :func:`estimate` returns: the ``result`` (:class:`~drillstring.estimation.results.EstimationResult`),
    the ``record`` it read (:class:`~drillstring.estimation.surface.SurfaceRecord`, with its ``notes``), and
    with a truth: ``truth`` (name -> values on the result's times, SI) and ``scores`` (name -> coverage of the
    90 % band [-], RMSE of the mean [SI]; for the bit speed also the RMSE of the surface-only guess, bit speed =
    measured top speed)."""

    result: object
    record: object
    truth: dict[str, np.ndarray] | None = None
    scores: dict[str, dict[str, float]] = field(default_factory=dict)

    @property
    def real_time_factor(self) -> float:
        """Record duration over the estimator's wall time [-] (> 1: faster than real time)."""
        duration = float(self.result.time[-1] - self.result.time[0])
        return duration / self.result.wall_time if self.result.wall_time > 0 else math.inf


def _truth_on(times: np.ndarray, truth_path: Path) -> dict[str, np.ndarray]:
    """The truth file's columns interpolated on ``times`` (the record's clock: both start at the record's
    first sample)."""
    from drillstring.estimation.synthetic import read_truth

    _, columns = read_truth(truth_path)
    t = columns.pop("time")
    return {name: np.interp(times, t, values) for name, values in columns.items()
            if np.issubdtype(np.asarray(values).dtype, np.number)}


def _scores(result, record, truth: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    scores = {}
    for name in SCORED:
        if name not in truth or name not in result.mean:
            continue
        error = result.mean[name] - truth[name]
        keep = np.isfinite(error)
        scores[name] = {"coverage_90": result.coverage(name, truth[name]),
                        "rmse": float(np.sqrt(np.mean(error[keep] ** 2)))}
    if "bit_speed" in scores and "top_speed" in record.channels:
        guess = np.interp(result.time, record.time, record.channels["top_speed"])  # bit speed = top speed
        error = guess - truth["bit_speed"]
        keep = np.isfinite(error)
        scores["bit_speed"]["surface_only_rmse"] = float(np.sqrt(np.mean(error[keep] ** 2)))
    return scores


@single_threaded_blas()
def estimate(case: Case | str | Path = "stick_slip", surface: str | Path | None = None, *,
             truth: str | Path | None = None, columns: dict[str, str] | None = None,
             units: dict[str, str] | None = None, progress: Callable[[float], None] | None = None,
             **settings) -> EstimateOutcome:
    """Estimate the downhole state of ``case`` from the surface record ``surface`` (a CSV file; None: the
    record shipped with a built-in case, and its hidden truth). The record is read and checked against the case
    (:func:`~drillstring.estimation.reading.read_surface_record`: ``columns`` and ``units`` map and give its
    columns; faults flagged, never used). ``settings``: the estimator's (:class:`~drillstring.estimation.
    ensemble.EstimatorSettings` keys, e.g. ``ensemble_size=16``) over the case's ``[estimator]`` table.
    ``truth``: a truth file (:func:`~drillstring.estimation.synthetic.read_truth`) to score the estimate against.
    ``progress``: called with the record time reached [s]."""
    from drillstring.estimation.ensemble import case_estimator_settings, estimate as run_estimator
    from drillstring.estimation.reading import read_surface_record

    the_case = as_case(case)
    if surface is None:
        shipped = builtin_record(the_case.name)
        if shipped is None:
            raise ValueError(f"surface: no record given, and case {the_case.name!r} ships none (built-in records: "
                             "stick_slip); give a surface record (CSV)")
        surface, shipped_truth = shipped
        truth = shipped_truth if truth is None else truth
    record = read_surface_record(surface, columns=columns, units=units, case=the_case)
    result = run_estimator(the_case, record, case_estimator_settings(the_case, **settings), progress=progress)
    outcome = EstimateOutcome(result, record)
    if truth is not None:
        outcome.truth = _truth_on(result.time, Path(truth))
        outcome.scores = _scores(result, record, outcome.truth)
    return outcome
