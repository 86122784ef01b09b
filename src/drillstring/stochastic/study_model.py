"""The reduced model of each realization of a study, built once per study and worker process (issue 35).

Rebuilding the model of every realization (:func:`~drillstring.dynamics.reduced.build.case_reduced_model`:
statics, the linear system, every family's modes and the free–free damping's dense eigenproblems) costs about a
sixth of the realization on the reference study. When the study's random parameters enter the model in a known
way, :class:`~drillstring.dynamics.reduced.parametric.ParametricReducedModel` is built once (per study and per
worker process, :func:`parametric_model`) and gives each realization's model in a few milliseconds:

- **prestress** (:data:`PRESTRESS_PATHS`): the weight-on-hook or the weight-on-bit, which move the static axial
  force and the geometric stiffness affinely; the model is built over the range of weights-on-bit that the
  study's law gives with probability ``1 − 2·`` :data:`RANGE_TAIL` (about ±6 σ for a Normal law); a draw outside it
  is rebuilt;
- **the mud's inlet velocity** (:data:`FLOW_PATH`), which moves the fluid damping affinely and the fluid
  stiffness with its square, on the bending DOFs only; built over the range its law gives with the same
  probability;
- **the top speed** (:data:`SPEED_PATH`), which the linear system does not depend on: it scales the damping's
  generalised force at an imposed speed and sets the top boundary and the turning loads, taken from the
  realized case;
- **force laws** (:data:`FORCE_PREFIXES`): the parameters of the bit–rock law, the contact law, the start
  (``initial``) and the integrator (``simulation``), which the model takes from the realized case as the
  rebuild does.

Any other random parameter (the geometry, the materials, the mud's density, the damping, the mesh, ...)
changes the linear system in ways the parametric form does not cover: such a study rebuilds every realization
(:func:`coverage` says why; the study notes it once). The nominal run is always rebuilt (the deterministic run
at the means, as ``drillstring simulate`` would build it). Sensitivity designs (Saltelli rows) use the same
models (:mod:`drillstring.stochastic.sensitivity_study`).

The model equals the rebuilt one to round-off in its axial and torsional parts and to the Ritz error of the
lateral modes (below :data:`~drillstring.dynamics.reduced.parametric.RITZ_TOLERANCE`, checked when built): a
realization's time histories differ from the rebuilt model's at that level, far below the digits a study prints
(tests/stochastic/test_study_model.py, benchmarks/bench_study_parametric.py). The study store's fingerprint
(case and settings) does not name the recipe: a study resumed across the change mixes realizations that agree
to that level.

Setting the environment variable :data:`REBUILD_VARIABLE` to ``1`` (read when a realization runs, inherited by
the worker processes) rebuilds every realization as before: for comparisons and benchmarks.
"""

from __future__ import annotations

import os
import weakref
from functools import partial

from drillstring.case import Case
from drillstring.dynamics.reduced.build import case_reduced_model
from drillstring.dynamics.reduced.model import ReducedOrderModel
from drillstring.dynamics.reduced.parametric import NotCovered, ParametricReducedModel
from drillstring.stochastic.parameters import WEIGHT_ON_HOOK
from drillstring.stochastic.runs import compile_kernels
from drillstring.stochastic.uncertainty import Uncertainty

#: The random parameters that enter the model through the prestress (the static axial force).
PRESTRESS_PATHS = (WEIGHT_ON_HOOK, "operation.weight_on_bit")
#: The random parameter that enters the model through the fluid matrices.
FLOW_PATH = "fluid.inlet_velocity"
#: The random parameter that enters the model through its generalised force, top boundary and turning loads.
SPEED_PATH = "operation.top_speed"
#: The tables whose parameters enter the model only through laws built from the realized case.
FORCE_PREFIXES = ("bit_rock.", "contact.", "initial.", "simulation.")
#: Probability of each tail of the weight-on-bit's law left outside the parametric model's range.
RANGE_TAIL = 1e-9
#: Environment variable: ``1`` rebuilds every realization's model (the recipe before the parametric model).
REBUILD_VARIABLE = "DRILLSTRING_STUDY_REBUILD"

#: The TOML text of the cases seen in this process, by object (a Case is frozen): the studies' cache keys
#: (:func:`case_text`).
_CASE_TEXTS: dict[int, tuple[weakref.ref, str]] = {}

#: Built parametric models (or the reason there is none) by study, in this process.
_MODELS: dict[tuple, ParametricReducedModel | str] = {}


def case_text(case: Case) -> str:
    """``case.to_toml()``, written once per case object in this process (0.5 ms each; a realization needs it
    three times as the key of its study's caches)."""
    found = _CASE_TEXTS.get(id(case))
    if found is not None and found[0]() is case:
        return found[1]
    text = case.to_toml()
    if len(_CASE_TEXTS) > 64:
        _CASE_TEXTS.clear()
    _CASE_TEXTS[id(case)] = (weakref.ref(case), text)
    return text


def coverage(case: Case, law: Uncertainty) -> str | None:
    """None when every random parameter of ``law`` is covered by the parametric model (module docstring), else
    why not (one sentence, naming the first parameter that is not)."""
    for path in law.paths:
        if path in PRESTRESS_PATHS or path in (FLOW_PATH, SPEED_PATH) or path.startswith(FORCE_PREFIXES):
            continue
        return (f"{path} changes the linear system beyond the prestress: every realization's reduced model is "
                "rebuilt (slower)")
    return None


def weight_on_bit_range(case: Case, law: Uncertainty) -> tuple[float, float]:
    """The weights-on-bit [N] the study's law gives with probability ``1 − 2 RANGE_TAIL``, within
    ``[0, case.weight]``, and holding the case's own; the case's weight-on-bit ± 1 N when it is not random."""
    w0 = float(case.operation.weight_on_bit)
    low, high = w0, w0
    for path, parameter in zip(law.paths, law.parameters):
        if path not in PRESTRESS_PATHS:
            continue
        density = parameter.law.density
        ends = (float(density.ppf(RANGE_TAIL)), float(density.ppf(1.0 - RANGE_TAIL)))
        if path == WEIGHT_ON_HOOK:
            ends = (case.weight - ends[1], case.weight - ends[0])
        low, high = min(low, ends[0]), max(high, ends[1])
    low, high = max(low, 0.0), min(high, case.weight)
    if not low < high:
        low, high = max(w0 - 1.0, 0.0), w0 + 1.0
    return low, high


def inlet_velocity_range(case: Case, law: Uncertainty) -> tuple[float, float] | None:
    """The inlet velocities [m/s] the study's law gives with probability ``1 − 2 RANGE_TAIL`` (at least 0), holding
    the case's own; None when the inlet velocity is not random."""
    if FLOW_PATH not in law.paths:
        return None
    density = law.parameters[law.paths.index(FLOW_PATH)].law.density
    u0 = float(case.fluid.inlet_velocity)
    low = max(min(float(density.ppf(RANGE_TAIL)), u0), 0.0)
    high = max(float(density.ppf(1.0 - RANGE_TAIL)), u0)
    return (low, high) if low < high else None


def parametric_model(case: Case, key, law: Uncertainty) -> ParametricReducedModel | str:
    """The study's parametric model, built once per ``key`` (the study: case and settings) in this process, or
    the reason there is none (:func:`coverage`, or the parametric form's own refusal)."""
    if key in _MODELS:
        return _MODELS[key]
    reason = coverage(case, law)
    if reason is None:
        try:
            found: ParametricReducedModel | str = ParametricReducedModel(
                case, *weight_on_bit_range(case, law), flow=inlet_velocity_range(case, law),
                speed=SPEED_PATH in law.paths)
        except NotCovered as error:
            found = f"{error}: every realization's reduced model is rebuilt (slower)"
    else:
        found = reason
    install_model(key, found)
    return found


def worker_setup(key):
    """The setup that installs this process's parametric model of the study ``key`` in a worker process
    (:func:`~drillstring.stochastic.execution.run_locked`'s ``prepare``), or None when none was built here."""
    found = _MODELS.get(key)
    return partial(install_model, key, found) if isinstance(found, ParametricReducedModel) else None


def install_model(key, model: ParametricReducedModel | str) -> None:
    """Keep ``model`` (built here or in the driver; or the reason there is none) as this process's parametric
    model of the study ``key``."""
    if len(_MODELS) > 4:
        _MODELS.clear()
    _MODELS[key] = model


def realization_model(case: Case, key, law: Uncertainty, realized: Case, *, nominal: bool = False
                      ) -> ReducedOrderModel:
    """The reduced model of the realized case ``realized`` of the study ``key`` on ``case``: from the study's
    parametric model when it covers the draw, else rebuilt (:func:`case_reduced_model`), as always for the
    nominal run and when :data:`REBUILD_VARIABLE` is set."""
    if nominal or os.environ.get(REBUILD_VARIABLE) == "1":
        return case_reduced_model(realized)
    found = parametric_model(case, key, law)
    if isinstance(found, str):
        return case_reduced_model(realized)
    try:
        return found.model(realized)
    except NotCovered:  # a draw outside the built range (probability about 2e-9 per draw)
        return case_reduced_model(realized)


def note_model(case: Case, key, law: Uncertainty, note) -> None:
    """Tell ``note`` (when given) why every realization of the study ``key`` is rebuilt, if it is
    (:func:`study_model_note`)."""
    model_note = study_model_note(case, key, law)
    if model_note is not None and note is not None:
        note(model_note)


def prepare_runs(case: Case, key, law: Uncertainty, note):
    """Before a study's or a sensitivity design's local runs (while the worker processes start,
    :func:`~drillstring.stochastic.execution.run_locked`'s ``prepare``): its parametric model built here (its
    note), the kernels compiled, and the setup that hands the model to each worker (:func:`worker_setup`: 6 MB
    pickled once per worker instead of a 0.45 s build in each)."""
    note_model(case, key, law, note)
    compile_kernels(case, note=note)
    return worker_setup(key)


def study_model_note(case: Case, key, law: Uncertainty) -> str | None:
    """The study's note on its models: None when the parametric model covers it, else why every realization is
    rebuilt (built here, in the calling process, and kept for its realizations)."""
    if os.environ.get(REBUILD_VARIABLE) == "1":
        return None
    found = parametric_model(case, key, law)
    return found if isinstance(found, str) else None
