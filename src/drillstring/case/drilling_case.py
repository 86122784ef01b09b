"""The :class:`Case`: the whole tree of tables, the inputs converted with the whole case (components, flow
rate), the quantities derived from it and its cross-field rules, and its TOML text.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import tomli_w
from pydantic import Field, model_validator

from drillstring.case.base import _Base
from drillstring.case.bounds import (
    MAX_DESCRIPTION_LENGTH,
    MAX_ELEMENTS,
    MAX_NAME_LENGTH,
    PHYSICAL_BOUNDS,
    _bound_problems,
)
from drillstring.case.component_tables import DownholeMotor, StringFriction, _from_components, _motor_problems
from drillstring.case.errors import _Problems
from drillstring.case.estimator_table import Estimator
from drillstring.case.tables import (
    BitRock,
    Borehole,
    Bow,
    Contact,
    Damping,
    Environment,
    Fluid,
    Initial,
    Material,
    Mesh,
    Model,
    Operation,
    ReducedModel,
    Section,
    Simulation,
    Stabilizer,
    TopDrive,
    UncertaintyTable,
    _default_materials,
)
from drillstring.case.well_table import Well, _well_problems
from drillstring.derived import (
    axial_load_per_length,
    element_counts,
    fluid_skin_friction,
    mesh_breaks,
    mode_family_sizes,
    string_axial_load,
)
from drillstring.units import LENGTH, VOLUME_FLOW, quantity_text, to_si


def _inlet_velocity_from_flow(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with ``fluid.flow_rate`` (a volume flow Q) replaced by ``fluid.inlet_velocity`` = Q / A_i, A_i
    the bore of the top section; left as it is when that bore cannot be read (reported elsewhere)."""
    fluid = dict(data["fluid"])
    flow = fluid.pop("flow_rate")
    where = ("fluid", "flow_rate")
    try:
        rate = to_si(flow, VOLUME_FLOW)
    except ValueError as exc:
        raise _Problems([(where, flow, str(exc))]) from None
    if "inlet_velocity" in fluid:
        raise _Problems([(where, flow, "give either fluid.flow_rate or fluid.inlet_velocity, not both")])
    try:
        bore = to_si(data["sections"][0]["inner_diameter"], LENGTH)
    except (KeyError, IndexError, TypeError, ValueError):
        return data
    if rate < 0.0 or bore <= 0.0:
        problem = "must be >= 0" if rate < 0.0 else "needs a bore: the top section's inner_diameter is 0"
        raise _Problems([(where, flow, problem)])
    fluid["inlet_velocity"] = rate / (math.pi * bore**2 / 4.0)
    data["fluid"] = fluid
    return data


class Case(_Base):
    """A complete drilling case. Sections are ordered from the top (x = 0) to the bit (x = L)."""

    name: str = Field(max_length=MAX_NAME_LENGTH)
    description: str = Field("", max_length=MAX_DESCRIPTION_LENGTH)
    materials: dict[str, Material] = Field(default_factory=_default_materials)
    sections: list[Section] = Field(min_length=1)
    borehole: Borehole
    stabilizers: list[Stabilizer] = Field(default_factory=list)
    fluid: Fluid = Field(default_factory=Fluid)
    bit_rock: BitRock = Field(default_factory=BitRock)
    contact: Contact = Field(default_factory=Contact)
    operation: Operation = Field(default_factory=Operation)
    top_drive: TopDrive = Field(default_factory=TopDrive)
    damping: Damping = Field(default_factory=Damping)
    environment: Environment = Field(default_factory=Environment)
    model: Model = Field(default_factory=Model)
    mesh: Mesh = Field(default_factory=Mesh)
    reduced_model: ReducedModel = Field(default_factory=ReducedModel)
    simulation: Simulation = Field(default_factory=Simulation)
    initial: Initial = Field(default_factory=Initial)
    bow: Bow = Field(default_factory=Bow)
    uncertainty: UncertaintyTable | None = Field(
        None, description="optional [uncertainty] table: the laws of a study's random parameters")
    well: Well | None = Field(None, description="optional [well]: survey, casing, friction (drillstring.well)")
    motor: DownholeMotor | None = Field(
        None, description="optional [motor]: a downhole motor (drillstring.forces.motor), from [[components]]")
    estimator: Estimator | None = Field(
        None, description="optional [estimator]: the ensemble estimator's settings (drillstring.estimation)")
    string_friction: StringFriction = Field(
        default_factory=StringFriction, description="along-string friction in a deviated well (its [well])")

    # -- inputs converted with the whole case: components, flow rate -------------------------------------

    @model_validator(mode="before")
    @classmethod
    def _whole_case_inputs(cls, data: Any) -> Any:
        if not isinstance(data, Mapping):
            return data
        data = dict(data)
        if "components" in data:
            data = _from_components(data)
        if isinstance(data.get("fluid"), Mapping) and "flow_rate" in data["fluid"]:
            data = _inlet_velocity_from_flow(data)
        return data

    # -- derived quantities ------------------------------------------------------------------------------

    @property
    def top_driven(self) -> bool:
        """Whether a top boundary drives the string (the quill free, its first torsional mode the rigid rotation):
        the top drive under a controller, or any other registered boundary (``top_drive.boundary``)."""
        return self.top_drive.boundary != "top_drive" or self.top_drive.controller != "imposed_speed"

    @property
    def length(self) -> float:
        """Total string length L [m]."""
        return math.fsum(s.length for s in self.sections)

    @property
    def section_boundaries(self) -> tuple[float, ...]:
        """x of the lower end of each section, top to bit [m]; the last one is ``length``."""
        ends, x = [], 0.0
        for s in self.sections:
            x += s.length
            ends.append(x)
        return tuple(ends)

    def material_of(self, section: Section | int) -> Material:
        """The material of a section (given as a Section or as its index)."""
        if isinstance(section, int):
            section = self.sections[section]
        return self.materials[section.material]

    @property
    def flow_rate(self) -> float:
        """Mud volume flow Q = U_i A_i of the top section [m^3/s] (U_i the inlet velocity)."""
        return self.fluid.inlet_velocity * self.sections[0].inner_area

    @property
    def axial_load_per_length(self) -> tuple[float, ...]:
        """Distributed axial load q of each section [N/m], along +x (down): ``(rho A - rho_b A_s) g``, with
        ``A_s`` the section's solid area (tool joints' steel included: :attr:`Material.solid_fraction`),
        ``rho_b`` the mud density when ``model.buoyancy`` is on (else 0) and ``g`` 0 when ``model.gravity``
        is off, plus the mud's skin friction when ``fluid.axial_loads`` is on
        (:func:`drillstring.derived.axial_load_per_length`; the statics uses the same values)."""
        g = self.environment.gravity if self.model.gravity else 0.0
        buoyancy = self.fluid.density if self.model.buoyancy else 0.0
        loads = []
        for s in self.sections:
            friction = 0.0
            if self.fluid.axial_loads:
                friction = fluid_skin_friction(s.outer_diameter, s.inner_diameter, self.borehole.diameter,
                                               self.fluid.density, self.flow_rate,
                                               self.fluid.friction_coefficient)
            material = self.material_of(s)
            loads.append(axial_load_per_length(steel_density=material.density, area=s.area, gravity=g,
                                               buoyancy_density=buoyancy, skin_friction=friction,
                                               solid_area=material.solid_fraction * s.area))
        return tuple(loads)

    @property
    def weight(self) -> float:
        """Total distributed axial load on the string [N], ``sum q L`` over the sections
        (:attr:`axial_load_per_length`): its weight (buoyed when ``model.buoyancy`` is on, 0 when
        ``model.gravity`` is off) plus the mud's skin friction when ``fluid.axial_loads`` is on. The hook and
        the bit carry it together; it equals the static state's ``weight``."""
        return string_axial_load(self.axial_load_per_length, [s.length for s in self.sections])

    @property
    def weight_on_hook(self) -> float:
        """Static hook load, weight - weight_on_bit [N]; negative when the hook pushes (gravity off)."""
        return self.weight - self.operation.weight_on_bit

    @property
    def element_count(self) -> int:
        """Number of finite elements of the case's mesh (:func:`drillstring.derived.element_counts`)."""
        points = [st.position for st in self.stabilizers] + list(self.mesh.probes)
        breaks = mesh_breaks([s.length for s in self.sections], points)
        return sum(element_counts(breaks, self.mesh.max_element_length))

    def weight_on_bit_problem(self, weight_on_bit: float) -> str | None:
        """Why ``weight_on_bit`` [N] cannot be this case's (the rule of ``operation.weight_on_bit``, also
        applied to the API's overrides), or None: at most its :data:`PHYSICAL_BOUNDS` ceiling, and, with
        gravity on, less than the string's weight (the hook cannot push; with gravity off the string weighs
        nothing and the hook pushes)."""
        high = next(h for path, _, h, _ in PHYSICAL_BOUNDS if path == ("operation", "weight_on_bit"))
        if not weight_on_bit <= high:
            return f"must be within [0, {high:g}] N"
        w = self.weight
        if self.model.gravity and weight_on_bit >= w:
            shown = [quantity_text(f, "force", digits=6) for f in (weight_on_bit, w)]
            return f"must be less than the string's weight: weight_on_bit {shown[0]} >= weight {shown[1]}"
        return None

    # -- cross-field validation --------------------------------------------------------------------------

    @model_validator(mode="after")
    def _cross_field(self) -> Case:
        problems = _bound_problems(self)
        if problems:  # the rules below compute with these values
            raise _Problems(problems)
        defined = ", ".join(self.materials) or "none"
        for i, s in enumerate(self.sections):
            if s.material not in self.materials:
                problems.append(((("sections", i, "material")), s.material, f"unknown material; defined: {defined}"))
            if s.outer_diameter >= self.borehole.diameter:
                problems.append(
                    (
                        ("sections", i, "outer_diameter"),
                        s.outer_diameter,
                        f"must be less than the borehole diameter ({self.borehole.diameter:g} m)",
                    )
                )
        if self.bit_rock.law == "detournay" and self.bit_rock.bit_radius > self.borehole.diameter / 2.0:
            problems.append((("bit_rock", "bit_radius"), self.bit_rock.bit_radius,
                             f"must be at most the borehole radius ({self.borehole.diameter / 2.0:g} m): the bit "
                             f"cuts the hole"))
        L = self.length
        for i, st in enumerate(self.stabilizers):
            if not 0.0 < st.position <= L:
                problems.append(
                    (("stabilizers", i, "position"), st.position, f"must be within the string, 0 < x <= {L:g} m")
                )
        for i, p in enumerate(self.mesh.probes):
            if not 0.0 <= p <= L:
                problems.append((("mesh", "probes", i), p, f"must be within the string, 0 <= x <= {L:g} m"))
        if self.bow.amplitude > 0.0:
            if not self.bow.end <= L:
                problems.append((("bow", "end"), self.bow.end, f"must be within the string, <= {L:g} m"))
            if not self.bow.start < self.bow.end:
                problems.append((("bow", "start"), self.bow.start,
                                 f"must be less than bow.end ({self.bow.end:g} m)"))
        if problems:  # the rules below need valid materials and gaps
            raise _Problems(problems)
        problems.extend(self._offset_problems())
        problems.extend(_well_problems(self))
        problems.extend(_motor_problems(self))

        problems.extend(self._mesh_problems())

        wob_problem = self.weight_on_bit_problem(self.operation.weight_on_bit)
        if wob_problem:
            problems.append((("operation", "weight_on_bit"), self.operation.weight_on_bit, wob_problem))
        gaps = [(self.borehole.diameter - s.outer_diameter) / 2.0 for s in self.sections]
        i_min = min(range(len(gaps)), key=gaps.__getitem__)
        amp = self.initial.lateral_perturbation
        if amp >= gaps[i_min]:
            problems.append(
                (
                    ("initial", "lateral_perturbation"),
                    amp,
                    f"must be less than the smallest radial gap, {gaps[i_min]:.6g} m"
                    f" (section {self.sections[i_min].name!r})",
                )
            )
        if problems:
            raise _Problems(problems)
        return self

    @model_validator(mode="after")
    def _top_drive_model(self) -> Case:
        if self.top_driven and self.model.nonlinear == "full":
            raise _Problems([(("top_drive", "controller"), self.top_drive.controller,
                              'a top drive needs model.nonlinear = "bit_and_contact" (case 1 with a top drive '
                              'is not supported yet); use "imposed_speed" for case 1')])
        return self

    def _offset_problems(self) -> list[tuple[tuple[str | int, ...], Any, str]]:
        """A section's mass eccentricity and the bow must be less than the radial gap where they are: a
        larger offset puts the string's unloaded shape (bow) or its imbalance orbit (eccentricity) beyond the
        borehole wall, where the contact law would answer with absurd forces instead of a drilling run."""
        problems = []
        top = 0.0
        bowed = []
        for i, s in enumerate(self.sections):
            gap = (self.borehole.diameter - s.outer_diameter) / 2.0
            if s.eccentricity >= gap:
                problems.append((("sections", i, "eccentricity"), s.eccentricity,
                                 f"must be less than the section's radial gap ({gap:.6g} m)"))
            if self.bow.amplitude > 0.0 and top < self.bow.end and top + s.length > self.bow.start:
                bowed.append((gap, s.name))
            top += s.length
        if bowed and self.bow.amplitude >= min(bowed)[0]:
            gap, name = min(bowed)
            problems.append((("bow", "amplitude"), self.bow.amplitude,
                             f"must be less than the radial gap along the bow ({gap:.6g} m, section {name!r})"))
        return problems

    def _mesh_problems(self) -> list[tuple[tuple[str | int, ...], Any, str]]:
        """The case can be meshed (element length within the string, at most :data:`MAX_ELEMENTS`
        elements) and reduced (no family asks for more modes than the mesh has DOFs)."""
        length, h = self.length, self.mesh.max_element_length
        where = ("mesh", "max_element_length")
        if h > length:
            return [(where, h, f"must be at most the string length ({length:g} m)")]
        elements = self.element_count
        if elements > MAX_ELEMENTS:
            return [(where, h, f"gives {elements:,} elements, more than the {MAX_ELEMENTS:,} allowed "
                               f"(about max_element_length >= {length / MAX_ELEMENTS:.3g} m for this "
                               f"{length:g} m string)")]
        nodes = elements + 1
        top_free = self.top_driven
        sizes = mode_family_sizes(nodes, top_free)
        problems = []
        for key, family, rigid in (("axial_modes", "axial", 1), ("torsional_modes", "torsional", int(top_free)),
                                   ("lateral_modes", "lateral", 0)):
            requested = getattr(self.reduced_model, key)
            most = sizes[family] - rigid
            if requested > most:
                dofs = f"{sizes[family]} {family} DOFs" + (" per plane" if family == "lateral" else "")
                rigid_note = ", one of them the rigid mode" if rigid else ""
                problems.append((("reduced_model", key), requested,
                                 f"must be at most {most}: the mesh has {nodes} nodes, {dofs}{rigid_note}; "
                                 f"ask for fewer modes or lower mesh.max_element_length"))
        return problems

    # -- serialisation -----------------------------------------------------------------------------------

    def to_toml(self) -> str:
        """The case as TOML text, every value a plain SI number; ``load_case`` reads it back to an equal Case."""
        header = f"# drillstring case {self.name!r}; all numbers in SI units (m, N, Pa, kg/m3, s, rad/s).\n\n"
        return header + tomli_w.dumps(self.model_dump(mode="python", exclude_none=True))
