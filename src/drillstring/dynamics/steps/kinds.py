"""The step kinds: what a step of the compiled loop must provide, and the registry that picks one by type.

The compiled loop (:func:`drillstring.dynamics.compiled._run_chunk`) owns the step-size controller,
acceptance, the pauses that let Ctrl-C through, the collapse check, the observations and the delayed-history
recording; a *step kind* owns one step attempt — its stages, its local error estimate and its dense output.
A kind is one module that registers one :class:`StepKind` (:func:`register`):

- ``method``: the Python type of the method's description a user passes (for an explicit Runge–Kutta pair
  :class:`~drillstring.dynamics.runge_kutta.ButcherTableau`; it has a ``name``);
- ``data``: a :class:`~typing.NamedTuple` class, the compiled loop's view of the method and of the step's
  buffers, built by ``allocate(method, n)`` for a state of ``n`` components. The loop reads three of its
  fields by name: ``order`` (float: the order ``q`` of the error estimate, for the controller's exponents
  ``1/(q + 1)``), ``dense`` ((m, p): dense-output coefficients) and ``dense_stages`` ((m, n): the accepted
  step's vectors), such that ``y(t_old + θh) = y_old + h Σ_i Σ_p dense[i, p] θ^(p+1) dense_stages[i]`` —
  the form :func:`~drillstring.dynamics.rom.accepted_step_kernel` records the bit's history from;
- ``attempt(data, rhs_data, t, h, y, f, y_new, err) -> (evaluations, finite)``: compiled; from the state
  ``y`` at ``t`` with ``f = dy/dt`` there, the candidate ``y_new`` at ``t + h`` and its local error estimate
  ``err`` (absolute, not scaled); the right-hand-side evaluations it made and whether every one was finite
  (when not, ``y_new`` and ``err`` are not used and the loop rejects the step);
- ``accept(data, y, f) -> known``: compiled, called once the loop has accepted the attempt and moved ``y``
  to the new state: keep the step's dense output in ``data.dense_stages``; when the step knows ``dy/dt`` at
  the new state (FSAL: its last stage), write it into ``f`` and return True, else return False and the loop
  evaluates it. (No right-hand-side data here: each compiled call passes the model's large structured data
  anew, which costs run time, see :func:`_implementation`);
- optionally ``prepare(data, rhs_data, t, y) -> data``: Python, called once per run with the model's
  right-hand-side data and the run's start (:func:`step_data`; ``t``, ``y`` may be None): what the step reads of
  the model besides the right-hand side (the exponential step's diagonalised linear part,
  :mod:`drillstring.dynamics.steps.exponential`), in arrays of fixed types;
- optionally ``allocates = False``: ``attempt`` and ``accept`` create no array (no NumPy allocation, no
  array returned), so the loop is compiled without Numba's reference counting (``_nrt=False``), which the
  right-hand side, the observation and the accepted-step kernels it calls then skip as well: on the
  reference case that halves the solve (docs/performance.md, "The solve at the physical limit");
- optionally ``reference(method, y)``: the NumPy reference of the same step for a right-hand side in Python,
  used by :class:`~drillstring.dynamics.runge_kutta.RungeKuttaStepper` (the reference integrator's own loop):
  an object with ``order``, ``dense``, ``dense_stages`` as above, ``attempt(rhs, t, h, y, f) -> (y_new, err,
  evaluations, cause)`` and ``accept(rhs, t_new, y_new) -> (f, evaluations)``.

The right-hand side is :func:`~drillstring.dynamics.rom.evaluate_rhs` of ``rhs_data`` (an implicit or
Rosenbrock kind reads its Jacobian from the model's data the same way). The loop is compiled once per kind,
with the kind's ``attempt`` and ``accept`` in place of :func:`attempt` and :func:`accept` and inlined into it
at Numba's IR level (:func:`drillstring.dynamics.compiled._loop`), so the loop never names a kind and compiles
only the one it runs. The two functions are Numba-compilable Python functions (or ``njit`` dispatchers, whose
Python function is used), their parameters named as those of :func:`attempt` and :func:`accept`. A kind
defined outside the package is not covered by the kernel cache's source hash (:mod:`drillstring.kernel_cache`), so the loop runs it compiled without the disk cache
(``cacheable = False``, the default for a module outside ``drillstring``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

__all__ = ["StepKind", "register", "kind_of", "kind_of_data", "step_data", "attempt", "accept"]


@dataclass(frozen=True)
class StepKind:
    """One kind of step (module docstring): the method's Python type, the compiled data's NamedTuple class,
    the function that builds that data, and the two compiled functions of the step."""

    method: type
    data: type
    allocate: Callable[[Any, int], Any]
    attempt: Callable  # Numba-compilable, its parameters named as those of `attempt` below
    accept: Callable  # Numba-compilable, its parameters named as those of `accept` below
    reference: Callable[[Any, Any], Any] | None = None
    prepare: Callable[..., Any] | None = None  # (data, rhs_data, t, y) -> data: what the step reads of the model
    cacheable: bool = field(default=None)  # type: ignore[assignment]
    allocates: bool = True  # False: attempt and accept create no array, the loop runs without reference counting

    def __post_init__(self) -> None:
        if not (isinstance(self.data, type) and issubclass(self.data, tuple) and hasattr(self.data, "_fields")):
            raise TypeError(f"StepKind.data must be a NamedTuple class, got {self.data!r}")
        missing = {"order", "dense", "dense_stages"} - set(self.data._fields)
        if missing:
            raise TypeError(f"StepKind.data {self.data.__name__} lacks the fields {sorted(missing)} the loop reads")
        if self.cacheable is None:
            inside = (self.data.__module__ or "").split(".")[0] == "drillstring"
            object.__setattr__(self, "cacheable", inside)


_BY_METHOD: dict[type, StepKind] = {}
_BY_DATA: dict[type, StepKind] = {}


def register(kind: StepKind) -> StepKind:
    """Make ``kind`` the step of every method of type ``kind.method`` (and of its subclasses)."""
    _BY_METHOD[kind.method] = kind
    _BY_DATA[kind.data] = kind
    return kind


def kind_of(method: Any) -> StepKind:
    """The registered kind for ``method`` (by its type, or the nearest registered base class)."""
    for cls in type(method).__mro__:
        if cls in _BY_METHOD:
            return _BY_METHOD[cls]
    known = ", ".join(sorted(cls.__name__ for cls in _BY_METHOD))
    raise TypeError(f"method {method!r}: no step kind is registered for {type(method).__name__} (known: {known})")


def step_data(method: Any, n: int, rhs_data: Any = None, t: float | None = None, y: Any = None) -> Any:
    """The compiled loop's data for ``method`` and a state of ``n`` components; with the model's right-hand-side
    data ``rhs_data`` (and the run's start ``t``, ``y``), what a kind with ``prepare`` reads of the model once
    per run (an exponential step's diagonalised linear part) is set as well."""
    kind = kind_of(method)
    data = kind.allocate(method, n)
    if kind.prepare is not None and rhs_data is not None:
        data = kind.prepare(data, rhs_data, t, y)
    return data


def attempt(data, rhs_data, t, h, y, f, y_new, err):
    """One step attempt of the kind of ``data`` (module docstring): the contract of a kind's ``attempt``. The
    compiled loop calls the kind's own function in its place (:func:`drillstring.dynamics.compiled._loop`)."""
    raise NotImplementedError("compiled code only: the loop is compiled with the kind's own attempt")


def accept(data, y, f):
    """What the kind of ``data`` keeps of an accepted step (module docstring): the contract of a kind's
    ``accept``, called in its place as :func:`attempt` is."""
    raise NotImplementedError("compiled code only: the loop is compiled with the kind's own accept")


def kind_of_data(data: Any) -> StepKind:
    """The registered kind whose compiled data ``data`` is."""
    try:
        return _BY_DATA[type(data)]
    except KeyError:
        raise TypeError(f"{type(data).__name__} is the data of no registered step kind") from None
