"""The reduced model's compiled right-hand side (docs/model.md §5–§9): dy/dt of case 2 (the bit–rock law, the
top boundary, the downhole motor, the turning loads and the contact on the linear modal equations) and of case 1
(case 2 plus the strain- and kinetic-energy forces), :func:`evaluate_rhs` picking one by the type of its data,
and the stiff part an implicit step reads (:func:`stiff_part`). The inner kernels per term are in
:mod:`drillstring.dynamics.reduced.terms`.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import overload

from drillstring.dynamics.kernel_data import DelayedRhsData, FullModelData, RhsData
from drillstring.dynamics.reduced.frame import (
    frame_speed,
    lateral_displacements,
    station_lateral_velocity,
    station_spin,
)
from drillstring.dynamics.reduced.terms import (
    _AXIAL_BIT,
    _AXIAL_TOP,
    _TORSION_BIT,
    _TORSION_MOTOR,
    _bit_rock,
    _bit_state,
    _block_damping,
    _delayed,
    _depth_of_cut,
    _downhole_motor,
    _is,
    _motor_speed,
    _string_friction,
    _surely_clear,
    _top_drive,
    _turning_loads,
    inner_kernel,
)
from drillstring.forces.nonlinear import _kinetic_forces_kernel, _strain_energy_forces_kernel
from drillstring.forces.registry import (  # noqa: F401 (BIT_LAW_SCALES, BIT_LAW_STEP: re-exported by rom)
    BIT_LAW_SCALES,
    BIT_LAW_STEP,
    MOTOR_CODE,
    STRING_FRICTION_CODE,
    TOP_BOUNDARY_CODE,
    BitContext,
    ContactContext,
    HookContext,
    MotorContext,
    bit_law_force,
    bit_law_jacobian,
    contact_law_forces,
    hook_load_force,
    motor_slope,
)


@njit(cache=True, _nrt=False)
def _rhs_kernel(d, t, y, out):
    """dy/dt of the case-2 ROM (module docstring) at time ``t`` [s] from :class:`RhsData` ``d``; contact
    work is done only at the stations that touch the borehole. Compiled without Numba's reference counting
    (``_nrt=False``: it allocates nothing; the counting of the arrays of ``d`` cost 3/4 of its time)."""
    n = d.omega2.shape[0]
    ranges = d.ranges
    a0, a1, t0, t1, y0, y1, z0, z1 = (ranges.axial_start, ranges.axial_end, ranges.torsion_start, ranges.torsion_end,
                                      ranges.lateral_y_start, ranges.lateral_y_end, ranges.lateral_z_start,
                                      ranges.lateral_z_end)
    eta = y[:n]
    eta_dot = y[n:]
    acc = out[n:]
    # linear part: -D η̇ - ω² η + the constant generalized force (D dense only where the fluid couples)
    for i in range(n):
        out[i] = eta_dot[i]
        acc[i] = d.generalized_force[i] - d.omega2[i] * eta[i]
    _block_damping(d.damping_t, d.damping_blocks, eta_dot, acc)
    if d.laws[TOP_BOUNDARY_CODE] != 0.0:
        _top_drive(d, t, y, out)
    if d.laws[MOTOR_CODE] != 0.0:  # a downhole motor: +T on the rotor side, -T on the stator side
        _, motor = _downhole_motor(d, t, y, out)
        for j in range(t0, t1):
            acc[j] += d.torsion_rows[_TORSION_MOTOR, j - t0] * motor
    # bit-rock interaction at the bit node; the hook's extra pull at the top during a ramped start
    axial_force, bit_torque, _, _, _, _ = _bit_rock(d, t, y)
    axial_force += d.weight_on_bit
    hook = hook_load_force(d.laws, HookContext(t, d.weight_on_bit))
    for j in range(a0, a1):
        acc[j] += d.axial_rows[_AXIAL_BIT, j - a0] * axial_force + d.axial_rows[_AXIAL_TOP, j - a0] * hook
    for j in range(t0, t1):
        acc[j] += d.torsion_rows[_TORSION_BIT, j - t0] * bit_torque
    if d.laws[STRING_FRICTION_CODE] != 0.0:  # the wall's friction along a string resting on it (a deviated well)
        _string_friction(d, t, y, acc)
    if y1 == y0 and z1 == z0:
        return
    _turning_loads(d, t, y, acc)
    # shocks and rubbing: find the stations outside the gap (none when a bound says no node can touch)
    if _surely_clear(d, eta):
        return
    c = d.contact
    cw = c.work
    lateral_displacements(d, eta, cw.v, cw.w)
    n_c = 0
    for k in range(c.node.shape[0]):
        i = c.node[k]
        if cw.v[i] * cw.v[i] + cw.w[i] * cw.w[i] > c.gap[k] * c.gap[k]:
            cw.stations[n_c] = k
            n_c += 1
    if n_c == 0:
        return
    for m in range(n_c):
        k = cw.stations[m]
        i = c.node[k]
        cw.v_c[m] = cw.v[i]
        cw.w_c[m] = cw.w[i]
        cw.gap[m] = c.gap[k]
        cw.outer_diameter[m] = c.outer_diameter[k]
        cw.stiffness[m] = c.stiffness[k]
        _, cw.spin[m] = station_spin(d, t, y, i, 0.0)
        vd = 0.0
        wd = 0.0
        if c.tangential:
            vd, wd = station_lateral_velocity(d, y, i)
        cw.v_dot[m] = vd
        cw.w_dot[m] = wd
    contact_law_forces(d.laws, ContactContext(cw.v_c[:n_c], cw.w_c[:n_c], cw.v_dot[:n_c], cw.w_dot[:n_c],
                                              cw.spin[:n_c], cw.gap[:n_c], cw.outer_diameter[:n_c],
                                              cw.stiffness[:n_c]),
                       cw.force_v[:n_c], cw.force_w[:n_c], cw.torque[:n_c])
    for m in range(n_c):
        i = c.node[cw.stations[m]]
        fv = cw.force_v[m]
        fw = cw.force_w[m]
        tq = cw.torque[m]
        for j in range(y0, y1):
            acc[j] += d.phi_v_t[j - y0, i] * fv
        for j in range(z0, z1):
            acc[j] += d.phi_w_t[j - z0, i] * fw
        for j in range(t0, t1):
            acc[j] += d.phi_tx_t[j - t0, i] * tq


@inner_kernel()
def _expand(shapes_t, dofs, y, offset, out):
    """out[dofs] += shapesᵀ-columns · y[offset:offset + n_f] (one family's part of Φη)."""
    for j in range(shapes_t.shape[0]):
        x = y[offset + j]
        if x != 0.0:
            for i in range(dofs.shape[0]):
                out[dofs[i]] += shapes_t[j, i] * x


@inner_kernel()
def _project(shapes_t, dofs, force, offset, out):
    """out[offset + j] = Σ_i shapes_t[j, i] force[dofs[i]] (one family's part of Φᵀ f)."""
    for j in range(shapes_t.shape[0]):
        total = 0.0
        for i in range(dofs.shape[0]):
            total += shapes_t[j, i] * force[dofs[i]]
        out[offset + j] = total


@njit(cache=True)
def _cholesky_solve(a, b, x):
    """x = a⁻¹ b for a symmetric positive definite ``a`` (n, n), by Cholesky ``a = L Lᵀ`` computed in the
    lower triangle of ``a`` (overwritten); ``x`` may be ``b`` itself. The case-1 mass ``I + Φᵀ M_nl Φ`` (here
    its Schur complement ``I − B Bᵀ``) is positive definite wherever the model holds
    (:mod:`drillstring.forces.nonlinear`); elsewhere (a non-positive pivot) ``x`` is NaN, which the
    integrator treats as a rejected step. Compiled loops instead of ``np.linalg.solve``: no
    allocation per call, and a fraction of the latter's compile time."""
    n = a.shape[0]
    for j in range(n):
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k]
        if not d > 0.0:
            x[:] = np.nan
            return
        d = np.sqrt(d)
        a[j, j] = d
        for i in range(j + 1, n):
            s = a[i, j]
            for k in range(j):
                s -= a[i, k] * a[j, k]
            a[i, j] = s / d
    for i in range(n):  # L z = b
        s = b[i]
        for k in range(i):
            s -= a[i, k] * x[k]
        x[i] = s / a[i, i]
    for i in range(n - 1, -1, -1):  # Lᵀ x = z
        s = x[i]
        for k in range(i + 1, n):
            s -= a[k, i] * x[k]
        x[i] = s / a[i, i]


@njit(cache=True, _nrt=False)
def _rhs_full_kernel(f, t, y, out):
    """Case 1 from :class:`FullModelData` ``f``: the case-2 right-hand side plus the strain- and
    kinetic-energy forces f_se and f_ke (:mod:`drillstring.forces.nonlinear`), evaluated on the physical
    state ``q̄ = Φη``, ``q̇ = Φη̇ + Ω`` (θx DOFs), projected on the basis. ``f_ke = f_vel − M_nl(q) q̈``:
    the configuration-dependent mass correction is moved to the left-hand side and
    ``(I + Φᵀ M_nl(Φη) Φ) η̈ = r`` is solved at every evaluation (exact, no lagged accelerations). Its only
    off-diagonal blocks are ``B`` (torsion × lateral y) and ``Bᵀ``: ``(I − B Bᵀ) a_t = r_t − B r_y``,
    ``a_y = r_y − Bᵀ a_t``, the other accelerations are ``r``."""
    _rhs_kernel(f.rhs, t, y, out)
    d = f.rhs
    n = d.omega2.shape[0]
    ranges = d.ranges
    a0, t0, t1, y0, y1, z0, z1 = (ranges.axial_start, ranges.torsion_start, ranges.torsion_end,
                                  ranges.lateral_y_start, ranges.lateral_y_end, ranges.lateral_z_start,
                                  ranges.lateral_z_end)
    f.q[:] = 0.0
    f.qd[:] = 0.0
    for shapes_t, dofs, offset in ((f.axial_shapes_t, f.axial_dofs, a0), (f.torsion_shapes_t, f.torsion_dofs, t0),
                                   (f.bending_y_shapes_t, f.bending_y_dofs, y0),
                                   (f.bending_z_shapes_t, f.bending_z_dofs, z0)):
        _expand(shapes_t, dofs, y, offset, f.q)
        _expand(shapes_t, dofs, y, n + offset, f.qd)
    spin = frame_speed(d)
    for i in range(f.theta_x_dofs.shape[0]):
        f.qd[f.theta_x_dofs[i]] += spin
    _strain_energy_forces_kernel(f.q, f.inv_length, f.weights, f.slope, f.axial_stiffness, f.f_se)
    _kinetic_forces_kernel(f.q, f.qd, f.xi, f.weights, f.rotation, f.polar_inertia, f.f_vel, f.coupling)
    for i in range(f.f_se.shape[0]):
        f.f_se[i] += f.f_vel[i]
    acc = f.acceleration
    acc[:] = 0.0
    for shapes_t, dofs, offset in ((f.axial_shapes_t, f.axial_dofs, a0), (f.torsion_shapes_t, f.torsion_dofs, t0),
                                   (f.bending_y_shapes_t, f.bending_y_dofs, y0),
                                   (f.bending_z_shapes_t, f.bending_z_dofs, z0)):
        _project(shapes_t, dofs, f.f_se, offset, acc)
    for i in range(n):
        out[n + i] += acc[i]
    n_t = t1 - t0
    n_y = y1 - y0
    if n_t == 0 or n_y == 0 or z1 == z0:
        return
    # B(η) = Σ_k η_z,k T_k
    b = f.block
    b[:, :] = 0.0
    for k in range(z1 - z0):
        eta = y[z0 + k]
        if eta != 0.0:
            for i in range(n_t):
                for j in range(n_y):
                    b[i, j] += eta * f.coupling_tensor[k, i, j]
    r = out[n:]
    rt = f.torsion_rhs
    for i in range(n_t):
        v = r[t0 + i]
        for j in range(n_y):
            v -= b[i, j] * r[y0 + j]
        rt[i] = v
        for k in range(n_t):
            total = 0.0
            for j in range(n_y):
                total += b[i, j] * b[k, j]
            f.schur[i, k] = (1.0 if i == k else 0.0) - total
    _cholesky_solve(f.schur, rt, rt)
    for j in range(n_y):
        v = r[y0 + j]
        for i in range(n_t):
            v -= b[i, j] * rt[i]
        r[y0 + j] = v
    for i in range(n_t):
        r[t0 + i] = rt[i]


def evaluate_rhs(data, t, y, out):
    """dy/dt of the ROM at time ``t`` [s] for the state ``y`` written into ``out``: case 2 for
    :class:`RhsData`, case 1 for :class:`FullModelData`. Callable from Python and from compiled code,
    where it is resolved by the type of ``data`` at compile time, so a case-2 run never compiles the
    case-1 kernel."""
    if isinstance(data, FullModelData):
        _rhs_full_kernel(data, t, y, out)
    else:
        _rhs_kernel(data, t, y, out)


@overload(evaluate_rhs)
def _evaluate_rhs_compiled(data, t, y, out):
    if _is(data, FullModelData):
        return lambda data, t, y, out: _rhs_full_kernel(data, t, y, out)
    if _is(data, RhsData) or _is(data, DelayedRhsData):
        return lambda data, t, y, out: _rhs_kernel(data, t, y, out)
    return None


@inner_kernel()
def _stiff_bit_law(d, t, y, shapes, partials, scratch):
    """:func:`stiff_part` for case-2 data ``d``."""
    n = d.omega2.shape[0]
    ranges = d.ranges
    a0, a1, t0, t1 = ranges.axial_start, ranges.axial_end, ranges.torsion_start, ranges.torsion_end
    for j in range(n):
        shapes[0, j] = 0.0
        shapes[1, j] = 0.0
    for j in range(a0, a1):
        shapes[0, j] = d.axial_rows[_AXIAL_BIT, j - a0]
    for j in range(t0, t1):
        shapes[1, j] = d.torsion_rows[_TORSION_BIT, j - t0]
    position, angle, velocity, speed = _bit_state(d, t, y)
    depth = _depth_of_cut(d, position, angle)
    f_u, f_w, f_d, t_u, t_w, t_d = bit_law_jacobian(d.laws, BitContext(t, position, angle, velocity, speed, depth,
                                                                       d.weight_on_bit))
    # the position moves a delayed law's depth of cut with it (∂d/∂u = 1 at a fixed angle); no other law reads it
    moves_depth = 1.0 if _delayed(d) else 0.0
    partials[0, 0] = f_u
    partials[0, 1] = f_w
    partials[0, 2] = moves_depth * f_d
    partials[1, 0] = t_u
    partials[1, 1] = t_w
    partials[1, 2] = moves_depth * t_d
    if shapes.shape[0] > 2:  # a third row: the downhole motor's (zero without one)
        for j in range(n):
            shapes[2, j] = 0.0
        for k in range(partials.shape[1]):
            partials[2, k] = 0.0
        if d.laws[MOTOR_CODE] != 0.0:
            for j in range(t0, t1):
                shapes[2, j] = d.torsion_rows[_TORSION_MOTOR, j - t0]
            # a motor without a compiled Jacobian is differenced, its states' rates written into the scratch
            partials[2, 0] = motor_slope(d.laws, MotorContext(t, _motor_speed(d, y)), y, scratch)


def stiff_part(data, t, y, shapes, partials, scratch):
    """The model's stiff part, for an implicit step (:mod:`drillstring.dynamics.steps.imex_ark`), at time ``t``
    [s] and state ``y``: writes the bit's axial and torsional mode-shape rows (u and θx at the bit over the n
    modal coordinates, zero outside their families) into ``shapes[0, :n]``, ``shapes[1, :n]``, and into
    ``partials`` (2, 3) the partial derivatives of the bit law's (axial force [N], torque [N·m]) in the bit's
    (axial velocity u̇ [m/s], speed θ̇ [rad/s], position u [m]; the position moves a delayed law's depth of
    cut with it, so its column is the law's depth partial, 0 for the others): the registered law's own compiled
    Jacobian (:func:`~drillstring.forces.registry.bit_law_jacobian`, the one its ``jacobian_at`` calls; central
    differences of its kernel only for a law that declares none). The
    bit law's part of ``∂(η̈)/∂(η, η̇)`` is then ``Bᵀ P[:, 2] b_uᵀ`` and ``Bᵀ P[:, :2] B`` (``B = shapes``,
    ``P = partials``), as :func:`drillstring.dynamics.stiffness._bit_rock_rows` builds it from ``jacobian_at``. When
    ``shapes`` and ``partials`` have a third row, it gets a downhole motor's: the rotor's relative torsional row
    (:attr:`ReducedOrderModel.motor_shapes`) in ``shapes[2, :n]`` and ``dT/dω_m`` [N·m·s/rad] of the registered
    motor's compiled Jacobian (:func:`~drillstring.forces.registry.motor_slope`) in ``partials[2, 0]`` (its part
    of ``∂(η̈)/∂η̇`` is ``m (dT/dω_m) mᵀ``; zeros without a motor; ``scratch``, of the state's size, takes the
    state rates of a motor differenced for want of a Jacobian, which are not kept: the function allocates
    nothing). Returns the linear part's ``(ω², Dᵀ, damping blocks)``.
    Compiled code only; case 1 (:class:`FullModelData`) reads its case-2 part."""
    raise NotImplementedError("compiled code only")


@overload(stiff_part, inline="always")
def _stiff_part_compiled(data, t, y, shapes, partials, scratch):
    # Inlined into its callers: the arrays it returns never cross a compiled call, so a caller with Numba's
    # reference counting and one without (the implicit-explicit loop) can share it (tests/dynamics/
    # test_reference_counting.py); _stiff_bit_law returns nothing.
    if _is(data, FullModelData):
        def full(data, t, y, shapes, partials, scratch):
            _stiff_bit_law(data.rhs, t, y, shapes, partials, scratch)
            return data.rhs.omega2, data.rhs.damping_t, data.rhs.damping_blocks
        return full
    if _is(data, RhsData) or _is(data, DelayedRhsData):
        def case_2(data, t, y, shapes, partials, scratch):
            _stiff_bit_law(data, t, y, shapes, partials, scratch)
            return data.omega2, data.damping_t, data.damping_blocks
        return case_2
    return None
