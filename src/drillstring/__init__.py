"""drillstring: stochastic nonlinear dynamics of oil-well drill-strings.

The pipeline, one layer per subpackage or module (data flows down the list):
case -> fem (sections, elements, mesh, assembly) -> statics -> modal -> forces ->
dynamics (reduced model, Runge-Kutta) -> stochastic (MaxEnt, Monte Carlo, statistics) ->
results, plots, report, cli.
"""

__version__ = "0.1.0"
