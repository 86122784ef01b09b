"""The reduced-order model (ROM) of the drill-string and its right-hand side (docs/model.md §5–§9).

The response about the prestressed static state, ``q = q_S + q̄``, is projected on mass-normalised
normal modes of the prestressed linear system (:mod:`drillstring.modal`):
``q̄ = Φ η``, ``Φᵀ (M + M_f) Φ = I``, ``Φᵀ (K + K_g + K_f) Φ = diag(ω²)``. The basis holds the rigid
axial translation, ``n_a`` elastic axial modes, ``n_t`` torsional modes (top fixed) and ``n_l``
lateral modes in each plane. The reduced equations are

    η̈ + (D + Φᵀ C_f Φ) η̇ + diag(ω²) η = Φᵀ (f_NL(q, q̇) + wob e_bit,u) + g

where ``D`` is the structural damping and ``g`` the constant generalised force of the damping of the
imposed top rotation (:mod:`drillstring.damping`: by default ξ, c1 and c2 defined on the free–free
modes, giving a dense torsional block; or ``2 ξ ω_i`` on every basis mode;
:attr:`ReducedOrderModel.generalized_force`, zero when not given), ``C_f`` the fluid (Coriolis + viscous)
damping, and ``wob e_bit,u`` removes the static bit reaction that ``q_S`` already balances (the hook force
stays equal to the static weight-on-hook, docs/model.md §6). The top rotation is imposed:
``θx(x, t) = Ω t + (Φ η)_θx``, so the total spin speed is ``Ω + (Φ η̇)_θx``; or, with a top drive
(:mod:`drillstring.forces.top_drive`), the torsional family is free at the top (rigid rotation first, the
top drive's inertia lumped at the top node), ``θx = (Φ η)_θx`` carries the whole spin, the motor torque
``τ_m`` adds ``φ_top τ_m`` to the torsional equations and the controller's states follow the modal
coordinates in the state vector ``[η, η̇, s]``. ``bit_rock.law = "off_bottom"`` removes the bit–rock force.
A downhole motor (:mod:`drillstring.forces.motor`) releases the rotation at its rotor station
(:mod:`drillstring.rotor`: the torsional basis is that of the released string) and adds its torque ``T(ω_m)``
along the rotor's relative row ``φ_r − φ_k``, ``ω_m = (φ_r − φ_k)ᵀ η̇``.

``f_NL`` (case 2, ``nonlinear = "bit_and_contact"``) is the Tucker–Wang bit–rock force and torque at
the bit node, the borehole shocks and rubbing at the contact stations
(:class:`~drillstring.forces.contact.ContactStations`: the wall is a distributed stiffness ``k'_sh``
[N/m per m of string], lumped by nodal quadrature, so the contact law does not change with the mesh)
and the loads that turn with the string (mass imbalance, stress-free bow:
:mod:`drillstring.forces.excitation`), evaluated in physical DOFs and projected. The turning loads
follow the local rotation ``Ω t + (Φ η)_θx``, so the right-hand side depends on ``t``.

The right-hand side is a Numba-compiled kernel over preallocated arrays; every compiled kernel takes
one structured argument (:class:`RhsData`, :class:`FullModelData`, :class:`ObserveData`, named tuples
built once by :class:`ReducedOrderModel`), and :func:`evaluate_rhs` picks the case-1 or case-2 kernel by
the type of that argument when it is compiled.

**The model's interface to the compiled step loop** (:mod:`drillstring.dynamics.compiled`, which names
nothing else of this module): the run's :class:`KernelData` (:meth:`ReducedOrderModel.kernel_data`: the
model's data ``rhs_data``, ``case2_data``, read only, with the run's own scratch and bit history) and four
public functions of them — :func:`evaluate_rhs` (dy/dt), :func:`observe_kernel` (one observation row),
:func:`impacts_kernel` (impacts at an accepted step) and :func:`observation_width` (the row's columns).
The components are called inside these kernels, so the loop never names a law: every kind the registry
dispatches through its compiled dispatch (:mod:`drillstring.forces.registry`, their numbers in
``RhsData.laws``); the turning loads of every registered source through their one shared kernel
(:mod:`drillstring.forces.turning_loads`).

The model lives in :mod:`drillstring.dynamics.reduced`, part by part; this module gathers its public names:

- :mod:`~drillstring.dynamics.reduced.model`: :class:`ReducedOrderModel` (the basis, its linear parts, the
  components and the kernels' data built from them), :func:`rigid_axial_column`, the impacts of a run;
- :mod:`~drillstring.dynamics.reduced.build`: :func:`reduced_model`, :func:`case_reduced_model` (from a case),
  :func:`case_hook_load`;
- :mod:`~drillstring.dynamics.reduced.terms`: the compiled inner kernels, one per term of the right-hand side;
- :mod:`~drillstring.dynamics.reduced.frame`: the frame, each station's spin from the state (one place);
- :mod:`~drillstring.dynamics.reduced.rhs`: the compiled right-hand side of case 2 and case 1,
  :func:`evaluate_rhs` and :func:`stiff_part`;
- :mod:`~drillstring.dynamics.reduced.observation`: :data:`OBSERVABLES`, the observation and the impacts
  (:func:`observe_kernel`, :func:`impacts_kernel`, :func:`accepted_step_kernel`);
- :mod:`~drillstring.dynamics.reduced.reference`: the NumPy right-hand side (:meth:`ReducedOrderModel.rhs_reference`).
"""

from __future__ import annotations

from drillstring.dynamics.kernel_data import (  # the kernels' data, by name
    AXIAL_ROW,
    AXIAL_ROWS,
    TORSION_ROW,
    TORSION_ROWS,
    ContactData,
    ContactWork,
    DelayedRhsData,
    FullModelData,
    KernelData,
    ModalRanges,
    ObserveData,
    RhsData,
)
from drillstring.dynamics.reduced.build import case_hook_load, case_reduced_model, reduced_model
from drillstring.dynamics.reduced.model import ImpactCounter, ReducedOrderModel, rigid_axial_column
from drillstring.dynamics.reduced.observation import (
    OBSERVABLE_COLUMN,
    OBSERVABLES,
    PROBE_COLUMN,
    accepted_step_kernel,
    impacts_kernel,
    new_contact_zones,
    observation_width,
    observe_kernel,
    observe_row,
    observes_rate,
)
from drillstring.dynamics.reduced.rhs import BIT_LAW_SCALES, BIT_LAW_STEP, evaluate_rhs, stiff_part
from drillstring.dynamics.reduced.terms import VECTOR_MATH, diagonal_blocks, inner_kernel

# kernels of the parts that the step loop (_rhs_kernel) and the tests call by these names
from drillstring.dynamics.reduced.rhs import _cholesky_solve, _rhs_full_kernel, _rhs_kernel  # noqa: F401, E402
from drillstring.dynamics.reduced.terms import _surely_clear  # noqa: F401, E402

__all__ = [
    "AXIAL_ROW", "AXIAL_ROWS", "BIT_LAW_SCALES", "BIT_LAW_STEP", "OBSERVABLES", "OBSERVABLE_COLUMN", "PROBE_COLUMN",
    "TORSION_ROW", "TORSION_ROWS", "VECTOR_MATH", "ContactData", "ContactWork", "DelayedRhsData", "FullModelData",
    "ImpactCounter", "KernelData", "ModalRanges", "ObserveData", "ReducedOrderModel", "RhsData",
    "accepted_step_kernel", "case_hook_load", "case_reduced_model", "diagonal_blocks", "evaluate_rhs",
    "impacts_kernel", "inner_kernel", "new_contact_zones", "observation_width", "observe_kernel", "observe_row",
    "observes_rate", "reduced_model", "rigid_axial_column", "stiff_part",
]
