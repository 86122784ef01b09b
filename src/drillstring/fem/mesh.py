"""Nodes and elements along the string.

``x`` is the axial coordinate pointing down from the hook (``x = 0``) to the bit (``x = L``), in m.
Nodes are placed exactly at section changes and at any requested point (stabilizers, output probes);
each interval between such points is cut into equal elements no longer than ``max_element_length``
(:func:`drillstring.derived.mesh_breaks` and :func:`~drillstring.derived.element_counts`, which the case
validation uses too).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from drillstring.derived import POSITION_TOLERANCE, element_counts, mesh_breaks
from drillstring.fem.dofs import DOFS_PER_NODE
from drillstring.fem.sections import BeamSection


@dataclass(frozen=True)
class Mesh:
    """A 1-D mesh of 2-node beam elements.

    Attributes:
        nodes: node positions x [m], increasing from 0 to L.
        sections: the distinct sections, top to bottom.
        element_section: index into ``sections`` for each element.
    """

    nodes: np.ndarray
    sections: tuple[BeamSection, ...]
    element_section: np.ndarray

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_elements(self) -> int:
        return len(self.nodes) - 1

    @property
    def n_dofs(self) -> int:
        return DOFS_PER_NODE * len(self.nodes)

    @property
    def length(self) -> float:
        """Total string length L [m]."""
        return float(self.nodes[-1])

    @property
    def element_lengths(self) -> np.ndarray:
        return np.diff(self.nodes)

    def element_sections(self) -> list[BeamSection]:
        return [self.sections[i] for i in self.element_section]

    def node_index(self, x: float) -> int:
        """Index of the node at position ``x`` [m]; ValueError if no node is there."""
        i = int(np.argmin(np.abs(self.nodes - x)))
        if abs(self.nodes[i] - x) > 1e-6 * max(1.0, self.length):
            raise ValueError(
                f"no node at x = {x!r} m (nearest node at {self.nodes[i]:.6g} m); "
                "pass the position to build_mesh(extra_points=...)"
            )
        return i

    def node_section(self) -> np.ndarray:
        """Section index per node: the element below it (the last node takes the last element's)."""
        return np.append(self.element_section, self.element_section[-1])


def build_mesh(
    section_lengths: Sequence[float],
    sections: Sequence[BeamSection],
    max_element_length: float,
    extra_points: Sequence[float] = (),
) -> Mesh:
    """Mesh a string of consecutive sections (top first).

    Args:
        section_lengths: length of each section [m], top to bottom.
        sections: the section of each piece.
        max_element_length: upper bound on element length [m].
        extra_points: positions [m] that must be nodes (stabilizers, probes).
    """
    if len(section_lengths) != len(sections) or not sections:
        raise ValueError("need one length per section and at least one section")
    if not max_element_length > 0:
        raise ValueError(f"max_element_length = {max_element_length!r}: must be > 0 m")
    if any(not length > 0 for length in section_lengths):
        raise ValueError(f"section lengths {list(section_lengths)!r}: each must be > 0 m")
    boundaries = np.concatenate([[0.0], np.cumsum(section_lengths)])
    total = boundaries[-1]
    for x in extra_points:
        if not -POSITION_TOLERANCE <= x <= total + POSITION_TOLERANCE:
            raise ValueError(f"point x = {x!r} m lies outside the string [0, {total:g}] m")
    breaks = mesh_breaks(section_lengths, extra_points)

    nodes = [0.0]
    element_section = []
    for start, end, n in zip(breaks[:-1], breaks[1:], element_counts(breaks, max_element_length)):
        nodes.extend(np.linspace(start, end, n + 1)[1:])
        middle = 0.5 * (start + end)
        index = int(np.searchsorted(boundaries, middle) - 1)
        element_section.extend([index] * n)
    return Mesh(
        nodes=np.asarray(nodes),
        sections=tuple(sections),
        element_section=np.asarray(element_section, dtype=int),
    )
