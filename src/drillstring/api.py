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
    progress=None,
) -> xr.Dataset:
    """Monte Carlo study of a random weight-on-hook (SPEC §8); returns the statistics Dataset.

    Exactly one of ``sigma`` [N] (standard deviation of the weight-on-hook) or ``dispersion``
    (σ / mean) is given. Realizations stream to the Zarr store ``out`` (a temporary folder when None);
    rerunning with the same ``out`` resumes. ``workers`` local processes (default: one per core), or a
    Dask scheduler address in ``scheduler``. See :mod:`drillstring.stochastic.montecarlo`.
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
    return study_statistics(load_study(store))
