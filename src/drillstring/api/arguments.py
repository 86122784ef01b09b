"""The checks of the notebook API's arguments (TypeError or ValueError naming the argument) and what its
recipes share: the case, the run window, the output folder, the uncertainty drawn at each point of a map or a
search, the run record of a store (the engine's settings: :mod:`drillstring.api.settings`)."""

from __future__ import annotations

import functools
import inspect
from pathlib import Path
from typing import Callable, Mapping

from drillstring.case import Case, load_case


def as_case(case: Case | str | Path) -> Case:
    """A Case as is, or loaded from a built-in name or a TOML path. Anything else — a dict included (build
    a Case from one with :func:`drillstring.case.case_from_dict`) — raises TypeError naming ``case``."""
    if isinstance(case, Case):
        return case
    if isinstance(case, (str, Path)):
        return load_case(case)
    hint = " (build one from a dict with drillstring.case.case_from_dict)" if isinstance(case, Mapping) else ""
    raise TypeError(f"case = {type(case).__name__}: must be a Case, a built-in case name or a path to a TOML "
                    f"file{hint}")


def checked_tolerance(name: str, value) -> float | None:
    """An integration tolerance override: None, or a number in (0, 1)."""
    from drillstring.checks import real_number

    return None if value is None else real_number(name, value, low=0.0, high=1.0, low_open=True, high_open=True,
                                                   allowed="a number in (0, 1), e.g. 1e-6")


def checked_weight_on_bit(case: Case, value) -> float:
    """The ``weight_on_bit`` argument [N] overriding the case's, checked as the case's own (> 0, at most
    1e9 N, less than the string's weight with gravity on): TypeError or ValueError naming the argument."""
    from drillstring.checks import real_number

    value = real_number("weight_on_bit", value, unit="N", low=0.0, low_open=True)
    problem = case.weight_on_bit_problem(value)
    if problem:
        raise ValueError(f"weight_on_bit = {value!r} N: {problem}")
    return value


def check_callable(name: str, value) -> None:
    if value is not None and not callable(value):
        raise TypeError(f"{name} = {value!r}: must be a callable or None")


def check_mapping(name: str, value) -> None:
    """Refuse (TypeError) ``value`` unless None or a mapping (a table: path -> law, or parameters/matrix)."""
    if value is not None and not isinstance(value, Mapping):
        raise TypeError(f"{name} = {type(value).__name__}: must be a dict (path -> law spec), e.g. "
                        "{'operation.top_speed': 'uniform 60 140 rpm'}")


def case_window(case: Case, t_end=None, output_step=None, transient=None):
    """The run window (:func:`~drillstring.dynamics.simulate.run_window`) of ``case`` with the given overrides."""
    from drillstring.dynamics.simulate import run_window

    return run_window(case.simulation.t_end if t_end is None else t_end,
                      case.simulation.output_step if output_step is None else output_step, transient)


def output_folder(out, prefix: str) -> Path:
    """The output folder, checked (ValueError naming ``out``), or a new temporary one when ``out`` is None."""
    import tempfile

    from drillstring.files import output_folder_problem

    if out is None:
        return Path(tempfile.mkdtemp(prefix=prefix))
    if not isinstance(out, (str, Path)):
        raise TypeError(f"out = {out!r}: must be a folder path (str or Path) or None")
    problem = output_folder_problem(out)
    if problem:
        raise ValueError(f"out = {str(out)!r}: {problem}")
    return Path(out)


def point_uncertainty(case, inputs):
    """What the realizations at each point of a map or a search draw from ``inputs`` (a
    :class:`~drillstring.api.settings.RandomInputs`): ``(sigma, uncertainty)``, the
    weight-on-hook's σ (its default when no parameter is declared) and the
    :class:`~drillstring.stochastic.uncertainty_settings.UncertaintySettings` of the other declared laws and the
    model dispersion, for the settings of :mod:`drillstring.stochastic.probabilistic_map` and
    :mod:`drillstring.stochastic.optimize`."""
    from drillstring.stochastic import DEFAULT_SIGMA
    from drillstring.stochastic.random_matrices import ModelDispersion
    from drillstring.stochastic.uncertainty import declared_uncertainty
    from drillstring.stochastic.uncertainty_settings import UncertaintySettings

    sigma = inputs.sigma
    dispersions = ModelDispersion.declared(case, inputs.model)
    declared = declared_uncertainty(case, inputs.parameters, inputs.correlation, tolerance=1.0)
    if declared is None and sigma is None:
        sigma = DEFAULT_SIGMA
    return sigma, UncertaintySettings.of(declared, dispersions)


def run_record(store, run, noun: str) -> dict:
    """Computation time and workers of a store's sessions, and this call's numbers (JSON-ready)."""
    from drillstring.stochastic.execution import computation_time

    sessions = store.sessions()
    wall_time, used = computation_time(sessions)
    return {
        "failures": store.failures(),
        "wall_time": wall_time,
        "wall_time_this_run": run.wall_time,
        f"{noun}_this_run": run.computed,
        "workers": used if isinstance(used, (int, str)) or used is None else str(used),
        "sessions": sessions,
    }


def run_table(record: dict, noun: str) -> dict:
    """Rows of a report's "Run" table."""
    rows = {"failures": record["failures"], "computation wall time [s]": round(record["wall_time"], 2),
            "workers": record["workers"]}
    if record[f"{noun}_this_run"] == 0 or len(record["sessions"]) > 1:
        rows["wall time of this run [s]"] = round(record["wall_time_this_run"], 2)
        rows[f"runs that computed {noun}"] = len(record["sessions"])
    return rows


def keywords_of(recipe: Callable, *, leaving_out: tuple[str, ...] = ()) -> Callable:
    """Decorator of a shorthand ``function(case, **options)`` that calls ``recipe`` with the same arguments: its
    signature (``help()``, the reference, :func:`inspect.signature`) is ``recipe``'s less the keywords
    ``leaving_out`` (with the shorthand's own return annotation), and a keyword it does not list is refused with
    Python's TypeError before anything runs. One list of keywords and defaults, written once on ``recipe``."""
    shared = inspect.signature(recipe)

    def decorate(function: Callable) -> Callable:
        signature = shared.replace(
            parameters=[p for name, p in shared.parameters.items() if name not in leaving_out],
            return_annotation=inspect.signature(function).return_annotation)

        @functools.wraps(function)
        def shorthand(*args, **kwargs):
            try:
                signature.bind(*args, **kwargs)
            except TypeError as error:  # as Python's own, for an argument it does not take
                raise TypeError(f"{function.__name__}() {error}") from None
            return function(*args, **kwargs)

        shorthand.__signature__ = signature
        return shorthand

    return decorate
