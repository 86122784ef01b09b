"""The truncation correction of a downhole motor's released torsion (drillstring.rotor): its attachment modes keep
the basis M- and K-orthogonal, reproduce the static (inertia-relief) response to the loads of the laws - the bit's
torque, the motor's torque pair, the top drive's torque - against an independent bordered solve, and give the
leading root of steady drilling of the `motor` case on the default basis within 2 % of a basis four times larger
(docs/verification.md, "Basis convergence with a downhole motor")."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import stability, steady_drilling
from drillstring.fem.assembly import THETA_X, dof
from drillstring.modal import case_linear_system, family_dofs, top_inertia_matrix
from drillstring.rotor import released_system, released_torsional_modes, rotor_node
from drillstring.statics import case_static_state

KEPT = 6  # elastic modes kept


@pytest.fixture(scope="module")
def coarse():
    """The motor case on a 50 m mesh: its released linear system and rotor station."""
    case = load_case("motor")
    case = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": 50.0})})
    system = case_linear_system(case, case_static_state(case))
    node = rotor_node(system.mesh, case.motor.position)
    return released_system(system, node), node


def _released_matrices(released, top_inertia):
    """The released torsion's DOFs (the rotor side's last), K and M there."""
    mesh = released.mesh
    dofs = np.concatenate([family_dofs(mesh, "torsional", top_inertia is not None), [mesh.n_dofs]])
    mass = released.mass
    if top_inertia is not None:
        mass = mass + sp.block_diag([top_inertia_matrix(mesh, top_inertia), sp.csr_matrix((1, 1))], format="csr")
    return dofs, released.stiffness[dofs][:, dofs], mass[dofs][:, dofs]


def _full(release, dofs, n_dofs):
    """The family's columns on the released DOFs ``dofs`` (the mesh's rows and the rotor side's)."""
    rows = np.vstack([release.family.shapes, release.rotor])
    return rows[np.minimum(dofs, n_dofs)]


@pytest.mark.parametrize("top_inertia", [None, 1000.0])
def test_the_released_attachment_modes_keep_the_basis_orthogonal(coarse, top_inertia):
    released, node = coarse
    rigid = 1 if top_inertia is None else 2
    plain = released_torsional_modes(released, node, rigid + KEPT, top_inertia)
    corrected = released_torsional_modes(released, node, rigid + KEPT, top_inertia, "static")
    count = rigid + KEPT
    assert corrected.family.attachments == 1 + rigid  # bit, torque pair (and top)
    np.testing.assert_array_equal(corrected.family.shapes[:, :count], plain.family.shapes)
    np.testing.assert_array_equal(corrected.rotor[:count], plain.rotor)
    dofs, k, m = _released_matrices(released, top_inertia)
    phi = _full(corrected, dofs, released.mesh.n_dofs)
    np.testing.assert_allclose(phi.T @ (m @ phi), np.eye(phi.shape[1]), atol=1e-10)
    stiffness = phi.T @ (k @ phi)
    np.testing.assert_allclose(stiffness, np.diag(corrected.family.eigenvalues), atol=1e-9 * np.abs(stiffness).max())
    assert corrected.family.angular_frequencies[count:].min() > plain.family.angular_frequencies.max()
    # orthogonal to the rigid motions: the string below does not turn relative to the string above in them
    assert np.abs(corrected.lower_rotation[count:]).max() < 1e-10 * np.abs(corrected.lower_rotation).max()


@pytest.mark.parametrize("top_inertia", [None, 1000.0])
def test_the_corrected_released_basis_gives_the_inertia_relief_response(coarse, top_inertia):
    """Each law's load (a torque at the bit, the motor's torque pair, a torque at the top with a top drive):
    the elastic response is the inertia-relief solution of the bordered system ``[[K, M R], [Rᵀ M, 0]]`` (R the
    rigid motions, an independent sparse solve); the corrected basis's ``Φ_e Ω_e⁻² Φ_eᵀ f`` reproduces it to
    rounding over the whole released string, the plain basis of the same size does not."""
    released, node = coarse
    rigid = 1 if top_inertia is None else 2
    n_dofs = released.mesh.n_dofs
    dofs, k, m = _released_matrices(released, top_inertia)
    shapes = [(dofs > dof(node, THETA_X)).astype(float)]  # the string below (and the rotor side) turning
    if top_inertia is not None:
        shapes.insert(0, np.ones(len(dofs)))
    mr = m @ np.column_stack(shapes)
    bordered = sp.bmat([[k, sp.csr_matrix(mr)], [sp.csr_matrix(mr.T), None]]).tocsc()
    loads = np.zeros((len(dofs), 1 + rigid))
    loads[np.searchsorted(dofs, dof(released.mesh.n_nodes - 1, THETA_X)), 0] = 1.0
    loads[-1, 1], loads[np.searchsorted(dofs, dof(node, THETA_X)), 1] = 1.0, -1.0
    if top_inertia is not None:
        loads[0, 2] = 1.0
    exact = spla.splu(bordered).solve(np.vstack([loads, np.zeros((rigid, loads.shape[1]))]))[:len(dofs)]

    def response(corrected):
        release = released_torsional_modes(released, node, rigid + KEPT, top_inertia,
                                           "static" if corrected else "none")
        phi = _full(release, dofs, n_dofs)[:, rigid:]  # the elastic columns
        return phi @ ((phi.T @ loads) / release.family.eigenvalues[rigid:, None])

    scale = np.abs(exact).max(axis=0)
    assert (np.abs(response(True) - exact).max(axis=0) < 1e-9 * scale).all()
    assert (np.abs(response(False) - exact).max(axis=0) > 1e-3 * scale).all()


def test_the_motor_cases_leading_root_converges_on_the_default_basis():
    """Steady drilling of the `motor` case: the leading root at its basis (10 + 10 modes, the attachment modes
    of the axial family and of the released torsion) within 2 % (growth rate) of 40 + 40, both bases; the first
    axial root (0.45 Hz), which the plain basis of 10 modes misses by 1.5 %, within 0.1 % with the correction."""
    case = load_case("motor")
    assert case.reduced_model.truncation_correction == "static"  # the case's basis is the default one

    def roots(correction, modes):
        model = case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
            update={"truncation_correction": correction, "axial_modes": modes, "torsional_modes": modes})}))
        found = stability(model)
        axial = min((m for m in found.modes if m.frequency > 0.1 and not m.beyond_basis and m.shares["axial"] > 0.5),
                    key=lambda m: m.frequency)
        return found.leading, axial

    lead, axial = roots("static", 10)
    large_lead, large_axial = roots("static", 40)
    plain_lead, plain_axial = roots("none", 10)
    assert not lead.beyond_basis and abs(lead.frequency - large_lead.frequency) < 1e-3
    assert lead.growth_rate == pytest.approx(large_lead.growth_rate, rel=0.02)
    assert plain_lead.growth_rate == pytest.approx(large_lead.growth_rate, rel=0.02)
    assert axial.growth_rate == pytest.approx(large_axial.growth_rate, rel=1e-3)
    assert abs(plain_axial.growth_rate / large_axial.growth_rate - 1) > 5e-3


@pytest.mark.parametrize("controller", ["pi", "soft_torque"])
def test_a_driving_top_on_the_corrected_basis(coarse, controller):
    """A top drive (PI, SoftTorque) with a motor on the corrected basis: the compiled right-hand side is the NumPy
    reference's, and steady drilling is the plain basis's (the attachment modes do no work on the rigid motions
    that set the motor's speed and the top's torque)."""
    case = load_case("motor")
    case = case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={"axial_modes": 4, "torsional_modes": 6,
                                                               "lateral_modes": 4}),
        "top_drive": case.top_drive.model_copy(update={"controller": controller})})

    def model_with(correction):
        return case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
            update={"truncation_correction": correction})}))

    corrected, plain = model_with("static"), model_with("none")
    assert corrected.size == plain.size + 4  # the bit's axial, and the bit, the pair and the top in torsion
    rng = np.random.default_rng(7)
    y = corrected.initial_state(0.0, 0) + 1e-3 * rng.standard_normal(corrected.state_size)
    reference = corrected.rhs_reference(0.3, y)
    np.testing.assert_allclose(corrected.rhs(0.3, y), reference, rtol=1e-10, atol=1e-12 * np.abs(reference).max())
    steady, steady_plain = steady_drilling(corrected), steady_drilling(plain)
    for name in ("motor_speed", "motor_torque", "string_speed"):
        assert steady.motor[name] == pytest.approx(steady_plain.motor[name], rel=1e-9)
    assert steady.rate_of_penetration == pytest.approx(steady_plain.rate_of_penetration, rel=1e-9)
