"""The reduced-order model of one drilling configuration (docs/model.md §5–§9): :class:`ReducedOrderModel`, the
modal basis with its linear parts (frequencies, damping, the constant generalised force) and the components, and
the data the compiled kernels read (:mod:`drillstring.dynamics.kernel_data`), built from them once; its right-hand
side, compiled (:mod:`drillstring.dynamics.reduced.rhs`) or by NumPy (:mod:`drillstring.dynamics.reduced.reference`),
its observation (:mod:`drillstring.dynamics.reduced.observation`), the start of a run and the impacts of one.
The model's build from a case is :mod:`drillstring.dynamics.reduced.build`.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from drillstring.dynamics.delay import allocate_storage, delayed_difference, record_bottom, view
from drillstring.dynamics.delay import start as start_history
from drillstring.dynamics.kernel_data import (  # the kernels' data, by name
    AXIAL_ROWS,
    TORSION_ROWS,
    ContactData,
    ContactWork,
    DelayedRhsData,
    FullModelData,
    KernelData,
    ModalRanges,
    ObserveData,
    RhsData,
    StringFrictionData,
    StringFrictionWork,
)
from drillstring.dynamics.reduced.observation import (
    _FOB,
    _QUILL_SPEED,
    _ROP,
    _SURFACE_TORQUE,
    _TOB,
    OBSERVABLES,
    impacts_kernel,
    observation_width,
    observe_row,
)
from drillstring.dynamics.reduced.reference import reference_rhs
from drillstring.dynamics.reduced.rhs import evaluate_rhs
from drillstring.dynamics.reduced.terms import diagonal_blocks
from drillstring.fem.dofs import THETA_X, THETA_Y, THETA_Z, U, V, W, dof
from drillstring.forces.contact import ContactStations
from drillstring.forces.excitation import TurningLoads
from drillstring.forces.hook_load import OnBottomStart
from drillstring.forces.nonlinear import NonlinearElements, modal_mass_coupling, nonlinear_elements
from drillstring.forces.registry import (
    BitContext,
    BitLaw,
    ContactLaw,
    HookLoad,
    Motor,
    StringFriction,
    StringFrictionContext,
    TopContext,
    compiled,
    pack,
)
from drillstring.forces.string_friction import FrictionStations
from drillstring.forces.top_drive import TopDriveParameters
from drillstring.forces.turning_loads import turning_load_data
from drillstring.modal import LinearSystem, Modes, family_dofs
from drillstring.rotor import RotorRelease
from drillstring.statics import StaticState


@dataclass
class ReducedOrderModel:
    """Modal model of one drilling configuration (SI units).

    Attributes:
        angular_frequencies: ω of each basis vector [rad/s] (0 for the rigid axial mode).
        damping: reduced damping matrix (modal + rigid + fluid) [1/s].
        basis: Φ, (n_dofs, n) global mode shapes.
        family: family label of each basis vector.
        probe_positions: x of the radial-displacement probes [m].
        contact: the contact law; its ``shock_stiffness`` is read as the wall's distributed stiffness
            k'_sh [N/m per m of string], acting on ``stations`` with ``k_i = k'_sh ℓ_i``.
        stations: where the wall acts (:class:`~drillstring.forces.contact.ContactStations`).
        generalized_force: (n,) constant generalized force added to the modal acceleration
            [N/√kg per unit modal mass, i.e. the right-hand side of η̈ = …]; ``None`` means zeros.
        turning_loads: loads turning with the string (:class:`~drillstring.forces.excitation.TurningLoads`:
            mass imbalance, stress-free bow), or ``None``.
        top_drive: the top boundary (:class:`~drillstring.forces.top_drive.TopDriveParameters`); ``None``
            is the imposed speed ``top_speed``. With a top drive the torsional family is free at the top
            (its first column the rigid rotation), ``top_speed`` is the set point, the kernels' base spin
            speed is 0 (the rigid rotation carries the spin) and the state ``[η, η̇, s]`` holds the
            controller's states ``s`` after the modal coordinates (:attr:`state_size`).
        hook_load: the start, a hook load of the protocol (:class:`~drillstring.forces.registry.HookLoad`:
            :class:`~drillstring.forces.hook_load.HookLoadRamp`, ...): ``None``, :class:`~drillstring.forces.
            hook_load.OnBottomStart` or a zero ramp time is the reference start (on the static state at t = 0); a ramp starts off bottom, the bit
            its ``clearance`` above the rock, and transfers the weight-on-bit over the ramp time.
        history_bins: bins per blade sector of the bit's history (:mod:`drillstring.dynamics.delay`) for a
            delayed bit–rock law.
        residual_columns: (n,) True on the columns that are residual-flexibility attachment modes (the truncation
            correction, :func:`drillstring.modal.residual_flexibility_modes`), not modes; None: none are.
        motor: a downhole motor (:mod:`drillstring.forces.motor`) or None; with one, ``rotor`` is the release of
            its rotor's rotation (:class:`~drillstring.rotor.RotorRelease`, its rows over the torsional columns)
            and the basis is that of the released string (:func:`~drillstring.rotor.released_modes`).
        string_friction: the along-string friction law (:mod:`drillstring.forces.string_friction`) or None; it
            acts at ``friction_stations`` (:class:`~drillstring.forces.string_friction.FrictionStations`: the
            nodes on the wall in a deviated well's static state, their normal forces), its axial force along
            the axial modes and its torque along the torsional ones. None or no stations: no friction (code 0).
        rest_offsets: (n_nodes, 2) each node's static lateral offset (v, w) from the hole's axis [m], where the
            contact's gap is measured from (the modal displacement is the motion from rest); None: zeros (the
            straight string on the axis).
        centreline_spin: the basis is in the nodes' frames (the well basis, :mod:`drillstring.well.well_modes`):
            θx of every node is its rotation about its own tangent, so the frame's spin ``Ω t`` is the curved
            string's spin about its centreline and a coupled basis may spin (an imposed top speed).

    Built from them: ``rhs_data`` (:class:`RhsData` for case 2, :class:`FullModelData` for case 1) and its
    case-2 part ``case2_data``, the model's data as the compiled kernels read it, by name. The model holds no
    run's state: nothing of a run writes its arrays. Each run, and each call of :meth:`rhs` or :meth:`observe`,
    takes :meth:`kernel_data` — that data with scratch of its own (contact work, the observation's, case 1's)
    and its own bit history — and the run's state (time, state vector, bit history, contact, controller) is
    passed in and returned by :func:`drillstring.dynamics.compiled.advance`.
    """

    static: StaticState
    system: LinearSystem
    modes: Modes
    basis: np.ndarray
    family: tuple[str, ...]
    angular_frequencies: np.ndarray
    damping: np.ndarray
    top_speed: float
    weight_on_bit: float
    bit_rock: BitLaw
    contact: ContactLaw
    stations: ContactStations
    probe_positions: np.ndarray
    nonlinear: str = "bit_and_contact"
    generalized_force: np.ndarray | None = None
    turning_loads: TurningLoads | None = None
    top_drive: TopDriveParameters | None = None
    hook_load: HookLoad | None = None
    history_bins: int = 2048
    residual_columns: np.ndarray | None = None
    coupled: bool = False
    motor: Motor | None = None
    rotor: RotorRelease | None = None
    string_friction: StringFriction | None = None
    friction_stations: FrictionStations | None = None
    rest_offsets: np.ndarray | None = None
    centreline_spin: bool = False

    def __post_init__(self) -> None:
        if self.nonlinear not in ("bit_and_contact", "full"):
            raise ValueError(f"nonlinear = {self.nonlinear!r}: must be 'bit_and_contact' or 'full'")
        if self.top_drive is None:
            self.top_drive = TopDriveParameters("imposed_speed", float(self.top_speed))
        #: the kernels' base spin speed [rad/s]: Ω with the top speed imposed, 0 with a top drive
        self.base_speed = 0.0 if self.top_drive.drives else float(self.top_speed)
        if self.top_drive.drives and self.nonlinear == "full":
            raise ValueError("nonlinear = 'full' with a top drive is not supported yet: use 'bit_and_contact'")
        if self.coupled:
            _check_coupled(self)
        if (self.motor is None) != (self.rotor is None):
            raise ValueError("motor and rotor: give both (a downhole motor and the release of its rotor) or neither")
        if self.motor is not None and self.nonlinear == "full":
            raise ValueError("nonlinear = 'full' with a downhole motor is not supported yet: use 'bit_and_contact'")
        if self.coupled and self.motor is not None:
            raise ValueError("a downhole motor on a coupled basis (a string out of the straight axis) is not supported "
                             "yet: its rotor is released in the torsional family of a straight string")
        mesh = self.static.mesh
        nodes = np.arange(mesh.n_nodes)
        phi = self.basis
        n = len(self.angular_frequencies)
        if self.generalized_force is None:
            self.generalized_force = np.zeros(n)
        force = np.array(self.generalized_force, dtype=float)
        if force.shape != (n,) or not np.all(np.isfinite(force)):
            raise ValueError(f"generalized_force: must be {n} finite numbers (one per mode), got shape "
                             f"{force.shape}")
        self.generalized_force = force
        self.residual_columns = (np.zeros(n, dtype=bool) if self.residual_columns is None
                                 else np.asarray(self.residual_columns, dtype=bool))
        if self.residual_columns.shape != (n,):
            raise ValueError(f"residual_columns: must be {n} booleans (one per basis column), got shape "
                             f"{self.residual_columns.shape}")
        if self.turning_loads is None:
            self.turning_loads = TurningLoads.empty(mesh.n_dofs)
        if self.hook_load is None:
            self.hook_load = OnBottomStart()
        self.omega2 = np.ascontiguousarray(np.sign(self.angular_frequencies) * self.angular_frequencies**2)
        self.bit_u = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, U)])
        self.top_u = np.ascontiguousarray(phi[dof(0, U)])
        self.bit_t = np.ascontiguousarray(phi[dof(mesh.n_nodes - 1, THETA_X)])
        self.phi_v = np.ascontiguousarray(phi[dof(nodes, V)])
        self.phi_w = np.ascontiguousarray(phi[dof(nodes, W)])
        self.phi_tx = np.ascontiguousarray(phi[dof(nodes, THETA_X)])
        self.probe_nodes = np.array([mesh.node_index(x) for x in self.probe_positions], dtype=np.int64)
        if len(self.stations) and (self.stations.node.min() < 0 or self.stations.node.max() >= mesh.n_nodes):
            raise ValueError("contact stations must sit on the mesh's nodes")
        #: k_i = k'_sh ℓ_i [N/m] of each contact station
        self.station_stiffness = self.stations.stiffness(self.contact.shock_stiffness)
        rest = np.zeros((mesh.n_nodes, 2)) if self.rest_offsets is None else np.asarray(self.rest_offsets, float)
        if rest.shape != (mesh.n_nodes, 2) or not np.all(np.isfinite(rest)):
            raise ValueError(f"rest_offsets: must be ({mesh.n_nodes}, 2) finite offsets [m], got shape {rest.shape}")
        #: (2, n_stations) the stations' static offsets (v, w) from the hole's axis [m]
        self.station_rest = np.ascontiguousarray(rest[self.stations.node].T)
        labels = np.array(self.family)
        blocks = []
        for names in (("rigid_axial", "axial"), ("torsional",), ("lateral_y",), ("lateral_z",)):
            if self.coupled:  # every physical quantity reads every column
                blocks += [0, n]
                continue
            columns = np.nonzero(np.isin(labels, names))[0]
            start = int(columns[0]) if len(columns) else 0
            end = int(columns[-1]) + 1 if len(columns) else 0
            if len(columns) and not np.array_equal(columns, np.arange(start, end)):
                raise ValueError("mode families must be contiguous in the basis")
            blocks += [start, end]
        self.blocks = np.array(blocks, dtype=np.int64)
        #: (n,) True on the columns that move the lateral DOFs (every column when the families couple)
        self.lateral_columns = np.zeros(n, dtype=bool)
        self.lateral_columns[blocks[4]:blocks[5]] = True
        self.lateral_columns[blocks[6]:blocks[7]] = True
        a0, a1, t0, t1, y0, y1, z0, z1 = blocks
        #: column of the rigid rotation (a top drive), None when the top is held
        self.rigid_rotation_column = t0 if self.top_drive.drives else None
        top_dof = dof(0, THETA_X)
        self.quill_shapes = np.ascontiguousarray(phi[top_dof])
        self.surface_torque_shapes = np.zeros(n)
        self.surface_torque_shapes[t0:t1] = self.system.stiffness[top_dof] @ phi[:, t0:t1]
        #: the rotor's rotation relative to the stator per modal coordinate (a downhole motor; zeros without)
        self.motor_shapes = np.zeros(n)
        if self.rotor is not None:
            self.motor_shapes[t0:t1] = self.rotor.relative
        c = self.contact
        st = self.stations
        transposed = np.ascontiguousarray
        history = (allocate_storage(self.bit_rock.sector, self.history_bins) if self.bit_rock.delayed
                   else allocate_storage(1.0, 4))
        if self.friction_stations is None:
            self.friction_stations = FrictionStations.empty()
        fs = self.friction_stations
        if len(fs) and (np.min(fs.node) < 0 or np.max(fs.node) >= mesh.n_nodes):
            raise ValueError("friction stations must sit on the mesh's nodes")
        #: the friction law the kernels run: None without a law or without stations (code 0, nothing added)
        self.active_friction = self.string_friction if len(fs) else None
        if self.active_friction is not None and self.motor is not None:
            raise ValueError("along-string friction with a downhole motor is not supported yet: the stations below "
                             "the rotor turn at the string's speed plus the motor's")
        self._friction_rows = (phi[dof(np.asarray(fs.node, dtype=np.int64), U)],
                               phi[dof(np.asarray(fs.node, dtype=np.int64), THETA_X)])
        laws, self.layout = pack(self.bit_rock, self.top_drive, self.hook_load, history, 2 * n, contact=self.contact,
                                 motor=self.motor, friction=self.active_friction)
        self.case2_data = (DelayedRhsData if self.bit_rock.delayed else RhsData)(
            omega2=self.omega2,
            damping_t=transposed(self.damping.T),
            damping_blocks=diagonal_blocks(self.damping),
            generalized_force=self.generalized_force,
            ranges=ModalRanges(*(int(b) for b in self.blocks)),
            axial_rows=_named_rows(AXIAL_ROWS, {"bit": self.bit_u, "top": self.top_u}, a0, a1),
            torsion_rows=_named_rows(TORSION_ROWS, {"bit": self.bit_t, "quill": self.quill_shapes,
                                                    "surface_torque": self.surface_torque_shapes,
                                                    "motor": self.motor_shapes}, t0, t1),
            phi_v_t=transposed(self.phi_v[:, y0:y1].T),
            phi_w_t=transposed(self.phi_w[:, z0:z1].T),
            phi_tx_t=transposed(self.phi_tx[:, t0:t1].T),
            smallest_gap=float(np.min(st.gap - np.hypot(*self.station_rest))) if len(st) else np.inf,
            lateral_shape_max=np.concatenate([np.abs(self.phi_v[:, y0:y1]).max(axis=0, initial=0.0),
                                              np.abs(self.phi_w[:, z0:z1]).max(axis=0, initial=0.0)]),
            top_speed=self.base_speed,
            weight_on_bit=float(self.weight_on_bit),
            laws=laws,
            contact=ContactData(
                node=transposed(st.node, dtype=np.int64), gap=transposed(st.gap, dtype=float),
                outer_diameter=transposed(st.outer_diameter, dtype=float),
                stiffness=transposed(self.station_stiffness, dtype=float),
                rest=transposed(rest.T),
                tangential=bool(c.reads_lateral_velocity), work=ContactWork.allocate(0, 0),  # kernel_data's
            ),
            turning=turning_load_data(self.turning_loads, phi[:, y0:y1], phi[:, z0:z1]),
            friction=StringFrictionData(
                node=transposed(fs.node, dtype=np.int64), normal_force=transposed(fs.normal_force, dtype=float),
                radius=transposed(fs.radius, dtype=float), friction=transposed(fs.friction, dtype=float),
                axial_t=transposed(phi[dof(np.asarray(fs.node, dtype=np.int64), U), a0:a1].T, dtype=float),
                work=StringFrictionWork.allocate(0)),  # kernel_data's
        )
        self.full = self.nonlinear == "full"
        self.rhs_data: RhsData | DelayedRhsData | FullModelData = (
            self._full_model_data(self.case2_data) if self.full else self.case2_data)

    def _full_model_data(self, case2: RhsData) -> FullModelData:
        mesh = self.static.mesh
        self.elements: NonlinearElements = nonlinear_elements(mesh)
        e = self.elements
        a0, a1, t0, t1, y0, y1, z0, z1 = (int(b) for b in self.blocks)
        c = np.ascontiguousarray
        rows = {}
        for name, (start, end) in {"axial": (a0, a1), "torsional": (t0, t1), "lateral_y": (y0, y1),
                                   "lateral_z": (z0, z1)}.items():
            dofs = family_dofs(mesh, name).astype(np.int64)
            rows[name] = (c(dofs), c(self.basis[dofs, start:end].T, dtype=float))
        tensor = modal_mass_coupling(e, self.basis[:, t0:t1], self.basis[:, y0:y1], self.basis[:, z0:z1])
        return FullModelData(
            rhs=case2,
            axial_dofs=rows["axial"][0], axial_shapes_t=rows["axial"][1],
            torsion_dofs=rows["torsional"][0], torsion_shapes_t=rows["torsional"][1],
            bending_y_dofs=rows["lateral_y"][0], bending_y_shapes_t=rows["lateral_y"][1],
            bending_z_dofs=rows["lateral_z"][0], bending_z_shapes_t=rows["lateral_z"][1],
            theta_x_dofs=dof(np.arange(mesh.n_nodes), THETA_X).astype(np.int64),
            inv_length=c(e.inv_length, dtype=float), xi=c(e.xi, dtype=float),
            weights=c(e.weights, dtype=float), slope=c(e.slope, dtype=float),
            rotation=c(e.rotation, dtype=float), axial_stiffness=c(e.axial_stiffness, dtype=float),
            polar_inertia=c(e.polar_inertia, dtype=float), coupling_tensor=c(tensor, dtype=float),
            **_full_model_scratch(0, 0, 0, 0, 0),  # each run's own: kernel_data
        )

    def kernel_data(self, history: np.ndarray | None = None) -> KernelData:
        """The compiled kernels' arguments for one run or one call (:class:`KernelData`): the model's data,
        which no kernel writes, with scratch of their own, and ``history`` (a storage of
        :mod:`drillstring.dynamics.delay`, e.g. :meth:`start_history`'s; copied in) as the bit's history of a
        delayed law (None: the model's own prehistory, :attr:`history`, read only). Two runs of one model
        with their own kernel data do not share a written array."""
        template = self.case2_data
        laws = template.laws
        if history is not None:
            offset = self.layout.numbers["history"]
            history = np.asarray(history, dtype=float)
            if history.shape != (laws.shape[0] - offset,):
                raise ValueError(f"history has shape {history.shape}: must be ({laws.shape[0] - offset},), a "
                                 f"storage of this model's bit history (ReducedOrderModel.start_history)")
            laws = laws.copy()
            laws[offset:] = history
        mesh = self.static.mesh
        case2 = template._replace(laws=laws, contact=template.contact._replace(
            work=ContactWork.allocate(mesh.n_nodes, len(self.stations))), friction=template.friction._replace(
            work=StringFrictionWork.allocate(len(self.friction_stations))))
        rhs = case2
        if self.full:
            t0, t1, y0, y1 = (int(b) for b in self.blocks[2:6])
            rhs = self.rhs_data._replace(rhs=case2, **_full_model_scratch(
                mesh.n_dofs, self.elements.n_elements, t1 - t0, y1 - y0, self.size))
        return KernelData(rhs, case2, ObserveData.allocate(self.probe_nodes, mesh.n_nodes))

    @property
    def lowest_lateral_eigenvalue(self) -> float:
        """ω₁² [rad²/s²] of the lowest lateral mode of the basis (signed; negative: the straight string is
        statically buckled, :mod:`drillstring.buckling`); NaN without lateral modes. When the families couple:
        the lowest ω² of the basis's modes (the rigid axial translation left out)."""
        if self.coupled:
            elastic = self.omega2[(np.array(self.family) != "rigid_axial") & ~self.residual_columns]
            return float(elastic.min()) if len(elastic) else math.nan
        y0, y1 = int(self.blocks[4]), int(self.blocks[5])
        return float(self.omega2[y0]) if y1 > y0 else math.nan

    @property
    def size(self) -> int:
        """Number of modal coordinates n (the state has 2n entries, plus the top drive's states)."""
        return len(self.angular_frequencies)

    @property
    def state_size(self) -> int:
        """Entries of the state ``[η, η̇, s]``: 2n plus the components' states ``s`` (the top boundary's), laid
        out by the registry (:attr:`layout`)."""
        return self.layout.state_size

    @property
    def observable_names(self) -> tuple[str, ...]:
        return OBSERVABLES

    @property
    def gap(self) -> np.ndarray:
        """Radial clearance at each node [m]: the smallest of its stations' (at a section change, the
        wider section's), so a node touches the wall exactly when ``r > gap``."""
        gap = np.full(self.static.mesh.n_nodes, np.inf)
        np.minimum.at(gap, self.stations.node, self.stations.gap)
        return gap

    @property
    def compiled(self) -> bool:
        """True when the compiled kernels hold the model's components (the package's registered ones); a
        component registered outside the package runs through :meth:`rhs_reference` only
        (:mod:`drillstring.forces.registry`)."""
        return all(compiled(c) for c in (self.bit_rock, self.top_drive, self.hook_load, self.contact, self.motor)
                   if c is not None)

    def require_compiled(self) -> None:
        """ValueError naming the component when :attr:`compiled` is False."""
        for kind, component in (("bit law", self.bit_rock), ("top boundary", self.top_drive),
                                ("hook load", self.hook_load), ("contact law", self.contact), ("motor", self.motor)):
            if component is not None and not compiled(component):
                raise ValueError(
                    f"{kind} {component.name!r} is registered outside the drillstring package, so the compiled "
                    f"kernels do not hold it: use engine = 'reference' (docs/extending.md)")

    def rhs(self, t: float, y: np.ndarray, history: np.ndarray | None = None) -> np.ndarray:
        """dy/dt for y = [η, η̇] at time ``t`` [s] (t enters through the rotation Ω t that turns the
        turning loads); ``history``: the bit's history of a delayed law (a storage of
        :mod:`drillstring.dynamics.delay`; None: the model's prehistory, :attr:`history`)."""
        self.require_compiled()
        out = np.empty_like(y)
        evaluate_rhs(self.kernel_data(history).rhs, float(t), np.ascontiguousarray(y, dtype=float), out)
        return out

    def rhs_reference(self, t: float, y: np.ndarray, history: np.ndarray | None = None) -> np.ndarray:
        """The straightforward NumPy right-hand side (full basis, every node): the reference
        implementation that the compiled :meth:`rhs` is tested against; same equations (``history`` as
        there)."""
        return reference_rhs(self, t, y, history)

    def observe(self, t: float, y: np.ndarray, history: np.ndarray | None = None) -> np.ndarray:
        """Observables (:data:`OBSERVABLES`) followed by the radial displacement r at each probe, then
        its v and w [m] (:func:`observation_width` columns); ``history`` as in :meth:`rhs`."""
        out = np.empty(observation_width(len(self.probe_nodes)))
        y = np.ascontiguousarray(y, dtype=float)
        data = self.kernel_data(history)
        observe_row(data.case2, data.observe, float(t), y, np.zeros_like(y), out)
        if not compiled(self.bit_rock):  # a law from outside the package: its force from its NumPy reference
            n = self.size
            position, angle = self.bit_position(t, y)
            depth = delayed_difference(self._history(history), angle, position) if self.bit_rock.delayed else 0.0
            force, torque = self.bit_rock.evaluate_at(BitContext(
                t, position, angle, out[_ROP], self.base_speed + self.bit_t @ y[n:2 * n], depth, self.weight_on_bit))
            out[_TOB], out[_FOB] = -float(torque), -float(force)
        if self.top_drive.drives and not compiled(self.top_drive):  # its motor torque from its NumPy reference
            n, first = self.size, self.layout.states["top_boundary"]
            torque, _ = self.top_drive.evaluate_at(TopContext(t, out[_QUILL_SPEED], self.surface_torque_shapes @ y[:n]),
                                                   y[first:first + self.top_drive.n_states])
            quill_acceleration = self.quill_shapes @ self.rhs_reference(t, y, history)[n:2 * n]
            out[_SURFACE_TORQUE] = float(torque) - self.top_drive.top_inertia * quill_acceleration
        return out

    def contact_mask(self, y: np.ndarray) -> np.ndarray:
        """(n_nodes,) bool: the nodes in contact with the borehole (a station outside its gap) at the state
        ``y``."""
        observe = ObserveData.allocate(self.probe_nodes, self.static.mesh.n_nodes)
        impacts_kernel(self.case2_data, observe, np.ascontiguousarray(y, dtype=float))
        return observe.current

    def impact_counter(self, in_contact: np.ndarray | None = None) -> ImpactCounter:
        """A counter of the impacts of one run (:class:`ImpactCounter`), from the nodes ``in_contact`` at its
        start (None: none, so that the contact zones of the first state counted are impacts)."""
        return ImpactCounter(self, in_contact)

    @property
    def history(self):
        """The model's own bit history (:class:`~drillstring.dynamics.delay.AngleHistory`): the flat
        prehistory that :meth:`rhs` and :meth:`observe` read when given none. A run reads and records its own
        (:meth:`start_history`, :meth:`kernel_data`); nothing of a run writes this one."""
        return view(self.case2_data.laws[self.layout.numbers["history"]:])

    def with_history(self, history: np.ndarray) -> ReducedOrderModel:
        """A shallow copy of this model whose own bit history (:attr:`history`, what :meth:`rhs` and
        :meth:`observe` read when given none) is a copy of ``history``: e.g. to analyse a run's state with code
        that takes a model (:mod:`drillstring.dynamics.stiffness`). This model is not changed."""
        data = self.kernel_data(history)
        other = copy.copy(self)
        other.case2_data = data.case2._replace(contact=self.case2_data.contact)
        other.rhs_data = self.rhs_data._replace(rhs=other.case2_data) if self.full else other.case2_data
        return other

    def _history(self, history: np.ndarray | None):
        """The :class:`~drillstring.dynamics.delay.AngleHistory` of a storage, or the model's own for None."""
        return self.history if history is None else view(np.asarray(history, dtype=float))

    def bit_position(self, t: float, y: np.ndarray) -> tuple[float, float]:
        """The bit's axial position u [m] (from the static state, down) and angle θ [rad] at time ``t``
        [s] for the state ``y``."""
        n = self.size
        return float(self.bit_u @ y[:n]), float(self.base_speed * t + self.bit_t @ y[:n])

    def start_history(self, y: np.ndarray, depth_of_cut: float | None = None) -> np.ndarray:
        """The bit's history at the start of a run from the state ``y`` at t = 0, a new storage of
        :mod:`drillstring.dynamics.delay` (the model's own is not changed): for a delayed bit–rock law, with a
        ramped start (:attr:`hook_load`) a flat bottom ``clearance`` below the bit; else the helical bottom of
        steady drilling with the depth of cut ``depth_of_cut`` [m] per blade under the bit — by default the
        law's own at the static weight-on-bit and the top speed (its ``start_depth_of_cut``; for the Detournay
        law the closed-form steady state, 0 when that weight does not exceed the wear flats' contact force).
        For a law without history: a copy of the model's (never read)."""
        storage = self.case2_data.laws[self.layout.numbers["history"]:].copy()
        if not self.bit_rock.delayed:
            return storage
        position, angle = self.bit_position(0.0, y)
        law = self.bit_rock
        if self.hook_load.active:
            start_history(view(storage), angle, position + self.hook_load.clearance, 0.0)
            return storage
        if depth_of_cut is None:
            speed = self.top_speed
            depth_of_cut = law.start_depth_of_cut(self.weight_on_bit, speed)
        start_history(view(storage), angle, position, depth_of_cut / law.sector)
        return storage

    def record_history(self, history: np.ndarray, t_old: float, h: float, y_old: np.ndarray,
                       coef: np.ndarray) -> None:
        """Record into ``history`` (a storage, :meth:`start_history`) the bit's position by angle over an
        accepted step from its dense-output polynomial ``y(t_old + σh) = y_old + Σ_p coef[p] σ^(p+1)``
        (``coef`` (p, len(y)): what :meth:`~drillstring.dynamics.runge_kutta.RungeKuttaStepper.dense_polynomial`
        gives): the NumPy path's counterpart of :func:`accepted_step_kernel`. Nothing for a law without
        history."""
        if not self.bit_rock.delayed:
            return
        n = self.size
        position, angle = self.bit_position(t_old, y_old)
        angle_coef = coef[:, :n] @ self.bit_t
        angle_coef[0] += self.base_speed * h
        record_bottom(view(history), angle, np.ascontiguousarray(angle_coef), position,
                      np.ascontiguousarray(coef[:, :n] @ self.bit_u))

    def turning_whirl(self) -> np.ndarray:
        """The steady lateral whirl [η, η̇] at t = 0 of the linear model spinning at Ω under the turning
        loads alone (mass imbalance, bow): with ``η_f(t) = Re(A_f e^{iΩt})`` in each lateral family,
        ``(diag(ω²) − Ω² I + iΩ D_ff) A_f = G_f``, ``G_y = Σ_k s_k e^{iφ_k} load_y[k]``,
        ``G_z = −i Σ_k s_k e^{iφ_k} load_z[k]`` (``s_k = Ω²`` for an imbalance, 1 for a bow). Zero
        without turning loads."""
        n = self.size
        y = np.zeros(2 * n)
        turning = self.case2_data.turning
        if not len(turning.node):
            return y
        omega = self.top_speed
        weight = np.exp(1j * turning.phase) * np.where(turning.speed_squared, omega**2, 1.0)
        _, _, _, _, y0, y1, z0, z1 = self.blocks
        if self.coupled:  # one system: both planes' loads on the whole basis, the full damping
            block = np.diag(self.omega2) - omega**2 * np.eye(n) + 1j * omega * self.damping
            amplitude = np.linalg.solve(block, weight @ turning.load_y - 1j * (weight @ turning.load_z))
            y[:n] = amplitude.real
            y[n:] = (1j * omega * amplitude).real
            return y
        for (start, end), load, factor in (((y0, y1), turning.load_y, 1.0), ((z0, z1), turning.load_z, -1j)):
            if end == start:
                continue
            rhs = factor * (weight @ load)
            block = np.diag(self.omega2[start:end]) - omega**2 * np.eye(end - start) \
                + 1j * omega * self.damping[start:end, start:end]
            amplitude = np.linalg.solve(block, rhs)
            y[start:end] = amplitude.real
            y[n + start:n + end] = (1j * omega * amplitude).real
        return y

    def initial_state(self, lateral_perturbation: float, seed: int) -> np.ndarray:
        """Initial state (docs/model.md §9): the static state, the whole string spinning at Ω, zero axial
        speed (η̇ = 0), in the steady whirl of its turning loads (:meth:`turning_whirl`; none without
        imbalance or bow: a string that has been spinning at Ω whirls so, and starting it straight would
        give it the impulse of a load switched on at t = 0), plus a seeded lateral perturbation defined
        physically, independent of the basis: ``v0(x) = Σ_k a_k sin(kπx/L)/k²``, ``w0`` likewise with
        ``b_k``, k = 1…10, ``a_k, b_k`` standard normal from ``numpy.random.default_rng(seed)``, scaled so
        that the largest radial displacement along the string is ``lateral_perturbation`` [m]; it is
        projected on the lateral modes (mass-orthogonal projection ``η0 = Φᵀ(M + M_f) q0``), so it
        converges to the physical shape as lateral modes are added. With a top drive the rigid rotation
        carries Ω (or the string starts at rest when the set point is ramped) and the controller's states
        start at 0 (the motor torque builds up from 0). With along-string friction and the top speed imposed,
        the string starts in its steady twist under that friction (:meth:`friction_twist`)."""
        at_rest = self.top_drive.starts_at_rest  # a ramped set point starts from rest: no spin, no whirl
        y0 = np.zeros(self.state_size)
        if not at_rest:
            y0[:2 * self.size] = self.turning_whirl()
        if self.active_friction is not None and not self.top_drive.drives:
            y0[:self.size] += self.friction_twist()
        if self.hook_load.active:
            y0[:self.size] += self.off_bottom_offsets()
        if self.rigid_rotation_column is not None and not at_rest:
            r = self.rigid_rotation_column  # spinning at Ω: the rigid rotation carries it
            y0[self.size + r] = self.top_speed / self.quill_shapes[r]
        lateral = self.lateral_columns
        if not (lateral_perturbation > 0 and lateral.any()):
            return y0
        mesh = self.static.mesh
        x = mesh.nodes / mesh.length
        k = np.arange(1, 11)
        rng = np.random.default_rng(seed)
        a, b = rng.standard_normal(10), rng.standard_normal(10)
        shapes = np.sin(np.pi * np.outer(x, k)) / k**2
        slopes = np.pi / mesh.length * np.cos(np.pi * np.outer(x, k)) / k
        v0, w0 = shapes @ a, shapes @ b
        scale = lateral_perturbation / np.hypot(v0, w0).max()
        nodes = np.arange(mesh.n_nodes)
        q0 = np.zeros(mesh.n_dofs)
        q0[dof(nodes, V)] = scale * v0
        q0[dof(nodes, W)] = scale * w0
        q0[dof(nodes, THETA_Z)] = scale * (slopes @ a)  # θz = ∂v/∂x
        q0[dof(nodes, THETA_Y)] = -scale * (slopes @ b)  # θy = −∂w/∂x
        eta0 = self.basis.T @ (self.system.mass @ q0)
        y0[: self.size] += np.where(lateral, eta0, 0.0)
        return y0

    def friction_twist(self) -> np.ndarray:
        """(n,) modal coordinates of the string's steady twist under its along-string friction, the string
        turning at the frame's speed Ω with no axial motion: ``η_j = φ_jᵀ τ(Ω) / ω_j²`` on the columns with
        ``ω_j² > 0`` (the torsional family held at the top; τ the law's torques at the stations, axial velocity
        0), so that a run does not start with the friction switched on at t = 0 (a torsional wave that
        nearly stops the bit of the ``deviated`` case). Zeros without friction."""
        n = self.size
        twist = np.zeros(n)
        if self.active_friction is None:
            return twist
        fs = self.friction_stations
        _, torque = self.active_friction.evaluate_at(StringFrictionContext(
            np.zeros(len(fs)), np.full(len(fs), self.base_speed), fs.normal_force, fs.radius, fs.friction))
        generalised = self.phi_tx[fs.node].T @ torque
        positive = self.omega2 > 0.0
        twist[positive] = generalised[positive] / self.omega2[positive]
        return twist

    def _friction_context(self, velocity: np.ndarray) -> StringFrictionContext:
        fs = self.friction_stations
        u, t = self._friction_rows
        return StringFrictionContext(u @ velocity, self.base_speed + t @ velocity, fs.normal_force, fs.radius,
                                     fs.friction)

    def friction_load(self, velocity: np.ndarray):
        """The along-string friction's generalised force ``Φ_uᵀ f + Φ_θᵀ τ`` (n,) with the modal velocities
        ``velocity`` = η̇ (the stations' axial velocity and spin from them, the frame's speed added); 0.0 without
        friction (the stability analysis's steady load, :mod:`drillstring.dynamics.stability`)."""
        if self.active_friction is None:
            return 0.0
        force, torque = self.active_friction.evaluate_at(self._friction_context(velocity))
        return self._friction_rows[0].T @ force + self._friction_rows[1].T @ torque

    def friction_jacobian(self, velocity: np.ndarray):
        """``∂(friction_load)/∂η̇`` (n, n) at ``velocity``: the law's closed-form Jacobian projected,
        ``Σ_ab Φ_aᵀ J_ab Φ_b`` over (u, θx); 0.0 without friction."""
        if self.active_friction is None:
            return 0.0
        jac = self.active_friction.jacobian_at(self._friction_context(velocity))
        rows = self._friction_rows
        return sum(rows[a].T @ (jac[:, a, b][:, None] * rows[b]) for a in range(2) for b in range(2))

    def friction_axial_resistance(self, speed: float) -> float:
        """``Σ_i −∂f_i/∂u̇`` at ``u̇ = 0`` with every station turning at ``speed`` [rad/s]: the friction's resistance
        [N·s/m] to a slow rigid axial motion of the turning string (``μ N g/s`` summed; exact to ``(V/rΩ)²`` at a
        speed V; the stability analysis's steady rate of penetration); 0.0 without friction."""
        if self.active_friction is None:
            return 0.0
        fs = self.friction_stations
        jac = self.active_friction.jacobian_at(StringFrictionContext(
            np.zeros(len(fs)), np.full(len(fs), float(speed)), fs.normal_force, fs.radius, fs.friction))
        return float(-jac[:, 0, 0].sum())

    def off_bottom_offsets(self) -> np.ndarray:
        """Modal coordinates η [√kg·m] of the string hanging off bottom at the start of a ramped start
        (:class:`~drillstring.forces.hook_load.HookLoadRamp`): relative to the static state the bit no longer
        carries the weight-on-bit W and the hook carries it instead, so the elastic axial modes take the
        static offsets of a force W down at the bit and W up at the top, ``ω_j² η_j = W (φ_bit − φ_top)_j``;
        the rigid axial coordinate puts the bit ``clearance`` above its static position (the rock)."""
        eta = np.zeros(self.size)
        a0, a1 = int(self.blocks[0]), int(self.blocks[1])
        load = self.weight_on_bit * (self.bit_u - self.top_u)
        rigid = rigid_axial_column(self)
        for j in range(a0, a1):
            if j != rigid:
                eta[j] = load[j] / self.omega2[j]
        eta[rigid] = (-self.hook_load.clearance - self.bit_u @ eta) / self.bit_u[rigid]
        return eta

    def energy(self, y: np.ndarray) -> float:
        """Linear mechanical energy ½ η̇ᵀη̇ + ½ Σ ω² η² [J] (conserved without damping and forcing)."""
        n = self.size
        return 0.5 * float(y[n:2 * n] @ y[n:2 * n] + self.omega2 @ (y[:n] ** 2))


def _named_rows(names: tuple[str, ...], shapes: dict[str, np.ndarray], start: int, end: int) -> np.ndarray:
    """The rows ``names`` (:data:`~drillstring.dynamics.kernel_data.AXIAL_ROWS`, ...) of the kernels' data: each
    named shape over the columns ``[start, end)``, in the names' order; a name without a shape is refused."""
    missing = [name for name in names if name not in shapes]
    if missing:
        raise ValueError(f"no shape for the rows {missing}: the reduced model builds {sorted(shapes)}")
    return np.ascontiguousarray(np.vstack([shapes[name][start:end] for name in names]))


class ImpactCounter:
    """The impacts of one run, counted state by state (:func:`new_contact_zones`): it holds the nodes in
    contact at the last state counted (:attr:`in_contact`), not the model."""

    def __init__(self, model: ReducedOrderModel, in_contact: np.ndarray | None = None) -> None:
        self._data = model.case2_data
        self._observe = ObserveData.allocate(model.probe_nodes, model.static.mesh.n_nodes)
        if in_contact is not None:
            self._observe.previous[:] = in_contact

    def __call__(self, y: np.ndarray) -> int:
        """The impacts at the accepted state ``y`` since the previous call: the contact zones that
        appeared."""
        return int(impacts_kernel(self._data, self._observe, np.ascontiguousarray(y, dtype=float)))

    @property
    def in_contact(self) -> np.ndarray:
        """The nodes in contact at the last state counted (a copy)."""
        return self._observe.previous.copy()


def _full_model_scratch(n_dofs: int, n_elements: int, n_t: int, n_y: int, n: int) -> dict:
    """The scratch fields of :class:`FullModelData` for ``n_dofs`` DOFs, ``n_elements`` elements, ``n_t``
    torsional and ``n_y`` lateral-y modes of ``n`` modal coordinates."""
    return dict(q=np.zeros(n_dofs), qd=np.zeros(n_dofs), f_se=np.zeros(n_dofs), f_vel=np.zeros(n_dofs),
                coupling=np.zeros((n_elements, 2, 4)), block=np.zeros((n_t, n_y)), schur=np.zeros((n_t, n_t)),
                torsion_rhs=np.zeros(n_t), acceleration=np.zeros(n))


def _check_coupled(model: ReducedOrderModel) -> None:
    """ValueError for what a model whose families couple does not support yet, naming it."""
    if model.nonlinear == "full":
        raise ValueError("nonlinear = 'full' with coupled families (a string out of its straight axis) is not "
                         "supported: its mass correction is built family by family; use 'bit_and_contact'")
    if model.top_drive.drives:
        raise ValueError(f"top boundary {model.top_drive.name!r} with coupled families (a string out of its "
                         "straight axis) is not supported: the rigid rotation of a bent string is not a motion of "
                         "its global θx DOFs; use an imposed top speed")
    if model.base_speed != 0.0 and not model.centreline_spin:
        raise ValueError(f"top_speed = {model.base_speed:g} rad/s with coupled families (a string out of its "
                         "straight axis): the spin of a bent string about its centreline is not a rotation of its "
                         "global θx DOFs (deviated-well dynamics); only 0 is supported")


def rigid_axial_column(model: ReducedOrderModel) -> int:
    """The column of the rigid axial translation in the model's basis."""
    columns = [i for i, f in enumerate(model.family) if f == "rigid_axial"]
    if len(columns) != 1:
        raise ValueError("the reduced model must hold exactly one rigid axial mode")
    return columns[0]
