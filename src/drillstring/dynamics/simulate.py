"""Time response of one drilling run: integrate the reduced-order model and collect observables."""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from drillstring.checks import real_number
from drillstring.dynamics.indicators import transient_end
from drillstring.dynamics.rom import (
    OBSERVABLE_COLUMN,
    OBSERVABLES,
    PROBE_COLUMN,
    ReducedOrderModel,
    observation_width,
)
from drillstring.dynamics.runge_kutta import IntegrationError, integrate


@dataclass
class SimulationResult:
    """Observables of one run on the output grid (SI units).

    Attributes:
        time: output times [s].
        observables: name -> values on ``time`` (names in :data:`~drillstring.dynamics.rom.OBSERVABLES`).
        radial_displacement: (n_time, n_probes) radial displacement r at the probes [m].
        lateral_displacement: (n_time, n_probes, 2) lateral displacements (v, w) at the probes [m], along
            y and z (the whirl orbit).
        probe_positions: x of the probes [m]; ``probe_gaps`` their radial gaps [m].
        impacts: number of times the string hit the borehole wall: contact zones (runs of consecutive
            nodes in contact) that appeared, checked after every accepted integration step
            (:func:`~drillstring.dynamics.rom.new_contact_zones`; a zone that moves along the string or
            grows is the same contact, not a new impact).
        status: "success" or "failed"; ``message`` says where and why a failed run stopped.
        state: where the run ended (:class:`~drillstring.dynamics.compiled.RunState`: the time, the state,
            the bit's history, the contact, the step-size controller), from which
            :func:`~drillstring.dynamics.compiled.advance` continues it; None with the reference engine.
        stats: solver statistics (right-hand-side evaluations, accepted/rejected steps, the solver's
            wall time ``wall_time`` [s]; with the compiled engine also ``compile_time`` [s], the time
            spent compiling the kernels or loading them from Numba's cache before solving, and
            ``compiled``, whether anything was compiled).
    """

    time: np.ndarray
    observables: dict[str, np.ndarray]
    radial_displacement: np.ndarray
    lateral_displacement: np.ndarray
    probe_positions: np.ndarray
    probe_gaps: np.ndarray
    impacts: int
    status: str
    message: str
    stats: dict = field(default_factory=dict)
    state: object = None

    @property
    def success(self) -> bool:
        return self.status == "success"


class SimulationError(RuntimeError):
    """A run that stopped early (divergence, step size collapse); ``.result`` keeps what was computed."""

    def __init__(self, message: str, result: SimulationResult) -> None:
        super().__init__(message)
        self.result = result


def simulate_model(
    model: ReducedOrderModel,
    *,
    t_end: float,
    output_step: float,
    rtol: float = 1e-6,
    atol: float = 1e-9,
    method: str | object = "dopri5",
    max_steps: int = 2_000_000,
    min_step: float = 1e-12,
    lateral_perturbation: float = 1e-4,
    seed: int = 0,
    progress: Callable[[float], None] | None = None,
    raise_on_failure: bool = True,
    engine: str = "compiled",
    initial_state: np.ndarray | None = None,
    initial_depth_of_cut: float | None = None,
) -> SimulationResult:
    """Integrate ``model`` from its initial state (:meth:`ReducedOrderModel.initial_state`) to ``t_end``
    [s], storing observables every ``output_step`` [s]. A failed integration raises
    :class:`SimulationError` (or, with ``raise_on_failure=False``, returns the partial result).

    ``engine``: "compiled" (default; :mod:`drillstring.dynamics.compiled`, the whole step loop in
    Numba) or "reference" (the generic :func:`~drillstring.dynamics.runge_kutta.integrate` calling
    the NumPy right-hand side :meth:`ReducedOrderModel.rhs_reference`). Both use the same method,
    controller and dense output; tests check they agree within the integration tolerance. ``method``: a
    name of :data:`~drillstring.dynamics.runge_kutta.TABLEAUS`, or a method object of a registered step
    kind (:mod:`drillstring.dynamics.steps`; the reference engine needs a kind with a NumPy reference).
    ``initial_state`` ([η, η̇] and the top drive's states, :attr:`ReducedOrderModel.state_size`) replaces the model's initial state (e.g. steady drilling plus a
    perturbation, :mod:`drillstring.dynamics.stability`). A delayed bit–rock law starts from the hole
    bottom of :meth:`ReducedOrderModel.start_history` (``initial_depth_of_cut`` [m] per blade under the bit
    for the reference start; default that of steady drilling at the static weight-on-bit).
    """
    if engine not in ("compiled", "reference"):
        raise ValueError(f"engine = {engine!r}: must be 'compiled' or 'reference'")
    if initial_state is None:
        y0 = model.initial_state(lateral_perturbation, seed)
    else:
        y0 = np.array(initial_state, dtype=float)
        if y0.shape != (model.state_size,):
            raise ValueError(f"initial_state has shape {y0.shape}: must be ({model.state_size},)")
    history = model.start_history(y0, initial_depth_of_cut)  # the run's own, as every array it writes
    if engine == "compiled":
        model.require_compiled()
        from drillstring.dynamics.compiled import RunState, SolverSettings, advance

        grid = output_grid(t_end, output_step)
        run = advance(model, SolverSettings(method, rtol, atol, min_step=min_step, max_steps=max_steps),
                      RunState(0.0, y0, history), t_end, output_times=grid, progress=progress)
        stats = run.stats
        impacts = int(stats.pop("impacts"))
        return _result(model, run.time, run.outputs, impacts, run.message, stats, raise_on_failure, run.state)
    counter = model.impact_counter()
    impacts = counter(y0)

    def count_impacts(t: float, y: np.ndarray) -> None:
        nonlocal impacts
        impacts += counter(y)

    def record(t_old: float, h: float, y_old: np.ndarray, coef: np.ndarray) -> None:
        model.record_history(history, t_old, h, y_old, coef)

    start = _time.perf_counter()
    failure = None
    try:
        solution = integrate(
            lambda t, y: model.rhs_reference(t, y, history), (0.0, t_end), y0, output_step=output_step,
            tableau=method, rtol=rtol, atol=atol, max_steps=max_steps, min_step=min_step, progress=progress,
            observe=lambda t, y: model.observe(t, y, history), on_step=count_impacts,
            on_dense_step=record if model.bit_rock.delayed else None,
        )
    except IntegrationError as error:
        failure = error
        solution = error.solution
    wall = _time.perf_counter() - start
    values = np.asarray(solution.y) if solution is not None and len(solution.t) else np.zeros(
        (0, observation_width(len(model.probe_nodes))))
    times = np.asarray(solution.t) if solution is not None else np.zeros(0)
    stats = dict(solution.stats) if solution is not None else {}
    stats["wall_time"] = wall
    return _result(model, times, values, impacts, str(failure) if failure else "", stats,
                   raise_on_failure)


def _result(model, times, values, impacts, message, stats, raise_on_failure, state=None) -> SimulationResult:
    """Split the observed rows into a :class:`SimulationResult`; raise if the run failed."""
    stats["status"] = "failed" if message else "success"
    n_p = len(model.probe_nodes)
    result = SimulationResult(
        time=times,
        observables={name: values[:, OBSERVABLE_COLUMN[name]] for name in OBSERVABLES},
        radial_displacement=values[:, PROBE_COLUMN:PROBE_COLUMN + n_p],
        lateral_displacement=np.stack([values[:, PROBE_COLUMN + n_p:PROBE_COLUMN + 2 * n_p],
                                       values[:, PROBE_COLUMN + 2 * n_p:PROBE_COLUMN + 3 * n_p]], axis=-1),
        probe_positions=model.probe_positions.copy(),
        probe_gaps=model.gap[model.probe_nodes].copy(),
        impacts=impacts,
        status=stats["status"],
        message=message,
        stats=stats,
        state=state,
    )
    if message and raise_on_failure:
        raise SimulationError(f"simulation stopped early: {message}", result)
    return result


#: Largest number of output times of one run: every observable of a run (and of each realization of a
#: study) is kept in memory on this grid; 2 million times of the ~14 observed columns take about 220 MB
#: (e.g. 20,000 s of drilling at the default 0.01 s output step).
MAX_OUTPUT_POINTS = 2_000_000


def output_points(t_end: float, output_step: float) -> int:
    """The number of times of :func:`output_grid` (computed without building it)."""
    n = math.floor(t_end / output_step + 1e-9)
    return n + 1 + (t_end - n * output_step > 1e-9 * output_step)


@dataclass(frozen=True)
class RunWindow:
    """The time window of a run, checked once (:func:`run_window`) for every kind of run.

    Attributes:
        t_end: simulated time [s], finite and > 0.
        output_step: output step [s], in (0, t_end].
        transient: start of the steady window of the summaries [s], in [0, t_end) (strictly below
            t_end: the window after it holds at least one output step).
    """

    t_end: float
    output_step: float
    transient: float

    @property
    def points(self) -> int:
        """Number of output times."""
        return output_points(self.t_end, self.output_step)

    @property
    def time(self) -> np.ndarray:
        """The output grid [s] (:func:`output_grid`)."""
        return output_grid(self.t_end, self.output_step)


def run_window(t_end, output_step, transient=None, *, max_points: int = MAX_OUTPUT_POINTS,
               names: Mapping[str, str] | None = None) -> RunWindow:
    """The checked :class:`RunWindow`: ``t_end`` [s] a finite number > 0, ``output_step`` [s] in (0, t_end],
    at most ``max_points`` output times (checked before anything is allocated), ``transient`` [s] in
    [0, t_end) (None: :func:`~drillstring.dynamics.indicators.transient_end`, ``min(10 s, t_end/2)``).
    TypeError for a value that is not a number, ValueError (one line naming the argument: its name in
    ``names`` when given there, e.g. ``{"t_end": "--t-end"}``) otherwise."""
    name = {"t_end": "t_end", "output_step": "output_step", "transient": "transient", **(names or {})}
    t_end = real_number(name["t_end"], t_end, unit="s", low=0.0, low_open=True)
    output_step = real_number(name["output_step"], output_step, unit="s", low=0.0, low_open=True, high=t_end,
                              allowed=f"a number in (0, t_end = {t_end:g} s]")
    points = output_points(t_end, output_step)
    if points > max_points:
        raise ValueError(f"{name['t_end']} = {t_end:g} s at output_step = {output_step:g} s: {points} output "
                         f"times, above the limit of {max_points} (lengthen output_step or shorten t_end)")
    if transient is None:
        transient = transient_end(t_end)
    transient = real_number(name["transient"], transient, unit="s", low=0.0, high=t_end, high_open=True,
                            allowed=f"a number in [0, t_end = {t_end:g} s)")
    return RunWindow(t_end, output_step, transient)


def output_grid(t_end: float, output_step: float) -> np.ndarray:
    """Output times k·Δt up to t_end, t_end included (the reference integrator's grid)."""
    n = int(np.floor(t_end / output_step + 1e-9))
    grid = np.arange(n + 1) * output_step
    if t_end - grid[-1] > 1e-9 * output_step:
        grid = np.append(grid, t_end)
    grid[-1] = min(grid[-1], t_end)
    return grid


#: Relative tolerance of :func:`settling_time`: the bit speed's range per oscillation period is settled once
#: it stays within this fraction of the last period's range (plus :data:`SETTLED_FLOOR` of the top speed).
SETTLED_TOLERANCE = 0.15
#: Absolute part of the settling tolerance, as a fraction of the top speed (steady drilling's range is ~0).
SETTLED_FLOOR = 0.01


def settling_time(time, bit_speed, top_speed: float, start: float = 0.0) -> float:
    """When the bit speed's oscillation has settled [s], measured on the run: the record from ``start`` [s]
    is cut into blocks of one oscillation period (:func:`~drillstring.dynamics.indicators.oscillation_period`
    of the last half of the record; 1 s without one), and the answer is the start of the first block from
    which every block's range (max − min) is within :data:`SETTLED_TOLERANCE` of the last block's, plus
    :data:`SETTLED_FLOOR` × ``top_speed`` [rad/s]. NaN when fewer than three blocks fit, or when only the
    last two agree (the oscillation still grows or decays at the end of the run)."""
    from drillstring.dynamics.indicators import oscillation_period

    t = np.asarray(time, dtype=float)
    speed = np.asarray(bit_speed, dtype=float)
    keep = np.isfinite(t) & np.isfinite(speed) & (t >= start)
    t, speed = t[keep], speed[keep]
    if t.size < 3:
        return math.nan
    late = t >= 0.5 * (t[0] + t[-1])
    period = oscillation_period(t[late], speed[late])
    period = 1.0 if not math.isfinite(period) else period
    edges = np.arange(t[0], t[-1] + 1e-9 * period, period)
    if edges.size < 4:
        return math.nan
    ranges = np.array([np.ptp(speed[(t >= a) & (t < b)]) if np.any((t >= a) & (t < b)) else np.nan
                       for a, b in zip(edges[:-1], edges[1:])])
    final = ranges[-1]
    close = np.abs(ranges - final) <= SETTLED_TOLERANCE * final + SETTLED_FLOOR * abs(top_speed)
    first = len(close)
    while first > 0 and close[first - 1]:
        first -= 1
    return math.nan if first >= len(ranges) - 2 else float(edges[first])


@dataclass(frozen=True)
class StartFacts:
    """What the start of a run leaves in its summaries, measured on the run (:func:`start_facts`).

    Attributes:
        negative_rop_until: the last time [s] the rate of penetration was below 0 before it first
            became positive (NaN when it never was below 0); ``force_on_bit_then``: the force on bit [N] at
            that time (the Tucker–Wang law, a law of rates, gives ROP < 0 under a light weight on bit:
            docs/model.md §8).
        window_start: the start of the summaries' window [s]; ``settled``: :func:`settling_time` from
            ``ramp_end`` (NaN: not settled by the end of the run); ``ramp_end``: the end of the weight ramp [s]
            (0 for a start on bottom).
    """

    negative_rop_until: float
    force_on_bit_then: float
    window_start: float
    settled: float
    ramp_end: float

    @property
    def window_before_settled(self) -> bool:
        """Whether the window starts before the oscillation has settled (or it never settles)."""
        return not (self.settled <= self.window_start + 1e-9)


def start_facts(time, observables: Mapping[str, np.ndarray], window_start: float, ramp_end: float,
                top_speed: float) -> StartFacts:
    """The :class:`StartFacts` of a run on the output ``time`` [s] with its ``observables`` (SI), the
    summaries' ``window_start`` [s], the end of its weight ramp ``ramp_end`` [s] (0 for a start on bottom) and
    the top speed [rad/s]."""
    t = np.asarray(time, dtype=float)
    rop = np.asarray(observables["rate_of_penetration"], dtype=float)
    force = np.asarray(observables["force_on_bit"], dtype=float)
    negative, until, then = np.flatnonzero(rop < 0.0), math.nan, math.nan
    if negative.size:
        positive = np.flatnonzero(rop > 0.0)
        later = negative[negative < positive[0]] if positive.size else negative
        if later.size:
            until, then = float(t[later[-1]]), float(force[later[-1]])
    settled = settling_time(t, observables["bit_speed"], top_speed, start=ramp_end)
    return StartFacts(until, then, float(window_start), settled, float(ramp_end))
