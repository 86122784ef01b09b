"""An ensemble Kalman filter on the reduced model: from the surface channels of a record
(:class:`~drillstring.estimation.surface.SurfaceRecord`) to the downhole state with its bands (issue 36).

**Filter.** One analysis per assimilation window (:mod:`drillstring.estimation.analysis`): the ensemble transform
Kalman filter (ETKF, :func:`~drillstring.estimation.analysis.etkf_analysis`; Hunt, Kostelich & Szunyogh 2007), a
deterministic square-root filter that for a linear observation gives the Kalman filter's update of the forecast's
sample mean and covariance; or, with ``particle_share`` > 0, the ensemble Kalman particle filter (EnKPF,
:func:`~drillstring.estimation.analysis.enkpf_analysis`; Frei & Künsch 2013), that share of the likelihood given
to a particle filter's weights and resampling: it can choose between the members that stick and those that slip
where the ETKF moves both as one Gaussian (a resampled member takes over its parent's model and recent outputs).
The observations are few (at most three scalars a time), so either costs little beside the forecasts.

**State.** The augmented state of a member is ``[y, log c, log μ, log κ, b, z0]``: ``y`` the reduced model's state
(:attr:`~drillstring.dynamics.rom.ReducedOrderModel.state_size`: modal coordinates, their rates, the top drive's
controller states), ``log c`` the logarithm of one bit–rock coefficient of the case's law
(``bit_rock_coefficient``, e.g. ``a5``, the frictional torque of the Tucker–Wang law; the logarithm keeps it
positive; left out for ``"none"``), ``log μ`` that of the along-string friction factor of one wall of a deviated
well (``friction_factor``: the open or the cased hole's; left out for ``"none"``, the default), ``log κ`` that
of a factor on the torsional stiffness (``stiffness_factor = "torsional"``; left out for ``"none"``, the
default; :func:`member_model`), ``b`` the
weight-on-bit bias [N] and ``z0`` the block position of the static state [m] (the record's zero is the
driller's). The parameters follow a random walk (``coefficient_walk``, ``friction_walk``, ``stiffness_walk``,
``weight_on_bit_bias_walk``, per √s) between observations: they may drift, and the walk keeps the ensemble from
collapsing on them.

**Forecast.** Each member runs its own copy of the model (the shared model with the law's numbers, the
weight-on-bit, μ at the stations on its wall and κ replaced in its kernel data: :func:`member_model`, a few
microseconds, where building a model takes 0.1-0.2 s) by :func:`~drillstring.dynamics.compiled.advance` from
the analysis to the next record time.
The weight-on-bit of a member over an interval is ``W = W_case + (H_static − H̄) + b``: the case's, plus the hook
load's drop below the static hook load (``H̄`` the mean of the usable hook-load samples over the last
``hook_load_window`` seconds, the hook load an input, not an observation), plus the member's bias ``b``, the
offset of the hook-load sensor (a hook load read ``b`` too high leaves ``b`` more on the bit than it says).

**Observations.** ``top_speed`` ↔ the ``quill_speed`` observable, ``surface_torque`` ↔ ``surface_torque`` (both
from the member's :class:`~drillstring.dynamics.compiled.AdvanceResult` at the record time), ``block_position`` ↔
``z0 − u_top`` (the top's axial displacement ``u_top = φ_top·η``, down positive). A sample is used only where
``record.usable(channel)``.

**Assimilation windows.** The record's time is cut into windows of ``assimilation_step`` seconds,
``(t₀ + (j−1)Δ, t₀ + jΔ]`` (the first sample alone in window 0); the members are forecast from sample to sample
(the results hold every sample) and one analysis is made at each window's last sample, of the mean of each
channel's usable samples in the window against the mean of each member's predictions at those samples (a linear
observation of the trajectory over the window, as in the four-dimensional ensemble filter of Hunt et al. 2004,
Tellus A 56, 273-277, whose analysis updates the state at the window's end through the ensemble's correlations).
The noise of that mean is the channel's setting, not divided by √(samples): the settings are the error of an
assimilated value, dominated by the model's error (another model, its basis truncated), which is correlated over
a window and does not average out. A 1 Hz record with the default step (1 s) is analysed at each sample, as
before; a 10 Hz one once per second: analysing each of its samples as independent over-fitted the model's error
(docs/estimation.md, "The shipped record": parameter bands collapsed, coverage 0.45-0.66).

**Spin-up.** A record starts in operation, not at the model's initial state: before the first sample the
members run ``spin_up`` seconds from the initial state (in steps of at most :data:`SPIN_UP_STEP`, each
preceded by the model error's kick, without the parameters' walk), which puts them on the model's own
stick-slip cycle with phases spread by their parameters and the model error; each member's ``z0`` is then
shifted by its ``u_top`` so that its predicted block position at the first sample is the first sample's
(± the prior's noise). ``spin_up = 0`` starts from the initial state (a record that starts where its run does,
as the twin experiments' do). Without it the shipped record's 10 Hz run started from a string with no twist
against a surface torque of 18 kN·m, and the first analyses put that on the weight-on-bit bias (−96 kN).

**Model error, inflation, localisation.** The estimator's basis is truncated (no lateral modes, few torsional
ones) and the truth is another model: before each forecast the torsional modal velocities of every member are
kicked by white noise scaled to ``model_speed_noise`` rad/s of bit speed per √s (additive model error; larger
kicks bias the estimated coefficient; 1.5 with the default 256 members, docs/estimation.md "The defaults").
Multiplicative prior inflation of the anomalies (``inflation``) is available, default 1: with the additive noise
it only widened the parameters' spread, and at 1.15 drove them off on the stick-slip twin. Relaxation to the
prior spread (``relaxation`` for the model state's rows, ``parameter_relaxation`` for the parameters'; default 0,
off: :func:`~drillstring.estimation.analysis.relax_to_prior_spread`) after each analysis gives back part of the
spread the analysis removed
(docs/estimation.md, "Coverage and relaxation"). No localisation: the
state is a few modal coordinates, each global along the string, and the default ensemble (256) exceeds the
augmented state's dimension (about 25).

**Model uncertainty.** With ``model_dispersion`` > 0 each member runs its own reduced model, its mass, stiffness
and damping matrices drawn once from the random-matrix model of that dispersion (:func:`member_models`; the
twin's and the shipped record's truths are such realizations) and kept for the whole record: the model's error
as an unknown, fixed operator, not only the kicks. A member's state is in its own model's coordinates ``q``; the
analysis (and the kicks, the block position) works on ``ξ = X q``, the estimator's model's coordinates of the
same displacement, so that the members are compared on one footing. Default 0: one shared model.

**Failures.** A member whose forecast fails (the integrator stops, a non-finite value, a bit speed beyond
``divergence_speed_ratio`` times the top speed) is replaced by a copy of a member drawn from those that
succeeded (its state, parameters, outputs, recent bit speed and model); the count per time is returned
(:attr:`~drillstring.estimation.results.EstimationResult.replaced`). The run stops (:class:`EstimateDiverged`)
when every member fails at one time, or when an analysis leaves a parameter non-finite or spreads a coefficient's
90 % band over more than its clip range (a factor exp(2 LOG_RANGE)); interrupted (KeyboardInterrupt), it stops
too. Either way it returns what it computed before the stop, the reason in
:attr:`~drillstring.estimation.results.EstimationResult.stopped` (a stop at the first sample raises).

**Stick-slip index.** ``(max − min)/(2 mean)`` of each member's bit speed over the last ``stick_slip_window``
seconds (the definition of :func:`drillstring.dynamics.indicators.cycle_metrics`), sampled every
``output_step`` along the forecasts (the analysis replacing the forecast at each record time); NaN for a member
whose mean is not positive.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import math
import time as _time
from collections.abc import Callable

import numpy as np

from drillstring.dynamics.compiled import RunState, SolverSettings, advance
from drillstring.dynamics.kernel_data import TORSION_ROW
from drillstring.dynamics.reduced.build import case_reduced_model, in_casing
from drillstring.dynamics.reduced.observation import OBSERVABLE_COLUMN
from drillstring.estimation.analysis import enkpf_analysis, etkf_analysis, relax_to_prior_spread
from drillstring.estimation.results import DOWNHOLE, QUANTILES, EstimationResult
from drillstring.estimation.settings import (  # noqa: F401  (the settings are read from here too)
    FRICTION_WALLS,
    STIFFNESS_FAMILIES,
    EstimatorSettings,
    case_estimator_settings,
)
from drillstring.estimation.surface import SurfaceRecord
from drillstring.stochastic.random_matrices import (
    ModelDispersion,
    model_generator,
    random_reduced_model_with_transform,
)

#: The channels the filter reads as observations (the hook load is an input).
OBSERVED = ("top_speed", "surface_torque", "block_position")
_QUILL = OBSERVABLE_COLUMN["quill_speed"]
_SURFACE_TORQUE = OBSERVABLE_COLUMN["surface_torque"]
_BIT_SPEED = OBSERVABLE_COLUMN["bit_speed"]
#: The estimated coefficient stays within exp(±LOG_RANGE) of the case's (an analysis can throw a member's far out).
LOG_RANGE = 5.0
#: The spin-up's longest step between the model error's kicks [s].
SPIN_UP_STEP = 1.0
#: Units of the Tucker–Wang coefficients (pint spelling), for the results.
COEFFICIENT_UNITS = {"a1": "m/s", "a2": "m/(N*s)", "a3": "m/rad", "a4": "N*rad", "a5": "N*m"}


class EstimateDiverged(RuntimeError):
    """The ensemble no longer describes the record (every forecast failed, or a parameter's spread blew up):
    :func:`estimate` stops there and returns what it computed before (:attr:`EstimationResult.stopped`)."""


def estimator_model(case, settings: EstimatorSettings = EstimatorSettings()):
    """The estimator's reduced model of ``case``: the case's, on the basis of ``settings`` (``axial_modes``,
    ``torsional_modes``, no lateral mode), case 2 (bit and contact nonlinear)."""
    return case_reduced_model(case, axial_modes=settings.axial_modes, torsional_modes=settings.torsional_modes,
                              lateral_modes=0, nonlinear="bit_and_contact")


def kick_scale(bit_speed: float | None, stick_speed: float) -> float:
    """The factor of a member's model-error kick: ``min(1, |bit_speed| / stick_speed)`` [-], the member's bit
    speed [rad/s] at the end of its last forecast against ``model_noise_stick_speed`` [rad/s]; 1 where that is 0
    (off) or the bit speed is unknown (before the first forecast) or not finite."""
    if stick_speed <= 0.0 or bit_speed is None or not math.isfinite(bit_speed):
        return 1.0
    return min(1.0, abs(bit_speed) / stick_speed)


def model_noise_columns(model, settings: EstimatorSettings) -> tuple[slice, float]:
    """Where and how hard the model error kicks (module docstring): the slice of the velocity's torsional columns
    kicked (the lowest ``model_noise_modes`` of ``model``'s torsional block) and the standard deviation of each
    column's kick per √s of the interval, such that the bit speed's is ``model_speed_noise`` [rad/s/√s]."""
    first = int(model.blocks[2])
    last = min(int(model.blocks[3]), first + settings.model_noise_modes)
    bit_shape = np.asarray(model.bit_t[first:last], dtype=float)
    return slice(first, last), settings.model_speed_noise / max(float(np.linalg.norm(bit_shape)), 1e-300)


def member_model(model, laws: np.ndarray, weight_on_bit: float, friction: np.ndarray | None = None,
                 torsional_stiffness: float | None = None):
    """A shallow copy of ``model`` (a case-2 :class:`~drillstring.dynamics.rom.ReducedOrderModel`) whose
    kernels read the numbers ``laws`` (the packed array of :func:`~drillstring.forces.registry.pack`, same
    layout), the weight-on-bit ``weight_on_bit`` [N], if given, the along-string friction factors
    ``friction`` [-] (one per station of ``model.friction_stations``, same order) and, if given, the torsional
    stiffness times ``torsional_stiffness`` = κ [-]; ``model`` is not changed. The components' objects
    (``model.bit_rock``, ``model.friction_stations``) stay the nominal ones: only what the compiled kernels read
    changes (the stations' static normal forces do not depend on μ: the stiff string's statics is frictionless,
    :mod:`drillstring.well.stiff_string`).

    κ K in place of the torsional family's stiffness K leaves its mass-normalised modes as they are and
    multiplies their ω² by κ, the stiffness reaction at the top (the surface torque of an imposed top speed,
    ``K[top] φ``) by κ and, the damping ratios held (the structural damping ``2 ξ M (M⁻¹K)^{1/2}``,
    :mod:`drillstring.damping`), the elastic modes' damping block by √κ; the rigid rotation's damping, the mass
    and the forces do not change. That is the model of the case with the shear modulus κ G (tested: the same
    run to 1e-5 of its range, measured 2e-6)."""
    other = copy.copy(model)
    data = model.case2_data._replace(laws=laws, weight_on_bit=float(weight_on_bit))
    if friction is not None:
        data = data._replace(friction=data.friction._replace(friction=np.ascontiguousarray(friction, dtype=float)))
    if torsional_stiffness is not None:
        first, last = int(model.blocks[2]), int(model.blocks[3])
        omega2 = data.omega2.copy()
        omega2[first:last] *= torsional_stiffness
        rows = data.torsion_rows.copy()
        rows[TORSION_ROW["surface_torque"]] *= torsional_stiffness
        elastic = np.arange(first, last)
        elastic = elastic[elastic != model.rigid_rotation_column]
        damping_t = data.damping_t.copy()
        damping_t[np.ix_(elastic, elastic)] *= math.sqrt(torsional_stiffness)
        data = data._replace(omega2=omega2, torsion_rows=rows, damping_t=damping_t)
    other.case2_data = data
    other.rhs_data = other.case2_data
    return other


def member_models(model, dispersion: float, seed: int, n_members: int) -> tuple[list, list]:
    """Each member's reduced model and its coordinates (model uncertainty as an unknown, fixed operator):
    member ``i``'s mass, stiffness and damping matrices drawn once, with the dispersion ``dispersion`` [-] for
    all three, from the random-matrix model (Soize's SE+ ensemble,
    :func:`~drillstring.stochastic.random_matrices.random_reduced_model_with_transform`) on the stream
    :func:`~drillstring.stochastic.random_matrices.model_generator` ``(seed, i)``, apart from the filter's
    own (the initial ensemble, the walks and the kicks are the same draws whatever the dispersion). Returns
    the models and, per member, ``(X, X⁻¹)`` with ``ξ = X q`` the estimator's model's coordinates of the
    member's ``q`` (the same displacement ``Φ ξ = Φ X q``: the analysis compares the members there). With
    ``dispersion = 0`` every member is ``model`` itself, transform None. ValueError naming
    ``estimator.model_dispersion`` at or above a family's bound ``sqrt((n+1)/(n+5))``."""
    if dispersion == 0.0:
        return [model] * n_members, [None] * n_members
    spread = ModelDispersion(dispersion, dispersion, dispersion)
    spread.check_model(model, "estimator.model_dispersion")
    models, transforms = [], []
    for i in range(n_members):
        drawn, x = random_reduced_model_with_transform(model, spread, model_generator(seed, i))
        models.append(drawn)
        transforms.append((x, np.linalg.inv(x)))
    return models, transforms


def coefficient_slot(model, name: str) -> int:
    """The index in the model's packed law array of the bit–rock coefficient ``name`` (found by changing it
    alone and re-packing the law: :meth:`kernel_array`); ValueError for a name the law does not have or does
    not pass to its kernel as itself."""
    law = model.bit_rock
    fields = [f.name for f in dataclasses.fields(law)]
    if name not in fields:
        raise ValueError(f"bit_rock_coefficient = {name!r}: the case's bit-rock law {law.name!r} has "
                         f"{', '.join(fields)}")
    value = getattr(law, name)
    base = np.asarray(law.kernel_array(), dtype=float)
    changed = np.asarray(dataclasses.replace(law, **{name: value * 1.5 + 1.0}).kernel_array(), dtype=float)
    moved = np.flatnonzero(base != changed)
    if len(moved) != 1 or not math.isclose(changed[moved[0]], value * 1.5 + 1.0) or not value > 0.0:
        raise ValueError(f"bit_rock_coefficient = {name!r}: not a positive coefficient that the law "
                         f"{law.name!r} passes to its kernel unchanged")
    return model.layout.numbers["bit_law"] + int(moved[0])


def friction_stations_of(case, model, wall: str) -> tuple[np.ndarray, float]:
    """The stations of ``model.friction_stations`` on the wall ``wall`` (``"open"`` or ``"cased"``, as
    ``friction_factor``) as a boolean mask, and the case's friction factor there [-]. ValueError naming
    ``friction_factor`` for a case without along-string friction on that wall."""
    key = FRICTION_WALLS[wall]
    stations = model.friction_stations
    if getattr(case, "well", None) is None or model.active_friction is None or stations is None or not len(stations):
        raise ValueError(f"friction_factor = {wall!r}: the case has no along-string friction (it needs a [well] "
                         "and a [string_friction] law other than 'none', with the string resting on the wall)")
    cased = in_casing(case, model.static.mesh, stations.node)
    mask = cased if wall == "cased" else ~cased
    value = float(getattr(case.well, key))
    if not np.any(mask) or not value > 0.0:
        raise ValueError(f"friction_factor = {wall!r}: no station of the string rests on the {wall} hole's wall, or "
                         f"well.{key} = {value!r} is not > 0 (its logarithm is estimated)")
    return mask, value


class _Members:
    """The ensemble's forecast bookkeeping: per member its run state, augmented parameters, last outputs, the
    recent bit speed (the stick-slip index's window), its reduced model and that model's coordinate transforms
    (:func:`member_models`; None: the estimator's model)."""

    #: What each member has, indexed by member: lists, or arrays whose rows are the members.
    PER_MEMBER = ("states", "parameters", "outputs", "speed", "models", "transforms")

    def __init__(self, states, parameters, window_samples, models, transforms):
        self.states = states
        self.parameters = parameters  # (N, p): [log c] [log μ] [log κ] b z0
        self.outputs = [None] * len(states)
        self.speed = np.full((len(states), window_samples), np.nan)
        self.models = list(models)
        self.transforms = list(transforms)  # (X, X⁻¹) with ξ = X q, or None

    def nominal(self, i) -> np.ndarray:
        """A copy of member ``i``'s state in the estimator's model's coordinates ``[X q, X q̇, s]``."""
        return _transformed(self.states[i].y, None if self.transforms[i] is None else self.transforms[i][0])

    def own(self, i, y) -> np.ndarray:
        """``y`` (in the estimator's model's coordinates) in member ``i``'s own ``[X⁻¹ ξ, X⁻¹ ξ̇, s]``."""
        return y if self.transforms[i] is None else _transformed(y, self.transforms[i][1])

    def push(self, i, speeds):
        speeds = np.asarray(speeds, dtype=float)[-self.speed.shape[1]:]
        k = len(speeds)
        if k:
            self.speed[i, :-k] = self.speed[i, k:]
            self.speed[i, -k:] = speeds

    def reorder(self, parents):
        """Member ``i`` becomes a copy of member ``parents[i]`` (all at once: a parent drawn twice is copied
        twice, one not drawn is gone): its run state, parameters, outputs, recent bit speed and model."""
        parents = [int(p) for p in parents]
        for name in self.PER_MEMBER:
            old = getattr(self, name)
            setattr(self, name, old[parents] if isinstance(old, np.ndarray) else [old[p] for p in parents])

    def copy_member(self, target, source):
        for name in self.PER_MEMBER:
            values = getattr(self, name)
            values[target] = values[source]


def _transformed(y: np.ndarray, matrix: np.ndarray | None) -> np.ndarray:
    """A copy of the state ``y = [η, η̇, s]`` with ``η``, ``η̇`` multiplied by ``matrix`` (n × n; None: a copy)."""
    out = np.array(y, dtype=float)
    if matrix is not None:
        n = matrix.shape[0]
        out[:n] = matrix @ out[:n]
        out[n:2 * n] = matrix @ out[n:2 * n]
    return out


def _hook_load_mean(record: SurfaceRecord, t: float, window: float) -> float:
    """Mean of the usable hook-load samples in ``(t − window, t]`` [N]; NaN without one (or channel)."""
    if "hook_load" not in record.channels:
        return math.nan
    time = record.time
    keep = record.usable("hook_load") & (time <= t + 1e-12) & (time > t - window)
    return float(np.mean(record.channels["hook_load"][keep])) if np.any(keep) else math.nan


def _correlation(parameters: np.ndarray, names: tuple[str, ...]) -> dict:
    """The members' correlation of each pair of ``names`` (the columns of ``parameters``: the coefficient and
    the friction factor as their logarithms, as the filter estimates them) [-]: ``{(a, b): r}``, NaN for a
    column with no spread."""
    out = {}
    for (j, a), (k, b) in itertools.combinations(enumerate(names), 2):
        x, y = parameters[:, j], parameters[:, k]
        with np.errstate(invalid="ignore", divide="ignore"):
            out[(a, b)] = float(np.corrcoef(x, y)[0, 1]) if np.std(x) > 0 and np.std(y) > 0 else math.nan
    return out


def _summaries(values: np.ndarray) -> tuple[float, np.ndarray]:
    finite = values[np.isfinite(values)]
    if not finite.size:
        return math.nan, np.full(len(QUANTILES), np.nan)
    return float(finite.mean()), np.quantile(finite, QUANTILES)


def estimate(case, record: SurfaceRecord, settings: EstimatorSettings = EstimatorSettings(), *,
             progress: Callable[[float], None] | None = None, model=None) -> EstimationResult:
    """The downhole state of ``case`` (a :class:`~drillstring.case.Case`) from the surface ``record`` by the
    ensemble filter of this module, the members started from the model's initial state (the static state
    spinning at the top speed, :meth:`~drillstring.dynamics.rom.ReducedOrderModel.initial_state`) with the prior
    spreads of ``settings`` and run ``spin_up`` seconds before the record's first time (module docstring).
    ``progress``: called with the record time reached [s] after each sample. ``model``: the estimator's model
    (default :func:`estimator_model`: building it takes ~0.5 s).
    Returns an :class:`~drillstring.estimation.results.EstimationResult`."""
    begin = _time.perf_counter()
    if not isinstance(record, SurfaceRecord):
        raise TypeError(f"record: must be a SurfaceRecord, not {type(record).__name__}")
    if not any(name in record.channels for name in OBSERVED):
        raise ValueError(f"record {record.source!r}: holds none of the channels the estimator reads "
                         f"({', '.join(OBSERVED)})")
    model = estimator_model(case, settings) if model is None else model
    if model.full:
        raise ValueError("estimate: the estimator's model must be case 2 (nonlinear = 'bit_and_contact')")
    models, transforms = member_models(model, settings.model_dispersion, settings.seed, settings.ensemble_size)
    # the augmented parameters' columns: [log c] [log μ] [log κ] b z0 (c, μ, κ where estimated)
    coefficient_name = None if settings.bit_rock_coefficient == "none" else settings.bit_rock_coefficient
    friction_name = FRICTION_WALLS[settings.friction_factor]
    stiffness_name = STIFFNESS_FAMILIES[settings.stiffness_factor]
    try:
        if coefficient_name is not None:
            slot = coefficient_slot(model, coefficient_name)
            coefficient = float(getattr(model.bit_rock, coefficient_name))
        if friction_name is not None:
            friction_mask, friction_value = friction_stations_of(case, model, settings.friction_factor)
    except ValueError as error:
        raise ValueError(f"estimator.{error}") from None
    estimated = [name for name in (coefficient_name, friction_name, stiffness_name) if name is not None]
    column = {name: j for j, name in enumerate(estimated + ["weight_on_bit_bias", "block_zero"])}
    n_parameters = len(column)
    bias_column, zero_column = column["weight_on_bit_bias"], column["block_zero"]
    # each walking parameter's random walk per √s, in the order of the walk's draws
    walks = {name: per_root_second for name, per_root_second in (
        (coefficient_name, settings.coefficient_walk), ("weight_on_bit_bias", settings.weight_on_bit_bias_walk),
        (friction_name, settings.friction_walk), (stiffness_name, settings.stiffness_walk)) if name is not None}
    rng = np.random.default_rng(settings.seed)
    n_members = settings.ensemble_size
    n = model.size
    solver = SolverSettings(rtol=settings.rtol, atol=settings.atol)
    top_speed = float(model.top_speed)
    weight = float(model.weight_on_bit)
    static_hook = float(model.static.weight_on_hook)
    top_u = np.asarray(model.top_u, dtype=float)
    time = np.asarray(record.time, dtype=float)
    spin = float(settings.spin_up)
    clock = time - time[0] + spin  # the model's time: the record's from its first sample, after the spin-up
    n_time = len(time)
    channels = [name for name in OBSERVED if name in record.channels]
    usable = {name: record.usable(name) for name in channels}
    noise = {"top_speed": settings.top_speed_noise, "surface_torque": settings.surface_torque_noise,
             "block_position": settings.block_position_noise}

    # the initial ensemble: the string's speed spread, the parameters' priors
    y0 = model.initial_state(0.0, settings.seed)
    states, parameters = [], np.zeros((n_members, n_parameters))
    block0 = math.nan
    if "block_position" in channels and np.any(usable["block_position"]):
        block0 = float(record.channels["block_position"][np.flatnonzero(usable["block_position"])[0]])
    for i in range(n_members):
        y = y0.copy() if models[i] is model else models[i].initial_state(0.0, settings.seed)
        if model.rigid_rotation_column is not None:
            r = model.rigid_rotation_column
            y[n + r] += settings.initial_speed_spread * rng.standard_normal() / models[i].quill_shapes[r]
        states.append(RunState.start(models[i], y))
        if coefficient_name is not None:
            parameters[i, column[coefficient_name]] = (math.log(coefficient)
                                                       + settings.coefficient_spread * rng.standard_normal())
        if friction_name is not None:
            parameters[i, column[friction_name]] = (math.log(friction_value)
                                                    + settings.friction_spread * rng.standard_normal())
        if stiffness_name is not None:
            parameters[i, column[stiffness_name]] = settings.stiffness_spread * rng.standard_normal()
        parameters[i, bias_column] = settings.weight_on_bit_bias_spread * rng.standard_normal()
        parameters[i, zero_column] = ((block0 if math.isfinite(block0) else 0.0)
                                      + settings.block_position_noise * rng.standard_normal())
    window_samples = max(round(settings.stick_slip_window / settings.output_step), 2)
    members = _Members(states, parameters, window_samples, models, transforms)

    names = tuple(DOWNHOLE) + tuple(estimated) + ("weight_on_bit_bias",)
    mean = {name: np.full(n_time, np.nan) for name in names}
    quantiles = {name: np.full((n_time, len(QUANTILES)), np.nan) for name in names}
    predicted_mean = {name: np.full(n_time, np.nan) for name in channels}
    predicted_quantiles = {name: np.full((n_time, len(QUANTILES)), np.nan) for name in channels}
    used = {name: np.zeros(n_time, dtype=bool) for name in channels}
    replaced = np.zeros(n_time, dtype=np.int64)
    effective_size = np.full(n_time, np.nan)  # the particle weights' effective sample size at each analysis
    kicked, speed_noise = model_noise_columns(model, settings)
    kicked = slice(n + kicked.start, n + kicked.stop)  # in the state [displacements, velocities]
    relaxation = None  # the RTPS factor of each row of the augmented state [y, parameters]
    if settings.relaxation > 0.0 or settings.parameter_relaxation > 0.0:
        relaxation = np.concatenate([np.full(len(y0), settings.relaxation),
                                     np.full(n_parameters, settings.parameter_relaxation)])
    friction_nominal = np.asarray(model.case2_data.friction.friction, dtype=float)

    def clipped(log_value: float, nominal: float) -> float:
        log_nominal = math.log(nominal)
        return math.exp(min(max(log_value, log_nominal - LOG_RANGE), log_nominal + LOG_RANGE))

    def member(i, hook_mean):
        laws = members.models[i].case2_data.laws
        if coefficient_name is not None:
            laws = laws.copy()
            laws[slot] = clipped(members.parameters[i, column[coefficient_name]], coefficient)
        friction = None
        if friction_name is not None:
            friction = friction_nominal.copy()
            friction[friction_mask] = clipped(members.parameters[i, column[friction_name]], friction_value)
        stiffness = (None if stiffness_name is None
                     else clipped(members.parameters[i, column[stiffness_name]], 1.0))
        drop = 0.0 if not math.isfinite(hook_mean) else static_hook - hook_mean
        return member_model(members.models[i], laws, weight + drop + members.parameters[i, bias_column], friction,
                            stiffness)

    # the assimilation windows (t0 + (j-1) step, t0 + j step] of the record (the first sample alone in window 0),
    # each analysed at its last sample with the means of its usable samples
    window = np.ceil((time - time[0]) / settings.assimilation_step - 1e-9).astype(np.int64)
    window_observed = {name: 0.0 for name in channels}
    window_predicted = {name: np.zeros(n_members) for name in channels}
    window_samples_used: dict[str, list[int]] = {name: [] for name in channels}

    def diverged_parameters(analysed: np.ndarray, t_record: float) -> None:
        """Stop (:class:`EstimateDiverged`) where the analysis ``analysed`` (parameter rows × members) left a
        parameter non-finite or spread a logarithm's 5-95 % band over more than the clip's range (2 LOG_RANGE):
        the ensemble no longer describes it (an inflation above what the record's information holds, e.g.)."""
        for name, j in column.items():
            if not np.all(np.isfinite(analysed[j])):
                raise EstimateDiverged(f"estimate: the analysis at t = {t_record:g} s of the record left {name} "
                                       "non-finite in some members")
        for name in estimated:
            low, high = np.quantile(analysed[column[name]], [0.05, 0.95])
            if high - low > 2.0 * LOG_RANGE:
                cause = (f"with inflation = {settings.inflation:g} the analyses widen the parameters faster than "
                         "the record narrows them: lower the inflation" if settings.inflation > 1.0 else
                         "the record does not hold it: estimate fewer parameters, or give it a narrower prior")
                raise EstimateDiverged(
                    f"estimate: the {name} ensemble diverged at t = {t_record:g} s of the record: its 90 % band "
                    f"spans a factor {math.exp(min(high - low, 700.0)):.3g} (at most exp(2 LOG_RANGE) = "
                    f"{math.exp(2.0 * LOG_RANGE):.3g}); {cause}")

    def forecast(t_from: float, t_to: float, hook_mean: float, walk: bool = True) -> int:
        """Every member from model time ``t_from`` to ``t_to`` [s]: the parameters' walk (if ``walk``), the model
        error's kick, the model; a failed member replaced by a copy of a good one. Returns the count replaced."""
        dt = t_to - t_from
        if walk:
            for name, per_root_second in walks.items():
                members.parameters[:, column[name]] += per_root_second * math.sqrt(dt) * rng.standard_normal(n_members)
        if speed_noise > 0.0:
            for i in range(n_members):
                y = members.nominal(i)
                kick = speed_noise * math.sqrt(dt) * rng.standard_normal(kicked.stop - kicked.start)
                last = members.outputs[i]
                y[kicked] += kick * kick_scale(None if last is None else float(last[_BIT_SPEED]),
                                                              settings.model_noise_stick_speed)
                members.states[i] = members.states[i].updated(members.own(i, y))
        grid = np.append(np.arange(t_from + settings.output_step, t_to - 1e-9 * dt, settings.output_step), t_to)
        ok = np.zeros(n_members, dtype=bool)
        for i in range(n_members):
            try:
                run = advance(member(i, hook_mean), solver, members.states[i], t_to, output_times=grid)
            except (ValueError, FloatingPointError, ZeroDivisionError):
                continue
            rows = run.outputs
            if not run.success or len(rows) != len(grid) or not np.all(np.isfinite(rows[:, :_SURFACE_TORQUE + 1])) \
                    or not np.all(np.isfinite(run.state.y)) \
                    or np.max(np.abs(rows[:, _BIT_SPEED])) > settings.divergence_speed_ratio * abs(top_speed):
                continue
            ok[i] = True
            members.states[i] = run.state
            members.outputs[i] = rows[-1]
            members.push(i, rows[:, _BIT_SPEED])
        if not ok.any():
            raise EstimateDiverged(f"estimate: every member's forecast failed between t = {t_from - spin:g} s and "
                                   f"{t_to - spin:g} s of the record")
        good = np.flatnonzero(ok)
        for i in np.flatnonzero(~ok):
            source = int(rng.choice(good))
            members.copy_member(i, source)
            for name in channels:
                window_predicted[name][i] = window_predicted[name][source]
        return int(np.sum(~ok))

    if spin > 0.0:
        # the spin-up: from the initial state to the record's first time, in steps of at most SPIN_UP_STEP
        hook_first = _hook_load_mean(record, float(time[0]), settings.hook_load_window)
        marks = np.linspace(0.0, spin, max(math.ceil(spin / SPIN_UP_STEP - 1e-9), 1) + 1)
        for a, b in itertools.pairwise(marks):
            forecast(float(a), float(b), hook_first, walk=False)
        # the block's zero: each member's predicted block position at the record's first time is the first sample's
        top_now = np.array([top_u @ members.nominal(i)[:n] for i in range(n_members)])
        members.parameters[:, zero_column] += top_now

    completed = 0  # the samples whose analysis and summaries are done
    stopped = ""
    try:
        for k in range(n_time):
            t = float(clock[k])
            hook_mean = _hook_load_mean(record, float(time[max(k - 1, 0)]), settings.hook_load_window)
            if k == 0:
                for i in range(n_members):
                    row = member(i, hook_mean).observe(t, members.states[i].y)
                    members.outputs[i] = row
                    if spin > 0.0:
                        members.speed[i, -1] = row[_BIT_SPEED]
                    else:
                        members.push(i, [row[_BIT_SPEED]])
            else:
                replaced[k] = forecast(float(clock[k - 1]), t, hook_mean)
            # the predicted surface channels, the analysis
            z = np.array([np.concatenate([members.nominal(i), members.parameters[i]]) for i in range(n_members)]).T
            predicted = {"top_speed": np.array([o[_QUILL] for o in members.outputs]),
                         "surface_torque": np.array([o[_SURFACE_TORQUE] for o in members.outputs]),
                         "block_position": z[-1] - top_u @ z[:n]}
            for name in channels:
                predicted_mean[name][k], predicted_quantiles[name][k] = _summaries(predicted[name])
            # the window's sums: the usable samples of each channel and each member's predictions at their times
            for name in channels:
                if usable[name][k]:
                    window_observed[name] += float(record.channels[name][k])
                    window_predicted[name] += predicted[name]
                    window_samples_used[name].append(k)
            rows = [name for name in channels if window_samples_used[name]]
            if rows and (k == n_time - 1 or window[k + 1] != window[k]):
                for name in rows:
                    used[name][window_samples_used[name]] = True
                count = {name: len(window_samples_used[name]) for name in rows}
                prior = z
                analysed = (np.array([window_predicted[name] / count[name] for name in rows]),
                            np.array([window_observed[name] / count[name] for name in rows]),
                            np.array([noise[name] for name in rows]))
                if settings.particle_share > 0.0:
                    particles = enkpf_analysis(z, *analysed, settings.particle_share, rng, settings.inflation,
                                               settings.particle_effective_size)
                    z, effective_size[k] = particles.ensemble, particles.effective_size
                    members.reorder(particles.parents)
                else:
                    z = etkf_analysis(z, *analysed, settings.inflation)
                if relaxation is not None:
                    z = relax_to_prior_spread(prior, z, relaxation)
                diverged_parameters(z[-n_parameters:], t - spin)
                for i in range(n_members):
                    members.states[i] = members.states[i].updated(members.own(i, z[:-n_parameters, i]))
                    members.parameters[i] = z[-n_parameters:, i]
                    row = member(i, hook_mean).observe(t, members.states[i].y)
                    members.outputs[i] = row
                    members.speed[i, -1] = row[_BIT_SPEED]
            if k == n_time - 1 or window[k + 1] != window[k]:
                for name in channels:
                    window_observed[name] = 0.0
                    window_predicted[name] = np.zeros(n_members)
                    window_samples_used[name] = []
            # the analysis's downhole state and parameters
            rows_out = np.array(members.outputs)
            values = {name: rows_out[:, OBSERVABLE_COLUMN[name]] for name in DOWNHOLE if name in OBSERVABLE_COLUMN}
            speed_window = members.speed
            with np.errstate(invalid="ignore", divide="ignore"):
                window_mean = np.nanmean(speed_window, axis=1)
                index = (np.nanmax(speed_window, axis=1) - np.nanmin(speed_window, axis=1)) / (2.0 * window_mean)
            values["stick_slip_index"] = np.where(window_mean > 0.0, index, np.nan)
            for name in estimated:
                values[name] = np.exp(members.parameters[:, column[name]])
            values["weight_on_bit_bias"] = members.parameters[:, bias_column]
            for name in names:
                mean[name][k], quantiles[name][k] = _summaries(values[name])
            completed = k + 1
            if progress is not None:
                progress(float(time[k]))
    except KeyboardInterrupt:
        if completed == 0:
            raise
        stopped = f"interrupted after t = {time[completed - 1]:g} s of the record"
    except EstimateDiverged as error:
        if completed == 0:
            raise
        stopped = str(error)
    if stopped:  # keep what was computed: the samples before the stop
        time = time[:completed]
        for table in (mean, quantiles, predicted_mean, predicted_quantiles, used):
            for name in table:
                table[name] = table[name][:completed]
        replaced = replaced[:completed]
        effective_size = effective_size[:completed]

    units = {name: unit for name, (unit, _) in DOWNHOLE.items()}
    if coefficient_name is not None:
        units[coefficient_name] = COEFFICIENT_UNITS.get(coefficient_name, "1")
    if friction_name is not None:
        units[friction_name] = "1"
    if stiffness_name is not None:
        units[stiffness_name] = "1"
    units["weight_on_bit_bias"] = "N"
    return EstimationResult(
        time=time, mean=mean, quantiles=quantiles, units=units,
        parameters=tuple(estimated) + ("weight_on_bit_bias",), parameter_correlation=_correlation(
            members.parameters[:, :n_parameters - 1], tuple(estimated) + ("weight_on_bit_bias",)),
        predicted_mean=predicted_mean, predicted_quantiles=predicted_quantiles,
        observed={name: np.asarray(record.channels[name], dtype=float)[:len(time)] for name in channels},
        used=used, replaced=replaced, settings=settings.as_dict(), wall_time=_time.perf_counter() - begin,
        source=record.source, stopped=stopped,
        effective_size=effective_size if settings.particle_share > 0.0 else None)
