"""Campbell diagram of the prestressed string: natural frequencies of each family against the rotary
speed, the excitation lines and the critical speeds.

Layer: after :mod:`drillstring.modal` (uses its linear system and modes only).

Linear model (docs/model.md §2–§4, the system of :func:`drillstring.modal.case_linear_system`): mass ``M + M_f``
(structure and the mud's added mass), stiffness ``K + K_stab + K_g(q_S) + K_f`` (elastic, stabilizers,
prestress by the string's weight and the weight-on-bit, centrifugal compression of the mud), plus, for a
string turning at ``Ω`` [rad/s], the gyroscopic matrix ``Ω G``
(:func:`drillstring.fem.assembly.gyroscopic_matrix`, checked against the exact Campbell diagram of a
spinning Timoshenko shaft)::

    (M + M_f) q̈ + Ω G q̇ + (K + K_stab + K_g + K_f) q = 0.

* **Axial and torsional** families: ``G`` does not act on them and nothing else in the linear model
  depends on ``Ω``, so their frequencies are the same at every speed (horizontal lines; the values of
  ``drillstring modes``).
* **Lateral** family: ``G`` couples the two bending planes and splits each degenerate pair into a
  **forward** whirl (the orbit turns the way the string spins) and a **backward** one. The planes are
  identical, so with the z-plane modes taken as the y-plane ones turned by 90° (``w = v``,
  ``θy = −θz``), on the basis of the ``n`` lowest non-rotating modes of one plane (unit modal mass,
  ``ω_j²`` on the diagonal ``Λ``) the complex coordinate ``z = q_y + i q_z ∝ e^{iωt}`` obeys

      (Λ + Ω ω H − ω² I) x = 0,        H = Φ_yᵀ G Φ_z (symmetric),

  a quadratic eigenproblem with real roots: ``ω > 0`` is forward whirl, ``ω < 0`` backward. With
  ``u = Λ^{1/2} x`` it is the symmetric eigenproblem ``[[0, Λ^{1/2}], [Λ^{1/2}, Ω H]] (u, ω x) =
  ω (u, ω x)`` (``eigh``); a buckled string (some ``ω_j² < 0``) is solved as the general linearised
  problem and keeps its real roots. The basis holds every lateral mode below twice the diagram's
  highest frequency (at least 20), so truncation stays far below the gyroscopic split. The roots are solved
  exactly at a few speeds and interpolated in between with their Hellmann–Feynman slopes, every interval
  checked against an exact solution (:func:`lateral_whirl`): 3,000 speeds in about 3 s.

The fluid's Coriolis and viscous terms ``C_f`` are left out, as in ``drillstring modes`` (they damp and
shift the modes slightly but do not depend on the rotary speed); at ``Ω = 0`` the diagram gives exactly
the frequencies of ``drillstring modes``.

**Excitation lines**: order ``k`` is the frequency ``kΩ/2π`` [Hz] — ``1×`` for mass imbalance and
whirl, ``n×`` for a bit with ``n`` blades (or cones) hitting the rock each turn. A **critical speed** is
a speed where a line crosses a frequency curve: ``Ω_c = 2π f / k`` exactly for the constant axial and
torsional curves, by linear interpolation of the lateral curves between the computed speeds.

A lateral mode of a long string is either a **BHA mode** (most of its kinetic energy in the
bottom-hole assembly: every section below the top one) or a drill-pipe mode (a long wave on the pipe in
tension, hardly loading the BHA). Each lateral curve carries its ``bha_energy_share`` (share of the
structural kinetic energy of its non-rotating mode below the top section, 1 for a one-section string)
so that tables can list the BHA modes and leave the many drill-pipe modes to the JSON.

References: Lalanne & Ferraris, *Rotordynamics Prediction in Engineering* (2nd ed., 1998), ch. 2–3
(Campbell diagram, forward and backward whirl); Nelson & McVaugh, J. Eng. Ind. 98 (1976) 593
(gyroscopic matrix); Jansen, *Nonlinear Dynamics of Oilwell Drillstrings* (1993), ch. 2 (critical
speeds of drill-strings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from drillstring.fem.assembly import THETA_Y, THETA_Z, V, W, assemble_matrix, dof, gyroscopic_matrix
from drillstring.fem.element import element_mass
from drillstring.modal import LinearSystem, family_modes, family_modes_below

#: Default rotary speeds of ``drillstring campbell``: 5 to 300 rpm in steps of 5 rpm.
DEFAULT_CAMPBELL_TOP_SPEED = "5 rpm:300 rpm:60"
#: Blades (or cones) of the bit when the case does not say: a three-cone or three-bladed bit, whose 3×
#: line is the classic bit-bounce excitation of the axial family.
DEFAULT_BLADES = 3
#: Most blades accepted (PDC bits have 3 to about 12; more only multiplies the modes to compute).
MAX_BLADES = 24
#: A lateral mode is a BHA mode when at least this share of its kinetic energy lies below the top section.
BHA_SHARE = 0.5
#: The lateral basis holds every mode below this multiple of the diagram's highest frequency.
_BASIS_FACTOR = 2.0
_MIN_BASIS = 20


@dataclass(frozen=True)
class CampbellCurve:
    """One frequency curve: ``family`` ("axial", "torsional", "lateral"), ``mode`` (1-based, per family
    and whirl direction), ``whirl`` ("forward", "backward", or "" for axial and torsional),
    ``frequencies`` [Hz] at each speed of the diagram, ``bha_energy_share`` (lateral only, else None)."""

    family: str
    mode: int
    whirl: str
    frequencies: np.ndarray
    bha_energy_share: float | None = None

    @property
    def label(self) -> str:
        return f"{self.family} {self.mode}" + (f" {self.whirl}" if self.whirl else "")


@dataclass(frozen=True)
class CriticalSpeed:
    """A crossing of the excitation line of ``order`` with a curve: ``speed`` [rad/s], ``frequency`` [Hz]."""

    family: str
    mode: int
    whirl: str
    order: int
    speed: float
    frequency: float
    bha_energy_share: float | None = None

    def to_dict(self) -> dict:
        return {"family": self.family, "mode": self.mode, "whirl": self.whirl, "order": self.order,
                "speed": self.speed, "frequency": self.frequency, "bha_energy_share": self.bha_energy_share}


@dataclass(frozen=True)
class CampbellDiagram:
    """A Campbell diagram (SI: speeds [rad/s], frequencies [Hz]).

    Attributes:
        speeds: rotary speeds Ω [rad/s], ascending.
        curves: frequency curves of every family, each below ``max_frequency``.
        orders: orders of the excitation lines (1 = once per turn).
        critical_speeds: crossings of the lines with the curves, by speed.
        operating_speed: the case's top speed [rad/s] (None when not given).
        max_frequency: highest frequency shown [Hz]: the highest line's at the highest speed.
        notes: warnings, e.g. a buckled string's unstable lateral modes left out.
    """

    speeds: np.ndarray
    curves: tuple[CampbellCurve, ...]
    orders: tuple[int, ...]
    critical_speeds: tuple[CriticalSpeed, ...]
    operating_speed: float | None
    max_frequency: float
    notes: tuple[str, ...] = field(default=())

    def curve(self, family: str, mode: int, whirl: str = "") -> CampbellCurve:
        for c in self.curves:
            if (c.family, c.mode, c.whirl) == (family, mode, whirl):
                return c
        raise KeyError((family, mode, whirl))

    def to_dict(self) -> dict:
        """JSON-ready, SI: ``speeds`` [rad/s], ``curves`` (``frequencies`` [Hz]), ``critical_speeds``
        (``speed`` [rad/s], ``frequency`` [Hz]), ``orders``, ``operating_speed`` [rad/s]."""
        return {
            "speeds": [float(s) for s in self.speeds],
            "orders": list(self.orders),
            "operating_speed": self.operating_speed,
            "max_frequency": self.max_frequency,
            "bha_share_threshold": BHA_SHARE,
            "curves": [{"family": c.family, "mode": c.mode, "whirl": c.whirl,
                        "bha_energy_share": c.bha_energy_share,
                        "frequencies": [float(f) for f in c.frequencies]} for c in self.curves],
            "critical_speeds": [c.to_dict() for c in self.critical_speeds],
            "notes": list(self.notes),
        }


def bha_energy_share(system: LinearSystem, shapes: np.ndarray) -> np.ndarray:
    """Share of each mode's structural kinetic energy ``φᵀ M φ`` in the elements below the top section
    (the bottom-hole assembly); 1 for a one-section string. ``shapes``: (n_dofs, n_modes)."""
    mesh = system.mesh
    if len(mesh.sections) < 2:
        return np.ones(shapes.shape[1])
    below = mesh.element_section > 0
    m_bha = assemble_matrix(mesh.n_dofs, (element_mass(s, h) if b else np.zeros((12, 12))
                                          for s, h, b in zip(mesh.element_sections(), mesh.element_lengths, below)))
    total = np.einsum("ij,ij->j", shapes, system.structural_mass @ shapes)
    return np.einsum("ij,ij->j", shapes, m_bha @ shapes) / total


def turned_plane(mesh, shapes_y: np.ndarray) -> np.ndarray:
    """The y-plane shapes (v, θz) turned by 90° about the axis into z-plane shapes (w = v, θy = −θz)."""
    nodes = np.arange(mesh.n_nodes)
    out = np.zeros_like(shapes_y)
    out[dof(nodes, W)] = shapes_y[dof(nodes, V)]
    out[dof(nodes, THETA_Y)] = -shapes_y[dof(nodes, THETA_Z)]
    return out


#: Interpolated whirl frequencies agree with the exact roots within this share of the highest root, checked
#: at the middle of every interval between exact solutions (:func:`lateral_whirl`).
WHIRL_TOLERANCE = 1e-8
#: Exact solutions first spread evenly over the speeds (then added where the check asks for them).
_FIRST_ANCHORS = 9
#: Most speeds of one diagram (each curve holds one frequency per speed; 10,000 speeds of the reference
#: string's 600 curves are 48 MB of numbers, and a JSON of about 100 MB).
MAX_CAMPBELL_SPEEDS = 10_000


def _whirl_roots(root: np.ndarray, h: np.ndarray, spin: float) -> tuple[np.ndarray, ...]:
    """Exact forward and backward whirl roots [rad/s] at one ``spin`` (all ω_j² > 0), ascending, and their
    slopes dω/dΩ: the eigenvalues θ of ``A(Ω) = [[0, Λ^{1/2}], [Λ^{1/2}, Ω H]]`` (module docstring) and, by
    Hellmann–Feynman, ``dθ/dΩ = vᵀ (∂A/∂Ω) v = v_2ᵀ H v_2`` for each unit eigenvector ``v = (v_1, v_2)``.
    ``A`` has exactly n positive and n negative eigenvalues at every speed (its determinant, ±∏ω_j², never
    vanishes, and at Ω = 0 they are ±ω_j)."""
    n = len(root)
    a = np.zeros((2 * n, 2 * n))
    a[np.arange(n), n + np.arange(n)] = root
    a[n + np.arange(n), np.arange(n)] = root
    a[n:, n:] = spin * h
    theta, v = sla.eigh(a)
    lower = v[n:, :]
    slope = np.einsum("ik,ik->k", lower, h @ lower)
    # theta ascending: the n negative ones first (backward, -θ ascending = theta reversed), then forward.
    return theta[n:], slope[n:], -theta[:n][::-1], -slope[:n][::-1]


def _hermite(s0: float, s1: float, y0, d0, y1, d1, s: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation on [s0, s1] of values ``y`` and slopes ``d`` (arrays over the roots), at the
    speeds ``s``: one row per speed."""
    width = s1 - s0
    t = ((np.asarray(s) - s0) / width)[:, None]
    return ((2 * t**3 - 3 * t**2 + 1) * y0 + (t**3 - 2 * t**2 + t) * width * d0
            + (-2 * t**3 + 3 * t**2) * y1 + (t**3 - t**2) * width * d1)


def lateral_whirl(system: LinearSystem, speeds, basis: int, *, tolerance: float = WHIRL_TOLERANCE,
                  progress=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Forward and backward whirl angular frequencies [rad/s] of the lateral family at each spin speed
    (module docstring), on the ``basis`` lowest non-rotating modes of one plane.

    Each root is an analytic function of the speed, whose slope the eigenvector gives (Hellmann–Feynman,
    :func:`_whirl_roots`). The roots are solved exactly at a few speeds (:data:`_FIRST_ANCHORS` spread
    evenly) and interpolated in between by cubic Hermite polynomials on their values and slopes; every
    interval is checked at its middle speed against an exact solution (which joins the exact ones) and split
    until the interpolation agrees there within ``tolerance`` times the largest root. The reference string
    (320 modes per plane, 3,000 speeds) needs a few tens of exact solutions instead of 3,000. A buckled
    string (some ω_j² < 0) is solved exactly at every speed (the general linearised problem, real roots
    kept). ``progress(done, total)``, if given, is called after each exact solution (``total`` is an upper
    bound: the number of speeds).

    Returns ``(forward, backward, share, eigenvalues)``: arrays (n_speeds, basis), each row ascending (NaN
    where a root is not real: an unstable mode of a buckled string), each basis mode's BHA energy share and
    its ω² [rad²/s²] at rest (ascending, negative for an unstable mode)."""
    found = family_modes(system, "lateral_y", basis)
    phi_y = found.shapes
    n = phi_y.shape[1]
    lam = found.eigenvalues
    h = phi_y.T @ (gyroscopic_matrix(system.mesh) @ turned_plane(system.mesh, phi_y))
    h = 0.5 * (h + h.T)
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    forward = np.full((len(speeds), n), np.nan)
    backward = np.full((len(speeds), n), np.nan)
    share = bha_energy_share(system, phi_y)
    if len(speeds) == 0:
        return forward, backward, share, lam
    if np.all(lam > 0.0):
        _interpolated_whirl(np.sqrt(lam), h, speeds, forward, backward, tolerance, progress)
        return forward, backward, share, lam
    for i, spin in enumerate(speeds):
        a = np.block([[np.zeros((n, n)), np.eye(n)], [np.diag(lam), spin * h]])
        roots = np.linalg.eigvals(a)
        scale = max(1.0, float(np.abs(roots).max()))
        roots = roots[np.abs(roots.imag) <= 1e-9 * scale].real
        fwd = np.sort(roots[roots > 0.0])[:n]
        bwd = np.sort(-roots[roots < 0.0])[:n]
        forward[i, :len(fwd)] = fwd
        backward[i, :len(bwd)] = bwd
        if progress is not None:
            progress(i + 1, len(speeds))
    return forward, backward, share, lam


def _interpolated_whirl(root, h, speeds, forward, backward, tolerance, progress) -> None:
    """Fill ``forward`` and ``backward`` (rows: ``speeds``) by checked Hermite interpolation between exact
    solutions (:func:`lateral_whirl`)."""
    grid, where = np.unique(speeds, return_inverse=True)
    m = len(grid)
    exact: dict[int, tuple[np.ndarray, ...]] = {}

    def solve(i: int) -> tuple[np.ndarray, ...]:
        if i not in exact:
            exact[i] = _whirl_roots(root, h, float(grid[i]))
            if progress is not None:
                progress(len(exact), m)
        return exact[i]

    first = sorted(set(np.linspace(0, m - 1, min(m, _FIRST_ANCHORS)).round().astype(int).tolist()))
    scale = float(root.max()) * (1.0 + 1e-3)  # about the largest root (the split is a small fraction of it)
    out_f = np.empty((m, len(root)))
    out_b = np.empty((m, len(root)))
    for i in first:
        f, _, b, _ = solve(i)
        out_f[i], out_b[i] = f, b
    stack = list(zip(first[:-1], first[1:]))
    while stack:
        lo, hi = stack.pop()
        if hi - lo <= 1:
            continue
        mid = (lo + hi) // 2
        f0, df0, b0, db0 = solve(lo)
        f1, df1, b1, db1 = solve(hi)
        fm, _, bm, _ = solve(mid)
        out_f[mid], out_b[mid] = fm, bm
        guess_f = _hermite(grid[lo], grid[hi], f0, df0, f1, df1, grid[mid:mid + 1])[0]
        guess_b = _hermite(grid[lo], grid[hi], b0, db0, b1, db1, grid[mid:mid + 1])[0]
        error = max(float(np.abs(guess_f - fm).max()), float(np.abs(guess_b - bm).max()))
        if error > tolerance * scale:
            stack.extend(((lo, mid), (mid, hi)))
            continue
        for a, c in ((lo, mid), (mid, hi)):  # both halves from their exact ends: better than the checked guess
            if c - a > 1:
                fa, dfa, ba, dba = solve(a)
                fc, dfc, bc, dbc = solve(c)
                inside = grid[a + 1:c]
                out_f[a + 1:c] = _hermite(grid[a], grid[c], fa, dfa, fc, dfc, inside)
                out_b[a + 1:c] = _hermite(grid[a], grid[c], ba, dba, bc, dbc, inside)
    forward[:] = np.sort(out_f, axis=1)[where]
    backward[:] = np.sort(out_b, axis=1)[where]


def _crossings(speeds: np.ndarray, frequencies: np.ndarray, order: int) -> list[tuple[float, float]]:
    """(speed [rad/s], frequency [Hz]) where the line ``order·Ω/2π`` crosses the curve, linear between
    speeds; exact for a constant curve."""
    line = order * speeds / (2.0 * math.pi)
    gap = frequencies - line
    out = []
    if np.all(frequencies == frequencies[0]) and np.isfinite(frequencies[0]):
        speed = 2.0 * math.pi * frequencies[0] / order
        if speeds[0] <= speed <= speeds[-1] and frequencies[0] > 0.0:
            out.append((float(speed), float(frequencies[0])))
        return out
    a, b = gap[:-1], gap[1:]
    usable = np.isfinite(a) & np.isfinite(b)
    at_node = np.flatnonzero(usable & (a == 0.0))
    across = np.flatnonzero(usable & (a * b < 0.0))
    t = a[across] / (a[across] - b[across])
    crossed = speeds[across] + t * (speeds[across + 1] - speeds[across])
    found = [(int(j), float(speeds[j]), float(frequencies[j])) for j in at_node]
    found += [(int(j), float(x), float(order * x / (2.0 * math.pi))) for j, x in zip(across, crossed)]
    out = [(speed, frequency) for _, speed, frequency in sorted(found)]
    if len(speeds) and gap[-1] == 0.0:
        out.append((float(speeds[-1]), float(frequencies[-1])))
    return out


def campbell_diagram(system: LinearSystem, speeds, orders=(1, DEFAULT_BLADES), *,
                     operating_speed: float | None = None, max_frequency: float | None = None,
                     lateral_basis: int | None = None, progress=None) -> CampbellDiagram:
    """The Campbell diagram of a prestressed linear system over ``speeds`` [rad/s] (module docstring).

    ``orders``: the excitation lines; ``max_frequency`` [Hz]: the highest frequency shown (default: the
    highest line at the highest speed); ``lateral_basis``: modes of one plane in the lateral basis
    (default: every mode below twice ``max_frequency``, at least 20); ``progress(done, total)``: called
    after each exact solution of the lateral family (:func:`lateral_whirl`). At most
    :data:`MAX_CAMPBELL_SPEEDS` speeds (refused before any work)."""
    speeds = np.sort(np.atleast_1d(np.asarray(speeds, dtype=float)))
    check_speed_count(len(speeds))
    if speeds.size == 0 or not np.all(np.isfinite(speeds)) or np.any(speeds < 0.0):
        raise ValueError(f"speeds = {list(speeds[:5])!r}...: must be finite numbers >= 0 [rad/s]")
    orders = tuple(sorted({int(k) for k in orders}))
    if not orders or orders[0] < 1:
        raise ValueError(f"orders = {orders!r}: every order must be an integer >= 1")
    if max_frequency is None:
        max_frequency = orders[-1] * float(speeds[-1]) / (2.0 * math.pi)
    if not max_frequency > 0.0:
        raise ValueError(f"max_frequency = {max_frequency!r}: must be > 0 Hz")
    cutoff = 2.0 * math.pi * max_frequency
    curves: list[CampbellCurve] = []
    for family in ("axial", "torsional"):
        found = family_modes_below(system, family, 1, cutoff)
        for j, f in enumerate(found.frequencies):
            if f <= max_frequency:
                curves.append(CampbellCurve(family, j + 1, "", np.full(len(speeds), float(f))))
    if lateral_basis is None:
        lateral_basis = max(_MIN_BASIS, len(family_modes_below(system, "lateral_y", 1,
                                                                 _BASIS_FACTOR * cutoff).frequencies))
    forward, backward, share, eigenvalues = lateral_whirl(system, speeds, lateral_basis, progress=progress)
    # A buckled string's statically unstable modes (ω² < 0, listed first by `drillstring modes`) have no real
    # whirl frequency: they are left out, and the other modes keep their numbers.
    unstable = int(np.count_nonzero(eigenvalues < 0.0))
    notes = []
    if unstable:
        notes.append(f"BUCKLED: {unstable} lateral mode(s) with ω² < 0 (statically unstable at the case's "
                     "weight-on-bit) have no whirl frequency and are not drawn")
    for whirl, omega in (("forward", forward), ("backward", backward)):
        hz = omega / (2.0 * math.pi)
        for j in range(hz.shape[1]):
            finite = hz[np.isfinite(hz[:, j]), j]
            if finite.size and finite.min() <= max_frequency:
                curves.append(CampbellCurve("lateral", unstable + j + 1, whirl, hz[:, j],
                                            float(share[unstable + j])))
    critical = []
    for c in curves:
        for order in orders:
            for speed, frequency in _crossings(speeds, c.frequencies, order):
                critical.append(CriticalSpeed(c.family, c.mode, c.whirl, order, speed, frequency,
                                              c.bha_energy_share))
    critical.sort(key=lambda c: (c.speed, c.order, c.family, c.mode))
    return CampbellDiagram(speeds, tuple(curves), orders, tuple(critical), operating_speed, float(max_frequency),
                           tuple(notes))


def check_speed_count(count: int, name: str = "speeds") -> None:
    """Refuse (ValueError naming ``name``) more than :data:`MAX_CAMPBELL_SPEEDS` speeds, before any work."""
    if count > MAX_CAMPBELL_SPEEDS:
        raise ValueError(f"{name}: {count:,} speeds, more than the {MAX_CAMPBELL_SPEEDS:,} allowed (the curves "
                         f"of a diagram already look smooth with a few hundred)")


def case_campbell(case, speeds, blades: int = DEFAULT_BLADES, progress=None) -> CampbellDiagram:
    """The Campbell diagram of a :class:`~drillstring.case.Case` prestressed at its weight-on-bit, over
    ``speeds`` [rad/s], with the lines 1× and ``blades`` × and the case's top speed marked;
    ``progress(done, total)`` as :func:`campbell_diagram`'s."""
    from drillstring.modal import case_linear_system
    from drillstring.statics import case_static_state

    check_speed_count(len(np.atleast_1d(speeds)))
    system = case_linear_system(case, case_static_state(case))
    return campbell_diagram(system, speeds, (1, blades), operating_speed=float(case.operation.top_speed),
                            progress=progress)
