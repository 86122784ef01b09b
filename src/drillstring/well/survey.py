"""The well path from a directional survey by the minimum-curvature method.

A survey lists stations ``(measured depth s_k, inclination I_k, azimuth A_k)`` [m, rad, rad], with the
inclination from the vertical (0 down, pi/2 horizontal, at most pi) and the azimuth clockwise from north.
The unit tangent at a station is, in (north, east, true vertical depth) coordinates,

    t = (sin I cos A, sin I sin A, cos I).                                                       (1)

Minimum curvature (Zaremba 1973; Taylor & Mason 1972; the ISCWSA's definition, Williamson 2000, SPE 67616)
joins two stations by the circular arc tangent to both. Its dogleg beta is computed from the haversine of the
two directions with ``atan2``,

    h = sin^2((I2 - I1)/2) + sin I1 sin I2 sin^2((A2 - A1)/2),   beta = 2 atan2(sqrt(h), sqrt(1 - h)),   (2)

which keeps full relative precision for doglegs of 1e-8 rad (``arccos`` of the dot product loses it below
about 1e-4 rad: ``cos beta`` rounds to 1) and is exact for azimuths given across north (the half-angle sine
squared has period 2 pi, so 359.98 deg to 0.02 deg is a 0.04 deg turn). The displacement over the arc is

    p2 - p1 = (s2 - s1)/2 (t1 + t2) RF,      RF = tan(beta/2)/(beta/2),                          (3)

with RF from its Taylor series 1 + b^2/12 + b^4/120 + 17 b^6/20160 (b = beta) below beta = 1e-3, so that a
straight section (beta = 0) is exact. A position at any depth inside an arc is (u the fraction of the course)

    t(u) = cos(u b) t1 + sin(u b)/sin(b) e,        e = t2 - cos(b) t1,
    p(u) = p1 + (s2 - s1) [ sin(u b)/b t1 + 2 sin^2(u b/2)/(b sin b) e ],                          (4)

which equals (3) at u = 1; the curvature vector of the arc is dt/ds = (b/(s2 - s1)) (-sin(u b) t1 +
cos(u b) e/sin b). Azimuth differences are wrapped to (-pi, pi] for the turn rate. Everything is in SI units.

This module imports nothing from the rest of ``drillstring`` but :mod:`drillstring.derived` (:func:`dogleg`,
which validating a case's survey also needs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drillstring.derived import dogleg

__all__ = ["Trajectory", "dogleg", "ratio_factor", "tangent", "trajectory", "wrap_angle"]

#: Below this dogleg [rad] the ratio factor is taken from its Taylor series (error < 1e-19).
_SERIES_BELOW = 1e-3


def wrap_angle(angle):
    """``angle`` [rad] wrapped to (-pi, pi]."""
    a = np.asarray(angle, dtype=float)
    wrapped = -np.remainder(-a + math.pi, 2.0 * math.pi) + math.pi
    return wrapped if wrapped.ndim else float(wrapped)


def tangent(inclination, azimuth) -> np.ndarray:
    """Unit tangent (north, east, down) of eq. (1); shape (..., 3)."""
    inc, azi = np.asarray(inclination, dtype=float), np.asarray(azimuth, dtype=float)
    return np.stack([np.sin(inc) * np.cos(azi), np.sin(inc) * np.sin(azi), np.cos(inc)], axis=-1)


def ratio_factor(beta):
    """RF = tan(beta/2)/(beta/2) of eq. (3), by its series for small beta; inf at beta = pi."""
    b = np.asarray(beta, dtype=float)
    b2 = b * b
    series = 1.0 + b2 / 12.0 + b2 * b2 / 120.0 + 17.0 * b2**3 / 20160.0
    with np.errstate(divide="ignore", invalid="ignore"):
        exact = np.tan(b / 2.0) / (b / 2.0)
    return np.where(b < _SERIES_BELOW, series, exact)


def _sin_ratio(x, b):
    """sin(x)/b with its limit x/b -> u for b -> 0 (x = u b)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(b > 0.0, np.sin(x) / np.where(b > 0.0, b, 1.0), 0.0)


@dataclass(frozen=True)
class Trajectory:
    """A well path by minimum curvature (SI units; stations in order of measured depth).

    Attributes:
        measured_depth: s_k [m], strictly increasing, starting at the surface (0).
        inclination: I_k [rad] in [0, pi].
        azimuth: A_k [rad], wrapped to [0, 2 pi).
        position: (north, east, true vertical depth) of each station [m], shape (n, 3).
        dogleg: beta of each course (n - 1) [rad].
    """

    measured_depth: np.ndarray
    inclination: np.ndarray
    azimuth: np.ndarray
    position: np.ndarray
    dogleg: np.ndarray

    @property
    def tangent(self) -> np.ndarray:
        return tangent(self.inclination, self.azimuth)

    @property
    def depth(self) -> float:
        """Measured depth of the last station [m]."""
        return float(self.measured_depth[-1])

    @property
    def true_vertical_depth(self) -> np.ndarray:
        return self.position[:, 2]

    @property
    def dogleg_severity(self) -> np.ndarray:
        """beta / course length of each course [rad/m]."""
        return self.dogleg / np.diff(self.measured_depth)

    @property
    def build_rate(self) -> np.ndarray:
        """Inclination change per length of each course [rad/m]."""
        return np.diff(self.inclination) / np.diff(self.measured_depth)

    @property
    def turn_rate(self) -> np.ndarray:
        """Azimuth change per length of each course, wrapped across north [rad/m]."""
        return wrap_angle(np.diff(self.azimuth)) / np.diff(self.measured_depth)

    def vertical_section(self, direction: float | None = None) -> np.ndarray:
        """Horizontal displacement of each station along ``direction`` [rad from north] (default: the
        direction of the last station from the wellhead) [m]."""
        if direction is None:
            north, east = self.position[-1, :2]
            direction = math.atan2(east, north) if (north or east) else 0.0
        return self.position[:, 0] * math.cos(direction) + self.position[:, 1] * math.sin(direction)

    def locate(self, depth) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Position, unit tangent and curvature vector at measured depths ``depth`` [m], eq. (4), and the
        index of the course each depth is on (a depth at a station belongs to the course below it, the last
        station to the last course). Shapes (m, 3), (m, 3), (m, 3), (m,). Raises ValueError outside the
        survey."""
        s = np.atleast_1d(np.asarray(depth, dtype=float))
        md = self.measured_depth
        if np.any(~np.isfinite(s)) or np.any(s < md[0]) or np.any(s > md[-1]):
            bad = s[~((s >= md[0]) & (s <= md[-1]))][0]
            raise ValueError(f"depth = {bad:g} m: must be within the survey, {md[0]:g} to {md[-1]:g} m")
        k = np.clip(np.searchsorted(md, s, side="right") - 1, 0, len(md) - 2)
        length = md[k + 1] - md[k]
        u = (s - md[k]) / length
        t = self.tangent
        t1, t2 = t[k], t[k + 1]
        b = self.dogleg[k]
        cos_b = np.cos(b)[:, None]
        e = t2 - cos_b * t1
        sin_b = np.sin(b)
        ub = u * b
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(b > 0.0, np.sin(ub) / np.where(b > 0.0, sin_b, 1.0), u)  # sin(u b)/sin b
            bend = np.where(b > 0.0, 2.0 * np.sin(ub / 2.0) ** 2 / np.where(b > 0.0, b * sin_b, 1.0),
                            u * u / 2.0)
        along = np.where(b > 0.0, _sin_ratio(ub, b), u)  # sin(u b)/b
        position = self.position[k] + length[:, None] * (along[:, None] * t1 + bend[:, None] * e)
        direction = np.cos(ub)[:, None] * t1 + ratio[:, None] * e
        direction /= np.linalg.norm(direction, axis=1)[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            b_over_sin = np.where(b > 0.0, b / np.where(b > 0.0, sin_b, 1.0), 1.0)
        curvature = (-(b * np.sin(ub))[:, None] * t1 + (np.cos(ub) * b_over_sin)[:, None] * e) / length[:, None]
        return position, direction, curvature, k


def trajectory(measured_depth, inclination, azimuth) -> Trajectory:
    """The minimum-curvature :class:`Trajectory` of a survey [m, rad, rad] (assumed valid: increasing
    depths from 0, inclinations in [0, pi], finite values; :func:`drillstring.case.survey_input.survey_problems`
    says why one is not). Positions by eq. (3), accumulated course by course."""
    md = np.asarray(measured_depth, dtype=float)
    inc = np.asarray(inclination, dtype=float)
    azi = np.remainder(np.asarray(azimuth, dtype=float), 2.0 * math.pi)
    beta = dogleg(inc[:-1], azi[:-1], inc[1:], azi[1:])
    t = tangent(inc, azi)
    course = np.diff(md)
    step = (course * ratio_factor(beta) / 2.0)[:, None] * (t[:-1] + t[1:])
    position = np.zeros((len(md), 3))
    position[1:] = np.cumsum(step, axis=0)
    return Trajectory(md, inc, azi, position, beta)
