"""Studies on the engine (:mod:`.execution`, :mod:`.store`): Monte Carlo studies of random case parameters
(laws :mod:`.maxent`, :mod:`.uncertainty`; :mod:`.montecarlo`, statistics :mod:`.statistics`, the store's
analysis :mod:`.analysis`), operating maps (:mod:`.operating_map`) and global sensitivity
(:mod:`.sensitivity`, :mod:`.sensitivity_study`).

The defaults are defined here, once, in a module that imports nothing, so that the command line can show
them in its help without loading the engine.
"""

#: Standard deviation of the weight-on-hook [N] of a study given neither sigma nor dispersion (the
#: largest of the reference studies).
DEFAULT_SIGMA = 5000.0
#: Number of realizations n_s of a study.
DEFAULT_SAMPLES = 50
#: Root seed of a study's random draws.
DEFAULT_SEED = 0

#: Default grid of an operating map: top speeds and weights-on-bit (17 × 13 points).
DEFAULT_MAP_TOP_SPEED = "40 rpm:200 rpm:17"
DEFAULT_MAP_WEIGHT_ON_BIT = "40 kN:160 kN:13"
#: Default number of base samples N of a sensitivity analysis (N(k + 2) runs for k parameters).
DEFAULT_BASE_SAMPLES = 128

#: The robust operating point (:mod:`.optimize`): the largest budget of design points (the surrogates are
#: refitted to every evaluated point before each batch, at a cost growing as the cube of their number) and of
#: realizations per design point.
MAX_OPTIMIZE_POINTS = 200
MAX_OPTIMIZE_SAMPLES = 1000
