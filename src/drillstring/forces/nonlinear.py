"""Case-1 nonlinear forces of the beam model: strain-energy forces ``f_se`` and kinetic-energy forces ``f_ke``.

docs/model.md §5 (``f_NL = f_ke + f_se + f_sh + f_br``); the model is that of Ritto, Soize & Sampaio, "Non-linear
dynamics of a drill-string with uncertain model of the bit–rock interaction", Int. J. Non-Linear Mech. 44
(2009) 865–876, whose axial–lateral coupling through the strain ``u' + ½(v'² + w'²)`` follows Sampaio,
Piovan & Venero Lozano, "Coupled axial/torsional vibrations of drill-strings by means of non-linear model",
Mech. Res. Comm. 34 (2007) 497–502. SI units throughout: displacements [m], rotations [rad], velocities
[m/s, rad/s], forces [N] on translational DOFs, moments [N·m] on rotational DOFs, energies [J].

Interpolation (the one of :mod:`drillstring.fem.element`)
----------------------------------------------------------
Element DOFs ``[u1, v1, w1, θx1, θy1, θz1, u2, …, θz2]``. ``u`` and ``θx`` are linear; ``(v, θz)`` use the
interdependent Timoshenko shapes ``N_v`` (displacement) and ``N_ψ`` (rotation) of
:func:`~drillstring.fem.element.planar_shapes` on ``(v1, θz1, v2, θz2)``; ``(w, θy)`` use the same shapes on
``S q_w = (w1, −θy1, w2, −θy2)``: ``w = N_v S q_w``, ``θy = −N_ψ S q_w``. Integrals are evaluated by
Gauss–Legendre quadrature with :data:`N_GAUSS_NL` = 6 points, exact for every integrand here (the quartic
strain energy has degree 8 in ``x``, 5 points suffice).

Strain-energy forces ``f_se`` — no double counting of the prestress
--------------------------------------------------------------------
The axial strain is ``ε = u' + ½(v'² + w'²)`` (moderate rotations) and the axial strain energy
``U = ½ ∫ EA ε² dx``. The response is written about the prestressed, straight static state (docs/model.md §1, §3):
``u = u_S + ū``, ``v = v̄``, ``w = w̄`` (static ``v = w = 0``), with static axial force ``N(x) = EA u_S'``.
With ``s = v'² + w'²``::

    ½ EA ε² = ½ EA u_S'²  +  N ū'                     (static energy; balanced by gravity + bit reaction)
            + ½ EA ū'²                                 -> [K]   (axial part of the elastic stiffness)
            + ½ N s                                    -> [K_g] = ∫ N (N_v'ᵀN_v' + N_w'ᵀN_w') dx
            + ½ EA ū' s + ⅛ EA s²                      =: U_nl(q̄)   (this module)

so the nonlinear strain energy **not already in the linear model** is::

    U_nl(q̄) = ∫ [ ½ EA ū' (v'² + w'²) + ⅛ EA (v'² + w'²)² ] dx,       f_se = −∂U_nl/∂q̄

(quadratic + cubic in ``q̄``). ``ū`` must be measured from the static state: if the static stretch were
included in ``ū`` (``ū' = N/EA``), the Hessian of ``U_nl`` at ``v = w = 0`` would be exactly ``[K_g]`` and
the prestress would be counted twice (this identity is tested). Pure axial motion, torsion and rigid
translations give ``f_se = 0``; an infinitesimal rigid rotation (``v = αx``) gives a force of order ``α³``.

Kinetic-energy forces ``f_ke`` — choice of ``T_nl``
---------------------------------------------------
The small-angle kinetic energy of the section rotation is
``T_rot = ½ ∫ [ρI_p (θ̇x − θ̇z θy)² + ρI (θ̇y² + θ̇z²)] dx``: with the section turned by θz about z, then θy
about the new y axis, then θx about its own axis, the spin about the tilted axis is
``ω_x'' = θ̇x − θ̇z sin θy`` (``ẑ·x̂'' = −sin θy``, ``ŷ'·x̂'' = 0``); here ``θy = −∂w/∂x`` and ``θz = ∂v/∂x``. (The
other order of the two bending rotations gives ``θ̇x + θ̇y θz``; the two differ by ``d(θy θz)/dt``, so at a
constant spin they give the same forces.) Its quadratic part ``½ρI_p θ̇x² + ½ρI(θ̇y² + θ̇z²)`` is in the
consistent mass matrix. **Decision:** as in Ritto, Soize & Sampaio (2009) we keep only the cubic term and
drop the quartic ``½ ρI_p θ̇z² θy²``::

    T_nl(q, q̇) = −∫ ρI_p θ̇x θ̇z θy dx

Linearised at the spin ``θ̇x = Ω`` its forces are ``−Ω G q̇``, ``G`` the gyroscopic matrix of
:func:`drillstring.fem.element.element_gyroscopic` (checked against the exact Campbell diagram of a spinning
shaft and the rate of spin angular momentum); the opposite sign would stiffen backward instead of forward
whirl (tested).

Reasons: (i) docs/model.md §5 calls ``f_ke`` *quadratic*; the quartic term would add cubic forces of the same order
as the terms already discarded by the small-angle expansion itself (e.g. the ``O(θ²θ̇²)`` corrections of the
bending rotary inertia), so keeping it would not improve consistency; (ii) it keeps ``T_nl`` linear in
``q``, so ``f_vel`` depends on ``q̇`` only and the projected mass correction is linear in the modal
coordinates (see :func:`modal_mass_coupling`). Here ``θ̇x`` is the **total** spin speed: callers pass ``q̇``
with the imposed top speed ``Ω`` added to every ``θ̇x`` DOF; ``θx`` itself never appears undifferentiated.

Lagrange's equations with ``T_nl = ½ q̇ᵀ M_nl(q) q̇`` give ``f_ke = −(d/dt ∂T_nl/∂q̇ − ∂T_nl/∂q)``::

    f_ke = f_vel(q̇) − M_nl(q) q̈
    M_nl(q) = −∫ ρI_p θy (a bᵀ + b aᵀ) dx                  (symmetric; couples θx with the (v, θz) plane)
    f_vel   = ∫ ρI_p [ θ̇y θ̇z a + θ̇y θ̇x b − θ̇x θ̇z c ] dx

with the shape vectors ``a = ∂θx/∂q``, ``b = ∂θz/∂q``, ``c = ∂θy/∂q`` at each point. The terms
``−ρI_p θ̇x θ̇z`` (on θy) and ``ρI_p θ̇x θ̇y`` (on θz) are the gyroscopic moments (skew, no power); the others
transfer energy between spin and whirl. ``M_nl`` couples the torsional acceleration with bending
(``−ρI_p θy θ̈z`` on θx, ``−ρI_p θy θ̈x`` on θz).

**Acceleration terms in the explicit scheme.** The reduced model moves ``M_nl`` to the left-hand side:
with ``q̄ = Φη`` and ``Φᵀ(M + M_f)Φ = I``, at each right-hand-side evaluation it solves
``(I + Φᵀ M_nl(q) Φ) η̈ = Φᵀ(f_vel + f_se + …) − D η̇ − Ω² η``, which is exact (no lag, no iteration) because
``M_nl`` depends on the configuration only. :func:`project_mass_correction` forms ``Φᵀ M_nl Φ`` from the
per-element couplings, or :func:`modal_mass_coupling` forms it from ``η`` directly (it is linear in ``η``,
and for a basis of family modes only its torsion × lateral-y block is not zero).

Small-angle validity
--------------------
``ε`` neglects ``½u'²`` and is accurate while slopes ``|v'|, |w'| ≪ 1``; with lateral displacements
bounded by the radial gap (~0.04 m) the slopes stay ~1e-2 and the error of ``ε`` is ``O(v'⁴)``.
``θ̇x − θ̇z θy`` is the spin rate to second order in the bending angles; at 0.1 rad the neglected terms are
~0.5 %. Every force here is a polynomial of the DOFs, hence finite and smooth for any state; the total mass
``M + M_nl`` stays positive definite for ``|θy| < sqrt(I/I_p) = 1/√2`` rad (pointwise sufficient condition),
far beyond the range where the model is meaningful.

Fast evaluators
---------------
:class:`NonlinearElements` (built by :func:`nonlinear_elements`) stores per element and Gauss point the
shape-function values and the coefficients ``EA`` and ``ρI_p``; its methods call ``numba.njit(cache=True)``
kernels that write into preallocated outputs and allocate nothing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from numba import njit

from drillstring.fem.assembly import assemble_matrix
from drillstring.fem.dofs import (
    AXIAL_DOFS,
    BENDING_Y_DOFS,
    BENDING_Z_DOFS,
    DOFS_PER_ELEMENT,
    DOFS_PER_NODE,
    THETA_X1,
    THETA_X2,
    THETA_Y1,
    THETA_Y2,
    THETA_Z1,
    THETA_Z2,
    TORSION_DOFS,
    U1,
    U2,
    V1,
    V2,
    W1,
    W2,
    element_dofs,
)
from drillstring.fem.element import PLANE_Z_SIGNS, planar_shapes, shear_parameter
from drillstring.fem.mesh import Mesh
from drillstring.fem.sections import BeamSection

__all__ = [
    "N_GAUSS_NL",
    "element_strain_energy",
    "element_strain_energy_force",
    "element_strain_energy_tangent",
    "element_kinetic_energy_nl",
    "element_kinetic_force",
    "NonlinearElements",
    "nonlinear_elements",
    "expand_mass_coupling",
    "element_rows",
    "project_mass_correction",
    "modal_mass_coupling",
]

#: Gauss points per element for the nonlinear forces (≥ 5 needed for the quartic strain energy).
N_GAUSS_NL = 6


# --- element level: reference implementation (NumPy) ------------------------------------------------


@dataclass(frozen=True)
class _ElementOperators:
    """Shape vectors of one element at the Gauss points: each row maps the 12 element DOFs to a field."""

    weights: np.ndarray  # (g,) quadrature weights × L [m]
    axial_strain: np.ndarray  # (12,) ∂u'/∂q [1/m]
    slope_v: np.ndarray  # (g, 12) ∂v'/∂q
    slope_w: np.ndarray  # (g, 12) ∂w'/∂q
    torsion: np.ndarray  # (g, 12) a = ∂θx/∂q
    rotation_z: np.ndarray  # (g, 12) b = ∂θz/∂q
    rotation_y: np.ndarray  # (g, 12) c = ∂θy/∂q


@lru_cache(maxsize=256)
def _operators(section: BeamSection, length: float) -> _ElementOperators:
    if not length > 0:
        raise ValueError(f"length = {length!r}: must be > 0 m")
    s = planar_shapes(length, shear_parameter(section, length), N_GAUSS_NL)
    n = len(s.xi)
    axial = np.zeros(DOFS_PER_ELEMENT)
    axial[AXIAL_DOFS] = [-1.0 / length, 1.0 / length]
    slope_v = np.zeros((n, DOFS_PER_ELEMENT))
    slope_v[:, BENDING_Y_DOFS] = s.slope
    slope_w = np.zeros((n, DOFS_PER_ELEMENT))
    slope_w[:, BENDING_Z_DOFS] = s.slope * PLANE_Z_SIGNS
    torsion = np.zeros((n, DOFS_PER_ELEMENT))
    torsion[:, TORSION_DOFS] = np.stack([1.0 - s.xi, s.xi], axis=1)
    rot_z = np.zeros((n, DOFS_PER_ELEMENT))
    rot_z[:, BENDING_Y_DOFS] = s.rotation
    rot_y = np.zeros((n, DOFS_PER_ELEMENT))
    rot_y[:, BENDING_Z_DOFS] = -s.rotation * PLANE_Z_SIGNS
    ops = _ElementOperators(s.weights, axial, slope_v, slope_w, torsion, rot_z, rot_y)
    for a in (ops.weights, axial, slope_v, slope_w, torsion, rot_z, rot_y):
        a.setflags(write=False)
    return ops


def _as_element_vector(q, name: str) -> np.ndarray:
    q = np.asarray(q, dtype=np.float64)
    if q.shape != (DOFS_PER_ELEMENT,):
        raise ValueError(f"{name} must have shape (12,), got {q.shape}")
    return q


def element_strain_energy(q_e, section: BeamSection, length: float) -> float:
    """Nonlinear strain energy ``U_nl`` [J] of one element (module docstring; docs/model.md §5).

    ``U_nl = ∫ [½ EA ū' (v'² + w'²) + ⅛ EA (v'² + w'²)²] dx`` — the part of ``½∫EA ε²`` not in ``[K]`` and
    ``[K_g]`` (Ritto, Soize & Sampaio 2009; Sampaio, Piovan & Venero Lozano 2007).

    Args:
        q_e: (12,) element DOFs measured from the static state [m, rad].
        section: the element's cross-section.
        length: element length [m].
    """
    q = _as_element_vector(q_e, "q_e")
    op = _operators(section, float(length))
    du = op.axial_strain @ q
    s = (op.slope_v @ q) ** 2 + (op.slope_w @ q) ** 2
    return float(section.axial_stiffness * op.weights @ (0.5 * du * s + 0.125 * s * s))


def element_strain_energy_force(q_e, section: BeamSection, length: float) -> np.ndarray:
    """Strain-energy force ``f_se = −∂U_nl/∂q`` (12,) [N, N·m] of one element (quadratic + cubic).

    ``∂U_nl/∂q = ∫ EA [½ s ∂u'/∂q + (ū' + ½ s)(v' ∂v'/∂q + w' ∂w'/∂q)] dx``, ``s = v'² + w'²``.
    Arguments as :func:`element_strain_energy`.
    """
    q = _as_element_vector(q_e, "q_e")
    op = _operators(section, float(length))
    du = op.axial_strain @ q
    vp = op.slope_v @ q
    wp = op.slope_w @ q
    s = vp * vp + wp * wp
    ea_w = section.axial_stiffness * op.weights
    h = vp[:, None] * op.slope_v + wp[:, None] * op.slope_w  # ½ ∂s/∂q
    grad = (0.5 * ea_w @ s) * op.axial_strain + (ea_w * (du + 0.5 * s)) @ h
    return -grad


def element_strain_energy_tangent(q_e, section: BeamSection, length: float) -> np.ndarray:
    """Tangent ``∂²U_nl/∂q²`` (12, 12) [N/m, N, N·m] of one element (symmetric; ``= −∂f_se/∂q``).

    ``∫ EA [B hᵀ + h Bᵀ + h hᵀ + (ū' + ½ s)(g_v g_vᵀ + g_w g_wᵀ)] dx`` with ``B = ∂u'/∂q``,
    ``g_v = ∂v'/∂q``, ``g_w = ∂w'/∂q``, ``h = v' g_v + w' g_w``. At ``v = w = 0`` and ``ū' = N/EA`` its lateral
    block is ``[K_g]`` for the uniform force ``N``. Arguments as :func:`element_strain_energy`.
    """
    q = _as_element_vector(q_e, "q_e")
    op = _operators(section, float(length))
    du = op.axial_strain @ q
    vp = op.slope_v @ q
    wp = op.slope_w @ q
    s = vp * vp + wp * wp
    ea_w = section.axial_stiffness * op.weights
    h = vp[:, None] * op.slope_v + wp[:, None] * op.slope_w
    hb = np.outer(ea_w @ h, op.axial_strain)
    hh = np.einsum("g,gi,gj->ij", ea_w, h, h)
    coef = ea_w * (du + 0.5 * s)
    gg = np.einsum("g,gi,gj->ij", coef, op.slope_v, op.slope_v) + np.einsum(
        "g,gi,gj->ij", coef, op.slope_w, op.slope_w
    )
    return hb + hb.T + hh + gg


def element_kinetic_energy_nl(q_e, qd_e, section: BeamSection, length: float) -> float:
    """Nonlinear kinetic energy ``T_nl = −∫ ρI_p θ̇x θ̇z θy dx`` [J] of one element (module docstring).

    Args:
        q_e: (12,) element DOFs [m, rad] (only θy enters).
        qd_e: (12,) element velocities [m/s, rad/s], ``θ̇x`` the TOTAL spin speed (imposed Ω included).
        section: the element's cross-section.
        length: element length [m].
    """
    q = _as_element_vector(q_e, "q_e")
    qd = _as_element_vector(qd_e, "qd_e")
    op = _operators(section, float(length))
    k = section.density * section.polar_moment * op.weights
    return -float(k @ ((op.torsion @ qd) * (op.rotation_z @ qd) * (op.rotation_y @ q)))


def element_kinetic_force(q_e, qd_e, section: BeamSection, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic-energy force of one element, ``f_ke = f_vel − m_nl q̈`` (module docstring).

    Returns:
        ``(f_vel, m_nl)``: ``f_vel`` (12,) [N, N·m], the velocity-dependent (quadratic) forces
        ``∫ ρI_p [θ̇y θ̇z a + θ̇y θ̇x b − θ̇x θ̇z c] dx``; ``m_nl`` (12, 12) [kg, kg·m, kg·m²], the symmetric
        configuration-dependent mass correction ``−∫ ρI_p θy (a bᵀ + b aᵀ) dx`` (``T_nl = ½ q̇ᵀ m_nl q̇``).
        Arguments as :func:`element_kinetic_energy_nl`.
    """
    q = _as_element_vector(q_e, "q_e")
    qd = _as_element_vector(qd_e, "qd_e")
    op = _operators(section, float(length))
    k = section.density * section.polar_moment * op.weights
    txd = op.torsion @ qd
    tzd = op.rotation_z @ qd
    tyd = op.rotation_y @ qd
    ty = op.rotation_y @ q
    f_vel = (k * tyd * tzd) @ op.torsion + (k * tyd * txd) @ op.rotation_z - (k * txd * tzd) @ op.rotation_y
    ab = np.einsum("g,gi,gj->ij", -k * ty, op.torsion, op.rotation_z)
    return f_vel, ab + ab.T


# --- global evaluators (Numba kernels) --------------------------------------------------------------


@njit(cache=True)
def _strain_energy_forces_kernel(q, inv_length, weights, slope, axial_stiffness, out):
    """out[:] = f_se(q) (global); see :func:`element_strain_energy_force`."""
    n_el, n_g = weights.shape
    out[:] = 0.0
    for e in range(n_el):
        b = DOFS_PER_NODE * e
        du = (q[b + U2] - q[b + U1]) * inv_length[e]
        v0, v1, v2, v3 = q[b + V1], q[b + THETA_Z1], q[b + V2], q[b + THETA_Z2]
        w0, w1, w2, w3 = q[b + W1], -q[b + THETA_Y1], q[b + W2], -q[b + THETA_Y2]
        fu = 0.0
        fv0 = fv1 = fv2 = fv3 = 0.0
        fw0 = fw1 = fw2 = fw3 = 0.0
        for g in range(n_g):
            s0, s1, s2, s3 = slope[e, g, 0], slope[e, g, 1], slope[e, g, 2], slope[e, g, 3]
            vp = s0 * v0 + s1 * v1 + s2 * v2 + s3 * v3
            wp = s0 * w0 + s1 * w1 + s2 * w2 + s3 * w3
            ss = vp * vp + wp * wp
            ea_w = axial_stiffness[e] * weights[e, g]
            fu += 0.5 * ea_w * ss
            c = ea_w * (du + 0.5 * ss)
            cv = c * vp
            cw = c * wp
            fv0 += cv * s0
            fv1 += cv * s1
            fv2 += cv * s2
            fv3 += cv * s3
            fw0 += cw * s0
            fw1 += cw * s1
            fw2 += cw * s2
            fw3 += cw * s3
        fu *= inv_length[e]
        out[b + U1] += fu
        out[b + U2] -= fu
        out[b + V1] -= fv0
        out[b + THETA_Z1] -= fv1
        out[b + V2] -= fv2
        out[b + THETA_Z2] -= fv3
        out[b + W1] -= fw0
        out[b + THETA_Y1] += fw1
        out[b + W2] -= fw2
        out[b + THETA_Y2] += fw3
    # nothing returned: a kernel compiled inside a caller without reference counting must not hand an array back


@njit(cache=True)
def _strain_energy_kernel(q, inv_length, weights, slope, axial_stiffness):
    n_el, n_g = weights.shape
    total = 0.0
    for e in range(n_el):
        b = DOFS_PER_NODE * e
        du = (q[b + U2] - q[b + U1]) * inv_length[e]
        v0, v1, v2, v3 = q[b + V1], q[b + THETA_Z1], q[b + V2], q[b + THETA_Z2]
        w0, w1, w2, w3 = q[b + W1], -q[b + THETA_Y1], q[b + W2], -q[b + THETA_Y2]
        acc = 0.0
        for g in range(n_g):
            s0, s1, s2, s3 = slope[e, g, 0], slope[e, g, 1], slope[e, g, 2], slope[e, g, 3]
            vp = s0 * v0 + s1 * v1 + s2 * v2 + s3 * v3
            wp = s0 * w0 + s1 * w1 + s2 * w2 + s3 * w3
            ss = vp * vp + wp * wp
            acc += weights[e, g] * (0.5 * du * ss + 0.125 * ss * ss)
        total += axial_stiffness[e] * acc
    return total


@njit(cache=True)
def _kinetic_forces_kernel(q, qd, xi, weights, rotation, polar_inertia, out, coupling):
    """out[:] = f_vel(q̇); coupling[e, i, j] = M_nl,e[TORSION_DOFS[i], BENDING_Y_DOFS[j]]."""
    n_el, n_g = weights.shape
    out[:] = 0.0
    for e in range(n_el):
        b = DOFS_PER_NODE * e
        ta, tb = qd[b + THETA_X1], qd[b + THETA_X2]
        vd0, vd1, vd2, vd3 = qd[b + V1], qd[b + THETA_Z1], qd[b + V2], qd[b + THETA_Z2]
        wd0, wd1, wd2, wd3 = qd[b + W1], -qd[b + THETA_Y1], qd[b + W2], -qd[b + THETA_Y2]
        w0, w1, w2, w3 = q[b + W1], -q[b + THETA_Y1], q[b + W2], -q[b + THETA_Y2]
        fx0 = fx1 = 0.0
        fz0 = fz1 = fz2 = fz3 = 0.0  # on the (v, θz) planar DOFs
        fy0 = fy1 = fy2 = fy3 = 0.0  # on the (w, −θy) planar DOFs
        c00 = c01 = c02 = c03 = c10 = c11 = c12 = c13 = 0.0
        for g in range(n_g):
            r0, r1, r2, r3 = rotation[e, g, 0], rotation[e, g, 1], rotation[e, g, 2], rotation[e, g, 3]
            l1 = xi[g]
            l0 = 1.0 - l1
            k = polar_inertia[e] * weights[e, g]
            txd = l0 * ta + l1 * tb
            tzd = r0 * vd0 + r1 * vd1 + r2 * vd2 + r3 * vd3
            tyd = -(r0 * wd0 + r1 * wd1 + r2 * wd2 + r3 * wd3)
            ty = -(r0 * w0 + r1 * w1 + r2 * w2 + r3 * w3)
            # θy-part: −k θ̇x θ̇z c, c = −N_ψ S on the w plane
            p = k * txd * tzd
            fy0 += p * r0
            fy1 += p * r1
            fy2 += p * r2
            fy3 += p * r3
            # θx-part: k θ̇y θ̇z a
            p = k * tyd * tzd
            fx0 += p * l0
            fx1 += p * l1
            # θz-part: k θ̇y θ̇x b
            p = k * tyd * txd
            fz0 += p * r0
            fz1 += p * r1
            fz2 += p * r2
            fz3 += p * r3
            # mass coupling −k θy a bᵀ
            p = -k * ty
            c00 += p * l0 * r0
            c01 += p * l0 * r1
            c02 += p * l0 * r2
            c03 += p * l0 * r3
            c10 += p * l1 * r0
            c11 += p * l1 * r1
            c12 += p * l1 * r2
            c13 += p * l1 * r3
        out[b + THETA_X1] += fx0
        out[b + THETA_X2] += fx1
        out[b + V1] += fz0
        out[b + THETA_Z1] += fz1
        out[b + V2] += fz2
        out[b + THETA_Z2] += fz3
        out[b + W1] += fy0
        out[b + THETA_Y1] -= fy1
        out[b + W2] += fy2
        out[b + THETA_Y2] -= fy3
        coupling[e, 0, 0] = c00
        coupling[e, 0, 1] = c01
        coupling[e, 0, 2] = c02
        coupling[e, 0, 3] = c03
        coupling[e, 1, 0] = c10
        coupling[e, 1, 1] = c11
        coupling[e, 1, 2] = c12
        coupling[e, 1, 3] = c13
    # nothing returned: a kernel compiled inside a caller without reference counting must not hand an array back


@njit(cache=True)
def _mass_coupling_kernel(q, xi, weights, rotation, polar_inertia, coupling):
    """coupling[e, i, j] = −∫ ρI_p θy a_i b_j (depends on the configuration only)."""
    n_el, n_g = weights.shape
    for e in range(n_el):
        b = DOFS_PER_NODE * e
        w0, w1, w2, w3 = q[b + W1], -q[b + THETA_Y1], q[b + W2], -q[b + THETA_Y2]
        for i in range(2):
            for j in range(4):
                coupling[e, i, j] = 0.0
        for g in range(n_g):
            r0, r1, r2, r3 = rotation[e, g, 0], rotation[e, g, 1], rotation[e, g, 2], rotation[e, g, 3]
            ty = -(r0 * w0 + r1 * w1 + r2 * w2 + r3 * w3)
            p = -polar_inertia[e] * weights[e, g] * ty
            for i in range(2):
                pl = p * (xi[g] if i == 1 else 1.0 - xi[g])
                for j in range(4):
                    coupling[e, i, j] += pl * rotation[e, g, j]
    # nothing returned: a kernel compiled inside a caller without reference counting must not hand an array back


@njit(cache=True)
def _kinetic_energy_kernel(q, qd, xi, weights, rotation, polar_inertia):
    n_el, n_g = weights.shape
    total = 0.0
    for e in range(n_el):
        b = DOFS_PER_NODE * e
        ta, tb = qd[b + THETA_X1], qd[b + THETA_X2]
        vd0, vd1, vd2, vd3 = qd[b + V1], qd[b + THETA_Z1], qd[b + V2], qd[b + THETA_Z2]
        w0, w1, w2, w3 = q[b + W1], -q[b + THETA_Y1], q[b + W2], -q[b + THETA_Y2]
        acc = 0.0
        for g in range(n_g):
            r0, r1, r2, r3 = rotation[e, g, 0], rotation[e, g, 1], rotation[e, g, 2], rotation[e, g, 3]
            txd = (1.0 - xi[g]) * ta + xi[g] * tb
            tzd = r0 * vd0 + r1 * vd1 + r2 * vd2 + r3 * vd3
            ty = -(r0 * w0 + r1 * w1 + r2 * w2 + r3 * w3)
            acc += weights[e, g] * txd * tzd * ty
        total -= polar_inertia[e] * acc
    return total


@njit(cache=True)
def _project_coupling_kernel(coupling, phi_elements, out, work):
    """out = Σ_e Φ_eᵀ M_nl,e Φ_e for the compact couplings (n_el, 2, 4); work (2, n) scratch."""
    n_el = coupling.shape[0]
    n = phi_elements.shape[2]
    out[:, :] = 0.0
    for e in range(n_el):
        # work[i, :] = Σ_j c_ij Φ_e[plane-y DOF j, :]
        for i in range(2):
            c0, c1, c2, c3 = coupling[e, i, 0], coupling[e, i, 1], coupling[e, i, 2], coupling[e, i, 3]
            for m in range(n):
                work[i, m] = (
                    c0 * phi_elements[e, V1, m]
                    + c1 * phi_elements[e, THETA_Z1, m]
                    + c2 * phi_elements[e, V2, m]
                    + c3 * phi_elements[e, THETA_Z2, m]
                )
        for m in range(n):
            t0 = phi_elements[e, THETA_X1, m]
            t1 = phi_elements[e, THETA_X2, m]
            x0 = work[0, m]
            x1 = work[1, m]
            if t0 == 0.0 and t1 == 0.0 and x0 == 0.0 and x1 == 0.0:
                continue  # mode m has neither torsion nor θy-coupled bending here (row m is zero)
            for k in range(n):
                out[m, k] += (t0 * work[0, k] + t1 * work[1, k] + x0 * phi_elements[e, THETA_X1, k]
                              + x1 * phi_elements[e, THETA_X2, k])
    # nothing returned: a kernel compiled inside a caller without reference counting must not hand an array back


@njit(cache=True)
def _project_blocks_kernel(blocks, phi_elements, out, work):
    """out = Σ_e Φ_eᵀ B_e Φ_e for generic (n_el, 12, 12) blocks; work (12, n) scratch."""
    n_el = blocks.shape[0]
    n = phi_elements.shape[2]
    out[:, :] = 0.0
    for e in range(n_el):
        for i in range(DOFS_PER_ELEMENT):
            for m in range(n):
                acc = 0.0
                for j in range(DOFS_PER_ELEMENT):
                    acc += blocks[e, i, j] * phi_elements[e, j, m]
                work[i, m] = acc
        for i in range(DOFS_PER_ELEMENT):
            for m in range(n):
                p = phi_elements[e, i, m]
                if p != 0.0:
                    for k in range(n):
                        out[m, k] += p * work[i, k]
    # nothing returned: a kernel compiled inside a caller without reference counting must not hand an array back


@dataclass(eq=False)
class NonlinearElements:
    """Per-element, per-Gauss-point data for the global ``f_se`` and ``f_ke`` kernels (module docstring).

    Attributes:
        n_dofs: global DOF count (6 per node, numbering ``6·node + k``).
        inv_length: (n_el,) 1/L_e [1/m].
        xi: (g,) Gauss abscissae ξ = x/L on [0, 1] (linear shapes ``1 − ξ``, ``ξ`` for u, θx).
        weights: (n_el, g) quadrature weights × L_e [m].
        slope: (n_el, g, 4) planar ``∂N_v/∂x`` on (v1, ψ1, v2, ψ2).
        rotation: (n_el, g, 4) planar ``N_ψ``.
        axial_stiffness: (n_el,) EA [N].
        polar_inertia: (n_el,) ρI_p [kg·m].

    The ``(w, θy)`` plane uses the same planar arrays through ``S = diag(1, −1, 1, −1)``.
    """

    n_dofs: int
    inv_length: np.ndarray
    xi: np.ndarray
    weights: np.ndarray
    slope: np.ndarray
    rotation: np.ndarray
    axial_stiffness: np.ndarray
    polar_inertia: np.ndarray
    _coupling: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._coupling = np.zeros((self.n_elements, 2, 4))

    @property
    def n_elements(self) -> int:
        return self.weights.shape[0]

    # strain energy ------------------------------------------------------------------------------

    def strain_energy_forces(self, q: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Write the global ``f_se(q̄)`` (n_dofs,) [N, N·m] into ``out`` and return it (no allocation).

        ``q`` (n_dofs,) float64: displacements from the static state [m, rad].
        """
        _strain_energy_forces_kernel(q, self.inv_length, self.weights, self.slope, self.axial_stiffness, out)
        return out

    def strain_energy(self, q: np.ndarray) -> float:
        """Global ``U_nl(q̄)`` [J]."""
        return _strain_energy_kernel(q, self.inv_length, self.weights, self.slope, self.axial_stiffness)

    # kinetic energy -----------------------------------------------------------------------------

    def kinetic_forces(
        self, q: np.ndarray, qd: np.ndarray, out_force: np.ndarray, out_coupling: np.ndarray | None = None
    ) -> np.ndarray:
        """Write ``f_vel(q̇)`` (n_dofs,) into ``out_force``; return the mass couplings (n_el, 2, 4).

        ``qd``'s θ̇x DOFs must hold the TOTAL spin speed (Ω added). The returned array ``c`` gives the
        configuration-dependent mass correction element by element:
        ``M_nl,e[TORSION_DOFS[i], BENDING_Y_DOFS[j]] = M_nl,e[BENDING_Y_DOFS[j], TORSION_DOFS[i]] = c[e, i, j]``
        (all other entries zero; :func:`expand_mass_coupling` gives the 12×12 blocks, and
        :func:`project_mass_correction` the projected ``Φᵀ M_nl Φ``). ``f_ke = f_vel − M_nl q̈``. Without
        ``out_coupling`` an internal buffer is reused (overwritten by the next call).
        """
        coupling = self._coupling if out_coupling is None else out_coupling
        _kinetic_forces_kernel(
            q, qd, self.xi, self.weights, self.rotation, self.polar_inertia, out_force, coupling
        )
        return coupling

    def mass_coupling(self, q: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The mass couplings (n_el, 2, 4) [kg·m, kg·m²] of ``M_nl(q)`` alone (see :meth:`kinetic_forces`)."""
        coupling = self._coupling if out is None else out
        _mass_coupling_kernel(q, self.xi, self.weights, self.rotation, self.polar_inertia, coupling)
        return coupling

    def mass_correction_matrix(self, q: np.ndarray) -> sp.csr_matrix:
        """Global sparse ``M_nl(q)`` (n_dofs × n_dofs); for checks and small problems, allocates."""
        blocks = expand_mass_coupling(self.mass_coupling(q, np.zeros((self.n_elements, 2, 4))))
        return assemble_matrix(self.n_dofs, blocks)

    def kinetic_energy_nl(self, q: np.ndarray, qd: np.ndarray) -> float:
        """Global ``T_nl(q, q̇)`` [J] (θ̇x total spin speed)."""
        return _kinetic_energy_kernel(q, qd, self.xi, self.weights, self.rotation, self.polar_inertia)


def nonlinear_elements(mesh: Mesh, n_gauss: int = N_GAUSS_NL) -> NonlinearElements:
    """Precompute the shape functions and coefficients of every element of ``mesh`` (SI units)."""
    if n_gauss < 5:
        raise ValueError(f"n_gauss = {n_gauss!r}: the quartic strain energy needs at least 5 points")
    sections = mesh.element_sections()
    lengths = mesh.element_lengths
    n_el = len(lengths)
    weights = np.empty((n_el, n_gauss))
    slope = np.empty((n_el, n_gauss, 4))
    rotation = np.empty((n_el, n_gauss, 4))
    xi = None
    for e, (section, h) in enumerate(zip(sections, lengths)):
        s = planar_shapes(float(h), shear_parameter(section, float(h)), n_gauss)
        weights[e] = s.weights
        slope[e] = s.slope
        rotation[e] = s.rotation
        xi = s.xi
    return NonlinearElements(
        n_dofs=mesh.n_dofs,
        inv_length=np.ascontiguousarray(1.0 / lengths, dtype=np.float64),
        xi=np.ascontiguousarray(xi, dtype=np.float64),
        weights=weights,
        slope=slope,
        rotation=rotation,
        axial_stiffness=np.array([s.axial_stiffness for s in sections], dtype=np.float64),
        polar_inertia=np.array([s.density * s.polar_moment for s in sections], dtype=np.float64),
    )


# --- projection helpers -----------------------------------------------------------------------------


def expand_mass_coupling(coupling: np.ndarray) -> np.ndarray:
    """The (n_el, 12, 12) element blocks of ``M_nl`` from the compact couplings (n_el, 2, 4)."""
    coupling = np.asarray(coupling, dtype=np.float64)
    blocks = np.zeros((coupling.shape[0], DOFS_PER_ELEMENT, DOFS_PER_ELEMENT))
    blocks[:, TORSION_DOFS[:, None], BENDING_Y_DOFS[None, :]] = coupling
    blocks[:, BENDING_Y_DOFS[:, None], TORSION_DOFS[None, :]] = np.swapaxes(coupling, 1, 2)
    return blocks


def element_rows(phi: np.ndarray, n_elements: int | None = None) -> np.ndarray:
    """(n_el, 12, n) contiguous rows of a basis ``Φ`` (n_dofs, n) for each element's 12 DOFs."""
    phi = np.asarray(phi, dtype=np.float64)
    n_el = phi.shape[0] // DOFS_PER_NODE - 1 if n_elements is None else n_elements
    return np.ascontiguousarray(np.stack([phi[element_dofs(e)] for e in range(n_el)]))


def project_mass_correction(
    blocks: np.ndarray, phi_elements: np.ndarray, out: np.ndarray | None = None, work: np.ndarray | None = None
) -> np.ndarray:
    """``Φᵀ M_nl Φ`` (n, n) from per-element mass blocks and the element rows of ``Φ`` (n_el, 12, n).

    ``blocks`` is either the compact coupling (n_el, 2, 4) returned by
    :meth:`NonlinearElements.kinetic_forces` (fast path, ``4 n²`` flops per element) or generic 12×12 blocks
    (n_el, 12, 12). Pass ``out`` (n, n) and ``work`` ((2, n) compact / (12, n) generic) to avoid allocation.
    """
    n = phi_elements.shape[2]
    if out is None:
        out = np.empty((n, n))
    if blocks.shape[1:] == (2, 4):
        if work is None:
            work = np.empty((2, n))
        _project_coupling_kernel(blocks, phi_elements, out, work)
        return out
    if blocks.shape[1:] == (12, 12):
        if work is None:
            work = np.empty((12, n))
        _project_blocks_kernel(blocks, phi_elements, out, work)
        return out
    raise ValueError(f"blocks must have shape (n_el, 2, 4) or (n_el, 12, 12), got {blocks.shape}")


def modal_mass_coupling(elements: NonlinearElements, torsional: np.ndarray, bending_y: np.ndarray,
                        bending_z: np.ndarray) -> np.ndarray:
    """The projected mass correction of a basis whose modes each live on one family, as a tensor.

    ``M_nl(q)`` couples the torsion ``θx`` with the (v, θz) bending plane, with a coefficient linear in ``θy``
    (module docstring). For a basis of torsional modes ``Ψ`` (n_dofs, n_t), lateral-y modes ``Φ_y`` (on v, θz)
    and lateral-z modes ``Φ_z`` (on w, θy) — axial modes take no part —, ``Φᵀ M_nl(Φη) Φ`` is therefore zero but
    for the torsion × lateral-y block ``B(η) = Σ_k η_z,k T_k`` and its transpose, with
    ``T_k = Ψᵀ M_nl(φ_z,k) Φ_y``. Returns ``T`` (n_z, n_t, n_y).
    """
    torsional = np.asarray(torsional, dtype=np.float64)
    bending_y = np.asarray(bending_y, dtype=np.float64)
    bending_z = np.asarray(bending_z, dtype=np.float64)
    n_t, n_y, n_z = torsional.shape[1], bending_y.shape[1], bending_z.shape[1]
    rows = element_rows(np.hstack([torsional, bending_y]), elements.n_elements)
    tensor = np.empty((n_z, n_t, n_y))
    coupling = np.empty((elements.n_elements, 2, 4))
    block = np.empty((n_t + n_y, n_t + n_y))
    work = np.empty((2, n_t + n_y))
    for k in range(n_z):
        elements.mass_coupling(np.ascontiguousarray(bending_z[:, k]), coupling)
        _project_coupling_kernel(coupling, rows, block, work)
        tensor[k] = block[:n_t, n_t:]
    return tensor
