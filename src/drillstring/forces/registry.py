"""The component protocol: the model's laws are components that register themselves (docs/extending.md); the
kinds, each described below, are the registry's (``_REGISTRY``).

A **component** is one module holding one class. The class is its parameters (built from the case by
``from_case``), and declares everything the reduced model, the integrators and the stability analysis ask of
it; nobody else names the component. Registering is one decorator, :func:`register`; docs/extending.md
walks through adding a law.

**Bit–rock laws** (:class:`BitLaw`): the force and torque the rock exerts on the string at the bit,
from a named context (:class:`BitContext`: time, bit position and angle, axial velocity, bit speed, depth
of cut, static weight-on-bit), never from positional arguments. A law declares ``name``, ``kernel_size``
(how many numbers its compiled kernel reads), ``kernel_array()`` (those numbers), ``kernel`` (the compiled
kernel, ``kernel(args, ctx) -> (axial_force, torque)``), ``evaluate_at(ctx)`` (the kernel at array
fields, broadcast; inherited), ``jacobian_kernel`` (its compiled Jacobian, ``(args, ctx) -> (f_u, f_θ, f_d, t_u,
t_θ, t_d)``; ``jacobian_at(ctx)``, ``[[f_u, f_θ], [t_u, t_θ]]``, and ``depth_partials(ctx)`` call it, inherited)
and ``steady_drilling(bit_speed,
axial_load, resistance)`` (the steady state, :class:`BitSteadyState`: the stability analysis asks the law,
it never samples it). A law that reads the depth of cut (``delayed = True``) also gives ``sector`` (the
lag angle).

**Top boundaries** (:class:`TopBoundary`): the top of the torsion; those that drive the string
(``drives = True``) declare ``n_states`` (their own states, integrated with the modal coordinates),
``kernel(args, ctx, states, rates) -> motor torque`` (reading the named context :class:`TopContext`; writes
the states' rates), ``evaluate_at(ctx, states) -> (torque, rates)``, ``jacobian_at(ctx, states)`` (at that
operating point; rows: torque then each state's rate; columns: quill speed, surface torque, then each state),
``steady_states(motor_torque, surface_torque)``, ``top_inertia``, ``steady_speed(motor_torque)`` and
``check_steady_torque``. The case's ``top_drive.boundary`` names it (``"top_drive"`` by default).

**Contact laws** (:class:`ContactLaw`): the force of the borehole wall on the string at the contact
stations outside their clearance, from the named context :class:`ContactContext` (arrays over those stations:
lateral displacements and velocities, spin speed, gap, outer diameter, station stiffness): ``kernel(args, ctx,
force_v, force_w, torque)`` fills the three arrays, ``evaluate_at(ctx) -> (force_v, force_w, torque)`` gives
them from Python and ``jacobian_at(ctx)`` the (n, 3, 5) partials over (v, w, v̇, ẇ, θ̇x) per station.
``reads_lateral_velocity`` says whether the kernels must gather the stations' lateral velocities for it (they
are left at 0 otherwise). The case's ``[contact]`` holds its keys.

**Turning-load sources** (:class:`TurningLoadSource`): loads fixed to the string's sections that turn with
them (mass imbalance, a stress-free bow, :mod:`drillstring.forces.turning_loads`). They share one compiled
kernel (a load fixed in the rotating section, scaled by 1 or by the local spin speed squared), so a source
declares no kernel: its ``keys``, ``from_case(case)`` and ``loads(mesh)`` (its entries, a
:class:`~drillstring.forces.excitation.TurningLoads`); the reduced model projects the entries of every source
on its modes once. A source from outside the package therefore runs in the compiled kernels too (passed
explicitly: the case builds the package's sources only, in their declared ``order``).

**Hook loads** (:class:`HookLoad`): the extra axial force the hook applies at the string's top relative to the
static state (a ramped start slacks off the weight-on-bit, :mod:`drillstring.forces.hook_load`), a prescribed
function of the named context :class:`HookContext` (time, static weight-on-bit): ``kernel(args, ctx) -> force``
and ``evaluate_at(ctx)``; it has no Jacobian on the state (it reads none). ``active`` says whether the run
starts off bottom (``clearance`` [m] above the rock, the string hanging from the hook). The case's
``initial.start`` names it (``"on_bottom"``: none, code 0, the kernels add nothing; ``"ramp"``).

**Downhole motors** (:class:`Motor`): a rotor between two sections (:mod:`drillstring.rotor` releases its
rotation), ``kernel(args, ctx, states, rates) -> torque`` (+T on the rotor side, −T on the stator side; the
named context :class:`MotorContext`; writes its states' rates), ``jacobian_kernel(args, ctx, states) ->
dT/dω_m`` (compiled), ``evaluate_at(ctx, states) -> (torque, rates)``, ``jacobian_at(ctx, states)`` (rows: torque then each state's rate; columns: the relative speed, then
each state), ``steady_states(relative_speed)``, ``position`` (the rotor station [m]) and ``n_states``; the
kernels call :func:`motor_torque` when the header's ``motor_code`` is not 0 (and the stiff part :func:`motor_slope`).

Every component also declares ``keys``, its case keys as its own pydantic model with units and bounds
(:class:`~drillstring.case.TuckerWangKeys`, ...), and the case names it in its kind's table (``bit_rock.law``,
``top_drive.boundary``, ``contact.law``, ``motor.law``). A component's keys live in its own sub-table of that
table, ``[bit_rock.<name>]``, read by :func:`case_keys`, so two components may use the same key name; the
package's built-in components keep their keys in the kind's table itself, as case files have always written
them.

**Codes are stable.** A component's code in the kernels' array is derived from its kind and name
(:func:`name_code`; or given explicitly, ``component_code`` in its class body), never from its rank among the
registered names: registering another component never changes the code of one already there. The kernel cache
is keyed on every source file of the package and checks the table of names and codes it was compiled with
(:func:`drillstring.kernel_cache.check_registry`, called by :func:`pack`).

**Offsets are computed, never written.** The compiled kernels read every component's numbers from one
flat float array (one field of the kernels' data: every field is an argument of each inner kernel, and
more fields made the reference realization 30 % slower, measured): a header of :data:`HEADER` entries (the
codes of the components and where their slices start), then the bit law's numbers (from
:data:`BIT_LAW`), the top boundary's, the hook load's and the bit's history, each where
:func:`pack` puts it. The states of the components follow the modal coordinates in the state vector at
the offsets :func:`pack` computes from their ``n_states``.

**Compiled dispatch.** The kernels call one dispatch function per kind whose components have kernels of their
own (``_DISPATCHED`` says which; the turning-load sources share one kernel instead); when they are compiled, the registry writes the dispatch over the codes of the package's registered components, each
component's kernel inlined into it at Numba's IR level (one compiled function per kind, not one per kernel;
likewise the bit laws' and motors' compiled Jacobians, :func:`bit_law_jacobian` and :func:`motor_slope`, with
central differences of the kernel for a component that declares none)
(:func:`package_components` imports every module of :mod:`drillstring.forces` first, so the set is the
same in every process and the on-disk kernel cache, keyed on the package's sources, stays valid). A
component registered from **outside the package** (a test, a user's script) runs through the NumPy
reference engine (``simulate_model(..., engine="reference")``) and the stability analysis; the compiled
engine refuses it with a clear error. Why: the cached kernels are keyed on the package's sources only
(:mod:`drillstring.kernel_cache`), so an outside kernel compiled into them would be left out of, or stale in,
the cache; compiling it in means a step loop of its own type per process (a cold compile, docs/extending.md).
"""

from __future__ import annotations

import importlib
import pkgutil
import zlib
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba.core.extending import overload

from drillstring.forces.protocol import (  # noqa: F401 (the protocol's names, re-exported: documented there)
    BIT_LAW_SCALES,
    BIT_LAW_STEP,
    BitContext,
    BitLaw,
    BitSteadyState,
    ContactContext,
    ContactLaw,
    HookContext,
    HookLoad,
    Motor,
    MotorContext,
    StringFriction,
    StringFrictionContext,
    TopBoundary,
    TopContext,
    TurningLoadSource,
    bit_context,
    differenced_bit_jacobian,
    differenced_motor_slope,
)

__all__ = [
    "BIT_LAW",
    "HISTORY",
    "HOOK_LOAD",
    "HOOK_LOAD_CODE",
    "MOTOR",
    "MOTOR_CODE",
    "MOTOR_STATES",
    "STRING_FRICTION",
    "STRING_FRICTION_CODE",
    "string_friction",
    "string_friction_forces",
    "string_frictions",
    "TOP_BOUNDARY_CODE",
    "TOP_INERTIA",
    "HEADER",
    "CONTACT_LAW",
    "CONTACT_LAW_CODE",
    "contact_law",
    "contact_law_forces",
    "contact_laws",
    "Layout",
    "bit_law",
    "bit_law_force",
    "bit_law_jacobian",
    "bit_laws",
    "case_keys",
    "compiled",
    "hook_load",
    "hook_load_force",
    "hook_loads",
    "turning_load_source",
    "turning_load_sources",
    "motor",
    "motor_slope",
    "motor_torque",
    "motors",
    "name_code",
    "pack",
    "package_components",
    "register",
    "registry_table",
    "top_boundaries",
    "top_boundary",
    "top_boundary_torque",
]

#: The header of the kernels' flat array: the bit law's code, the top boundary's code (0: it does not drive
#: the string), where the top boundary's numbers start, the index of its first state in the state vector, the
#: inertia [kg·m²] it lumps at the quill (0 when it does not drive), where the hook load's numbers start, where the
#: bit's history starts, the hook load's code (0: none, the kernels add nothing), the contact law's code and where
#: its numbers start, the downhole motor's code (0: none), where its numbers start and the index of its first state,
#: the along-string friction's code (0: none, the kernels add nothing) and where its numbers start.
HEADER = ("bit_law_code", "top_boundary_code", "top_boundary", "top_boundary_states", "top_inertia", "hook_load",
          "history", "hook_load_code", "contact_law_code", "contact_law",
          "motor_code", "motor", "motor_states", "string_friction_code", "string_friction")
(BIT_LAW_CODE, TOP_BOUNDARY_CODE, TOP_BOUNDARY, TOP_BOUNDARY_STATES, TOP_INERTIA, HOOK_LOAD, HISTORY,
 HOOK_LOAD_CODE, CONTACT_LAW_CODE, CONTACT_LAW, MOTOR_CODE, MOTOR, MOTOR_STATES, STRING_FRICTION_CODE,
 STRING_FRICTION) = range(len(HEADER))
#: Where the bit law's numbers start (right after the header).
BIT_LAW = len(HEADER)



_REGISTRY: dict[str, dict[str, type]] = {"bit_law": {}, "top_boundary": {}, "hook_load": {}, "contact_law": {},
                                          "turning_load": {}, "motor": {}, "string_friction": {}}
_KINDS = {BitLaw: "bit_law", TopBoundary: "top_boundary", HookLoad: "hook_load", ContactLaw: "contact_law",
          TurningLoadSource: "turning_load", Motor: "motor", StringFriction: "string_friction"}
#: whether a registered class of each kind enters the compiled dispatch (has a nonzero code)
_DISPATCHED = {"bit_law": lambda c: True, "top_boundary": lambda c: c.drives, "hook_load": lambda c: c.adds,
               "contact_law": lambda c: True, "turning_load": lambda c: False,
               "motor": lambda c: True, "string_friction": lambda c: True}


def _kind(cls: type) -> str:
    for base, kind in _KINDS.items():
        if issubclass(cls, base):
            return kind
    raise TypeError(f"{cls.__name__} is not a BitLaw, a TopBoundary, a HookLoad, a ContactLaw, a "
                    "TurningLoadSource, a Motor or a StringFriction")


def _in_package(cls: type) -> bool:
    return cls.__module__.split(".")[0] == __name__.split(".")[0]


#: Codes derived from names lie in [1, CODE_RANGE] (exact in float64).
CODE_RANGE = 2**24


def name_code(kind: str, name: str) -> float:
    """The code of the component ``name`` of ``kind`` derived from its name alone (CRC-32 of ``kind:name``
    folded into [1, :data:`CODE_RANGE`]): the same in every process and version, whatever else is registered."""
    return float(zlib.crc32(f"{kind}:{name}".encode()) % CODE_RANGE + 1)


def register(cls: type) -> type:
    """Class decorator: register a component under its ``name``. Its code is given in its class body
    (``component_code``, a positive whole number) or derived from its kind and name (:func:`name_code`),
    never from the other registered names; 0 for one that the kernels skip (a top boundary that does not
    drive, a hook load that adds nothing); negative for one from outside the package (never in the compiled
    dispatch). ValueError when another class of the package holds the name or the code."""
    kind = _kind(cls)
    table = _REGISTRY[kind]
    known = table.get(cls.name)
    if known is not None and _in_package(known) and \
            (known.__module__, known.__qualname__) != (cls.__module__, cls.__qualname__):
        raise ValueError(f"{kind} {cls.name!r} is already registered by {known.__module__}.{known.__qualname__}")
    given = cls.__dict__.get("component_code")
    code = float(given) if given is not None and given > 0.0 else name_code(kind, cls.name)
    if not _DISPATCHED[kind](cls):
        code = 0.0
    elif not _in_package(cls):
        code = -code
    clash = [c for n, c in table.items() if n != cls.name and code != 0.0 and c.component_code == code]
    if clash:
        raise ValueError(f"{kind} {cls.name!r}: its code {code:g} is that of {clash[0].name!r}: give it "
                         f"another name or an explicit component_code")
    cls.component_code = code
    table[cls.name] = cls
    return cls


def registry_table() -> dict[str, dict[str, float]]:
    """kind -> {name: code} of the package's components that the compiled dispatch holds (code > 0)."""
    package_components()
    return {kind: {name: c.component_code for name, c in sorted(table.items())
                   if _in_package(c) and c.component_code > 0.0}
            for kind, table in _REGISTRY.items()}


_CHECKED: list = []


def _check_cache_table() -> None:
    """The kernel cache's check of :func:`registry_table` (once per process and table)."""
    table = registry_table()
    if _CHECKED != [table]:
        from drillstring.kernel_cache import check_registry

        check_registry(table)
        _CHECKED[:] = [table]


def case_keys(table, cls: type):
    """The keys of the component ``cls`` from its case ``table`` (the kind's table of a case, e.g.
    ``case.bit_rock``): its own sub-table ``[<kind table>.<name>]`` validated by its ``keys`` model (units
    converted, bounds checked); a built-in component's keys are the kind's table itself."""
    extra = getattr(table, "model_extra", None) or {}
    if cls.name in extra:
        return cls.keys.model_validate(dict(extra[cls.name]))
    if cls.keys is not None and isinstance(table, cls.keys):
        return table
    return cls.keys.model_validate({})


_LOADED = False


def package_components() -> None:
    """Import every module of :mod:`drillstring.forces` once, so that every component of the package is
    registered (their set, hence their codes and the compiled dispatch, is the same in every process)."""
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    package = importlib.import_module("drillstring.forces")
    for info in pkgutil.iter_modules(package.__path__):
        importlib.import_module(f"drillstring.forces.{info.name}")


def _lookup(kind: str, name: str, field: str | None = None):
    package_components()
    table = _REGISTRY[kind]
    if name not in table:
        what = f"{field} = {name!r}" if field else f"{kind.replace('_', ' ')} {name!r}"
        raise ValueError(f"{what}: must be one of {', '.join(sorted(table))} (the registered "
                         f"{kind.replace('_', ' ')}s)")
    return table[name]


def bit_law(name: str, field: str | None = None) -> type[BitLaw]:
    """The registered bit–rock law ``name`` (ValueError naming the registered ones otherwise, and the case's
    ``field`` that gave the name, if any)."""
    return _lookup("bit_law", name, field)


def top_boundary(name: str, field: str | None = None) -> type[TopBoundary]:
    """The registered top boundary ``name``."""
    return _lookup("top_boundary", name, field)


def hook_load(name: str) -> type[HookLoad]:
    """The registered hook load ``name`` (the case's ``initial.start``)."""
    return _lookup("hook_load", name)


def contact_law(name: str, field: str | None = None) -> type[ContactLaw]:
    """The registered contact law ``name``."""
    return _lookup("contact_law", name, field)


def contact_laws() -> tuple[str, ...]:
    """Names of the registered contact laws."""
    package_components()
    return tuple(sorted(_REGISTRY["contact_law"]))


def turning_load_sources(package_only: bool = False) -> tuple[str, ...]:
    """Names of the registered turning-load sources, in their ``order`` (then by name); ``package_only``: the
    package's only."""
    package_components()
    table = _REGISTRY["turning_load"]
    return tuple(sorted((n for n, c in table.items() if _in_package(c) or not package_only),
                        key=lambda n: (table[n].order, n)))


def turning_load_source(name: str) -> type[TurningLoadSource]:
    """The registered turning-load source ``name``."""
    return _lookup("turning_load", name)


def hook_loads() -> tuple[str, ...]:
    """Names of the registered hook loads."""
    package_components()
    return tuple(sorted(_REGISTRY["hook_load"]))


def motor(name: str, field: str | None = None) -> type[Motor]:
    """The registered downhole motor ``name``."""
    return _lookup("motor", name, field)


def motors() -> tuple[str, ...]:
    """Names of the registered downhole motors."""
    package_components()
    return tuple(sorted(_REGISTRY["motor"]))


def string_friction(name: str, field: str | None = None) -> type[StringFriction]:
    """The registered along-string friction law ``name``."""
    return _lookup("string_friction", name, field)


def string_frictions() -> tuple[str, ...]:
    """Names of the registered along-string friction laws."""
    package_components()
    return tuple(sorted(_REGISTRY["string_friction"]))


def bit_laws() -> tuple[str, ...]:
    """Names of the registered bit–rock laws."""
    package_components()
    return tuple(sorted(_REGISTRY["bit_law"]))


def top_boundaries() -> tuple[str, ...]:
    """Names of the registered top boundaries."""
    package_components()
    return tuple(sorted(_REGISTRY["top_boundary"]))


def compiled(component) -> bool:
    """True when the compiled kernels dispatch to ``component`` (a package component)."""
    return _in_package(type(component))


# ---------------------------------------------------------------------------------------------------------
# The flat array of the kernels and the state vector: offsets computed from the components' sizes
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Layout:
    """Where each component's numbers start in the kernels' array and where each component's states start
    in the state vector (absolute indices)."""

    numbers: dict[str, int]
    states: dict[str, int]
    state_size: int


def pack(bit: BitLaw, top: TopBoundary, hook: HookLoad, history: np.ndarray,
         modal_states: int, contact: ContactLaw | None = None,
         motor: Motor | None = None, friction: StringFriction | None = None) -> tuple[np.ndarray, Layout]:
    """The kernels' flat array ``[header, bit law, top boundary, hook load, contact law, motor, string friction,
    history]`` (the history
    last: it runs to the end) and its :class:`Layout`; the top boundary's states follow the ``modal_states``
    entries ``[η, η̇]``, the motor's (none for the package's motors) the top boundary's. ``contact`` None: no
    contact law (code 0, its kernel gives no force); ``motor`` None: no downhole motor (code 0); ``friction`` None:
    no along-string friction (code 0)."""
    _check_cache_table()  # every package component registered; the cached kernels were written for this table
    parts = {"bit_law": np.asarray(bit.kernel_array(), dtype=np.float64),
             "top_boundary": np.asarray(top.kernel_array(), dtype=np.float64),
             "hook_load": np.asarray(hook.kernel_array(), dtype=np.float64),
             "contact_law": np.asarray(contact.kernel_array() if contact is not None else np.zeros(0), dtype=np.float64),
             "motor": np.zeros(0) if motor is None else np.asarray(motor.kernel_array(), dtype=np.float64),
             "string_friction": np.zeros(0) if friction is None else np.asarray(friction.kernel_array(),
                                                                                  dtype=np.float64),
             "history": np.asarray(history, dtype=np.float64)}
    checked = [("bit law", bit), ("top boundary", top), ("hook load", hook)] + (
        [("contact law", contact)] if contact is not None else []) + ([("motor", motor)] if motor is not None else []) + (
        [("string friction", friction)] if friction is not None else [])
    for kind, component in checked:
        values = parts[kind.replace(" ", "_")]
        if values.shape != (type(component).kernel_size,):
            raise ValueError(f"{kind} {component.name!r}: kernel_array() has {values.size} numbers, "
                             f"kernel_size says {type(component).kernel_size}")
    numbers, offset = {}, BIT_LAW
    for name, values in parts.items():
        numbers[name] = offset
        offset += values.size
    states = {"top_boundary": modal_states, "motor": modal_states + top.n_states}
    size = modal_states + top.n_states + (0 if motor is None else motor.n_states)
    header = np.zeros(len(HEADER))
    header[BIT_LAW_CODE] = bit.component_code
    header[TOP_BOUNDARY_CODE] = top.component_code if top.drives else 0.0
    header[TOP_BOUNDARY] = numbers["top_boundary"]
    header[TOP_BOUNDARY_STATES] = states["top_boundary"]
    header[TOP_INERTIA] = top.top_inertia if top.drives else 0.0
    header[HOOK_LOAD] = numbers["hook_load"]
    header[HISTORY] = numbers["history"]
    header[HOOK_LOAD_CODE] = hook.component_code if hook.adds else 0.0
    header[CONTACT_LAW_CODE] = contact.component_code if contact is not None else 0.0
    header[CONTACT_LAW] = numbers["contact_law"]
    header[MOTOR_CODE] = 0.0 if motor is None else motor.component_code
    header[MOTOR] = numbers["motor"]
    header[MOTOR_STATES] = states["motor"]
    header[STRING_FRICTION_CODE] = 0.0 if friction is None else friction.component_code
    header[STRING_FRICTION] = numbers["string_friction"]
    return np.concatenate([header, *parts.values()]), Layout(numbers, states, size)


# ---------------------------------------------------------------------------------------------------------
# Compiled dispatch, written from the registry when the kernels are compiled
# ---------------------------------------------------------------------------------------------------------


def bit_law_force(laws, ctx):
    """``(axial_force [N], torque [N·m])`` of the bit law whose code and numbers ``laws`` holds (the kernels'
    flat array) at the context ``ctx`` (:class:`BitContext`); NaN for a code no package law has. Compiled
    code only."""
    raise NotImplementedError("compiled code only")


def top_boundary_torque(laws, ctx, y, out):
    """The motor torque [N·m] of the top boundary whose code and numbers ``laws`` holds, at ``ctx``
    (:class:`TopContext`), reading its states in ``y`` and writing their rates in ``out`` at the index the
    header gives; NaN for a code no package boundary has. Compiled code only."""
    raise NotImplementedError("compiled code only")


def hook_load_force(laws, ctx):
    """The extra axial force [N] on the string's top of the hook load whose code and numbers ``laws`` holds, at
    ``ctx`` (:class:`HookContext`): 0 for code 0 (none), NaN for a code no package hook load has. Compiled code
    only."""
    raise NotImplementedError("compiled code only")


def contact_law_forces(laws, ctx, force_v, force_w, torque):
    """Fill ``force_v``, ``force_w`` [N] and ``torque`` [N·m] at the stations of ``ctx`` (:class:`ContactContext`)
    with the contact law whose code and numbers ``laws`` holds: 0 for code 0 (none), NaN for a code no package
    law has. Compiled code only."""
    raise NotImplementedError("compiled code only")


def string_friction_forces(laws, ctx, force, torque):
    """Fill ``force`` [N] (along the string) and ``torque`` [N·m] (about it) at the stations of ``ctx``
    (:class:`StringFrictionContext`) with the along-string friction law whose code and numbers ``laws`` holds: 0
    for code 0 (none), NaN for a code no package law has. Compiled code only."""
    raise NotImplementedError("compiled code only")


def motor_torque(laws, ctx, y, out):
    """The torque [N·m] of the downhole motor whose code and numbers ``laws`` holds at ``ctx``
    (:class:`MotorContext`), reading its states in ``y`` and writing their rates in ``out`` at the index the
    header gives; NaN for a code no package motor has. Compiled code only."""
    raise NotImplementedError("compiled code only")


_CODE_ENTRY = {"bit_law": BIT_LAW_CODE, "top_boundary": TOP_BOUNDARY_CODE, "hook_load": HOOK_LOAD_CODE,
               "contact_law": CONTACT_LAW_CODE, "motor": MOTOR_CODE, "string_friction": STRING_FRICTION_CODE}


def inlined(function):
    """``function`` (a Numba dispatcher or a plain function) as a dispatcher that Numba inlines into its compiled
    callers at the IR level, before typing: no compiled function of its own (the registry's dispatch inlines each
    component's kernel; the step loop, its step kind's functions)."""
    from numba import njit

    return njit(inline="always")(getattr(function, "py_func", function))


def _dispatch(kind: str, signature: str, call: str, fallback: str, none: str | None = None, member=None,
              helpers: dict | None = None, title: str = "dispatch"):
    """The dispatch over the package's components of ``kind`` by their code (a function written from the
    registry's table and compiled by Numba into its callers); ``none``: what code 0 returns (first test), when
    the kind has a component that adds nothing; ``member(cls) -> (function, call)``: what is dispatched to
    instead of ``cls.kernel`` called with ``call`` (a component's compiled Jacobian); ``helpers``: more names
    the source reads; ``title``: the source's name in tracebacks."""
    _check_cache_table()
    entries = sorted((c.component_code, c) for c in _REGISTRY[kind].values()
                     if _in_package(c) and c.component_code > 0.0)
    namespace: dict[str, Any] = {"np": np, **(helpers or {})}
    lines = [f"def dispatch({signature}):", f"    code = laws[{_CODE_ENTRY[kind]}]"]
    if none is not None:
        lines += ["    if code == 0.0:", f"        return {none}"]
    for i, (code, cls) in enumerate(entries):
        function, arguments = (cls.kernel, call) if member is None else member(cls)
        namespace[f"kernel_{i}"] = inlined(function)
        lines.append(f"    if code == {code!r}:")
        lines.append(f"        return kernel_{i}({arguments})")
    lines.append(f"    return {fallback}")
    exec(compile("\n".join(lines) + "\n", f"<{title}>", "exec"), namespace)
    return namespace["dispatch"]


@overload(bit_law_force)
def _bit_law_force_compiled(laws, ctx):
    return _dispatch("bit_law", "laws, ctx", f"laws[{BIT_LAW}:], ctx", "np.nan, np.nan",
                     title="bit_law_force dispatch")


def bit_law_jacobian(laws, ctx):
    """``(f_u, f_θ, f_d, t_u, t_θ, t_d)``: the partials of :func:`bit_law_force` in the axial velocity [m/s],
    the bit speed [rad/s] and the depth of cut [m] at ``ctx``, from the law's own compiled ``jacobian_kernel``
    (the one its ``jacobian_at`` calls), or central differences of its kernel for a law that declares none
    (:func:`~drillstring.forces.protocol.differenced_bit_jacobian`); NaN for a code no package law has.
    Compiled code only."""
    raise NotImplementedError("compiled code only")


def _bit_law_jacobian_member(cls):
    jacobian = cls.jacobian_kernel
    if jacobian is None:
        jacobian = differenced_bit_jacobian(inlined(cls.kernel))
    return jacobian, f"laws[{BIT_LAW}:], ctx"


@overload(bit_law_jacobian)
def _bit_law_jacobian_compiled(laws, ctx):
    return _dispatch("bit_law", "laws, ctx", "", ", ".join(["np.nan"] * 6), member=_bit_law_jacobian_member,
                     title="bit_law_jacobian dispatch")


@overload(top_boundary_torque)
def _top_boundary_torque_compiled(laws, ctx, y, out):
    return _dispatch(
        "top_boundary", "laws, ctx, y, out",
        f"laws[int(laws[{TOP_BOUNDARY}]):], ctx, y[int(laws[{TOP_BOUNDARY_STATES}]):], "
        f"out[int(laws[{TOP_BOUNDARY_STATES}]):]", "np.nan", title="top_boundary_torque dispatch")


@overload(hook_load_force)
def _hook_load_force_compiled(laws, ctx):
    return _dispatch("hook_load", "laws, ctx", f"laws[int(laws[{HOOK_LOAD}]):], ctx", "np.nan", none="0.0",
                     title="hook_load_force dispatch")


def _fill(force_v, force_w, torque, value):
    for i in range(force_v.shape[0]):
        force_v[i] = value
        force_w[i] = value
        torque[i] = value


@overload(contact_law_forces)
def _contact_law_forces_compiled(laws, ctx, force_v, force_w, torque):
    from numba import njit

    return _dispatch(
        "contact_law", "laws, ctx, force_v, force_w, torque",
        f"laws[int(laws[{CONTACT_LAW}]):], ctx, force_v, force_w, torque", "fill(force_v, force_w, torque, np.nan)",
        none="fill(force_v, force_w, torque, 0.0)", helpers={"fill": njit(_fill)}, title="contact_law_forces dispatch")


@overload(motor_torque)
def _motor_torque_compiled(laws, ctx, y, out):
    return _dispatch(
        "motor", "laws, ctx, y, out",
        f"laws[int(laws[{MOTOR}]):], ctx, y[int(laws[{MOTOR_STATES}]):], out[int(laws[{MOTOR_STATES}]):]", "np.nan",
        title="motor_torque dispatch")


def motor_slope(laws, ctx, y, out):
    """``dT/dω_m`` [N·m·s/rad] of the downhole motor whose code and numbers ``laws`` holds at ``ctx``
    (:class:`MotorContext`), its states in ``y`` held: its own compiled ``jacobian_kernel`` (the one its
    ``jacobian_at`` calls), or a central difference of its kernel for a motor that declares none
    (:func:`~drillstring.forces.protocol.differenced_motor_slope`, writing the states' rates in ``out``, not
    kept); NaN for a code no package motor has. Compiled code only."""
    raise NotImplementedError("compiled code only")


_MOTOR_STATES_AT = f"int(laws[{MOTOR_STATES}])"


def _motor_slope_member(cls):
    arguments = f"laws[int(laws[{MOTOR}]):], ctx, y[{_MOTOR_STATES_AT}:]"
    if cls.jacobian_kernel is not None:
        return cls.jacobian_kernel, arguments
    return differenced_motor_slope(inlined(cls.kernel)), f"{arguments}, out[{_MOTOR_STATES_AT}:]"


@overload(motor_slope)
def _motor_slope_compiled(laws, ctx, y, out):
    return _dispatch("motor", "laws, ctx, y, out", "", "np.nan", member=_motor_slope_member,
                     title="motor_slope dispatch")


def _fill_two(force, torque, value):
    for i in range(force.shape[0]):
        force[i] = value
        torque[i] = value


@overload(string_friction_forces)
def _string_friction_forces_compiled(laws, ctx, force, torque):
    from numba import njit

    return _dispatch(
        "string_friction", "laws, ctx, force, torque",
        f"laws[int(laws[{STRING_FRICTION}]):], ctx, force, torque", "fill(force, torque, np.nan)",
        none="fill(force, torque, 0.0)", helpers={"fill": njit(_fill_two)}, title="string_friction_forces dispatch")
