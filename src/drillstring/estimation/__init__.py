"""From surface data to the downhole state (the drill-string's digital twin): a surface record
(:mod:`drillstring.estimation.surface`), an ensemble estimator on the reduced model, its results."""
