"""Geometry out of the element code: the direction of each element, applied by the assembler.

An element's local matrices (:mod:`drillstring.fem.element`) are a function of its section and length only,
written in the element's own frame: ``x'`` along its axis, ``y'`` and ``z'`` across it. The assembler turns
them into the global frame (x down the hole's axis at the top, y and z across it) with one rotation per
element, ``K_e = Tᵀ K'_e T``, ``T = diag(R, R, R, R)`` over the 12 DOFs (the translations and the rotation
vector of each node transform alike under a proper rotation), ``R`` (3, 3) the direction cosines whose rows
are the element's local axes written in global coordinates (Cook, Malkus, Plesha & Witt, *Concepts and
Applications of Finite Element Analysis*, 4th ed., 2002, §2.9 and §7.2). A straight vertical string has
``R = I`` everywhere and is assembled without any rotation (bit-identical to the unrotated assembly).

The directions come from a centreline (:func:`centreline_directions`: the chords between consecutive node
positions), so a curved well can use the same mapping; :func:`direction_cosines` completes each tangent into
a right-handed frame. Rotated elements couple the axial, torsional and lateral families
(:func:`drillstring.modal.family_coupling`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["centreline_directions", "direction_cosines", "rotate_element_matrices"]


def centreline_directions(points) -> np.ndarray:
    """Unit tangent of each element (n_nodes − 1, 3) from the node positions ``points`` (n_nodes, 3) [m] of a
    centreline: the chord from node e to node e + 1. ValueError for coincident nodes."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 2:
        raise ValueError(f"points: must be (n_nodes >= 2, 3) positions, got shape {points.shape}")
    chords = np.diff(points, axis=0)
    lengths = np.linalg.norm(chords, axis=1)
    if not np.all(lengths > 0.0):
        raise ValueError(f"points: nodes {int(np.argmin(lengths))} and {int(np.argmin(lengths)) + 1} coincide")
    return chords / lengths[:, None]


def direction_cosines(tangents) -> np.ndarray:
    """The rotations R (n_el, 3, 3) from global to element coordinates of elements along the unit ``tangents``
    (n_el, 3): row 0 the tangent, row 2 the unit ``t × ŷ`` (``t × ẑ`` when the tangent is within 1e-8 of ŷ),
    row 1 = row 2 × row 0. A tangent along +x gives R = I exactly."""
    t = np.asarray(tangents, dtype=float)
    if t.ndim != 2 or t.shape[1] != 3:
        raise ValueError(f"tangents: must be (n_elements, 3), got shape {t.shape}")
    norm = np.linalg.norm(t, axis=1)
    if not np.all(np.abs(norm - 1.0) < 1e-9):
        raise ValueError(f"tangents: must be unit vectors, got norms from {norm.min():.6g} to {norm.max():.6g}")
    lateral = np.cross(t, [0.0, 1.0, 0.0])
    small = np.linalg.norm(lateral, axis=1) < 1e-8
    lateral[small] = np.cross(t[small], [0.0, 0.0, 1.0])
    lateral /= np.linalg.norm(lateral, axis=1)[:, None]
    return np.stack([t, np.cross(lateral, t), lateral], axis=1)


def rotate_element_matrices(local: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """``Tᵀ K' T`` for each element (module docstring): ``local`` (n_el, 12, 12) in element coordinates,
    ``rotations`` (n_el, 3, 3) from :func:`direction_cosines`; returns the (n_el, 12, 12) global matrices."""
    n_el = local.shape[0]
    blocks = local.reshape(n_el, 4, 3, 4, 3)
    rotated = np.einsum("eji,eajbk,ekl->eaibl", rotations, blocks, rotations)
    return rotated.reshape(n_el, 12, 12)
