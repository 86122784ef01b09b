"""Shocks and rubbing of the string against the borehole wall (SPEC §6, ``f_sh``).

At every node the string section (outer diameter ``D_o``) sits in the borehole (diameter ``D_ch``) with a
radial clearance ``g = (D_ch − D_o)/2``. With the lateral displacements ``v`` (along y) and ``w`` (along z)
of the section centre, the radial displacement is ``r = sqrt(v² + w²)`` and the outward unit normal is
``n = (v, w)/r``. When ``r > g`` the wall is penetrated by ``δ = r − g`` and (SPEC §6, the penalty model of
Ritto, Soize & Sampaio 2009)::

    normal force        F_n = k_sh δ                          [N]    on the string, along −n
    friction torque     T   = −μ F_n (D_o/2) sgn_ε(θ̇x)        [N·m]  about +x, opposing the spin
    tangential force    F_t = −μ F_n sgn_ε(s) t   (optional)  [N]    along the tangent t = (−w, v)/r

with the regularised sign ``sgn_ε(a) = a / sqrt(a² + ε²)``. The normal force derives from the penalty
potential ``½ k_sh (r − g)²`` (``F = −∇``). Inside the clearance (``r ≤ g``, including ``r = g`` exactly)
every contribution is zero.

Slip velocity of the contact point (derivation)
-----------------------------------------------
The material point of the section that touches the wall is at ``c + R n`` (``c = (v, w)`` the centre,
``R = D_o/2``). Its velocity is the centre velocity plus the spin contribution
``θ̇x x̂ × R n = θ̇x R (−n_w, n_v) = θ̇x R t`` (``x̂ × ŷ = ẑ``, ``x̂ × ẑ = −ŷ``). The wall is fixed, so the
sliding velocity along the tangent is::

    s = θ̇x R + (v̇, ẇ)·t = θ̇x D_o/2 + (v ẇ − w v̇)/r                    [m/s]

(the second term is the whirl velocity ``r φ̇`` of the centre; the radial velocity does not slide). The
tangential force opposes ``s``. Its sign is regularised on the velocity scale ``ε R`` [m/s], i.e.
``sgn_ε(s/R)`` with the same ``ε`` [rad/s] as the torque, so that ``ε`` keeps one unit.

Decision: as written in SPEC §6, the friction torque uses the sign of the spin ``θ̇x`` (not of ``s``), so with
``tangential=False`` the model is exactly the SPEC's; with ``tangential=True`` the lateral force is added
and the torque is unchanged (the two differ only when the whirl velocity is comparable with the surface
speed ``θ̇x R``, e.g. in backward whirl).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = [
    "ContactParameters",
    "radial_gap",
    "regularized_sign",
    "contact_forces",
    "evaluate_contact",
]


@dataclass(frozen=True)
class ContactParameters:
    """String–borehole contact coefficients (SPEC §6; reference values in SPEC §9).

    Attributes
    ----------
    shock_stiffness : float
        ``k_sh`` [N/m], penalty stiffness of the wall (reference 1e8 N/m).
    friction_coefficient : float
        ``μ_sh`` [-], string–borehole friction (reference 0.0005).
    speed_regularization : float
        ``ε`` [rad/s], regularisation of the sign of the spin speed, ``sgn_ε(s) = s/sqrt(s² + ε²)``.
    tangential_friction : bool
        Add the tangential friction force on the lateral DOFs (off by default; SPEC §6 "optionally").
    """

    shock_stiffness: float
    friction_coefficient: float
    speed_regularization: float
    tangential_friction: bool = False

    def __post_init__(self) -> None:
        for name in ("shock_stiffness", "friction_coefficient", "speed_regularization"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")


def radial_gap(borehole_diameter, outer_diameter):
    """Radial clearance ``g = (D_ch − D_o)/2`` [m] from the borehole and string outer diameters [m]."""
    return 0.5 * (np.asarray(borehole_diameter, dtype=np.float64) - np.asarray(outer_diameter, dtype=np.float64))


@njit(cache=True)
def regularized_sign(s, eps):
    """``sgn_ε(s) = s / sqrt(s² + ε²)`` (odd, continuous, ``-> ±1`` for ``|s| >> ε``; 0 at ``s = 0``)."""
    h = math.hypot(s, eps)
    if h == 0.0:
        return 0.0
    return s / h


@njit(cache=True)
def contact_forces(
    v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, k_sh, mu, eps, tangential, force_v, force_w, torque
):
    """Contact forces on the string at every node, written in place; returns the number of nodes in contact.

    Inputs (1-D float64 arrays, one entry per node): ``v``, ``w`` lateral displacements [m], ``v_dot``,
    ``w_dot`` lateral velocities [m/s], ``spin_speed`` θ̇x [rad/s], ``gap`` radial clearance
    ``(D_ch − D_o)/2`` [m], ``outer_diameter`` D_o [m]. Scalars: ``k_sh`` [N/m], ``mu`` [-], ``eps``
    [rad/s], ``tangential`` (bool). Outputs (overwritten, no allocation): ``force_v``, ``force_w`` [N]
    along y and z, ``torque`` [N·m] about +x. Model and slip-velocity derivation in the module docstring
    (SPEC §6).
    """
    n_contacts = 0
    for i in range(v.shape[0]):
        vi = v[i]
        wi = w[i]
        r = math.hypot(vi, wi)
        g = gap[i]
        if r > g and r > 0.0:
            n_contacts += 1
            normal = k_sh * (r - g)
            nv = vi / r
            nw = wi / r
            radius = 0.5 * outer_diameter[i]
            fv = -normal * nv
            fw = -normal * nw
            friction = mu * normal
            torque[i] = -friction * radius * regularized_sign(spin_speed[i], eps)
            if tangential:
                # slip = θ̇x R + (v ẇ − w v̇)/r ; tangent t = (−n_w, n_v); sign regularised on ε R [m/s]
                slip = spin_speed[i] * radius + nv * w_dot[i] - nw * v_dot[i]
                ft = -friction * regularized_sign(slip, eps * radius)
                fv += ft * (-nw)
                fw += ft * nv
            force_v[i] = fv
            force_w[i] = fw
        else:
            force_v[i] = 0.0
            force_w[i] = 0.0
            torque[i] = 0.0
    return n_contacts


def evaluate_contact(v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, params: ContactParameters):
    """Contact forces for arrays of nodes: ``(force_v [N], force_w [N], torque [N·m], n_contacts)``.

    Array-likes are broadcast together to 1-D (``gap`` [m] and ``outer_diameter`` [m] may be scalars);
    see :func:`contact_forces` for units and the model (SPEC §6).
    """
    arrays = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(a, dtype=np.float64)) for a in (v, w, v_dot, w_dot, spin_speed, gap, outer_diameter))
    )
    if arrays[0].ndim != 1:
        raise ValueError("evaluate_contact expects 1-D arrays (one entry per node)")
    v_, w_, vd_, wd_, s_, g_, d_ = (np.ascontiguousarray(a) for a in arrays)
    if np.any(g_ < 0.0):
        raise ValueError("gap must be >= 0 (the string is wider than the borehole)")
    n = v_.shape[0]
    force_v = np.zeros(n)
    force_w = np.zeros(n)
    torque = np.zeros(n)
    n_contacts = contact_forces(
        v_,
        w_,
        vd_,
        wd_,
        s_,
        g_,
        d_,
        float(params.shock_stiffness),
        float(params.friction_coefficient),
        float(params.speed_regularization),
        bool(params.tangential_friction),
        force_v,
        force_w,
        torque,
    )
    return force_v, force_w, torque, int(n_contacts)
