"""Cases shared by the tests of the well."""

from __future__ import annotations

from drillstring.case import load_case


def deviated_for_well_basis(element_length: float):
    """``deviated`` on a mesh of ``element_length`` [m] with what the well basis needs
    (``reduced_model.lateral_basis = "well"`` refuses the free–free damping and the ramped start): the
    constrained damping and the start on bottom."""
    case = load_case("deviated")
    return case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": element_length}),
                                   "damping": case.damping.model_copy(update={"basis": "constrained"}),
                                   "initial": case.initial.model_copy(update={"start": "on_bottom"})})
