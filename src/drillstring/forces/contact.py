"""Shocks and rubbing of the string against the borehole wall (docs/model.md §5, ``f_sh``).

At every node the string section (outer diameter ``D_o``) sits in the borehole (diameter ``D_ch``) with a
radial clearance ``g = (D_ch − D_o)/2``. With the lateral displacements ``v`` (along y) and ``w`` (along z)
of the section centre, the radial displacement is ``r = sqrt(v² + w²)`` and the outward unit normal is
``n = (v, w)/r``. When ``r > g`` the wall is penetrated by ``δ = r − g`` and (docs/model.md §5, the penalty model of
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

Distributed wall stiffness (mesh-objective contact)
---------------------------------------------------
A per-node ``k_sh`` makes the law depend on the mesh: a length ``ℓ`` of string pressed ``δ`` into the wall
pushes back ``k_sh δ`` times the number of nodes on ``ℓ``. The wall is therefore modelled as a
**distributed** stiffness ``k'_sh`` [N/m per m of string = N/m²]: the string section at ``x`` receives
``f(x) = −k'_sh (r(x) − g(x))₊ n(x)`` per unit length [N/m]. Its work-consistent nodal forces
``F_i = ∫ f N_i dx`` are integrated element by element with **nodal (trapezoidal, Lobatto) quadrature**:
each element of length ``h_e`` gives each of its two nodes ``h_e/2 · f(x_node)``, evaluated with the
element's own gap and diameter. The contact is thus carried by *stations* (:class:`ContactStations`), one
per node and adjacent section: a node inside a section has one station of tributary length
``(h_{e−1} + h_e)/2``; a node at a section change has two (``h/2`` with each section's gap), so the
collar's smaller gap does not extend half an element into the drill pipe. Station ``i`` acts as a point
spring ``k_i = k'_sh ℓ_i`` (:meth:`ContactStations.stiffness`) in :func:`distributed_contact_forces`.

Why nodal quadrature (rather than the consistent integral or Gauss points):

- it is exact for the total force of any penetration that is linear on each element (the trapezoidal
  rule), in particular for a uniform penetration over any set of whole sections, on any mesh; for a
  smooth penetration that starts and ends inside elements (a bow touching the wall) the force resultant
  and its moment converge as ``O(h²)`` (kinks included: the integrand is continuous);
- it samples the penetration where the DOFs are: no interpolation of the bending shape inside the kernel,
  no forces on the rotation DOFs, the same per-station loop as the per-node law;
- each station derives from its own convex potential ``½ k_i (r_i − g_i)₊²``, so the discrete contact is
  conservative and purely repulsive; the consistent (``∫ N_vᵀ N_v``) integration of a penalty produces
  adhesive nodal forces when an element penetrates at one end only, and Gauss points can miss a contact
  that peaks at a node (a stabilizer-supported bow, the bit).

Reading of the reference data: the reference study gives ``k_sh = 1e8 N/m`` for the shocks "per meter" of
string. It is read as the distributed stiffness ``k'_sh = 1e8 N/m per m``: one metre of string pressed
``δ`` into the wall pushes back ``1e8 δ`` N. On the default 10 m mesh an interior station then has
``k_i = 1e9 N/m`` (5e8 N/m at the bit), ten times the old per-node value, which it equals on a 1 m mesh.
Stabilizers stay point springs (:func:`drillstring.fem.assembly.stabilizer_stiffness`). The reduced model
uses this law (:mod:`drillstring.dynamics.rom`); the per-node :func:`contact_forces` remains for
comparison (the convergence benchmark shows its mesh dependence).

Decision: as written in docs/model.md §5, the friction torque uses the sign of the spin ``θ̇x`` (not of ``s``), so with
``tangential=False`` the model is exactly that one; with ``tangential=True`` the lateral force is added
and the torque is unchanged (the two differ only when the whirl velocity is comparable with the surface
speed ``θ̇x R``, e.g. in backward whirl).

The component (docs/extending.md)
---------------------------------
Borehole contact is one component of the reduced model, registered on the component protocol
(:mod:`drillstring.forces.registry`, a :class:`~drillstring.forces.registry.ContactLaw` named ``"penalty"``).
Its pieces: :class:`ContactParameters` (its keys the case's ``[contact]``, :class:`~drillstring.case.Contact`;
built from the case in one place, :meth:`ContactParameters.from_case`), the stations where the wall acts
(:class:`ContactStations`, :func:`mesh_contact_stations`: the model's geometry, not the law's numbers), the
compiled kernel :func:`penalty_contact_kernel` over the named context
:class:`~drillstring.forces.registry.ContactContext` (the station law :func:`distributed_contact_forces`), the
law at arrays of stations :func:`evaluate_contact` (:meth:`ContactParameters.evaluate_at`, which the NumPy
reference engine calls: the same kernel, not an independent reference) and its Jacobian
:func:`contact_jacobian` (:meth:`ContactParameters.jacobian_at`). The law is written once, in
:func:`_station_contact`; the tests check it against the equations above written out by hand, the
potential it derives from, the work its friction does over a revolution and a whirl, and finite
differences of the Jacobian (docs/extending.md).

Jacobian (closed form). With ``N = k (r − g)``, ``n = (n_v, n_w)``, ``t = (−n_w, n_v)``, ``∂n/∂(v, w) =
t tᵀ / r`` and ``sgn_ε'(a) = ε² / (a² + ε²)^{3/2}``, the normal force ``−N n`` has the symmetric derivative
``−(k n nᵀ + (N/r) t tᵀ)`` over ``(v, w)``; the torque ``−μ N R sgn_ε(θ̇x)`` has ``−μ R sgn_ε(θ̇x) k n``
over ``(v, w)`` and ``−μ N R sgn_ε'(θ̇x)`` over ``θ̇x``; the tangential force ``F_t t`` (``F_t = −μ N
sgn_{εR}(s)``) has ``t ∇F_t + F_t ∇t`` with ``∇F_t = −μ (sgn_{εR}(s) ∇N + N sgn_{εR}'(s) ∇s)``, ``∇N =
k n`` over ``(v, w)``, ``∂s/∂(v, w) = −(n·(v̇, ẇ)/r) t``, ``∂s/∂(v̇, ẇ) = t``, ``∂s/∂θ̇x = R`` and ``∂t/∂(v, w)
= −n tᵀ / r``. Inside the clearance every derivative is zero; at ``r = g`` exactly, where the normal
force has a kink, the derivative from inside (zero) is returned.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from drillstring.case import Contact
from drillstring.forces.registry import ContactContext, ContactLaw, register
from drillstring.forces.registry import contact_law as registered_contact_law

__all__ = [
    "ContactParameters",
    "ContactStations",
    "contact_stations",
    "mesh_contact_stations",
    "radial_gap",
    "regularized_sign",
    "contact_forces",
    "distributed_contact_forces",
    "evaluate_contact",
    "contact_jacobian",
    "case_contact",
    "penalty_contact_kernel",
    "JACOBIAN_INPUTS",
    "JACOBIAN_OUTPUTS",
]

#: Columns of :func:`contact_jacobian`: the station's lateral displacements [m] and velocities [m/s], and
#: its spin speed θ̇x [rad/s].
JACOBIAN_INPUTS = ("v", "w", "v_dot", "w_dot", "spin_speed")
#: Rows of :func:`contact_jacobian`: the contact force along y and z [N] and the torque about +x [N·m].
JACOBIAN_OUTPUTS = ("force_v", "force_w", "torque")


@njit(cache=True)
def penalty_contact_kernel(args, ctx, force_v, force_w, torque):
    """The compiled kernel of :class:`ContactParameters`: :func:`distributed_contact_forces` at the stations of
    ``ctx`` (:class:`~drillstring.forces.registry.ContactContext`) with ``args = [μ_sh, ε, tangential (1/0)]``
    (:meth:`ContactParameters.kernel_array`); fills ``force_v``, ``force_w`` [N] and ``torque`` [N·m]."""
    distributed_contact_forces(ctx.v, ctx.w, ctx.v_dot, ctx.w_dot, ctx.spin_speed, ctx.gap, ctx.outer_diameter,
                               ctx.stiffness, args[0], args[1], args[2] != 0.0, force_v, force_w, torque)


@register
@dataclass(frozen=True)
class ContactParameters(ContactLaw):
    """String–borehole contact coefficients (docs/model.md §5; reference values in §12): the contact law ``"penalty"``
    of the component protocol (module docstring).

    Attributes
    ----------
    shock_stiffness : float
        ``k'_sh`` [N/m per m of string], the wall's distributed penalty stiffness (reference 1e8): the
        reduced model (:mod:`drillstring.dynamics.rom`) gives each contact station ``k'_sh ℓ_i``
        (:meth:`ContactStations.stiffness`; module docstring). The per-node law :func:`contact_forces`
        (kept for comparison) would use the same number as a stiffness [N/m] at every node.
    friction_coefficient : float
        ``μ_sh`` [-], string–borehole friction (reference 0.0005).
    speed_regularization : float
        ``ε`` [rad/s], regularisation of the sign of the spin speed, ``sgn_ε(s) = s/sqrt(s² + ε²)``.
    tangential_friction : bool
        Add the tangential friction force on the lateral DOFs (off by default; docs/model.md §5).
    """

    name: ClassVar[str] = "penalty"
    kernel_size: ClassVar[int] = 3
    kernel: ClassVar = penalty_contact_kernel
    keys: ClassVar = Contact

    shock_stiffness: float
    friction_coefficient: float
    speed_regularization: float
    tangential_friction: bool = False

    def __post_init__(self) -> None:
        for name in ("shock_stiffness", "friction_coefficient", "speed_regularization"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")

    @classmethod
    def from_case(cls, case) -> "ContactParameters":
        """The law of a :class:`~drillstring.case.Case` (``[contact]``): the wall's distributed stiffness k'_sh
        [N/m per m], the friction coefficient, the regularisation speed and the tangential friction switch."""
        c = case.contact
        return cls(c.shock_stiffness, c.friction_coefficient, c.speed_regularization, c.tangential_friction)

    @property
    def reads_lateral_velocity(self) -> bool:
        """Only the tangential friction reads the stations' lateral velocities."""
        return bool(self.tangential_friction)

    def kernel_array(self) -> np.ndarray:
        """``[μ_sh, ε, tangential (1/0)]``, what :func:`penalty_contact_kernel` reads (the stations' stiffness
        ``k'_sh ℓ_i`` comes with the context)."""
        return np.array([self.friction_coefficient, self.speed_regularization,
                         1.0 if self.tangential_friction else 0.0], dtype=np.float64)

    def evaluate_at(self, ctx: ContactContext):
        """The kernel at the stations of ``ctx``: ``(force_v [N], force_w [N], torque [N·m])``
        (:func:`evaluate_contact`, the law's one implementation)."""
        force_v, force_w, torque, _ = evaluate_contact(ctx.v, ctx.w, ctx.v_dot, ctx.w_dot, ctx.spin_speed, ctx.gap,
                                                       ctx.outer_diameter, self, stiffness=ctx.stiffness)
        return force_v, force_w, torque

    def jacobian_at(self, ctx: ContactContext) -> np.ndarray:
        """:func:`contact_jacobian` at the stations of ``ctx``: (n, 3, 5)."""
        return contact_jacobian(ctx.v, ctx.w, ctx.v_dot, ctx.w_dot, ctx.spin_speed, ctx.gap, ctx.outer_diameter,
                                self, stiffness=ctx.stiffness)

    def evaluate(self, v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, stiffness=None):
        """:func:`evaluate_contact` of this law: ``(force_v [N], force_w [N], torque [N·m], n_contacts)``."""
        return evaluate_contact(v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, self, stiffness=stiffness)

    def jacobian(self, v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, stiffness=None) -> np.ndarray:
        """:func:`contact_jacobian` of this law: ``(n, 3, 5)``, one 3 × 5 block per node or station."""
        return contact_jacobian(v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, self, stiffness=stiffness)


def radial_gap(borehole_diameter, outer_diameter):
    """Radial clearance ``g = (D_ch − D_o)/2`` [m] from the borehole and string outer diameters [m]."""
    return 0.5 * (np.asarray(borehole_diameter, dtype=np.float64) - np.asarray(outer_diameter, dtype=np.float64))


@dataclass(frozen=True)
class ContactStations:
    """Where the distributed wall stiffness acts: nodal quadrature of each element (module docstring).

    Attributes (one entry per station, ordered by node):
        node: index of the node the station sits on (int64); a node at a section change has two stations.
        length: tributary length ℓ_i [m], half of each adjacent element of the station's section.
        gap: radial clearance (D_ch − D_o)/2 of the station's section [m].
        outer_diameter: D_o of the station's section [m].
    """

    node: np.ndarray
    length: np.ndarray
    gap: np.ndarray
    outer_diameter: np.ndarray

    def __len__(self) -> int:
        return len(self.node)

    def stiffness(self, stiffness_per_length: float) -> np.ndarray:
        """Station stiffnesses ``k_i = k'_sh ℓ_i`` [N/m] of a wall stiffness ``k'_sh`` [N/m per m]."""
        if not (math.isfinite(stiffness_per_length) and stiffness_per_length >= 0.0):
            raise ValueError(
                f"stiffness_per_length = {stiffness_per_length!r} N/m per m: must be finite and >= 0"
            )
        return stiffness_per_length * self.length

    def subset(self, keep: np.ndarray) -> ContactStations:
        """The stations where ``keep`` (one bool per station) is True."""
        keep = np.asarray(keep, dtype=bool)
        return ContactStations(self.node[keep], self.length[keep], self.gap[keep], self.outer_diameter[keep])

    def gather(self, nodal: np.ndarray) -> np.ndarray:
        """Values at the stations of a per-node array (the last axis indexes nodes)."""
        return np.asarray(nodal)[..., self.node]

    def scatter(self, values: np.ndarray, n_nodes: int) -> np.ndarray:
        """Per-node sums of per-station values (forces or torques of the stations on each node)."""
        return np.bincount(self.node, weights=np.asarray(values, dtype=float), minlength=n_nodes)


def contact_stations(nodes, element_outer_diameter, borehole_diameter) -> ContactStations:
    """Contact stations of a string by nodal quadrature of each element (module docstring).

    Args:
        nodes: node positions x [m], increasing.
        element_outer_diameter: D_o of each element [m] (one fewer than the nodes).
        borehole_diameter: D_ch [m], scalar or one per element.
    """
    x = np.asarray(nodes, dtype=np.float64)
    d_o = np.asarray(element_outer_diameter, dtype=np.float64)
    if x.ndim != 1 or len(x) < 2 or d_o.shape != (len(x) - 1,):
        raise ValueError("need node positions (n >= 2) and one outer diameter per element (n − 1)")
    h = np.diff(x)
    if np.any(h <= 0.0):
        raise ValueError("node positions must increase strictly")
    gap = np.broadcast_to(radial_gap(borehole_diameter, d_o), d_o.shape)
    if np.any(gap < 0.0):
        raise ValueError("borehole diameter must be at least the outer diameter (gap >= 0)")
    # each element gives h/2 to each of its nodes, with its own gap and diameter
    element = np.arange(len(h))
    node = np.concatenate([element, element + 1])
    half = np.concatenate([h, h]) / 2.0
    g = np.concatenate([gap, gap])
    d = np.concatenate([d_o, d_o])
    keys = np.stack([node, g, d], axis=1)
    unique, inverse = np.unique(keys, axis=0, return_inverse=True)
    length = np.bincount(inverse.ravel(), weights=half)
    return ContactStations(
        node=unique[:, 0].astype(np.int64),
        length=length,
        gap=np.ascontiguousarray(unique[:, 1]),
        outer_diameter=np.ascontiguousarray(unique[:, 2]),
    )


def mesh_contact_stations(mesh, borehole_diameter: float) -> ContactStations:
    """:func:`contact_stations` of a :class:`~drillstring.fem.mesh.Mesh` in a borehole of diameter D_ch [m]."""
    outer = np.array([mesh.sections[i].outer_diameter for i in mesh.element_section])
    return contact_stations(mesh.nodes, outer, borehole_diameter)


@njit(cache=True)
def regularized_sign(s, eps):
    """``sgn_ε(s) = s / sqrt(s² + ε²)`` (odd, continuous, ``-> ±1`` for ``|s| >> ε``; 0 at ``s = 0``)."""
    h = math.hypot(s, eps)
    if h == 0.0:
        return 0.0
    return s / h


@njit(cache=True)
def _station_contact(v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, k, mu, eps, tangential):
    """Contact force ``(f_v, f_w)`` [N] and torque [N·m] at one station of stiffness ``k`` [N/m], and
    whether it touches: the law of the module docstring, shared by every kernel."""
    r = math.hypot(v, w)
    if not (r > gap and r > 0.0):
        return 0.0, 0.0, 0.0, False
    normal = k * (r - gap)
    nv = v / r
    nw = w / r
    radius = 0.5 * outer_diameter
    fv = -normal * nv
    fw = -normal * nw
    friction = mu * normal
    torque = -friction * radius * regularized_sign(spin_speed, eps)
    if tangential:
        # slip = θ̇x R + (v ẇ − w v̇)/r ; tangent t = (−n_w, n_v); sign regularised on ε R [m/s]
        slip = spin_speed * radius + nv * w_dot - nw * v_dot
        ft = -friction * regularized_sign(slip, eps * radius)
        fv += ft * (-nw)
        fw += ft * nv
    return fv, fw, torque, True


@njit(cache=True)
def contact_forces(
    v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, k_sh, mu, eps, tangential, force_v, force_w, torque
):
    """Contact forces on the string at every node, written in place; returns the number of nodes in contact.

    Inputs (1-D float64 arrays, one entry per node): ``v``, ``w`` lateral displacements [m], ``v_dot``,
    ``w_dot`` lateral velocities [m/s], ``spin_speed`` θ̇x [rad/s], ``gap`` radial clearance
    ``(D_ch − D_o)/2`` [m], ``outer_diameter`` D_o [m]. Scalars: ``k_sh`` [N/m] (one stiffness for every
    node: the mesh-dependent per-node law; see :func:`distributed_contact_forces`), ``mu`` [-], ``eps``
    [rad/s], ``tangential`` (bool). Outputs (overwritten, no allocation): ``force_v``, ``force_w`` [N]
    along y and z, ``torque`` [N·m] about +x. Model and slip-velocity derivation in the module docstring
    (docs/model.md §5).
    """
    n_contacts = 0
    for i in range(v.shape[0]):
        fv, fw, tq, touching = _station_contact(v[i], w[i], v_dot[i], w_dot[i], spin_speed[i], gap[i],
                                                outer_diameter[i], k_sh, mu, eps, tangential)
        force_v[i] = fv
        force_w[i] = fw
        torque[i] = tq
        n_contacts += touching
    return n_contacts


@njit(cache=True)
def distributed_contact_forces(
    v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, stiffness, mu, eps, tangential, force_v, force_w,
    torque,
):
    """:func:`contact_forces` with one stiffness per station: ``stiffness`` [N/m] (1-D float64), e.g.
    :meth:`ContactStations.stiffness` of a distributed wall stiffness [N/m per m]. The other arrays hold
    one entry per station (gather node values with ``ContactStations.node``); returns the number of
    stations in contact."""
    n_contacts = 0
    for i in range(v.shape[0]):
        fv, fw, tq, touching = _station_contact(v[i], w[i], v_dot[i], w_dot[i], spin_speed[i], gap[i],
                                                outer_diameter[i], stiffness[i], mu, eps, tangential)
        force_v[i] = fv
        force_w[i] = fw
        torque[i] = tq
        n_contacts += touching
    return n_contacts


def _station_inputs(caller, v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, stiffness):
    """The inputs of :func:`evaluate_contact` and :func:`contact_jacobian` broadcast together to contiguous
    1-D float64 arrays (``stiffness`` None stays None); refuses other shapes and a negative gap."""
    inputs = [v, w, v_dot, w_dot, spin_speed, gap, outer_diameter]
    if stiffness is not None:
        inputs.append(stiffness)
    arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64)) for a in inputs))
    if arrays[0].ndim != 1:
        raise ValueError(f"{caller} expects 1-D arrays (one entry per node)")
    arrays = [np.ascontiguousarray(a) for a in arrays]
    if np.any(arrays[5] < 0.0):
        raise ValueError("gap must be >= 0 (the string is wider than the borehole)")
    return (*arrays[:7], arrays[7] if stiffness is not None else None)


def evaluate_contact(v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, params: ContactParameters,
                     stiffness=None):
    """Contact forces for arrays of nodes or stations: ``(force_v [N], force_w [N], torque [N·m], n_contacts)``.

    Array-likes are broadcast together to 1-D (``gap`` [m] and ``outer_diameter`` [m] may be scalars);
    see :func:`contact_forces` for units and the model (docs/model.md §5); the compiled kernels themselves, not an
    independent reference. Without ``stiffness`` every entry has
    ``params.shock_stiffness`` [N/m] (per-node law); with ``stiffness`` [N/m] (one per entry, e.g.
    :meth:`ContactStations.stiffness`) it replaces it (:func:`distributed_contact_forces`).
    """
    v_, w_, vd_, wd_, s_, g_, d_, k_ = _station_inputs("evaluate_contact", v, w, v_dot, w_dot, spin_speed, gap,
                                                       outer_diameter, stiffness)
    n = v_.shape[0]
    force_v = np.zeros(n)
    force_w = np.zeros(n)
    torque = np.zeros(n)
    common = (float(params.friction_coefficient), float(params.speed_regularization),
              bool(params.tangential_friction), force_v, force_w, torque)
    if stiffness is None:
        n_contacts = contact_forces(v_, w_, vd_, wd_, s_, g_, d_, float(params.shock_stiffness), *common)
    else:
        if not np.all(np.isfinite(k_) & (k_ >= 0.0)):
            raise ValueError("stiffness must be finite and >= 0 N/m at every station")
        n_contacts = distributed_contact_forces(v_, w_, vd_, wd_, s_, g_, d_, k_, *common)
    return force_v, force_w, torque, int(n_contacts)


def _sign_slope(s, eps):
    """``d sgn_ε(s)/ds = ε² / (s² + ε²)^{3/2}`` [1/(unit of s)], elementwise; 0 where ``s² + ε² = 0``
    (there :func:`regularized_sign` is 0 by convention)."""
    h2 = s * s + eps * eps
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = eps * eps / (h2 * np.sqrt(h2))
    return np.where(h2 > 0.0, slope, 0.0)


def contact_jacobian(v, w, v_dot, w_dot, spin_speed, gap, outer_diameter, params: ContactParameters,
                     stiffness=None) -> np.ndarray:
    """Jacobian of the contact law at each node or station (closed form, module docstring).

    Same inputs as :func:`evaluate_contact`. Returns ``J`` of shape ``(n, 3, 5)``: ``J[i, a, b] =
    ∂out_a/∂in_b`` with ``out`` = (force_v [N], force_w [N], torque [N·m]) (:data:`JACOBIAN_OUTPUTS`) and
    ``in`` = (v [m], w [m], v̇ [m/s], ẇ [m/s], θ̇x [rad/s]) (:data:`JACOBIAN_INPUTS`). Zero for an entry
    inside its clearance (``r ≤ g``).
    """
    v_, w_, vd, wd, spin, g, d_o, k = _station_inputs("contact_jacobian", v, w, v_dot, w_dot, spin_speed, gap,
                                                      outer_diameter, stiffness)
    if k is None:
        k = np.full(v_.shape, float(params.shock_stiffness))
    mu = float(params.friction_coefficient)
    eps = float(params.speed_regularization)
    r = np.hypot(v_, w_)
    touching = (r > g) & (r > 0.0)
    r_safe = np.where(touching, r, 1.0)
    nv = np.where(touching, v_ / r_safe, 0.0)
    nw = np.where(touching, w_ / r_safe, 0.0)
    normal = np.where(touching, k * (r - g), 0.0)
    kc = np.where(touching, k, 0.0)
    radius = 0.5 * d_o
    curvature = normal / r_safe  # N / r
    jac = np.zeros((v_.shape[0], 3, 5))
    # normal force −N n: −(k n nᵀ + (N/r) t tᵀ), t = (−n_w, n_v)
    jac[:, 0, 0] = -(kc * nv * nv + curvature * nw * nw)
    jac[:, 0, 1] = -(kc - curvature) * nv * nw
    jac[:, 1, 0] = jac[:, 0, 1]
    jac[:, 1, 1] = -(kc * nw * nw + curvature * nv * nv)
    # torque −μ N R sgn_ε(θ̇x)
    sign = spin / np.where(np.hypot(spin, eps) > 0.0, np.hypot(spin, eps), 1.0)
    jac[:, 2, 0] = -mu * radius * sign * kc * nv
    jac[:, 2, 1] = -mu * radius * sign * kc * nw
    jac[:, 2, 4] = -mu * normal * radius * _sign_slope(spin, eps)
    if params.tangential_friction:
        # slip s = θ̇x R + n_v ẇ − n_w v̇; F_t = −μ N sgn_{εR}(s); force F_t t
        slip = spin * radius + nv * wd - nw * vd
        eps_r = eps * radius
        slip_sign = slip / np.where(np.hypot(slip, eps_r) > 0.0, np.hypot(slip, eps_r), 1.0)
        f_t = -mu * normal * slip_sign
        slope = _sign_slope(slip, eps_r)
        radial_velocity = (nv * vd + nw * wd) / r_safe  # (n·(v̇, ẇ))/r
        # ∂s/∂(v, w, v̇, ẇ, θ̇x); ∂n_v/∂(v, w) = n_w (n_w, −n_v)/r, ∂n_w/∂(v, w) = −n_v (n_w, −n_v)/r
        d_slip = np.stack([nw * radial_velocity, -nv * radial_velocity, -nw, nv, radius], axis=1)
        d_normal = np.stack([kc * nv, kc * nw, 0.0 * nv, 0.0 * nv, 0.0 * nv], axis=1)
        d_ft = -mu * (d_normal * slip_sign[:, None] + (normal * slope)[:, None] * d_slip)
        d_ft = np.where(touching[:, None], d_ft, 0.0)
        # ∂t/∂(v, w) for t = (−n_w, n_v)
        dtv = np.stack([nv * nw / r_safe, -nv * nv / r_safe], axis=1)  # ∂(−n_w)/∂(v, w)
        dtw = np.stack([nw * nw / r_safe, -nv * nw / r_safe], axis=1)  # ∂n_v/∂(v, w)
        jac[:, 0, :] += -nw[:, None] * d_ft
        jac[:, 1, :] += nv[:, None] * d_ft
        jac[:, 0, :2] += f_t[:, None] * dtv
        jac[:, 1, :2] += f_t[:, None] * dtw
    return jac


def case_contact(case) -> ContactLaw:
    """The borehole contact law of a :class:`~drillstring.case.Case`: the registered law ``contact.law`` names
    (``"penalty"``: :meth:`ContactParameters.from_case`, its keys ``[contact]``)."""
    return registered_contact_law(case.contact.law, "contact.law").from_case(case)
