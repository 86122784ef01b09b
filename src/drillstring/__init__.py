"""drillstring: stochastic nonlinear dynamics of oil-well drill-strings.

The pipeline, one layer per subpackage or module (data flows down the list):
case -> fem (sections, elements, mesh, assembly) -> statics -> modal -> forces ->
dynamics (reduced model, Runge-Kutta) -> stochastic (MaxEnt, Monte Carlo, statistics) ->
results, plots, report, cli.

The notebook API: :func:`load_case`, :func:`static` (the prestressed static state and the buckling margin),
:func:`modes` (natural frequencies), :func:`simulate`, :func:`stability` (steady drilling and its linear
stability), :func:`compare` (case 1 against case 2), :func:`study` / :func:`monte_carlo_study` for Monte Carlo studies of any parameters,
:func:`operating_map` (performance and vibration over top speed × weight-on-bit) and :func:`sensitivity`
(Sobol' indices), :func:`campbell` (Campbell diagram and critical speeds), :func:`optimize` (the robust operating point under
chance constraints), :func:`estimate` (the downhole state from a surface record, with its uncertainty). The
engine functions take their settings as objects: :class:`RunOptions` (output folder, workers or Dask scheduler,
callbacks, unit system), :class:`SimulationWindow` (run length, output step, transient), :class:`RandomInputs`
(the laws drawn) and :class:`SearchOptions` (the search's budget), :mod:`drillstring.api.settings`.
"""

from drillstring._version import __version__  # noqa: F401  (the package's version)
from drillstring.kernel_cache import configure as _configure_kernel_cache

_configure_kernel_cache()  # before any kernel is compiled or loaded: a cache per version of their sources


def __getattr__(name):  # lazy, so `import drillstring` stays cheap for the command line
    if name == "load_case":
        from drillstring.case import load_case

        return load_case
    if name == "simulate":
        from drillstring.api import simulate

        return simulate
    if name == "stability":
        from drillstring.api import stability

        return stability
    if name in ("static", "modes", "study", "monte_carlo_study", "operating_map", "sensitivity", "compare",
                "campbell", "estimate"):
        from drillstring import api

        return getattr(api, name)
    if name in ("RunOptions", "SimulationWindow", "RandomInputs", "SearchOptions"):
        from drillstring.api import settings

        return getattr(settings, name)
    if name == "optimize":
        from drillstring.operating_point import optimize

        return optimize
    raise AttributeError(f"module 'drillstring' has no attribute {name!r}")
