import numpy as np
import pytest

from drillstring.fem.assembly import (
    THETA_X, U, V, W, Stabilizer, assemble_matrix, dof, stabilizer_stiffness, structural_matrices,
)
from drillstring.fem.mesh import build_mesh
from exact_solutions import spinning_timoshenko_whirl


def test_assembly_of_uniform_bar_is_tridiagonal_with_summed_nodes(drill_pipe):
    mesh = build_mesh([30.0], [drill_pipe], 10.0)
    k, m = structural_matrices(mesh)
    kd = k.toarray()
    axial = kd[np.ix_(dof(np.arange(4), U), dof(np.arange(4), U))]
    ea_l = drill_pipe.axial_stiffness / 10.0
    expected = ea_l * np.array([[1, -1, 0, 0], [-1, 2, -1, 0], [0, -1, 2, -1], [0, 0, -1, 1]])
    np.testing.assert_allclose(axial, expected, rtol=1e-12)
    ones = np.zeros(mesh.n_dofs)
    ones[dof(np.arange(4), V)] = 1.0
    assert ones @ m @ ones == pytest.approx(drill_pipe.mass_per_length * 30.0, rel=1e-12)
    assert abs(k - k.T).max() < 1e-6


def test_stabilizer_springs_on_lateral_dofs(drill_pipe):
    mesh = build_mesh([30.0], [drill_pipe], 10.0)
    ks = stabilizer_stiffness(mesh, [Stabilizer(20.0, 5.0e6)]).toarray()
    node = mesh.node_index(20.0)
    assert ks[dof(node, V), dof(node, V)] == 5.0e6
    assert ks[dof(node, W), dof(node, W)] == 5.0e6
    assert ks[dof(node, THETA_X), dof(node, THETA_X)] == 0.0
    assert np.count_nonzero(ks) == 2


def test_generic_assembler_overlaps_shared_node():
    k = assemble_matrix(18, [np.ones((12, 12)), np.ones((12, 12))])
    assert k[6, 6] == 2.0 and k[0, 0] == 1.0 and k[17, 17] == 1.0 and k[0, 17] == 0.0


# --- gyroscopic matrix: Campbell diagram of a spinning shaft ----------------------------------------------


def _whirl(k, m, g, spin, v_rows, w_rows):
    """Whirl frequencies [rad/s] of M q̈ + Ω G q̇ + K q = 0 and their direction (+1 forward: the
    orbit turns y → z like the spin; −1 backward), ascending."""
    n = k.shape[0]
    a = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(m, k), -spin * np.linalg.solve(m, g)]])
    lam, vec = np.linalg.eig(a)
    keep = lam.imag > 1e-9
    lam, vec = lam[keep], vec[:, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    # v = Re(a e^{iωt}), w = Re(b e^{iωt}): the orbit turns y → z when Im(conj(a) b) < 0
    direction = -np.sign(np.sum(np.imag(np.conj(vec[v_rows]) * vec[w_rows]), axis=0))
    return lam.imag, direction, np.abs(lam.real).max()


def _shaft(s):
    """(EI, ρA, ρI, ρI_p, k_sGA) of a section, the arguments of the exact spinning-shaft solution."""
    return (s.bending_stiffness, s.mass_per_length, s.density * s.second_moment, s.density * s.polar_moment,
            s.shear_stiffness)


def test_spinning_shaft_whirl_against_closed_form(drill_collar):
    """Campbell diagram of a 4 m pinned–pinned drill collar up to 5000 rad/s: FE forward and
    backward whirl frequencies (orbit direction from the mode shapes) equal the exact Timoshenko
    values; the forward branch rises, the backward one falls, no mode is damped or unstable."""
    from drillstring.fem.assembly import THETA_Y, THETA_Z, gyroscopic_matrix

    length = 4.0
    mesh = build_mesh([length], [drill_collar], length / 32)
    k, m = structural_matrices(mesh)
    g = gyroscopic_matrix(mesh)
    nodes = np.arange(mesh.n_nodes)
    inner = nodes[1:-1]
    dofs = np.sort(np.concatenate([dof(inner, V), dof(inner, W), dof(nodes, THETA_Y), dof(nodes, THETA_Z)]))
    kd, md, gd = (a[dofs][:, dofs].toarray() for a in (k, m, g))
    np.testing.assert_array_equal(gd, -gd.T)
    v_rows, w_rows = np.searchsorted(dofs, dof(inner, V)), np.searchsorted(dofs, dof(inner, W))
    previous = None
    for spin in (0.0, 1000.0, 2000.0, 5000.0):
        omega, direction, damping = _whirl(kd, md, gd, spin, v_rows, w_rows)
        assert damping < 1e-8 * omega.max()
        for mode in (1, 2):
            forward, backward = spinning_timoshenko_whirl(mode, length, *_shaft(drill_collar), spin)
            if spin == 0.0:
                fem = omega[2 * mode - 2: 2 * mode]  # degenerate pair
                np.testing.assert_allclose(fem, forward, rtol=1e-4)
                continue
            assert omega[direction > 0][mode - 1] == pytest.approx(forward, rel=1e-4)
            assert omega[direction < 0][mode - 1] == pytest.approx(backward, rel=1e-4)
        if spin > 0.0:
            first = (omega[direction > 0][0], omega[direction < 0][0])
            if previous is not None:
                assert first[0] > previous[0] and first[1] < previous[1]
            previous = first
    # At 5000 rad/s the first pair is split by ~12 % (forward 202.7, backward 180.6 rad/s).
    assert (previous[0] - previous[1]) / previous[1] > 0.1


def test_gyroscopic_terms_are_negligible_for_the_reference_string():
    """Lowest lateral whirl frequencies of the reference string at 100 rpm, with and without the
    gyroscopic matrix, on the basis of 20 lateral modes per plane: the forward/backward split stays
    below 3e-4 (relative) for the first ten pairs, so case 2 can ignore it at this speed."""
    from drillstring.case import load_case
    from drillstring.fem.assembly import gyroscopic_matrix
    from drillstring.modal import case_linear_system, family_modes
    from drillstring.statics import case_static_state

    case = load_case("reference")
    system = case_linear_system(case, case_static_state(case))
    phi = np.hstack([family_modes(system, plane, 20).shapes for plane in ("lateral_y", "lateral_z")])
    k = phi.T @ (system.stiffness @ phi)
    m = phi.T @ (system.mass @ phi)
    g = phi.T @ (gyroscopic_matrix(system.mesh) @ phi)
    nodes = np.arange(system.mesh.n_nodes)
    modal_v, modal_w = phi[dof(nodes, V)], phi[dof(nodes, W)]
    n = phi.shape[1]
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(m, k), -case.operation.top_speed * np.linalg.solve(m, g)]])
    lam, vec = np.linalg.eig(a)
    keep = lam.imag > 0
    lam, vec = lam[keep], vec[:n, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    direction = -np.sign(np.sum(np.imag(np.conj(modal_v @ vec) * (modal_w @ vec)), axis=0))
    still = np.sqrt(np.linalg.eigvals(np.linalg.solve(m, k)).real)
    still = np.sort(still)[::2]
    forward, backward = lam.imag[direction > 0][:10], lam.imag[direction < 0][:10]
    split = (forward - backward) / still[:10]
    assert np.all(split >= 0) and split.max() < 3e-4 and split.max() > 1e-5
    np.testing.assert_allclose(0.5 * (forward + backward), still[:10], rtol=1e-6)


def test_gyroscopic_terms_barely_change_the_imbalance_whirl_of_the_contact_case():
    """The contact case's imbalance (5 mm on the collar) makes the string whirl forward at Ω: the harmonic
    response of the finite-element model, (K − Ω² M + iΩ (C_f + Ω G)) X = F, changes by less than 1 %
    (measured 0.23 % at the probe) when the gyroscopic matrix is added — below the lateral basis'
    truncation error — so case 2 leaves it out."""
    import scipy.sparse.linalg as spla

    from drillstring.case import load_case
    from drillstring.forces.turning_loads import case_turning_loads
    from drillstring.fem.assembly import gyroscopic_matrix
    from drillstring.modal import case_linear_system, family_dofs
    from drillstring.statics import case_static_state

    case = load_case("contact")
    static = case_static_state(case)
    system = case_linear_system(case, static)
    mesh = static.mesh
    omega = case.operation.top_speed
    dofs = np.concatenate([family_dofs(mesh, "lateral_y"), family_dofs(mesh, "lateral_z")])
    loads = case_turning_loads(case, mesh)
    weights = np.exp(1j * loads.phase) * np.where(loads.speed_squared, omega**2, 1.0)
    force = (loads.force_y @ weights - 1j * (loads.force_z @ weights))[dofs]  # forward: z lags y by 90°
    base = system.stiffness - omega**2 * system.mass + 1j * omega * system.fluid_damping
    gyro = 1j * omega**2 * gyroscopic_matrix(mesh)
    without = spla.spsolve(base[dofs][:, dofs].tocsc(), force)
    with_g = spla.spsolve((base + gyro)[dofs][:, dofs].tocsc(), force)
    probe = list(dofs).index(dof(mesh.node_index(1560.0), V))
    change = abs(abs(with_g[probe]) / abs(without[probe]) - 1)
    assert 1e-4 < change < 1e-2
    assert np.abs(with_g - without).max() < 1e-2 * np.abs(without).max()
