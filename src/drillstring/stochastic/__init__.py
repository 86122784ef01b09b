"""Monte Carlo studies of a random weight-on-hook: Maximum-Entropy laws (:mod:`.maxent`), the study
engine (:mod:`.montecarlo`), statistics (:mod:`.statistics`) and the store's analysis (:mod:`.analysis`).

The study defaults are defined here, once, in a module that imports nothing, so that the command line
can show them in its help without loading the engine.
"""

#: Standard deviation of the weight-on-hook [N] of a study given neither sigma nor dispersion (the
#: largest of the reference studies).
DEFAULT_SIGMA = 5000.0
#: Number of realizations n_s of a study.
DEFAULT_SAMPLES = 50
#: Root seed of a study's random draws.
DEFAULT_SEED = 0
