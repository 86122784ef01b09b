"""Reduced-order model: projection, energy conservation, steady drilling against closed forms."""

import dataclasses

import numpy as np
import pytest

from drillstring.dynamics.rom import (
    OBSERVABLE_COLUMN,
    OBSERVABLES,
    PROBE_COLUMN,
    case_reduced_model,
    reduced_model,
)
from drillstring.dynamics.runge_kutta import integrate
from drillstring.dynamics.simulate import simulate_model
from drillstring.fem.build import stabilizers
from drillstring.forces.bit_rock import BitRockParameters, evaluate_bit_rock, steady_state
from drillstring.forces.contact import ContactParameters
from drillstring.modal import build_linear_system
from drillstring.fem.build import section_fluid_coefficients
from drillstring.statics import case_static_state


def test_projection_is_mass_normalised_and_diagonal(coarse_case):
    rom = case_reduced_model(coarse_case, axial_modes=3, torsional_modes=3, lateral_modes=4)
    phi = rom.basis
    m = phi.T @ (rom.system.mass @ phi)
    k = phi.T @ (rom.system.stiffness @ phi)
    np.testing.assert_allclose(m, np.eye(rom.size), atol=1e-8)
    np.testing.assert_allclose(k, np.diag(rom.omega2), atol=1e-6 * rom.omega2.max())
    assert rom.family[0] == "rigid_axial" and rom.angular_frequencies[0] == 0.0
    assert rom.size == 1 + 3 + 3 + 2 * 4
    # Modal damping 2 ξ ω on the elastic axial modes (their basis is free–free, the damping's own;
    # the fluid adds to lateral ones only); the top-held torsional modes get less (tests/test_damping.py).
    xi = coarse_case.damping.modal_damping_ratio
    for i in range(1, 4):
        assert rom.damping[i, i] == pytest.approx(2 * xi * rom.angular_frequencies[i], rel=1e-9)
    for i in range(4, 7):
        assert 0 < rom.damping[i, i] < 2 * xi * rom.angular_frequencies[i]


def conservative_model(case):
    """Undamped, unforced ROM: no modal/fluid damping, no contact, no bit-rock force, no wob."""
    static = dataclasses.replace(case_static_state(case), weight_on_bit=0.0)
    fluid = section_fluid_coefficients(case.model_copy(update={"fluid": case.fluid.model_copy(
        update={"coriolis": False, "viscous_damping": False})}), static.mesh)
    system = build_linear_system(static.mesh, static, stabilizers(case), fluid)
    return reduced_model(
        static, system, axial_modes=3, torsional_modes=3, lateral_modes=4, modal_damping_ratio=0.0,
        rigid_axial_damping=0.0, top_speed=1.0,
        bit_rock=BitRockParameters(0.0, 1e40, 0.0, 0.0, 0.0, 2.0),
        contact=ContactParameters(0.0, 0.0, 0.1, False), borehole_diameter=case.borehole.diameter,
    )


def test_energy_is_conserved_without_damping_and_forcing(coarse_case):
    rom = conservative_model(coarse_case)
    rng = np.random.default_rng(3)
    y0 = rng.normal(size=2 * rom.size) * 1e-2
    y0[0] = 0.0  # no rigid drift, so energies stay O(1)
    lowest = np.min(rom.angular_frequencies[rom.angular_frequencies > 0])
    t_end = 20 * 2 * np.pi / lowest * 0.05  # several periods of all but the slowest lateral modes
    sol = integrate(rom.rhs, (0.0, t_end), y0, output_step=t_end / 50, rtol=1e-9, atol=1e-12,
                    observe=lambda t, y: np.array([rom.energy(y)]))
    energy = sol.y[:, 0]
    drift = np.abs(energy / energy[0] - 1).max()
    assert drift < 1e-6, drift


@pytest.mark.parametrize(
    "weight_on_bit, top_speed",
    [(100e3, 100 * np.pi / 30), (80e3, 60 * np.pi / 30), (140e3, 140 * np.pi / 30)],
)
def test_steady_drilling_matches_closed_form_without_lateral_modes(coarse_case, weight_on_bit,
                                                                    top_speed):
    """From rest, the integrated response settles on the closed-form steady state where steady drilling
    is stable: with damping on the constrained modes (with the default free–free damping steady
    drilling is unstable on this string; tests/dynamics/test_stability.py checks the steady state and
    its growth rate there)."""
    case = coarse_case.model_copy(update={
        "operation": coarse_case.operation.model_copy(update={"top_speed": top_speed}),
        "damping": coarse_case.damping.model_copy(update={"basis": "constrained"})})
    rom = case_reduced_model(case, weight_on_bit=weight_on_bit, lateral_modes=0)
    result = simulate_model(rom, t_end=20.0, output_step=0.01, lateral_perturbation=0.0)
    late = result.time >= 15.0
    rop, tob = steady_state(weight_on_bit, top_speed, rom.bit_rock)
    # what is left of the decaying transient after 15 s is below 1e-3 of each (observed: <= 9.5e-4)
    assert result.observables["rate_of_penetration"][late].mean() == pytest.approx(rop, rel=2e-3)
    assert result.observables["torque_on_bit"][late].mean() == pytest.approx(tob, rel=2e-3)
    assert result.observables["bit_speed"][late].mean() == pytest.approx(top_speed, rel=2e-3)
    # Force balance of the rigid motion: the rock carries the weight-on-bit (minus c1 · ROP).
    assert result.observables["force_on_bit"][late].mean() == pytest.approx(weight_on_bit, rel=1e-3)


def test_initial_state_is_seeded_physical_and_converges_with_modes(coarse_case):
    rom = case_reduced_model(coarse_case, lateral_modes=5)
    a = rom.initial_state(1e-4, seed=7)
    np.testing.assert_array_equal(a, rom.initial_state(1e-4, seed=7))
    assert not np.array_equal(a, rom.initial_state(1e-4, seed=8))
    n = rom.size
    assert np.all(a[n:] == 0)  # at rest relative to the spinning string
    labels = np.array(rom.family)
    assert np.all(a[:n][~np.char.startswith(labels, "lateral")] == 0)
    # The projected shape approaches the physical one (max radius 1e-4 m) as lateral modes grow.
    errors = []
    for count in (5, 20, 60):
        m = case_reduced_model(coarse_case, lateral_modes=count)
        eta = m.initial_state(1e-4, seed=7)[: m.size]
        errors.append(abs(np.hypot(m.phi_v @ eta, m.phi_w @ eta).max() - 1e-4))
    assert errors[2] < errors[1] < errors[0] and errors[2] < 2e-6


def test_observables_are_written_by_name(coarse_case):
    """Each observable sits in the column its name gives (OBSERVABLE_COLUMN, derived from OBSERVABLES)
    and equals its definition, computed here independently from the full mode shapes."""
    rom = case_reduced_model(coarse_case, lateral_modes=5)
    assert sorted(OBSERVABLE_COLUMN.values()) == list(range(len(OBSERVABLES)))
    assert [OBSERVABLE_COLUMN[name] for name in OBSERVABLES] == list(range(len(OBSERVABLES)))
    n = rom.size
    y = np.random.default_rng(2).normal(size=2 * n) * 30.0  # several nodes touch the wall
    out = rom.observe(0.0, y)
    eta, eta_dot = y[:n], y[n:]
    rop = rom.bit_u @ eta_dot
    speed = rom.top_speed + rom.bit_t @ eta_dot
    axial_force, torque = evaluate_bit_rock(rop, speed, rom.bit_rock)
    radius = np.hypot(rom.phi_v @ eta, rom.phi_w @ eta)
    st = rom.stations
    expected = {
        "rate_of_penetration": rop,
        "bit_speed": speed,
        "torque_on_bit": -torque,
        "force_on_bit": -axial_force,
        "bit_depth": rom.bit_u @ eta,
        "nodes_in_contact": np.count_nonzero(radius > rom.gap),
        "contact_force": np.sum(rom.station_stiffness
                                * np.clip(np.hypot(st.gather(rom.phi_v @ eta), st.gather(rom.phi_w @ eta))
                                          - st.gap, 0.0, None)),
    }
    assert expected["nodes_in_contact"] >= 2
    for name, value in expected.items():
        assert out[OBSERVABLE_COLUMN[name]] == pytest.approx(value, rel=1e-10, abs=1e-14), name
    n_p = len(rom.probe_nodes)
    np.testing.assert_allclose(out[PROBE_COLUMN:PROBE_COLUMN + n_p], radius[rom.probe_nodes], rtol=1e-10)
    np.testing.assert_allclose(out[PROBE_COLUMN + n_p:PROBE_COLUMN + 2 * n_p], (rom.phi_v @ eta)[rom.probe_nodes],
                               rtol=1e-10)
    np.testing.assert_allclose(out[PROBE_COLUMN + 2 * n_p:], (rom.phi_w @ eta)[rom.probe_nodes], rtol=1e-10)
    np.testing.assert_array_equal(rom.contact_mask(y), radius > rom.gap)


def test_generalized_force_is_added_to_the_modal_acceleration(coarse_case):
    base = case_reduced_model(coarse_case, lateral_modes=4)
    unforced = dataclasses.replace(base, generalized_force=None)
    np.testing.assert_array_equal(unforced.generalized_force, np.zeros(base.size))  # None: zeros
    rng = np.random.default_rng(5)
    force = rng.normal(size=base.size)
    forced = dataclasses.replace(base, generalized_force=base.generalized_force + force)
    n = base.size
    for scale in (1e-6, 30.0):  # without and with contact
        y = rng.normal(size=2 * n) * scale
        difference = forced.rhs(0.0, y) - base.rhs(0.0, y)
        np.testing.assert_allclose(difference[:n], 0.0, atol=0)
        np.testing.assert_allclose(difference[n:], force, rtol=1e-9, atol=1e-9 * np.abs(force).max())
        reference = forced.rhs_reference(0.0, y)
        np.testing.assert_allclose(forced.rhs(0.0, y), reference, rtol=1e-10,
                                   atol=1e-10 * np.abs(reference).max())
    with pytest.raises(ValueError, match="generalized_force"):
        dataclasses.replace(base, generalized_force=np.ones(n + 1))
    with pytest.raises(ValueError, match="generalized_force"):
        dataclasses.replace(base, generalized_force=np.full(n, np.nan))


def test_reduced_model_pushes_a_buckled_string_away_from_the_centre(reference_case):
    """The reduced model keeps the signed ω² of a buckled string: a small displacement along the
    unstable lateral mode (η̇ = 0, inside the gap) gets the outward acceleration −ω₁² η > 0."""
    from drillstring.modal import family_modes

    model = case_reduced_model(reference_case, weight_on_bit=130e3, axial_modes=2,
                               torsional_modes=2, lateral_modes=3)
    first = model.family.index("lateral_y")
    omega2 = family_modes(model.system, "lateral_y", 1).eigenvalues[0]
    assert omega2 < 0
    y = np.zeros(2 * model.size)
    y[first] = 1e-5
    acceleration = model.rhs(0.0, y)[model.size + first]
    assert acceleration == pytest.approx(-omega2 * 1e-5, rel=1e-9)


def whirling_model(case, lateral_modes):
    """Undamped lateral ROM (no modal, Coriolis or viscous damping; no axial or torsional modes) of the
    coarse reference string spinning at 100 rpm with an eccentric collar (5 mm, φ = 0) and a bow of the
    collar (2 mm, φ = 1 rad)."""
    from drillstring.fem.assembly import structural_matrices
    from drillstring.forces.excitation import bow_loads, imbalance_loads

    static = case_static_state(case)
    fluid = section_fluid_coefficients(case.model_copy(update={"fluid": case.fluid.model_copy(
        update={"coriolis": False, "viscous_damping": False})}), static.mesh)
    system = build_linear_system(static.mesh, static, stabilizers(case), fluid)
    mesh = static.mesh
    loads = (imbalance_loads(mesh, [0.0, 0.005], [0.0, 0.0])
             + bow_loads(mesh, structural_matrices(mesh)[0], 0.002, 1420.0, 1580.0, 1.0))
    return reduced_model(
        static, system, axial_modes=0, torsional_modes=0, lateral_modes=lateral_modes,
        modal_damping_ratio=0.0, rigid_axial_damping=0.0, top_speed=100 * np.pi / 30,
        bit_rock=BitRockParameters(0.0, 1e40, 0.0, 0.0, 0.0, 2.0),
        contact=ContactParameters(1e8, 0.0, 0.1, False), borehole_diameter=case.borehole.diameter,
        probe_positions=[1560.0], turning_loads=loads,
    )


def test_imbalance_and_bow_whirl_at_the_harmonic_response_of_the_finite_element_model(coarse_case):
    """At a constant spin Ω the turning loads make the string whirl on a circle: the simulated radius at
    the probe stays at the ROM's harmonic amplitude (the time-dependent kernel agrees with the frequency
    domain), and that amplitude converges with the lateral modes to the direct harmonic solution of the
    finite-element model, (K − Ω² M) X = Σ_k s_k e^{iφ_k} F_k, on every lateral DOF."""
    import scipy.sparse.linalg as spla

    from drillstring.fem.dofs import V, dof
    from drillstring.modal import family_dofs

    errors = []
    for count in (10, 20, 40):
        rom = whirling_model(coarse_case, count)
        omega = rom.top_speed
        turning = rom.turning_loads
        weights = np.exp(1j * turning.phase) * np.where(turning.speed_squared, omega**2, 1.0)
        dofs = family_dofs(rom.static.mesh, "lateral_y")
        stiffness = rom.system.stiffness[dofs][:, dofs] - omega**2 * rom.system.mass[dofs][:, dofs]
        exact = np.zeros(rom.static.mesh.n_dofs, dtype=complex)
        exact[dofs] = spla.spsolve(stiffness.tocsc().astype(complex), (turning.force_y @ weights)[dofs])
        probe = rom.probe_nodes[0]
        radius = abs(exact[dof(probe, V)])
        run = simulate_model(rom, t_end=2.0, output_step=0.01, rtol=1e-9, atol=1e-12, lateral_perturbation=0.0)
        r = run.radial_displacement[:, 0]
        assert np.ptp(r) < 1e-5 * r.mean()  # a circle: the steady whirl the run started on
        orbit = run.lateral_displacement[:, 0, :]
        assert np.allclose(np.hypot(orbit[:, 0], orbit[:, 1]), r, rtol=1e-12)
        angle = np.unwrap(np.arctan2(orbit[:, 1], orbit[:, 0]))
        assert angle[-1] - angle[0] == pytest.approx(omega * 2.0, rel=1e-6)  # forward, at Ω
        errors.append(abs(r.mean() - radius) / radius)
    assert errors[2] < errors[1] < errors[0] and errors[2] < 1e-2, errors


def test_a_clear_state_counts_no_impact_and_forgets_the_contact(coarse_case):
    """The impacts count skips a state whose lateral coordinates the right-hand side's bound clears
    (``_surely_clear``): no impact, no node left in contact, so the next touching state is a new impact; a
    touching state is counted as by the contact state of every node."""
    from drillstring.dynamics.rom import _surely_clear

    rom = case_reduced_model(coarse_case, lateral_modes=5)
    n = rom.size
    touching = np.random.default_rng(2).normal(size=2 * n) * 30.0  # several nodes touch the wall
    radius = np.hypot(rom.phi_v @ touching[:n], rom.phi_w @ touching[:n])
    zones = np.count_nonzero(np.diff(np.concatenate([[0], (radius > rom.gap).astype(int)])) == 1)
    clear = touching.copy()
    clear[:n] *= 1e-9
    assert zones >= 1 and _surely_clear(rom.case2_data, clear) and not _surely_clear(rom.case2_data, touching)
    counter = rom.impact_counter()
    assert counter(touching) == zones
    assert counter(touching) == 0  # the same zones: no new impact
    assert counter(clear) == 0
    assert not counter.in_contact.any()
    assert counter(touching) == zones  # the contact was forgotten: the zones are impacts again


def test_energy_is_conserved_through_impacts_without_damping_and_friction(coarse_case):
    """Undamped, unforced, frictionless: the string thrown at the wall bounces off it several times, and
    its energy ½η̇ᵀη̇ + ½Σω²η² + Σ_i ½ k_i (r_i − g_i)₊² (the wall's penalty potential, computed here from
    the stations) is the same before, during and after the impacts, up to the integration tolerance."""
    rom = dataclasses.replace(conservative_model(coarse_case),
                              contact=ContactParameters(1e8, 0.0, 0.1, False))
    st = rom.stations
    n = rom.size

    def energy(y):
        eta = y[:n]
        r = np.hypot(st.gather(rom.phi_v @ eta), st.gather(rom.phi_w @ eta))
        return rom.energy(y) + 0.5 * np.sum(rom.station_stiffness * np.clip(r - st.gap, 0.0, None) ** 2)

    y0 = np.zeros(2 * n)
    lateral = np.array([f.startswith("lateral") for f in rom.family])
    y0[n:][lateral] = np.random.default_rng(1).normal(size=lateral.sum()) * 10.0
    drifts = {}
    for rtol in (1e-6, 1e-9):
        counter = rom.impact_counter()
        impacts = [counter(y0)]
        run = integrate(rom.rhs, (0.0, 10.0), y0, output_step=0.01, rtol=rtol, atol=rtol * 1e-3,
                        observe=lambda t, y: np.array([energy(y), rom.observe(t, y)[OBSERVABLE_COLUMN["contact_force"]]]),
                        on_step=lambda t, y: impacts.append(counter(y)))
        e, force = run.y[:, 0], run.y[:, 1]
        assert sum(impacts) >= 2 and force.max() > 0
        drifts[rtol] = np.abs(e / e[0] - 1).max()
    assert drifts[1e-9] < 1e-6 and drifts[1e-9] < 0.01 * drifts[1e-6], drifts


def test_diagonal_blocks_of_the_damping():
    from drillstring.dynamics.rom import diagonal_blocks

    a = np.zeros((7, 7))
    a[0, 0] = 1.0
    a[1, 3] = 2.0  # couples 1..3
    a[5, 6] = a[6, 5] = 1.0
    np.testing.assert_array_equal(diagonal_blocks(a), [[0, 1], [1, 4], [5, 7]])  # row 4 all zero: left out
    assert diagonal_blocks(np.zeros((3, 3))).shape == (0, 2)


def test_reference_damping_is_block_diagonal_by_family(coarse_case):
    rom = case_reduced_model(coarse_case, axial_modes=3, torsional_modes=3, lateral_modes=4)
    blocks = rom.case2_data.damping_blocks
    np.testing.assert_array_equal(blocks, rom.blocks.reshape(4, 2))  # axial, torsional, lateral y, z
    mask = np.zeros_like(rom.damping, dtype=bool)
    for start, end in blocks:
        mask[start:end, start:end] = True
    assert not rom.damping[~mask].any()


def test_contact_bound_never_skips_a_touching_node(coarse_case):
    """The cheap bound that skips the contact search is rigorous: whenever it says "clear", no node is
    outside its gap; and near the wall it lets the search run."""
    from drillstring.dynamics.rom import _surely_clear

    rom = case_reduced_model(coarse_case, axial_modes=2, torsional_modes=2, lateral_modes=6)
    d = rom.case2_data
    rng = np.random.default_rng(0)
    lateral = np.char.startswith(np.array(rom.family), "lateral")
    cleared = searched = 0
    for scale in np.geomspace(1e-3, 10.0, 40):
        eta = np.zeros(rom.size)
        eta[lateral] = rng.normal(size=lateral.sum()) * scale
        radius = np.hypot(rom.phi_v @ eta, rom.phi_w @ eta)
        if _surely_clear(d, eta):
            cleared += 1
            assert np.all(radius <= rom.gap)
        else:
            searched += 1
    assert cleared and searched


def test_the_kernels_data_is_named(coarse_case):
    """The compiled kernels read the model's data by name: the columns of each family (ModalRanges) and each
    mode-shape row the laws act along by its name (AXIAL_ROWS, TORSION_ROWS), each equal to the shape it names."""
    from drillstring.dynamics.kernel_data import AXIAL_ROW, TORSION_ROW

    rom = case_reduced_model(coarse_case, lateral_modes=5)
    d = rom.case2_data
    assert list(d.ranges) == [int(b) for b in rom.blocks]
    r = d.ranges
    (a0, a1), (t0, t1) = (r.axial_start, r.axial_end), (r.torsion_start, r.torsion_end)
    assert (r.lateral_y_end - r.lateral_y_start, r.lateral_z_end - r.lateral_z_start) == (5, 5)
    named = {("axial", "bit"): rom.bit_u[a0:a1], ("axial", "top"): rom.top_u[a0:a1],
             ("torsion", "bit"): rom.bit_t[t0:t1], ("torsion", "quill"): rom.quill_shapes[t0:t1],
             ("torsion", "surface_torque"): rom.surface_torque_shapes[t0:t1],
             ("torsion", "motor"): rom.motor_shapes[t0:t1]}
    rows = {"axial": (d.axial_rows, AXIAL_ROW), "torsion": (d.torsion_rows, TORSION_ROW)}
    assert {(group, name) for group, (_, index) in rows.items() for name in index} == set(named)
    for (group, name), shape in named.items():
        array, index = rows[group]
        np.testing.assert_array_equal(array[index[name]], shape, err_msg=f"{group} {name}")
    assert "blocks" not in d._fields
