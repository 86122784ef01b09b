"""The reduced model's data as its compiled kernels read it, by name (:mod:`drillstring.dynamics.rom` builds it
once per model, :meth:`~drillstring.dynamics.rom.ReducedOrderModel.kernel_data` once per run).

The model's data (:class:`RhsData`, :class:`FullModelData`) is read only during a run; what a kernel writes —
the contact search's work (:class:`ContactWork`), case 1's buffers, the observation's scratch
(:class:`ObserveData`) and the bit's history (in ``RhsData.laws``) — is each run's own (:class:`KernelData`).
Every field is an argument of each compiled kernel that takes the data (a field costs run and compile time:
measured, ``benchmarks/bench_protocol.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from drillstring.forces.turning_loads import TurningLoadData

#: The boundary components' numbers sit in ``RhsData.laws``, one flat array laid out by the registry
#: (:func:`~drillstring.forces.registry.pack`: a header with the components' codes and offsets, then the bit
#: law's numbers, the top boundary's, the hook load's and the bit's history, the hole bottom by angle). One
#: array, not a field each: every field of RhsData is an argument of each inner kernel, and four more fields
#: made the reference realization 30 % slower (measured; LLVM inlines less).
#: Coefficients of a dense-output polynomial the scratch of :class:`ObserveData` holds (dopri5: 4).
_DENSE_ORDER_MAX = 8


class ContactWork(NamedTuple):
    """Scratch arrays of the contact search: ``v``, ``w`` at every node, the rest one entry per contact
    station (the first ``n_c``, the stations in contact, used)."""

    v: np.ndarray  # (n_nodes,) lateral displacement v [m]
    w: np.ndarray  # (n_nodes,) lateral displacement w [m]
    stations: np.ndarray  # (n_stations,) int64, indices of the stations in contact
    v_c: np.ndarray  # the same quantities at the stations in contact ...
    w_c: np.ndarray
    v_dot: np.ndarray
    w_dot: np.ndarray
    spin: np.ndarray
    gap: np.ndarray
    outer_diameter: np.ndarray
    stiffness: np.ndarray
    force_v: np.ndarray  # ... and the contact forces [N] and torque [N·m] there
    force_w: np.ndarray
    torque: np.ndarray

    @classmethod
    def allocate(cls, n_nodes: int, n_stations: int) -> ContactWork:
        sizes = {"v": n_nodes, "w": n_nodes}
        return cls(*(np.zeros(sizes.get(name, n_stations), dtype=np.int64 if name == "stations" else np.float64)
                     for name in cls._fields))


class ContactData(NamedTuple):
    """The wall as the kernels read it: one entry per contact station
    (:class:`~drillstring.forces.contact.ContactStations`), ordered by node; a node's offset from the hole's
    axis is its static offset (``rest``, (v, w) per node: the stiff string's in a well basis, zeros for
    the straight string) plus the modal lateral displacement
    (:func:`~drillstring.dynamics.reduced.frame.lateral_displacements`). The contact law's numbers are in
    the kernels' flat array (:func:`~drillstring.forces.registry.pack`), not here."""

    node: np.ndarray  # (n_stations,) int64
    gap: np.ndarray  # (n_stations,) radial clearance [m]
    outer_diameter: np.ndarray  # (n_stations,) [m]
    stiffness: np.ndarray  # (n_stations,) k_i = k'_sh ℓ_i [N/m]
    rest: np.ndarray  # (2, n_nodes) each node's static lateral offset (v, w) from the hole's axis [m] (0: straight);
    #                   one field, not two: each field is an argument of every inner kernel (two: +8.5 % run time)
    tangential: bool  # gather the stations' lateral velocities: the contact law reads them
    work: ContactWork  # scratch: each run's own (ReducedOrderModel.kernel_data), empty in the model's data


class StringFrictionWork(NamedTuple):
    """Scratch of the along-string friction, one entry per friction station: the context's velocities and the
    law's forces (each run's own)."""

    axial_velocity: np.ndarray  # u̇ [m/s]
    spin: np.ndarray  # θ̇x [rad/s]
    force: np.ndarray  # axial force on the string [N]
    torque: np.ndarray  # torque on the string [N·m]

    @classmethod
    def allocate(cls, n_stations: int) -> StringFrictionWork:
        return cls(*(np.zeros(n_stations) for _ in cls._fields))


class StringFrictionData(NamedTuple):
    """The along-string friction's stations as the kernels read them
    (:class:`~drillstring.forces.string_friction.FrictionStations`): the nodes resting on the wall in the static
    state, their static normal force, contact radius and friction coefficient, and the axial mode shapes there.
    The law's numbers are in the kernels' flat array (:func:`~drillstring.forces.registry.pack`)."""

    node: np.ndarray  # (m,) int64 mesh nodes
    normal_force: np.ndarray  # (m,) N_i [N]
    radius: np.ndarray  # (m,) r_i [m]
    friction: np.ndarray  # (m,) μ_i [-]
    axial_t: np.ndarray  # (a1 − a0, m): u at each station, columns of the axial range
    work: StringFrictionWork  # scratch: each run's own (ReducedOrderModel.kernel_data), empty in the model's data


class ModalRanges(NamedTuple):
    """The columns ``[start, end)`` of the basis that can move each physical quantity: the axial DOFs, the
    torsional ones (θx), the lateral ones along y (v, θz) and along z (w, θy). For a straight string each range
    is its family's (the fast path: a quantity reads only its family's columns); when the families couple
    (:attr:`ReducedOrderModel.coupled`) every range is the whole basis ``[0, n)``."""

    axial_start: int
    axial_end: int
    torsion_start: int
    torsion_end: int
    lateral_y_start: int
    lateral_y_end: int
    lateral_z_start: int
    lateral_z_end: int


#: The rows of ``RhsData.axial_rows``, by name: mode-shape rows over the axial range's columns
#: (:class:`ModalRanges`) [m per unit modal coordinate]: u at the bit (the bit–rock law's force acts along it), u at
#: the top (where the hook pulls). A term that reads or acts along a new row adds its name here and its shape where
#: :class:`~drillstring.dynamics.rom.ReducedOrderModel` builds the rows (by these names); the kernels read a row by
#: its name's index (:data:`AXIAL_ROW`), never by a position of their own. One array, not a field per row: each
#: field is an argument of every compiled kernel that takes the data, and six rows as fields made the reference
#: realization 7 % slower (measured).
AXIAL_ROWS = ("bit", "top")
#: The rows of ``RhsData.torsion_rows``, by name, over the torsional range's columns: θx at the bit [rad] (the
#: bit–rock law's torque acts along it), θx at the top, the quill (a top drive's motor torque acts along it; 0 when
#: held), the elastic torque of the top element, (K Φ) at the top's θx [N·m], and a downhole motor's rotor rotation
#: relative to its stator [rad] (0 without one).
TORSION_ROWS = ("bit", "quill", "surface_torque", "motor")
#: Row of each name in ``axial_rows`` and ``torsion_rows``.
AXIAL_ROW = {name: row for row, name in enumerate(AXIAL_ROWS)}
TORSION_ROW = {name: row for row, name in enumerate(TORSION_ROWS)}


class RhsData(NamedTuple):
    """What the case-2 right-hand side reads (SI units), by name: a new force term adds its own fields (or
    rows to a group of rows), and no kernel writes any of it during a run (the run's scratch and the bit's
    history, in ``laws``, are each run's own: :meth:`ReducedOrderModel.kernel_data`). Each physical quantity
    is read from the columns that can move it (``ranges``, :class:`ModalRanges`); the rows ``axial_rows``,
    ``torsion_rows`` (by name: :data:`AXIAL_ROWS`, :data:`TORSION_ROWS`) hold the columns of their range and ``phi_v_t``, ``phi_w_t``, ``phi_tx_t`` (range columns ×
    nodes) and ``damping_t`` are stored transposed so that products run column by column. When the families
    couple every row holds every column and the damping is one full block."""

    omega2: np.ndarray  # (n,) signed ω² [1/s²]
    damping_t: np.ndarray  # (n, n) Dᵀ [1/s]
    damping_blocks: np.ndarray  # (k, 2) int64: diagonal blocks [start, end) holding every nonzero of D
    generalized_force: np.ndarray  # (n,) constant modal force added to the modal acceleration
    ranges: ModalRanges
    axial_rows: np.ndarray  # (len(AXIAL_ROWS), a1 − a0): the rows named by AXIAL_ROWS
    torsion_rows: np.ndarray  # (len(TORSION_ROWS), t1 − t0): the rows named by TORSION_ROWS
    phi_v_t: np.ndarray  # (y1 − y0, n_nodes): v at every node, columns of the lateral-y range
    phi_w_t: np.ndarray  # (z1 − z0, n_nodes): w at every node, columns of the lateral-z range
    phi_tx_t: np.ndarray  # (t1 − t0, n_nodes): θx at every node, columns of the torsional range
    smallest_gap: float  # min of the stations' gaps [m]
    lateral_shape_max: np.ndarray  # max over nodes of |φ_v| (lateral-y range's columns), then |φ_w| (z range's)
    top_speed: float  # base spin speed [rad/s]: Ω with an imposed top speed, 0 with a top drive
    weight_on_bit: float  # static bit reaction [N]
    laws: np.ndarray  # the components' numbers (drillstring.forces.registry.pack): header, the bit law's, the
    #                   top boundary's, the hook load's, the contact law's, the bit's history (the hole bottom)
    contact: ContactData
    turning: TurningLoadData
    friction: StringFrictionData  # the along-string friction's stations (none: zero stations)


#: The case-2 data of a model whose bit–rock law reads the bit's history (the Detournay law): the same fields
#: as :class:`RhsData`, a type of its own so that the kernels compiled for it read the history and those
#: compiled for the other laws hold no code for it (the depth-of-cut lookup in the right-hand side, never
#: run with those laws, made the reference realization 15 % slower: it changed how the kernel compiles).
DelayedRhsData = NamedTuple("DelayedRhsData", list(RhsData.__annotations__.items()))
DelayedRhsData.__doc__ = """:class:`RhsData` of a model with a delayed bit–rock law (same fields)."""


class FullModelData(NamedTuple):
    """What the case-1 right-hand side reads in addition to the case-2 data (``rhs``): the basis by family
    (each family's modes live on its own DOFs only: ``*_dofs`` the global DOFs of the family,
    ``*_shapes_t`` its mode shapes there, transposed), the element data of
    :class:`~drillstring.forces.nonlinear.NonlinearElements`, the modal coupling tensor of the mass
    correction, and scratch arrays.

    The projected mass correction ``Φᵀ M_nl(Φη) Φ`` has only a torsion × lateral-y block
    ``B(η) = Σ_k η_z,k T_k`` (and its transpose): ``M_nl`` couples θx with the (v, θz) plane with a
    coefficient linear in θy, which only the lateral-z modes carry
    (:func:`~drillstring.forces.nonlinear.modal_mass_coupling`)."""

    rhs: RhsData  # or DelayedRhsData
    axial_dofs: np.ndarray  # int64
    axial_shapes_t: np.ndarray  # (n_a, len(axial_dofs))
    torsion_dofs: np.ndarray
    torsion_shapes_t: np.ndarray
    bending_y_dofs: np.ndarray
    bending_y_shapes_t: np.ndarray
    bending_z_dofs: np.ndarray
    bending_z_shapes_t: np.ndarray
    theta_x_dofs: np.ndarray  # int64, the θx DOF of every node
    inv_length: np.ndarray
    xi: np.ndarray
    weights: np.ndarray
    slope: np.ndarray
    rotation: np.ndarray
    axial_stiffness: np.ndarray
    polar_inertia: np.ndarray
    coupling_tensor: np.ndarray  # (n_z, n_t, n_y) T_k
    q: np.ndarray  # (n_dofs,) scratch: q̄ = Φη
    qd: np.ndarray  # (n_dofs,) scratch: q̇
    f_se: np.ndarray  # (n_dofs,) scratch
    f_vel: np.ndarray  # (n_dofs,) scratch
    coupling: np.ndarray  # (n_el, 2, 4) scratch
    block: np.ndarray  # (n_t, n_y) scratch: B(η)
    schur: np.ndarray  # (n_t, n_t) scratch: I − B Bᵀ
    torsion_rhs: np.ndarray  # (n_t,) scratch
    acceleration: np.ndarray  # (n,) scratch


class ObserveData(NamedTuple):
    """What the observation kernel reads besides the right-hand-side data, and fills."""

    probe_nodes: np.ndarray  # (n_probes,) int64
    v: np.ndarray  # (n_nodes,) scratch
    w: np.ndarray  # (n_nodes,) scratch
    in_contact: np.ndarray  # (n_nodes,) bool: which nodes touch the borehole (filled)
    current: np.ndarray  # (n_nodes,) bool: nodes in contact at the accepted step being counted (impacts)
    previous: np.ndarray  # (n_nodes,) bool: nodes in contact at the previous accepted step (impacts)
    dense: np.ndarray  # (2, _DENSE_ORDER_MAX) scratch: the bit's angle and position polynomials of a step

    @classmethod
    def allocate(cls, probe_nodes: np.ndarray, n_nodes: int) -> ObserveData:
        """Fresh scratch for ``n_nodes`` nodes, no node in contact."""
        return cls(probe_nodes=probe_nodes, v=np.zeros(n_nodes), w=np.zeros(n_nodes),
                   in_contact=np.zeros(n_nodes, dtype=np.bool_), current=np.zeros(n_nodes, dtype=np.bool_),
                   previous=np.zeros(n_nodes, dtype=np.bool_), dense=np.zeros((2, _DENSE_ORDER_MAX)))


class KernelData(NamedTuple):
    """The compiled kernels' arguments for one run (:meth:`ReducedOrderModel.kernel_data`): the model's data,
    read only, with the run's own scratch (contact work, the case-1 buffers, the observation's) and the run's
    own copy of the bit's history, so that nothing a run writes is held by the model."""

    rhs: object  # RhsData, DelayedRhsData or FullModelData: what evaluate_rhs reads
    case2: object  # its case-2 part (RhsData or DelayedRhsData): what the observation kernels read
    observe: ObserveData
