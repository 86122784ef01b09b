"""Physical constants shared by the whole package (SI units).

This module imports nothing; every part of ``drillstring`` that needs one of these numbers reads it here.
"""

from __future__ import annotations

__all__ = ["STANDARD_GRAVITY"]

#: Standard acceleration of gravity g_n [m/s^2], exact by definition (3rd CGPM, 1901; ISO 80000-3). It is the
#: default of a case's ``environment.gravity`` and the g that defines the pound-force and the kilogram-force
#: (1 lbf = 0.45359237 kg x g_n), so that a string of ``w`` lb/ft weighs ``w`` lbf per foot in air.
STANDARD_GRAVITY = 9.80665
