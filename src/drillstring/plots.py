"""Matplotlib figures of one run and of a Monte Carlo study (no physics here): every figure of
:mod:`drillstring.outputs` under one name (its modules: ``canvas``, what the figures share; ``run_plots``,
``study_plots``, ``map_plots``, ``sensitivity_plots``).

Every function takes the Datasets produced by the package (SI units) and converts to engineering units
only for the axes, in the unit system ``units`` (``"si"``: ROP in m/h, torque in kN·m, force in kN,
displacements in mm, positions in m; ``"field"``: ft/h, kft·lbf, klbf, in, ft; bit speed in rpm in both;
None: ``$DRILLSTRING_UNITS``, else si; :mod:`drillstring.units`).

Figures are drawn on :class:`matplotlib.figure.Figure` objects rendered by the Agg canvas, without
``pyplot``: nothing here changes the global Matplotlib backend or leaves figures open, so the functions
are safe in scripts, notebooks, worker processes and tests.

* :func:`plot_run` — one simulation: ROP, bit speed, radial displacement at a probe, torque-on-bit, the
  whirl orbit at the probe with the borehole wall, the contact force.
* :func:`plot_compare` — the same six panels for case 1 (full) and case 2 (bit–rock + contact) overlaid.
* :func:`plot_convergence` — mean-square convergence ``conv(n_s)`` of each observable.
* :func:`plot_envelopes` — 95 % envelope, mean and nominal response of ROP, bit speed, TOB and FOB (and,
  with a top drive, of the quill speed and the surface torque).
* :func:`plot_dispersion` — dispersion [%] of the same observables vs time, transient shaded.
* :func:`plot_study` — the three study figures in one folder.
* :func:`plot_map` — an operating map: ROP, vibration, MSE, lateral displacement over top speed × WOB, with
  the linear stability boundary, the buckling limit and the simulated points.
* :func:`plot_campbell` — a Campbell diagram: frequencies of each family vs rotary speed, excitation lines,
  critical speeds, the operating speed.
* :func:`plot_sobol` — Sobol' indices (first order and total, with confidence intervals) per output;
  :func:`plot_sobol_convergence` — the indices at N/4, N/2, N.
"""

from drillstring.outputs.canvas import TITLES, axis_unit
from drillstring.outputs.map_plots import (COEXISTING_HANDLE, MAP_PANELS, PROBABILITY_PANELS, STABILITY_PANELS,
                                           plot_map, plot_map_stability, plot_probability_map, plot_quantile_map)
from drillstring.outputs.run_plots import plot_campbell, plot_compare, plot_run, run_panels
from drillstring.outputs.sensitivity_plots import OUTPUT_TITLES, plot_sobol, plot_sobol_convergence, short_labels
from drillstring.outputs.study_plots import (STUDY_PANELS, plot_convergence, plot_dispersion, plot_envelopes,
                                             plot_realizations, plot_study)

__all__ = [
    "TITLES",
    "axis_unit",
    "COEXISTING_HANDLE",
    "MAP_PANELS",
    "PROBABILITY_PANELS",
    "STABILITY_PANELS",
    "plot_map",
    "plot_map_stability",
    "plot_probability_map",
    "plot_quantile_map",
    "plot_campbell",
    "plot_compare",
    "plot_run",
    "run_panels",
    "OUTPUT_TITLES",
    "plot_sobol",
    "plot_sobol_convergence",
    "short_labels",
    "STUDY_PANELS",
    "plot_convergence",
    "plot_dispersion",
    "plot_envelopes",
    "plot_realizations",
    "plot_study",
]
