"""Deviated wells: the well path from a survey (minimum curvature), soft-string torque and drag, buckling
in inclined and curved holes, and the calibration of friction factors from measured hook loads.

Layer: after :mod:`drillstring.case`, :mod:`drillstring.units` and :mod:`drillstring.fem.sections`; nothing
here imports plotting or the command line. See ``docs/torque_drag.md``.
"""
