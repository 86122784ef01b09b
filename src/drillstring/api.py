"""The Python API for notebooks: load a case, run one drilling simulation.

>>> import drillstring
>>> ds = drillstring.simulate("reference", t_end=5.0)        # doctest: +SKIP
>>> ds.rate_of_penetration.sel(time=slice(2, None)).mean()  # doctest: +SKIP
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import xarray as xr

from drillstring.case import Case, load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import SimulationError, simulate_model
from drillstring.results import run_dataset


def as_case(case: Case | str | Path) -> Case:
    """A Case as is, or loaded from a built-in name or a TOML path."""
    return case if isinstance(case, Case) else load_case(case)


def simulate(
    case: Case | str | Path = "reference",
    *,
    t_end: float | None = None,
    output_step: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    weight_on_bit: float | None = None,
    progress: Callable[[float], None] | None = None,
    raise_on_failure: bool = True,
) -> xr.Dataset:
    """Simulate one drilling run of ``case`` (SPEC §7) and return its observables as a Dataset.

    Arguments left as None take the case's ``[simulation]`` values; ``weight_on_bit`` [N] overrides
    the static weight-on-bit. A run that stops early raises :class:`SimulationError` whose
    ``.dataset`` holds what was computed (or, with ``raise_on_failure=False``, that Dataset is
    returned with ``attrs["status"] == "failed"``).
    """
    case = as_case(case)
    s = case.simulation
    model = case_reduced_model(case, weight_on_bit=weight_on_bit)
    extra = {
        "weight_on_hook": model.static.weight_on_hook,
        "weight_on_bit": model.static.weight_on_bit,
        "top_speed": case.operation.top_speed,
        "modes": f"{case.reduced_model.axial_modes} axial + rigid, {case.reduced_model.torsional_modes} "
                 f"torsional, {case.reduced_model.lateral_modes} lateral per plane",
        "elements": model.static.mesh.n_elements,
    }
    kwargs = dict(
        t_end=s.t_end if t_end is None else t_end,
        output_step=s.output_step if output_step is None else output_step,
        rtol=s.rtol if rtol is None else rtol,
        atol=s.atol if atol is None else atol,
        method=s.method,
        max_steps=s.max_steps,
        min_step=s.min_step,
        lateral_perturbation=case.initial.lateral_perturbation,
        seed=case.initial.seed,
        progress=progress,
    )
    try:
        result = simulate_model(model, **kwargs)
    except SimulationError as error:
        dataset = run_dataset(error.result, case_toml=case.to_toml(), extra_attrs=extra)
        if raise_on_failure:
            error.dataset = dataset
            raise
        return dataset
    return run_dataset(result, case_toml=case.to_toml(), extra_attrs=extra)


def stability(case: Case | str | Path = "reference", *, weight_on_bit: float | None = None):
    """Steady drilling of ``case`` (closed form) and the eigenvalues of its reduced model linearised
    about it, bit–rock law included (:mod:`drillstring.dynamics.stability`).

    Returns a :class:`~drillstring.dynamics.stability.StabilityResult`: ``.stable``, ``.steady_state``
    (``rate_of_penetration`` [m/s], ``bit_speed`` [rad/s], ``torque_on_bit`` [N·m], ``force_on_bit``
    [N]), ``.modes`` sorted by frequency (``family``, ``frequency`` [Hz], ``damping_ratio``,
    ``growth_rate`` [1/s]), ``.leading`` and ``.to_dict()`` (JSON-ready). ``weight_on_bit`` [N]
    overrides the case's.
    """
    from drillstring.dynamics.stability import case_stability

    return case_stability(as_case(case), weight_on_bit=weight_on_bit)


def study(
    case: Case | str | Path = "reference",
    *,
    sigma: float | None = None,
    dispersion: float | None = None,
    samples: int = 50,
    seed: int = 0,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    t_end: float | None = None,
    output_step: float | None = None,
    transient: float | None = None,
    progress=None,
) -> xr.Dataset:
    """Monte Carlo study of a random weight-on-hook (SPEC §8); returns the statistics Dataset.

    Exactly one of ``sigma`` [N] (standard deviation of the weight-on-hook) or ``dispersion``
    (σ / mean) is given. Realizations stream to the Zarr store ``out`` (a temporary folder when None);
    rerunning with the same ``out`` resumes. ``workers`` local processes (default: one per core), or a
    Dask scheduler address in ``scheduler``. ``transient`` [s]: start of the steady window for the
    per-realization vibration indicators (default ``min(10 s, t_end/2)``). See
    :mod:`drillstring.stochastic.montecarlo`.
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.
    """
    import tempfile

    from drillstring.stochastic.analysis import load_study, study_statistics
    from drillstring.stochastic.montecarlo import StudySettings, nominal_weight_on_hook, run_study

    case = as_case(case)
    if (sigma is None) == (dispersion is None):
        raise ValueError("give exactly one of sigma [N] or dispersion (sigma / mean weight_on_hook)")
    if dispersion is not None:
        if not dispersion > 0:
            raise ValueError(f"dispersion = {dispersion!r}: must be > 0")
        sigma = dispersion * nominal_weight_on_hook(case)
    settings = StudySettings(
        samples=samples, sigma=float(sigma), seed=seed,
        t_end=case.simulation.t_end if t_end is None else t_end,
        output_step=case.simulation.output_step if output_step is None else output_step,
    )
    store = Path(out) / "study.zarr" if out is not None else Path(tempfile.mkdtemp()) / "study.zarr"
    run_study(case, settings, store, workers=workers, scheduler=scheduler, progress=progress)
    return study_statistics(load_study(store), t_transient=transient)


import math  # noqa: E402  (used by the comparison helpers below)

#: The two nonlinear models compared by :func:`compare`, in the order returned: case 1, case 2.
COMPARED_MODELS = ("full", "bit_and_contact")
#: Scalar observables compared by :func:`compare` (the radial displacement is added per probe).
COMPARED_OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")


def _ratio(numerator: float, denominator: float) -> float | None:
    """``numerator / denominator`` as a JSON-ready float, None when undefined (0/0, x/0, NaN)."""
    if not (math.isfinite(numerator) and math.isfinite(denominator)) or denominator == 0.0:
        return None
    return float(numerator / denominator)


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _difference_numbers(full, reduced, steady) -> dict[str, float | None]:
    """Differences of one observable, case 1 (``full``) minus case 2 (``reduced``), SI units: the largest
    absolute difference over time, the RMS difference relative to the RMS of case 2, and the difference of
    the means over the ``steady`` samples (t after the transient), absolute and relative to case 2's."""
    import numpy as np

    full = np.asarray(full, dtype=float)
    reduced = np.asarray(reduced, dtype=float)
    delta = full - reduced
    mean_full = float(np.mean(full[steady]))
    mean_reduced = float(np.mean(reduced[steady]))
    return {
        "max_abs_difference": _finite_or_none(float(np.max(np.abs(delta)))),
        "rms_relative_difference": _ratio(float(np.sqrt(np.mean(delta**2))),
                                          float(np.sqrt(np.mean(reduced**2)))),
        "mean_full": _finite_or_none(mean_full),
        "mean_bit_and_contact": _finite_or_none(mean_reduced),
        "mean_difference": _finite_or_none(mean_full - mean_reduced),
        "mean_relative_difference": _ratio(mean_full - mean_reduced, abs(mean_reduced)),
    }


def compare(
    case: Case | str | Path = "reference",
    *,
    t_end: float | None = None,
    output_step: float | None = None,
    progress: Callable[[str, float], None] | None = None,
) -> tuple[xr.Dataset, xr.Dataset, dict]:
    """Run ``case`` with the full nonlinear model (case 1: kinetic- and strain-energy forces added) and with
    the bit–rock and contact forces only (case 2), everything else equal (SPEC §6), and compare them.

    Returns ``(full, bit_and_contact, differences)``: the two run Datasets and a JSON-ready dict (SI
    units) with, under ``observables``, for the rate of penetration, bit speed, torque- and force-on-bit
    and the radial displacement at each probe (``radial_displacement_<j>``, with its ``probe_x``):
    ``max_abs_difference`` over time, ``rms_relative_difference`` (RMS of the difference / RMS of case 2),
    the means after the transient (t >= min(10 s, t_end/2)) of each case, their ``mean_difference`` and
    ``mean_relative_difference`` (relative to |mean of case 2|; None when that mean is 0). Differences are
    case 1 minus case 2. ``wall_time`` holds the wall time [s] of each ``simulate`` call (model build and
    integration, measured around the call), ``ratio`` = full / bit_and_contact; ``solver_wall_time`` and
    ``n_rhs`` the integrator's own numbers. ``progress(model, t)`` is called with the model name
    ("full" or "bit_and_contact") and the simulated time [s]. A run that stops early raises
    :class:`SimulationError` (``.dataset`` the partial run, ``.nonlinear`` which model failed).
    """
    import time

    import numpy as np

    from drillstring.dynamics.indicators import transient_end

    case = as_case(case)
    runs: dict[str, xr.Dataset] = {}
    wall: dict[str, float] = {}
    for nonlinear in COMPARED_MODELS:
        variant = case.model_copy(update={"model": case.model.model_copy(update={"nonlinear": nonlinear})})
        report = None if progress is None else (lambda t, _m=nonlinear: progress(_m, t))
        start = time.perf_counter()
        try:
            runs[nonlinear] = simulate(variant, t_end=t_end, output_step=output_step, progress=report)
        except SimulationError as error:
            error.nonlinear = nonlinear
            raise
        wall[nonlinear] = time.perf_counter() - start
    full, reduced = runs["full"], runs["bit_and_contact"]

    t = np.asarray(full["time"].values, dtype=float)
    t_reduced = np.asarray(reduced["time"].values, dtype=float)

    def on_grid(values) -> np.ndarray:
        values = np.asarray(values, dtype=float)
        if t_reduced.shape == t.shape and np.allclose(t_reduced, t, rtol=0.0, atol=1e-12):
            return values
        return np.interp(t, t_reduced, values)

    t_final = float(t[-1])
    t_transient = transient_end(t_final)
    steady = t >= t_transient - 1e-9 * max(1.0, t_final)
    if not steady.any():
        steady = np.ones_like(t, dtype=bool)

    observables: dict[str, dict] = {}
    for name in COMPARED_OBSERVABLES:
        observables[name] = _difference_numbers(full[name].values, on_grid(reduced[name].values), steady)
    x = np.atleast_1d(np.asarray(full["x"].values, dtype=float))
    radial_full = np.asarray(full["radial_displacement"].values, dtype=float)
    radial_reduced = np.asarray(reduced["radial_displacement"].values, dtype=float)
    for j, position in enumerate(x):
        entry = {"probe_x": float(position)}
        entry.update(_difference_numbers(radial_full[:, j], on_grid(radial_reduced[:, j]), steady))
        observables[f"radial_displacement_{j}"] = entry

    def pair(key: str, cast=float) -> dict:
        return {m: cast(runs[m].attrs.get(key, float("nan"))) for m in COMPARED_MODELS}

    differences = {
        "case": case.name,
        "t_end": t_final,
        "t_transient": float(t_transient),
        "difference": "case 1 (full) minus case 2 (bit_and_contact)",
        "observables": observables,
        "wall_time": {**{m: float(wall[m]) for m in COMPARED_MODELS},
                      "ratio": _ratio(wall["full"], wall["bit_and_contact"])},
        "solver_wall_time": pair("solver_wall_time"),
        "n_rhs": pair("solver_n_rhs", int),
        "impacts": pair("impacts", int),
    }
    return full, reduced, differences
