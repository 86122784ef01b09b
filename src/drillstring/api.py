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
