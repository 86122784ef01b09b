"""Fast path: the adaptive step loop for the reduced-order model, compiled with Numba.

The loop is split from the step. The *step* — its stages, its local error estimate and its dense output — is
a step kind of :mod:`drillstring.dynamics.steps`, chosen by the type of the method's data when the loop is
compiled (:mod:`drillstring.dynamics.steps.explicit_rk` for a
:class:`~drillstring.dynamics.runge_kutta.ButcherTableau`, :mod:`drillstring.dynamics.steps.imex_ark` for an
:class:`~drillstring.dynamics.additive_rk.AdditiveTableau`: the stiff part implicit;
:mod:`drillstring.dynamics.steps.exponential` for an :class:`~drillstring.dynamics.exponential_rk.ExponentialTableau`:
the linear modal part exact, its data prepared from the run's model data and start).
The *loop* (:func:`_run_chunk`) owns the rest: the step-size controller — the compiled functions
:func:`~drillstring.dynamics.runge_kutta.error_norm` and :func:`~drillstring.dynamics.runge_kutta.step_factor`,
shared with the reference integrator :func:`~drillstring.dynamics.runge_kutta.integrate` —, acceptance, landing
on t_end, the pauses and the collapse check, the observations on the output grid from the step's dense output,
and what the model does after each accepted step (impacts, the delayed bit history). It calls the ROM's
right-hand side (:func:`~drillstring.dynamics.rom.evaluate_rhs`, through the step) and observation kernels
(:func:`~drillstring.dynamics.rom.observe_kernel`, :func:`~drillstring.dynamics.rom.accepted_step_kernel`: the
model's public interface to the loop, see :mod:`drillstring.dynamics.rom`) directly from compiled code, so that
no Python runs inside the step loop; the loop is generic over the model's components and over the step kinds.
Tests check that the compiled and the reference paths agree to within the integration tolerance.

**State in, state out.** :func:`advance` integrates a run from a :class:`RunState` (time, state, the bit's
history, the nodes in contact, the step-size controller's state, dy/dt) to a time ``t1`` and returns an
:class:`AdvanceResult` (the state where it stopped, the outputs it observed, statistics): after diffrax's
``diffeqsolve`` and SciPy's ``OdeSolver``. Every array a run writes is created for the call (the workspace,
the step's buffers, and the model's :meth:`~drillstring.dynamics.rom.ReducedOrderModel.kernel_data`: the
model's data, which nothing writes, with the run's own scratch and bit history), so a run can be continued,
restarted from a modified state (a filter's update) or interleaved with another run of the same model.
:func:`drillstring.dynamics.simulate.simulate_model` is one :func:`advance` from t = 0.

The compiled loop takes five structured arguments built in one place each: :class:`Workspace` (state
and buffers, :meth:`Workspace.allocate`), the step's data (:func:`~drillstring.dynamics.steps.step_data`),
:class:`StepperSettings` (controller and limits, :meth:`StepperSettings.create`), and the run's kernel data
(``rhs``, ``case2`` and ``observe`` of :class:`~drillstring.dynamics.rom.KernelData`). It is compiled once per
type of the right-hand side's data (case 2 or case 1) and of the step's data, and cached on disk (a step kind
defined outside the package runs uncached); the first compilation in a fresh cache is announced on stderr and
its duration is reported as ``compile_time``, apart from the solver's ``wall_time``; the announcement names
the kernel set (:func:`kernel_set`: the step kind and the model's data type), each announced once per process.

The loop runs in chunks so a progress callback can be called between chunks; the step sequence does not
depend on the chunking (steps never land on chunk boundaries, only on ``t1``, or, with ``land=False``, on
none).
A chunk also pauses after a bounded number of step attempts (about :data:`CALL_SECONDS` of work), so the
loop returns to Python often: Ctrl-C (``KeyboardInterrupt``) takes effect within a fraction of a second
even when the step size has collapsed, and the collapse itself is detected early: a run whose mean step
(over the last :data:`COLLAPSE_WINDOW` attempts, and since the start unless the recent one is below
:data:`COLLAPSE_RATIO` times the output step) would take more than ``max_steps`` attempts to reach t_end
stops with the time, the step size and the likely stiff term (:mod:`drillstring.dynamics.stiffness`), keeping
the rows already computed.
"""

from __future__ import annotations

import math
import sys
import time as _time
from dataclasses import dataclass, replace
from types import FunctionType
from typing import Callable, NamedTuple

import numpy as np
from numba import njit, typeof
from numba.core import event

from drillstring.dynamics.rom import (
    accepted_step_kernel,
    _rhs_kernel,
    evaluate_rhs,
    impacts_kernel,
    observation_width,
    observe_kernel,
    observe_row,
    observes_rate,
)
from drillstring.dynamics.runge_kutta import StepSizeController, error_norm, method_named, step_factor
from drillstring.dynamics.steps import accept as step_accept
from drillstring.dynamics.steps import attempt as step_attempt
from drillstring.dynamics.steps import kind_of, step_data
from drillstring.dynamics.steps.kinds import kind_of_data
from drillstring.forces.registry import inlined
from drillstring.dynamics.stiffness import stiffness_diagnosis

SUCCESS, MIN_STEP, MAX_STEPS, NON_FINITE, PAUSED, COLLAPSED = 0, 1, 2, 3, 4, 5
# indices into the integrator's scalar state array (PAUSE_AT: step attempts after which a chunk pauses)
# T_END: where the run ends; LANDS: 1 when its last step lands on T_END, 0 when it ends with the first step that
# reaches T_END (advance's ``land``)
T, H, ERR_PREV, REJECTED_LAST, N_RHS, N_ACCEPTED, N_REJECTED, IMPACTS, N_OUT, LAST_CAUSE, PAUSE_AT, T_END, LANDS = \
    range(13)
N_STATE = 13
#: Wall time [s] one call of the compiled loop aims at before it returns to Python (Ctrl-C, progress).
CALL_SECONDS = 0.1
#: Step attempts of the first call (then adapted to take about CALL_SECONDS each).
FIRST_CALL_ATTEMPTS = 200
#: Step attempts over which the mean step is measured (the window), and the fraction of the output step
#: below which that mean alone predicts the run's length: a run stops as collapsed when reaching t_end
#: would take more than max_steps attempts at the window's mean step, if it is below this floor, else at
#: the larger of the window's and the whole run's mean steps. The contact case's impacts take steps of
#: about 1e-4 of its output step; a fluid at 1e3 m/s, 2e-6; at 1e4 m/s, 3e-8.
COLLAPSE_WINDOW, COLLAPSE_RATIO = 20_000, 1e-5
CAUSES = {0: "", 1: "error estimate not met", 2: "non-finite values in the right-hand side"}


class StepperSettings(NamedTuple):
    """The step-size controller and the run's limits, as the compiled loop reads them (the method's data is
    the step kind's own, :mod:`drillstring.dynamics.steps`)."""

    rtol: float
    atol: np.ndarray  # (n,) one absolute tolerance per state component
    safety: float
    min_factor: float
    max_factor: float
    beta1: float
    beta2: float
    max_step: float  # [s]
    min_step: float  # [s]
    max_steps: float  # step attempts, accepted + rejected
    stretch: float  # a step within this fraction of t_end is stretched to land on it

    @classmethod
    def create(cls, controller: StepSizeController, n: int, *, min_step: float, max_steps: int,
               stretch: float = 0.01) -> StepperSettings:
        return cls(
            rtol=float(controller.rtol), atol=controller.atol_vector(n), safety=float(controller.safety),
            min_factor=float(controller.min_factor), max_factor=float(controller.max_factor),
            beta1=float(controller.beta1), beta2=float(controller.beta2),
            max_step=float(controller.max_step), min_step=float(min_step), max_steps=float(max_steps),
            stretch=float(stretch),
        )


class Workspace(NamedTuple):
    """The integrator's state and buffers: ``state`` (scalars indexed by ``T``, ``H``, …), the current
    state ``y`` and its derivative ``f``, the state ``y_old`` at the start of the last accepted step (dense
    output), and the output ``grid`` and the rows ``out`` it fills. The step's own buffers (stages) are in
    its data (:mod:`drillstring.dynamics.steps`)."""

    state: np.ndarray  # (N_STATE,)
    y: np.ndarray  # (n,)
    f: np.ndarray  # (n,)
    y_old: np.ndarray  # (n,)
    y_new: np.ndarray  # (n,) scratch: the candidate solution, then dense output
    error: np.ndarray  # (n,) scratch: local error estimate
    rate: np.ndarray  # (n,) dy/dt of the case-2 model at an observed state, where the observation reads it
    grid: np.ndarray  # (n_out,) output times [s]
    out: np.ndarray  # (n_out, n_columns) observations

    @classmethod
    def allocate(cls, y0: np.ndarray, grid: np.ndarray, n_columns: int) -> Workspace:
        n = y0.shape[0]
        return cls(
            state=np.zeros(N_STATE), y=np.array(y0, dtype=float), f=np.zeros(n), y_old=np.zeros(n),
            y_new=np.zeros(n), error=np.zeros(n), rate=np.zeros(n), grid=np.ascontiguousarray(grid, dtype=float),
            out=np.full((len(grid), n_columns), np.nan),
        )


def _run_chunk(work, t_stop, step, settings, rhs_data, case2, observe_data):
    """Step until the time reaches ``t_stop`` (at most ``state[T_END]``), observing every output time of
    ``work.grid`` that the steps pass. Returns a status code.
    ``step`` is the step kind's data (:mod:`drillstring.dynamics.steps`: its type chooses the step),
    ``rhs_data`` the model's right-hand-side data (case 2 or case 1), ``case2`` its case-2 part
    (what the observation kernel reads)."""
    st = settings
    state, y, f, y_old, y_new, err = work.state, work.y, work.f, work.y_old, work.y_new, work.error
    grid = work.grid
    n = y.shape[0]
    n_grid = grid.shape[0]
    t_end = state[T_END]
    lands = state[LANDS] > 0.0
    while True:
        t = state[T]
        row = int(state[N_OUT])
        if t >= t_stop:
            return SUCCESS
        if state[N_ACCEPTED] + state[N_REJECTED] >= st.max_steps:
            return MAX_STEPS
        if state[N_ACCEPTED] + state[N_REJECTED] >= state[PAUSE_AT]:
            return PAUSED
        h = state[H]
        remaining = t_end - t
        last = False
        if lands and h * (1.0 + st.stretch) >= remaining:
            h = remaining
            last = True
        elif h < st.min_step:
            return MIN_STEP
        evaluations, finite = step_attempt(step, rhs_data, t, h, y, f, y_new, err)
        state[N_RHS] += evaluations
        norm = math.nan
        if finite:
            norm = error_norm(y, y_new, err, st.rtol, st.atol)
        accepted, factor, err_prev = step_factor(
            norm, state[ERR_PREV], state[REJECTED_LAST] > 0.0, step.order, st.safety, st.min_factor,
            st.max_factor, st.beta1, st.beta2)
        state[ERR_PREV] = err_prev
        if not accepted:
            state[N_REJECTED] += 1
            state[REJECTED_LAST] = 1.0
            state[LAST_CAUSE] = 1.0 if math.isfinite(norm) else 2.0
            state[H] = min(h * factor, st.max_step)
            continue
        state[REJECTED_LAST] = 0.0
        state[LAST_CAUSE] = 0.0
        for j in range(n):
            if not math.isfinite(y_new[j]):
                return NON_FINITE
        # commit; the step keeps what its dense output needs and gives f at the new state
        for j in range(n):
            y_old[j] = y[j]
            y[j] = y_new[j]
        t_new = t_end if last else t + h
        if not step_accept(step, y, f):
            evaluate_rhs(rhs_data, t_new, y, f)
            state[N_RHS] += 1
        dense, kept = step.dense, step.dense_stages
        state[IMPACTS] += accepted_step_kernel(case2, observe_data, t, h, y_old, kept, dense, y)
        state[T] = t_new
        state[H] = min(h * factor, st.max_step)
        state[N_ACCEPTED] += 1
        # outputs inside (t, t_new]: y(t + θh) = y_old + h Σ_m Σ_p dense[m, p] θ^(p+1) kept[m]
        while row < n_grid and grid[row] <= t_new:
            tg = grid[row]
            observed = y
            if tg != t_new:
                theta = (tg - t) / h
                for j in range(n):
                    acc = 0.0
                    for m in range(kept.shape[0]):
                        bm = 0.0
                        power = theta
                        for p in range(dense.shape[1]):
                            bm += dense[m, p] * power
                            power *= theta
                        acc += bm * kept[m, j]
                    y_new[j] = y_old[j] + h * acc
                observed = y_new
            if observes_rate(case2):  # the observation reads dy/dt: evaluated here, not in it (observe_row)
                _rhs_kernel(case2, tg, observed, work.rate)
            observe_kernel(case2, observe_data, tg, observed, work.rate, work.out[row])
            row += 1
            state[N_OUT] = row


_LOOPS: dict = {}  # StepKind -> its compiled loop


def _loop(step) -> Callable:
    """The loop compiled for the kind of ``step`` (its data): :func:`_run_chunk` with ``step_attempt`` and
    ``step_accept`` bound to the kind's own functions, which Numba inlines into it (IR level); cached on disk
    for the package's kinds, not for kinds defined elsewhere (the kernel cache's source hash does not cover
    them, :mod:`drillstring.dynamics.steps.kinds`). One loop per kind, sharing the source and the cache index
    (their signatures differ by the step's data type). A kind whose step allocates nothing
    (``StepKind.allocates`` False: the explicit Runge–Kutta pairs, the IMEX step) gets a loop compiled without Numba's reference
    counting (``_nrt=False``, the kernels it calls compiled so too; every array they touch is the run's own,
    allocated in Python): the increments and decrements of the arrays of the model's structured data, at every
    call of an inner kernel, cost more than the arithmetic (docs/performance.md). Why not the loop calling the kind's functions through
    the ``overload`` of :func:`drillstring.dynamics.steps.attempt`: each compiled function that calls the
    right-hand side carries a copy of its call tree, which Numba generates again — the attempt compiled on its
    own cost 2–2.4 s of the reference case's first compilation (docs/performance.md)."""
    kind = kind_of_data(step)
    loop = _LOOPS.get(kind)
    if loop is None:
        namespace = dict(_run_chunk.__globals__, step_attempt=inlined(kind.attempt), step_accept=inlined(kind.accept))
        function = FunctionType(_run_chunk.__code__, namespace, _run_chunk.__name__)
        function.__qualname__, function.__doc__ = _run_chunk.__qualname__, _run_chunk.__doc__
        loop = _LOOPS[kind] = njit(cache=kind.cacheable, _nrt=kind.allocates)(function)
    return loop


# ---------------------------------------------------------------------------------------------------------
# Compilation: once per process, visibly
# ---------------------------------------------------------------------------------------------------------

#: About how long the first compilation takes on a 2-core machine [s], per nonlinear model.
COMPILE_ESTIMATE = {"bit_and_contact": 17, "full": 24}


def _notify_stderr(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


#: Called with a one-line message when kernels start compiling (first run in a fresh cache only).
compile_notice: Callable[[str], None] = _notify_stderr
#: The kernel sets (:func:`kernel_set`) announced in this process.
_announced: set = set()


def kernel_set(model, method) -> str:
    """What the step loop is compiled for, in words: the kind of step of ``method`` (explicit Runge–Kutta,
    or implicit–explicit for an :class:`~drillstring.dynamics.additive_rk.AdditiveTableau`; its name) and the
    type of the model's data — case 2 or case 1 (``model.nonlinear``), with or without a delayed bit–rock law
    (its depth-of-cut history). One loop is compiled per such set (the kernels depend on the types of their
    data, not on sizes or values: :func:`prepare_kernels`), so a case that adds a set (the first ``ark43`` run
    of a delayed law, say) compiles once more, then loads it from the cache."""
    from drillstring.dynamics.additive_rk import AdditiveTableau
    from drillstring.dynamics.exponential_rk import ExponentialTableau
    from drillstring.dynamics.runge_kutta import ButcherTableau

    if isinstance(method, AdditiveTableau):
        kind = "implicit-explicit step"
    elif isinstance(method, ExponentialTableau):
        kind = "exponential step"
    elif isinstance(method, ButcherTableau):
        kind = "explicit Runge-Kutta step"
    else:
        kind = f"{type(method).__name__} step"
    name = getattr(method, "name", "")
    model_kind = "case 1 (full) model" if model.nonlinear == "full" else "case 2 model"
    if model.bit_rock.delayed:
        model_kind += " with a delayed bit-rock law"
    return f"the {kind}{f' ({name})' if name else ''} of the {model_kind}"


class _CompileMonitor(event.Listener):
    """Counts the time Numba spends compiling (cache misses only: loading a cached kernel fires no
    compile event) and announces, once per process, the first compilation of each kernel set (``what``,
    :func:`kernel_set`)."""

    def __init__(self, estimate: float, what: str = "") -> None:
        self.estimate = estimate
        self.what = what
        self.depth = 0
        self.started = 0.0
        self.seconds = 0.0
        self.compiled = False

    def on_start(self, ev) -> None:
        if self.depth == 0:
            self.started = _time.perf_counter()
            if self.what not in _announced:
                _announced.add(self.what)
                what = f" for {self.what}" if self.what else ""
                compile_notice(f"drillstring: compiling the simulation kernels{what} (first run of this kind "
                               f"only, cached afterwards; up to about {self.estimate:g} s)...")
        self.depth += 1
        self.compiled = True

    def on_end(self, ev) -> None:
        self.depth -= 1
        if self.depth == 0:
            self.seconds += _time.perf_counter() - self.started


def _structure(value):
    """A key that is equal for two values Numba types alike, None for a value it cannot vouch for: an array's
    dtype, dimensions, layout and flags, a tuple's class and members' keys, a number's class. About 15 times
    cheaper than :func:`numba.typeof` on a model's kernel data (40 µs against 0.6 ms), which a study paid three
    times a realization."""
    if isinstance(value, np.ndarray):
        flags = value.flags
        return value.dtype.str, value.ndim, flags.c_contiguous, flags.f_contiguous, flags.writeable, flags.aligned
    if isinstance(value, tuple):
        members = tuple(_structure(member) for member in value)
        return None if None in members else (type(value), members)
    if type(value) in (float, int, bool):
        return type(value)
    return None


#: (dispatcher, structure of the arguments) already compiled or loaded in this process (:func:`_prepare`).
_PREPARED: set = set()


def _prepare(dispatcher, *args) -> None:
    """Compile ``dispatcher`` for the types of ``args``, or load it from the cache, without running it; once
    per process and argument structure (:func:`_structure`)."""
    key = _structure(args)
    if key is not None and (dispatcher, key) in _PREPARED:
        return
    dispatcher.compile(tuple(typeof(a) for a in args))
    if key is not None:
        _PREPARED.add((dispatcher, key))


def _compile_kernels(model, data, work: Workspace, step, settings: StepperSettings,
                     method=None) -> tuple[float, bool]:
    """Compile (or load from the cache) every kernel the integration of ``model`` (its kernel data ``data``,
    :class:`~drillstring.dynamics.rom.KernelData`) with the step ``step`` (the data of ``method``) calls.
    Returns the time it took [s] and whether anything was compiled; the first compilation of each kernel set
    (:func:`kernel_set`) in the process is announced, naming it."""
    start = _time.perf_counter()
    monitor = _CompileMonitor(COMPILE_ESTIMATE.get(model.nonlinear, 20),
                              "" if method is None else kernel_set(model, method))
    with event.install_listener("numba:compile", monitor):
        _prepare(_loop(step), work, 0.0, step, settings, data.rhs, data.case2, data.observe)
        _prepare(observe_kernel, data.case2, data.observe, 0.0, work.y, work.rate, work.rate)
        _prepare(impacts_kernel, data.case2, data.observe, work.y)
        evaluate_rhs(data.rhs, 0.0, work.y, work.rate)  # the right-hand side as called from Python
    return _time.perf_counter() - start, monitor.compiled


def _method(method):
    """A method given by name (:func:`~drillstring.dynamics.runge_kutta.method_named`) or as itself."""
    return method_named(method) if isinstance(method, str) else method


def prepare_kernels(model, tableau="dopri5") -> tuple[float, bool]:
    """Compile, or load from Numba's cache, the kernels that integrating ``model`` (a
    :class:`~drillstring.dynamics.rom.ReducedOrderModel`) with the method ``tableau`` (a name, a
    :class:`~drillstring.dynamics.runge_kutta.ButcherTableau` or a method of another registered step kind,
    :mod:`drillstring.dynamics.steps`) needs, without integrating.
    Kernels depend on the types of the model's data only (case 1 or case 2), not on its sizes, so one
    call prepares every realization of a study. Returns ``(seconds, compiled)``."""
    method = _method(tableau)
    n = model.state_size
    settings = StepperSettings.create(StepSizeController(), n, min_step=1e-12, max_steps=1)
    work = Workspace.allocate(np.zeros(n), np.zeros(2), observation_width(len(model.probe_nodes)))
    return _compile_kernels(model, model.kernel_data(), work, step_data(method, n), settings, method)


@dataclass(frozen=True)
class SolverSettings:
    """How a run is integrated: the method (a name of :data:`~drillstring.dynamics.runge_kutta.TABLEAUS`, a
    :class:`~drillstring.dynamics.runge_kutta.ButcherTableau`, or a method of any registered step kind,
    :mod:`drillstring.dynamics.steps`, whose type chooses the step), the step-size controller's tolerances
    ``rtol`` [-] and ``atol`` (the state's units), the largest and smallest step [s] and the most step attempts
    (accepted and rejected) of one :func:`advance`."""

    method: object = "dopri5"
    rtol: float = 1e-6
    atol: float = 1e-9
    max_step: float = math.inf
    min_step: float = 1e-12
    max_steps: int = 2_000_000


class ControllerState(NamedTuple):
    """The step-size controller after a run's last step: what it needs to go on as if never stopped."""

    step: float  # [s] the step size it proposes for the next attempt
    error: float  # the previous accepted step's error norm (the proportional–integral controller's memory)
    rejected: bool  # whether the last attempt was rejected (the step does not grow on the next acceptance)


@dataclass(frozen=True)
class RunState:
    """Where a run stands, all that continuing it needs (:func:`advance`): the time ``t`` [s], the state
    ``y`` = [η, η̇, s] (:attr:`~drillstring.dynamics.rom.ReducedOrderModel.state_size`), the bit's ``history``
    (a storage of :mod:`drillstring.dynamics.delay`: the hole bottom of the Detournay law's state-dependent
    delay; :meth:`~drillstring.dynamics.rom.ReducedOrderModel.start_history` at a start), the nodes
    ``in_contact`` with the wall (the impacts count the contact zones that appear; None: none), the step-size
    ``controller``'s state (None: the initial step size is chosen, Hairer–Nørsett–Wanner I §II.4) and ``rate``,
    dy/dt at ``(t, y)`` as the last step computed it (None: evaluated). :meth:`start` builds one at the start of
    a run, :meth:`updated` one from a modified state (a filter's update)."""

    t: float
    y: np.ndarray
    history: np.ndarray
    in_contact: np.ndarray | None = None
    controller: ControllerState | None = None
    rate: np.ndarray | None = None

    @classmethod
    def start(cls, model, y0: np.ndarray, t0: float = 0.0, depth_of_cut: float | None = None) -> RunState:
        """The start of a run of ``model`` from ``y0`` at ``t0`` [s]: the bit's history of
        :meth:`~drillstring.dynamics.rom.ReducedOrderModel.start_history` (``depth_of_cut`` [m] per blade), no
        node in contact before, the initial step size to be chosen."""
        y0 = np.array(y0, dtype=float)
        if y0.shape != (model.state_size,):
            raise ValueError(f"y0 has shape {y0.shape}: must be ({model.state_size},), the model's state")
        return cls(float(t0), y0, model.start_history(y0, depth_of_cut))

    def updated(self, y: np.ndarray) -> RunState:
        """This state with ``y`` in place of its state vector (e.g. a filter's analysis): the history, the
        contact and the controller kept, dy/dt evaluated anew."""
        y = np.array(y, dtype=float)
        if y.shape != self.y.shape:
            raise ValueError(f"y has shape {y.shape}: must be {self.y.shape}")
        return replace(self, y=y, rate=None)


@dataclass
class AdvanceResult:
    """What :func:`advance` returns: the ``state`` where the run stopped (at ``t1`` when it succeeded and
    landed there), the output ``time`` [s] it observed and the ``outputs`` there (rows of
    :func:`~drillstring.dynamics.rom.observation_width` columns, :data:`~drillstring.dynamics.rom.OBSERVABLES`
    first), solver statistics (``stats``, this call's: right-hand sides, steps, ``wall_time`` and
    ``compile_time`` [s], ``compiled``, ``impacts``) and ``message``, empty or why the run stopped early."""

    state: RunState
    time: np.ndarray
    outputs: np.ndarray
    stats: dict
    message: str

    @property
    def success(self) -> bool:
        return not self.message


def advance(model, solver: SolverSettings, start: RunState, t1: float, *, output_times=(), land: bool = True,
            progress: Callable[[float], None] | None = None, chunks: int = 100) -> AdvanceResult:
    """Integrate ``model`` (a :class:`~drillstring.dynamics.rom.ReducedOrderModel`, only read) from the state
    ``start`` (a :class:`RunState`) to ``t1`` [s] with ``solver`` (:class:`SolverSettings`), in compiled code;
    state in, state out, after diffrax's ``diffeqsolve`` and SciPy's ``OdeSolver``. Every array a run writes —
    the bit's history, the contact work, the workspace — is this call's own (the model's
    :meth:`~drillstring.dynamics.rom.ReducedOrderModel.kernel_data`), so two runs of one model may be
    interleaved, continued or restarted from a modified state.

    ``output_times``: ascending times [s] at which to observe, none before ``start.t`` (one equal to it is
    observed at the start); those the steps reach are observed (the rest, beyond a failure or beyond the last
    step, are left to the next call). ``land``: the last step lands on ``t1`` exactly (the returned state is at
    ``t1``); False: the run stops after the first step that reaches ``t1`` (the state at that step's time, at
    or after ``t1``) — continuing from it with the same settings repeats one run to the end bit for bit,
    where landing at an intermediate time changes the steps that follow (by the integration tolerance).
    ``progress``: called with the time reached, about every ``CALL_SECONDS`` of work; ``chunks``: the number of
    stops, evenly spaced, at which it is called at least (without ``progress`` the loop makes no such stops)."""
    method = _method(solver.method)
    kind_of(method)  # a clear TypeError for a method of no registered kind
    y0 = np.array(start.y, dtype=float)
    t0, t1 = float(start.t), float(t1)
    if not t1 >= t0:
        raise ValueError(f"t1 = {t1!r} s: must be at or after the state's time {t0:g} s")
    grid = np.ascontiguousarray(output_times, dtype=float).reshape(-1)
    if len(grid) and (grid[0] < t0 or np.any(np.diff(grid) <= 0.0)):
        raise ValueError(f"output_times: must be increasing and at or after the state's time {t0:g} s")
    ctrl = StepSizeController(rtol=solver.rtol, atol=solver.atol, max_step=solver.max_step)
    settings = StepperSettings.create(ctrl, y0.shape[0], min_step=solver.min_step, max_steps=solver.max_steps)
    work = Workspace.allocate(y0, grid, observation_width(len(model.probe_nodes)))
    data = model.kernel_data(start.history)
    step = step_data(method, y0.shape[0], data.rhs, t0, y0)
    rhs_data, case2, observe_data = data.rhs, data.case2, data.observe
    if start.in_contact is not None:
        observe_data.previous[:] = start.in_contact
    compile_time, compiled = _compile_kernels(model, data, work, step, settings, method)
    run_chunk = _loop(step)

    def rhs(t, y):
        out = np.empty_like(y)
        evaluate_rhs(rhs_data, float(t), y, out)
        return out

    begin = _time.perf_counter()
    state = work.state
    state[T], state[T_END], state[LANDS] = t0, t1, 1.0 if land else 0.0
    if start.rate is not None:
        work.f[:] = start.rate
    else:
        work.f[:] = rhs(t0, work.y)
        state[N_RHS] = 1
    if start.controller is None:
        state[H] = ctrl.initial_step(rhs, t0, work.y, work.f, step.order)
        state[ERR_PREV] = 1.0
        state[N_RHS] += 1
    else:
        state[H], state[ERR_PREV] = start.controller.step, start.controller.error
        state[REJECTED_LAST] = 1.0 if start.controller.rejected else 0.0
    state[IMPACTS] = impacts_kernel(case2, observe_data, work.y)
    if len(grid) and grid[0] == t0:
        observe_row(case2, observe_data, t0, work.y, work.rate, work.out[0])
        state[N_OUT] = 1
    status, collapse = _drive(run_chunk, work, step, settings, data, t0, t1, grid, chunks, solver.max_steps,
                              progress)
    n_written = int(state[N_OUT])
    stats = {
        "status": "success" if status == SUCCESS else "failed",
        "n_out": n_written,
        "n_rhs": int(state[N_RHS]),
        "n_accepted": int(state[N_ACCEPTED]),
        "n_rejected": int(state[N_REJECTED]),
        "n_steps": int(state[N_ACCEPTED] + state[N_REJECTED]),
        "wall_time": _time.perf_counter() - begin,
        "compile_time": compile_time,
        "compiled": compiled,
        "impacts": int(state[IMPACTS]),
        "n_jacobians": int(getattr(step, "n_jacobians", 0)),  # a step kind with a Jacobian counts them
    }
    history = case2.laws[model.layout.numbers["history"]:].copy()
    message = "" if status == SUCCESS else _failure(model.with_history(history), work, status, collapse, solver,
                                                    method.name)
    end = RunState(float(state[T]), work.y.copy(), history, observe_data.previous.copy(),
                   ControllerState(float(state[H]), float(state[ERR_PREV]), bool(state[REJECTED_LAST] > 0.0)),
                   work.f.copy())
    return AdvanceResult(end, grid[:n_written].copy(), work.out[:n_written], stats, message)


def _drive(run_chunk, work, step, settings, data, t0, t1, grid, chunks, max_steps, progress):
    """Call the compiled loop until ``t1`` or a stop, pausing at ``chunks`` evenly spaced times (where there is a
    ``progress`` to call) and about every :data:`CALL_SECONDS` (Ctrl-C, ``progress``), and stop a run whose step
    has collapsed. Returns the status and, for a collapse, ``(recent mean step, attempts in the window, mean step, attempts needed)``."""
    state = work.state
    status, collapse = SUCCESS, None
    # the evenly spaced stops serve the progress callback only: without one the loop pauses on its budget alone
    # (each call's dispatch costs ~30 µs; a study's realization made 100 of them, 4 % of its solve)
    stops = np.linspace(t0, t1, max(int(chunks), 1) + 1)[1:] if progress is not None else np.array([t1])
    stops[-1] = t1
    output_step = float(grid[1] - grid[0]) if len(grid) > 1 else t1 - t0
    # step attempts per call; (attempts, t) at the start of the window of the collapse check
    budget, window = float(FIRST_CALL_ATTEMPTS), (0.0, t0)
    for t_stop in stops:
        while True:
            attempts = state[N_ACCEPTED] + state[N_REJECTED]
            state[PAUSE_AT] = attempts + budget
            called = _time.perf_counter()
            status = run_chunk(work, float(t_stop), step, settings, data.rhs, data.case2, data.observe)
            elapsed = _time.perf_counter() - called  # Ctrl-C is raised here, between calls
            if progress is not None:
                progress(float(state[T]))
            if status == PAUSED:
                budget = min(max(budget * CALL_SECONDS / max(elapsed, 1e-6), 10.0), 1e7)
            attempts = state[N_ACCEPTED] + state[N_REJECTED]
            if status in (PAUSED, SUCCESS) and state[T] < t1 and attempts - window[0] >= COLLAPSE_WINDOW:
                recent = (state[T] - window[1]) / (attempts - window[0])  # mean step of the window [s]
                average = (state[T] - t0) / attempts  # mean step of the whole call [s]
                # the attempts reaching t1 would take: at the recent mean step when it is below the floor,
                # else at the larger of the recent and the whole call's (both must say it cannot finish)
                rate = recent if recent < COLLAPSE_RATIO * output_step else max(recent, average)
                needed = attempts + (t1 - state[T]) / max(rate, 1e-300)
                if needed > max_steps:
                    return COLLAPSED, (recent, attempts - window[0], average, needed, t0)
                window = (attempts, float(state[T]))
            if status != PAUSED:
                break
        if status != SUCCESS:
            break
    return status, collapse


def _failure(model, work, status, collapse, solver, method_name) -> str:
    """The message of a run stopped by ``status``: where, why, and the likely stiff term."""
    state = work.state
    t, h = state[T], state[H]
    if status == COLLAPSED:
        recent, window, average, needed, t0 = collapse
        cause = (f"step size collapsed: mean step {recent:.3g} s over the last {window:,.0f} "
                 f"attempts ({average:.3g} s since t = {t0:g}); reaching t_end would take about {needed:.3g} "
                 f"attempts, more than max_steps = {solver.max_steps:,}")
    else:
        cause = {
            MIN_STEP: f"step size fell below min_step = {solver.min_step:.3g} s",
            MAX_STEPS: f"maximum number of steps ({solver.max_steps}) exceeded",
            NON_FINITE: "non-finite state after an accepted step",
        }[status]
    last = CAUSES.get(int(state[LAST_CAUSE]), "")
    if last and status != NON_FINITE:
        cause += f"; last rejection: {last}"
    if status != NON_FINITE:
        cause += "; " + stiffness_diagnosis(model, t, work.y, method_name)
    return f"integration failed at t = {t:.10g} s (h = {h:.3g} s): {cause}"
