"""Settings objects of the notebook API's engine functions (:func:`~drillstring.api.monte_carlo_study`,
:func:`~drillstring.api.study`, :func:`~drillstring.api.operating_map`, :func:`~drillstring.api.sensitivity`,
:func:`~drillstring.optimize`): what their signatures share, given once as an object instead of keyword by keyword.

- :class:`RunOptions`: how the runs execute and where they go (the output folder and its resumable store, local
  worker processes or a Dask scheduler, the progress and note callbacks, the unit system of the files);
- :class:`SimulationWindow`: the simulated time of each run, its output step and the transient left out of the
  summaries [s];
- :class:`RandomInputs`: what is drawn at random (the laws of case parameters, their correlation, the
  weight-on-hook's σ, the model dispersion), turned by each function into its
  :class:`~drillstring.stochastic.uncertainty_settings.UncertaintySettings`;
- :class:`SearchOptions`: the budget of the robust operating point's search.

Each is frozen and checked when built (TypeError or ValueError naming the field, its value and the allowed range);
what depends on the case (a transient below the case's own ``t_end``, a law's range) is checked by the function.
The functions still take each field as a keyword of its own (their earlier signatures), gathered into these objects
by :func:`gathered`, the one place that does it: an unknown keyword, or a field given both ways, is refused.

>>> import drillstring
>>> from drillstring import RandomInputs, RunOptions, SimulationWindow
>>> run = RunOptions(out="study", workers=4)
>>> window = SimulationWindow(t_end=30.0, transient=10.0)
>>> inputs = RandomInputs(parameters={"operation.top_speed": "uniform 60 140 rpm"})
>>> drillstring.study("reference", inputs=inputs, window=window, run=run)   # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

__all__ = ["RandomInputs", "RunOptions", "SearchOptions", "SimulationWindow", "gathered"]

#: Realizations per design point of a search by default.
DEFAULT_POINT_SAMPLES = 8


def _callable(name: str, value) -> None:
    if value is not None and not callable(value):
        raise TypeError(f"{name} = {value!r}: must be a callable or None")


@dataclass(frozen=True)
class RunOptions:
    """How an engine function's runs execute and where their files go.

    Attributes:
        out: the output folder (str or Path): its store (``study.zarr``, ``map.zarr``, ...) resumes when the same
            call is made again; None: a new temporary folder, and no files but the store.
        workers: local worker processes, an integer >= 1 (None: one per core; 1 runs in the calling process).
        scheduler: a Dask scheduler address (``"tcp://host:8786"``) or a connected ``distributed.Client``;
            not together with ``workers``.
        progress: ``progress(done, failed, total)``, called after each run.
        note: ``note(text)``, given one-line notes (a stale lock taken over); None: a RuntimeWarning.
        worker_timeout: seconds [s] a Dask run waits with no worker left before it stops, resumably (None: the
            default, :data:`~drillstring.stochastic.execution.DASK_WORKER_TIMEOUT`); > 0.
        units: the unit system of figures and reports, ``"si"`` or ``"field"`` (None: ``$DRILLSTRING_UNITS``,
            else si); JSON and NetCDF stay SI.
        stage: ``stage(text)``, told what runs after the runs ("statistics", "figures", "report"), where the
            function has such steps (:func:`~drillstring.api.monte_carlo_study`).
    """

    out: str | Path | None = None
    workers: int | None = None
    scheduler: Any = None
    progress: Callable[[int, int, int], None] | None = None
    note: Callable[[str], None] | None = None
    worker_timeout: float | None = None
    units: str | None = None
    stage: Callable[[str], None] | None = None

    def __post_init__(self) -> None:
        if self.out is not None and not isinstance(self.out, (str, Path)):
            raise TypeError(f"out = {self.out!r}: must be a folder path (str or Path) or None")
        if self.units is not None:
            from drillstring.units import unit_system

            unit_system(self.units, "units")
        _callable("stage", self.stage)
        engine = self.engine()  # the engine's own checks: workers, scheduler, progress, note, worker_timeout
        if self.workers is not None:
            object.__setattr__(self, "workers", engine.workers)

    def engine(self):
        """The :class:`~drillstring.stochastic.execution.Engine` that runs the tasks."""
        from drillstring.stochastic.execution import DASK_WORKER_TIMEOUT, Engine

        return Engine(workers=self.workers, scheduler=self.scheduler, progress=self.progress, note=self.note,
                      worker_timeout=DASK_WORKER_TIMEOUT if self.worker_timeout is None else self.worker_timeout)


@dataclass(frozen=True)
class SimulationWindow:
    """The time window of each run [s].

    Attributes:
        t_end: simulated time of each run [s], > 0 (None: the case's ``simulation.t_end``).
        output_step: time between stored outputs [s], in (0, t_end] (None: the case's ``simulation.output_step``).
        transient: start of the steady window of the summaries [s], in [0, t_end) (None:
            ``min(10 s, t_end/2)``, :func:`~drillstring.dynamics.indicators.transient_end`).
    """

    t_end: float | None = None
    output_step: float | None = None
    transient: float | None = None

    def __post_init__(self) -> None:
        from drillstring.checks import real_number

        if self.t_end is not None:
            object.__setattr__(self, "t_end", real_number("t_end", self.t_end, unit="s", low=0.0, low_open=True))
        if self.output_step is not None:
            high = self.t_end
            object.__setattr__(self, "output_step", real_number(
                "output_step", self.output_step, unit="s", low=0.0, low_open=True, high=high,
                allowed=None if high is None else f"a number in (0, t_end = {high:g} s]"))
        if self.transient is not None:
            high = self.t_end
            object.__setattr__(self, "transient", real_number(
                "transient", self.transient, unit="s", low=0.0, high=high, high_open=True,
                allowed=None if high is None else f"a number in [0, t_end = {high:g} s)"))

    def on(self, case):
        """The checked :class:`~drillstring.dynamics.simulate.RunWindow` of ``case``: this window, the case's
        ``simulation`` table where a field is None (:func:`~drillstring.dynamics.simulate.run_window`)."""
        from drillstring.api.arguments import case_window

        return case_window(case, self.t_end, self.output_step, self.transient)


@dataclass(frozen=True)
class RandomInputs:
    """What the runs draw at random (docs/uncertainty.md).

    Attributes:
        parameters: case-parameter path -> law spec or table (``{"fluid.inlet_velocity": "uniform 1.2 1.8 m/s"}``;
            laws by the Maximum Entropy Principle, :mod:`~drillstring.stochastic.uncertainty`); None: the case's
            ``[uncertainty]`` table.
        correlation: correlated normal parameters, ``{"parameters": [...], "matrix": [[...]]}``.
        sigma: standard deviation of the weight-on-hook [N], > 0 (a Normal law about its nominal value).
        dispersion: the weight-on-hook's σ as a fraction of its mean, > 0, instead of ``sigma`` (studies only).
        model: the model uncertainty, ``{"mass_dispersion": δ_M, "stiffness_dispersion": δ_K,
            "damping_dispersion": δ_D}`` (random reduced matrices, :mod:`~drillstring.stochastic.random_matrices`);
            None: the case's ``[uncertainty.model]`` table.

    The tables are copied when built (a later change to the caller's dict does not reach them). Each function
    turns these into its :class:`~drillstring.stochastic.uncertainty_settings.UncertaintySettings` and refuses a
    field it does not use (a sensitivity run draws only ``parameters``).
    """

    parameters: Mapping[str, Any] | None = None
    correlation: Mapping[str, Any] | None = None
    sigma: float | None = None
    dispersion: float | None = None
    model: Mapping[str, float] | None = None

    def __post_init__(self) -> None:
        from drillstring.api.arguments import check_mapping
        from drillstring.checks import real_number

        for name in ("parameters", "correlation", "model"):
            check_mapping(name, getattr(self, name))
            if getattr(self, name) is not None:
                object.__setattr__(self, name, dict(getattr(self, name)))
        if self.sigma is not None and self.dispersion is not None:
            raise ValueError("give sigma [N] or dispersion (sigma / mean weight_on_hook), not both")
        if self.sigma is not None:
            object.__setattr__(self, "sigma", real_number("sigma", self.sigma, unit="N", low=0.0, low_open=True))
        if self.dispersion is not None:
            object.__setattr__(self, "dispersion", real_number("dispersion", self.dispersion, low=0.0,
                                                               low_open=True))

    def declared(self) -> bool:
        """Whether any field is given (else each function's default applies)."""
        return any(getattr(self, f.name) is not None for f in fields(self))


@dataclass(frozen=True)
class SearchOptions:
    """The budget of the robust operating point's search (:func:`~drillstring.optimize`).

    Attributes:
        samples: realizations per design point, an integer from 2 to
            :data:`~drillstring.stochastic.optimize.MAX_SAMPLES`.
        points: design points in all (None: twice ``initial``).
        initial: points of the initial space-filling design (None: 4 per decision variable, at least 4).
        batch: points chosen together after the initial design, their realizations run in one pass of the engine
            (None: :data:`~drillstring.stochastic.optimize.DEFAULT_BATCH`).
        probability_mean: the prior mean of the constraints' surrogates, ``"constant"`` or ``"linear"`` (a fitted
            plane, where the processes return far from the data).

    Their ranges against each other and the decision variables are checked by
    :func:`~drillstring.stochastic.optimize.check_optimization`.
    """

    samples: int = DEFAULT_POINT_SAMPLES
    points: int | None = None
    initial: int | None = None
    batch: int | None = None
    probability_mean: str = "constant"

    def __post_init__(self) -> None:
        from drillstring.stochastic.optimize import checked_budget

        budget = checked_budget(self.samples, self.initial, self.points, self.batch, self.probability_mean)
        for name, value in zip(("samples", "initial", "points", "batch"), budget):
            object.__setattr__(self, name, value)


def gathered(function: str, keywords: Mapping[str, Any], given: Mapping[str, Any],
             taken: Mapping[str, tuple[str, ...]]) -> tuple:
    """The settings objects of ``function`` (its name, for messages): for each ``name -> object or None`` of
    ``given`` (``{"window": ..., "run": ...}``; the class by the name: :data:`SETTINGS`), the object, or one built
    from the ``keywords`` that are its fields (the function's earlier keyword-by-keyword signature).

    ``taken`` names, per object, the fields the function uses; a keyword that is none of them is refused
    (TypeError naming the keywords and objects the function takes), as is a keyword given while its object is too
    (TypeError), and an object with a field the function does not use set (ValueError naming it)."""
    objects = {}
    for name, value in given.items():
        cls = SETTINGS[name]
        if value is not None and not isinstance(value, cls):
            raise TypeError(f"{name} = {value!r}: must be a {cls.__name__} or None")
    owner = {field: name for name in given for field in taken[name]}
    for key in keywords:
        if key not in owner:
            allowed = ", ".join(sorted(owner))
            raise TypeError(f"{function}() got an unexpected keyword argument {key!r}; it takes the settings "
                            f"objects {', '.join(given)} or their fields as keywords: {allowed}")
        if given[owner[key]] is not None:
            raise TypeError(f"{function}(): {key} is given both as a keyword and in {owner[key]}= "
                            f"({type(given[owner[key]]).__name__}); give it once")
    for name, value in given.items():
        cls = SETTINGS[name]
        if value is None:
            value = cls(**{key: keywords[key] for key in taken[name] if key in keywords})
        defaults = cls()
        for field in fields(cls):
            if field.name not in taken[name] and getattr(value, field.name) != getattr(defaults, field.name):
                raise ValueError(f"{function}(): {name}.{field.name} = {getattr(value, field.name)!r}: not used "
                                 f"here; it uses {', '.join(taken[name])}")
        objects[name] = value
    return tuple(objects.values())


#: The class of each settings object by the keyword that names it in the functions' signatures.
SETTINGS = {"run": RunOptions, "window": SimulationWindow, "inputs": RandomInputs, "search": SearchOptions}

#: Every field of each settings object (what a function that uses the whole object takes).
ALL_FIELDS = {name: tuple(f.name for f in fields(cls)) for name, cls in SETTINGS.items()}
