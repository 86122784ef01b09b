"""The 2-node, 12-DOF Timoshenko beam element (pure functions of a section and a length).

Nodal DOFs, in this order at each node (docs/model.md §1; numbered in :mod:`drillstring.fem.dofs`): axial
``u``, lateral ``v`` (y), lateral ``w`` (z), torsion ``θx``, bending rotations ``θy``, ``θz``. Element
DOFs 0–5 belong to the first (upper) node, 6–11 to the second.

Interpolation (docs/model.md §2):

- ``u`` and ``θx``: linear.
- bending: the shear-locking-free *interdependent* interpolation of Friedman & Kosmatka,
  "An improved two-node Timoshenko beam finite element", Computers & Structures 47 (1993) 473–481:
  cubic displacement and quadratic rotation that solve the homogeneous Timoshenko equations exactly,
  parametrised by ``Φ = 12 EI / (k_s G A L²)``.

In the x–y plane the pair is (v, θz) with θz = ∂v/∂x − γ; in the x–z plane the pair is (w, θy) with
θy = −(∂w/∂x − γ) (right-hand rule). Both planes therefore use the same planar matrices, the x–z ones
conjugated by ``S = diag(1, −1, 1, −1)``.

Every matrix is obtained by Gauss–Legendre quadrature of the shape functions (4 points, exact for the
polynomial degrees involved, including a linearly varying axial force), so mass, stiffness, geometric
stiffness and the fluid matrices of :mod:`drillstring.fem.fluid` all share one interpolation.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from drillstring.fem.dofs import (  # noqa: F401  (element-local DOF sets, named in fem.dofs)
    AXIAL_DOFS,
    BENDING_Y_DOFS,
    BENDING_Z_DOFS,
    DOFS_PER_ELEMENT,
    TORSION_DOFS,
)
from drillstring.fem.sections import BeamSection
#: Sign change that maps the x–y planar matrices onto the x–z plane (θy = −∂w/∂x).
PLANE_Z_SIGNS = np.array([1.0, -1.0, 1.0, -1.0])

N_GAUSS = 4


@lru_cache(maxsize=8)
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre points on [0, 1] and their weights."""
    points, weights = np.polynomial.legendre.leggauss(n)
    return 0.5 * (points + 1.0), 0.5 * weights


def shear_parameter(section: BeamSection, length: float) -> float:
    """Φ = 12 EI / (k_s G A L²) [-], the ratio of bending to shear flexibility."""
    return 12.0 * section.bending_stiffness / (section.shear_stiffness * length**2)


@dataclass(frozen=True)
class PlanarShapes:
    """Bending shape functions of one plane sampled at the Gauss points.

    Arrays have shape (n_gauss, 4), columns for the planar DOFs (v1, ψ1, v2, ψ2), ψ the section rotation
    (θz in the x–y plane). ``weights`` already include the Jacobian (sum to the length).
    """

    xi: np.ndarray  # (n_gauss,) positions ξ = x/L
    weights: np.ndarray  # (n_gauss,) quadrature weights × L [m]
    displacement: np.ndarray  # N_v [-, m]
    slope: np.ndarray  # ∂N_v/∂x [1/m, -]
    rotation: np.ndarray  # N_ψ [1/m, -]
    curvature: np.ndarray  # ∂N_ψ/∂x [1/m², 1/m]


def planar_shapes(length: float, phi: float, n_gauss: int = N_GAUSS) -> PlanarShapes:
    """Friedman–Kosmatka interdependent shape functions and derivatives at the Gauss points.

    With ξ = x/L and Φ the shear parameter (Friedman & Kosmatka 1993, eqs. 17–18)::

        N_v = [2ξ³−3ξ²−Φξ+1+Φ,  L(ξ³−(2+Φ/2)ξ²+(1+Φ/2)ξ),  −2ξ³+3ξ²+Φξ,  L(ξ³−(1−Φ/2)ξ²−(Φ/2)ξ)] / (1+Φ)
        N_ψ = [6(ξ²−ξ)/L,  3ξ²−(4+Φ)ξ+1+Φ,  −6(ξ²−ξ)/L,  3ξ²−(2−Φ)ξ] / (1+Φ)
    """
    xi, w = _gauss(n_gauss)
    L = length
    d = 1.0 + phi
    x2, x3 = xi**2, xi**3
    one = np.ones_like(xi)
    displacement = np.stack(
        [
            2 * x3 - 3 * x2 - phi * xi + 1 + phi,
            L * (x3 - (2 + phi / 2) * x2 + (1 + phi / 2) * xi),
            -2 * x3 + 3 * x2 + phi * xi,
            L * (x3 - (1 - phi / 2) * x2 - (phi / 2) * xi),
        ],
        axis=1,
    ) / d
    slope = np.stack(
        [
            (6 * x2 - 6 * xi - phi) / L,
            3 * x2 - 2 * (2 + phi / 2) * xi + (1 + phi / 2),
            (-6 * x2 + 6 * xi + phi) / L,
            3 * x2 - 2 * (1 - phi / 2) * xi - phi / 2,
        ],
        axis=1,
    ) / d
    rotation = np.stack(
        [
            6 * (x2 - xi) / L,
            3 * x2 - (4 + phi) * xi + (1 + phi) * one,
            -6 * (x2 - xi) / L,
            3 * x2 - (2 - phi) * xi,
        ],
        axis=1,
    ) / d
    curvature = np.stack(
        [
            6 * (2 * xi - 1) / L**2,
            (6 * xi - (4 + phi)) / L,
            -6 * (2 * xi - 1) / L**2,
            (6 * xi - (2 - phi)) / L,
        ],
        axis=1,
    ) / d
    return PlanarShapes(xi, w * L, displacement, slope, rotation, curvature)


def _frozen(function):
    """Cache a pure matrix function of hashable arguments (sections are frozen dataclasses); the
    cached arrays are made read-only so no caller can alter them."""

    @lru_cache(maxsize=4096)
    def cached(*args):
        result = function(*args)
        for array in result if isinstance(result, tuple) else (result,):
            array.setflags(write=False)
        return result

    cached.__doc__ = function.__doc__
    cached.__name__ = function.__name__
    cached.__wrapped__ = function
    return cached


def _integrate(weights: np.ndarray, left: np.ndarray, right: np.ndarray, density=1.0) -> np.ndarray:
    """∫ density(x) leftᵀ right dx by quadrature; ``density`` scalar or one value per Gauss point."""
    return np.einsum("g,gi,gj->ij", weights * np.broadcast_to(density, weights.shape), left, right)


# --- planar (one bending plane) matrices -------------------------------------------------------------


@_frozen
def bending_stiffness(section: BeamSection, length: float) -> np.ndarray:
    """Planar Timoshenko stiffness ∫ EI ψ'ᵀψ' + k_s G A (v' − ψ)ᵀ(v' − ψ) dx, 4×4 [N/m, N, N·m]."""
    s = planar_shapes(length, shear_parameter(section, length))
    shear_strain = s.slope - s.rotation
    return section.bending_stiffness * _integrate(s.weights, s.curvature, s.curvature) + (
        section.shear_stiffness * _integrate(s.weights, shear_strain, shear_strain)
    )


@_frozen
def bending_mass(section: BeamSection, length: float) -> np.ndarray:
    """Planar consistent mass ∫ ρA N_vᵀN_v + ρI N_ψᵀN_ψ dx, 4×4 (translational + rotary inertia)."""
    s = planar_shapes(length, shear_parameter(section, length))
    rho_i = section.density * section.second_moment
    return section.mass_per_length * _integrate(s.weights, s.displacement, s.displacement) + (
        rho_i * _integrate(s.weights, s.rotation, s.rotation)
    )


def bending_geometric_stiffness(
    section: BeamSection, length: float, axial_force_start: float, axial_force_end: float
) -> np.ndarray:
    """Planar geometric stiffness ∫ N(x) N_v'ᵀ N_v' dx (docs/model.md §2), 4×4.

    ``N(x)`` [N], tension positive, varies linearly from ``axial_force_start`` (upper node) to
    ``axial_force_end`` (lower node), as it does under gravity. Being linear in N, it is
    ``N_start G_start + N_end G_end`` with the cached unit matrices of :func:`_unit_geometric`.
    """
    g_start, g_end = _unit_geometric(section, length)
    return axial_force_start * g_start + axial_force_end * g_end


@_frozen
def _unit_geometric(section: BeamSection, length: float) -> tuple[np.ndarray, np.ndarray]:
    """(∫(1 − ξ) N_v'ᵀN_v' dx, ∫ξ N_v'ᵀN_v' dx): geometric stiffness of unit end forces."""
    s = planar_shapes(length, shear_parameter(section, length))
    return (_integrate(s.weights, s.slope, s.slope, 1.0 - s.xi),
            _integrate(s.weights, s.slope, s.slope, s.xi))


# --- axial and torsion ------------------------------------------------------------------------------


def _linear_pair(stiffness_coefficient: float, inertia_per_length: float, length: float):
    k = stiffness_coefficient / length * np.array([[1.0, -1.0], [-1.0, 1.0]])
    m = inertia_per_length * length / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    return k, m


@_frozen
def axial_matrices(section: BeamSection, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear bar element: (EA/L [[1,−1],[−1,1]], ρAL/6 [[2,1],[1,2]])."""
    return _linear_pair(section.axial_stiffness, section.mass_per_length, length)


@_frozen
def torsion_matrices(section: BeamSection, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear shaft element: (G I_p/L [[1,−1],[−1,1]], ρ I_p L/6 [[2,1],[1,2]])."""
    return _linear_pair(
        section.torsional_stiffness, section.density * section.polar_moment, length
    )


# --- 12 × 12 element matrices -----------------------------------------------------------------------


def place_planar(planar: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Put a planar 4×4 matrix in both bending planes of a 12×12 element matrix (adds to ``out``)."""
    if out is None:
        out = np.zeros((DOFS_PER_ELEMENT, DOFS_PER_ELEMENT))
    out[np.ix_(BENDING_Y_DOFS, BENDING_Y_DOFS)] += planar
    out[np.ix_(BENDING_Z_DOFS, BENDING_Z_DOFS)] += PLANE_Z_SIGNS[:, None] * planar * PLANE_Z_SIGNS
    return out


def _element_matrix(planar: np.ndarray, section: BeamSection, length: float, kind: int):
    """Both bending planes plus the axial and torsion pairs (``kind`` 0: stiffness, 1: mass)."""
    matrix = place_planar(planar)
    matrix[np.ix_(AXIAL_DOFS, AXIAL_DOFS)] += axial_matrices(section, length)[kind]
    matrix[np.ix_(TORSION_DOFS, TORSION_DOFS)] += torsion_matrices(section, length)[kind]
    return matrix


@_frozen
def element_stiffness(section: BeamSection, length: float) -> np.ndarray:
    """Elastic stiffness [K_e], 12×12, symmetric positive semi-definite (6 rigid-body modes)."""
    return _element_matrix(bending_stiffness(section, length), section, length, 0)


@_frozen
def element_mass(section: BeamSection, length: float) -> np.ndarray:
    """Consistent mass [M_e], 12×12: translational, rotary (ρI) and polar (ρI_p) inertia."""
    return _element_matrix(bending_mass(section, length), section, length, 1)


def element_geometric_stiffness(
    section: BeamSection, length: float, axial_force_start: float, axial_force_end: float
) -> np.ndarray:
    """Geometric stiffness [K_g,e], 12×12, from the static axial force (tension positive) [N]."""
    return place_planar(
        bending_geometric_stiffness(section, length, axial_force_start, axial_force_end)
    )


@_frozen
def polar_rotary_inertia(section: BeamSection, length: float) -> np.ndarray:
    """Planar ``R = ρI_p ∫ N_ψᵀ N_ψ dx``, 4×4 [kg·m², kg·m, kg] (DOFs v1, ψ1, v2, ψ2)."""
    s = planar_shapes(length, shear_parameter(section, length))
    return section.density * section.polar_moment * _integrate(s.weights, s.rotation, s.rotation)


@_frozen
def element_gyroscopic(section: BeamSection, length: float) -> np.ndarray:
    """Gyroscopic matrix [G_e], 12×12, skew-symmetric, per unit spin speed [kg·m²/rad]: a string
    spinning at Ω [rad/s] about +x gets ``Ω G q̇`` on the left-hand side of its lateral equations
    (``M q̈ + Ω G q̇ + K q = f``).

    Derivation: a section tilted by the small bending rotations (θy, θz) has its axis along
    ``n = (1, θz, −θy)``; its spin about that axis is ``θ̇x + θ̇y θz`` to second order (rotation
    sequence θy then θz then θx; other sequences differ by ``d(θyθz)/dt``, which gives no force at
    constant Ω). The kinetic energy ``½ ρI_p (Ω + θ̇y θz)²`` has the gyroscopic part
    ``T_G = Ω ∫ ρI_p θ̇y θz dx``, and Lagrange's equations give the moments ``+ρI_p Ω θ̇z`` on θy and
    ``−ρI_p Ω θ̇y`` on θz (the rate of change of the spin angular momentum ``ρI_p Ω n``). With
    ``θz = N_ψ q_y``, ``θy = −N_ψ S q_z`` (module docstring) and ``R`` = :func:`polar_rotary_inertia`::

        G[y, z] = R S,    G[z, y] = −S R = −G[y, z]ᵀ

    (Nelson & McVaugh, J. Eng. Ind. 98 (1976) 593, eq. for the gyroscopic matrix, in this element's
    interpolation and DOF signs). With Ω > 0 it raises forward whirl (orbit y → z, with the spin)
    and lowers backward whirl.
    """
    r = polar_rotary_inertia(section, length)
    rs = r * PLANE_Z_SIGNS  # R S
    out = np.zeros((DOFS_PER_ELEMENT, DOFS_PER_ELEMENT))
    out[np.ix_(BENDING_Y_DOFS, BENDING_Z_DOFS)] = rs
    out[np.ix_(BENDING_Z_DOFS, BENDING_Y_DOFS)] = -rs.T
    return out


def element_gravity_load(mass_per_length: float, length: float, gravity: float) -> np.ndarray:
    """Consistent nodal loads of a uniform axial weight ρ_eff A g [N/m] along +x (down): ½ each node."""
    f = np.zeros(DOFS_PER_ELEMENT)
    f[AXIAL_DOFS] = 0.5 * mass_per_length * gravity * length
    return f
