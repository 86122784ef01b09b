"""The Python API for notebooks: load a case, run one drilling simulation, a Monte Carlo study, a
comparison of the two nonlinear models. The command line calls these functions (one set of defaults,
one set of checks) and only parses and formats. Each public function runs its dense linear algebra
single-threaded (:mod:`drillstring.blas_threads`), whatever the caller's BLAS settings.

The functions live in the package's modules, one per kind of work: :mod:`~drillstring.api.runs` (one case: a run,
its static state, modes, stability, Campbell diagram, the comparison of the two nonlinear models),
:mod:`~drillstring.api.studies` (Monte Carlo studies), :mod:`~drillstring.api.maps` (operating maps and global
sensitivity), :mod:`~drillstring.api.estimates` (the downhole state from a surface record), :mod:`~drillstring.api.settings` (the
settings objects the engine functions take: :class:`RunOptions`, :class:`SimulationWindow`, :class:`RandomInputs`,
:class:`SearchOptions`) and :mod:`~drillstring.api.arguments` (the checks of the arguments they share); this module
offers them all under one name.

>>> import drillstring
>>> ds = drillstring.simulate("reference", t_end=5.0)        # doctest: +SKIP
>>> ds.rate_of_penetration.sel(time=slice(2, None)).mean()  # doctest: +SKIP
"""

# The public names, offered here and documented once, in their own modules (no __all__: autodoc would list
# them twice).
from drillstring.api.arguments import (  # noqa: F401
    as_case,
)
from drillstring.api.estimates import (  # noqa: F401
    EstimateOutcome,
    estimate,
)
from drillstring.api.maps import (  # noqa: F401
    MAX_RESAMPLES,
    MapOutcome,
    SensitivityOutcome,
    map_settings,
    operating_map,
    sensitivity,
)
from drillstring.api.runs import (  # noqa: F401
    COMPARED_MODELS,
    COMPARED_OBSERVABLES,
    MAX_MODES,
    campbell,
    compare,
    modes,
    simulate,
    stability,
    stability_boundary,
    static,
)
from drillstring.api.settings import (  # noqa: F401
    RandomInputs,
    RunOptions,
    SearchOptions,
    SimulationWindow,
)
from drillstring.api.studies import (  # noqa: F401
    StudyFailed,
    StudyOutcome,
    monte_carlo_study,
    study,
    study_settings,
)
